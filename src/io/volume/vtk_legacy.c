/*
 * VTK legacy files ("# vtk DataFile Version x.x"), DATASET
 * STRUCTURED_POINTS with one scalar array, ASCII or BINARY (big-endian).
 */
#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/types.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

#define VTK_LINE_MAX 1024
#define VTK_TOKEN_MAX 256

typedef struct vtk_in {
    FILE *fp;
    uint64_t size;
} vtk_in;

static uint64_t
vtk_remaining(const vtk_in *in) {
    off_t pos = ftello(in->fp);
    if (pos < 0 || (uint64_t)pos > in->size)
        return 0;
    return in->size - (uint64_t)pos;
}

/* Reads one line without its end-of-line; 0 at end of file. */
static int
vtk_line(vtk_in *in, char *buf, size_t cap) {
    size_t n = 0;
    int c;
    while ((c = getc(in->fp)) != EOF && c != '\n') {
        if (n + 1 < cap)
            buf[n++] = (char)c;
    }
    if (n > 0 && buf[n - 1] == '\r')
        n--;
    buf[n] = '\0';
    return c != EOF || n > 0;
}

/* Next whitespace-separated token; 0 at end of file. */
static int
vtk_token(vtk_in *in, char *buf, size_t cap) {
    int c;
    size_t n = 0;
    do {
        c = getc(in->fp);
    } while (c != EOF && isspace(c));
    while (c != EOF && !isspace(c)) {
        /* Binary junk never ends up in an error message. */
        if (c < 0x21 || c > 0x7E)
            return vv_error_set(VV_ERR_FORMAT, "unexpected byte 0x%02x in a text part",
                                (unsigned)c),
                   -1;
        if (n + 1 < cap)
            buf[n++] = (char)c;
        else
            return vv_error_set(VV_ERR_FORMAT, "token too long"), -1;
        c = getc(in->fp);
    }
    if (c != EOF)
        ungetc(c, in->fp);
    buf[n] = '\0';
    return n > 0;
}

/* Reads a token that must be present, for keywords and their arguments. */
static vv_status
vtk_need(vtk_in *in, char *buf, size_t cap, const char *what) {
    int r = vtk_token(in, buf, cap);
    if (r < 0)
        return VV_ERR_FORMAT;
    if (r == 0)
        return vv_error_set(VV_ERR_FORMAT, "%s: missing (truncated header)", what);
    return VV_OK;
}

static vv_status
vtk_need_double(vtk_in *in, const char *what, double *out) {
    char buf[VTK_TOKEN_MAX];
    vv_status s = vtk_need(in, buf, sizeof buf, what);
    if (s != VV_OK)
        return s;
    char *end;
    *out = strtod(buf, &end);
    if (*end != '\0' || !isfinite(*out))
        return vv_error_set(VV_ERR_FORMAT, "%s: expected a number, got \"%s\"", what, buf);
    return VV_OK;
}

static vv_status
vtk_need_long(vtk_in *in, const char *what, long *out) {
    char buf[VTK_TOKEN_MAX];
    vv_status s = vtk_need(in, buf, sizeof buf, what);
    if (s != VV_OK)
        return s;
    char *end;
    errno = 0;
    *out = strtol(buf, &end, 10);
    if (*end != '\0' || errno == ERANGE)
        return vv_error_set(VV_ERR_FORMAT, "%s: expected an integer, got \"%s\"", what, buf);
    return VV_OK;
}

static vv_status
vtk_parse_type(const char *s, vv_voxel_type *t) {
    static const struct {
        const char *name;
        vv_voxel_type type;
    } map[] = {{"unsigned_char", VV_U8},  {"char", VV_I8},
               {"signed_char", VV_I8},    {"unsigned_short", VV_U16},
               {"short", VV_I16},         {"unsigned_int", VV_U32},
               {"int", VV_I32},           {"float", VV_F32},
               {"double", VV_F64},        {"vtktypeuint8", VV_U8},
               {"vtktypeint8", VV_I8},    {"vtktypeuint16", VV_U16},
               {"vtktypeint16", VV_I16},  {"vtktypeuint32", VV_U32},
               {"vtktypeint32", VV_I32},  {"vtktypefloat32", VV_F32},
               {"vtktypefloat64", VV_F64}};
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (!strcasecmp(s, map[i].name)) {
            *t = map[i].type;
            return VV_OK;
        }
    return vv_error_set(VV_ERR_UNSUPPORTED, "scalar type %s is not supported", s);
}

