/*
 * VTK XML image data (.vti, ParaView's image format) read through libxml2
 * ("VTK File Formats", XML file formats, ImageData): one Piece covering the
 * WholeExtent, the point data's scalars (the array PointData's Scalars
 * attribute names, else the first), its components the file's channels.
 * The file-level work (no entities, the appended data cut out, base64,
 * zlib blocks, header words) is the .vtu reader's (grid_vtu.c,
 * vv_vtkxml_open and vv_vtkxml_array_bytes).
 *
 * Hostile files: the extent, component count and type are checked, and the
 * array's size against what the file can hold, before anything that size
 * is allocated; the decoded bytes must be exactly the size the extent and
 * type give.
 */
#include <libxml/parser.h>
#include <libxml/tree.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "io/grid/grid_io_internal.h"
#include "io/volume/vti.h"
#include "volvis/volume.h"

/* Largest .vti file read (it is held in memory while it is decoded). */
#define VTI_FILE_MAX (36ull << 30)
/* Components of one array at most. */
#define VTI_MAX_COMPONENTS 64

static char *
prop(xmlNode *n, const char *name) {
    return (char *)xmlGetProp(n, (const xmlChar *)name);
}

/* Attribute @p name of @p n as exactly @p count numbers into @p out; absent:
 * 0 (out untouched), present and well-formed: 1, else -1. */
static int
numbers(xmlNode *n, const char *name, int count, double *out) {
    char *s = prop(n, name);
    if (!s)
        return 0;
    const char *p = s;
    int k = 0, ok = 1;
    for (; k < count && ok; k++) {
        char *end;
        out[k] = strtod(p, &end);
        ok = end != p && isfinite(out[k]);
        p = end;
    }
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r')
        p++;
    ok = ok && *p == '\0';
    xmlFree(s);
    return ok ? 1 : -1;
}

static int
voxel_type(vv_gtype g, vv_voxel_type *t) {
    switch (g) {
    case VV_GT_I8:
        *t = VV_I8;
        return 1;
    case VV_GT_U8:
        *t = VV_U8;
        return 1;
    case VV_GT_I16:
        *t = VV_I16;
        return 1;
    case VV_GT_U16:
        *t = VV_U16;
        return 1;
    case VV_GT_I32:
        *t = VV_I32;
        return 1;
    case VV_GT_U32:
        *t = VV_U32;
        return 1;
    case VV_GT_F32:
        *t = VV_F32;
        return 1;
    case VV_GT_F64:
        *t = VV_F64;
        return 1;
    default:
        return 0;
    }
}

static int
host_big_endian(void) {
    const uint16_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 0;
}

/* The ImageData's geometry into @p v's place: dims from WholeExtent, and
 * the one Piece covering it. */
static vv_status
image_geometry(xmlNode *img, int dims[3], double origin[3], double spacing[3], double direction[9],
               xmlNode **piece) {
    double ext[6], pext[6];
    if (numbers(img, "WholeExtent", 6, ext) != 1)
        return vv_error_set(VV_ERR_FORMAT, "ImageData without a WholeExtent of six integers");
    for (int a = 0; a < 3; a++) {
        const double n = ext[2 * a + 1] - ext[2 * a] + 1;
        if (ext[2 * a] != floor(ext[2 * a]) || ext[2 * a + 1] != floor(ext[2 * a + 1]) ||
            fabs(ext[2 * a]) > 1e9 || !(n >= 1))
            return vv_error_set(VV_ERR_FORMAT, "WholeExtent %g..%g on axis %d", ext[2 * a],
                                ext[2 * a + 1], a);
        if (n > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT, "WholeExtent: %.0f points on axis %d (at most %d)", n,
                                a, VV_VOLUME_MAX_DIM);
        dims[a] = (int)n;
    }
    double o[3] = {0, 0, 0}, d[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    spacing[0] = spacing[1] = spacing[2] = 1;
    if (numbers(img, "Origin", 3, o) < 0 || numbers(img, "Spacing", 3, spacing) < 0 ||
        numbers(img, "Direction", 9, d) < 0)
        return vv_error_set(VV_ERR_FORMAT, "ImageData's Origin, Spacing or Direction is not 3, 3 "
                                           "or 9 numbers");
    for (int a = 0; a < 3; a++)
        if (!(spacing[a] > 0))
            return vv_error_set(VV_ERR_FORMAT, "Spacing %g on axis %d (must be > 0)", spacing[a],
                                a);
    /* the extent's first point: Origin + Direction (first index x spacing) */
    for (int r = 0; r < 3; r++) {
        origin[r] = o[r];
        for (int a = 0; a < 3; a++)
            origin[r] += d[3 * r + a] * ext[2 * a] * spacing[a];
    }
    memcpy(direction, d, sizeof d);
    *piece = NULL;
    for (xmlNode *c = img->children; c; c = c->next) {
        if (c->type != XML_ELEMENT_NODE || strcmp((const char *)c->name, "Piece"))
            continue;
        if (*piece)
            return vv_error_set(VV_ERR_UNSUPPORTED, "several pieces are not supported");
        *piece = c;
    }
    if (!*piece)
        return vv_error_set(VV_ERR_FORMAT, "ImageData without a Piece");
    if (numbers(*piece, "Extent", 6, pext) != 1 || memcmp(pext, ext, sizeof ext) != 0)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "the Piece's Extent is not the WholeExtent (pieces of a larger image "
                            "are not supported)");
    return VV_OK;
}

