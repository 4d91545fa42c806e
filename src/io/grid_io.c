/*
 * Grid files: detection and loading (volvis/grid.h), and the two text-led
 * formats, VTK legacy UNSTRUCTURED_GRID (ASCII and binary; "VTK User's
 * Guide", file formats) and OpenDX native files with positions,
 * connections and data, text or binary, either byte order ("IBM
 * Visualization Data Explorer, User's Guide", appendix B, "Data Explorer
 * native file format").
 *
 * Both read the whole file into memory (at most VV_GRID_FILE_MAX bytes) and
 * check every count against the bytes that remain before allocating, so a
 * header announcing a billion points in a small file fails at once.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/internal.h"
#include "io/grid_io_internal.h"
#include "volvis/grid.h"

#define VV_GRID_FILE_MAX (4ull << 30)

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
/* Detection and loading                                                    */

static int
ends_with(const char *s, const char *suffix) {
    const size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

int
vv_grid_file_detect(const char *path, vv_grid_format *fmt) {
    vv_grid_format f = VV_GRID_FORMAT_AUTO;
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return 0;
    char head[1024];
    const size_t n = fread(head, 1, sizeof head - 1, fp);
    fclose(fp);
    head[n] = '\0';
    for (size_t i = 0; i < n; i++)
        if (head[i] == '\0')
            head[i] = ' ';
    if (n >= 4 && !memcmp(head, "CDF", 3) && (head[3] == 1 || head[3] == 2 || head[3] == 5))
        f = VV_GRID_FORMAT_NETCDF;
    else if (n >= 8 && !memcmp(head, "\x89HDF\r\n\x1a\n", 8) &&
             (ends_with(path, ".nc") || ends_with(path, ".cdf")))
        f = VV_GRID_FORMAT_NETCDF;
    else if (!strncmp(head, "# vtk DataFile", 14) && strstr(head, "UNSTRUCTURED_GRID"))
        f = VV_GRID_FORMAT_VTK;
    else if (strstr(head, "<VTKFile") && strstr(head, "UnstructuredGrid"))
        f = VV_GRID_FORMAT_VTU;
    else if ((ends_with(path, ".dx") || !strncmp(head, "object ", 7)) &&
             strstr(head, "class array"))
        f = VV_GRID_FORMAT_DX;
    else if (ends_with(path, ".xyz") || ends_with(path, "xyz.bin"))
        f = VV_GRID_FORMAT_PLOT3D;
    if (fmt)
        *fmt = f;
    return f != VV_GRID_FORMAT_AUTO;
}

vv_status
vv_grid_load(vv_grid **out, const char *path) {
    *out = NULL;
    vv_grid_format f;
    if (!vv_grid_file_detect(path, &f)) {
        FILE *fp = fopen(path, "rb");
        if (!fp)
            return vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
        fclose(fp);
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: not a grid file this build reads (VTK UNSTRUCTURED_GRID, .vtu, "
                            "OpenDX, PLOT3D, NetCDF)",
                            path);
    }
    switch (f) {
    case VV_GRID_FORMAT_VTK:
        return vv_grid_read_vtk(out, path);
    case VV_GRID_FORMAT_VTU:
        return vv_grid_read_vtu(out, path);
    case VV_GRID_FORMAT_DX:
        return vv_grid_read_dx(out, path);
    case VV_GRID_FORMAT_PLOT3D: {
        /* the solution beside the grid: xxxxyz.bin -> xxxq.bin, x.xyz -> x.q */
        char q[4096];
        snprintf(q, sizeof q, "%s", path);
        size_t n = strlen(q);
        int have = 0;
        if (ends_with(q, "xyz.bin") && n >= 7) {
            snprintf(q + n - 7, sizeof q - (n - 7), "q.bin");
            have = 1;
        } else if (ends_with(q, ".xyz") && n >= 4) {
            snprintf(q + n - 4, sizeof q - (n - 4), ".q");
            have = 1;
        }
        FILE *fp = have ? fopen(q, "rb") : NULL;
        if (fp)
            fclose(fp);
        return vv_grid_read_plot3d(out, path, fp ? q : NULL);
    }
    case VV_GRID_FORMAT_NETCDF:
        return vv_grid_read_netcdf(out, path);
    case VV_GRID_FORMAT_AUTO:
        break;
    }
    return vv_error_set(VV_ERR_FORMAT, "%s: unknown grid format", path);
}

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

/* ---------------------------------------------------------------------- */
/* VTK legacy UNSTRUCTURED_GRID                                             */

/* Reads n tuples of ncomp values into a new field. */
static vv_status
vtk_field(vv_gcur *c, vv_grid *g, int binary, const char *name, int cell_data, int ncomp,
          vv_gtype t, size_t n) {
    vv_grid_field *f = NULL;
    vv_status s = vv_grid_add_field(g, name, cell_data, ncomp, &f);
    if (s != VV_OK)
        return s;
    if (f->n_tuples != n)
        return vv_error_set(VV_ERR_FORMAT, "%s: field %s: %zu tuples for %zu %s", c->path, name, n,
                            f->n_tuples, cell_data ? "cells" : "points");
    const size_t nv = n * (size_t)ncomp;
    double *tmp = malloc((nv ? nv : 1) * sizeof *tmp);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    s = vv_gcur_values(c, binary, 1, t, nv, tmp, name);
    for (size_t i = 0; s == VV_OK && i < nv; i++)
        f->values[i] = (float)tmp[i];
    free(tmp);
    return s;
}

/* The cells of a VTK 5.1 legacy file, after "CELLS n_offsets n_conn
 * OFFSETS": OFFSETS type, n_offsets values, CONNECTIVITY type, n_conn
 * values. */
static vv_status
vtk51_cells(vv_gcur *c, vv_grid *g, int binary, size_t n_off, size_t n_conn, size_t n_points) {
    char ty[64], kw[64];
    vv_gtype t;
    if (n_off < 1)
        return vv_error_set(VV_ERR_FORMAT, "%s: CELLS: no offsets", c->path);
    vv_status s = vv_gcur_need(c, ty, sizeof ty, "OFFSETS type");
    if (s != VV_OK)
        return s;
    if (!vv_gtype_parse(ty, &t))
        return vv_error_set(VV_ERR_FORMAT, "%s: OFFSETS: unknown type \"%s\"", c->path, ty);
    if (n_off > vv_gcur_left(c) || n_conn > vv_gcur_left(c))
        return vv_error_set(VV_ERR_FORMAT, "%s: CELLS %zu %zu: more than the %zu bytes left",
                            c->path, n_off, n_conn, vv_gcur_left(c));
    double *pts = g->points;
    g->points = NULL;
    g->n_points = 0;
    s = vv_grid_alloc(g, 0, n_off - 1, n_conn);
    free(g->points);
    g->points = pts;
    g->n_points = n_points;
    if (s != VV_OK)
        return s;
    double *tmp = malloc((n_off > n_conn ? n_off : n_conn ? n_conn : 1) * sizeof *tmp);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    if (binary)
        vv_gcur_skip_line(c);
    if ((s = vv_gcur_values(c, binary, 1, t, n_off, tmp, "OFFSETS")) != VV_OK)
        goto done;
    for (size_t i = 0; i < n_off; i++) {
        const double prev = i ? tmp[i - 1] : 0;
        if (!(tmp[i] >= prev) || tmp[i] > (double)n_conn || (i == 0 && tmp[0] != 0)) {
            s = vv_error_set(VV_ERR_FORMAT, "%s: OFFSETS[%zu] = %g out of order or past %zu",
                             c->path, i, tmp[i], n_conn);
            goto done;
        }
        if (i)
            g->cell_offsets[i] = (size_t)tmp[i];
    }
    if (g->cell_offsets[n_off - 1] != n_conn) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: OFFSETS end at %zu, not %zu", c->path,
                         g->cell_offsets[n_off - 1], n_conn);
        goto done;
    }
    if ((s = vv_gcur_need(c, kw, sizeof kw, "CONNECTIVITY")) != VV_OK ||
        (s = vv_gcur_need(c, ty, sizeof ty, "CONNECTIVITY type")) != VV_OK)
        goto done;
    if (strcasecmp(kw, "CONNECTIVITY") || !vv_gtype_parse(ty, &t)) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: expected CONNECTIVITY <type>, got \"%s %s\"", c->path,
                         kw, ty);
        goto done;
    }
    if (binary)
        vv_gcur_skip_line(c);
    if ((s = vv_gcur_values(c, binary, 1, t, n_conn, tmp, "CONNECTIVITY")) != VV_OK)
        goto done;
    for (size_t i = 0; i < n_conn; i++) {
        if (!(tmp[i] >= 0) || tmp[i] >= (double)n_points) {
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: CONNECTIVITY[%zu] uses point %g but there are %zu points",
                             c->path, i, tmp[i], n_points);
            goto done;
        }
        g->connectivity[i] = (uint32_t)tmp[i];
    }
