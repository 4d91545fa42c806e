/*
 * Volume and surface area of an isosurface (Measurement component of the
 * VolVis paper), on the whole volume, a region, or a surface-tracked
 * section, by voxel counting or by Marching Cubes.
 *
 * Surface tracking: the section is the 6-connected component of inside
 * voxels (value >= isovalue) that holds the seed, found by a flood fill.
 * For Marching Cubes the section's surface is extracted from a copy of its
 * bounding box (plus one voxel) in which the inside voxels of other
 * components are lowered below the isovalue. Such a voxel never shares a
 * cell edge with the section (it would be in the section), so the section's
 * own crossings and face decisions are unchanged.
 *
 * Marching Cubes volume: divergence theorem V = 1/3 ∮ (x − c) · n dA over
 * the closed boundary of the inside region, i.e. the triangles plus the
 * caps where the region's box faces cut the inside region. The caps are
 * computed by marching squares on the box faces with the extraction's own
 * edge interpolation and face decider (vv_mc_face_inside_area), and on a
 * face of outward normal n through x_F they contribute (x_F − c) · n A / 3.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "measure/measure_internal.h"
#include "volvis/surface.h"

void
vv_isosurface_measure_options_init(vv_isosurface_measure_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    o->method = VV_MEASURE_MC;
    vv_roi_init(&o->region);
}

static inline int
inside(const vv_volume *v, size_t i, double iso) {
    return vv_voxel_at(v, i) >= iso;
}

#define COUNT_RUN(T)                                                                               \
    {                                                                                              \
        const T *d = (const T *)v->data + i0;                                                      \
        for (int i = 0; i < n; i++)                                                                \
            c += (double)d[i] >= iso;                                                              \
        return c;                                                                                  \
    }

/* Voxels >= iso among n voxels from linear index i0. */
static uint64_t
count_run(const vv_volume *v, size_t i0, int n, double iso) {
    uint64_t c = 0;
    switch (v->type) {
    case VV_U8:
        COUNT_RUN(uint8_t)
    case VV_I8:
        COUNT_RUN(int8_t)
    case VV_U16:
        COUNT_RUN(uint16_t)
    case VV_I16:
        COUNT_RUN(int16_t)
    case VV_U32:
        COUNT_RUN(uint32_t)
    case VV_I32:
        COUNT_RUN(int32_t)
    case VV_F32:
        COUNT_RUN(float)
    default:
        COUNT_RUN(double)
    }
}

/* The inside voxel of the region nearest (in world distance) to seed, within 2 voxels. */
static vv_status
find_seed(const vv_volume *v, double iso, const region_box *rb, const double seed[3], int out[3]) {
    for (int a = 0; a < 3; a++)
        if (!isfinite(seed[a]) || seed[a] < -0.5 || seed[a] > v->dims[a] - 0.5)
            return vv_error_set(VV_ERR_INVALID,
                                "seed (%g, %g, %g) is outside the volume (voxels 0..%d, 0..%d, "
                                "0..%d)",
                                seed[0], seed[1], seed[2], v->dims[0] - 1, v->dims[1] - 1,
                                v->dims[2] - 1);
    double best = INFINITY;
    int c[3] = {(int)floor(seed[0] + 0.5), (int)floor(seed[1] + 0.5), (int)floor(seed[2] + 0.5)};
    for (int dk = -2; dk <= 2; dk++)
        for (int dj = -2; dj <= 2; dj++)
            for (int di = -2; di <= 2; di++) {
                int p[3] = {c[0] + di, c[1] + dj, c[2] + dk};
                int ok = 1;
                for (int a = 0; a < 3; a++)
                    ok &= p[a] >= rb->lo[a] && p[a] <= rb->hi[a];
                if (!ok || !region_keeps(rb, p[0], p[1], p[2]) ||
                    !(vv_volume_get(v, p[0], p[1], p[2]) >= iso))
                    continue;
                double d = 0;
                for (int a = 0; a < 3; a++)
                    d += (p[a] - seed[a]) * (p[a] - seed[a]) * v->spacing[a] * v->spacing[a];
                if (d < best) {
                    best = d;
                    memcpy(out, p, sizeof p);
                }
            }
    if (!isfinite(best))
        return vv_error_set(VV_ERR_INVALID,
                            "seed (%g, %g, %g) is not at the isosurface: no voxel >= %g within 2 "
                            "voxels",
                            seed[0], seed[1], seed[2], iso);
    return VV_OK;
}

