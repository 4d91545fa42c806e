/*
 * Volume-sampled voxelization of a model tree (Wang and Kaufman, IEEE
 * Visualization '93; VolVis paper, section 3, Modeling).
 *
 * The grid is walked in subvolumes of 4^3 voxels. For each subvolume every
 * node of the tree is classified as inside, outside or near its surface,
 * from a lower bound of the primitive's distance at the subvolume centre
 * (with the subvolume's half diagonal plus the kernel radius as margin) and
 * the CSG rules; a subvolume whose root is inside is filled, one outside is
 * skipped, and only the others are sampled voxel by voxel, evaluating the
 * primitives that are near there. A voxel's density from one primitive is
 * the kernel table at its signed distance; CSG combines densities with
 * max / min / min(a, 1 - b). Meshes are scan converted onto the grid first
 * (mesh_scan.c).
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "modeling_internal.h"

#define BRICK 4

enum { CLS_OUT = 0, CLS_IN = 1, CLS_MIXED = 2 };

typedef struct fnode {
    const vv_shape *s;
    int first, count; /* children, in the kids array */
    vv_mat4 inv;      /* world -> shape coordinates */
    double sigma;     /* world distance per shape-coordinate distance (lower bound) */
    vv_box wbox;      /* world bounds of the primitive */
    float *sd;        /* mesh: signed distance grid */
    unsigned char *bcls;
} fnode;

typedef struct vctx {
    fnode *nodes;
    int n_nodes, cap_nodes;
    int *kids;
    int n_kids, cap_kids;
    const vv_sampling_kernel_table *table;
    const float *tab;          /* table->density */
    double tab_scale, tab_off; /* entry = d_world * tab_scale + tab_off */
    int tab_last;
    double inv_h; /* voxels of the kernel table per world unit */
    double rw;    /* kernel radius, world units */
    int dims[3];
    double spacing[3], origin[3];
    int nb[3]; /* bricks per axis */
} vctx;

/* smallest singular value of the upper 3x3 of M (sqrt of the smallest
 * eigenvalue of A^T A, by the trigonometric formula) */