/* Stores one ASCII value into voxel @p i, rejecting values the type cannot
   hold rather than silently clamping them. */
static vv_status
vtk_store(void *data, vv_voxel_type t, uint64_t i, const char *tok) {
    char *end;
    double x = strtod(tok, &end);
    if (*end != '\0' || end == tok)
        return vv_error_set(VV_ERR_FORMAT, "value %llu: expected a number, got \"%s\"",
                            (unsigned long long)i, tok);
    static const double lo[] = {0, -128, 0, -32768, 0, -2147483648.0};
    static const double hi[] = {255, 127, 65535, 32767, 4294967295.0, 2147483647.0};
    if (t <= VV_I32 && (!(x >= lo[t] && x <= hi[t]) || x != floor(x)))
        return vv_error_set(VV_ERR_FORMAT, "value %llu: \"%s\" is not a valid %s",
                            (unsigned long long)i, tok, vv_voxel_type_name(t));
    switch (t) {
    case VV_U8:
        ((uint8_t *)data)[i] = (uint8_t)x;
        break;
    case VV_I8:
        ((int8_t *)data)[i] = (int8_t)x;
        break;
    case VV_U16:
        ((uint16_t *)data)[i] = (uint16_t)x;
        break;
    case VV_I16:
        ((int16_t *)data)[i] = (int16_t)x;
        break;
    case VV_U32:
        ((uint32_t *)data)[i] = (uint32_t)x;
        break;
    case VV_I32:
        ((int32_t *)data)[i] = (int32_t)x;
        break;
    case VV_F32:
        if (isfinite(x) && fabs(x) > FLT_MAX)
            return vv_error_set(VV_ERR_FORMAT, "value %llu: \"%s\" is out of float range",
                                (unsigned long long)i, tok);
        ((float *)data)[i] = (float)x;
        break;
    case VV_F64:
        ((double *)data)[i] = x;
        break;
    }
    return VV_OK;
}

/* What the header of a STRUCTURED_POINTS file says. */
typedef struct vtk_header {
    int binary;
    int dims[3];
    double spacing[3], origin[3];
    uint64_t count; /* voxels */
    vv_voxel_type type;
    uint64_t bytes;   /* one component's voxels */
    int n_components; /* SCALARS' numComp, 1..4: interleaved per point */
    int component;    /* the one read (a channel) */
} vtk_header;

/* The first three lines: the version line, the title and ASCII or BINARY. */
static vv_status
vtk_read_preamble(vtk_in *in, vtk_header *h) {
    char line[VTK_LINE_MAX], tok[VTK_TOKEN_MAX];
    if (!vtk_line(in, line, sizeof line))
        return vv_error_set(VV_ERR_FORMAT, "empty file");
    if (strncmp(line, "# vtk DataFile Version", 22) != 0)
        return vv_error_set(VV_ERR_FORMAT, "not a VTK legacy file (no \"# vtk DataFile\" line)");
    if (!vtk_line(in, line, sizeof line))
        return vv_error_set(VV_ERR_FORMAT, "truncated header (no title line)");
    /* The format keyword is a token: some writers put a blank line before it. */
    int r = vtk_token(in, tok, sizeof tok);
    if (r < 0)
        return vv_error_prefix(VV_ERR_FORMAT, "ASCII/BINARY line");
    if (r == 0)
        return vv_error_set(VV_ERR_FORMAT, "truncated header (no ASCII/BINARY line)");
    if (!strcasecmp(tok, "BINARY"))
        h->binary = 1;
    else if (!strcasecmp(tok, "ASCII"))
        h->binary = 0;
    else
        return vv_error_set(VV_ERR_FORMAT, "third line is \"%.40s\", expected ASCII or BINARY",
                            tok);
    return VV_OK;
}

/* The dataset keywords up to POINT_DATA: DATASET STRUCTURED_POINTS,
 * DIMENSIONS, SPACING (or ASPECT_RATIO), ORIGIN; checked dimensions. */
