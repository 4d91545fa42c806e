/* Irregular grids: the data model (see volvis/grid.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "volvis/grid.h"

/** Points of a cell type (0 for types the grid model does not know). */
static int
cell_type_points(int type) {
    switch (type) {
    case VV_CELL_VERTEX:
        return 1;
    case VV_CELL_LINE:
        return 2;
    case VV_CELL_TRIANGLE:
        return 3;
    case VV_CELL_QUAD:
    case VV_CELL_TETRA:
        return 4;
    case VV_CELL_HEXAHEDRON:
        return 8;
    case VV_CELL_WEDGE:
        return 6;
    case VV_CELL_PYRAMID:
        return 5;
    default:
        return 0;
    }
}

const char *
vv_cell_type_name(int type) {
    switch (type) {
    case VV_CELL_VERTEX:
        return "vertex";
    case VV_CELL_LINE:
        return "line";
    case VV_CELL_TRIANGLE:
        return "triangle";
    case VV_CELL_POLYGON:
        return "polygon";
    case VV_CELL_QUAD:
        return "quad";
    case VV_CELL_TETRA:
        return "tetra";
    case VV_CELL_HEXAHEDRON:
        return "hexahedron";
    case VV_CELL_WEDGE:
        return "wedge";
    case VV_CELL_PYRAMID:
        return "pyramid";
    default:
        return "unknown";
    }
}

/** 1 for the 3-D types (tetra, hexahedron, wedge, pyramid). */
static int
cell_type_is_3d(int type) {
    return type == VV_CELL_TETRA || type == VV_CELL_HEXAHEDRON || type == VV_CELL_WEDGE ||
           type == VV_CELL_PYRAMID;
}

const char *
vv_grid_kind_name(vv_grid_kind k) {
    switch (k) {
    case VV_GRID_UNSTRUCTURED:
        return "unstructured";
    case VV_GRID_CURVILINEAR:
        return "curvilinear";
    case VV_GRID_SPHERICAL:
        return "spherical";
    }
    return "unknown";
}

vv_status
vv_grid_new(vv_grid **out, vv_grid_kind kind) {
    *out = calloc(1, sizeof **out);
    if (!*out)
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory");
    (*out)->kind = kind;
    (*out)->refcount = 1;
    return VV_OK;
}

vv_grid *
vv_grid_ref(vv_grid *g) {
    if (g) {
#pragma omp atomic
        g->refcount++;
    }
    return g;
}

void
vv_grid_free(vv_grid *g) {
    if (!g)
        return;
    int left;
#pragma omp atomic capture
    left = --g->refcount;
    if (left > 0)
        return;
    free(g->points);
    free(g->cell_types);
    free(g->cell_offsets);
    free(g->connectivity);
    free(g->block_dims);
    for (int a = 0; a < 3; a++)
        free(g->sph_axes[a]);
    for (int i = 0; i < g->n_fields; i++)
        free(g->fields[i].values);
    free(g->fields);
    free(g);
}

vv_status
vv_grid_alloc(vv_grid *g, size_t n_points, size_t n_cells, size_t n_conn) {
    if (n_points > VV_GRID_MAX_POINTS)
        return vv_error_set(VV_ERR_LIMIT, "grid: %zu points (at most %u)", n_points,
                            VV_GRID_MAX_POINTS);
    if (n_cells > VV_GRID_MAX_CELLS)
        return vv_error_set(VV_ERR_LIMIT, "grid: %zu cells (at most %u)", n_cells,
                            VV_GRID_MAX_CELLS);
    if (n_conn > (size_t)VV_GRID_MAX_CELLS * 8u)
        return vv_error_set(VV_ERR_LIMIT, "grid: %zu point indices in cells (at most %zu)", n_conn,
                            (size_t)VV_GRID_MAX_CELLS * 8u);
    uint64_t bytes = (uint64_t)n_points * 3 * sizeof *g->points + (uint64_t)n_cells * 9 +
                     (uint64_t)n_conn * sizeof *g->connectivity;
    vv_status sb = vv_memory_budget_check(bytes, "grid");
    if (sb != VV_OK)
        return sb;
    free(g->points);
    free(g->cell_types);
    free(g->cell_offsets);
    free(g->connectivity);
    g->points = calloc(n_points ? 3 * n_points : 1, sizeof *g->points);
    g->cell_types = calloc(n_cells ? n_cells : 1, 1);
    g->cell_offsets = calloc(n_cells + 1, sizeof *g->cell_offsets);
    g->connectivity = calloc(n_conn ? n_conn : 1, sizeof *g->connectivity);
    g->n_points = n_points;
    g->n_cells = n_cells;
    if (!g->points || !g->cell_types || !g->cell_offsets || !g->connectivity) {
        free(g->points);
        free(g->cell_types);
        free(g->cell_offsets);
        free(g->connectivity);
        g->points = NULL;
        g->cell_types = NULL;
        g->cell_offsets = NULL;
        g->connectivity = NULL;
        g->n_points = g->n_cells = 0;
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory for %zu points and %zu cells",
                            n_points, n_cells);
    }
    return VV_OK;
}