/* Flood fill: mask[i] = 1 for the voxels of the 6-connected inside component of s. */
static vv_status
flood_fill(const vv_volume *v, double iso, const region_box *rb, const int s[3], uint8_t *mask,
           uint64_t *count, int bmin[3], int bmax[3]) {
    const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
    size_t cap = 1 << 16, n = 0;
    uint64_t *stack = malloc(cap * sizeof *stack);
    if (!stack)
        return vv_error_set(VV_ERR_NOMEM, "surface tracking: out of memory");
    size_t s0 = (size_t)s[2] * sz + (size_t)s[1] * sy + (size_t)s[0];
    mask[s0] = 1;
    stack[n++] = s0;
    uint64_t cnt = 0;
    for (int a = 0; a < 3; a++)
        bmin[a] = bmax[a] = s[a];
    while (n) {
        size_t c = stack[--n];
        cnt++;
        int p[3] = {(int)(c % sy), (int)(c / sy % (size_t)v->dims[1]), (int)(c / sz)};
        for (int a = 0; a < 3; a++) {
            bmin[a] = p[a] < bmin[a] ? p[a] : bmin[a];
            bmax[a] = p[a] > bmax[a] ? p[a] : bmax[a];
        }
        static const int nb[6][3] = {{-1, 0, 0}, {1, 0, 0},  {0, -1, 0},
                                     {0, 1, 0},  {0, 0, -1}, {0, 0, 1}};
        for (int q = 0; q < 6; q++) {
            int r[3] = {p[0] + nb[q][0], p[1] + nb[q][1], p[2] + nb[q][2]};
            if (r[0] < rb->lo[0] || r[0] > rb->hi[0] || r[1] < rb->lo[1] || r[1] > rb->hi[1] ||
                r[2] < rb->lo[2] || r[2] > rb->hi[2])
                continue;
            size_t ri = (size_t)r[2] * sz + (size_t)r[1] * sy + (size_t)r[0];
            if (mask[ri] || !inside(v, ri, iso) ||
                (rb->n_planes && !region_keeps(rb, r[0], r[1], r[2])))
                continue;
            mask[ri] = 1;
            if (n == cap) {
                uint64_t *ns = realloc(stack, 2 * cap * sizeof *stack);
                if (!ns) {
                    free(stack);
                    return vv_error_set(VV_ERR_NOMEM, "surface tracking: out of memory");
                }
                stack = ns;
                cap *= 2;
            }
            stack[n++] = ri;
        }
    }
    free(stack);
    *count = cnt;
    return VV_OK;
}

/* Voxel counting over the region (mask NULL) or the section (mask set):
 * the voxels of @p rb counted; a face whose neighbour lies outside the box
 * @p olo .. @p ohi (the region's boundary; the volume's, for a box of it
 * with its ghost voxels) is cut, others are area when the neighbour is
 * outside the surface. Adds to *m's counts. */
static void
voxel_measure(const vv_volume *v, double iso, const region_box *rb, const int olo[3],
              const int ohi[3], const uint8_t *mask, vv_isosurface_measure *m) {
    const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
    const double fa[3] = {v->spacing[1] * v->spacing[2], v->spacing[0] * v->spacing[2],
                          v->spacing[0] * v->spacing[1]};
    uint64_t count = 0;
    double area = 0, cut = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : count, area, cut)
    for (int k = rb->lo[2]; k <= rb->hi[2]; k++)
        for (int j = rb->lo[1]; j <= rb->hi[1]; j++)
            for (int i = rb->lo[0]; i <= rb->hi[0]; i++) {
                size_t c = (size_t)k * sz + (size_t)j * sy + (size_t)i;
                int in = mask ? mask[c]
                              : inside(v, c, iso) && (!rb->n_planes || region_keeps(rb, i, j, k));
                if (!in)
                    continue;
                count++;
                for (int a = 0; a < 3; a++)
                    for (int d = -1; d <= 1; d += 2) {
                        int q[3] = {i, j, k};
                        q[a] += d;
                        if (q[a] < olo[a] || q[a] > ohi[a]) {
                            cut += fa[a]; /* the region's boundary cuts here */
                            continue;
                        }
                        size_t qc = (size_t)q[2] * sz + (size_t)q[1] * sy + (size_t)q[0];
                        int qin = mask ? mask[qc]
                                       : inside(v, qc, iso) &&
                                             (!rb->n_planes || region_keeps(rb, q[0], q[1], q[2]));
                        if (!qin)
                            area += fa[a];
                    }
            }
    m->voxels += count;
    m->volume = (double)m->voxels * v->spacing[0] * v->spacing[1] * v->spacing[2];
    m->area += area;
    m->cut_area += cut;
    m->area_bias = 1.5;
}

/* ---- cut planes: clipping the closed boundary ---------------------------------------- */

/*
 * With cut planes the solid is S ∩ H_0 ∩ ... ∩ H_{k-1} (S the inside region of the
 * box, H_j = {x : n_j · x + d_j >= 0}). Its boundary is a closed polygon soup: the
 * Marching Cubes triangles and the box-face caps, each clipped by every plane
 * (Sutherland–Hodgman), plus one cap per plane. A polygon clipped by plane j leaves
 * edges on the plane (from its exit to its entry point); reversed, they form the
 * boundary of cap j, a 1-cycle because the soup it comes from is closed. Cap j is
 * then the fan of triangles (o_j, b, a) from a point o_j on the plane over its
 * reversed edges: a signed 2-chain whose winding number is 1 on the cap and 0
 * elsewhere, so its integrals are the cap's whatever the cap's shape (holes, several
 * pieces). Its triangles are clipped by the later planes j+1.. and feed their caps.
 * The divergence volume and the areas are sums over the clipped pieces.
 */

#define CLIP_MAX_POINTS (8 + 2 * VV_MAX_CUT_PLANES + 4)

typedef struct cap_segment {
    double a[3], b[3]; /* cap boundary edge a -> b */
} cap_segment;

typedef struct clipper {
    int np;
    double n[VV_MAX_CUT_PLANES][3], d[VV_MAX_CUT_PLANES]; /* keep n·x + d >= 0 */
    double c[3];                                          /* reference point of the volume */
    cap_segment *seg[VV_MAX_CUT_PLANES];
    size_t n_seg[VV_MAX_CUT_PLANES], cap_seg[VV_MAX_CUT_PLANES];
    double vol6, area2, cut2; /* 6 V, 2 A, 2 cut area */
    int nomem;
} clipper;

enum { PIECE_SURFACE, PIECE_CAP };