static vv_status
vtk_read_dataset(vtk_in *in, vtk_header *h) {
    char tok[VTK_TOKEN_MAX];
    vv_status s;
    long dims[3] = {0, 0, 0};
    int have_dims = 0, have_dataset = 0;
    long npoints = -1;
    for (int a = 0; a < 3; a++) {
        h->spacing[a] = 1;
        h->origin[a] = 0;
    }
    for (;;) {
        if ((s = vtk_need(in, tok, sizeof tok, "POINT_DATA")) != VV_OK)
            return s;
        if (!strcasecmp(tok, "DATASET")) {
            if ((s = vtk_need(in, tok, sizeof tok, "DATASET type")) != VV_OK)
                return s;
            if (strcasecmp(tok, "STRUCTURED_POINTS"))
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "DATASET %s is not supported (only STRUCTURED_POINTS)", tok);
            have_dataset = 1;
        } else if (!strcasecmp(tok, "DIMENSIONS")) {
            for (int a = 0; a < 3; a++)
                if ((s = vtk_need_long(in, "DIMENSIONS", &dims[a])) != VV_OK)
                    return s;
            have_dims = 1;
        } else if (!strcasecmp(tok, "SPACING") || !strcasecmp(tok, "ASPECT_RATIO")) {
            for (int a = 0; a < 3; a++)
                if ((s = vtk_need_double(in, "SPACING", &h->spacing[a])) != VV_OK)
                    return s;
            for (int a = 0; a < 3; a++)
                if (!(h->spacing[a] > 0))
                    return vv_error_set(VV_ERR_FORMAT, "bad SPACING %g %g %g", h->spacing[0],
                                        h->spacing[1], h->spacing[2]);
        } else if (!strcasecmp(tok, "ORIGIN")) {
            for (int a = 0; a < 3; a++)
                if ((s = vtk_need_double(in, "ORIGIN", &h->origin[a])) != VV_OK)
                    return s;
        } else if (!strcasecmp(tok, "POINT_DATA")) {
            if ((s = vtk_need_long(in, "POINT_DATA", &npoints)) != VV_OK)
                return s;
            break;
        } else if (!strcasecmp(tok, "CELL_DATA") || !strcasecmp(tok, "FIELD")) {
            return vv_error_set(VV_ERR_UNSUPPORTED, "%s before POINT_DATA is not supported", tok);
        } else {
            return vv_error_set(VV_ERR_FORMAT, "unexpected keyword \"%.40s\" in the header", tok);
        }
    }
    if (!have_dataset)
        return vv_error_set(VV_ERR_FORMAT, "no DATASET line");
    if (!have_dims)
        return vv_error_set(VV_ERR_FORMAT, "no DIMENSIONS");
    if (dims[0] < 1 || dims[1] < 1 || dims[2] < 1)
        return vv_error_set(VV_ERR_FORMAT, "bad DIMENSIONS %ld %ld %ld", dims[0], dims[1], dims[2]);
    if (dims[0] > VV_VOLUME_MAX_DIM || dims[1] > VV_VOLUME_MAX_DIM || dims[2] > VV_VOLUME_MAX_DIM)
        return vv_error_set(VV_ERR_LIMIT, "DIMENSIONS %ld %ld %ld over the limit of %d per axis",
                            dims[0], dims[1], dims[2], VV_VOLUME_MAX_DIM);
    for (int a = 0; a < 3; a++)
        h->dims[a] = (int)dims[a];
    h->count = (uint64_t)dims[0] * (uint64_t)dims[1] * (uint64_t)dims[2];
    if (npoints < 0 || (uint64_t)npoints != h->count)
        return vv_error_set(VV_ERR_FORMAT, "POINT_DATA %ld does not match DIMENSIONS (%llu)",
                            npoints, (unsigned long long)h->count);
    return VV_OK;
}

/* SCALARS name type [ncomp] on one line, then an optional LOOKUP_TABLE
 * line; the size checked. */