done:
    free(tmp);
    return s;
}

vv_status
vv_grid_read_vtk(vv_grid **out, const char *path) {
    *out = NULL;
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, VV_GRID_FILE_MAX, &data, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "%s", path);
    vv_gcur c;
    vv_gcur_init(&c, data, (size_t)size, path);
    vv_grid *g = NULL;
    double *tmp = NULL;
    char tok[256];
    if (size < 14 || strncmp((const char *)data, "# vtk DataFile", 14) != 0) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: not a VTK legacy file", path);
        goto done;
    }
    vv_gcur_skip_line(&c); /* version */
    vv_gcur_skip_line(&c); /* title */
    if ((s = vv_gcur_need(&c, tok, sizeof tok, "ASCII or BINARY")) != VV_OK)
        goto done;
    const int binary = !strcasecmp(tok, "BINARY");
    if (!binary && strcasecmp(tok, "ASCII")) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: expected ASCII or BINARY, got \"%s\"", path, tok);
        goto done;
    }
    if ((s = vv_gcur_need(&c, tok, sizeof tok, "DATASET")) != VV_OK ||
        (s = vv_gcur_need(&c, tok + 128, 128, "dataset type")) != VV_OK)
        goto done;
    if (strcasecmp(tok, "DATASET") || strcasecmp(tok + 128, "UNSTRUCTURED_GRID")) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: \"%s %s\" is not DATASET UNSTRUCTURED_GRID", path, tok,
                         tok + 128);
        goto done;
    }
    if ((s = vv_grid_new(&g, VV_GRID_UNSTRUCTURED)) != VV_OK)
        goto done;
    size_t n_points = 0, n_cells = 0, n_types = 0;
    int have_points = 0, have_cells = 0, have_types = 0;
    int section = -1; /* 0 point data, 1 cell data */
    size_t section_n = 0;
    size_t *counts = NULL;
    while (vv_gcur_token(&c, tok, sizeof tok)) {
        if (!strcasecmp(tok, "POINTS")) {
            char ty[64];
            vv_gtype t;
            if ((s = vv_gcur_need_size(&c, "POINTS count", VV_GRID_MAX_POINTS, &n_points)) !=
                    VV_OK ||
                (s = vv_gcur_need(&c, ty, sizeof ty, "POINTS type")) != VV_OK)
                goto done;
            if (!vv_gtype_parse(ty, &t)) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: POINTS: unknown type \"%s\"", path, ty);
                goto done;
            }
            if (3 * n_points > vv_gcur_left(&c)) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: POINTS %zu: the file has only %zu bytes left",
                                 path, n_points, vv_gcur_left(&c));
                goto done;
            }
            if (binary)
                vv_gcur_skip_line(&c);
            if ((s = vv_grid_alloc(g, n_points, 0, 0)) != VV_OK)
                goto done;
            if ((s = vv_gcur_values(&c, binary, 1, t, 3 * n_points, g->points, "POINTS")) != VV_OK)
                goto done;
            have_points = 1;
        } else if (!strcasecmp(tok, "CELLS")) {
            size_t n_ints = 0;
            if ((s = vv_gcur_need_size(&c, "CELLS count", VV_GRID_MAX_CELLS, &n_cells)) != VV_OK ||
                (s = vv_gcur_need_size(&c, "CELLS size", (size_t)VV_GRID_MAX_CELLS * 9, &n_ints)) !=
                    VV_OK)
                goto done;
            if (!have_points) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: CELLS before POINTS", path);
                goto done;
            }
            {
                /* VTK 5.1: CELLS n_offsets n_connectivity, then OFFSETS and CONNECTIVITY */
                const unsigned char *save = c.p;
                char kw[64];
                if (vv_gcur_token(&c, kw, sizeof kw) && !strcasecmp(kw, "OFFSETS")) {
                    if ((s = vtk51_cells(&c, g, binary, n_cells, n_ints, n_points)) != VV_OK)
                        goto done;
                    n_cells = n_cells ? n_cells - 1 : 0;
                    have_cells = 1;
                    continue;
                }
                c.p = save;
            }
            if (n_ints > vv_gcur_left(&c) || n_ints < n_cells) {
                s = vv_error_set(VV_ERR_FORMAT,
                                 "%s: CELLS %zu %zu: inconsistent with the %zu bytes "
                                 "left",
                                 path, n_cells, n_ints, vv_gcur_left(&c));
                goto done;
            }
            if (binary)
                vv_gcur_skip_line(&c);
            /* keep the points, allocate the cells */
            double *pts = g->points;
            g->points = NULL;
            g->n_points = 0;
            s = vv_grid_alloc(g, 0, n_cells, n_ints - n_cells);
            free(g->points);
            g->points = pts;
            g->n_points = n_points;
            if (s != VV_OK)
                goto done;
            tmp = malloc((n_ints ? n_ints : 1) * sizeof *tmp);
            if (!tmp) {
                s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
                goto done;
            }
            if ((s = vv_gcur_values(&c, binary, 1, VV_GT_I32, n_ints, tmp, "CELLS")) != VV_OK)
                goto done;
            size_t k = 0, o = 0;
            for (size_t i = 0; i < n_cells; i++) {
                const double cnt = tmp[k++];
                /* the ints left, less one count for each cell still to come */
                if (!(cnt >= 1) || cnt > (double)(n_ints - k - (n_cells - 1 - i))) {
                    s = vv_error_set(VV_ERR_FORMAT, "%s: CELLS: cell %zu has %g points", path, i,
                                     cnt);
                    goto done;
                }
                for (size_t j = 0; j < (size_t)cnt; j++) {
                    const double v = tmp[k++];
                    if (!(v >= 0) || v >= (double)n_points) {
                        s = vv_error_set(VV_ERR_FORMAT,
                                         "%s: CELLS: cell %zu uses point %g but there are %zu "
                                         "points",
                                         path, i, v, n_points);
                        goto done;
                    }
                    g->connectivity[o++] = (uint32_t)v;
                }
                g->cell_offsets[i + 1] = o;
            }
            if (o != n_ints - n_cells) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: CELLS: size %zu disagrees with the cells",
                                 path, n_ints);
                goto done;
            }
            free(tmp);
            tmp = NULL;
            have_cells = 1;
        } else if (!strcasecmp(tok, "CELL_TYPES")) {
            if ((s = vv_gcur_need_size(&c, "CELL_TYPES count", VV_GRID_MAX_CELLS, &n_types)) !=
                VV_OK)
                goto done;
            if (!have_cells || n_types != n_cells) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: CELL_TYPES %zu without CELLS of as many", path,
                                 n_types);
                goto done;
            }
            if (binary)
                vv_gcur_skip_line(&c);
            tmp = malloc((n_types ? n_types : 1) * sizeof *tmp);
            if (!tmp) {
                s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
                goto done;
            }
            if ((s = vv_gcur_values(&c, binary, 1, VV_GT_I32, n_types, tmp, "CELL_TYPES")) != VV_OK)
                goto done;
            for (size_t i = 0; i < n_types; i++)
                g->cell_types[i] = (uint8_t)(tmp[i] >= 0 && tmp[i] < 256 ? tmp[i] : 255);
            free(tmp);
            tmp = NULL;
            have_types = 1;
        } else if (!strcasecmp(tok, "POINT_DATA") || !strcasecmp(tok, "CELL_DATA")) {
            section = !strcasecmp(tok, "CELL_DATA");
            if ((s = vv_gcur_need_size(&c, tok, VV_GRID_MAX_CELLS, &section_n)) != VV_OK)
                goto done;
            if (section_n != (section ? n_cells : n_points)) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: %s %zu but the grid has %zu", path, tok,
                                 section_n, section ? n_cells : n_points);
                goto done;
            }
        } else if (!strcasecmp(tok, "SCALARS") || !strcasecmp(tok, "VECTORS") ||
                   !strcasecmp(tok, "NORMALS")) {
            char name[128], ty[64];
            vv_gtype t;
            const int scal = !strcasecmp(tok, "SCALARS");
            if (section < 0) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: %s outside POINT_DATA / CELL_DATA", path, tok);
                goto done;
            }
            if ((s = vv_gcur_need(&c, name, sizeof name, "field name")) != VV_OK ||
                (s = vv_gcur_need(&c, ty, sizeof ty, "field type")) != VV_OK)
                goto done;
            if (!vv_gtype_parse(ty, &t)) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: %s %s: unknown type \"%s\"", path, tok, name,
                                 ty);
                goto done;
            }
            int ncomp = scal ? 1 : 3;
            if (scal) {
                /* optional component count, then LOOKUP_TABLE name */
                const unsigned char *save = c.p;
                char nx[128];
                if (vv_gcur_token(&c, nx, sizeof nx) && isdigit((unsigned char)nx[0])) {
                    ncomp = atoi(nx);
                    if (ncomp < 1 || ncomp > 4) {
                        s = vv_error_set(VV_ERR_FORMAT, "%s: SCALARS %s: %d components", path, name,
                                         ncomp);
                        goto done;
                    }
                } else {
                    c.p = save;
                }
                save = c.p;
                if (vv_gcur_token(&c, nx, sizeof nx) && !strcasecmp(nx, "LOOKUP_TABLE"))
                    vv_gcur_token(&c, nx, sizeof nx);
                else
                    c.p = save;
            }
            if (binary)
                vv_gcur_skip_line(&c);
            if ((s = vtk_field(&c, g, binary, name, section, ncomp, t, section_n)) != VV_OK)
                goto done;
        } else if (!strcasecmp(tok, "FIELD")) {
            char name[128];
            size_t narr = 0;
            if ((s = vv_gcur_need(&c, name, sizeof name, "FIELD name")) != VV_OK ||
                (s = vv_gcur_need_size(&c, "FIELD arrays", VV_GRID_MAX_FIELDS, &narr)) != VV_OK)
                goto done;
            for (size_t a = 0; a < narr; a++) {
                char an[128], ty[64];
                size_t nc = 0, nt = 0;
                vv_gtype t;
                if ((s = vv_gcur_need(&c, an, sizeof an, "array name")) != VV_OK ||
                    (s = vv_gcur_need_size(&c, "components", 9, &nc)) != VV_OK ||
                    (s = vv_gcur_need_size(&c, "tuples", VV_GRID_MAX_POINTS, &nt)) != VV_OK ||
                    (s = vv_gcur_need(&c, ty, sizeof ty, "array type")) != VV_OK)
                    goto done;
                if (!vv_gtype_parse(ty, &t) || nc < 1) {
                    s = vv_error_set(VV_ERR_FORMAT, "%s: FIELD %s: bad array %s", path, name, an);
                    goto done;
                }
                if (binary)
                    vv_gcur_skip_line(&c);
                if (section < 0 || nt != section_n) {
                    s = vv_error_set(VV_ERR_FORMAT, "%s: FIELD array %s: %zu tuples", path, an, nt);
                    goto done;
                }
                if ((s = vtk_field(&c, g, binary, an, section, (int)nc, t, nt)) != VV_OK)
                    goto done;
            }
        } else if (!strcasecmp(tok, "LOOKUP_TABLE")) {
            char name[128];
            size_t n = 0;
            if ((s = vv_gcur_need(&c, name, sizeof name, "table name")) != VV_OK ||
                (s = vv_gcur_need_size(&c, "table size", 1u << 24, &n)) != VV_OK)
                goto done;
            if (binary)
                vv_gcur_skip_line(&c);
            if (binary) {
                if (4 * n > vv_gcur_left(&c)) {
                    s = vv_error_set(VV_ERR_FORMAT, "%s: LOOKUP_TABLE truncated", path);
                    goto done;
                }
                c.p += 4 * n;
            } else {
                for (size_t i = 0; i < 4 * n; i++)
                    if (!vv_gcur_token(&c, name, sizeof name))
                        break;
            }
        } else if (!strcasecmp(tok, "METADATA")) {
            /* skipped to the blank line that ends it */
            while (c.p < c.end) {
                vv_gcur_skip_line(&c);
                if (c.p < c.end && (*c.p == '\n' || *c.p == '\r'))
                    break;
            }
        } else {
            s = vv_error_set(VV_ERR_FORMAT, "%s: unexpected keyword \"%s\" at byte %zu", path, tok,
                             (size_t)(c.p - c.begin));
            goto done;
        }
    }
    if (!have_points || !have_cells || !have_types) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s missing", path,
                         !have_points  ? "POINTS"
                         : !have_cells ? "CELLS"
                                       : "CELL_TYPES");
        goto done;
    }
    free(counts);
    free(data);
    return vv_grid_finish(g, path, out);