/* The point-data array to read: PointData's Scalars, else its first. */
static vv_status
scalars_array(xmlNode *piece, xmlNode **da) {
    xmlNode *pd = vv_vtkxml_child(piece, "PointData");
    char *want = pd ? prop(pd, "Scalars") : NULL;
    *da = NULL;
    for (xmlNode *c = pd ? pd->children : NULL; c && !*da; c = c->next) {
        if (c->type != XML_ELEMENT_NODE || strcmp((const char *)c->name, "DataArray"))
            continue;
        char *nm = prop(c, "Name");
        if (!want || (nm && !strcmp(nm, want)))
            *da = c;
        xmlFree(nm);
    }
    vv_status s = VV_OK;
    if (!*da && want)
        s = vv_error_set(VV_ERR_FORMAT, "PointData names Scalars \"%s\", which it does not hold",
                         want);
    else if (!*da)
        s = vv_error_set(vv_vtkxml_child(piece, "CellData") ? VV_ERR_UNSUPPORTED : VV_ERR_FORMAT,
                         "no point data (cell data are not read as voxels)");
    xmlFree(want);
    return s;
}

/* Component @p c of the @p nv tuples of @p comps components (each @p sz
 * bytes, @p swap: the other byte order) in @p raw into @p dst. */
static void
copy_component(unsigned char *dst, const unsigned char *raw, size_t nv, int comps, int c, size_t sz,
               int swap) {
    if (comps == 1 && !swap) {
        memcpy(dst, raw, nv * sz);
        return;
    }
    const size_t stride = (size_t)comps * sz;
    const unsigned char *src = raw + (size_t)c * sz;
    for (size_t i = 0; i < nv; i++, src += stride, dst += sz)
        for (size_t b = 0; b < sz; b++)
            dst[b] = src[swap ? sz - 1 - b : b];
}

