/*
 * OME-Zarr groups beside an image (OME-NGFF 0.4 .zattrs, 0.5 zarr.json
 * attributes.ome): an image's "labels" group and its label images
 * ("image-label": colors, properties), HCS plates ("plate": rows, columns,
 * wells, field_count, acquisitions) and their wells ("well": images).
 *
 * What is listed is what `volvis info` prints; an image is opened by its
 * own path (PLATE/A/1/0, IMAGE/labels/cells), read by zarr_read.c as any
 * other. Every path the metadata names is checked as a dataset's path is
 * (zarr_read.c): relative, no ".." or "." part, no empty part, and every
 * metadata file read through zr_store_get, which refuses a file that a
 * link leads out of the store. Lists are bounded (VV_OME_ZARR_WELLS_MAX,
 * VV_OME_ZARR_LABELS_MAX) before anything is read for them.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <jansson.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/zarr.h"

/* The store rooted at @p root: what zr_store_get needs (its real path). */
static void
meta_store(zr_array *a, const char *root) {
    memset(a, 0, sizeof *a);
    char *r = realpath(root, NULL);
    snprintf(a->real, sizeof a->real, "%s", r ? r : "");
    free(r);
    snprintf(a->root, sizeof a->root, "%s", root);
}

/* The OME attributes of the group at @p prefix ("" the root) into *out (a
 * new reference; NULL: no group metadata there): its zarr.json's
 * attributes.ome (or attributes), else its .zattrs. *md names the file
 * read (for messages). *array = 1 when it is a Zarr array, not a group. */
static vv_status
group_attrs(const zr_array *a, const char *prefix, json_t **out, char *md, size_t cap, int *array) {
    vv_status s;
    char key[600];
    *out = NULL;
    *array = 0;
    snprintf(key, sizeof key, "%s%szarr.json", prefix, prefix[0] ? "/" : "");
    snprintf(md, cap, "%s", key);
    json_t *z = zr_load_json(a, key, key, 1, &s);
    if (s != VV_OK)
        return s;
    if (z) {
        const char *nt = json_string_value(json_object_get(z, "node_type"));
        json_t *at = json_object_get(z, "attributes");
        json_t *ome = json_object_get(at, "ome");
        if (nt && !strcmp(nt, "array"))
            *array = 1;
        else if (!nt || strcmp(nt, "group"))
            s = vv_error_set(VV_ERR_FORMAT, "%s: node_type is not \"array\" or \"group\"", key);
        else if (json_is_object(ome) || json_is_object(at))
            *out = json_incref(json_is_object(ome) ? ome : at);
        json_decref(z);
        return s;
    }
    snprintf(key, sizeof key, "%s%s.zarray", prefix, prefix[0] ? "/" : "");
    unsigned char *b = NULL;
    size_t n = 0;
    int missing = 1;
    if ((s = zr_store_get(a, key, 0, 0, 0, &b, &n, NULL, &missing)) != VV_OK)
        return s;
    free(b);
    *array = !missing;
    snprintf(key, sizeof key, "%s%s.zattrs", prefix, prefix[0] ? "/" : "");
    snprintf(md, cap, "%s", key);
    *out = zr_load_json(a, key, key, 1, &s);
    if (*out && !json_is_object(*out)) {
        json_decref(*out);
        *out = NULL;
        s = vv_error_set(VV_ERR_FORMAT, "%s: not a JSON object", key);
    }
    return s;
}

/* A path the metadata names (a well's, a field's, a label's): relative,
 * every part non-empty and neither "." nor "..", printable, shorter than
 * VV_OME_ZARR_NAME_MAX; @p parts > 0: exactly that many parts. The error
 * names @p md and @p field and quotes the path. */
