/*
 * HDF5 multiresolution pyramids through libhdf5: BigDataViewer's layout
 * (Pietzsch et al., Nature Methods 12, 2015: t<TTTTT>/s<SS>/<level>/cells,
 * s<SS>/resolutions, s<SS>/subdivisions) and Imaris 5.5's (DataSet/
 * ResolutionLevel N/TimePoint T/Channel C/Data, DataSetInfo/Image's extents).
 *
 * Two users: the format record "hdf5" (one level read whole, in the
 * reader sandbox like every third-party parser) and the pyramid's store
 * (src/io/store/pyramid.h), opened in the long-lived sandboxed readers
 * (vv_sandbox_open_store, src/sandbox/store.c) or, with VOLVIS_SANDBOX=0, in
 * this process.
 *
 * Geometry. BigDataViewer: level l of factors f (s00/resolutions) has
 * spacing f times level 0's voxel size and its voxel 0 at (f - 1) / 2 of
 * them, BigDataViewer's mipmap transform. The voxel size and its unit are
 * the companion XML's (NAME.xml beside NAME.h5, as BigDataViewer and Fiji
 * write them: SpimData/SequenceDescription/ViewSetups/ViewSetup[id]/
 * voxelSize, read through libxml2); without one a voxel is 1 unit a side.
 * A 16-bit signed "cells" dataset holds unsigned 16-bit voxels
 * (the format's convention), read bit for bit as u16. Imaris: the image
 * spans ExtMin .. ExtMax (DataSetInfo/Image), level l has ImageSizeX/Y/Z
 * voxels (its Channel group's attributes; the Data dataset may be padded
 * beyond them), so its spacing is the extent over the size and its voxel 0
 * sits half a voxel inside ExtMin.
 *
 * Thread-safety: Debian's libhdf5 is not built thread-safe; one h5p is
 * used from one thread at a time, and two open at once must not be used
 * concurrently.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <hdf5.h>
#include <libxml/parser.h>
#include <libxml/tree.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/store/pyramid.h"
#include "volvis/sys/format.h"

#define H5P_MAX_CHUNK 128 /* the store's chunk box at most, a side */

/* One level as the reader found it. */
typedef struct h5p_level {
    int dims[3];       /* voxels along x, y, z */
    int cdims[3];      /* the chunk box the store reads by (the dataset's chunks) */
    int hchunk[3];     /* the dataset's own HDF5 chunk; 0: contiguous */
    double spacing[3]; /* in the XML's or the file's units (Imaris), else level-0 voxels */
    double origin[3];  /* the centre of voxel 0 */
    int unit;          /* vv_unit of the spacing (the XML's or Imaris's; else unknown) */
    int has_range;     /* 1: range is the data's (Imaris's HistogramMin/Max) */
    double range[2];
} h5p_level;

typedef struct h5p {
    char file[256]; /* its base name, for errors */
    hid_t fid;
    int kind; /* 1 BigDataViewer, 2 Imaris */
    int n_levels, n_channels, n_times;
    hid_t dset[VV_PYRAMID_MAX_LEVELS];
    h5p_level lv[VV_PYRAMID_MAX_LEVELS];
    hid_t mtype; /* the memory type read */
    vv_voxel_type type;
    hid_t lapl, dapl, gapl; /* link, dataset and group access: never through an external link */
    char elink[256];        /* the file an external link named ("": none met) */
} h5p;

/* An external link would open another file, anywhere: refused (the name
 * kept for the message). */
static herr_t
refuse_elink(const char *parent_file, const char *parent_group, const char *child_file,
             const char *child_object, unsigned *acc_flags, hid_t fapl, void *op) {
    (void)parent_file;
    (void)parent_group;
    (void)child_object;
    (void)acc_flags;
    (void)fapl;
    h5p *h = op;
    snprintf(h->elink, sizeof h->elink, "%s", child_file ? child_file : "?");
    return -1;
}

static int
link_exists(const h5p *h, const char *path) {
    return H5Lexists(h->fid, path, h->lapl) > 0;
}

/* 1 when dataset @p d's voxels lie in other files: a virtual dataset or
 * external raw storage (H5Pset_external), paths the file chooses. */
static int
data_elsewhere(hid_t d) {
    hid_t pl = H5Dget_create_plist(d);
    const int out = pl < 0 || H5Pget_layout(pl) == H5D_VIRTUAL || H5Pget_external_count(pl) != 0;
    if (pl >= 0)
        H5Pclose(pl);
    return out;
}

/* The voxel type of a dataset's type, the memory type to read it with;
 * @p bdv: a signed 16-bit dataset holds unsigned voxels. -1: not one of
 * ours. */