static void
add_segment(clipper *C, int j, const double *a, const double *b) {
    if (C->n_seg[j] == C->cap_seg[j]) {
        size_t cap = C->cap_seg[j] ? 2 * C->cap_seg[j] : 256;
        cap_segment *ns = realloc(C->seg[j], cap * sizeof *ns);
        if (!ns) {
            C->nomem = 1;
            return;
        }
        C->seg[j] = ns;
        C->cap_seg[j] = cap;
    }
    cap_segment *g = C->seg[j] + C->n_seg[j]++;
    memcpy(g->a, a, sizeof g->a);
    memcpy(g->b, b, sizeof g->b);
}

/* The crossing of the plane on edge ab, computed from the lexicographically lower end so
 * that the two polygons sharing the edge get the same point. */
static void
crossing(const double *a, double da, const double *b, double db, double *x) {
    if (b[0] < a[0] || (b[0] == a[0] && (b[1] < a[1] || (b[1] == a[1] && b[2] < a[2])))) {
        const double *t = a;
        a = b;
        b = t;
        double td = da;
        da = db;
        db = td;
    }
    double t = da / (da - db);
    for (int q = 0; q < 3; q++)
        x[q] = a[q] + t * (b[q] - a[q]);
}

/* Clips polygon p (n points, world) by planes first.. and adds the rest to the sums: its
 * divergence volume, its area (PIECE_SURFACE) or its area along outward normal out
 * (PIECE_CAP). The clip edges go to the planes' caps. */
static void
clip_piece(clipper *C, int n, const double (*p)[3], int first, int kind, const double *out) {
    double buf[2][CLIP_MAX_POINTS][3];
    int cur = 0;
    memcpy(buf[0], p, (size_t)n * sizeof *buf[0]);
    for (int j = first; j < C->np && n >= 3; j++) {
        double dist[CLIP_MAX_POINTS];
        int all_in = 1;
        for (int i = 0; i < n; i++) {
            const double *x = buf[cur][i];
            dist[i] = C->n[j][0] * x[0] + C->n[j][1] * x[1] + C->n[j][2] * x[2] + C->d[j];
            all_in &= dist[i] >= 0;
        }
        if (all_in)
            continue;
        double(*src)[3] = buf[cur], (*dst)[3] = buf[cur ^ 1];
        int m = 0, n_on = 0, on_idx[CLIP_MAX_POINTS], on_exit[CLIP_MAX_POINTS];
        for (int i = 0; i < n && m < CLIP_MAX_POINTS - 1; i++) {
            int i1 = i + 1 == n ? 0 : i + 1;
            int in0 = dist[i] >= 0, in1 = dist[i1] >= 0;
            if (in0)
                memcpy(dst[m++], src[i], sizeof dst[0]);
            if (in0 != in1) {
                crossing(src[i], dist[i], src[i1], dist[i1], dst[m]);
                on_idx[n_on] = m++;
                on_exit[n_on++] = in0;
            }
        }
        /* each exit point is followed (cyclically) by its entry point: edge exit -> entry */
        for (int q = 0; q < n_on; q++) {
            int r = q + 1 == n_on ? 0 : q + 1;
            if (on_exit[q] && !on_exit[r])
                add_segment(C, j, dst[on_idx[r]], dst[on_idx[q]]); /* reversed for the cap */
        }
        n = m;
        cur ^= 1;
    }
    if (n < 3)
        return;
    const double(*q)[3] = (const double(*)[3])buf[cur];
    double va[3] = {0, 0, 0}, v6 = 0;
    double a0 = q[0][0] - C->c[0], a1 = q[0][1] - C->c[1], a2 = q[0][2] - C->c[2];
    for (int i = 1; i + 1 < n; i++) {
        double b0 = q[i][0] - C->c[0], b1 = q[i][1] - C->c[1], b2 = q[i][2] - C->c[2];
        double e0 = q[i + 1][0] - C->c[0], e1 = q[i + 1][1] - C->c[1], e2 = q[i + 1][2] - C->c[2];
        v6 += a0 * (b1 * e2 - b2 * e1) + a1 * (b2 * e0 - b0 * e2) + a2 * (b0 * e1 - b1 * e0);
        double u0 = b0 - a0, u1 = b1 - a1, u2 = b2 - a2, w0 = e0 - a0, w1 = e1 - a1, w2 = e2 - a2;
        va[0] += u1 * w2 - u2 * w1;
        va[1] += u2 * w0 - u0 * w2;
        va[2] += u0 * w1 - u1 * w0;
    }
    C->vol6 += v6;
    if (kind == PIECE_SURFACE)
        C->area2 += sqrt(va[0] * va[0] + va[1] * va[1] + va[2] * va[2]);
    else
        C->cut2 += va[0] * out[0] + va[1] * out[1] + va[2] * out[2];
}

/* Box-face cap polygons: index coordinates mapped to world, wound outwards. */
typedef struct face_ctx {
    clipper *C;
    vv_mat4 M;
    int reverse;
    double out[3];
} face_ctx;

static void
face_polygon(void *vctx, int n, const double *pts) {
    face_ctx *f = vctx;
    double w[CLIP_MAX_POINTS][3];
    for (int i = 0; i < n; i++) {
        const double *x = pts + 3 * (f->reverse ? n - 1 - i : i);
        vv_vec3 y = vv_mat4_mul_point(f->M, vv_vec3_make(x[0], x[1], x[2]));
        w[i][0] = y.x;
        w[i][1] = y.y;
        w[i][2] = y.z;
    }
    clip_piece(f->C, n, (const double(*)[3])w, 0, PIECE_CAP, f->out);
}

/* Marching Cubes measurement of volume w over its box lo..hi cut by world planes
 * (n·(x − p) >= 0 kept). */