static vv_status
check_path(json_t *pj, int parts, const char *md, const char *field) {
    const char *p = json_string_value(pj);
    if (!p || !*p)
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: no path", md, field);
    const size_t n = strlen(p);
    int bad = n >= VV_OME_ZARR_NAME_MAX || p[0] == '/' || p[n - 1] == '/', k = 1;
    for (const char *c = p; !bad && *c; c++) {
        if ((unsigned char)*c < 0x20 || *c == 0x7f || *c == '\\')
            bad = 1;
        if (*c == '/')
            k++;
    }
    /* each part: not empty, not "." or ".." */
    for (const char *c = p; !bad && *c;) {
        const char *e = strchr(c, '/');
        const size_t len = e ? (size_t)(e - c) : strlen(c);
        if (len == 0 || (len == 1 && c[0] == '.') || (len == 2 && c[0] == '.' && c[1] == '.'))
            bad = 1;
        c = e ? e + 1 : c + len;
    }
    if (bad)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: %s: path \"%.200s\" leaves the store or is not a "
                            "relative path of the store",
                            md, field, p);
    if (parts > 0 && k != parts)
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: path \"%.200s\" is not ROW/COLUMN", md, field,
                            p);
    return VV_OK;
}

/* The list @p l (a JSON array of at most @p max entries) named @p field
 * of @p md. */
static vv_status
check_list(json_t *l, size_t max, const char *md, const char *field) {
    if (!json_is_array(l))
        return vv_error_set(VV_ERR_FORMAT, "%s: %s is not a list", md, field);
    if (json_array_size(l) > max)
        return vv_error_set(VV_ERR_LIMIT, "%s: %s: %zu entries (at most %zu are read)", md, field,
                            json_array_size(l), max);
    return VV_OK;
}

/* A label image's colours (image-label.colors): each a label-value and
 * an rgba of four integers 0..255. */
static vv_status
check_colors(json_t *il, const char *md, int *n) {
    json_t *cl = json_object_get(il, "colors");
    *n = 0;
    if (!cl)
        return VV_OK;
    vv_status s = check_list(cl, 1u << 16, md, "image-label.colors");
    size_t i;
    json_t *c;
    json_array_foreach(cl, i, c) {
        if (s != VV_OK)
            break;
        json_t *lv = json_object_get(c, "label-value"), *rgba = json_object_get(c, "rgba");
        int ok =
            json_is_number(lv) && (!rgba || (json_is_array(rgba) && json_array_size(rgba) == 4));
        for (size_t k = 0; ok && rgba && k < 4; k++) {
            json_t *x = json_array_get(rgba, k);
            ok = json_is_integer(x) && json_integer_value(x) >= 0 && json_integer_value(x) <= 255;
        }
        if (!ok)
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: image-label.colors %zu: not a label-value with an rgba of four "
                             "integers 0..255",
                             md, i);
    }
    *n = (int)json_array_size(cl);
    return s;
}

/* The label images of the labels group at @p prefix ("labels", or "" when
 * the group itself was opened) of store @p a, listed by @p attrs. */