static int
type_of(hid_t ftype, int bdv, hid_t *mtype) {
    const H5T_class_t cl = H5Tget_class(ftype);
    const size_t sz = H5Tget_size(ftype);
    if (cl == H5T_INTEGER) {
        const int sgn = H5Tget_sign(ftype) == H5T_SGN_2;
        if (sz == 1) {
            *mtype = sgn ? H5T_NATIVE_INT8 : H5T_NATIVE_UINT8;
            return sgn ? VV_I8 : VV_U8;
        }
        if (sz == 2) {
            if (sgn && bdv) { /* the bits as they are: no conversion clamps them */
                *mtype = H5T_NATIVE_INT16;
                return VV_U16;
            }
            *mtype = sgn ? H5T_NATIVE_INT16 : H5T_NATIVE_UINT16;
            return sgn ? VV_I16 : VV_U16;
        }
        if (sz == 4) {
            *mtype = sgn ? H5T_NATIVE_INT32 : H5T_NATIVE_UINT32;
            return sgn ? VV_I32 : VV_U32;
        }
        return -1;
    }
    if (cl == H5T_FLOAT && (sz == 4 || sz == 8)) {
        *mtype = sz == 4 ? H5T_NATIVE_FLOAT : H5T_NATIVE_DOUBLE;
        return sz == 4 ? VV_F32 : VV_F64;
    }
    return -1;
}

/* Dataset @p path's dims (x, y, z from its z, y, x), HDF5 chunk (0:
 * contiguous) and the chunk box the store reads by (the HDF5 chunk within
 * 8 .. H5P_MAX_CHUNK, else 64), opened into *d. */
static vv_status
open_volume(h5p *h, const char *path, hid_t *d, h5p_level *L) {
    int *dims = L->dims, *cdims = L->cdims;
    h->elink[0] = '\0';
    if (!link_exists(h, path) || (*d = H5Dopen2(h->fid, path, h->dapl)) < 0)
        return h->elink[0] ? vv_error_set(VV_ERR_FORMAT,
                                          "%s: an external link to \"%s\" (no other file is "
                                          "read)",
                                          path, h->elink)
                           : vv_error_set(VV_ERR_FORMAT, "no dataset %s", path);
    if (data_elsewhere(*d))
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: a virtual dataset or external storage (its voxels lie in other "
                            "files, never read)",
                            path);
    hid_t sp = H5Dget_space(*d);
    hsize_t sh[4] = {0};
    const int nd = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
    if (nd == 3)
        H5Sget_simple_extent_dims(sp, sh, NULL);
    H5Sclose(sp);
    if (nd != 3)
        return vv_error_set(VV_ERR_FORMAT, "%s: %d dimensions, not 3 (z, y, x)", path, nd);
    for (int k = 0; k < 3; k++) {
        if (sh[2 - k] < 1 || sh[2 - k] > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT, "%s: %llu voxels along axis %d (1 .. %d allowed)",
                                path, (unsigned long long)sh[2 - k], k, VV_VOLUME_MAX_DIM);
        dims[k] = (int)sh[2 - k];
        cdims[k] = 64;
        L->hchunk[k] = 0;
    }
    hid_t pl = H5Dget_create_plist(*d);
    hsize_t ch[4] = {0};
    if (pl >= 0 && H5Pget_layout(pl) == H5D_CHUNKED && H5Pget_chunk(pl, 3, ch) == 3)
        for (int k = 0; k < 3; k++) { /* whole HDF5 chunks, within 8 .. H5P_MAX_CHUNK */
            L->hchunk[k] = ch[2 - k] <= (hsize_t)VV_VOLUME_MAX_DIM ? (int)ch[2 - k] : 0;
            cdims[k] = ch[2 - k] < 8 ? (int)(8 / ch[2 - k] + (8 % ch[2 - k] != 0)) * (int)ch[2 - k]
                       : ch[2 - k] > H5P_MAX_CHUNK ? H5P_MAX_CHUNK
                                                   : (int)ch[2 - k];
        }
    if (pl >= 0)
        H5Pclose(pl);
    return VV_OK;
}

