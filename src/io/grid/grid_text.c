/*
 * What the grid readers share (io/grid/grid_io_internal.h): a cursor over a file
 * held in memory, with whitespace-separated tokens and checked counts; the
 * value types of the VTK, VTK XML and OpenDX formats, read as text or binary
 * in either byte order, every count checked against the bytes left before
 * anything is allocated; and the common end of a reader (validation and
 * field ranges).
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/internal.h"
#include "io/grid/grid_io_internal.h"
#include "volvis/grid.h"

/* ---------------------------------------------------------------------- */
/* A cursor over a file in memory                                          */

void
vv_gcur_init(vv_gcur *c, const unsigned char *data, size_t size, const char *path) {
    c->p = data;
    c->end = data + size;
    c->begin = data;
    c->path = path;
}

size_t
vv_gcur_left(const vv_gcur *c) {
    return (size_t)(c->end - c->p);
}

int
vv_gcur_token(vv_gcur *c, char *buf, size_t cap) {
    while (c->p < c->end && isspace(*c->p))
        c->p++;
    size_t n = 0;
    while (c->p < c->end && !isspace(*c->p)) {
        if (n + 1 < cap)
            buf[n++] = (char)(*c->p >= 0x21 && *c->p <= 0x7e ? *c->p : '?');
        c->p++;
    }
    buf[n] = '\0';
    return n > 0;
}

void
vv_gcur_skip_line(vv_gcur *c) {
    while (c->p < c->end && *c->p != '\n')
        c->p++;
    if (c->p < c->end)
        c->p++;
}

vv_status
vv_gcur_need(vv_gcur *c, char *buf, size_t cap, const char *what) {
    if (!vv_gcur_token(c, buf, cap))
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: missing (truncated file)", c->path, what);
    return VV_OK;
}

vv_status
vv_gcur_need_size(vv_gcur *c, const char *what, size_t max, size_t *out) {
    char buf[64];
    vv_status s = vv_gcur_need(c, buf, sizeof buf, what);
    if (s != VV_OK)
        return s;
    char *end;
    errno = 0;
    long long v = strtoll(buf, &end, 10);
    if (*end || errno || v < 0)
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: expected a count, got \"%s\"", c->path, what,
                            buf);
    if ((unsigned long long)v > max)
        return vv_error_set(VV_ERR_LIMIT, "%s: %s: %lld is over the limit of %zu", c->path, what, v,
                            max);
    *out = (size_t)v;
    return VV_OK;
}

int
vv_gtype_parse(const char *s, vv_gtype *t) {
    static const struct {
        const char *name;
        vv_gtype t;
    } map[] = {{"unsigned_char", VV_GT_U8},
               {"char", VV_GT_I8},
               {"signed_char", VV_GT_I8},
               {"unsigned_short", VV_GT_U16},
               {"short", VV_GT_I16},
               {"unsigned_int", VV_GT_U32},
               {"int", VV_GT_I32},
               {"unsigned_long", VV_GT_U64},
               {"long", VV_GT_I64},
               {"float", VV_GT_F32},
               {"double", VV_GT_F64},
               {"vtktypeint8", VV_GT_I8},
               {"vtktypeuint8", VV_GT_U8},
               {"vtktypeint16", VV_GT_I16},
               {"vtktypeuint16", VV_GT_U16},
               {"vtktypeint32", VV_GT_I32},
               {"vtktypeuint32", VV_GT_U32},
               {"vtktypeint64", VV_GT_I64},
               {"vtktypeuint64", VV_GT_U64},
               {"vtktypefloat32", VV_GT_F32},
               {"vtktypefloat64", VV_GT_F64},
               {"Int8", VV_GT_I8},
               {"UInt8", VV_GT_U8},
               {"Int16", VV_GT_I16},
               {"UInt16", VV_GT_U16},
               {"Int32", VV_GT_I32},
               {"UInt32", VV_GT_U32},
               {"Int64", VV_GT_I64},
               {"UInt64", VV_GT_U64},
               {"Float32", VV_GT_F32},
               {"Float64", VV_GT_F64},
               {"byte", VV_GT_U8},
               {"ubyte", VV_GT_U8}};
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (!strcasecmp(s, map[i].name)) {
            *t = map[i].t;
            return 1;
        }
    return 0;
}

size_t
vv_gtype_size(vv_gtype t) {
    switch (t) {
    case VV_GT_I8:
    case VV_GT_U8:
        return 1;
    case VV_GT_I16:
    case VV_GT_U16:
        return 2;
    case VV_GT_I32:
    case VV_GT_U32:
    case VV_GT_F32:
        return 4;
    case VV_GT_I64:
    case VV_GT_U64:
    case VV_GT_F64:
        return 8;
    }
    return 1;
}

double
vv_gtype_get(const unsigned char *p, vv_gtype t, int big_endian) {
    unsigned char b[8];
    const size_t n = vv_gtype_size(t);
    for (size_t i = 0; i < n; i++)
        b[i] = big_endian ? p[n - 1 - i] : p[i];
    switch (t) {
    case VV_GT_I8:
        return (int8_t)b[0];
    case VV_GT_U8:
        return b[0];
    case VV_GT_I16: {
        int16_t v;
        memcpy(&v, b, 2);
        return v;
    }
    case VV_GT_U16: {
        uint16_t v;
        memcpy(&v, b, 2);
        return v;
    }
    case VV_GT_I32: {
        int32_t v;
        memcpy(&v, b, 4);
        return v;
    }
    case VV_GT_U32: {
        uint32_t v;
        memcpy(&v, b, 4);
        return v;
    }
    case VV_GT_I64: {
        int64_t v;
        memcpy(&v, b, 8);
        return (double)v;
    }
    case VV_GT_U64: {
        uint64_t v;
        memcpy(&v, b, 8);
        return (double)v;
    }
    case VV_GT_F32: {
        float v;
        memcpy(&v, b, 4);
        return v;
    }
    case VV_GT_F64: {
        double v;
        memcpy(&v, b, 8);
        return v;
    }
    }
    return 0;
}

vv_status
vv_gcur_values(vv_gcur *c, int binary, int big_endian, vv_gtype t, size_t n, double *out,
               const char *what) {
    if (binary) {
        const size_t sz = vv_gtype_size(t);
        if (n > vv_gcur_left(c) / sz)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: %s: %zu values of %zu bytes but only %zu bytes are left",
                                c->path, what, n, sz, vv_gcur_left(c));
        for (size_t i = 0; i < n; i++)
            out[i] = vv_gtype_get(c->p + i * sz, t, big_endian);
        c->p += n * sz;
        return VV_OK;
    }
    char buf[128];
    for (size_t i = 0; i < n; i++) {
        if (!vv_gcur_token(c, buf, sizeof buf))
            return vv_error_set(VV_ERR_FORMAT, "%s: %s: value %zu of %zu missing (truncated)",
                                c->path, what, i, n);
        char *end;
        out[i] = strtod(buf, &end);
        if (*end)
            return vv_error_set(VV_ERR_FORMAT, "%s: %s: value %zu is \"%s\", not a number", c->path,
                                what, i, buf);
    }
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* The end of every reader                                                  */

/* Finishes a reader: validation, field ranges. Frees the grid on failure. */
vv_status
vv_grid_finish(vv_grid *g, const char *path, vv_grid **out) {
    vv_status s = vv_grid_validate(g);
    if (s != VV_OK) {
        vv_grid_free(g);
        return vv_error_prefix(s, "%s", path);
    }
    for (int i = 0; i < g->n_fields; i++)
        vv_grid_field_update_range(&g->fields[i]);
    *out = g;
    return VV_OK;
}