static double
sigma_min(vv_mat4 M) {
    double a[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0;
            for (int k = 0; k < 3; k++)
                s += M.m[k][i] * M.m[k][j];
            a[i][j] = s;
        }
    double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    double q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    double p2 = (a[0][0] - q) * (a[0][0] - q) + (a[1][1] - q) * (a[1][1] - q) +
                (a[2][2] - q) * (a[2][2] - q) + 2.0 * p1;
    double p = sqrt(p2 / 6.0);
    if (!(p > 1e-300 * (q > 0 ? q : 1)))
        return sqrt(q > 0 ? q : 0);
    double b[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            b[i][j] = (a[i][j] - (i == j ? q : 0)) / p;
    double det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                 b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                 b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    double r = det / 2.0;
    double phi = r <= -1 ? VV_PI / 3.0 : (r >= 1 ? 0.0 : acos(r) / 3.0);
    double emin = q + 2.0 * p * cos(phi + 2.0 * VV_PI / 3.0);
    return sqrt(emin > 0 ? emin : 0);
}

/* Deepest tree voxelized (bounds and evaluation recurse once per level). */
#define MAX_DEPTH 1000

/* The depth of a tree, without recursion (a hostile tree may be deep);
 * -1 when out of memory. */
static int
tree_depth(const vv_shape *root) {
    typedef struct item {
        const vv_shape *s;
        int depth;
    } item;
    size_t n = 0, cap = 64;
    item *st = malloc(cap * sizeof *st);
    if (!st)
        return -1;
    st[n++] = (item){root, 0};
    int deepest = 0;
    while (n) {
        item it = st[--n];
        if (it.depth > deepest)
            deepest = it.depth;
        if (it.depth > MAX_DEPTH)
            break;
        for (int i = 0; i < it.s->n_children; i++) {
            if (n == cap) {
                item *g = realloc(st, 2 * cap * sizeof *st);
                if (!g) {
                    free(st);
                    return -1;
                }
                st = g;
                cap *= 2;
            }
            st[n++] = (item){it.s->children[i], it.depth + 1};
        }
    }
    free(st);
    return deepest;
}

static vv_status
flatten(vctx *c, const vv_shape *s, vv_mat4 parent, int *index, int depth) {
    if (depth > MAX_DEPTH)
        return vv_error_set(VV_ERR_LIMIT, "voxelize: the model tree is deeper than %d levels",
                            MAX_DEPTH);
    if (c->n_nodes == c->cap_nodes) {
        int cap = c->cap_nodes ? 2 * c->cap_nodes : 16;
        fnode *n = realloc(c->nodes, (size_t)cap * sizeof *n);
        if (!n)
            return vv_error_set(VV_ERR_NOMEM, "voxelize: out of memory");
        c->nodes = n;
        c->cap_nodes = cap;
    }
    int me = c->n_nodes++;
    *index = me;
    fnode *f = &c->nodes[me];
    memset(f, 0, sizeof *f);
    f->s = s;
    vv_mat4 W = vv_mat4_mul(parent, vv_mat4_mul(s->M, s->frame));
    if (s->kind != SHAPE_CSG) {
        int ok;
        f->inv = vv_mat4_inverse(W, &ok);
        f->sigma = sigma_min(W);
        if (!ok || !(f->sigma > 0) || !isfinite(f->sigma))
            return vv_error_set(VV_ERR_INVALID, "voxelize: %s: the transform is not invertible",
                                s->name);
        f->wbox = vv_box_transform(vv_shape_local_box(s), W);
        f->inv = s->kind == SHAPE_MESH ? W : f->inv; /* meshes keep to-world */
        return VV_OK;
    }
    vv_mat4 Wc = vv_mat4_mul(parent, s->M);
    int first = c->n_kids;
    if (c->n_kids + s->n_children > c->cap_kids) {
        int cap = 2 * (c->n_kids + s->n_children) + 16;
        int *k = realloc(c->kids, (size_t)cap * sizeof *k);
        if (!k)
            return vv_error_set(VV_ERR_NOMEM, "voxelize: out of memory");
        c->kids = k;
        c->cap_kids = cap;
    }
    c->n_kids += s->n_children;
    c->nodes[me].first = first;
    c->nodes[me].count = s->n_children;
    for (int i = 0; i < s->n_children; i++) {
        int ci = 0;
        vv_status st = flatten(c, s->children[i], Wc, &ci, depth + 1);
        if (st != VV_OK)
            return st;
        c->kids[first + i] = ci;
    }
    return VV_OK;
}

static inline vv_vec3
affine(const vv_mat4 *M, vv_vec3 p) {
    return (vv_vec3){M->m[0][0] * p.x + M->m[0][1] * p.y + M->m[0][2] * p.z + M->m[0][3],
                     M->m[1][0] * p.x + M->m[1][1] * p.y + M->m[1][2] * p.z + M->m[1][3],
                     M->m[2][0] * p.x + M->m[2][1] * p.y + M->m[2][2] * p.z + M->m[2][3]};
}

static int
classify(const vctx *c, int idx, const double lo[3], const double hi[3], vv_vec3 centre, double hd,
         const int bijk[3], unsigned char *cls) {
    const fnode *f = &c->nodes[idx];
    const vv_shape *s = f->s;
    int r;
    if (s->kind == SHAPE_MESH) {
        r = f->bcls[((size_t)bijk[2] * c->nb[1] + bijk[1]) * c->nb[0] + bijk[0]];
    } else if (s->kind != SHAPE_CSG) {
        double m = c->rw;
        if (lo[0] > f->wbox.max.x + m || hi[0] < f->wbox.min.x - m || lo[1] > f->wbox.max.y + m ||
            hi[1] < f->wbox.min.y - m || lo[2] > f->wbox.max.z + m || hi[2] < f->wbox.min.z - m) {
            r = CLS_OUT;
        } else {
            double b = f->sigma * vv_shape_sdf_bound(s, affine(&f->inv, centre));
            r = b > hd + m ? CLS_OUT : (b < -(hd + m) ? CLS_IN : CLS_MIXED);
        }
    } else {
        int n_in = 0, n_out = 0, first = CLS_MIXED;
        for (int i = 0; i < f->count; i++) {
            int k = classify(c, c->kids[f->first + i], lo, hi, centre, hd, bijk, cls);
            if (i == 0)
                first = k;
            n_in += k == CLS_IN;
            n_out += k == CLS_OUT;
        }
        if (s->op == VV_CSG_UNION)
            r = n_in ? CLS_IN : (n_out == f->count ? CLS_OUT : CLS_MIXED);
        else if (s->op == VV_CSG_INTERSECTION)
            r = n_out ? CLS_OUT : (n_in == f->count ? CLS_IN : CLS_MIXED);
        else {
            int rest_in = n_in - (first == CLS_IN), rest_out = n_out - (first == CLS_OUT);
            if (first == CLS_OUT || rest_in > 0)
                r = CLS_OUT;
            else if (first == CLS_IN && rest_out == f->count - 1)
                r = CLS_IN;
            else
                r = CLS_MIXED;
        }
    }
    cls[idx] = (unsigned char)r;
    return r;
}

/* the kernel table at signed world distance d (vv_sampling_kernel_table_eval, inlined) */
static inline double
table_at(const vctx *c, double d) {
    double x = d * c->tab_scale + c->tab_off;
    if (!(x > 0.0))
        return 1.0;
    if (x >= c->tab_last)
        return 0.0;
    int i = (int)x;
    double f = x - i;
    return c->tab[i] + f * (c->tab[i + 1] - c->tab[i]);
}

static double
density(const vctx *c, int idx, vv_vec3 p, size_t voxel, const unsigned char *cls) {
    if (cls[idx] != CLS_MIXED)
        return cls[idx] == CLS_IN ? 1.0 : 0.0;
    const fnode *f = &c->nodes[idx];
    const vv_shape *s = f->s;
    if (s->kind == SHAPE_MESH)
        return table_at(c, f->sd[voxel]);
    if (s->kind != SHAPE_CSG)
        return table_at(c, f->sigma * vv_shape_sdf(s, affine(&f->inv, p)));
    const int *k = c->kids + f->first;
    double v = density(c, k[0], p, voxel, cls);
    for (int i = 1; i < f->count; i++) {
        if (s->op == VV_CSG_UNION) {
            if (v >= 1.0)
                break;
            v = fmax(v, density(c, k[i], p, voxel, cls));
        } else if (s->op == VV_CSG_INTERSECTION) {
            if (v <= 0.0)
                break;
            v = fmin(v, density(c, k[i], p, voxel, cls));
        } else {
            if (v <= 0.0)
                break;
            v = fmin(v, 1.0 - density(c, k[i], p, voxel, cls));
        }
    }
    return v;
}

void
vv_voxelize_options_init(vv_voxelize_options *o) {
    memset(o, 0, sizeof *o);
    o->kernel = VV_SAMPLING_KERNEL_TENT;
    o->radius = 1.5;
    o->type = VV_U8;
    o->size = 128;
    o->margin = -1.0;
}

static int
box_empty(vv_box b) {
    return !(b.min.x <= b.max.x && b.min.y <= b.max.y && b.min.z <= b.max.z);
}

/* The output grid from the options and the model's bounds. */
static vv_status
make_grid(vctx *c, const vv_shape *shape, const vv_voxelize_options *o) {
    if (o->dims[0] > 0) {
        for (int a = 0; a < 3; a++) {
            if (o->dims[a] < 1 || o->dims[a] > VV_VOLUME_MAX_DIM)
                return vv_error_set(VV_ERR_LIMIT,
                                    "voxelize: %d voxels along axis %d is outside [1, %d]",
                                    o->dims[a], a, VV_VOLUME_MAX_DIM);
            if (!(o->spacing[a] > 0) || !isfinite(o->spacing[a]) || !isfinite(o->origin[a]))
                return vv_error_set(VV_ERR_INVALID,
                                    "voxelize: voxel spacing %g along axis %d must be > 0",
                                    o->spacing[a], a);
            c->dims[a] = o->dims[a];
            c->spacing[a] = o->spacing[a];
            c->origin[a] = o->origin[a];
        }
        return VV_OK;
    }
    vv_box b = vv_shape_bounds(shape);
    if (box_empty(b))
        return vv_error_set(VV_ERR_INVALID, "voxelize: the model is empty (no bounded solid)");
    double lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
    double ext = 0;
    for (int a = 0; a < 3; a++) {
        if (!isfinite(lo[a]) || !isfinite(hi[a]))
            return vv_error_set(VV_ERR_INVALID, "voxelize: the model's bounds are not finite");
        ext = fmax(ext, hi[a] - lo[a]);
    }
    double margin = o->margin >= 0 ? o->margin : o->radius + 1.0;
    if (!isfinite(margin) || margin > 1e6)
        return vv_error_set(VV_ERR_INVALID, "voxelize: margin %g voxels is not reasonable", margin);
    int m = (int)ceil(margin);
    double h;
    if (o->voxel_spacing > 0) {
        if (!isfinite(o->voxel_spacing))
            return vv_error_set(VV_ERR_INVALID, "voxelize: voxel spacing is not finite");
        h = o->voxel_spacing;
        if (ext / h + 1.0 + 2.0 * m > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT,
                                "voxelize: voxel spacing %g gives %.0f voxels along the longest "
                                "axis, over the limit of %d",
                                h, ext / h + 1.0 + 2.0 * m, VV_VOLUME_MAX_DIM);
    } else {
        if (o->size > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT,
                                "voxelize: resolution %d voxels per axis is over the limit of %d",
                                o->size, VV_VOLUME_MAX_DIM);
        if (o->size - 2 * m < 2)
            return vv_error_set(VV_ERR_INVALID,
                                "voxelize: resolution %d voxels leaves no room inside the "
                                "margin of %d voxels on each side",
                                o->size, m);
        h = ext > 0 ? ext / (o->size - 1 - 2 * m) : 1.0;
    }
    for (int a = 0; a < 3; a++) {
        double n = ceil((hi[a] - lo[a]) / h - 1e-9) + 1.0 + 2.0 * m;
        if (n > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT, "voxelize: %.0f voxels along axis %d", n, a);
        c->dims[a] = (int)n;
        c->spacing[a] = h;
        c->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * (n - 1) * h;
    }
    return VV_OK;
}

/* Kept whole: the grid set-up, the meshes' scan conversion, the brick
 * classification and the parallel brick loop with its progress share the
 * classified bricks and one cleanup. */
vv_status
vv_voxelize(vv_volume **out, const vv_shape *shape, const vv_voxelize_options *opt) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "voxelize: NULL output");
    *out = NULL;
    if (!shape)
        return vv_error_set(VV_ERR_INVALID, "voxelize: no model");
    vv_voxelize_options def;
    if (!opt) {
        vv_voxelize_options_init(&def);
        opt = &def;
    }
    if (opt->type != VV_U8 && opt->type != VV_F32)
        return vv_error_set(VV_ERR_INVALID, "voxelize: voxel type %s; expected u8 or f32",
                            vv_voxel_type_name(opt->type));
    vctx c;
    memset(&c, 0, sizeof c);
    double vmin_all = 1.0, vmax_all = 0.0;
    vv_sampling_kernel_table *table = NULL;
    vv_volume *vol = NULL;
    vv_status st = vv_sampling_kernel_table_new(&table, opt->kernel, opt->radius, 0);
    if (st != VV_OK)
        return vv_error_prefix(st, "voxelize");
    c.table = table;
    int depth = tree_depth(shape);
    if (depth < 0 || depth > MAX_DEPTH) {
        vv_sampling_kernel_table_free(table);
        return depth < 0
                   ? vv_error_set(VV_ERR_NOMEM, "voxelize: out of memory")
                   : vv_error_set(VV_ERR_LIMIT, "voxelize: the model tree is deeper than %d levels",
                                  MAX_DEPTH);
    }
    int threads = opt->threads > 0 ? opt->threads : vv_threads_get();
    int root;
    if ((st = make_grid(&c, shape, opt)) != VV_OK ||
        (st = flatten(&c, shape, vv_mat4_identity(), &root, 0)) != VV_OK)
        goto done;
    if ((st = vv_volume_new(&vol, c.dims, opt->type)) != VV_OK) {
        vv_error_prefix(st, "voxelize");
        goto done;
    }
    double h = fmax(c.spacing[0], fmax(c.spacing[1], c.spacing[2]));
    c.inv_h = 1.0 / h;
    c.rw = opt->radius * h;
    c.tab = table->density;
    c.tab_last = table->n - 1;
    c.tab_scale = 0.5 * (table->n - 1) / c.rw;
    c.tab_off = 0.5 * (table->n - 1);
    for (int a = 0; a < 3; a++) {
        vol->spacing[a] = c.spacing[a];
        vol->origin[a] = c.origin[a];
        c.nb[a] = (c.dims[a] + BRICK - 1) / BRICK;
    }
    vol->data_origin = VV_ORIGIN_FUZZY_VOXELIZED;
    vol->modification = VV_MOD_ORIGINAL;
    size_t nvox = (size_t)c.dims[0] * c.dims[1] * c.dims[2];
    size_t nbricks = (size_t)c.nb[0] * c.nb[1] * c.nb[2];

    /* meshes first: scan conversion onto the grid, then brick classes */
    int n_mesh = 0, done_mesh = 0;
    for (int i = 0; i < c.n_nodes; i++)
        n_mesh += c.nodes[i].s->kind == SHAPE_MESH;
    double mesh_share = n_mesh ? 0.5 : 0.0;
    for (int i = 0; i < c.n_nodes && st == VV_OK; i++) {
        fnode *f = &c.nodes[i];
        if (f->s->kind != SHAPE_MESH)
            continue;
        f->sd = malloc(nvox * sizeof *f->sd);
        f->bcls = malloc(nbricks);
        if (!f->sd || !f->bcls) {
            st = vv_error_set(VV_ERR_NOMEM, "voxelize: out of memory for a mesh distance grid");
            break;
        }
        int solid = f->s->mesh_mode == VV_MESH_SOLID;
        double th = f->s->thickness > 0 ? f->s->thickness : 2.0 * h;
        if (c.n_nodes == 1) {
            /* a lone mesh: densities straight from the distance grid, no
             * subvolume classes needed */
            st = vv_mesh_scan(f->s->mesh, f->inv, solid, th, c.dims, c.spacing, c.origin, c.rw,
                              f->sd, threads);
            if (st != VV_OK)
                break;
            unsigned char *o8 = opt->type == VV_U8 ? vol->data : NULL;
            float *o32 = opt->type == VV_F32 ? vol->data : NULL;
            double lo = 1.0, hi = 0.0;
// clang-format off
#pragma omp parallel for schedule(dynamic, 32768) num_threads(threads) \
    reduction(min : lo) reduction(max : hi)
            // clang-format on
            for (long long v = 0; v < (long long)nvox; v++) {
                double d = table_at(&c, f->sd[v]);
                lo = d < lo ? d : lo;
                hi = d > hi ? d : hi;
                if (o8)
                    o8[v] = (unsigned char)(d * 255.0 + 0.5);
                else
                    o32[v] = (float)d;
            }
            vmin_all = lo;
            vmax_all = hi;
            if (vv_progress_report(&opt->progress, 1.0))
                st = vv_error_set(VV_ERR_CANCELLED, "voxelize: cancelled");
            goto done;
        }
        st = vv_mesh_scan(f->s->mesh, f->inv, solid, th, c.dims, c.spacing, c.origin, c.rw, f->sd,
                          threads);
        if (st != VV_OK)
            break;
        float rw = (float)c.rw;
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
        for (long long bb = 0; bb < (long long)nbricks; bb++) {
            int bi = (int)(bb % c.nb[0]), bj = (int)((bb / c.nb[0]) % c.nb[1]),
                bk = (int)(bb / ((long long)c.nb[0] * c.nb[1]));
            int any_in = 0, any_out = 0, mixed = 0;
            for (int k = bk * BRICK; k < c.dims[2] && k < (bk + 1) * BRICK && !mixed; k++)
                for (int j = bj * BRICK; j < c.dims[1] && j < (bj + 1) * BRICK && !mixed; j++)
                    for (int ii = bi * BRICK; ii < c.dims[0] && ii < (bi + 1) * BRICK; ii++) {
                        float d = f->sd[((size_t)k * c.dims[1] + j) * c.dims[0] + ii];
                        if (d <= -rw)
                            any_in = 1;
                        else if (d >= rw)
                            any_out = 1;
                        else {
                            mixed = 1;
                            break;
                        }
                    }
            f->bcls[bb] =
                (unsigned char)(mixed || (any_in && any_out) ? CLS_MIXED
                                                             : (any_in ? CLS_IN : CLS_OUT));
        }
        done_mesh++;
        if (vv_progress_report(&opt->progress, mesh_share * done_mesh / n_mesh))
            st = vv_error_set(VV_ERR_CANCELLED, "voxelize: cancelled");
    }
    if (st != VV_OK)
        goto done;

    /* the bricks, in parallel; thread 0 reports progress */
    {
        const double hd = 0.5 * (BRICK - 1) *
                          sqrt(c.spacing[0] * c.spacing[0] + c.spacing[1] * c.spacing[1] +
                               c.spacing[2] * c.spacing[2]);
        long long nb = (long long)nbricks, done_b = 0;
        int cancelled = 0;
        double vmin = 1.0, vmax = 0.0;
        int nn = c.n_nodes;
        unsigned char *vox8 = opt->type == VV_U8 ? vol->data : NULL;
        float *vox32 = opt->type == VV_F32 ? vol->data : NULL;
#pragma omp parallel num_threads(threads) reduction(min : vmin) reduction(max : vmax)
        {
            unsigned char *cls = malloc((size_t)nn);
#pragma omp for schedule(dynamic, 4)
            for (long long bb = 0; bb < nb; bb++) {
                int stop;
#pragma omp atomic read
                stop = cancelled;
                if (stop || !cls)
                    continue;
                int bijk[3] = {(int)(bb % c.nb[0]), (int)((bb / c.nb[0]) % c.nb[1]),
                               (int)(bb / ((long long)c.nb[0] * c.nb[1]))};
                int i0[3], i1[3];
                double lo[3], hi[3];
                for (int a = 0; a < 3; a++) {
                    i0[a] = bijk[a] * BRICK;
                    i1[a] = i0[a] + BRICK < c.dims[a] ? i0[a] + BRICK : c.dims[a];
                    lo[a] = c.origin[a] + i0[a] * c.spacing[a];
                    hi[a] = c.origin[a] + (i0[a] + BRICK - 1) * c.spacing[a];
                }
                vv_vec3 centre = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]),
                                  0.5 * (lo[2] + hi[2])};
                int r = classify(&c, root, lo, hi, centre, hd, bijk, cls);
                if (r == CLS_OUT)
                    vmin = 0.0;
                else if (r == CLS_IN)
                    vmax = 1.0;
                if (r != CLS_OUT) {
                    for (int k = i0[2]; k < i1[2]; k++)
                        for (int j = i0[1]; j < i1[1]; j++) {
                            size_t row = ((size_t)k * c.dims[1] + j) * c.dims[0];
                            for (int i = i0[0]; i < i1[0]; i++) {
                                double d = 1.0;
                                if (r == CLS_MIXED) {
                                    vv_vec3 p = {c.origin[0] + i * c.spacing[0],
                                                 c.origin[1] + j * c.spacing[1],
                                                 c.origin[2] + k * c.spacing[2]};
                                    d = density(&c, root, p, row + i, cls);
                                    vmin = d < vmin ? d : vmin;
                                    vmax = d > vmax ? d : vmax;
                                }
                                if (vox8)
                                    vox8[row + i] = (unsigned char)(d * 255.0 + 0.5);
                                else
                                    vox32[row + i] = (float)d;
                            }
                        }
                }
                long long now;