/* A small dataset of @p n doubles in a row-major (levels, 3) table. */
static int
read_table(h5p *h, const char *path, hid_t mtype, void *buf, int max_rows, int *rows) {
    hid_t d = link_exists(h, path) ? H5Dopen2(h->fid, path, h->dapl) : -1;
    if (d < 0)
        return 0;
    if (data_elsewhere(d)) {
        H5Dclose(d);
        return 0;
    }
    hid_t sp = H5Dget_space(d);
    hsize_t sh[2] = {0, 0};
    int ok = sp >= 0 && H5Sget_simple_extent_ndims(sp) == 2 &&
             H5Sget_simple_extent_dims(sp, sh, NULL) == 2 && sh[1] == 3 && sh[0] >= 1 &&
             sh[0] <= (hsize_t)max_rows;
    if (ok)
        ok = H5Dread(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0;
    if (ok)
        *rows = (int)sh[0];
    if (sp >= 0)
        H5Sclose(sp);
    H5Dclose(d);
    return ok;
}

/* BigDataViewer's layout: setup @p channel (s%02d) at time point @p time
 * (t%05d); @p ids 1: the setup and time point are ids the caller has (a
 * dataset XML's), not counted from s00 and t00000 (the store then holds one
 * of each). */
static vv_status
open_bdv(h5p *h, int channel, int time, int ids) {
    const int setup = channel < 0 ? 0 : channel, t = time < 0 ? 0 : time;
    char path[256];
    if (ids) {
        h->n_channels = h->n_times = 1;
        snprintf(path, sizeof path, "t%05d/s%02d", t, setup);
        if (setup > 99 || t > 99999 || !link_exists(h, path))
            return vv_error_set(VV_ERR_FORMAT, "no setup %d at time point %d (t%05d/s%02d)", setup,
                                t, t, setup);
        goto levels;
    }
    h->n_channels = 0;
    for (int s = 0; s < 100; s++) {
        snprintf(path, sizeof path, "s%02d", s);
        if (!link_exists(h, path))
            break;
        h->n_channels = s + 1;
    }
    h->n_times = 0;
    for (int k = 0; k < 100000; k++) {
        snprintf(path, sizeof path, "t%05d", k);
        if (!link_exists(h, path))
            break;
        h->n_times = k + 1;
    }
    if (setup >= h->n_channels)
        return vv_error_set(VV_ERR_INVALID, "channel %d asked, the file has %d setups (s00 ..)",
                            setup, h->n_channels);
    if (t >= h->n_times)
        return vv_error_set(VV_ERR_INVALID, "time step %d asked, the file has %d (t00000 ..)", t,
                            h->n_times);
levels:;
    double res[VV_PYRAMID_MAX_LEVELS][3];
    int sub[VV_PYRAMID_MAX_LEVELS][3], nr = 0, ns = 0;
    snprintf(path, sizeof path, "s%02d/resolutions", setup);
    if (!read_table(h, path, H5T_NATIVE_DOUBLE, res, VV_PYRAMID_MAX_LEVELS, &nr))
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: missing, or not a table of (x, y, z) factors "
                            "of 1 .. 16 levels",
                            path);
    snprintf(path, sizeof path, "s%02d/subdivisions", setup);
    const int has_sub =
        read_table(h, path, H5T_NATIVE_INT, sub, VV_PYRAMID_MAX_LEVELS, &ns) && ns == nr;
    h->n_levels = nr;
    for (int l = 0; l < nr; l++) {
        h5p_level *L = &h->lv[l];
        snprintf(path, sizeof path, "t%05d/s%02d/%d/cells", t, setup, l);
        vv_status s = open_volume(h, path, &h->dset[l], L);
        if (s != VV_OK)
            return s;
        for (int k = 0; k < 3; k++) {
            const double f = res[l][k];
            if (!(f >= 1 && f <= 65536) || (l > 0 && f < res[l - 1][k]))
                return vv_error_set(VV_ERR_FORMAT,
                                    "s%02d/resolutions: level %d's factor %g along axis %d "
                                    "(inconsistent multiscales)",
                                    setup, l, f, k);
            L->spacing[k] = f;
            L->origin[k] = 0.5 * (f - 1);
            if (has_sub && sub[l][k] >= 8 && sub[l][k] <= H5P_MAX_CHUNK)
                L->cdims[k] = sub[l][k];
        }
    }
    return VV_OK;
}

/* Text of the first child element @p name of @p n, or NULL (xmlFree it). */
static char *
xml_child_text(xmlNode *n, const char *name) {
    for (xmlNode *c = n ? n->children : NULL; c; c = c->next)
        if (c->type == XML_ELEMENT_NODE && strcmp((const char *)c->name, name) == 0)
            return (char *)xmlNodeGetContent(c);
    return NULL;
}

static xmlNode *
xml_child(xmlNode *n, const char *name) {
    for (xmlNode *c = n ? n->children : NULL; c; c = c->next)
        if (c->type == XML_ELEMENT_NODE && strcmp((const char *)c->name, name) == 0)
            return c;
    return NULL;
}

