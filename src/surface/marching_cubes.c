/*
 * Marching Cubes isosurface extraction (Lorensen and Cline 1987) with the
 * asymptotic decider on ambiguous faces (Nielson and Hamann 1991); tables in
 * mc_tables.c. See include/volvis/surface.h for the conventions.
 *
 * The method is organised for speed like Flying Edges (Schroeder, Maynard
 * and Geveci, LDAV 2015): a few passes over grid rows, each independent, so
 * every pass is parallel and the output does not depend on the thread
 * count.
 *
 *  1. Classify: one bit per voxel (inside = value >= isovalue), a row of
 *     the region per task. With a min/max subvolume grid, uniform
 *     subvolumes are filled without reading their voxels.
 *  2. Count: per grid row (j, k), the crossing edges it owns (x edges of
 *     the row, y edges to row j+1, z edges to row k+1: XOR and popcount of
 *     bit words) and the triangles of the cell row. Cells are found 64 at a
 *     time: a cell is active when its 8 corner bits are not all equal,
 *     computed with word operations, so empty space costs a few
 *     instructions per 64 cells.
 *  3. Prefix sums give every row its first vertex and triangle.
 *  4. Generate: each row writes its vertices (interpolated positions,
 *     gradient normals) and its cells' triangles straight into the mesh.
 *     A vertex's index is its row's first vertex plus the number of
 *     crossings before it on its row and axis (a popcount), so the 12 edges
 *     of a cell find their shared vertices without any hash table.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/parallel_for.h"
#include "surface_internal.h"

#define MC_WORD 64
#define VV_MC_MAX_THREADS VV_PARALLEL_MAX_THREADS
#define MC_CNT 5 /* counts per row */

typedef struct mc_job {
    const vv_volume *v;
    double iso;
    int lo[3];     /* region origin (voxels) */
    int n[3];      /* region size (voxels) */
    int W;         /* 64-bit words per row */
    size_t sy, sz; /* voxel strides of the whole volume */
    uint64_t *bits;
    uint64_t *cellmask; /* W words: cells i < n[0] - 1 */
    uint32_t *cnt;      /* per row: x, y, z crossings, triangles, centre vertices */
    uint64_t *voff;     /* per row: first vertex; [rows] = total */
    uint64_t *toff;     /* per row: first triangle; [rows] = total */
    const mc_tables *tb;
    double M[3][4]; /* index -> world */
    double G[3][3]; /* index-space gradient -> world gradient */
    int normals;
    const vv_volume *sv; /* scalar volume or NULL */
    int quantize;
    uint32_t *edge_ids;
    uint8_t *codes;
    int edges_only; /* see mc_extra */
    float *centres; /* edges_only: centre vertex positions */
    uint64_t *coff; /* edges_only: per row, its first centre vertex */
    vv_mesh *m;
    int failed;
} mc_job;

static inline double
val(const vv_volume *v, size_t i) {
    return vv_voxel_value(v->type, v->data, i);
}

#if defined(__GNUC__)
#define MC_INLINE static inline __attribute__((always_inline))
#else
#define MC_INLINE static inline
#endif
/* Hardware popcount where the CPU has it, chosen at load time (the build is for any x86-64). */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define MC_POPCNT_CLONES __attribute__((target_clones("popcnt", "default")))
#else
#define MC_POPCNT_CLONES
#endif

/* Instantiates name##_t for every voxel type: a switch calling the inlined body with a
 * constant type. */
#define MC_DISPATCH(call_with_type)                                                                \
    switch (J->v->type) {                                                                          \
    case VV_U8:                                                                                    \
        return call_with_type(VV_U8);                                                              \
    case VV_I8:                                                                                    \
        return call_with_type(VV_I8);                                                              \
    case VV_U16:                                                                                   \
        return call_with_type(VV_U16);                                                             \
    case VV_I16:                                                                                   \
        return call_with_type(VV_I16);                                                             \
    case VV_U32:                                                                                   \
        return call_with_type(VV_U32);                                                             \
    case VV_I32:                                                                                   \
        return call_with_type(VV_I32);                                                             \
    case VV_F32:                                                                                   \
        return call_with_type(VV_F32);                                                             \
    default:                                                                                       \
        return call_with_type(VV_F64);                                                             \
    }

/* ---- pass 1: classification ----------------------------------------------- */

/* Smallest float f with (double)f >= iso, so that for float v: v >= f <=> v >= iso. */
static float
float_threshold(double iso) {
    float f = (float)iso;
    if (isinf(f) && !isinf(iso))
        return f > 0 ? f : -FLT_MAX;
    if ((double)f < iso)
        f = nextafterf(f, INFINITY);
    while ((double)nextafterf(f, -INFINITY) >= iso)
        f = nextafterf(f, -INFINITY);
    return f;
}

/* Integer types: v >= iso <=> v >= ceil(iso); clamp the threshold to [lo, hi + 1]. */
static double
int_threshold(double iso, double lo, double hi) {
    double t = ceil(iso);
    if (t < lo)
        t = lo;
    if (t > hi + 1)
        t = hi + 1;
    return t;
}

#define CLASSIFY_INT(T, LO, HI)                                                                    \
    {                                                                                              \
        const T *d = (const T *)p;                                                                 \
        double th_ = int_threshold(iso, LO, HI);                                                   \
        if (th_ > HI) {                                                                            \
            memset(c, 0, (size_t)n);                                                               \
        } else {                                                                                   \
            const T th = (T)th_;                                                                   \
            for (int i = 0; i < n; i++)                                                            \
                c[i] = d[i] >= th;                                                                 \
        }                                                                                          \
    }                                                                                              \
    break;

/* c[0..n-1] = (voxel >= iso) for n voxels of type t starting at p. */
static void
classify_run(const void *p, vv_voxel_type t, int n, double iso, uint8_t *c) {
    switch (t) {
    case VV_U8:
        CLASSIFY_INT(uint8_t, 0.0, 255.0)
    case VV_I8:
        CLASSIFY_INT(int8_t, -128.0, 127.0)
    case VV_U16:
        CLASSIFY_INT(uint16_t, 0.0, 65535.0)
    case VV_I16:
        CLASSIFY_INT(int16_t, -32768.0, 32767.0)
    case VV_U32:
        CLASSIFY_INT(uint32_t, 0.0, 4294967295.0)
    case VV_I32:
        CLASSIFY_INT(int32_t, -2147483648.0, 2147483647.0)
    case VV_F32: {
        const float *d = (const float *)p;
        const float th = float_threshold(iso);
        for (int i = 0; i < n; i++)
            c[i] = d[i] >= th;
        break;
    }
    default: {
        const double *d = (const double *)p;
        for (int i = 0; i < n; i++)
            c[i] = d[i] >= iso;
        break;
    }
    }
}

