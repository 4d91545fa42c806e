/*
 * VTK legacy UNSTRUCTURED_GRID files, ASCII and binary ("VTK User's Guide",
 * file formats), also the VTK 5.1 form of CELLS (OFFSETS and CONNECTIVITY).
 *
 * The reader holds the whole file in memory (at most VV_GRID_FILE_MAX
 * bytes) and checks every count against the bytes that remain before
 * allocating, so a header announcing a billion points in a small file fails
 * at once. Its stages: the header (version, title, ASCII/BINARY, DATASET),
 * then one function per keyword of the body (POINTS, CELLS, CELL_TYPES,
 * POINT_DATA/CELL_DATA, SCALARS/VECTORS/NORMALS, FIELD, LOOKUP_TABLE,
 * METADATA), each reading its section from the cursor.
 */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/internal.h"
#include "io/grid/grid_io_internal.h"
#include "io/io_internal.h"
#include "volvis/grid.h"
#include "volvis/sys/format.h"

/* A file being read. */
typedef struct vtk_reader {
    vv_gcur c;
    const char *path;
    vv_grid *g;
    int binary;
    size_t n_points, n_cells;
    int have_points, have_cells, have_types;
    int section;      /* data section: -1 none yet, 0 POINT_DATA, 1 CELL_DATA */
    size_t section_n; /* its tuple count */
} vtk_reader;

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

/* Allocates @p n_cells cells with @p n_conn point indices, keeping the
 * points already read. */
static vv_status
alloc_cells(vtk_reader *r, size_t n_cells, size_t n_conn) {
    vv_grid *g = r->g;
    double *pts = g->points;
    g->points = NULL;
    g->n_points = 0;
    vv_status s = vv_grid_alloc(g, 0, n_cells, n_conn);
    free(g->points);
    g->points = pts;
    g->n_points = r->n_points;
    return s;
}

/* The cells of a VTK 5.1 legacy file, after "CELLS n_offsets n_conn
 * OFFSETS": OFFSETS type, n_offsets values, CONNECTIVITY type, n_conn
 * values. */
static vv_status
vtk51_cells(vtk_reader *r, size_t n_off, size_t n_conn) {
    vv_gcur *c = &r->c;
    vv_grid *g = r->g;
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
    if ((s = alloc_cells(r, n_off - 1, n_conn)) != VV_OK)
        return s;
    double *tmp = malloc((n_off > n_conn ? n_off : n_conn ? n_conn : 1) * sizeof *tmp);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    if (r->binary)
        vv_gcur_skip_line(c);
    if ((s = vv_gcur_values(c, r->binary, 1, t, n_off, tmp, "OFFSETS")) != VV_OK)
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
    if (r->binary)
        vv_gcur_skip_line(c);
    if ((s = vv_gcur_values(c, r->binary, 1, t, n_conn, tmp, "CONNECTIVITY")) != VV_OK)
        goto done;
    for (size_t i = 0; i < n_conn; i++) {
        if (!(tmp[i] >= 0) || tmp[i] >= (double)r->n_points) {
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: CONNECTIVITY[%zu] uses point %g but there are %zu points",
                             c->path, i, tmp[i], r->n_points);
            goto done;
        }
        g->connectivity[i] = (uint32_t)tmp[i];
    }
done:
    free(tmp);
    return s;
}

/* The header: version and title lines, ASCII or BINARY, DATASET
 * UNSTRUCTURED_GRID. */