/* Reads the array's component into a new volume of @p dims. */
static vv_status
read_array(const vv_vtkxml *x, xmlNode *da, uint64_t file_size, const int dims[3], int channel,
           vv_load_info *info, vv_volume **out) {
    char *type = prop(da, "type"), *fmt = prop(da, "format"), *nc = prop(da, "NumberOfComponents"),
         *name = prop(da, "Name");
    const char *nm = name ? name : "(unnamed)";
    vv_status s = VV_OK;
    vv_gtype g;
    vv_voxel_type vt = VV_U8;
    char *end = NULL;
    long comps = nc ? strtol(nc, &end, 10) : 1;
    unsigned char *raw = NULL;
    double *vals = NULL;
    vv_volume *v = NULL;
    if (!type || !vv_gtype_parse(type, &g)) {
        s = vv_error_set(VV_ERR_FORMAT, "DataArray %s: type \"%s\"", nm, type ? type : "");
        goto done;
    }
    if (!voxel_type(g, &vt)) {
        s = vv_error_set(VV_ERR_UNSUPPORTED,
                         "DataArray %s: type %s (voxels are 8-, 16- or 32-bit integers or "
                         "floats)",
                         nm, type);
        goto done;
    }
    if ((nc && (end == nc || *end)) || comps < 1 || comps > VTI_MAX_COMPONENTS) {
        s = vv_error_set(VV_ERR_FORMAT, "DataArray %s: NumberOfComponents \"%s\" (1..%d)", nm,
                         nc ? nc : "", VTI_MAX_COMPONENTS);
        goto done;
    }
    if (info) {
        info->n_channels = (int)comps;
        char key[32];
        snprintf(key, sizeof key, "ComponentName%d", channel);
        char *cn = prop(da, key);
        if (cn)
            snprintf(info->channel_name, sizeof info->channel_name, "%s", cn);
        xmlFree(cn);
    }
    if (channel >= comps) {
        s = vv_error_set(VV_ERR_INVALID, "channel %d asked, the scalars have %ld component%s",
                         channel, comps, comps == 1 ? "" : "s");
        goto done;
    }
    const size_t nv = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
    const size_t sz = vv_voxel_type_size(vt);
    if ((double)nv * (double)comps * (double)sz > (double)VV_VOLUME_MAX_BYTES * 4) {
        s = vv_error_set(VV_ERR_LIMIT, "DataArray %s: %zu x %ld values are over the limits", nm, nv,
                         comps);
        goto done;
    }
    const size_t nbytes = nv * (size_t)comps * sz;
    const int ascii = fmt && !strcmp(fmt, "ascii");
    /* what the file can hold: a value in text takes two characters at least,
     * a compressed byte expands to about 1032 at most */
    if ((ascii ? 2.0 * (double)nv * (double)comps - 1 : (double)nbytes) >
        (x->zlib && !ascii ? 1032.0 : 1.0) * (double)file_size + 64) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "DataArray %s: %d x %d x %d points of %ld %s cannot fit in the file's "
                         "%llu bytes (truncated?)",
                         nm, dims[0], dims[1], dims[2], comps, type, (unsigned long long)file_size);
        goto done;
    }
    if ((s = vv_volume_new(&v, dims, vt)) != VV_OK)
        goto done;
    if (ascii) {
        vals = malloc(nv * (size_t)comps * sizeof *vals);
        if (!vals) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            goto done;
        }
        xmlChar *text = xmlNodeGetContent(da);
        vv_gcur cur;
        vv_gcur_init(&cur, text ? text : (const xmlChar *)"", text ? strlen((char *)text) : 0,
                     x->path);
        s = vv_gcur_values(&cur, 0, 0, g, nv * (size_t)comps, vals, nm);
        xmlFree(text);
        size_t i = 0;
        for (int k = 0; s == VV_OK && k < dims[2]; k++)
            for (int j = 0; j < dims[1]; j++)
                for (int ii = 0; ii < dims[0]; ii++, i++)
                    vv_volume_set(v, ii, j, k, vals[i * (size_t)comps + (size_t)channel]);
    } else if ((s = vv_vtkxml_array_bytes(x, da, nbytes, nm, &raw)) == VV_OK) {
        copy_component(v->data, raw, nv, (int)comps, channel, sz,
                       sz > 1 && x->big_endian != host_big_endian());
    }
done:
    free(raw);
    free(vals);
    xmlFree(type);
    xmlFree(fmt);
    xmlFree(nc);
    xmlFree(name);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    *out = v;
    return VV_OK;
}

vv_status
vv_vti_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "vti: NULL argument");
    *out = NULL;
    const char *base = vv_path_basename(path);
    unsigned char *data = NULL, *xml = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, VTI_FILE_MAX, &data, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "vti: %s", base);
    vv_vtkxml x = {path, 0, 0, 0, NULL, 0, 0};
    xmlDoc *doc = NULL;
    xmlNode *img = NULL, *piece = NULL, *da = NULL;
    int dims[3];
    double origin[3], spacing[3], direction[9];
    vv_volume *v = NULL;
    vv_load_info *info = opt ? opt->info : NULL;
    const int channel = opt && opt->channel > 0 ? opt->channel : 0;
    if (info) {
        info->n_channels = info->n_times = 1;
        info->channel_name[0] = '\0';
    }
    if ((s = vv_vtkxml_open(&x, data, size, "ImageData", &doc, &xml, &img)) == VV_OK &&
        (s = image_geometry(img, dims, origin, spacing, direction, &piece)) == VV_OK &&
        (s = scalars_array(piece, &da)) == VV_OK)
        s = read_array(&x, da, size, dims, channel, info, &v);
    if (doc)
        xmlFreeDoc(doc);
    if (xml && xml != data)
        free(xml);
    free(data);
    if (s == VV_OK && opt && opt->time > 0) {
        s = vv_error_set(VV_ERR_INVALID, "time step %d asked, the file has 1 time step", opt->time);
    }
    if (s != VV_OK) {
        vv_volume_free(v);
        /* vv_vtkxml_open's messages name the path already */
        const char *m = vv_error_message();
        if (!strncmp(m, path, strlen(path)))
            return s;
        return vv_error_prefix(s, "vti: %s", base);
    }
    memcpy(v->origin, origin, sizeof origin);
    memcpy(v->spacing, spacing, sizeof spacing);
    memcpy(v->direction, direction, sizeof direction);
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

int
vv_vti_looks_like(const vv_format_probe *p, int deep) {
    return !deep && !p->is_dir && strstr(p->text, "<VTKFile") && strstr(p->text, "\"ImageData\"");
}