/* Packs bytes 0/1 into bits, 8 at a time by one multiplication. */
static void
pack_bits(const uint8_t *c, int W, uint64_t *out) {
    for (int w = 0; w < W; w++) {
        uint64_t word = 0;
        for (int g = 0; g < 8; g++) {
            uint64_t x;
            memcpy(&x, c + 64 * w + 8 * g, 8);
            word |= ((x * 0x0102040810204080ULL) >> 56) << (8 * g);
        }
        out[w] = word;
    }
}

/* Whether the min/max grid's values are exact for this type (float holds every value). */
static int
grid_exact(vv_voxel_type t) {
    return t == VV_U8 || t == VV_I8 || t == VV_U16 || t == VV_I16 || t == VV_F32;
}

static void
classify_row(mc_job *J, const vv_minmax_grid *g, int j, int k, uint8_t *c) {
    const vv_volume *v = J->v;
    const size_t vs = vv_voxel_type_size(v->type);
    const int J0 = J->lo[1] + j, K0 = J->lo[2] + k, I0 = J->lo[0], n0 = J->n[0];
    const size_t base = (size_t)K0 * J->sz + (size_t)J0 * J->sy;
    const char *row = (const char *)v->data + base * vs;
    memset(c + n0, 0, (size_t)(J->W * MC_WORD - n0));
    if (!g) {
        classify_run(row + (size_t)I0 * vs, v->type, n0, J->iso, c);
    } else {
        const int B = g->block;
        int bj = J0 / B, bk = K0 / B;
        if (bj >= g->dims[1])
            bj = g->dims[1] - 1;
        if (bk >= g->dims[2])
            bk = g->dims[2] - 1;
        const size_t gb = ((size_t)bk * (size_t)g->dims[1] + (size_t)bj) * (size_t)g->dims[0];
        int i = I0;
        const int iend = I0 + n0; /* exclusive */
        /* runs of subvolumes in the same state (0 all outside, 1 all inside, 2 mixed) are
         * handled in one go */
        while (i < iend) {
            int e = i, state = -1;
            while (e < iend) {
                int bi = e / B;
                if (bi >= g->dims[0])
                    bi = g->dims[0] - 1;
                float mn = g->min[gb + (size_t)bi], mx = g->max[gb + (size_t)bi];
                int s = (double)mx < J->iso ? 0 : (double)mn >= J->iso ? 1 : 2;
                if (state >= 0 && s != state)
                    break;
                state = s;
                /* the subvolume's voxels are bi*B .. bi*B+B; the last one reaches the end */
                int next = bi == g->dims[0] - 1 ? iend : (bi + 1) * B + 1;
                e = next > iend ? iend : next;
            }
            if (state == 0)
                memset(c + (i - I0), 0, (size_t)(e - i));
            else if (state == 1)
                memset(c + (i - I0), 1, (size_t)(e - i));
            else
                classify_run(row + (size_t)i * vs, v->type, e - i, J->iso, c + (i - I0));
            i = e;
        }
    }
    pack_bits(c, J->W, J->bits + ((size_t)k * (size_t)J->n[1] + (size_t)j) * (size_t)J->W);
}

/* ---- cells ------------------------------------------------------------------ */

/* The 8 corner bits of the cells of word w: lo/hi halves of the 4 rows. */
typedef struct mc_words {
    uint64_t lo[4], hi[4];
} mc_words;

static inline void
load_words(const mc_job *J, const uint64_t *const r[4], int w, mc_words *q) {
    for (int a = 0; a < 4; a++) {
        uint64_t x = r[a][w];
        q->lo[a] = x;
        q->hi[a] = (x >> 1) | (w + 1 < J->W ? r[a][w + 1] << 63 : 0);
    }
}

static inline uint64_t
active_cells(const mc_words *q, uint64_t mask) {
    uint64_t all = mask, any = 0;
    for (int a = 0; a < 4; a++) {
        all &= q->lo[a] & q->hi[a];
        any |= q->lo[a] | q->hi[a];
    }
    return any & ~all & mask;
}

/* Rows: 0 (j,k), 1 (j+1,k), 2 (j,k+1), 3 (j+1,k+1); corners as in mc_tables.c. */
static inline int
cell_case(const mc_words *q, int b) {
    return (int)(((q->lo[0] >> b) & 1) | (((q->hi[0] >> b) & 1) << 1) |
                 (((q->hi[1] >> b) & 1) << 2) | (((q->lo[1] >> b) & 1) << 3) |
                 (((q->lo[2] >> b) & 1) << 4) | (((q->hi[2] >> b) & 1) << 5) |
                 (((q->hi[3] >> b) & 1) << 6) | (((q->lo[3] >> b) & 1) << 7));
}

/* Configuration index of case cs at the cell whose corner 0 is voxel index c0. */
MC_INLINE int
cell_config(const mc_job *J, int cs, size_t c0, const vv_voxel_type T) {
    const mc_tables *tb = J->tb;
    int na = tb->n_amb[cs];
    if (!na)
        return tb->base[cs];
    const size_t sy = J->sy, sz = J->sz;
    const size_t off[8] = {0, 1, 1 + sy, sy, sz, 1 + sz, 1 + sy + sz, sy + sz};
    double w[8];
    for (int c = 0; c < 8; c++)
        w[c] = vv_voxel_value(T, J->v->data, c0 + off[c]) - J->iso;
    int d = 0;
    for (int m = 0; m < na; m++) {
        const int *q = mc_face_corner[tb->amb_face[cs][m]];
        d |= mc_face_joined(w[q[0]], w[q[1]], w[q[2]], w[q[3]]) << m;
    }
    return tb->base[cs] + d;
}

static inline const uint64_t *
row_bits(const mc_job *J, int j, int k) {
    return J->bits + ((size_t)k * (size_t)J->n[1] + (size_t)j) * (size_t)J->W;
}