done:
    free(tmp);
    free(data);
    vv_grid_free(g);
    return s;
}

/* ---------------------------------------------------------------------- */
/* OpenDX native files                                                      */

typedef struct dx_array {
    int id;        /* object number, or -1 for named objects */
    char name[64]; /* named object */
    vv_gtype type;
    int big_endian;
    int rank, shape;
    size_t items;
    int follows;   /* data follows: inline after the header line */
    size_t offset; /* data offset in the binary section */
    int text;      /* ascii data */
    const unsigned char *inline_data;
    char dep[64];     /* attribute "dep" */
    char element[64]; /* attribute "element type" */
} dx_array;

typedef struct dx_field {
    char name[64];
    int data, positions, connections; /* array ids, -1 none */
} dx_field;

#define DX_MAX_OBJ 256

static int
dx_quoted_or_number(vv_gcur *c, char *buf, size_t cap, int *id) {
    while (c->p < c->end && isspace(*c->p) && *c->p != '\n')
        c->p++;
    if (c->p < c->end && *c->p == '"') {
        c->p++;
        size_t n = 0;
        while (c->p < c->end && *c->p != '"' && *c->p != '\n') {
            /* binary junk never reaches an error message */
            if (n + 1 < cap)
                buf[n++] = (char)(*c->p >= 0x20 && *c->p <= 0x7e ? *c->p : '?');
            c->p++;
        }
        if (c->p < c->end && *c->p == '"')
            c->p++;
        buf[n] = '\0';
        *id = -1;
        return 1;
    }
    if (!vv_gcur_token(c, buf, cap))
        return 0;
    *id = atoi(buf);
    return 1;
}