vv_status
vv_grid_add_field(vv_grid *g, const char *name, int cell_data, int n_components,
                  vv_grid_field **out) {
    if (g->n_fields >= VV_GRID_MAX_FIELDS)
        return vv_error_set(VV_ERR_LIMIT, "grid: more than %d fields", VV_GRID_MAX_FIELDS);
    if (n_components < 1 || n_components > 9)
        return vv_error_set(VV_ERR_INVALID, "grid: field '%s' has %d components (1..9)",
                            name ? name : "", n_components);
    size_t n = cell_data ? g->n_cells : g->n_points;
    float *vals = calloc(n ? n * (size_t)n_components : 1, sizeof *vals);
    if (!vals)
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory for field '%s'", name ? name : "");
    vv_grid_field *nf = realloc(g->fields, (size_t)(g->n_fields + 1) * sizeof *nf);
    if (!nf) {
        free(vals);
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory");
    }
    g->fields = nf;
    vv_grid_field *f = &g->fields[g->n_fields++];
    memset(f, 0, sizeof *f);
    snprintf(f->name, sizeof f->name, "%s", name ? name : "field");
    f->cell_data = cell_data;
    f->n_components = n_components;
    f->values = vals;
    f->n_tuples = n;
    *out = f;
    return VV_OK;
}

int
vv_grid_field_missing(const vv_grid_field *f, size_t i) {
    for (int c = 0; c < f->n_components; c++) {
        const float v = f->values[i * (size_t)f->n_components + (size_t)c];
        if (v != v || (f->has_fill && (double)v == f->fill))
            return 1;
    }
    return 0;
}

static double
tuple_scalar(const vv_grid_field *f, size_t i, int component) {
    const float *v = f->values + i * (size_t)f->n_components;
    if (f->n_components == 1)
        return v[0];
    if (component >= 0)
        return v[component];
    double s = 0;
    for (int c = 0; c < f->n_components; c++)
        s += (double)v[c] * v[c];
    return sqrt(s);
}

void
vv_grid_field_update_range(vv_grid_field *f) {
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < f->n_tuples; i++) {
        if (vv_grid_field_missing(f, i))
            continue;
        double s = tuple_scalar(f, i, -1);
        lo = s < lo ? s : lo;
        hi = s > hi ? s : hi;
    }
    if (lo > hi)
        lo = hi = 0;
    f->range[0] = lo;
    f->range[1] = hi;
}

int
vv_grid_find_field(const vv_grid *g, const char *name, int time) {
    if (!name || !name[0])
        return g->n_fields > 0 ? 0 : -1;
    char buf[VV_GRID_FIELD_NAME_MAX + 16];
    snprintf(buf, sizeof buf, "%s%d", name, time);
    int exact = -1;
    for (int i = 0; i < g->n_fields; i++) {
        if (time > 0 && strcmp(g->fields[i].name, buf) == 0)
            return i;
        if (exact < 0 && strcmp(g->fields[i].name, name) == 0)
            exact = i;
    }
    if (exact >= 0)
        return exact; /* a field without time steps */
    for (int i = 0; time == 0 && i < g->n_fields; i++)
        if (strcmp(g->fields[i].name, buf) == 0)
            return i;
    return -1;
}

vv_status
vv_grid_field_scalars(const vv_grid *g, int field, int component, float **out) {
    *out = NULL;
    if (field < 0 || field >= g->n_fields)
        return vv_error_set(VV_ERR_INVALID, "grid: no field %d (the grid has %d)", field,
                            g->n_fields);
    const vv_grid_field *f = &g->fields[field];
    if (component >= f->n_components)
        return vv_error_set(VV_ERR_INVALID, "grid: field '%s' has %d components, not %d", f->name,
                            f->n_components, component + 1);
    float *s = malloc((f->n_tuples ? f->n_tuples : 1) * sizeof *s);
    if (!s)
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory");
    for (size_t i = 0; i < f->n_tuples; i++)
        s[i] = vv_grid_field_missing(f, i) ? NAN : (float)tuple_scalar(f, i, component);
    *out = s;
    return VV_OK;
}