/* ---- pass 2: counting -------------------------------------------------------- */

MC_INLINE void
count_row_t(mc_job *J, int j, int k, const vv_voxel_type T) {
    const int W = J->W, n1 = J->n[1], n2 = J->n[2];
    const uint64_t *r0 = row_bits(J, j, k);
    uint32_t nx = 0, ny = 0, nz = 0, nt = 0, nc = 0;
    for (int w = 0; w < W; w++) {
        uint64_t x = r0[w], hi = (x >> 1) | (w + 1 < W ? r0[w + 1] << 63 : 0);
        nx += (uint32_t)__builtin_popcountll((x ^ hi) & J->cellmask[w]);
    }
    if (j + 1 < n1) {
        const uint64_t *r1 = row_bits(J, j + 1, k);
        for (int w = 0; w < W; w++)
            ny += (uint32_t)__builtin_popcountll(r0[w] ^ r1[w]);
    }
    if (k + 1 < n2) {
        const uint64_t *r2 = row_bits(J, j, k + 1);
        for (int w = 0; w < W; w++)
            nz += (uint32_t)__builtin_popcountll(r0[w] ^ r2[w]);
    }
    if (j + 1 < n1 && k + 1 < n2) {
        const uint64_t *r[4] = {r0, row_bits(J, j + 1, k), row_bits(J, j, k + 1),
                                row_bits(J, j + 1, k + 1)};
        const size_t rowbase =
            (size_t)(J->lo[2] + k) * J->sz + (size_t)(J->lo[1] + j) * J->sy + (size_t)J->lo[0];
        for (int w = 0; w < W; w++) {
            mc_words q;
            load_words(J, r, w, &q);
            uint64_t act = active_cells(&q, J->cellmask[w]);
            while (act) {
                int b = __builtin_ctzll(act);
                act &= act - 1;
                int cs = cell_case(&q, b);
                const mc_config *cf =
                    &J->tb->configs[cell_config(J, cs, rowbase + (size_t)(w * MC_WORD + b), T)];
                nt += cf->n_tri;
                nc += cf->n_centre;
            }
        }
    }
    uint32_t *c = J->cnt + MC_CNT * ((size_t)k * (size_t)n1 + (size_t)j);
    c[0] = nx;
    c[1] = ny;
    c[2] = nz;
    c[3] = nt;
    c[4] = nc;
}

/* ---- pass 4: generation -------------------------------------------------------- */

MC_INLINE void
gradient(const mc_job *J, int I, int Jy, int K, size_t idx, double g[3], const vv_voxel_type T) {
    const vv_volume *v = J->v;
    const void *d = v->data;
    const int P[3] = {I, Jy, K};
    const size_t st[3] = {1, J->sy, J->sz};
    for (int a = 0; a < 3; a++) {
        int n = v->dims[a], p = P[a];
        if (n < 2)
            g[a] = 0;
        else if (p == 0)
            g[a] = vv_voxel_value(T, d, idx + st[a]) - vv_voxel_value(T, d, idx);
        else if (p == n - 1)
            g[a] = vv_voxel_value(T, d, idx) - vv_voxel_value(T, d, idx - st[a]);
        else
            g[a] = 0.5 * (vv_voxel_value(T, d, idx + st[a]) - vv_voxel_value(T, d, idx - st[a]));
    }
}

/* Writes vertex vi on the edge from voxel (I, Jy, K) along axis; returns 1 if its normal is 0. */
MC_INLINE int
emit_vertex(mc_job *J, uint64_t vi, int I, int Jy, int K, int axis, const vv_voxel_type T) {
    const vv_volume *v = J->v;
    const size_t st[3] = {1, J->sy, J->sz};
    const size_t i0 = (size_t)K * J->sz + (size_t)Jy * J->sy + (size_t)I, i1 = i0 + st[axis];
    const double a = vv_voxel_value(T, v->data, i0), b = vv_voxel_value(T, v->data, i1);
    double t = (J->iso - a) / (b - a);
    if (!(t >= 0))
        t = 0; /* also NaN */
    if (t > 1)
        t = 1;
    if (J->quantize) {
        int code = (int)(t * 4);
        code = code > 3 ? 3 : code;
        t = (code + 0.5) * 0.25;
        J->codes[vi] = (uint8_t)code;
    }
    if (J->edge_ids)
        J->edge_ids[vi] = (uint32_t)(3 * i0 + (size_t)axis);
    if (J->edges_only)
        return 0; /* the edge and the code are the vertex */
    double p[3] = {I, Jy, K};
    p[axis] += t;
    float *out = J->m->positions + 3 * vi;
    for (int r = 0; r < 3; r++)
        out[r] = (float)(J->M[r][0] * p[0] + J->M[r][1] * p[1] + J->M[r][2] * p[2] + J->M[r][3]);
    if (J->sv) {
        double sa = val(J->sv, i0), sb = val(J->sv, i1);
        J->m->scalars[vi] = (float)(sa + t * (sb - sa));
    }
    if (!J->normals)
        return 0;
    int P1[3] = {I, Jy, K};
    P1[axis]++;
    double g0[3], g1[3], gw[3];
    gradient(J, I, Jy, K, i0, g0, T);
    gradient(J, P1[0], P1[1], P1[2], i1, g1, T);
    for (int r = 0; r < 3; r++)
        g0[r] += t * (g1[r] - g0[r]);
    for (int r = 0; r < 3; r++)
        gw[r] = J->G[r][0] * g0[0] + J->G[r][1] * g0[1] + J->G[r][2] * g0[2];
    double l2 = gw[0] * gw[0] + gw[1] * gw[1] + gw[2] * gw[2];
    float *nrm = J->m->normals + 3 * vi;
    if (!(l2 > 0)) {
        nrm[0] = nrm[1] = nrm[2] = 0;
        return 1;
    }
    double s = -1.0 / sqrt(l2); /* outward = towards decreasing value */
    for (int r = 0; r < 3; r++)
        nrm[r] = (float)(gw[r] * s);
    return 0;
}