/* The voxel size of setup @p setup from BigDataViewer's companion XML
 * (NAME.xml beside NAME.h5). No companion, one that is not SpimData or
 * whose ImageLoader names another HDF5 file: level 0's voxel stays 1 unit
 * (VV_OK). A companion that cannot be parsed, or whose setup's voxelSize is
 * not three positive finite numbers: VV_ERR_FORMAT naming the XML. */
static vv_status
bdv_voxel_size(h5p *h, const char *path, int setup) {
    char xml[4096];
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    const size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - path) : strlen(path);
    if (stem + 5 > sizeof xml)
        return VV_OK;
    memcpy(xml, path, stem);
    memcpy(xml + stem, ".xml", 5);
    const char *xname = vv_path_basename(xml);
    struct stat xs;
    if (stat(xml, &xs) != 0)
        return VV_OK;
    if (!S_ISREG(xs.st_mode)) /* a FIFO would block the open */
        return vv_error_set(VV_ERR_FORMAT, "%s: the companion XML is not a regular file", xname);
    FILE *f = fopen(xml, "rb");
    if (!f)
        return VV_OK;
    fseek(f, 0, SEEK_END);
    const long size = ftell(f);
    fclose(f);
    if (size < 0 || size > (64L << 20))
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: %ld bytes, over the 64 MiB a companion XML may have", xname, size);
    int doctype = 0;
    xmlDoc *doc = vv_bdv_xml_read(xml, &doctype);
    xmlNode *root = doc ? xmlDocGetRootElement(doc) : NULL;
    if (!root) {
        xmlFreeDoc(doc);
        return vv_error_set(VV_ERR_FORMAT, "%s: the companion XML %s", xname,
                            doctype ? "has a <!DOCTYPE> (entities and DTDs are refused)"
                                    : "cannot be parsed");
    }
    vv_status st = VV_OK;
    xmlNode *seq = xml_child(root, "SequenceDescription");
    char *loader = xml_child_text(xml_child(seq, "ImageLoader"), "hdf5");
    const int other = loader && strcmp(vv_path_basename(loader), vv_path_basename(path)) != 0;
    xmlFree(loader);
    if (strcmp((const char *)root->name, "SpimData") != 0 || other) {
        xmlFreeDoc(doc);
        return VV_OK;
    }
    for (xmlNode *vs = xml_child(xml_child(seq, "ViewSetups"), "ViewSetup"); vs; vs = vs->next) {
        if (vs->type != XML_ELEMENT_NODE || strcmp((const char *)vs->name, "ViewSetup") != 0)
            continue;
        char *id = xml_child_text(vs, "id");
        const int mine = id && atoi(id) == setup;
        xmlFree(id);
        xmlNode *vox = mine ? xml_child(vs, "voxelSize") : NULL;
        if (!vox)
            continue;
        char *text = xml_child_text(vox, "size"), *unit = xml_child_text(vox, "unit");
        double d[3];
        char tail = 0;
        if (!text || sscanf(text, "%lf %lf %lf %c", &d[0], &d[1], &d[2], &tail) != 3 ||
            !(d[0] > 0 && d[1] > 0 && d[2] > 0 && d[0] < 1e30 && d[1] < 1e30 && d[2] < 1e30))
            st = vv_error_set(VV_ERR_FORMAT,
                              "%s: ViewSetup %d's voxelSize \"%s\" is not three positive "
                              "numbers",
                              xname, setup, text ? text : "");
        else
            for (int l = 0; l < h->n_levels; l++) {
                for (int k = 0; k < 3; k++) {
                    h->lv[l].spacing[k] *= d[k];
                    h->lv[l].origin[k] *= d[k];
                }
                h->lv[l].unit = unit ? (int)vv_unit_parse(unit) : (int)VV_UNIT_UNKNOWN;
            }
        xmlFree(text);
        xmlFree(unit);
        break;
    }
    xmlFreeDoc(doc);
    return st;
}

/* Attribute @p name of @p obj as text: Imaris writes numbers as arrays of
 * one-byte strings ("5", "1", "2"); a fixed-length string is read alike. */