static vv_status
read_labels(const zr_array *a, const char *root, const char *prefix, json_t *attrs, const char *md,
            vv_ome_zarr_contents *out) {
    json_t *l = json_object_get(attrs, "labels");
    vv_status s = check_list(l, VV_OME_ZARR_LABELS_MAX, md, "labels");
    if (s != VV_OK)
        return s;
    const size_t n = json_array_size(l);
    out->labels = calloc(n ? n : 1, sizeof *out->labels);
    if (!out->labels)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    zr_array *la = calloc(1, sizeof *la);
    if (!la)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n && s == VV_OK; i++) {
        char field[64];
        snprintf(field, sizeof field, "labels %zu", i);
        json_t *pj = json_array_get(l, i);
        if ((s = check_path(pj, 0, md, field)) != VV_OK)
            break;
        vv_ome_zarr_label *L = &out->labels[out->n_labels];
        snprintf(L->name, sizeof L->name, "%s", json_string_value(pj));
        char sub[600], lmd[700];
        snprintf(sub, sizeof sub, "%s%s%s", prefix, prefix[0] ? "/" : "", L->name);
        json_t *la_attrs = NULL;
        int array = 0;
        if ((s = group_attrs(a, sub, &la_attrs, lmd, sizeof lmd, &array)) != VV_OK)
            break;
        if (!la_attrs || !json_object_get(la_attrs, "multiscales")) {
            json_decref(la_attrs);
            s = vv_error_set(VV_ERR_FORMAT, "%s: %s: \"%s\" is not a multiscales image (%s)", md,
                             field, L->name, lmd);
            break;
        }
        s = check_colors(json_object_get(la_attrs, "image-label"), lmd, &L->n_colors);
        json_decref(la_attrs);
        if (s != VV_OK)
            break;
        /* its level 0, as a read would parse it (its own paths checked) */
        char full[8400];
        snprintf(full, sizeof full, "%s/%s", root, sub);
        memset(la, 0, sizeof *la);
        zr_layout J;
        s = vv_zr_parse_store(full, 0, la, 0, NULL, &L->n_levels);
        if (s == VV_OK)
            s = vv_zr_layout(la, -1, -1, &J);
        if (s == VV_OK) {
            memcpy(L->dims, J.dims, sizeof L->dims);
            L->type = la->type;
        }
        vv_zr_array_release(la);
        if (s != VV_OK)
            s = vv_error_prefix(s, "%s", sub);
        else
            out->n_labels++;
    }
    free(la);
    return s;
}

/* A well's images (its group at @p prefix): the count and the first path. */
static vv_status
read_well(const zr_array *a, const char *prefix, vv_ome_zarr_well *w) {
    json_t *attrs = NULL;
    char md[700];
    int array = 0;
    vv_status s = group_attrs(a, prefix, &attrs, md, sizeof md, &array);
    if (s != VV_OK || !attrs)
        return s; /* a well the plate lists and nobody wrote: no fields */
    json_t *im = json_object_get(json_object_get(attrs, "well"), "images");
    if (!json_object_get(attrs, "well"))
        s = vv_error_set(VV_ERR_FORMAT, "%s: no well metadata", md);
    else
        s = check_list(im, VV_OME_ZARR_WELLS_MAX, md, "well.images");
    for (size_t i = 0; s == VV_OK && i < json_array_size(im); i++) {
        char field[64];
        snprintf(field, sizeof field, "well.images %zu", i);
        json_t *pj = json_object_get(json_array_get(im, i), "path");
        if ((s = check_path(pj, 0, md, field)) == VV_OK && i == 0)
            snprintf(w->first_field, sizeof w->first_field, "%s", json_string_value(pj));
    }
    if (s == VV_OK)
        w->n_fields = (int)json_array_size(im);
    json_decref(attrs);
    return s;
}