static vv_status
vtk_header(vtk_reader *r) {
    char tok[256];
    vv_status s;
    if (vv_gcur_left(&r->c) < 14 || strncmp((const char *)r->c.p, "# vtk DataFile", 14) != 0)
        return vv_error_set(VV_ERR_FORMAT, "%s: not a VTK legacy file", r->path);
    vv_gcur_skip_line(&r->c); /* version */
    vv_gcur_skip_line(&r->c); /* title */
    if ((s = vv_gcur_need(&r->c, tok, sizeof tok, "ASCII or BINARY")) != VV_OK)
        return s;
    r->binary = !strcasecmp(tok, "BINARY");
    if (!r->binary && strcasecmp(tok, "ASCII"))
        return vv_error_set(VV_ERR_FORMAT, "%s: expected ASCII or BINARY, got \"%s\"", r->path,
                            tok);
    if ((s = vv_gcur_need(&r->c, tok, sizeof tok, "DATASET")) != VV_OK ||
        (s = vv_gcur_need(&r->c, tok + 128, 128, "dataset type")) != VV_OK)
        return s;
    if (strcasecmp(tok, "DATASET") || strcasecmp(tok + 128, "UNSTRUCTURED_GRID"))
        return vv_error_set(VV_ERR_FORMAT, "%s: \"%s %s\" is not DATASET UNSTRUCTURED_GRID",
                            r->path, tok, tok + 128);
    return vv_grid_new(&r->g, VV_GRID_UNSTRUCTURED);
}

/* POINTS n type, then 3n values. */
static vv_status
vtk_points(vtk_reader *r) {
    char ty[64];
    vv_gtype t;
    vv_status s;
    /* a second POINTS would reallocate the grid under the cells and fields
       already read for the first (CELL_TYPES then wrote past the types) */
    if (r->have_points)
        return vv_error_set(VV_ERR_FORMAT, "%s: POINTS given twice", r->path);
    if ((s = vv_gcur_need_size(&r->c, "POINTS count", VV_GRID_MAX_POINTS, &r->n_points)) != VV_OK ||
        (s = vv_gcur_need(&r->c, ty, sizeof ty, "POINTS type")) != VV_OK)
        return s;
    if (!vv_gtype_parse(ty, &t))
        return vv_error_set(VV_ERR_FORMAT, "%s: POINTS: unknown type \"%s\"", r->path, ty);
    if (3 * r->n_points > vv_gcur_left(&r->c))
        return vv_error_set(VV_ERR_FORMAT, "%s: POINTS %zu: the file has only %zu bytes left",
                            r->path, r->n_points, vv_gcur_left(&r->c));
    if (r->binary)
        vv_gcur_skip_line(&r->c);
    if ((s = vv_grid_alloc(r->g, r->n_points, 0, 0)) != VV_OK ||
        (s = vv_gcur_values(&r->c, r->binary, 1, t, 3 * r->n_points, r->g->points, "POINTS")) !=
            VV_OK)
        return s;
    r->have_points = 1;
    return VV_OK;
}

/* The classic CELLS list: per cell its point count, then its points. */
static vv_status
vtk_cell_list(vtk_reader *r, size_t n_ints, double *tmp) {
    vv_grid *g = r->g;
    const size_t n_cells = r->n_cells;
    vv_status s = vv_gcur_values(&r->c, r->binary, 1, VV_GT_I32, n_ints, tmp, "CELLS");
    if (s != VV_OK)
        return s;
    size_t k = 0, o = 0;
    for (size_t i = 0; i < n_cells; i++) {
        const double cnt = tmp[k++];
        /* the ints left, less one count for each cell still to come */
        if (!(cnt >= 1) || cnt > (double)(n_ints - k - (n_cells - 1 - i)))
            return vv_error_set(VV_ERR_FORMAT, "%s: CELLS: cell %zu has %g points", r->path, i,
                                cnt);
        for (size_t j = 0; j < (size_t)cnt; j++) {
            const double v = tmp[k++];
            if (!(v >= 0) || v >= (double)r->n_points)
                return vv_error_set(VV_ERR_FORMAT,
                                    "%s: CELLS: cell %zu uses point %g but there are %zu "
                                    "points",
                                    r->path, i, v, r->n_points);
            g->connectivity[o++] = (uint32_t)v;
        }
        g->cell_offsets[i + 1] = o;
    }
    if (o != n_ints - n_cells)
        return vv_error_set(VV_ERR_FORMAT, "%s: CELLS: size %zu disagrees with the cells", r->path,
                            n_ints);
    return VV_OK;
}