static vv_status
mc_measure_cut(const vv_volume *w, double iso, const int lo[3], const int hi[3], int n_planes,
               const vv_cut_plane *planes, int threads, const vv_progress *progress,
               vv_isosurface_measure *m) {
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.threads = threads;
    o.compute_normals = 0;
    if (progress)
        o.progress = *progress;
    for (int a = 0; a < 3; a++) {
        o.roi_min[a] = lo[a];
        o.roi_max[a] = hi[a];
    }
    vv_mesh *mesh = NULL;
    vv_status s = vv_isosurface_extract(&mesh, w, iso, &o);
    if (s != VV_OK)
        return s;
    const vv_mat4 M = vv_volume_index_to_world(w);
    const vv_vec3 c = vv_mat4_mul_point(
        M, vv_vec3_make(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])));
    clipper base;
    memset(&base, 0, sizeof base);
    base.np = n_planes;
    base.c[0] = c.x;
    base.c[1] = c.y;
    base.c[2] = c.z;
    for (int j = 0; j < n_planes; j++) {
        vv_vec3 n = vv_vec3_normalize(planes[j].normal);
        base.n[j][0] = n.x;
        base.n[j][1] = n.y;
        base.n[j][2] = n.z;
        base.d[j] = -vv_vec3_dot(n, planes[j].point);
    }
    const int nt = threads > 0 ? threads : 1;
    clipper *C = calloc((size_t)nt, sizeof *C);
    if (!C) {
        vv_mesh_free(mesh);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for the cut-plane caps");
    }
    for (int t = 0; t < nt; t++)
        C[t] = base;
    const float *P = mesh->positions;
    const long n_tri = (long)mesh->n_triangles;
#pragma omp parallel num_threads(nt)
    {
        clipper *my = C + omp_get_thread_num();
#pragma omp for schedule(static)
        for (long t = 0; t < n_tri; t++) {
            double q[3][3];
            for (int v = 0; v < 3; v++)
                for (int a = 0; a < 3; a++)
                    q[v][a] = P[3 * (size_t)mesh->triangles[3 * t + v] + a];
            clip_piece(my, 3, (const double(*)[3])q, 0, PIECE_SURFACE, NULL);
        }
    }
    m->n_triangles = mesh->n_triangles;
    vv_mesh_free(mesh);
    /* gather the threads' sums and cap edges into C[0] */
    clipper *A = C;
    for (int t = 1; t < nt; t++) {
        A->vol6 += C[t].vol6;
        A->area2 += C[t].area2;
        A->cut2 += C[t].cut2;
        A->nomem |= C[t].nomem;
        for (int j = 0; j < n_planes; j++) {
            for (size_t g = 0; g < C[t].n_seg[j]; g++)
                add_segment(A, j, C[t].seg[j][g].a, C[t].seg[j][g].b);
            free(C[t].seg[j]);
        }
    }
    /* caps on the six faces of the box, wound outwards, clipped */
    face_ctx f;
    f.C = A;
    f.M = M;
    vv_vec3 col[3];
    for (int a = 0; a < 3; a++)
        col[a] = vv_vec3_make(M.m[0][a], M.m[1][a], M.m[2][a]); /* world step of one index */
    for (int a = 0; a < 3; a++) {
        const int u = a == 0 ? 1 : 0, ww = a == 2 ? 1 : 2;
        vv_vec3 ccw = vv_vec3_cross(col[u], col[ww]); /* vector area of an emitted polygon */
        vv_vec3 nrm = vv_vec3_normalize(ccw);
        if (vv_vec3_dot(nrm, col[a]) < 0)
            nrm = vv_vec3_scale(nrm, -1); /* towards increasing index a */
        for (int side = 0; side < 2; side++) {
            vv_vec3 out = side ? nrm : vv_vec3_scale(nrm, -1);
            f.reverse = vv_vec3_dot(ccw, out) < 0;
            f.out[0] = out.x;
            f.out[1] = out.y;
            f.out[2] = out.z;
            vv_mc_face_inside_polygons(w, iso, a, side ? hi[a] : lo[a], lo, hi, face_polygon, &f);
        }
    }
    /* the planes' caps, in order: cap j is clipped by the planes after it */
    for (int j = 0; j < n_planes && !A->nomem; j++) {
        const double *n = A->n[j];
        double h = n[0] * A->c[0] + n[1] * A->c[1] + n[2] * A->c[2] + A->d[j];
        double tri[3][3], out[3] = {-n[0], -n[1], -n[2]};
        for (int q = 0; q < 3; q++)
            tri[0][q] = A->c[q] - h * n[q]; /* o_j: c projected onto the plane */
        for (size_t g = 0; g < A->n_seg[j]; g++) {
            memcpy(tri[1], A->seg[j][g].a, sizeof tri[1]);
            memcpy(tri[2], A->seg[j][g].b, sizeof tri[2]);
            clip_piece(A, 3, (const double(*)[3])tri, j + 1, PIECE_CAP, out);
        }
    }
    int nomem = A->nomem;
    m->volume = A->vol6 / 6;
    m->area = A->area2 / 2;
    m->cut_area = A->cut2 / 2;
    m->area_bias = 1;
    for (int j = 0; j < n_planes; j++)
        free(A->seg[j]);
    free(C);
    if (nomem)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for the cut-plane caps");
    return VV_OK;
}

/* Marching Cubes area and capped divergence volume of volume w over its box lo..hi.
 * Caps close the volume on all six faces; cut_area counts those on the faces
 * whose bit is set in @p outer (bit 2a: the low face of axis a, 2a + 1 the
 * high one; a box measured as part of a larger one leaves its inner faces
 * out: their caps cancel between the two boxes sharing them). */