/* An HCS plate's rows, columns and wells, each well's fields. */
static vv_status
read_plate(const zr_array *a, json_t *pl, const char *md, vv_ome_zarr_contents *out) {
    if (!json_is_object(pl))
        return vv_error_set(VV_ERR_FORMAT, "%s: plate is not an object", md);
    json_t *rows = json_object_get(pl, "rows"), *cols = json_object_get(pl, "columns");
    json_t *wells = json_object_get(pl, "wells"), *acq = json_object_get(pl, "acquisitions");
    json_t *fc = json_object_get(pl, "field_count");
    vv_status s;
    if ((s = check_list(rows, VV_OME_ZARR_WELLS_MAX, md, "plate.rows")) != VV_OK ||
        (s = check_list(cols, VV_OME_ZARR_WELLS_MAX, md, "plate.columns")) != VV_OK ||
        (s = check_list(wells, VV_OME_ZARR_WELLS_MAX, md, "plate.wells")) != VV_OK ||
        (acq && (s = check_list(acq, VV_OME_ZARR_WELLS_MAX, md, "plate.acquisitions")) != VV_OK))
        return s;
    if (fc && (!json_is_integer(fc) || json_integer_value(fc) < 1 ||
               json_integer_value(fc) > VV_OME_ZARR_WELLS_MAX))
        return vv_error_set(VV_ERR_FORMAT, "%s: plate.field_count is not a count of 1 to %d", md,
                            VV_OME_ZARR_WELLS_MAX);
    out->n_rows = (int)json_array_size(rows);
    out->n_columns = (int)json_array_size(cols);
    out->n_acquisitions = (int)json_array_size(acq);
    out->field_count = fc ? (int)json_integer_value(fc) : 0;
    const char *name = json_string_value(json_object_get(pl, "name"));
    snprintf(out->plate_name, sizeof out->plate_name, "%s", name ? name : "");
    for (char *c = out->plate_name; *c; c++)
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            *c = '?';
    const size_t n = json_array_size(wells);
    out->wells = calloc(n ? n : 1, sizeof *out->wells);
    if (!out->wells)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n && s == VV_OK; i++) {
        char field[64];
        snprintf(field, sizeof field, "plate.wells %zu", i);
        json_t *w = json_array_get(wells, i);
        json_t *ri = json_object_get(w, "rowIndex"), *ci = json_object_get(w, "columnIndex");
        if ((s = check_path(json_object_get(w, "path"), 2, md, field)) != VV_OK)
            break;
        vv_ome_zarr_well *W = &out->wells[out->n_wells];
        snprintf(W->path, sizeof W->path, "%s", json_string_value(json_object_get(w, "path")));
        /* 0.4 and 0.5 require the indices; 0.3 and older have none */
        W->row = W->column = -1;
        if ((ri && (!json_is_integer(ri) || json_integer_value(ri) < 0 ||
                    json_integer_value(ri) >= out->n_rows)) ||
            (ci && (!json_is_integer(ci) || json_integer_value(ci) < 0 ||
                    json_integer_value(ci) >= out->n_columns))) {
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: %s: rowIndex or columnIndex is not a row or column of the plate",
                             md, field);
            break;
        }
        if (ri)
            W->row = (int)json_integer_value(ri);
        if (ci)
            W->column = (int)json_integer_value(ci);
        if ((s = read_well(a, W->path, W)) == VV_OK)
            out->n_wells++;
    }
    return s;
}

/* vv_ome_zarr_contents_get without the prefix on its errors. */
static vv_status
contents_get(const char *path, vv_ome_zarr_contents *out) {
    memset(out, 0, sizeof *out);
    zr_array *a = calloc(1, sizeof *a);
    if (!a)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    meta_store(a, path);
    json_t *attrs = NULL;
    char md[700];
    int array = 0;
    /* an N5 or precomputed store (by URL the Zarr row reads them too): one
     * image, its metadata the reader's */
    if (bs_url_format(path)) {
        out->kind = VV_OME_ZARR_IMAGE;
        free(a);
        return VV_OK;
    }
    vv_status s = group_attrs(a, "", &attrs, md, sizeof md, &array);
    if (s == VV_OK && !attrs && !array) {
        static const char *const other[] = {"attributes.json", "info"};
        int found = 0;
        for (int i = 0; s == VV_OK && i < 2 && !found; i++) {
            unsigned char *b = NULL;
            size_t n = 0;
            int missing = 1;
            s = zr_store_get(a, other[i], 0, 0, 0, &b, &n, NULL, &missing);
            free(b);
            found = s == VV_OK && !missing;
        }
        if (found) {
            out->kind = VV_OME_ZARR_IMAGE;
            free(a);
            return VV_OK;
        }
    }
    json_t *pl = json_object_get(attrs, "plate"), *well = json_object_get(attrs, "well");
    if (s != VV_OK) {
        ;
    } else if (array && !json_object_get(attrs, "multiscales")) {
        out->kind = VV_OME_ZARR_IMAGE; /* a plain array */
    } else if (!attrs) {
        s = vv_error_set(VV_ERR_FORMAT, "no zarr.json, .zattrs or .zarray (not a Zarr store)");
    } else if (json_object_get(attrs, "multiscales")) {
        out->kind = VV_OME_ZARR_IMAGE;
        out->is_label = json_is_object(json_object_get(attrs, "image-label"));
        json_t *la = NULL;
        char lmd[700];
        int larray = 0;
        s = group_attrs(a, "labels", &la, lmd, sizeof lmd, &larray);
        if (s == VV_OK && la && json_object_get(la, "labels"))
            s = read_labels(a, path, "labels", la, lmd, out);
        json_decref(la);
    } else if (pl) {
        out->kind = VV_OME_ZARR_PLATE;
        s = read_plate(a, pl, md, out);
    } else if (well) {
        out->kind = VV_OME_ZARR_WELL;
        out->wells = calloc(1, sizeof *out->wells);
        if (!out->wells)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        else if ((s = read_well(a, "", out->wells)) == VV_OK)
            out->n_wells = 1;
    } else if (json_object_get(attrs, "labels")) {
        out->kind = VV_OME_ZARR_LABELS;
        s = read_labels(a, path, "", attrs, md, out);
    } else {
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: no multiscales, plate, well or labels (not an OME-Zarr group)", md);
    }
    json_decref(attrs);
    free(a);
    if (s != VV_OK)
        vv_ome_zarr_contents_clear(out);
    return s;
}