vv_status
vv_grid_validate(const vv_grid *g) {
    for (size_t i = 0; i < 3 * g->n_points; i++)
        if (!isfinite(g->points[i]))
            return vv_error_set(VV_ERR_FORMAT,
                                "grid: point %zu has a coordinate that is not finite", i / 3);
    if (g->n_cells && (!g->cell_offsets || g->cell_offsets[0] != 0))
        return vv_error_set(VV_ERR_FORMAT, "grid: cell offsets do not start at 0");
    for (size_t c = 0; c < g->n_cells; c++) {
        const int t = g->cell_types[c];
        const size_t o0 = g->cell_offsets[c], o1 = g->cell_offsets[c + 1];
        if (o1 < o0)
            return vv_error_set(VV_ERR_FORMAT, "grid: cell %zu: offsets decrease", c);
        const int np = cell_type_points(t);
        if (t == VV_CELL_POLYGON) {
            if (o1 - o0 < 3)
                return vv_error_set(VV_ERR_FORMAT, "grid: cell %zu: polygon of %zu points", c,
                                    o1 - o0);
        } else if (np == 0) {
            return vv_error_set(VV_ERR_FORMAT, "grid: cell %zu: unsupported cell type %d", c, t);
        } else if (o1 - o0 != (size_t)np) {
            return vv_error_set(VV_ERR_FORMAT, "grid: cell %zu: a %s has %d points, not %zu", c,
                                vv_cell_type_name(t), np, o1 - o0);
        }
        for (size_t k = o0; k < o1; k++)
            if (g->connectivity[k] >= g->n_points)
                return vv_error_set(VV_ERR_FORMAT,
                                    "grid: cell %zu (%s) uses point %u but there are %zu points", c,
                                    vv_cell_type_name(t), g->connectivity[k], g->n_points);
    }
    for (int i = 0; i < g->n_fields; i++) {
        const vv_grid_field *f = &g->fields[i];
        if (f->n_tuples != (f->cell_data ? g->n_cells : g->n_points))
            return vv_error_set(VV_ERR_FORMAT, "grid: field '%s' has %zu tuples for %zu %s",
                                f->name, f->n_tuples, f->cell_data ? g->n_cells : g->n_points,
                                f->cell_data ? "cells" : "points");
    }
    return VV_OK;
}

vv_box
vv_grid_bounds(const vv_grid *g) {
    vv_box b = {{0, 0, 0}, {0, 0, 0}};
    if (!g->n_points)
        return b;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < g->n_points; i++)
        for (int a = 0; a < 3; a++) {
            const double x = g->points[3 * i + (size_t)a];
            lo[a] = x < lo[a] ? x : lo[a];
            hi[a] = x > hi[a] ? x : hi[a];
        }
    b.min = vv_vec3_make(lo[0], lo[1], lo[2]);
    b.max = vv_vec3_make(hi[0], hi[1], hi[2]);
    return b;
}

void
vv_grid_count_cells(const vv_grid *g, size_t *n3d, size_t *n_surface) {
    size_t a = 0, s = 0;
    for (size_t c = 0; c < g->n_cells; c++) {
        const int t = g->cell_types[c];
        a += cell_type_is_3d(t);
        s += t == VV_CELL_TRIANGLE || t == VV_CELL_QUAD || t == VV_CELL_POLYGON;
    }
    if (n3d)
        *n3d = a;
    if (n_surface)
        *n_surface = s;
}