/* CELLS n size: the classic list, or the VTK 5.1 OFFSETS and CONNECTIVITY. */
static vv_status
vtk_cells(vtk_reader *r) {
    size_t n_ints = 0;
    vv_status s;
    if ((s = vv_gcur_need_size(&r->c, "CELLS count", VV_GRID_MAX_CELLS, &r->n_cells)) != VV_OK ||
        (s = vv_gcur_need_size(&r->c, "CELLS size", (size_t)VV_GRID_MAX_CELLS * 9, &n_ints)) !=
            VV_OK)
        return s;
    if (!r->have_points)
        return vv_error_set(VV_ERR_FORMAT, "%s: CELLS before POINTS", r->path);
    if (r->have_cells)
        return vv_error_set(VV_ERR_FORMAT, "%s: CELLS given twice", r->path);
    /* VTK 5.1: CELLS n_offsets n_connectivity, then OFFSETS and CONNECTIVITY */
    const unsigned char *save = r->c.p;
    char kw[64];
    if (vv_gcur_token(&r->c, kw, sizeof kw) && !strcasecmp(kw, "OFFSETS")) {
        if ((s = vtk51_cells(r, r->n_cells, n_ints)) != VV_OK)
            return s;
        r->n_cells = r->n_cells ? r->n_cells - 1 : 0;
        r->have_cells = 1;
        return VV_OK;
    }
    r->c.p = save;
    if (n_ints > vv_gcur_left(&r->c) || n_ints < r->n_cells)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: CELLS %zu %zu: inconsistent with the %zu bytes "
                            "left",
                            r->path, r->n_cells, n_ints, vv_gcur_left(&r->c));
    if (r->binary)
        vv_gcur_skip_line(&r->c);
    if ((s = alloc_cells(r, r->n_cells, n_ints - r->n_cells)) != VV_OK)
        return s;
    double *tmp = malloc((n_ints ? n_ints : 1) * sizeof *tmp);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", r->path);
    s = vtk_cell_list(r, n_ints, tmp);
    free(tmp);
    if (s == VV_OK)
        r->have_cells = 1;
    return s;
}

/* CELL_TYPES n, then n VTK cell-type numbers. */
static vv_status
vtk_cell_types(vtk_reader *r) {
    size_t n_types = 0;
    vv_status s = vv_gcur_need_size(&r->c, "CELL_TYPES count", VV_GRID_MAX_CELLS, &n_types);
    if (s != VV_OK)
        return s;
    if (!r->have_cells || n_types != r->n_cells)
        return vv_error_set(VV_ERR_FORMAT, "%s: CELL_TYPES %zu without CELLS of as many", r->path,
                            n_types);
    if (r->binary)
        vv_gcur_skip_line(&r->c);
    double *tmp = malloc((n_types ? n_types : 1) * sizeof *tmp);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", r->path);
    s = vv_gcur_values(&r->c, r->binary, 1, VV_GT_I32, n_types, tmp, "CELL_TYPES");
    for (size_t i = 0; s == VV_OK && i < n_types; i++)
        r->g->cell_types[i] = (uint8_t)(tmp[i] >= 0 && tmp[i] < 256 ? tmp[i] : 255);
    free(tmp);
    if (s == VV_OK)
        r->have_types = 1;
    return s;
}

/* POINT_DATA n or CELL_DATA n (@p kw): the section the fields that follow are in. */
static vv_status
vtk_section(vtk_reader *r, const char *kw) {
    r->section = !strcasecmp(kw, "CELL_DATA");
    vv_status s = vv_gcur_need_size(&r->c, kw, VV_GRID_MAX_CELLS, &r->section_n);
    if (s != VV_OK)
        return s;
    const size_t have = r->section ? r->n_cells : r->n_points;
    if (r->section_n != have)
        return vv_error_set(VV_ERR_FORMAT, "%s: %s %zu but the grid has %zu", r->path, kw,
                            r->section_n, have);
    return VV_OK;
}