vv_status
vv_ome_zarr_contents_get(const char *path, vv_ome_zarr_contents *out) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "zarr: NULL argument");
    const vv_status s = contents_get(path, out);
    return s == VV_OK ? s : vv_error_prefix(s, "zarr: %s", bs_name(path));
}

void
vv_ome_zarr_contents_clear(vv_ome_zarr_contents *c) {
    if (!c)
        return;
    free(c->labels);
    free(c->wells);
    memset(c, 0, sizeof *c);
}

vv_status
zr_refuse_group(const char *root, void *attrs, const char *md) {
    json_t *j = attrs;
    const int plate = json_object_get(j, "plate") != NULL,
              well = json_object_get(j, "well") != NULL,
              labels = json_object_get(j, "labels") != NULL;
    if (!plate && !well && !labels)
        return VV_OK;
    vv_ome_zarr_contents c;
    vv_status s = contents_get(root, &c);
    if (s != VV_OK) /* its own refusal (a hostile path) */
        return s;
    char first[2 * VV_OME_ZARR_NAME_MAX + 2] = "";
    for (int i = 0; i < c.n_wells && !first[0]; i++)
        if (c.wells[i].first_field[0])
            snprintf(first, sizeof first, "%s%s%s", c.wells[i].path, c.wells[i].path[0] ? "/" : "",
                     c.wells[i].first_field);
    if (c.kind == VV_OME_ZARR_PLATE)
        s = first[0] ? vv_error_set(VV_ERR_FORMAT,
                                    "%s: an HCS plate of %d x %d wells, not an image: name one "
                                    "field's path (the first: %s/%s)",
                                    md, c.n_rows, c.n_columns, root, first)
                     : vv_error_set(VV_ERR_FORMAT,
                                    "%s: an HCS plate of %d x %d wells, none with a field", md,
                                    c.n_rows, c.n_columns);
    else if (c.kind == VV_OME_ZARR_WELL)
        s = first[0] ? vv_error_set(VV_ERR_FORMAT,
                                    "%s: a well of an HCS plate, not an image: name one field's "
                                    "path (the first: %s/%s)",
                                    md, root, first)
                     : vv_error_set(VV_ERR_FORMAT, "%s: a well of an HCS plate without fields", md);
    else if (c.kind == VV_OME_ZARR_LABELS)
        s = c.n_labels ? vv_error_set(VV_ERR_FORMAT,
                                      "%s: a labels group, not an image: name one label image's "
                                      "path (the first: %s/%s)",
                                      md, root, c.labels[0].name)
                       : vv_error_set(VV_ERR_FORMAT, "%s: an empty labels group", md);
    else
        s = VV_OK;
    vv_ome_zarr_contents_clear(&c);
    return s;
}