static vv_status
mc_measure(const vv_volume *w, double iso, const int lo[3], const int hi[3], int threads,
           const vv_progress *progress, unsigned outer, vv_isosurface_measure *m) {
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.threads = threads;
    o.compute_normals = 0;
    if (progress)
        o.progress = *progress;
    for (int a = 0; a < 3; a++) {
        o.roi_min[a] = lo[a];
        o.roi_max[a] = hi[a];
    }
    vv_mesh *mesh = NULL;
    vv_status s = vv_isosurface_extract(&mesh, w, iso, &o);
    if (s != VV_OK)
        return s;
    const vv_mat4 M = vv_volume_index_to_world(w);
    const vv_vec3 c = vv_mat4_mul_point(
        M, vv_vec3_make(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])));
    double vol = 0, area = 0;
    const double cx = c.x, cy = c.y, cz = c.z;
    const float *P = mesh->positions;
#pragma omp parallel for num_threads(threads > 0 ? threads : vv_threads_get())                  \
    schedule(static) reduction(+ : vol, area)
    for (long t = 0; t < (long)mesh->n_triangles; t++) {
        const uint32_t *tr = mesh->triangles + 3 * t;
        const float *q0 = P + 3 * (size_t)tr[0], *q1 = P + 3 * (size_t)tr[1],
                    *q2 = P + 3 * (size_t)tr[2];
        double a0 = q0[0] - cx, a1 = q0[1] - cy, a2 = q0[2] - cz;
        double b0 = q1[0] - cx, b1 = q1[1] - cy, b2 = q1[2] - cz;
        double d0 = q2[0] - cx, d1 = q2[1] - cy, d2 = q2[2] - cz;
        /* p0 . (p1 x p2) and |(p1 - p0) x (p2 - p0)| */
        vol += a0 * (b1 * d2 - b2 * d1) + a1 * (b2 * d0 - b0 * d2) + a2 * (b0 * d1 - b1 * d0);
        double u0 = b0 - a0, u1 = b1 - a1, u2 = b2 - a2, w0 = d0 - a0, w1 = d1 - a1, w2 = d2 - a2;
        double x0 = u1 * w2 - u2 * w1, x1 = u2 * w0 - u0 * w2, x2 = u0 * w1 - u1 * w0;
        area += sqrt(x0 * x0 + x1 * x1 + x2 * x2);
    }
    vol /= 6;
    m->area = 0.5 * area;
    m->n_triangles = mesh->n_triangles;
    vv_mesh_free(mesh);
    /* caps on the six faces of the box */
    double cut = 0;
    vv_vec3 col[3];
    for (int a = 0; a < 3; a++)
        col[a] = vv_vec3_make(M.m[0][a], M.m[1][a], M.m[2][a]); /* world step of one index */
    for (int a = 0; a < 3; a++) {
        const int u = a == 0 ? 1 : 0, ww = a == 2 ? 1 : 2;
        vv_vec3 nrm = vv_vec3_cross(col[u], col[ww]);
        double cell_area = vv_vec3_length(nrm);
        nrm = vv_vec3_normalize(nrm);
        if (vv_vec3_dot(nrm, col[a]) < 0)
            nrm = vv_vec3_scale(nrm, -1); /* nrm points towards increasing index a */
        for (int side = 0; side < 2; side++) {
            int pos = side ? hi[a] : lo[a];
            double A = vv_mc_face_inside_area(w, iso, a, pos, lo, hi) * cell_area;
            if (A == 0)
                continue;
            double x[3] = {lo[0], lo[1], lo[2]};
            x[a] = pos;
            vv_vec3 xf = vv_vec3_sub(vv_mat4_mul_point(M, vv_vec3_make(x[0], x[1], x[2])), c);
            vv_vec3 n = side ? nrm : vv_vec3_scale(nrm, -1);
            vol += vv_vec3_dot(xf, n) * A / 3;
            if (outer & (1u << (2 * a + side)))
                cut += A;
        }
    }
    m->volume = vol;
    m->cut_area = cut;
    m->area_bias = 1;
    return VV_OK;
}

/* Copy of the section's box (bmin..bmax) plus one voxel (two with cut planes), clamped to
 * the region, in which the inside voxels not in mask that the cut planes keep are lowered
 * just below the isovalue. */
static vv_status
masked_copy(const vv_volume *v, double isovalue, const region_box *rbp, const uint8_t *mask,
            const int bmin[3], const int bmax[3], int threads, vv_volume **out) {
    const region_box rb = *rbp;
    vv_status s;
    int lo[3], hi[3], dims[3];
    const int margin = rb.n_planes ? 2 : 1;
    for (int a = 0; a < 3; a++) {
        lo[a] = bmin[a] - margin < rb.lo[a] ? rb.lo[a] : bmin[a] - margin;
        hi[a] = bmax[a] + margin > rb.hi[a] ? rb.hi[a] : bmax[a] + margin;
        if (hi[a] == lo[a]) { /* keep two voxels for cells */
            if (hi[a] < rb.hi[a])
                hi[a]++;
            else
                lo[a]--;
        }
        dims[a] = hi[a] - lo[a] + 1;
    }
    const int exact_float = v->type == VV_U8 || v->type == VV_I8 || v->type == VV_U16 ||
                            v->type == VV_I16 || v->type == VV_F32;
    vv_volume *w = NULL;
    if ((s = vv_volume_new(&w, dims, exact_float ? VV_F32 : VV_F64)) != VV_OK)
        return s;
    vv_mat4 M = vv_volume_index_to_world(v);
    vv_vec3 o = vv_mat4_mul_point(M, vv_vec3_make(lo[0], lo[1], lo[2]));
    w->origin[0] = o.x;
    w->origin[1] = o.y;
    w->origin[2] = o.z;
    memcpy(w->spacing, v->spacing, sizeof w->spacing);
    memcpy(w->direction, v->direction, sizeof w->direction);
    float below_f = (float)isovalue;
    while ((double)below_f >= isovalue)
        below_f = nextafterf(below_f, -INFINITY);
    const double below_d = nextafter(isovalue, -INFINITY);
    const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int k = 0; k < dims[2]; k++)
        for (int j = 0; j < dims[1]; j++)
            for (int i = 0; i < dims[0]; i++) {
                int I = lo[0] + i, Jj = lo[1] + j, K = lo[2] + k;
                const size_t src = (size_t)K * sz + (size_t)Jj * sy + (size_t)I;
                double x = vv_voxel_at(v, src);
                /* voxels the cut planes remove keep their values: the section's surface
                 * reaches across the planes unchanged and is clipped there */
                int own = mask[src] || (rb.n_planes && !region_keeps(&rb, I, Jj, K));
                size_t q = ((size_t)k * (size_t)dims[1] + (size_t)j) * (size_t)dims[0] + (size_t)i;
                if (exact_float)
                    ((float *)w->data)[q] = !own && x >= isovalue ? below_f : (float)x;
                else
                    ((double *)w->data)[q] = !own && x >= isovalue ? below_d : x;
            }
    vv_volume_update_range(w);
    *out = w;
    return VV_OK;
}