static int
attr_text(hid_t obj, const char *name, char *buf, size_t cap) {
    if (H5Aexists(obj, name) <= 0)
        return 0;
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    hid_t ft = a >= 0 ? H5Aget_type(a) : -1, sp = a >= 0 ? H5Aget_space(a) : -1;
    int ok = 0;
    if (ft >= 0 && sp >= 0 && H5Tget_class(ft) == H5T_STRING && !H5Tis_variable_str(ft)) {
        const hssize_t np = H5Sget_simple_extent_npoints(sp);
        const size_t sz = H5Tget_size(ft);
        if (np >= 1 && sz >= 1 && (uint64_t)np < cap && sz < cap && (size_t)np * sz < cap) {
            hid_t mt = H5Tcopy(H5T_C_S1);
            H5Tset_size(mt, sz);
            H5Tset_strpad(mt, H5T_STR_NULLPAD);
            memset(buf, 0, cap);
            ok = H5Aread(a, mt, buf) >= 0;
            H5Tclose(mt);
            /* the pieces joined, NUL padding removed */
            size_t n = 0;
            for (size_t i = 0; ok && i < (size_t)np * sz; i++)
                if (buf[i])
                    buf[n++] = buf[i];
            buf[n] = '\0';
        }
    }
    if (ft >= 0)
        H5Tclose(ft);
    if (sp >= 0)
        H5Sclose(sp);
    if (a >= 0)
        H5Aclose(a);
    return ok;
}

static int
attr_number(hid_t obj, const char *name, double *x) {
    char t[64], *end;
    if (!attr_text(obj, name, t, sizeof t))
        return 0;
    errno = 0;
    *x = strtod(t, &end);
    return end != t && *end == '\0' && errno == 0 && isfinite(*x);
}

static vv_status
open_ims(h5p *h, int channel, int time) {
    const int c = channel < 0 ? 0 : channel, t = time < 0 ? 0 : time;
    char path[256];
    h->n_levels = 0;
    for (int l = 0; l < VV_PYRAMID_MAX_LEVELS + 1; l++) {
        snprintf(path, sizeof path, "DataSet/ResolutionLevel %d", l);
        if (!link_exists(h, path))
            break;
        h->n_levels = l + 1;
    }
    if (h->n_levels > VV_PYRAMID_MAX_LEVELS)
        return vv_error_set(VV_ERR_LIMIT, "more than %d resolution levels", VV_PYRAMID_MAX_LEVELS);
    h->n_times = h->n_channels = 0;
    for (int k = 0; k < 100000; k++) {
        snprintf(path, sizeof path, "DataSet/ResolutionLevel 0/TimePoint %d", k);
        if (!link_exists(h, path))
            break;
        h->n_times = k + 1;
    }
    for (int k = 0; k < 1000; k++) {
        snprintf(path, sizeof path, "DataSet/ResolutionLevel 0/TimePoint 0/Channel %d", k);
        if (!link_exists(h, path))
            break;
        h->n_channels = k + 1;
    }
    if (c >= h->n_channels)
        return vv_error_set(VV_ERR_INVALID, "channel %d asked, the file has %d", c, h->n_channels);
    if (t >= h->n_times)
        return vv_error_set(VV_ERR_INVALID, "time step %d asked, the file has %d", t, h->n_times);
    /* the extent, when the image's attributes give it */
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    int has_ext = link_exists(h, "DataSetInfo") && link_exists(h, "DataSetInfo/Image");
    hid_t img = has_ext ? H5Gopen2(h->fid, "DataSetInfo/Image", h->gapl) : -1;
    for (int k = 0; k < 3 && img >= 0; k++) {
        char a[32], b[32];
        snprintf(a, sizeof a, "ExtMin%d", k);
        snprintf(b, sizeof b, "ExtMax%d", k);
        has_ext = has_ext && attr_number(img, a, &lo[k]) && attr_number(img, b, &hi[k]);
    }
    char unit[64] = "";
    if (img >= 0 && attr_text(img, "Unit", unit, sizeof unit))
        h->lv[0].unit = (int)vv_unit_parse(unit);
    if (img >= 0)
        H5Gclose(img);
    for (int l = 0; l < h->n_levels; l++) {
        h5p_level *L = &h->lv[l];
        snprintf(path, sizeof path, "DataSet/ResolutionLevel %d/TimePoint %d/Channel %d/Data", l, t,
                 c);
        vv_status s = open_volume(h, path, &h->dset[l], L);
        if (s != VV_OK)
            return s;
        /* the image's size within the padded dataset */
        snprintf(path, sizeof path, "DataSet/ResolutionLevel %d/TimePoint %d/Channel %d", l, t, c);
        hid_t g = H5Gopen2(h->fid, path, h->gapl);
        for (int k = 0; k < 3 && g >= 0; k++) {
            static const char *const names[3] = {"ImageSizeX", "ImageSizeY", "ImageSizeZ"};
            double n;
            if (attr_number(g, names[k], &n)) {
                if (!(n >= 1 && n <= L->dims[k])) {
                    H5Gclose(g);
                    return vv_error_set(VV_ERR_FORMAT,
                                        "%s: %s %g outside the Data dataset's %d voxels", path,
                                        names[k], n, L->dims[k]);
                }
                L->dims[k] = (int)n;
            }
        }
        double r0, r1; /* the channel's value range, as Imaris computes it */
        if (l == 0 && g >= 0 && attr_number(g, "HistogramMin", &r0) &&
            attr_number(g, "HistogramMax", &r1) && r1 >= r0) {
            L->has_range = 1;
            L->range[0] = r0;
            L->range[1] = r1;
        }
        if (g >= 0)
            H5Gclose(g);
        L->unit = h->lv[0].unit;
        for (int k = 0; k < 3; k++) {
            const double sp = has_ext && hi[k] > lo[k] ? (hi[k] - lo[k]) / L->dims[k]
                                                       : (double)h->lv[0].dims[k] / L->dims[k];
            if (!(sp > 0) || !isfinite(sp))
                return vv_error_set(VV_ERR_FORMAT,
                                    "DataSetInfo/Image: ExtMin%d %g .. ExtMax%d %g over %d voxels "
                                    "is a spacing of %g (not positive and finite)",
                                    k, lo[k], k, hi[k], L->dims[k], sp);
            L->spacing[k] = sp;
            L->origin[k] = (has_ext ? lo[k] : 0) + 0.5 * sp;
            if (l > 0 && L->dims[k] > h->lv[0].dims[k])
                return vv_error_set(VV_ERR_FORMAT,
                                    "level %d: %d voxels along axis %d, more than level 0's %d "
                                    "(inconsistent multiscales)",
                                    l, L->dims[k], k, h->lv[0].dims[k]);
        }
    }
    return h->n_levels > 0 ? VV_OK : vv_error_set(VV_ERR_FORMAT, "no DataSet/ResolutionLevel 0");
}