static vv_status
vtk_read_scalars(vtk_in *in, vtk_header *h) {
    char line[VTK_LINE_MAX], tok[VTK_TOKEN_MAX];
    vv_status s;
    if ((s = vtk_need(in, tok, sizeof tok, "SCALARS")) != VV_OK)
        return s;
    if (strcasecmp(tok, "SCALARS"))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "point data \"%.40s\" is not supported (only SCALARS)", tok);
    if (!vtk_line(in, line, sizeof line))
        return vv_error_set(VV_ERR_FORMAT, "SCALARS: truncated");
    char name[VTK_TOKEN_MAX], tname[VTK_TOKEN_MAX], extra[VTK_TOKEN_MAX];
    long ncomp = 1;
    int nf = sscanf(line, "%255s %255s %ld %255s", name, tname, &ncomp, extra);
    if (nf < 2)
        return vv_error_set(VV_ERR_FORMAT, "SCALARS: expected a name and a type");
    h->type = VV_U8;
    if ((s = vtk_parse_type(tname, &h->type)) != VV_OK)
        return s;
    /* numComp is 1..4 (the file-format document); each is a channel */
    if (nf >= 3 && (ncomp < 1 || ncomp > 4))
        return vv_error_set(VV_ERR_FORMAT, "SCALARS with %ld components (1 to 4)", ncomp);
    h->n_components = nf >= 3 ? (int)ncomp : 1;
    if (h->component >= h->n_components)
        return vv_error_set(VV_ERR_INVALID, "channel %d asked, the file has %d (from 0)",
                            h->component, h->n_components);
    if ((s = vv_volume_check_size(h->dims, h->type, &h->bytes)) != VV_OK)
        return s;
    off_t mark = ftello(in->fp);
    if (mark < 0)
        return vv_error_set(VV_ERR_IO, "cannot tell the position");
    int r = vtk_token(in, tok, sizeof tok);
    if (r < 0)
        return VV_ERR_FORMAT;
    if (r > 0 && !strcasecmp(tok, "LOOKUP_TABLE")) {
        if (!vtk_line(in, line, sizeof line))
            return vv_error_set(VV_ERR_FORMAT, "LOOKUP_TABLE: truncated");
    } else if (fseeko(in->fp, mark, SEEK_SET) != 0) {
        return vv_error_set(VV_ERR_IO, "cannot seek");
    }
    return VV_OK;
}

/* The values, binary (big-endian) or ASCII, into @p v. */
static vv_status
vtk_read_values(vtk_in *in, const vtk_header *h, vv_volume *v) {
    const uint64_t nc = (uint64_t)h->n_components, total = h->count * nc;
    if (h->binary) {
        size_t vs = vv_voxel_type_size(h->type);
        if (nc == 1) {
            if (fread(v->data, 1, (size_t)h->bytes, in->fp) != (size_t)h->bytes)
                return vv_error_set(VV_ERR_FORMAT, "truncated binary data");
        } else { /* the component's values out of the points' tuples, a block at a time */
            enum { BLOCK = 1 << 16 };
            unsigned char *buf = malloc((size_t)BLOCK * nc * vs);
            if (!buf)
                return vv_error_set(VV_ERR_NOMEM, "out of memory");
            unsigned char *dst = v->data;
            for (uint64_t p = 0; p < h->count; p += BLOCK) {
                size_t n = (size_t)(h->count - p < BLOCK ? h->count - p : BLOCK);
                if (fread(buf, vs * nc, n, in->fp) != n) {
                    free(buf);
                    return vv_error_set(VV_ERR_FORMAT, "truncated binary data");
                }
                for (size_t i = 0; i < n; i++)
                    memcpy(dst + (p + i) * vs, buf + (i * nc + (size_t)h->component) * vs, vs);
            }
            free(buf);
        }
        if (vs > 1 && vv_host_is_little_endian())
            vv_byteswap(v->data, h->count, vs);
        return VV_OK;
    }
    char tok[VTK_TOKEN_MAX];
    for (uint64_t i = 0; i < total; i++) {
        int r = vtk_token(in, tok, sizeof tok);
        if (r < 0)
            return vv_error_prefix(VV_ERR_FORMAT, "value %llu", (unsigned long long)i);
        if (r == 0)
            return vv_error_set(VV_ERR_FORMAT, "truncated data: %llu of %llu values",
                                (unsigned long long)i, (unsigned long long)total);
        if (i % nc != (uint64_t)h->component)
            continue;
        vv_status s = vtk_store(v->data, h->type, i / nc, tok);
        if (s != VV_OK)
            return s;
    }
    return VV_OK;
}