static const dx_array *
dx_find(const dx_array *arr, int n, int id) {
    for (int i = 0; id >= 0 && i < n; i++)
        if (arr[i].id == id)
            return &arr[i];
    return NULL;
}

/* Reads an array's values as doubles. */
static vv_status
dx_values(const vv_gcur *c0, const unsigned char *binary_start, const dx_array *a, double *out) {
    const size_t n = a->items * (size_t)(a->shape > 0 ? a->shape : 1);
    vv_gcur c = *c0;
    if (a->follows) {
        c.p = a->inline_data;
        return vv_gcur_values(&c, !a->text, a->big_endian, a->type, n, out, "data follows");
    }
    if (!binary_start)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: array %d refers to data but the file has no "
                            "\"end\" line",
                            c.path, a->id);
    if (a->offset > (size_t)(c.end - binary_start))
        return vv_error_set(VV_ERR_FORMAT, "%s: array %d: data offset %zu is past the end", c.path,
                            a->id, a->offset);
    c.p = binary_start + a->offset;
    return vv_gcur_values(&c, !a->text, a->big_endian, a->type, n, out, "array data");
}

vv_status
vv_grid_read_dx(vv_grid **out, const char *path) {
    *out = NULL;
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, VV_GRID_FILE_MAX, &data, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "%s", path);
    vv_gcur c;
    vv_gcur_init(&c, data, (size_t)size, path);
    dx_array *arr = calloc(DX_MAX_OBJ, sizeof *arr);
    dx_field fields[DX_MAX_OBJ];
    int n_arr = 0, n_fields = 0;
    const unsigned char *binary_start = NULL;
    vv_grid *g = NULL;
    double *tmp = NULL;
    char tok[128];
    if (!arr) {
        free(data);
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
    }
    dx_array *cur = NULL;
    dx_field *curf = NULL;
    while (vv_gcur_token(&c, tok, sizeof tok)) {
        if (tok[0] == '#') {
            vv_gcur_skip_line(&c);
            continue;
        }
        if (!strcmp(tok, "end")) {
            vv_gcur_skip_line(&c);
            binary_start = c.p;
            break;
        }
        if (!strcmp(tok, "object")) {
            char name[64];
            int id;
            if (!dx_quoted_or_number(&c, name, sizeof name, &id)) {
                s = vv_error_set(VV_ERR_FORMAT, "%s: object without a name", path);
                goto done;
            }
            char cl[32], kind[32];
            if ((s = vv_gcur_need(&c, cl, sizeof cl, "class")) != VV_OK ||
                (s = vv_gcur_need(&c, kind, sizeof kind, "class name")) != VV_OK)
                goto done;
            cur = NULL;
            curf = NULL;
            if (!strcmp(kind, "array")) {
                if (n_arr >= DX_MAX_OBJ) {
                    s = vv_error_set(VV_ERR_LIMIT, "%s: more than %d arrays", path, DX_MAX_OBJ);
                    goto done;
                }
                cur = &arr[n_arr++];
                cur->id = id;
                snprintf(cur->name, sizeof cur->name, "%s", name);
                cur->type = VV_GT_F32;
                cur->big_endian = 1;
                cur->text = 1;
                cur->shape = 1;
                /* the rest of the line: type, rank, shape, items, byte order, data */
                while (c.p < c.end && *c.p != '\n') {
                    if (!vv_gcur_token(&c, tok, sizeof tok))
                        break;
                    if (!strcmp(tok, "type")) {
                        vv_gcur_token(&c, tok, sizeof tok);
                        if (!vv_gtype_parse(tok, &cur->type)) {
                            s = vv_error_set(VV_ERR_FORMAT, "%s: array %d: type %s", path, id, tok);
                            goto done;
                        }
                    } else if (!strcmp(tok, "rank")) {
                        vv_gcur_token(&c, tok, sizeof tok);
                        cur->rank = atoi(tok);
                    } else if (!strcmp(tok, "shape")) {
                        vv_gcur_token(&c, tok, sizeof tok);
                        cur->shape = atoi(tok);
                        if (cur->shape < 1 || cur->shape > 9) {
                            s = vv_error_set(VV_ERR_FORMAT, "%s: array %d: shape %d", path, id,
                                             cur->shape);
                            goto done;
                        }
                    } else if (!strcmp(tok, "items")) {
                        if ((s = vv_gcur_need_size(&c, "items", VV_GRID_MAX_POINTS, &cur->items)) !=
                            VV_OK)
                            goto done;
                    } else if (!strcmp(tok, "msb")) {
                        cur->big_endian = 1;
                    } else if (!strcmp(tok, "lsb")) {
                        cur->big_endian = 0;
                    } else if (!strcmp(tok, "ieee") || !strcmp(tok, "binary")) {
                        cur->text = 0;
                    } else if (!strcmp(tok, "ascii") || !strcmp(tok, "text")) {
                        cur->text = 1;
                    } else if (!strcmp(tok, "data")) {
                        vv_gcur_token(&c, tok, sizeof tok);
                        if (!strcmp(tok, "follows")) {
                            cur->follows = 1;
                            vv_gcur_skip_line(&c);
                            cur->inline_data = c.p;
                            /* skip the inline values */
                            const size_t n = cur->items * (size_t)cur->shape;
                            if (cur->text) {
                                for (size_t i = 0; i < n; i++)
                                    vv_gcur_token(&c, tok, sizeof tok);
                            } else {
                                const size_t nb = n * vv_gtype_size(cur->type);
                                if (nb > vv_gcur_left(&c)) {
                                    s = vv_error_set(VV_ERR_FORMAT, "%s: array %d truncated", path,
                                                     id);
                                    goto done;
                                }
                                c.p += nb;
                            }
                            break;
                        }
                        if (!strcmp(tok, "file")) {
                            s = vv_error_set(VV_ERR_UNSUPPORTED,
                                             "%s: array %d: data in another file", path, id);
                            goto done;
                        }
                        char *end;
                        const long long off = strtoll(tok, &end, 10);
                        if (*end || off < 0) {
                            s = vv_error_set(VV_ERR_FORMAT, "%s: array %d: data \"%s\"", path, id,
                                             tok);
                            goto done;
                        }
                        cur->offset = (size_t)off;
                    }
                }
            } else if (!strcmp(kind, "field")) {
                if (n_fields >= DX_MAX_OBJ) {
                    s = vv_error_set(VV_ERR_LIMIT, "%s: more than %d fields", path, DX_MAX_OBJ);
                    goto done;
                }
                curf = &fields[n_fields++];
                snprintf(curf->name, sizeof curf->name, "%s", id < 0 ? name : "field");
                curf->data = curf->positions = curf->connections = -1;
            }
            continue;
        }
        if (!strcmp(tok, "attribute")) {
            char an[64], av[64];
            int dummy;
            dx_quoted_or_number(&c, an, sizeof an, &dummy);
            vv_gcur_token(&c, tok, sizeof tok); /* "string" */
            dx_quoted_or_number(&c, av, sizeof av, &dummy);
            if (cur && !strcmp(an, "dep"))
                snprintf(cur->dep, sizeof cur->dep, "%s", av);
            else if (cur && !strcmp(an, "element type"))
                snprintf(cur->element, sizeof cur->element, "%s", av);
            else if (curf && !strcmp(an, "name"))
                snprintf(curf->name, sizeof curf->name, "%s", av);
            continue;
        }
        if (!strcmp(tok, "component") && curf) {
            char cn[64], val[64];
            int id, dummy;
            dx_quoted_or_number(&c, cn, sizeof cn, &dummy);
            vv_gcur_token(&c, tok, sizeof tok); /* "value" */
            dx_quoted_or_number(&c, val, sizeof val, &id);
            if (id < 0) {
                s = vv_error_set(VV_ERR_UNSUPPORTED,
                                 "%s: field %s: component %s by name is not supported", path,
                                 curf->name, cn);
                goto done;
            }
            if (!strcmp(cn, "data"))
                curf->data = id;
            else if (!strcmp(cn, "positions"))
                curf->positions = id;
            else if (!strcmp(cn, "connections"))
                curf->connections = id;
            continue;
        }
        vv_gcur_skip_line(&c); /* member, other keywords */
    }
    if (n_fields == 0) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: no field object", path);
        goto done;
    }
    /* the grid: positions and connections of the first field that has both */
    const dx_field *gf = NULL;
    for (int i = 0; i < n_fields && !gf; i++)
        if (fields[i].positions >= 0 && fields[i].connections >= 0)
            gf = &fields[i];
    if (!gf) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: no field has positions and connections", path);
        goto done;
    }
    const dx_array *pos = dx_find(arr, n_arr, gf->positions);
    const dx_array *con = dx_find(arr, n_arr, gf->connections);
    if (!pos || !con) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: field %s refers to a missing array", path, gf->name);
        goto done;
    }
    if (pos->shape != 3) {
        s = vv_error_set(VV_ERR_UNSUPPORTED, "%s: positions of shape %d (3 supported)", path,
                         pos->shape);
        goto done;
    }
    int ctype, per;
    if (!strcmp(con->element, "tetrahedra")) {
        ctype = VV_CELL_TETRA;
        per = 4;
    } else if (!strcmp(con->element, "cubes")) {
        ctype = VV_CELL_HEXAHEDRON;
        per = 8;
    } else if (!strcmp(con->element, "triangles")) {
        ctype = VV_CELL_TRIANGLE;
        per = 3;
    } else if (!strcmp(con->element, "quads")) {
        ctype = VV_CELL_QUAD;
        per = 4;
    } else {
        s = vv_error_set(VV_ERR_UNSUPPORTED, "%s: connections of element type \"%s\"", path,
                         con->element);
        goto done;
    }
    if (con->shape != per) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s connections of shape %d", path, con->element,
                         con->shape);
        goto done;
    }
    const size_t np = pos->items, nc = con->items;
    if ((s = vv_grid_new(&g, VV_GRID_UNSTRUCTURED)) != VV_OK ||
        (s = vv_grid_alloc(g, np, nc, nc * (size_t)per)) != VV_OK)
        goto done;
    if ((s = dx_values(&c, binary_start, pos, g->points)) != VV_OK)
        goto done;
    const size_t nconn = nc * (size_t)per;
    tmp = malloc((nconn ? nconn : 1) * sizeof *tmp);
    if (!tmp) {
        s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
        goto done;
    }
    if ((s = dx_values(&c, binary_start, con, tmp)) != VV_OK)
        goto done;
    /* DX cubes order their corners as bits (z fastest); VTK's hexahedron differs */
    static const int cube_to_vtk[8] = {0, 4, 6, 2, 1, 5, 7, 3};
    for (size_t i = 0; i < nc; i++) {
        for (int k = 0; k < per; k++) {
            const double v =
                tmp[i * (size_t)per + (size_t)(ctype == VV_CELL_HEXAHEDRON ? cube_to_vtk[k] : k)];
            if (!(v >= 0) || v >= (double)np) {
                s = vv_error_set(VV_ERR_FORMAT,
                                 "%s: connection %zu uses position %g but there are %zu", path, i,
                                 v, np);
                goto done;
            }
            g->connectivity[i * (size_t)per + (size_t)k] = (uint32_t)v;
        }
        g->cell_types[i] = (uint8_t)ctype;
        g->cell_offsets[i + 1] = (i + 1) * (size_t)per;
    }
    free(tmp);
    tmp = NULL;
    /* data of every field on these positions (or connections) */
    for (int i = 0; i < n_fields; i++) {
        const dx_array *d = fields[i].data >= 0 ? dx_find(arr, n_arr, fields[i].data) : NULL;
        if (!d)
            continue;
        const int cell = !strcmp(d->dep, "connections");
        if (d->items != (cell ? nc : np))
            continue; /* a field on other positions */
        vv_grid_field *f = NULL;
        if ((s = vv_grid_add_field(g, fields[i].name, cell, d->shape, &f)) != VV_OK)
            goto done;
        const size_t nv = d->items * (size_t)d->shape;
        tmp = malloc((nv ? nv : 1) * sizeof *tmp);
        if (!tmp) {
            s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
            goto done;
        }
        if ((s = dx_values(&c, binary_start, d, tmp)) != VV_OK)
            goto done;
        for (size_t k = 0; k < nv; k++)
            f->values[k] = (float)tmp[k];
        free(tmp);
        tmp = NULL;
    }
    free(arr);
    free(data);
    return vv_grid_finish(g, path, out);
done:
    free(tmp);
    free(arr);
    free(data);
    vv_grid_free(g);
    return s;
}