static void
h5p_close(h5p *h) {
    if (!h)
        return;
    for (int l = 0; l < VV_PYRAMID_MAX_LEVELS; l++)
        if (h->dset[l] > 0)
            H5Dclose(h->dset[l]);
    if (h->fid > 0)
        H5Fclose(h->fid);
    const hid_t pl[3] = {h->lapl, h->dapl, h->gapl};
    for (int i = 0; i < 3; i++)
        if (pl[i] > 0)
            H5Pclose(pl[i]);
    free(h);
}

static vv_status
h5p_open(h5p **out, const char *path, int channel, int time, int ids) {
    *out = NULL;
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* errors are ours to report */
    h5p *h = calloc(1, sizeof *h);
    if (!h)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    snprintf(h->file, sizeof h->file, "%s", vv_path_basename(path));
    vv_status s = VV_OK;
    struct stat st;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) { /* libhdf5 would block on a FIFO */
        h5p_close(h);
        return vv_error_set(VV_ERR_FORMAT, "not a regular file");
    }
    h->lapl = H5Pcreate(H5P_LINK_ACCESS);
    h->dapl = H5Pcreate(H5P_DATASET_ACCESS);
    h->gapl = H5Pcreate(H5P_GROUP_ACCESS);
    if (h->lapl < 0 || h->dapl < 0 || h->gapl < 0 ||
        H5Pset_elink_cb(h->lapl, refuse_elink, h) < 0 ||
        H5Pset_elink_cb(h->dapl, refuse_elink, h) < 0 ||
        H5Pset_elink_cb(h->gapl, refuse_elink, h) < 0) {
        h5p_close(h);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    h->fid = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (h->fid < 0)
        s = vv_error_set(VV_ERR_IO, "cannot open it as an HDF5 file");
    else if (link_exists(h, "DataSet") && link_exists(h, "DataSet/ResolutionLevel 0"))
        h->kind = 2;
    else if (ids || (link_exists(h, "s00") && link_exists(h, "t00000")))
        h->kind = 1;
    else
        s = vv_error_set(VV_ERR_UNSUPPORTED, /* a plain HDF5 file: read whole */
                         "neither a BigDataViewer file (t00000/s00/0/cells) nor an Imaris one "
                         "(DataSet/ResolutionLevel 0)");
    if (s == VV_OK)
        s = h->kind == 1 ? open_bdv(h, channel, time, ids) : open_ims(h, channel, time);
    if (s == VV_OK && h->kind == 1 && !ids) /* a dataset XML gives the geometry itself */
        s = bdv_voxel_size(h, path, channel < 0 ? 0 : channel);
    for (int l = 0; l < h->n_levels && s == VV_OK; l++) {
        hid_t ft = H5Dget_type(h->dset[l]);
        hid_t mt = 0;
        const int t = ft >= 0 ? type_of(ft, h->kind == 1, &mt) : -1;
        if (ft >= 0)
            H5Tclose(ft);
        if (t < 0)
            s = vv_error_set(VV_ERR_UNSUPPORTED,
                             "level %d: a voxel type other than 8/16/32-bit integers or 32/64-bit "
                             "floats",
                             l);
        else if (l == 0) {
            h->type = (vv_voxel_type)t;
            h->mtype = mt;
        } else if ((vv_voxel_type)t != h->type)
            s = vv_error_set(VV_ERR_FORMAT,
                             "level %d: its type differs from level 0's (inconsistent "
                             "multiscales)",
                             l);
        for (int k = 0; k < 3 && s == VV_OK; k++)
            if (h->lv[l].dims[k] > h->lv[0].dims[k])
                s = vv_error_set(VV_ERR_FORMAT,
                                 "level %d: %d voxels along axis %d, more than level 0's %d "
                                 "(inconsistent multiscales)",
                                 l, h->lv[l].dims[k], k, h->lv[0].dims[k]);
    }
    if (s != VV_OK) {
        h5p_close(h);
        return s;
    }
    *out = h;
    return VV_OK;
}