/* SCALARS name type [n] [LOOKUP_TABLE t], VECTORS name type, NORMALS name type (@p kw). */
static vv_status
vtk_attribute(vtk_reader *r, const char *kw) {
    char name[128], ty[64];
    vv_gtype t;
    const int scal = !strcasecmp(kw, "SCALARS");
    vv_status s;
    if (r->section < 0)
        return vv_error_set(VV_ERR_FORMAT, "%s: %s outside POINT_DATA / CELL_DATA", r->path, kw);
    if ((s = vv_gcur_need(&r->c, name, sizeof name, "field name")) != VV_OK ||
        (s = vv_gcur_need(&r->c, ty, sizeof ty, "field type")) != VV_OK)
        return s;
    if (!vv_gtype_parse(ty, &t))
        return vv_error_set(VV_ERR_FORMAT, "%s: %s %s: unknown type \"%s\"", r->path, kw, name, ty);
    int ncomp = scal ? 1 : 3;
    if (scal) {
        /* optional component count, then LOOKUP_TABLE name */
        const unsigned char *save = r->c.p;
        char nx[128];
        if (vv_gcur_token(&r->c, nx, sizeof nx) && isdigit((unsigned char)nx[0])) {
            /* strtol, not atoi: 4294967297 is not 1 */
            char *end;
            const long v = strtol(nx, &end, 10);
            if (*end || v < 1 || v > 4)
                return vv_error_set(VV_ERR_FORMAT, "%s: SCALARS %s: %s components", r->path, name,
                                    nx);
            ncomp = (int)v;
        } else {
            r->c.p = save;
        }
        save = r->c.p;
        if (vv_gcur_token(&r->c, nx, sizeof nx) && !strcasecmp(nx, "LOOKUP_TABLE"))
            vv_gcur_token(&r->c, nx, sizeof nx);
        else
            r->c.p = save;
    }
    if (r->binary)
        vv_gcur_skip_line(&r->c);
    return vtk_field(&r->c, r->g, r->binary, name, r->section, ncomp, t, r->section_n);
}

/* FIELD name n, then n arrays: name components tuples type, values. */
static vv_status
vtk_field_data(vtk_reader *r) {
    char name[128];
    size_t narr = 0;
    vv_status s;
    if ((s = vv_gcur_need(&r->c, name, sizeof name, "FIELD name")) != VV_OK ||
        (s = vv_gcur_need_size(&r->c, "FIELD arrays", VV_GRID_MAX_FIELDS, &narr)) != VV_OK)
        return s;
    for (size_t a = 0; a < narr; a++) {
        char an[128], ty[64];
        size_t nc = 0, nt = 0;
        vv_gtype t;
        if ((s = vv_gcur_need(&r->c, an, sizeof an, "array name")) != VV_OK ||
            (s = vv_gcur_need_size(&r->c, "components", 9, &nc)) != VV_OK ||
            (s = vv_gcur_need_size(&r->c, "tuples", VV_GRID_MAX_POINTS, &nt)) != VV_OK ||
            (s = vv_gcur_need(&r->c, ty, sizeof ty, "array type")) != VV_OK)
            return s;
        if (!vv_gtype_parse(ty, &t) || nc < 1)
            return vv_error_set(VV_ERR_FORMAT, "%s: FIELD %s: bad array %s", r->path, name, an);
        if (r->binary)
            vv_gcur_skip_line(&r->c);
        if (r->section < 0 || nt != r->section_n)
            return vv_error_set(VV_ERR_FORMAT, "%s: FIELD array %s: %zu tuples", r->path, an, nt);
        if ((s = vtk_field(&r->c, r->g, r->binary, an, r->section, (int)nc, t, nt)) != VV_OK)
            return s;
    }
    return VV_OK;
}

