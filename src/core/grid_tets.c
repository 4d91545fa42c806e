/* Irregular grids split into tetrahedra, with face adjacency (see grid_internal.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/grid_internal.h"

const int vv_tet_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/* Faces of the non-tetrahedral cells in VTK's point order (-1 ends a triangle). */
static const int hex_faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                    {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
static const int wedge_faces[5][4] = {
    {0, 1, 2, -1}, {3, 5, 4, -1}, {0, 3, 4, 1}, {1, 4, 5, 2}, {2, 5, 3, 0}};
static const int pyramid_faces[5][4] = {
    {0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}};
/* Kuhn split of a lattice cube: corners as bits (1: +i, 2: +j, 4: +k), and
 * the VTK hexahedron point of each bit corner */
static const int kuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                               {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
static const int bit_to_vtk[8] = {0, 1, 3, 2, 4, 5, 7, 6};

void
vv_tetmesh_clear(vv_tetmesh *m) {
    free(m->p);
    free(m->val);
    free(m->grad);
    free(m->tet);
    free(m->tval);
    free(m->nb);
    memset(m, 0, sizeof *m);
}

static double
orient(const double *p, const uint32_t *t) {
    const double *a = p + 3 * (size_t)t[0], *b = p + 3 * (size_t)t[1], *c = p + 3 * (size_t)t[2],
                 *d = p + 3 * (size_t)t[3];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
           u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* The cube of the tetrahedron's longest edge, the scale its volume is compared with. */
static double
edge_scale3(const double *p, const uint32_t *t) {
    double l = 0;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++) {
            const double *a = p + 3 * (size_t)t[i], *b = p + 3 * (size_t)t[j];
            const double d = fabs(a[0] - b[0]) + fabs(a[1] - b[1]) + fabs(a[2] - b[2]);
            l = d > l ? d : l;
        }
    return l * l * l;
}

typedef struct build {
    vv_tetmesh *m;
    const float *cell_val; /* cell data */
    size_t cap;
} build;

/* Appends a tetrahedron unless it is degenerate or touches a missing value. */
static void
emit(build *b, uint32_t a, uint32_t c, uint32_t d, uint32_t e, float cv) {
    vv_tetmesh *m = b->m;
    uint32_t t[4] = {a, c, d, e};
    if (m->val) {
        for (int i = 0; i < 4; i++)
            if (m->val[t[i]] != m->val[t[i]]) {
                m->n_missing++;
                return;
            }
    } else if (cv != cv) {
        m->n_missing++;
        return;
    }
    double o = orient(m->p, t);
    if (!(fabs(o) > 1e-12 * edge_scale3(m->p, t))) {
        m->n_degenerate++;
        return;
    }
    if (o < 0) {
        uint32_t x = t[2];
        t[2] = t[3];
        t[3] = x;
    }
    memcpy(m->tet + 4 * m->n_tets, t, sizeof t);
    if (m->tval)
        m->tval[m->n_tets] = cv;
    m->n_tets++;
}

/* A face of a centred cell: one or two triangles to the centre. */
static void
emit_face(build *b, const uint32_t *pts, const int *f, uint32_t centre, float cv) {
    if (f[3] < 0) {
        emit(b, pts[f[0]], pts[f[1]], pts[f[2]], centre, cv);
        return;
    }
    uint32_t q[4] = {pts[f[0]], pts[f[1]], pts[f[2]], pts[f[3]]};
    int lo = 0;
    for (int i = 1; i < 4; i++)
        if (q[i] < q[lo])
            lo = i;
    emit(b, q[lo], q[(lo + 1) & 3], q[(lo + 2) & 3], centre, cv);
    emit(b, q[lo], q[(lo + 2) & 3], q[(lo + 3) & 3], centre, cv);
}

/* Face adjacency by an open-addressing hash of the sorted point triples. */
static vv_status
build_adjacency(vv_tetmesh *m) {
    const size_t nf = 4 * m->n_tets;
    if (nf > (size_t)INT32_MAX)
        return vv_error_set(VV_ERR_LIMIT, "grid: %zu tetrahedra, too many for adjacency",
                            m->n_tets);
    m->nb = malloc((nf ? nf : 1) * sizeof *m->nb);
    size_t cap = 16;
    while (cap < 2 * nf)
        cap <<= 1;
    int32_t *slot = malloc(cap * sizeof *slot);
    if (!m->nb || !slot) {
        free(slot);
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory for face adjacency");
    }
    memset(slot, 0xff, cap * sizeof *slot);
    for (size_t f = 0; f < nf; f++)
        m->nb[f] = -1;
    for (size_t f = 0; f < nf; f++) {
        const uint32_t *t = m->tet + 4 * (f >> 2);
        const int *fv = vv_tet_face[f & 3];
        uint32_t k[3] = {t[fv[0]], t[fv[1]], t[fv[2]]};
        if (k[0] > k[1]) {
            uint32_t x = k[0];
            k[0] = k[1];
            k[1] = x;
        }
        if (k[1] > k[2]) {
            uint32_t x = k[1];
            k[1] = k[2];
            k[2] = x;
        }
        if (k[0] > k[1]) {
            uint32_t x = k[0];
            k[0] = k[1];
            k[1] = x;
        }
        uint64_t h = ((uint64_t)k[0] * 0x9E3779B97F4A7C15ull) ^
                     ((uint64_t)k[1] * 0xC2B2AE3D27D4EB4Full) ^
                     ((uint64_t)k[2] * 0x165667B19E3779F9ull);
        h ^= h >> 29;
        size_t s = (size_t)h & (cap - 1);
        for (;; s = (s + 1) & (cap - 1)) {
            if (slot[s] < 0) {
                slot[s] = (int32_t)f;
                break;
            }
            const size_t g = (size_t)slot[s];
            const uint32_t *u = m->tet + 4 * (g >> 2);
            const int *gv = vv_tet_face[g & 3];
            uint32_t q[3] = {u[gv[0]], u[gv[1]], u[gv[2]]};
            /* same triple? (sorted compare) */
            uint32_t mn = q[0] < q[1] ? (q[0] < q[2] ? q[0] : q[2]) : (q[1] < q[2] ? q[1] : q[2]);
            uint32_t mx = q[0] > q[1] ? (q[0] > q[2] ? q[0] : q[2]) : (q[1] > q[2] ? q[1] : q[2]);
            uint32_t md = q[0] + q[1] + q[2] - mn - mx;
            if (mn != k[0] || md != k[1] || mx != k[2])
                continue;
            if (m->nb[g] >= 0) {
                free(slot);
                return vv_error_set(VV_ERR_FORMAT,
                                    "grid: the face (%u, %u, %u) is shared by three or more "
                                    "tetrahedra (overlapping or inverted cells)",
                                    k[0], k[1], k[2]);
            }
            m->nb[g] = (int32_t)f;
            m->nb[f] = (int32_t)g;
            break;
        }
    }
    free(slot);
    return VV_OK;
}

static vv_status
build_gradients(vv_tetmesh *m) {
    m->grad = calloc(3 * (m->n_points ? m->n_points : 1), sizeof *m->grad);
    double *w = calloc(m->n_points ? m->n_points : 1, sizeof *w);
    if (!m->grad || !w) {
        free(w);
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory for gradients");
    }
    for (size_t t = 0; t < m->n_tets; t++) {
        const uint32_t *v = m->tet + 4 * t;
        const double *a = m->p + 3 * (size_t)v[0];
        double e[3][3], df[3];
        for (int i = 0; i < 3; i++) {
            const double *b = m->p + 3 * (size_t)v[i + 1];
            for (int c = 0; c < 3; c++)
                e[i][c] = b[c] - a[c];
            df[i] = (double)m->val[v[i + 1]] - m->val[v[0]];
        }
        /* solve e g = df by Cramer's rule */
        const double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                           e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                           e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
        if (!(det > 0))
            continue;
        double g[3];
        for (int c = 0; c < 3; c++) {
            double mm[3][3];
            memcpy(mm, e, sizeof mm);
            for (int r = 0; r < 3; r++)
                mm[r][c] = df[r];
            g[c] = (mm[0][0] * (mm[1][1] * mm[2][2] - mm[1][2] * mm[2][1]) -
                    mm[0][1] * (mm[1][0] * mm[2][2] - mm[1][2] * mm[2][0]) +
                    mm[0][2] * (mm[1][0] * mm[2][1] - mm[1][1] * mm[2][0])) /
                   det;
        }
        const double vol = det / 6;
        for (int i = 0; i < 4; i++) {
            for (int c = 0; c < 3; c++)
                m->grad[3 * (size_t)v[i] + (size_t)c] += (float)(vol * g[c]);
            w[v[i]] += vol;
        }
    }
    for (size_t i = 0; i < m->n_points; i++)
        if (w[i] > 0)
            for (int c = 0; c < 3; c++)
                m->grad[3 * i + (size_t)c] = (float)(m->grad[3 * i + (size_t)c] / w[i]);
    free(w);
    return VV_OK;
}

vv_status
vv_tetmesh_build(vv_tetmesh *m, const vv_grid *g, const float *scalars, int cell_data,
                 int adjacency, int gradients) {
    memset(m, 0, sizeof *m);
    const int lattice = g->kind != VV_GRID_UNSTRUCTURED;
    size_t n_tet = 0, n_centre = 0;
    for (size_t c = 0; c < g->n_cells; c++) {
        switch (g->cell_types[c]) {
        case VV_CELL_TETRA:
            n_tet += 1;
            break;
        case VV_CELL_HEXAHEDRON:
            if (lattice) {
                n_tet += 6;
                break;
            }
            n_tet += 12;
            n_centre++;
            break;
        case VV_CELL_WEDGE:
            n_tet += 8;
            n_centre++;
            break;
        case VV_CELL_PYRAMID:
            n_tet += 6;
            n_centre++;
            break;
        default:
            break;
        }
    }
    if (n_tet == 0)
        return vv_error_set(VV_ERR_INVALID, "grid: no 3-D cells (tetrahedra, hexahedra, wedges, "
                                            "pyramids) to render");
    if (n_tet > (size_t)INT32_MAX / 4 || g->n_points + n_centre > UINT32_MAX)
        return vv_error_set(VV_ERR_LIMIT, "grid: %zu tetrahedra, too many", n_tet);
    m->n_points = g->n_points + n_centre;
    m->p = malloc(3 * m->n_points * sizeof *m->p);
    m->tet = malloc(4 * n_tet * sizeof *m->tet);
    if (!cell_data)
        m->val = malloc(m->n_points * sizeof *m->val);
    else
        m->tval = malloc(n_tet * sizeof *m->tval);
    if (!m->p || !m->tet || (!cell_data && !m->val) || (cell_data && !m->tval)) {
        vv_tetmesh_clear(m);
        return vv_error_set(VV_ERR_NOMEM, "grid: out of memory for %zu tetrahedra", n_tet);
    }
    memcpy(m->p, g->points, 3 * g->n_points * sizeof *m->p);
    if (!cell_data)
        memcpy(m->val, scalars, g->n_points * sizeof *m->val);
    build b = {m, scalars, n_tet};
    size_t centre = g->n_points;
    for (size_t c = 0; c < g->n_cells; c++) {
        const int type = g->cell_types[c];
        const uint32_t *pts = g->connectivity + g->cell_offsets[c];
        const float cv = cell_data ? scalars[c] : 0;
        if (type == VV_CELL_TETRA) {
            emit(&b, pts[0], pts[1], pts[2], pts[3], cv);
            continue;
        }
        if (type == VV_CELL_HEXAHEDRON && lattice) {
            for (int t = 0; t < 6; t++)
                emit(&b, pts[bit_to_vtk[kuhn[t][0]]], pts[bit_to_vtk[kuhn[t][1]]],
                     pts[bit_to_vtk[kuhn[t][2]]], pts[bit_to_vtk[kuhn[t][3]]], cv);
            continue;
        }
        const int(*faces)[4];
        int nfaces, np;
        if (type == VV_CELL_HEXAHEDRON) {
            faces = hex_faces;
            nfaces = 6;
            np = 8;
        } else if (type == VV_CELL_WEDGE) {
            faces = wedge_faces;
            nfaces = 5;
            np = 6;
        } else if (type == VV_CELL_PYRAMID) {
            faces = pyramid_faces;
            nfaces = 5;
            np = 5;
        } else {
            continue;
        }
        double s[3] = {0, 0, 0}, sv = 0;
        for (int i = 0; i < np; i++) {
            for (int a = 0; a < 3; a++)
                s[a] += m->p[3 * (size_t)pts[i] + (size_t)a];
            if (m->val)
                sv += m->val[pts[i]];
        }
        for (int a = 0; a < 3; a++)
            m->p[3 * centre + (size_t)a] = s[a] / np;
        if (m->val)
            m->val[centre] = (float)(sv / np);
        for (int f = 0; f < nfaces; f++)
            emit_face(&b, pts, faces[f], (uint32_t)centre, cv);
        centre++;
    }
    (void)b.cap;
    double lo = INFINITY, hi = -INFINITY;
    if (m->val) {
        for (size_t t = 0; t < 4 * m->n_tets; t++) {
            const float v = m->val[m->tet[t]];
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    } else {
        for (size_t t = 0; t < m->n_tets; t++) {
            lo = m->tval[t] < lo ? m->tval[t] : lo;
            hi = m->tval[t] > hi ? m->tval[t] : hi;
        }
    }
    m->range[0] = lo <= hi ? lo : 0;
    m->range[1] = lo <= hi ? hi : 0;
    vv_status st = VV_OK;
    if (adjacency)
        st = build_adjacency(m);
    if (st == VV_OK && gradients && m->val)
        st = build_gradients(m);
    if (st != VV_OK)
        vv_tetmesh_clear(m);
    return st;
}

/* ---------------------------------------------------------------------- */
/* Face adjacency of the cells                                              */

typedef struct face_rec {
    uint32_t key[4]; /* sorted point indices; a triangle's fourth is UINT32_MAX */
    size_t slot;     /* index into neighbours */
    size_t cell;
} face_rec;

static int
face_cmp(const void *a, const void *b) {
    const face_rec *x = a, *y = b;
    for (int i = 0; i < 4; i++)
        if (x->key[i] != y->key[i])
            return x->key[i] < y->key[i] ? -1 : 1;
    return 0;
}

static const int tet_faces_vtk[4][4] = {{1, 2, 3, -1}, {0, 3, 2, -1}, {0, 1, 3, -1}, {0, 2, 1, -1}};

static int
cell_faces(int type, const int (**faces)[4]) {
    switch (type) {
    case VV_CELL_TETRA:
        *faces = tet_faces_vtk;
        return 4;
    case VV_CELL_HEXAHEDRON:
        *faces = hex_faces;
        return 6;
    case VV_CELL_WEDGE:
        *faces = wedge_faces;
        return 5;
    case VV_CELL_PYRAMID:
        *faces = pyramid_faces;
        return 5;
    default:
        return 0;
    }
}

vv_status
vv_grid_face_adjacency(const vv_grid *g, size_t **offsets, int64_t **neighbours,
                       size_t *n_boundary) {
    *offsets = NULL;
    *neighbours = NULL;
    size_t *off = malloc((g->n_cells + 1) * sizeof *off);
    if (!off)
        return vv_error_set(VV_ERR_NOMEM, "grid adjacency: out of memory");
    off[0] = 0;
    for (size_t c = 0; c < g->n_cells; c++) {
        const int(*faces)[4];
        off[c + 1] = off[c] + (size_t)cell_faces(g->cell_types[c], &faces);
    }
    const size_t nf = off[g->n_cells];
    int64_t *nb = malloc((nf ? nf : 1) * sizeof *nb);
    face_rec *rec = malloc((nf ? nf : 1) * sizeof *rec);
    if (!nb || !rec) {
        free(off);
        free(nb);
        free(rec);
        return vv_error_set(VV_ERR_NOMEM, "grid adjacency: out of memory for %zu faces", nf);
    }
    for (size_t c = 0; c < g->n_cells; c++) {
        const int(*faces)[4];
        const int n = cell_faces(g->cell_types[c], &faces);
        const uint32_t *pts = g->connectivity + g->cell_offsets[c];
        for (int k = 0; k < n; k++) {
            face_rec *r = &rec[off[c] + (size_t)k];
            for (int i = 0; i < 4; i++)
                r->key[i] = faces[k][i] < 0 ? UINT32_MAX : pts[faces[k][i]];
            /* sort the four keys */
            for (int i = 1; i < 4; i++)
                for (int j = i; j > 0 && r->key[j] < r->key[j - 1]; j--) {
                    const uint32_t x = r->key[j];
                    r->key[j] = r->key[j - 1];
                    r->key[j - 1] = x;
                }
            r->slot = off[c] + (size_t)k;
            r->cell = c;
            nb[r->slot] = -1;
        }
    }
    qsort(rec, nf, sizeof *rec, face_cmp);
    size_t boundary = 0;
    for (size_t i = 0; i < nf;) {
        size_t j = i + 1;
        while (j < nf && face_cmp(&rec[i], &rec[j]) == 0)
            j++;
        if (j - i > 2) {
            const size_t c0 = rec[i].cell, c1 = rec[i + 1].cell, c2 = rec[i + 2].cell;
            free(off);
            free(nb);
            free(rec);
            return vv_error_set(VV_ERR_FORMAT,
                                "grid: cells %zu, %zu and %zu share a face (overlapping cells)", c0,
                                c1, c2);
        }
        if (j - i == 2) {
            nb[rec[i].slot] = (int64_t)rec[i + 1].cell;
            nb[rec[i + 1].slot] = (int64_t)rec[i].cell;
        } else {
            boundary++;
        }
        i = j;
    }
    free(rec);
    *offsets = off;
    *neighbours = nb;
    if (n_boundary)
        *n_boundary = boundary;
    return VV_OK;
}