static vv_status
h5p_read_box(h5p *h, int level, const int lo[3], const int dims[3], void *dst) {
    if (level < 0 || level >= h->n_levels)
        return vv_error_set(VV_ERR_INVALID, "level %d of %d", level, h->n_levels);
    for (int k = 0; k < 3; k++)
        if (lo[k] < 0 || dims[k] < 1 || lo[k] > h->lv[level].dims[k] - dims[k])
            return vv_error_set(VV_ERR_INVALID, "box %d + %d outside level %d's %d voxels", lo[k],
                                dims[k], level, h->lv[level].dims[k]);
    hsize_t start[3], count[3];
    for (int k = 0; k < 3; k++) {
        start[2 - k] = (hsize_t)lo[k];
        count[2 - k] = (hsize_t)dims[k];
    }
    hid_t fs = H5Dget_space(h->dset[level]);
    hid_t ms = H5Screate_simple(3, count, NULL);
    herr_t e =
        fs >= 0 && ms >= 0 ? H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) : -1;
    if (e >= 0)
        e = H5Dread(h->dset[level], h->mtype, ms, fs, H5P_DEFAULT, dst);
    if (ms >= 0)
        H5Sclose(ms);
    if (fs >= 0)
        H5Sclose(fs);
    if (e < 0)
        return vv_error_set(VV_ERR_FORMAT,
                            "level %d: the chunk at voxel (%d, %d, %d) does not read (a corrupt "
                            "or truncated dataset, or a filter libhdf5 lacks)",
                            level, lo[0], lo[1], lo[2]);
    return VV_OK;
}

/* ---- the format record: one level read whole -------------------------------- */

static void
h5p_geometry(const h5p_level *L, vv_volume *v) {
    for (int k = 0; k < 3; k++) {
        v->spacing[k] = L->spacing[k];
        v->origin[k] = L->origin[k];
    }
    v->unit = L->unit > 0 && L->unit <= VV_UNIT_LAST ? (vv_unit)L->unit : VV_UNIT_UNKNOWN;
    v->modification = VV_MOD_ORIGINAL;
}

static vv_status
h5_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    *out = NULL;
    h5p *h = NULL;
    vv_status s = h5p_open(&h, path, opt->channel, opt->time, 0);
    const int level = opt->level > 0 ? opt->level : 0;
    if (s == VV_OK && level >= h->n_levels)
        s = vv_error_set(VV_ERR_INVALID, "level %d asked, the file has %d", level, h->n_levels);
    vv_volume *v = NULL;
    if (s == VV_OK)
        s = vv_volume_new(&v, h->lv[level].dims, h->type);
    const int zero[3] = {0, 0, 0};
    if (s == VV_OK)
        s = h5p_read_box(h, level, zero, h->lv[level].dims, v->data);
    if (s == VV_OK) {
        h5p_geometry(&h->lv[level], v);
        vv_volume_update_range(v);
        if (opt->info) {
            opt->info->n_channels = h->n_channels;
            opt->info->n_times = h->n_times;
            opt->info->n_levels = h->n_levels;
        }
    }
    h5p_close(h);
    if (s != VV_OK) {
        vv_volume_free(v);
        return vv_error_prefix(s, "hdf5: %s", vv_path_basename(path));
    }
    *out = v;
    return VV_OK;
}

static const unsigned char h5_signature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};