/* The boxes vv_measure_isosurface_boxes measures: IB_X x IB_Y x IB_Z voxels
 * of their own, read with a ghost voxel beyond each face inside the volume
 * (voxel counting: the faces to the neighbours), or beyond each upper face
 * (Marching Cubes: the cells of the box's own voxels, so that the boxes'
 * cells tile the volume's). */
#define IB_X 128
#define IB_Y 128
#define IB_Z 64

/* vv_measure_isosurface_boxes by Marching Cubes, one box: @p v holds
 * voxels glo .. ghi of a volume of @p d voxels (its own hi, and a layer
 * beyond each upper inner face). Its cells' surface is closed by caps on
 * its faces, which cancel between neighbours, so that the volumes add up;
 * the caps on the volume's own faces are its cut. Adds to @p out the area,
 * volume, cut and triangles, and the inside voxels of the box's own. */
static vv_status
box_mc(const vv_volume *v, double iso, const int glo[3], const int hi[3], const int ghi[3],
       const int d[3], vv_isosurface_measure *out) {
    unsigned outer = 0;
    for (int a = 0; a < 3; a++)
        outer |= (glo[a] == 0 ? 1u : 0u) << (2 * a) | (ghi[a] == d[a] - 1 ? 1u : 0u) << (2 * a + 1);
    const int blo[3] = {0, 0, 0}, bhi[3] = {v->dims[0] - 1, v->dims[1] - 1, v->dims[2] - 1};
    vv_isosurface_measure m;
    memset(&m, 0, sizeof m);
    vv_status s = mc_measure(v, iso, blo, bhi, 0, NULL, outer, &m);
    if (s != VV_OK)
        return s;
    out->area += m.area;
    out->volume += m.volume;
    out->cut_area += m.cut_area;
    out->n_triangles += m.n_triangles;
    /* the voxels inside: the box's own (not the layer after it) */
    const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
    const int nk = hi[2] - glo[2] + 1, nj = hi[1] - glo[1] + 1, ni = hi[0] - glo[0] + 1;
    uint64_t cnt = 0;
#pragma omp parallel for num_threads(vv_threads_get()) reduction(+ : cnt)
    for (int k = 0; k < nk; k++)
        for (int j = 0; j < nj; j++)
            cnt += count_run(v, (size_t)k * sz + (size_t)j * sy, ni, iso);
    out->voxels += cnt;
    return VV_OK;
}

/* vv_measure_isosurface_boxes by voxel counting, one box: @p v holds
 * voxels glo .. of a volume of @p d voxels, its own lo .. hi and a ghost
 * layer beyond each inner face; adds its own voxels' counts and faces
 * to @p out. */
static vv_status
box_voxels(const vv_volume *v, double iso, const int lo[3], const int hi[3], const int glo[3],
           const int d[3], vv_isosurface_measure *out) {
    /* the box's own voxels, and the volume's extent, in the box's indices */
    region_box rb;
    memset(&rb, 0, sizeof rb);
    int olo[3], ohi[3];
    for (int a = 0; a < 3; a++) {
        rb.lo[a] = lo[a] - glo[a];
        rb.hi[a] = hi[a] - glo[a];
        olo[a] = -glo[a];
        ohi[a] = d[a] - 1 - glo[a];
    }
    voxel_measure(v, iso, &rb, olo, ohi, NULL, out);
    return VV_OK;
}