/* Corner offsets (index space) of the cube corners. */
static const int corner_xyz[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/* Writes centre vertex vi of the cell at voxel c0 = (I, Jy, K): the mean of the crossings
 * of the edges in mask, with the mean gradient. Returns 1 if its normal is 0. */
static int
emit_centre(mc_job *J, uint64_t vi, uint64_t ci, size_t c0, int I, int Jy, int K, unsigned mask) {
    double p[3] = {0, 0, 0}, g[3] = {0, 0, 0};
    int n = 0;
    for (int e = 0; e < 12; e++) {
        if (!(mask >> e & 1))
            continue;
        const int *ca = corner_xyz[mc_edge_corner[e][0]], *cb = corner_xyz[mc_edge_corner[e][1]];
        size_t ia = c0 + (size_t)ca[0] + (size_t)ca[1] * J->sy + (size_t)ca[2] * J->sz;
        size_t ib = c0 + (size_t)cb[0] + (size_t)cb[1] * J->sy + (size_t)cb[2] * J->sz;
        double a = val(J->v, ia), b = val(J->v, ib);
        double t = (J->iso - a) / (b - a);
        if (!(t >= 0))
            t = 0;
        if (t > 1)
            t = 1;
        for (int r = 0; r < 3; r++)
            p[r] += ca[r] + t * (cb[r] - ca[r]);
        if (J->normals) {
            double ga[3], gb[3];
            gradient(J, I + ca[0], Jy + ca[1], K + ca[2], ia, ga, J->v->type);
            gradient(J, I + cb[0], Jy + cb[1], K + cb[2], ib, gb, J->v->type);
            for (int r = 0; r < 3; r++)
                g[r] += ga[r] + t * (gb[r] - ga[r]);
        }
        n++;
    }
    const double P[3] = {I + p[0] / n, Jy + p[1] / n, K + p[2] / n};
    float *out = J->edges_only ? J->centres + 3 * ci : J->m->positions + 3 * vi;
    for (int r = 0; r < 3; r++)
        out[r] = (float)(J->M[r][0] * P[0] + J->M[r][1] * P[1] + J->M[r][2] * P[2] + J->M[r][3]);
    if (J->edge_ids)
        J->edge_ids[vi] = UINT32_MAX;
    if (J->codes)
        J->codes[vi] = 0;
    if (J->sv) {
        /* trilinear in the cell */
        double s = 0, fx = p[0] / n, fy = p[1] / n, fz = p[2] / n;
        for (int c = 0; c < 8; c++) {
            const int *cc = corner_xyz[c];
            double wgt = (cc[0] ? fx : 1 - fx) * (cc[1] ? fy : 1 - fy) * (cc[2] ? fz : 1 - fz);
            s += wgt *
                 val(J->sv, c0 + (size_t)cc[0] + (size_t)cc[1] * J->sy + (size_t)cc[2] * J->sz);
        }
        J->m->scalars[vi] = (float)s;
    }
    if (!J->normals)
        return 0;
    double gw[3];
    for (int r = 0; r < 3; r++)
        gw[r] = J->G[r][0] * g[0] + J->G[r][1] * g[1] + J->G[r][2] * g[2];
    double l2 = gw[0] * gw[0] + gw[1] * gw[1] + gw[2] * gw[2];
    float *nrm = J->m->normals + 3 * vi;
    if (!(l2 > 0)) {
        nrm[0] = nrm[1] = nrm[2] = 0;
        return 1;
    }
    double s = -1.0 / sqrt(l2);
    for (int r = 0; r < 3; r++)
        nrm[r] = (float)(gw[r] * s);
    return 0;
}

MC_INLINE int
generate_row_t(mc_job *J, int j, int k, const vv_voxel_type T) {
    const int W = J->W, n1 = J->n[1], n2 = J->n[2];
    const size_t R = (size_t)k * (size_t)n1 + (size_t)j;
    const uint32_t *c = J->cnt + MC_CNT * R;
    const uint64_t xoff = J->voff[R], yoff = xoff + c[0], zoff = yoff + c[1];
    const int I0 = J->lo[0], Jy = J->lo[1] + j, K = J->lo[2] + k;
    const uint64_t *r0 = row_bits(J, j, k);
    const uint64_t *r1 = j + 1 < n1 ? row_bits(J, j + 1, k) : NULL;
    const uint64_t *r2 = k + 1 < n2 ? row_bits(J, j, k + 1) : NULL;
    int zero_normals = 0;
    /* vertices owned by this row */
    uint64_t vx = xoff, vy = yoff, vz = zoff;
    for (int w = 0; w < W; w++) {
        uint64_t x = r0[w], hi = (x >> 1) | (w + 1 < W ? r0[w + 1] << 63 : 0);
        uint64_t X = (x ^ hi) & J->cellmask[w];
        while (X) {
            int b = __builtin_ctzll(X);
            X &= X - 1;
            zero_normals += emit_vertex(J, vx++, I0 + w * MC_WORD + b, Jy, K, 0, T);
        }
        if (r1) {
            uint64_t Y = x ^ r1[w];
            while (Y) {
                int b = __builtin_ctzll(Y);
                Y &= Y - 1;
                zero_normals += emit_vertex(J, vy++, I0 + w * MC_WORD + b, Jy, K, 1, T);
            }
        }
        if (r2) {
            uint64_t Z = x ^ r2[w];
            while (Z) {
                int b = __builtin_ctzll(Z);
                Z &= Z - 1;
                zero_normals += emit_vertex(J, vz++, I0 + w * MC_WORD + b, Jy, K, 2, T);
            }
        }
    }
    if (!r1 || !r2)
        return zero_normals;
    /* triangles of the cell row */
    const uint64_t *r[4] = {r0, r1, r2, row_bits(J, j + 1, k + 1)};
    const uint32_t *c1 = J->cnt + MC_CNT * (R + 1), *c2 = J->cnt + MC_CNT * (R + (size_t)n1);
    uint64_t vc = zoff + c[2]; /* centre vertices of this cell row */
    uint64_t vcc = J->coff ? J->coff[R] : 0;
    const uint64_t R1 = R + 1, R2 = R + (size_t)n1, R3 = R2 + 1;
    /* first x, y, z vertex of the rows the cell row's edges belong to */
    const uint64_t x0 = xoff, x1 = J->voff[R1], x2 = J->voff[R2], x3 = J->voff[R3];
    const uint64_t y0 = yoff, y2 = J->voff[R2] + c2[0];
    const uint64_t z0 = zoff, z1 = J->voff[R1] + c1[0] + c1[1];
    uint64_t cx[4] = {0, 0, 0, 0}, cy[2] = {0, 0}, cz[2] = {0, 0};
    uint32_t *tri = J->m->triangles + 3 * J->toff[R];
    const size_t rowbase = (size_t)K * J->sz + (size_t)Jy * J->sy + (size_t)I0;
    for (int w = 0; w < W; w++) {
        mc_words q;
        load_words(J, r, w, &q);
        const uint64_t cm = J->cellmask[w];
        uint64_t X[4], Y0 = r[0][w] ^ r[1][w], Y2 = r[2][w] ^ r[3][w], Z0 = r[0][w] ^ r[2][w],
                       Z1 = r[1][w] ^ r[3][w];
        for (int a = 0; a < 4; a++)
            X[a] = (q.lo[a] ^ q.hi[a]) & cm;
        uint64_t act = active_cells(&q, cm);
        while (act) {
            int b = __builtin_ctzll(act);
            act &= act - 1;
            int cs = cell_case(&q, b);
            const mc_config *cf =
                &J->tb->configs[cell_config(J, cs, rowbase + (size_t)(w * MC_WORD + b), T)];
            /* Every crossing bit of these rows sits at an active cell (an inactive cell has no
             * crossing edge), so counting the bits of the active cells visited so far gives
             * the crossings before this cell: no popcount. */
            const unsigned bx0 = (unsigned)(X[0] >> b) & 1, bx1 = (unsigned)(X[1] >> b) & 1,
                           bx2 = (unsigned)(X[2] >> b) & 1, bx3 = (unsigned)(X[3] >> b) & 1,
                           by0 = (unsigned)(Y0 >> b) & 1, by2 = (unsigned)(Y2 >> b) & 1,
                           bz0 = (unsigned)(Z0 >> b) & 1, bz1 = (unsigned)(Z1 >> b) & 1;
            uint32_t e[12];
            e[0] = (uint32_t)(x0 + cx[0]);
            e[2] = (uint32_t)(x1 + cx[1]);
            e[4] = (uint32_t)(x2 + cx[2]);
            e[6] = (uint32_t)(x3 + cx[3]);
            e[3] = (uint32_t)(y0 + cy[0]);
            e[1] = e[3] + by0;
            e[7] = (uint32_t)(y2 + cy[1]);
            e[5] = e[7] + by2;
            e[8] = (uint32_t)(z0 + cz[0]);
            e[9] = e[8] + bz0;
            e[11] = (uint32_t)(z1 + cz[1]);
            e[10] = e[11] + bz1;
            cx[0] += bx0;
            cx[1] += bx1;
            cx[2] += bx2;
            cx[3] += bx3;
            cy[0] += by0;
            cy[1] += by2;
            cz[0] += bz0;
            cz[1] += bz1;
            uint32_t ev[12 + MC_MAX_CENTRE];
            memcpy(ev, e, sizeof e);
            for (int q2 = 0; q2 < cf->n_centre; q2++) {
                ev[12 + q2] = (uint32_t)vc;
                zero_normals += emit_centre(J, vc++, vcc++, rowbase + (size_t)(w * MC_WORD + b),
                                            I0 + w * MC_WORD + b, Jy, K, cf->centre_edges[q2]);
            }
            for (int t = 0; t < cf->n_tri; t++) {
                tri[0] = ev[cf->tri[t][0]];
                tri[1] = ev[cf->tri[t][1]];
                tri[2] = ev[cf->tri[t][2]];
                tri += 3;
            }
        }
    }
    return zero_normals;
}

#define MC_GENERATE(T) generate_row_t(J, j, k, T)
static int
generate_row(mc_job *J, int j, int k) {
    MC_DISPATCH(MC_GENERATE)
}

#define MC_COUNT(T) (count_row_t(J, j, k, T), 0)
static MC_POPCNT_CLONES int
count_row(mc_job *J, int j, int k) {
    MC_DISPATCH(MC_COUNT)
}

/* Replaces zero normals (vanishing gradient) by the area-weighted face normals. */
static void
fix_zero_normals(vv_mesh *m) {
    float *n = m->normals;
    size_t nv = m->n_vertices;
    unsigned char *zero = calloc(nv ? nv : 1, 1);
    double *acc = calloc(nv ? nv : 1, 3 * sizeof(double));
    if (!zero || !acc) {
        free(zero);
        free(acc);
        return; /* normals stay zero: harmless for the geometry */
    }
    for (size_t i = 0; i < nv; i++)
        zero[i] = n[3 * i] == 0 && n[3 * i + 1] == 0 && n[3 * i + 2] == 0;
    for (size_t t = 0; t < m->n_triangles; t++) {
        const uint32_t *tr = m->triangles + 3 * t;
        if (!zero[tr[0]] && !zero[tr[1]] && !zero[tr[2]])
            continue;
        vv_vec3 p0 = vv_mesh_vertex(m, tr[0]), p1 = vv_mesh_vertex(m, tr[1]),
                p2 = vv_mesh_vertex(m, tr[2]);
        vv_vec3 f = vv_vec3_cross(vv_vec3_sub(p1, p0), vv_vec3_sub(p2, p0));
        for (int c = 0; c < 3; c++)
            if (zero[tr[c]]) {
                acc[3 * tr[c]] += f.x;
                acc[3 * tr[c] + 1] += f.y;
                acc[3 * tr[c] + 2] += f.z;
            }
    }
    for (size_t i = 0; i < nv; i++)
        if (zero[i]) {
            double *a = acc + 3 * i, l = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            if (l > 0)
                for (int c = 0; c < 3; c++)
                    n[3 * i + c] = (float)(a[c] / l);
        }
    free(zero);
    free(acc);
}

/* ---- threads -------------------------------------------------------------------- */

/*
 * Each pass is one vv_parallel_for (core/parallel_for.h) over the grid rows,
 * handed out 16 at a time, so a descheduled thread delays a pass by at most
 * its 16 rows.
 */
typedef struct mc_pass {
    mc_job *J;
    int which;          /* MC_PASS_* */
    uint8_t **scratch;  /* per worker: classify's byte row */
    long *zero_normals; /* per worker */
    const vv_minmax_grid *grid;
} mc_pass;

enum { MC_PASS_CLASSIFY, MC_PASS_COUNT, MC_PASS_GENERATE };
#define MC_CHUNK 16

static void
pass_rows(void *ctx, long r0, long r1, int w) {
    mc_pass *P = ctx;
    mc_job *J = P->J;
    for (long r = r0; r < r1; r++) {
        int j = (int)(r % J->n[1]), k = (int)(r / J->n[1]);
        if (P->which == MC_PASS_CLASSIFY)
            classify_row(J, P->grid, j, k, P->scratch[w]);
        else if (P->which == MC_PASS_COUNT)
            count_row(J, j, k);
        else
            P->zero_normals[w] += generate_row(J, j, k);
    }
}

/* Runs pass P over @p rows on nt threads; the generate pass reports progress
 * 0.4 .. 0.9 every 4 chunks of the calling thread. VV_ERR_CANCELLED on a
 * cancel. */
static vv_status
run_pass(mc_pass *P, long rows, int nt, const vv_progress *progress) {
    const vv_parallel_progress pr = {progress, 0.4, 0.9, 4};
    return vv_parallel_for(rows, MC_CHUNK, nt, pass_rows, P,
                           P->which == MC_PASS_GENERATE ? &pr : NULL);
}

/* ---- driver ------------------------------------------------------------------- */

void
vv_isosurface_options_init(vv_isosurface_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    o->compute_normals = 1;
    o->roi_max[0] = o->roi_max[1] = o->roi_max[2] = -1;
}

static int
report(const vv_progress *p, double f) {
    return p && p->fn ? vv_progress_report(p, f) : 0;
}

vv_status
vv_isosurface_extract(vv_mesh **out, const vv_volume *v, double isovalue,
                      const vv_isosurface_options *opt) {
    return vv_isosurface_extract_ex(out, v, isovalue, opt, NULL);
}

/* Pass 3: each row's first vertex, triangle and centre vertex from the
 * counts of pass 2; the totals. */
static void
prefix_sums(mc_job *J, size_t rows, uint64_t *nv_out, uint64_t *ntri_out, uint64_t *ncent_out) {
    uint64_t nv = 0, ntri = 0, ncent = 0;
    for (size_t r = 0; r < rows; r++) {
        J->voff[r] = nv;
        J->toff[r] = ntri;
        if (J->coff)
            J->coff[r] = ncent;
        const uint32_t *c = J->cnt + MC_CNT * r;
        nv += (uint64_t)c[0] + c[1] + c[2] + c[4];
        ntri += c[3];
        ncent += c[4];
    }
    J->voff[rows] = nv;
    J->toff[rows] = ntri;
    *nv_out = nv;
    *ntri_out = ntri;
    *ncent_out = ncent;
}

/* The extras of a coarse surface (mc_extra): edge ids, quantised codes and,
 * with edges only, the centre vertices. */
static vv_status
extra_alloc(mc_job *J, mc_extra *x, uint64_t nv, uint64_t ncent) {
    x->edge_ids = malloc((nv ? (size_t)nv : 1) * sizeof(uint32_t));
    x->codes = x->quantize ? malloc(nv ? (size_t)nv : 1) : NULL;
    if (!x->edge_ids || (x->quantize && !x->codes)) {
        return vv_error_set(VV_ERR_NOMEM, "isosurface: out of memory");
    }
    if (3 * (uint64_t)vv_volume_voxel_count(J->v) > UINT32_MAX) {
        return vv_error_set(VV_ERR_LIMIT, "isosurface: edge ids need %llu voxels < 2^32 / 3",
                            (unsigned long long)vv_volume_voxel_count(J->v));
    }
    J->edge_ids = x->edge_ids;
    J->codes = x->codes;
    if (J->edges_only) {
        x->n_vertices = (size_t)nv;
        x->n_centres = (size_t)ncent;
        x->centres = J->centres = malloc((ncent ? (size_t)ncent : 1) * 3 * sizeof(float));
        if (!J->centres) {
            return vv_error_set(VV_ERR_NOMEM, "isosurface: out of memory");
        }
    }
    return VV_OK;
}

/* The job of one extraction: the region, the checks of the options (errors
 * as vv_isosurface_extract), the strides and transforms; *grid_out the
 * min/max grid when it is this volume's and exact. */
static vv_status
job_init(mc_job *J, const vv_volume *v, double isovalue, const vv_isosurface_options *opt,
         const mc_extra *x, const vv_minmax_grid **grid_out) {
    const mc_tables *tb = mc_tables_get();
    if (!tb)
        return vv_error_set(VV_ERR_INVALID, "isosurface: internal error building the case tables");
    memset(J, 0, sizeof *J);
    J->v = v;
    J->iso = isovalue;
    J->tb = tb;
    for (int a = 0; a < 3; a++) {
        int lo = 0, hi = v->dims[a] - 1;
        if (opt->roi_max[0] >= 0) {
            lo = opt->roi_min[a];
            hi = opt->roi_max[a];
            if (lo < 0 || hi >= v->dims[a] || lo > hi)
                return vv_error_set(VV_ERR_INVALID,
                                    "isosurface: region of interest %d..%d on axis %c is empty or "
                                    "outside the volume's 0..%d",
                                    lo, hi, "ijk"[a], v -> dims[a] - 1);
        }
        J->lo[a] = lo;
        J->n[a] = hi - lo + 1;
    }
    if (opt->n_cut_planes < 0 || opt->n_cut_planes > VV_MAX_CUT_PLANES)
        return vv_error_set(VV_ERR_INVALID, "isosurface: %d cut planes (0..%d)", opt->n_cut_planes,
                            VV_MAX_CUT_PLANES);
    for (int p = 0; p < opt->n_cut_planes; p++)
        if (!(vv_vec3_length(opt->cut_planes[p].normal) > 0))
            return vv_error_set(VV_ERR_INVALID, "isosurface: cut plane %d has a zero normal", p);
    if (opt->scalar_volume) {
        const vv_volume *s = opt->scalar_volume;
        if (s->dims[0] != v->dims[0] || s->dims[1] != v->dims[1] || s->dims[2] != v->dims[2])
            return vv_error_set(
                VV_ERR_INVALID, "isosurface: scalar volume is %dx%dx%d, the volume %dx%dx%d",
                s->dims[0], s->dims[1], s->dims[2], v->dims[0], v->dims[1], v->dims[2]);
    }
    const vv_minmax_grid *grid = opt->minmax;
    if (grid && (!grid_exact(v->type) || grid->block < 1 ||
                 grid->dims[0] != (v->dims[0] > 1 ? (v->dims[0] - 2) / grid->block + 1 : 1) ||
                 grid->dims[1] != (v->dims[1] > 1 ? (v->dims[1] - 2) / grid->block + 1 : 1) ||
                 grid->dims[2] != (v->dims[2] > 1 ? (v->dims[2] - 2) / grid->block + 1 : 1)))
        grid = NULL; /* not this volume's grid, or values not exact in float: read voxels */
    *grid_out = grid;
    J->sy = (size_t)v->dims[0];
    J->sz = J->sy * (size_t)v->dims[1];
    J->W = (J->n[0] + MC_WORD - 1) / MC_WORD;
    J->normals = opt->compute_normals != 0;
    J->sv = opt->scalar_volume;
    J->quantize = x ? x->quantize : 0;
    J->edges_only = x && x->quantize && x->edges_only;
    if (J->edges_only) {
        if (opt->n_cut_planes)
            return vv_error_set(VV_ERR_INVALID, "isosurface: cut planes need vertex positions");
        J->normals = 0;
        J->sv = NULL;
    }
    vv_mat4 M = vv_volume_index_to_world(v);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            J->M[r][c] = M.m[r][c];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            J->G[r][c] = v->direction[3 * r + c] / v->spacing[c];
    return VV_OK;
}

vv_status
vv_isosurface_extract_ex(vv_mesh **out, const vv_volume *v, double isovalue,
                         const vv_isosurface_options *opt, mc_extra *x) {
    if (out)
        *out = NULL;
    if (!out || !v || !v->data)
        return vv_error_set(VV_ERR_INVALID, "isosurface: NULL argument");
    if (!isfinite(isovalue))
        return vv_error_set(VV_ERR_INVALID, "isosurface: isovalue %g is not finite", isovalue);
    vv_isosurface_options defaults;
    if (!opt) {
        vv_isosurface_options_init(&defaults);
        opt = &defaults;
    }
    mc_job J;
    const vv_minmax_grid *grid = NULL;
    vv_status jst = job_init(&J, v, isovalue, opt, x, &grid);
    if (jst != VV_OK)
        return jst;
    int nt = opt->threads;
    if (nt <= 0) {
        /* by default at most one thread per 2^18 voxels: on small grids starting the
         * threads of the three passes costs more than they save */
        const uint64_t region_voxels = (uint64_t)J.n[0] * (uint64_t)J.n[1] * (uint64_t)J.n[2];
        const uint64_t cap = region_voxels >> 18 > 0 ? region_voxels >> 18 : 1;
        nt = vv_threads_get();
        if ((uint64_t)nt > cap)
            nt = (int)cap;
    }
    if (nt > VV_MC_MAX_THREADS)
        nt = VV_MC_MAX_THREADS;
    const size_t rows = (size_t)J.n[1] * (size_t)J.n[2];
    vv_status st = VV_OK;
    vv_mesh *m = NULL;
    J.bits = malloc(rows * (size_t)J.W * sizeof(uint64_t) + sizeof(uint64_t));
    J.cellmask = calloc((size_t)J.W, sizeof(uint64_t));
    J.cnt = malloc(MC_CNT * rows * sizeof(uint32_t));
    J.voff = malloc((rows + 1) * sizeof(uint64_t));
    J.toff = malloc((rows + 1) * sizeof(uint64_t));
    J.coff = J.edges_only ? malloc((rows + 1) * sizeof(uint64_t)) : NULL;
    if (!J.bits || !J.cellmask || !J.cnt || !J.voff || !J.toff || (J.edges_only && !J.coff)) {
        st = vv_error_set(VV_ERR_NOMEM, "isosurface: out of memory for %zu grid rows", rows);
        goto done;
    }
    for (int i = 0; i + 1 < J.n[0]; i++)
        J.cellmask[i / MC_WORD] |= 1ULL << (i % MC_WORD);

    /* pass 1: classify */
    mc_pass P;
    memset(&P, 0, sizeof P);
    P.J = &J;
    P.grid = grid;
    long zn[VV_MC_MAX_THREADS] = {0};
    uint8_t *scratch[VV_MC_MAX_THREADS] = {NULL};
    P.scratch = scratch;
    P.zero_normals = zn;
    for (int w = 0; w < nt; w++)
        if (!(scratch[w] = malloc((size_t)J.W * MC_WORD))) {
            for (int q = 0; q < w; q++)
                free(scratch[q]);
            st = vv_error_set(VV_ERR_NOMEM, "isosurface: out of memory");
            goto done;
        }
    P.which = MC_PASS_CLASSIFY;
    run_pass(&P, (long)rows, nt, NULL);
    for (int w = 0; w < nt; w++)
        free(scratch[w]);
    if (report(&opt->progress, 0.2)) {
        st = vv_error_set(VV_ERR_CANCELLED, "isosurface: cancelled");
        goto done;
    }
    /* pass 2: count */
    P.which = MC_PASS_COUNT;
    run_pass(&P, (long)rows, nt, NULL);
    /* pass 3: prefix sums */
    uint64_t nv, ntri, ncent;
    prefix_sums(&J, rows, &nv, &ntri, &ncent);
    if (nv > VV_MESH_MAX_ELEMENTS || ntri > VV_MESH_MAX_ELEMENTS || nv > UINT32_MAX) {
        st = vv_error_set(
            VV_ERR_LIMIT, "isosurface: %llu vertices and %llu triangles (at most %zu each)",
            (unsigned long long)nv, (unsigned long long)ntri, (size_t)VV_MESH_MAX_ELEMENTS);
        goto done;
    }
    if (report(&opt->progress, 0.4)) {
        st = vv_error_set(VV_ERR_CANCELLED, "isosurface: cancelled");
        goto done;
    }
    if ((st = vv_mesh_new(&m)) != VV_OK ||
        (st = vv_mesh_reserve(m, nv && !J.edges_only ? (size_t)nv : 1, ntri ? (size_t)ntri : 1)) !=
            VV_OK ||
        (st = vv_mesh_enable_attributes(m, J.normals, J.sv != NULL)) != VV_OK) {
        vv_error_prefix(st, "isosurface");
        goto done;
    }
    if (x && (st = extra_alloc(&J, x, nv, ncent)) != VV_OK)
        goto done;
    m->n_vertices = J.edges_only ? 0 : (size_t)nv;
    m->n_triangles = (size_t)ntri;
    J.m = m;
    /* pass 4: generate */
    P.which = MC_PASS_GENERATE;
    if (run_pass(&P, (long)rows, nt, &opt->progress) != VV_OK) {
        st = vv_error_set(VV_ERR_CANCELLED, "isosurface: cancelled");
        goto done;
    }
    long zero_normals = 0;
    for (int w = 0; w < nt; w++)
        zero_normals += zn[w];
    if (J.normals && zero_normals > 0)
        fix_zero_normals(m);
    for (int p = 0; p < opt->n_cut_planes; p++) {
        vv_vec3 n = vv_vec3_normalize(opt->cut_planes[p].normal);
        if ((st = vv_mesh_clip_plane(m, n, -vv_vec3_dot(n, opt->cut_planes[p].point))) != VV_OK) {
            vv_error_prefix(st, "isosurface: cut plane %d", p);
            goto done;
        }
    }
    report(&opt->progress, 1.0);
done:
    free(J.bits);
    free(J.cellmask);
    free(J.cnt);
    free(J.voff);
    free(J.toff);
    free(J.coff);
    if (st != VV_OK) {
        vv_mesh_free(m);
        if (x) {
            free(x->edge_ids);
            free(x->codes);
            free(x->centres);
            x->edge_ids = NULL;
            x->codes = NULL;
            x->centres = NULL;
        }
        return st;
    }
    *out = m;
    return VV_OK;
}

/* ---- caps: inside area of a grid face ------------------------------------------ */

/* Crossing on the edge from a (lower index) to b, as the extraction places it. */
static double
crossing_t(double a, double b, double iso) {
    double t = (iso - a) / (b - a);
    if (!(t >= 0))
        t = 0;
    return t > 1 ? 1 : t;
}

/* Emits the polygon (n points qu, qw in face cell (a, b)) in index coordinates. */
static void
face_emit(vv_mc_face_polygon_fn emit, void *ctx, int axis, int pos, int a, int b, int n,
          const double *qu, const double *qw) {
    const int u = axis == 0 ? 1 : 0, w = axis == 2 ? 1 : 2;
    double pts[8][3];
    for (int c = 0; c < n; c++) {
        pts[c][axis] = pos;
        pts[c][u] = a + qu[c];
        pts[c][w] = b + qw[c];
    }
    emit(ctx, n, &pts[0][0]);
}

double
vv_mc_face_inside_area(const vv_volume *v, double isovalue, int axis, int pos, const int lo[3],
                       const int hi[3]) {
    return vv_mc_face_inside_polygons(v, isovalue, axis, pos, lo, hi, NULL, NULL);
}

double
vv_mc_face_inside_polygons(const vv_volume *v, double isovalue, int axis, int pos, const int lo[3],
                           const int hi[3], vv_mc_face_polygon_fn emit, void *ctx) {
    const int u = axis == 0 ? 1 : 0, w = axis == 2 ? 1 : 2;
    const size_t st[3] = {1, (size_t)v->dims[0], (size_t)v->dims[0] * (size_t)v->dims[1]};
    double area = 0;
    for (int b = lo[w]; b < hi[w]; b++)
        for (int a = lo[u]; a < hi[u]; a++) {
            size_t i0 = (size_t)pos * st[axis] + (size_t)a * st[u] + (size_t)b * st[w];
            /* cyclic corners (a,b) (a+1,b) (a+1,b+1) (a,b+1) */
            const double cu[4] = {0, 1, 1, 0}, cw[4] = {0, 0, 1, 1};
            double f[4] = {val(v, i0), val(v, i0 + st[u]), val(v, i0 + st[u] + st[w]),
                           val(v, i0 + st[w])};
            int in[4], nin = 0;
            for (int c = 0; c < 4; c++)
                nin += in[c] = f[c] >= isovalue;
            if (nin == 0)
                continue;
            if (nin == 4) {
                area += 1;
                if (emit)
                    face_emit(emit, ctx, axis, pos, a, b, 4, cu, cw);
                continue;
            }
            /* crossing points on the cyclic edges c -> c+1, t measured from the lower index */
            double pu[4] = {0, 0, 0, 0}, pw[4] = {0, 0, 0, 0};
            for (int c = 0; c < 4; c++) {
                int d = (c + 1) & 3;
                if (in[c] == in[d])
                    continue;
                int l = (c == 2 || c == 3) ? d : c; /* edges 2 and 3 run towards lower index */
                int h = l == c ? d : c;
                double t = crossing_t(f[l], f[h], isovalue);
                pu[c] = cu[l] + t * (cu[h] - cu[l]);
                pw[c] = cw[l] + t * (cw[h] - cw[l]);
            }
            int amb = nin == 2 && in[0] == in[2];
            if (amb && !mc_face_joined(f[0] - isovalue, f[1] - isovalue, f[2] - isovalue,
                                       f[3] - isovalue)) {
                for (int c = 0; c < 4; c++)
                    if (in[c]) { /* triangle corner, crossing before, crossing after */
                        int e0 = (c + 3) & 3, e1 = c;
                        area += 0.5 * fabs((pu[e0] - cu[c]) * (pw[e1] - cw[c]) -
                                           (pw[e0] - cw[c]) * (pu[e1] - cu[c]));
                        if (emit) {
                            const double tu[3] = {cu[c], pu[e1], pu[e0]},
                                         tw[3] = {cw[c], pw[e1], pw[e0]};
                            face_emit(emit, ctx, axis, pos, a, b, 3, tu, tw);
                        }
                    }
                continue;
            }
            double qu[8], qw[8];
            int n = 0;
            for (int c = 0; c < 4; c++) {
                if (in[c]) {
                    qu[n] = cu[c];
                    qw[n++] = cw[c];
                }
                if (in[c] != in[(c + 1) & 3]) {
                    qu[n] = pu[c];
                    qw[n++] = pw[c];
                }
            }
            double s = 0;
            for (int c = 0; c < n; c++) {
                int d = (c + 1) % n;
                s += qu[c] * qw[d] - qu[d] * qw[c];
            }
            area += 0.5 * fabs(s);
            if (emit)
                face_emit(emit, ctx, axis, pos, a, b, n, qu, qw);
        }
    return area;
}