/* Appends a lattice of dims points (already in g->points from p0) as hexahedra. */
static vv_status
append_lattice_cells(vv_grid *g, size_t p0, const int dims[3], int wrap_k) {
    const size_t ni = (size_t)dims[0], nj = (size_t)dims[1], nk = (size_t)dims[2];
    const size_t nck = wrap_k ? nk : nk - 1;
    const size_t nc = (ni - 1) * (nj - 1) * nck;
    const size_t c0 = g->n_cells;
    if (c0 + nc > VV_GRID_MAX_CELLS)
        return vv_error_set(VV_ERR_LIMIT, "grid: %zu cells (at most %u)", c0 + nc,
                            VV_GRID_MAX_CELLS);
    uint8_t *ct = realloc(g->cell_types, c0 + nc ? c0 + nc : 1);
    if (!ct)
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory");
    g->cell_types = ct;
    size_t *co = realloc(g->cell_offsets, (c0 + nc + 1) * sizeof *co);
    if (!co)
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory");
    g->cell_offsets = co;
    if (c0 == 0)
        co[0] = 0;
    const size_t k0 = co[c0];
    uint32_t *cn = realloc(g->connectivity, (k0 + 8 * nc) * sizeof *cn);
    if (!cn)
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory");
    g->connectivity = cn;
    size_t c = c0;
    for (size_t k = 0; k < nck; k++)
        for (size_t j = 0; j + 1 < nj; j++)
            for (size_t i = 0; i + 1 < ni; i++, c++) {
                const size_t k1 = (k + 1) % nk;
#define LP(ii, jj, kk) (uint32_t)(p0 + ((kk)*nj + (jj)) * ni + (ii))
                uint32_t *h = cn + co[c];
                h[0] = LP(i, j, k);
                h[1] = LP(i + 1, j, k);
                h[2] = LP(i + 1, j + 1, k);
                h[3] = LP(i, j + 1, k);
                h[4] = LP(i, j, k1);
                h[5] = LP(i + 1, j, k1);
                h[6] = LP(i + 1, j + 1, k1);
                h[7] = LP(i, j + 1, k1);
#undef LP
                ct[c] = VV_CELL_HEXAHEDRON;
                co[c + 1] = co[c] + 8;
            }
    g->n_cells = c0 + nc;
    return VV_OK;
}

vv_status
vv_grid_add_block(vv_grid *g, const int dims[3], const double *xyz) {
    for (int a = 0; a < 3; a++)
        if (dims[a] < 2)
            return vv_error_set(VV_ERR_INVALID, "grid: block dimension %d is %d (at least 2)", a,
                                dims[a]);
    if (g->n_blocks >= VV_GRID_MAX_BLOCKS)
        return vv_error_set(VV_ERR_LIMIT, "grid: more than %d blocks", VV_GRID_MAX_BLOCKS);
    const size_t np = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
    if (g->n_points + np > VV_GRID_MAX_POINTS)
        return vv_error_set(VV_ERR_LIMIT, "grid: %zu points (at most %u)", g->n_points + np,
                            VV_GRID_MAX_POINTS);
    double *pts = realloc(g->points, 3 * (g->n_points + np) * sizeof *pts);
    if (!pts)
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory");
    g->points = pts;
    memcpy(pts + 3 * g->n_points, xyz, 3 * np * sizeof *pts);
    const size_t p0 = g->n_points;
    g->n_points += np;
    int(*bd)[3] = realloc(g->block_dims, (size_t)(g->n_blocks + 1) * sizeof *bd);
    if (!bd)
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory");
    g->block_dims = bd;
    memcpy(bd[g->n_blocks++], dims, sizeof bd[0]);
    return append_lattice_cells(g, p0, dims, 0);
}

vv_status
vv_grid_new_spherical(vv_grid **out, const double *r, int nr, const double *theta, int ntheta,
                      const double *phi, int nphi, int wrap_phi) {
    *out = NULL;
    const double *ax[3] = {r, theta, phi};
    const int n[3] = {nr, ntheta, nphi};
    static const char *names[3] = {"r", "theta", "phi"};
    for (int a = 0; a < 3; a++) {
        if (n[a] < 2)
            return vv_error_set(VV_ERR_INVALID, "spherical grid: axis %s has %d values (>= 2)",
                                names[a], n[a]);
        for (int i = 1; i < n[a]; i++)
            if (!(ax[a][i] > ax[a][i - 1]))
                return vv_error_set(VV_ERR_INVALID,
                                    "spherical grid: axis %s does not increase at %d", names[a], i);
    }
    const size_t np = (size_t)nr * (size_t)ntheta * (size_t)nphi;
    if (np > VV_GRID_MAX_POINTS)
        return vv_error_set(VV_ERR_LIMIT, "spherical grid: %zu points (at most %u)", np,
                            VV_GRID_MAX_POINTS);
    vv_grid *g = NULL;
    vv_status s = vv_grid_new(&g, VV_GRID_SPHERICAL);
    if (s != VV_OK)
        return s;
    g->points = malloc(3 * np * sizeof *g->points);
    for (int a = 0; a < 3; a++) {
        g->sph_dims[a] = n[a];
        g->sph_axes[a] = malloc((size_t)n[a] * sizeof(double));
        if (g->sph_axes[a])
            memcpy(g->sph_axes[a], ax[a], (size_t)n[a] * sizeof(double));
    }
    if (!g->points || !g->sph_axes[0] || !g->sph_axes[1] || !g->sph_axes[2]) {
        vv_grid_free(g);
        return vv_error_set(VV_ERR_NOMEM, "spherical grid: out of memory");
    }
    size_t p = 0;
    for (int k = 0; k < nphi; k++)
        for (int j = 0; j < ntheta; j++)
            for (int i = 0; i < nr; i++, p++) {
                const double st = sin(theta[j]), ct = cos(theta[j]);
                g->points[3 * p + 0] = r[i] * st * cos(phi[k]);
                g->points[3 * p + 1] = r[i] * st * sin(phi[k]);
                g->points[3 * p + 2] = r[i] * ct;
            }
    g->n_points = np;
    s = append_lattice_cells(g, 0, n, wrap_phi);
    if (s != VV_OK) {
        vv_grid_free(g);
        return s;
    }
    *out = g;
    return VV_OK;
}

