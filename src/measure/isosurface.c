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
#include <stdlib.h>
#include <string.h>

#include "measure_internal.h"
#include "surface/surface_internal.h"

void
vv_isosurface_measure_options_init(vv_isosurface_measure_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    o->method = VV_MEASURE_MC;
    vv_region_init(&o->region);
}

/* Voxel i (linear index) as double. */
static inline double
get(const vv_volume *v, size_t i) {
    switch (v->type) {
    case VV_U8:
        return ((const uint8_t *)v->data)[i];
    case VV_I8:
        return ((const int8_t *)v->data)[i];
    case VV_U16:
        return ((const uint16_t *)v->data)[i];
    case VV_I16:
        return ((const int16_t *)v->data)[i];
    case VV_U32:
        return ((const uint32_t *)v->data)[i];
    case VV_I32:
        return ((const int32_t *)v->data)[i];
    case VV_F32:
        return ((const float *)v->data)[i];
    default:
        return ((const double *)v->data)[i];
    }
}

static inline int
inside(const vv_volume *v, size_t i, double iso) {
    return get(v, i) >= iso;
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

/* Voxel counting over the region (mask NULL) or the section (mask set). */
static void
voxel_measure(const vv_volume *v, double iso, const region_box *rb, const uint8_t *mask,
              vv_isosurface_measure *m) {
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
                        if (q[a] < rb->lo[a] || q[a] > rb->hi[a]) {
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
    m->voxels = count;
    m->volume = (double)count * v->spacing[0] * v->spacing[1] * v->spacing[2];
    m->area = area;
    m->cut_area = cut;
    m->area_bias = 1.5;
}

/* Marching Cubes area and capped divergence volume of volume w over its box lo..hi. */
static vv_status
mc_measure(const vv_volume *w, double iso, const int lo[3], const int hi[3], int threads,
           const vv_progress *progress, vv_isosurface_measure *m) {
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
    double vol = 0;
#pragma omp parallel for num_threads(threads > 0 ? threads : vv_threads_get())                  \
    schedule(static) reduction(+ : vol)
    for (long t = 0; t < (long)mesh->n_triangles; t++) {
        const uint32_t *tr = mesh->triangles + 3 * t;
        vv_vec3 p0 = vv_vec3_sub(vv_mesh_vertex(mesh, tr[0]), c),
                p1 = vv_vec3_sub(vv_mesh_vertex(mesh, tr[1]), c),
                p2 = vv_vec3_sub(vv_mesh_vertex(mesh, tr[2]), c);
        vol += vv_vec3_dot(p0, vv_vec3_cross(p1, p2));
    }
    vol /= 6;
    m->area = vv_mesh_area(mesh);
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
            cut += A;
        }
    }
    m->volume = vol;
    m->cut_area = cut;
    m->area_bias = 1;
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
        if (rb.n_planes)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "measure: cut planes are supported by voxel counting only (the "
                                "Marching Cubes volume closes the surface on box faces)");
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
            voxel_measure(v, isovalue, &rb, NULL, out);
            return VV_OK;
        }
        s = mc_measure(v, isovalue, rb.lo, rb.hi, threads, &opt->progress, out);
        if (s != VV_OK)
            return vv_error_prefix(s, "measure");
        /* voxel count for the report */
        uint64_t cnt = 0;
        const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
#pragma omp parallel for num_threads(threads) reduction(+ : cnt)
        for (int k = rb.lo[2]; k <= rb.hi[2]; k++)
            for (int j = rb.lo[1]; j <= rb.hi[1]; j++)
                for (int i = rb.lo[0]; i <= rb.hi[0]; i++)
                    cnt += inside(v, (size_t)k * sz + (size_t)j * sy + (size_t)i, isovalue);
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
        voxel_measure(v, isovalue, &rb, mask, out);
        free(mask);
        return VV_OK;
    }
    /* copy of the section's box plus one voxel, other components lowered below the isovalue */
    int lo[3], hi[3], dims[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = bmin[a] - 1 < rb.lo[a] ? rb.lo[a] : bmin[a] - 1;
        hi[a] = bmax[a] + 1 > rb.hi[a] ? rb.hi[a] : bmax[a] + 1;
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
    if ((s = vv_volume_new(&w, dims, exact_float ? VV_F32 : VV_F64)) != VV_OK) {
        free(mask);
        return vv_error_prefix(s, "measure");
    }
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
                double x = get(v, src);
                int own = mask[src];
                size_t q = ((size_t)k * (size_t)dims[1] + (size_t)j) * (size_t)dims[0] + (size_t)i;
                if (exact_float)
                    ((float *)w->data)[q] = !own && x >= isovalue ? below_f : (float)x;
                else
                    ((double *)w->data)[q] = !own && x >= isovalue ? below_d : x;
            }
    free(mask);
    vv_volume_update_range(w);
    const int wlo[3] = {0, 0, 0}, whi[3] = {dims[0] - 1, dims[1] - 1, dims[2] - 1};
    s = mc_measure(w, isovalue, wlo, whi, threads, &opt->progress, out);
    vv_volume_free(w);
    if (s != VV_OK)
        return vv_error_prefix(s, "measure");
    out->voxels = cnt;
    return VV_OK;
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