vv_status
vv_measure_isosurface_boxes(vv_isosurface_measure *out, const vv_volume *hdr, vv_box_reader read,
                            void *ctx, double isovalue, vv_measure_method method,
                            const vv_progress *progress) {
    if (!out || !hdr || !read)
        return vv_error_set(VV_ERR_INVALID, "measure: NULL argument");
    memset(out, 0, sizeof *out);
    if (!isfinite(isovalue) || !(isovalue > hdr->range[0]) || !(isovalue <= hdr->range[1]))
        return vv_error_set(VV_ERR_INVALID,
                            "measure: isovalue %g is outside the volume's range (%g, %g]: there "
                            "is no isosurface",
                            isovalue, hdr->range[0], hdr->range[1]);
    if (method != VV_MEASURE_MC && method != VV_MEASURE_VOXEL)
        return vv_error_set(VV_ERR_INVALID, "measure: unknown method %d", (int)method);
    const int mc = method == VV_MEASURE_MC;
    for (int a = 0; mc && a < 3; a++)
        if (hdr->dims[a] < 2)
            return vv_error_set(VV_ERR_INVALID,
                                "measure: Marching Cubes needs at least 2 voxels along %c",
                                "ijk"[a]);
    out->method = method;
    out->isovalue = isovalue;
    out->unit = hdr->unit;
    out->area_bias = mc ? 1 : 0;
    const int *d = hdr->dims, side[3] = {IB_X, IB_Y, IB_Z};
    int nb[3];
    for (int a = 0; a < 3; a++)
        nb[a] = (d[a] + side[a] - 1) / side[a];
    const long n = (long)nb[0] * nb[1] * nb[2];
    for (long b = 0; b < n; b++) {
        const int c[3] = {(int)(b % nb[0]), (int)(b / nb[0] % nb[1]),
                          (int)(b / ((long)nb[0] * nb[1]))};
        int lo[3], hi[3], glo[3], ghi[3], cells = 1;
        for (int a = 0; a < 3; a++) {
            lo[a] = c[a] * side[a];
            hi[a] = lo[a] + side[a] - 1 < d[a] - 1 ? lo[a] + side[a] - 1 : d[a] - 1;
            glo[a] = lo[a] > 0 && !mc ? lo[a] - 1 : lo[a];
            ghi[a] = hi[a] < d[a] - 1 ? hi[a] + 1 : hi[a];
            cells &= ghi[a] > glo[a];
        }
        if (mc && !cells) /* a last layer of one voxel: its cells are the box before's */
            continue;
        vv_volume *v = NULL;
        vv_status s = read(ctx, glo, ghi, &v);
        if (s != VV_OK)
            return vv_error_prefix(s, "measure");
        if (!v || v->dims[0] != ghi[0] - glo[0] + 1 || v->dims[1] != ghi[1] - glo[1] + 1 ||
            v->dims[2] != ghi[2] - glo[2] + 1) {
            vv_volume_free(v);
            return vv_error_set(VV_ERR_INVALID, "measure: the reader gave a box of another shape");
        }
        memcpy(v->spacing, hdr->spacing, sizeof v->spacing);
        memcpy(v->direction, hdr->direction, sizeof v->direction);
        s = mc ? box_mc(v, isovalue, glo, hi, ghi, d, out)
               : box_voxels(v, isovalue, lo, hi, glo, d, out);
        vv_volume_free(v);
        if (s != VV_OK)
            return vv_error_prefix(s, "measure");
        if (progress && vv_progress_report(progress, (double)(b + 1) / n))
            return vv_error_set(VV_ERR_CANCELLED, "measure: cancelled");
    }
    if (!mc)
        out->volume = (double)out->voxels * hdr->spacing[0] * hdr->spacing[1] * hdr->spacing[2];
    return VV_OK;
}

vv_status
vv_measure_isosurface(vv_isosurface_measure *out, const vv_volume *v, double isovalue,
                      const vv_isosurface_measure_options *opt) {
    if (!out || !v || !v->data)
        return vv_error_set(VV_ERR_INVALID, "measure: NULL argument");
    memset(out, 0, sizeof *out);
    vv_isosurface_measure_options defaults;
    if (!opt) {
        vv_isosurface_measure_options_init(&defaults);
        opt = &defaults;
    }
    if (!isfinite(isovalue) || !(isovalue > v->range[0]) || !(isovalue <= v->range[1]))
        return vv_error_set(VV_ERR_INVALID,
                            "measure: isovalue %g is outside the volume's range (%g, %g]: there "
                            "is no isosurface",
                            isovalue, v->range[0], v->range[1]);
    if (opt->method != VV_MEASURE_MC && opt->method != VV_MEASURE_VOXEL)
        return vv_error_set(VV_ERR_INVALID, "measure: unknown method %d", (int)opt->method);
    region_box rb;
    vv_status s = region_resolve(v, &opt->region, &rb);
    if (s != VV_OK)
        return vv_error_prefix(s, "measure");
    if (opt->method == VV_MEASURE_MC) {
        for (int a = 0; a < 3; a++)
            if (rb.hi[a] - rb.lo[a] < 1)
                return vv_error_set(VV_ERR_INVALID,
                                    "measure: Marching Cubes needs at least 2 voxels along %c",
                                    "ijk"[a]);
    }
    out->method = opt->method;
    out->isovalue = isovalue;
    out->unit = v->unit;
    const int threads = opt->threads > 0 ? opt->threads : vv_threads_get();
    if (!opt->has_seed) {
        if (opt->method == VV_MEASURE_VOXEL) {
            voxel_measure(v, isovalue, &rb, rb.lo, rb.hi, NULL, out);
            return VV_OK;
        }
        s = rb.n_planes ? mc_measure_cut(v, isovalue, rb.lo, rb.hi, rb.n_planes,
                                         opt->region.cut_planes, threads, &opt->progress, out)
                        : mc_measure(v, isovalue, rb.lo, rb.hi, threads, &opt->progress, 0x3f, out);
        if (s != VV_OK)
            return vv_error_prefix(s, "measure");
        /* voxel count for the report */
        uint64_t cnt = 0;
        const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
#pragma omp parallel for num_threads(threads) reduction(+ : cnt)
        for (int k = rb.lo[2]; k <= rb.hi[2]; k++)
            for (int j = rb.lo[1]; j <= rb.hi[1]; j++) {
                const size_t r0 = (size_t)k * sz + (size_t)j * sy;
                if (!rb.n_planes) {
                    cnt += count_run(v, r0 + (size_t)rb.lo[0], rb.hi[0] - rb.lo[0] + 1, isovalue);
                    continue;
                }
                for (int i = rb.lo[0]; i <= rb.hi[0]; i++)
                    cnt += region_keeps(&rb, i, j, k) && inside(v, r0 + (size_t)i, isovalue);
            }
        out->voxels = cnt;
        return VV_OK;
    }
    /* surface-tracked section */
    int sv[3];
    if ((s = find_seed(v, isovalue, &rb, opt->seed, sv)) != VV_OK)
        return vv_error_prefix(s, "measure");
    memcpy(out->seed_voxel, sv, sizeof sv);
    uint8_t *mask = calloc((size_t)vv_volume_voxel_count(v), 1);
    if (!mask)
        return vv_error_set(VV_ERR_NOMEM, "measure: out of memory for the section mask");
    uint64_t cnt = 0;
    int bmin[3], bmax[3];
    if ((s = flood_fill(v, isovalue, &rb, sv, mask, &cnt, bmin, bmax)) != VV_OK) {
        free(mask);
        return vv_error_prefix(s, "measure");
    }
    if (opt->method == VV_MEASURE_VOXEL) {
        voxel_measure(v, isovalue, &rb, rb.lo, rb.hi, mask, out);
        free(mask);
        return VV_OK;
    }
    vv_volume *w = NULL;
    s = masked_copy(v, isovalue, &rb, mask, bmin, bmax, threads, &w);
    free(mask);
    if (s != VV_OK)
        return vv_error_prefix(s, "measure");
    const int dims[3] = {w->dims[0], w->dims[1], w->dims[2]};
    const int wlo[3] = {0, 0, 0}, whi[3] = {dims[0] - 1, dims[1] - 1, dims[2] - 1};
    s = rb.n_planes ? mc_measure_cut(w, isovalue, wlo, whi, rb.n_planes, opt->region.cut_planes,
                                     threads, &opt->progress, out)
                    : mc_measure(w, isovalue, wlo, whi, threads, &opt->progress, 0x3f, out);
    vv_volume_free(w);
    if (s != VV_OK)
        return vv_error_prefix(s, "measure");
    out->voxels = cnt;
    return VV_OK;
}