static vv_status
vtk_read_stream(vv_volume **out, vtk_in *in, int channel, vv_load_info *info) {
    vtk_header h;
    memset(&h, 0, sizeof h);
    h.component = channel > 0 ? channel : 0;
    vv_status s;
    if ((s = vtk_read_preamble(in, &h)) != VV_OK || (s = vtk_read_dataset(in, &h)) != VV_OK ||
        (s = vtk_read_scalars(in, &h)) != VV_OK)
        return s;
    /* Every ASCII value takes at least two characters, every binary value
       its size: check the file can hold the data before allocating it. */
    uint64_t rest = vtk_remaining(in), values = h.count * (uint64_t)h.n_components;
    uint64_t need = h.binary ? h.bytes * (uint64_t)h.n_components : 2 * values - 1;
    if (rest < need)
        return vv_error_set(VV_ERR_FORMAT,
                            "truncated data: %llu %s values need %s%llu bytes, the file has %llu "
                            "left",
                            (unsigned long long)values, vv_voxel_type_name(h.type),
                            h.binary ? "" : "at least ", (unsigned long long)need,
                            (unsigned long long)rest);
    if (info)
        info->n_channels = h.n_components;
    vv_volume *v = NULL;
    if ((s = vv_volume_new(&v, h.dims, h.type)) != VV_OK)
        return s;
    if ((s = vtk_read_values(in, &h, v)) != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    for (int a = 0; a < 3; a++) {
        v->spacing[a] = h.spacing[a];
        v->origin[a] = h.origin[a];
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

/* Component @p channel (-1: 0) of the file's SCALARS; @p info (may be
 * NULL) gets their count as the channels. */
static vv_status
vtk_read_channel(vv_volume **out, const char *path, int channel, vv_load_info *info) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "vtk: NULL argument");
    *out = NULL;
    const char *name = vv_path_basename(path);
    vtk_in in = {NULL, 0};
    vv_status s = vv_open_regular(path, &in.fp, &in.size);
    if (s != VV_OK)
        return vv_error_prefix(s, "vtk: %s", name);
    s = vtk_read_stream(out, &in, channel, info);
    fclose(in.fp);
    if (s != VV_OK)
        return vv_error_prefix(s, "vtk: %s", name);
    return VV_OK;
}

vv_status
vv_vtk_read(vv_volume **out, const char *path) {
    return vtk_read_channel(out, path, -1, NULL);
}

/* ---- the format record ------------------------------------------------------ */

static int
vtk_looks_like(const vv_format_probe *p, int deep) {
    if (deep || p->is_dir)
        return 0;
    size_t i = 0;
    while (i < p->n && isspace(p->head[i]))
        i++;
    /* the grid row (grid_vtk.c) reads the unstructured ones */
    return p->n - i >= 14 && !memcmp(p->head + i, "# vtk DataFile", 14) &&
           !strstr(p->text, "UNSTRUCTURED_GRID");
}

static vv_status
vtk_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    return vtk_read_channel(out, path, opt ? opt->channel : -1, opt ? opt->info : NULL);
}

static int
vtk_fits(const vv_volume *v, char *why, size_t cap) {
    for (int i = 0; i < 9; i++)
        if (v->direction[i] != (i % 4 == 0 ? 1.0 : 0.0)) {
            snprintf(why, cap,
                     "VTK legacy STRUCTURED_POINTS holds no direction matrix: the oblique volume "
                     "is written axis-aligned (write .vti to keep it)");
            return 0;
        }
    return 1;
}

static vv_status
vtk_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    (void)opt;
    return vv_vtk_write(v, path);
}

static const char *const vtk_extensions[] = {"vtk", NULL};

const vv_format_record vv_format_vtk = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "vtk",
    .title = "VTK legacy",
    .extensions = vtk_extensions,
    .doc = "VTK legacy STRUCTURED_POINTS, binary or ASCII: the first SCALARS array; writes "
           "binary, every voxel type, origin and spacing (no direction matrix)",
    .looks_like = vtk_looks_like,
    .fits = vtk_fits,
    .read = vtk_read_record,
    .write = vtk_write_record,
};