#pragma omp atomic capture
                now = ++done_b;
                if (omp_get_thread_num() == 0 && (now & 255) == 0) {
                    if (vv_progress_report(&opt->progress,
                                           mesh_share + (1 - mesh_share) * (double)now / nb)) {
#pragma omp atomic write
                        cancelled = 1;
                    }
                }
            }
            if (!cls) {
#pragma omp atomic write
                cancelled = 2;
            }
            free(cls);
        }
        vmin_all = vmin;
        vmax_all = vmax;
        if (cancelled == 2)
            st = vv_error_set(VV_ERR_NOMEM, "voxelize: out of memory");
        else if (cancelled)
            st = vv_error_set(VV_ERR_CANCELLED, "voxelize: cancelled");
        else if (vv_progress_report(&opt->progress, 1.0))
            st = vv_error_set(VV_ERR_CANCELLED, "voxelize: cancelled");
    }
done:
    for (int i = 0; i < c.n_nodes; i++) {
        free(c.nodes[i].sd);
        free(c.nodes[i].bcls);
    }
    free(c.nodes);
    free(c.kids);
    vv_sampling_kernel_table_free(table);
    if (st != VV_OK) {
        vv_volume_free(vol);
        return st;
    }
    /* the range from the densities written (the skipped bricks are 0) */
    if (vmin_all > vmax_all)
        vmin_all = vmax_all = 0.0;
    vol->range[0] = opt->type == VV_U8 ? floor(vmin_all * 255.0 + 0.5) : (float)vmin_all;
    vol->range[1] = opt->type == VV_U8 ? floor(vmax_all * 255.0 + 0.5) : (float)vmax_all;
    vol->modified++;
    *out = vol;
    return VV_OK;
}