vv_status
vv_measure_isosurface_mesh(vv_mesh **out, const vv_volume *v, double isovalue,
                           const vv_isosurface_measure_options *opt) {
    if (out)
        *out = NULL;
    if (!out || !v || !v->data)
        return vv_error_set(VV_ERR_INVALID, "measure: NULL argument");
    vv_isosurface_measure_options defaults;
    if (!opt) {
        vv_isosurface_measure_options_init(&defaults);
        opt = &defaults;
    }
    if (!isfinite(isovalue) || !(isovalue > v->range[0]) || !(isovalue <= v->range[1]))
        return vv_error_set(VV_ERR_INVALID,
                            "measure: isovalue %g is outside the volume's range (%g, %g]: there "
                            "is no isosurface",
                            isovalue, v->range[0], v->range[1]);
    region_box rb;
    vv_status s = region_resolve(v, &opt->region, &rb);
    if (s != VV_OK)
        return vv_error_prefix(s, "measure");
    const int threads = opt->threads > 0 ? opt->threads : vv_threads_get();
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.threads = threads;
    o.progress = opt->progress;
    o.n_cut_planes = opt->region.n_cut_planes;
    memcpy(o.cut_planes, opt->region.cut_planes, sizeof o.cut_planes);
    if (!opt->has_seed) {
        for (int a = 0; a < 3; a++) {
            o.roi_min[a] = rb.lo[a];
            o.roi_max[a] = rb.hi[a];
        }
        s = vv_isosurface_extract(out, v, isovalue, &o);
        return s == VV_OK ? VV_OK : vv_error_prefix(s, "measure");
    }
    int sv[3], bmin[3], bmax[3];
    uint64_t cnt;
    if ((s = find_seed(v, isovalue, &rb, opt->seed, sv)) != VV_OK)
        return vv_error_prefix(s, "measure");
    uint8_t *mask = calloc((size_t)vv_volume_voxel_count(v), 1);
    if (!mask)
        return vv_error_set(VV_ERR_NOMEM, "measure: out of memory for the section mask");
    vv_volume *w = NULL;
    if ((s = flood_fill(v, isovalue, &rb, sv, mask, &cnt, bmin, bmax)) == VV_OK)
        s = masked_copy(v, isovalue, &rb, mask, bmin, bmax, threads, &w);
    free(mask);
    if (s == VV_OK)
        s = vv_isosurface_extract(out, w, isovalue, &o);
    vv_volume_free(w);
    return s == VV_OK ? VV_OK : vv_error_prefix(s, "measure");
}

vv_status
vv_measure_distance(const vv_volume *v, vv_vec3 a, int a_voxel, vv_vec3 b, int b_voxel,
                    double *out) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "distance: NULL output");
    if ((a_voxel || b_voxel) && !v)
        return vv_error_set(VV_ERR_INVALID, "distance: voxel coordinates need a volume");
    if (!isfinite(a.x + a.y + a.z + b.x + b.y + b.z))
        return vv_error_set(VV_ERR_INVALID, "distance: coordinates are not finite");
    if (a_voxel || b_voxel) {
        vv_mat4 M = vv_volume_index_to_world(v);
        if (a_voxel)
            a = vv_mat4_mul_point(M, a);
        if (b_voxel)
            b = vv_mat4_mul_point(M, b);
    }
    *out = vv_vec3_length(vv_vec3_sub(a, b));
    return VV_OK;
}