static int
h5_looks_like(const vv_format_probe *p, int deep) {
    (void)deep;
    /* NetCDF-4 files are HDF5 files too: the grid row (grid_netcdf.c) reads them */
    return !p->is_dir && p->n >= 8 && !memcmp(p->head, h5_signature, 8) &&
           !vv_format_path_has_ext(p->path, "nc") && !vv_format_path_has_ext(p->path, "cdf");
}

static const char *const h5_extensions[] = {"h5", "ims", "hdf5", NULL};

/* The row's store: the file's levels of setup (channel) @p channel at
 * time point @p time. */
static vv_status
h5_open_store(vv_store *st, const char *path, int channel, int time, vv_load_info *info) {
    (void)info;
    return vv_h5_pyramid_store(st, path, channel, time);
}

const vv_format_record vv_format_hdf5 = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "hdf5",
    .title = "BigDataViewer / Imaris HDF5",
    .extensions = h5_extensions,
    .doc = "BigDataViewer HDF5 (t00000/s00/<level>/cells) and Imaris .ims (DataSet/"
           "ResolutionLevel N): read, one level (--level), channel and time step; 8/16/32-bit "
           "integer and float voxels; rendered out of core by level of detail (volvis render "
           "--lod)",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = h5_looks_like,
    .read = h5_read,
    .open_store = h5_open_store,
};

/* ---- the pyramid's store ------------------------------------------------------ */

/* The bytes libhdf5 reads from the file for the box @p lo + @p dims of
 * @p level: the stored (compressed) size of every HDF5 chunk it touches
 * (a chunk never written costs none), or the box's bytes where the
 * dataset is contiguous. Statistics only (volvis render -v). */
static uint64_t
stored_bytes(h5p *h, int level, const int lo[3], const int dims[3]) {
    const h5p_level *L = &h->lv[level];
    if (!L->hchunk[0] || !L->hchunk[1] || !L->hchunk[2])
        return (uint64_t)dims[0] * (uint64_t)dims[1] * (uint64_t)dims[2] *
               vv_voxel_type_size(h->type);
    uint64_t total = 0;
    int a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = lo[k] / L->hchunk[k];
        b[k] = (lo[k] + dims[k] - 1) / L->hchunk[k];
    }
    for (int z = a[2]; z <= b[2]; z++)
        for (int y = a[1]; y <= b[1]; y++)
            for (int x = a[0]; x <= b[0]; x++) {
                hsize_t off[3] = {(hsize_t)z * (hsize_t)L->hchunk[2],
                                  (hsize_t)y * (hsize_t)L->hchunk[1],
                                  (hsize_t)x * (hsize_t)L->hchunk[0]};
                hsize_t n = 0;
                if (H5Dget_chunk_storage_size(h->dset[level], off, &n) >= 0)
                    total += n;
            }
    return total;
}

static vv_status
h5s_read_chunk(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
               const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    (void)c;
    (void)scratch;
    h5p *h = ctx;
    *missing = 0;
    *file_bytes = stored_bytes(h, level, org, dims);
    return h5p_read_box(h, level, org, dims, dst);
}

static void
h5s_close(void *ctx) {
    h5p_close(ctx);
}

/* The store of @p path (@p ids: as vv_h5_bdv_store). */
static vv_status
h5_store(vv_store *st, const char *path, int channel, int time, int ids) {
    memset(st, 0, sizeof *st);
    st->name = "hdf5";
    h5p *h = NULL;
    vv_status s = h5p_open(&h, path, channel, time, ids);
    if (s != VV_OK)
        return s;
    st->ctx = h;
    st->close = h5s_close;
    st->read_chunk = h5s_read_chunk;
    st->parallel = 0; /* libhdf5 is not thread-safe: one chunk at a time */
    st->n_levels = h->n_levels;
    st->n_channels = h->n_channels;
    st->n_times = h->n_times;
    st->has_range = h->lv[0].has_range;
    st->range[0] = h->lv[0].range[0];
    st->range[1] = h->lv[0].range[1];
    for (int l = 0; l < h->n_levels; l++) {
        if ((s = vv_store_set_level(st, l, h->type, h->lv[l].dims, h->lv[l].cdims)) != VV_OK)
            return s;
        h5p_geometry(&h->lv[l], st->lv[l].hdr);
    }
    return VV_OK;
}

vv_status
vv_h5_pyramid_store(vv_store *st, const char *path, int channel, int time) {
    return h5_store(st, path, channel, time, 0);
}

vv_status
vv_h5_bdv_store(vv_store *st, const char *path, int setup, int timepoint) {
    return h5_store(st, path, setup, timepoint, 1);
}