vv_status
vv_grid_new_from_volume(vv_grid **out, const vv_volume *v, int tetrahedra) {
    *out = NULL;
    for (int a = 0; a < 3; a++)
        if (v->dims[a] < 2)
            return vv_error_set(VV_ERR_INVALID, "grid from volume: dimension %d is %d (>= 2)", a,
                                v->dims[a]);
    const size_t nx = (size_t)v->dims[0], ny = (size_t)v->dims[1], nz = (size_t)v->dims[2];
    const size_t np = nx * ny * nz, ncube = (nx - 1) * (ny - 1) * (nz - 1);
    const size_t nc = tetrahedra ? 6 * ncube : ncube;
    const int per = tetrahedra ? 4 : 8;
    vv_grid *g = NULL;
    vv_status s = vv_grid_new(&g, VV_GRID_UNSTRUCTURED);
    if (s == VV_OK)
        s = vv_grid_alloc(g, np, nc, nc * (size_t)per);
    vv_grid_field *f = NULL;
    if (s == VV_OK)
        s = vv_grid_add_field(g, "scalars", 0, 1, &f);
    if (s != VV_OK) {
        vv_grid_free(g);
        return s;
    }
    const vv_mat4 m = vv_volume_index_to_world(v);
    for (size_t k = 0, p = 0; k < nz; k++)
        for (size_t j = 0; j < ny; j++)
            for (size_t i = 0; i < nx; i++, p++) {
                vv_vec3 w = vv_mat4_mul_point(m, vv_vec3_make((double)i, (double)j, (double)k));
                g->points[3 * p] = w.x;
                g->points[3 * p + 1] = w.y;
                g->points[3 * p + 2] = w.z;
                f->values[p] = (float)vv_volume_get(v, (int)i, (int)j, (int)k);
            }
    /* Kuhn split: the 6 paths from corner 0 to corner 7 through the cube */
    static const int kuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                                   {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
    size_t c = 0;
    for (size_t k = 0; k + 1 < nz; k++)
        for (size_t j = 0; j + 1 < ny; j++)
            for (size_t i = 0; i + 1 < nx; i++) {
                uint32_t corner[8]; /* bit 0: +i, bit 1: +j, bit 2: +k */
                for (int b = 0; b < 8; b++)
                    corner[b] =
                        (uint32_t)(((k + (size_t)(b >> 2 & 1)) * ny + (j + (size_t)(b >> 1 & 1))) *
                                       nx +
                                   i + (size_t)(b & 1));
                if (tetrahedra) {
                    for (int t = 0; t < 6; t++, c++) {
                        for (int q = 0; q < 4; q++)
                            g->connectivity[4 * c + (size_t)q] = corner[kuhn[t][q]];
                        g->cell_types[c] = VV_CELL_TETRA;
                        g->cell_offsets[c + 1] = g->cell_offsets[c] + 4;
                    }
                } else {
                    static const int hex[8] = {0, 1, 3, 2, 4, 5, 7, 6};
                    for (int q = 0; q < 8; q++)
                        g->connectivity[8 * c + (size_t)q] = corner[hex[q]];
                    g->cell_types[c] = VV_CELL_HEXAHEDRON;
                    g->cell_offsets[c + 1] = g->cell_offsets[c] + 8;
                    c++;
                }
            }
    vv_grid_field_update_range(f);
    *out = g;
    return VV_OK;
}