/* LOOKUP_TABLE name n: skipped (4n colour values). */
static vv_status
vtk_lookup_table(vtk_reader *r) {
    char name[128];
    size_t n = 0;
    vv_status s;
    if ((s = vv_gcur_need(&r->c, name, sizeof name, "table name")) != VV_OK ||
        (s = vv_gcur_need_size(&r->c, "table size", 1u << 24, &n)) != VV_OK)
        return s;
    if (r->binary) {
        vv_gcur_skip_line(&r->c);
        if (4 * n > vv_gcur_left(&r->c))
            return vv_error_set(VV_ERR_FORMAT, "%s: LOOKUP_TABLE truncated", r->path);
        r->c.p += 4 * n;
        return VV_OK;
    }
    for (size_t i = 0; i < 4 * n; i++)
        if (!vv_gcur_token(&r->c, name, sizeof name))
            break;
    return VV_OK;
}

/* The section of keyword @p kw. */
static vv_status
vtk_keyword(vtk_reader *r, const char *kw) {
    if (!strcasecmp(kw, "POINTS"))
        return vtk_points(r);
    if (!strcasecmp(kw, "CELLS"))
        return vtk_cells(r);
    if (!strcasecmp(kw, "CELL_TYPES"))
        return vtk_cell_types(r);
    if (!strcasecmp(kw, "POINT_DATA") || !strcasecmp(kw, "CELL_DATA"))
        return vtk_section(r, kw);
    if (!strcasecmp(kw, "SCALARS") || !strcasecmp(kw, "VECTORS") || !strcasecmp(kw, "NORMALS"))
        return vtk_attribute(r, kw);
    if (!strcasecmp(kw, "FIELD"))
        return vtk_field_data(r);
    if (!strcasecmp(kw, "LOOKUP_TABLE"))
        return vtk_lookup_table(r);
    if (!strcasecmp(kw, "METADATA")) {
        /* skipped to the blank line that ends it */
        while (r->c.p < r->c.end) {
            vv_gcur_skip_line(&r->c);
            if (r->c.p < r->c.end && (*r->c.p == '\n' || *r->c.p == '\r'))
                break;
        }
        return VV_OK;
    }
    return vv_error_set(VV_ERR_FORMAT, "%s: unexpected keyword \"%s\" at byte %zu", r->path, kw,
                        (size_t)(r->c.p - r->c.begin));
}

vv_status
vv_grid_read_vtk(vv_grid **out, const char *path) {
    *out = NULL;
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, VV_GRID_FILE_MAX, &data, &size);
    if (s != VV_OK)
        return s; /* the message names the file */
    vtk_reader r;
    memset(&r, 0, sizeof r);
    r.path = path;
    r.section = -1;
    vv_gcur_init(&r.c, data, (size_t)size, path);
    char tok[256];
    s = vtk_header(&r);
    while (s == VV_OK && vv_gcur_token(&r.c, tok, sizeof tok))
        s = vtk_keyword(&r, tok);
    if (s == VV_OK && (!r.have_points || !r.have_cells || !r.have_types))
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s missing", path,
                         !r.have_points  ? "POINTS"
                         : !r.have_cells ? "CELLS"
                                         : "CELL_TYPES");
    free(data);
    if (s != VV_OK) {
        vv_grid_free(r.g);
        return s;
    }
    return vv_grid_finish(r.g, path, out);
}

/* ---- the format record ------------------------------------------------------ */

/* "# vtk DataFile" with UNSTRUCTURED_GRID in the head. */
static int
vtk_grid_looks_like(const vv_format_probe *p, int deep) {
    return !deep && !strncmp(p->text, "# vtk DataFile", 14) &&
           strstr(p->text, "UNSTRUCTURED_GRID") != NULL;
}

static const char *const vtk_extensions[] = {"vtk", NULL};

const vv_format_record vv_format_vtk_grid = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "vtk_grid",
    .title = "VTK UNSTRUCTURED_GRID",
    .extensions = vtk_extensions,
    .doc = "VTK legacy UNSTRUCTURED_GRID, ASCII or binary (also 5.1 OFFSETS/CONNECTIVITY)",
    .holds = VV_DATA_GRID,
    .looks_like = vtk_grid_looks_like,
    .read_grid = vv_grid_read_vtk,
};
