/*
 * Sort-last distributed volume rendering over MPI (include/volvis/parallel.h).
 *
 * Decomposition. The rank count n is written as a product of round sizes
 * k_0 k_1 ... k_{m-1} (binary swap: 2 x 2 x ... over the largest power of
 * two R <= n, the n - R extra ranks folded into ranks 0 .. n - R - 1 first;
 * radix-k: factors <= the radix, a prime count being its own factor). A core
 * rank c has the mixed-radix digits d_j of c. The volume's box is cut
 * top-down, one level per digit from d_{m-1} to d_0 (and a last cut in two
 * for the ranks with an extra partner), each level into k_j slabs along the
 * longest axis that can take them, at multiples of 16 voxels, in proportion
 * to the ranks below each slab. Round j of compositing then joins the k_j
 * ranks that differ only in d_j: siblings of one node of that tree, whose
 * slabs have one visibility order for every pixel (the slab holding the
 * eye first, then outward; orthographic: along the view direction).
 *
 * Compositing. Every core rank starts with the whole image and a pixel
 * range [a, b) = [0, P). In round j the range is cut into k_j pieces; the
 * rank with digit d keeps piece d, sends piece c to the group member with
 * digit c and receives piece d from each of them, and composites the k_j
 * pieces in the node's visibility order (Porter-Duff over of premultiplied
 * colour; for projections the extreme value; for isosurfaces the nearest).
 * For k = 2 throughout this is binary swap; radix-k with k = n is direct
 * send. After the last round each core rank holds 1/R of the image,
 * gathered to rank 0.
 *
 * Bricks. A rank keeps the voxels of its box and one ghost voxel beyond each
 * face (gradients by central differences and trilinear samples at the box
 * faces then read the same voxels as in the whole volume; iso two, for a
 * crossing up to a step before the box, VV_REGION_NEAREST), as a volume with
 * the whole volume's geometry and value range
 * (a region's voxels, include/volvis/sys/renderer.h), cut from the World's volume or read
 * from the object's source (a bricked file, a pyramid's level: only the box
 * is read).
 */
#include <math.h>
#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/internal.h"
#include "volvis/io.h"
#include "volvis/parallel.h"
#include "volvis/sys/renderer.h"

#define PAR_ALIGN 16 /* brick faces: multiples of this many voxels */
#define PAR_MAX_LEVELS 40
#define PAR_MAX_K 4096 /* largest group of one round (a prime rank count) */
#define PAR_REC 6      /* floats per pixel in messages: r, g, b, a, depth, key */

struct vv_parallel {
    vv_parallel_options opt;
    vv_renderer *ren;
    int owns_ren;
    int rank, size;
    /* the brick kept between frames */
    /* read bricks from the object's source (vv_object_new_source), or NULL */
    vv_source *source;
    int level;      /* the source's level read */
    vv_volume hdr;  /* the level's geometry (its voxels never read); range once learnt */
    int range_done; /* the source's value range is known (agreed over the ranks) */
    const void *src;
    uint64_t src_modified;
    vv_volume *brick;
    /* a multi-channel object: every channel's brick over the same box
     * (cbrick[0] is brick), nb of them; an object of one channel: nb 1 */
    vv_volume *cbrick[VV_MAX_CHANNELS];
    int nb;
    vv_render_region rg; /* the region the brick is (voxels, rectangle: set per frame) */
    int box_lo[3], box_hi[3];
    int ghost; /* the brick's voxels beyond each face of the box: 1, iso 2 */
};

/* One cut of the decomposition tree on a rank's path. */
typedef struct par_level {
    int k;           /* children */
    int n_nodes;     /* k - 1 cuts in two, preorder (cut_tree) */
    int *axis, *pos; /* per cut: the index axis and the voxel index of the plane */
} par_level;

/* The decomposition as seen by one rank. */
typedef struct par_plan {
    int n, R, extras, m;
    int k[PAR_MAX_LEVELS];
    int is_extra;                      /* this rank is an extra (binary swap fold) */
    int core;                          /* its core rank (itself, or the one it folds into) */
    par_level lev[PAR_MAX_LEVELS + 1]; /* per digit j; lev[m]: the fold cut */
    int has_fold;
    int lo[3], hi[3]; /* this rank's box, voxel indices inclusive */
} par_plan;

static int g_started; /* MPI_Init was ours (set once, on the main thread) */

int
vv_parallel_available(void) {
    return 1;
}

int
vv_parallel_launched(void) {
    return getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMI_SIZE") || getenv("PMIX_RANK");
}

vv_status
vv_parallel_init(int *argc, char ***argv, int *rank, int *size) {
    int inited = 0;
    MPI_Initialized(&inited);
    if (!inited) {
        /* A rank never opens an X display. Open MPI's hwloc looks for GPUs
         * on the X servers :0 to :9 (its "gl" component), whatever DISPLAY
         * says, in every process that discovers the topology itself: a
         * singleton (MPI_Init without mpirun) and the orted it forks,
         * which inherits this environment. A display that dies during the
         * probe (another program's Xvfb) ends the process with "XIO: fatal
         * IO error". Under mpirun the ranks adopt the launcher's topology
         * and probe nothing: the launcher's environment must say it there
         * (docs/parallel.md). A user's own HWLOC_COMPONENTS is kept. Set
         * on the main thread, before MPI starts threads that read the
         * environment. */
        setenv("HWLOC_COMPONENTS", "-gl", 0);
        int provided = 0;
        if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
            return vv_error_set(VV_ERR_IO, "MPI_Init_thread failed");
        g_started = 1;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
    return VV_OK;
}

void
vv_parallel_finalize(void) {
    int fin = 0;
    MPI_Finalized(&fin);
    if (g_started && !fin)
        MPI_Finalize();
    g_started = 0;
}

vv_status
vv_parallel_agree(vv_status s) {
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    int mine = s != VV_OK ? rank : size, first = size;
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first == size)
        return VV_OK;
    struct {
        int code;
        char msg[1000];
    } m;
    memset(&m, 0, sizeof m);
    if (rank == first) {
        m.code = (int)s;
        snprintf(m.msg, sizeof m.msg, "%s", vv_error_message());
    }
    MPI_Bcast(&m, (int)sizeof m, MPI_BYTE, first, MPI_COMM_WORLD);
    vv_error_clear();
    return vv_error_set((vv_status)m.code, "rank %d: %s", first, m.msg);
}

vv_status
vv_parallel_check_same(const void *data, size_t n, const char *what) {
    uint64_t h = 1469598103934665603ull;
    const unsigned char *b = data;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= 1099511628211ull;
    }
    uint64_t h0 = h;
    MPI_Bcast(&h0, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    int bad = h0 != h, any = 0;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (any)
        return vv_error_set(VV_ERR_INVALID,
                            "ranks disagree on %s (its hash differs from rank 0's on %d rank%s)",
                            what, any, any == 1 ? "" : "s");
    return VV_OK;
}

vv_status
vv_parallel_broadcast(void *data, size_t n) {
    if (n > (size_t)0x7fffffff)
        return vv_error_set(VV_ERR_LIMIT, "parallel: broadcast of %zu bytes", n);
    int rc = MPI_Bcast(data, (int)n, MPI_BYTE, 0, MPI_COMM_WORLD);
    return rc == MPI_SUCCESS ? VV_OK : vv_error_set(VV_ERR_IO, "parallel: MPI_Bcast failed");
}

vv_status
vv_parallel_max(const double *value, double *out) {
    double in = *value, r = in;
    int rc = MPI_Reduce(&in, &r, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    if (rc != MPI_SUCCESS)
        return vv_error_set(VV_ERR_IO, "parallel: MPI_Reduce failed");
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0)
        *out = r;
    return VV_OK;
}

void
vv_parallel_options_init(vv_parallel_options *o) {
    memset(o, 0, sizeof *o);
    o->method = VV_COMPOSITING_BINARY_SWAP;
    o->radix = 4;
}

vv_status
vv_parallel_new(vv_parallel **out, vv_renderer *ren, const vv_parallel_options *opt) {
    *out = NULL;
    if (ren && !(vv_renderer_get_info(ren)->caps & VV_RENDERER_REGION))
        return vv_error_set(VV_ERR_INVALID,
                            "parallel: %s renders no regions; distributed rendering needs a "
                            "renderer with the region contract (`volvis renderers`)",
                            vv_renderer_name(ren));
    int inited = 0;
    MPI_Initialized(&inited);
    if (!inited)
        return vv_error_set(VV_ERR_UNSUPPORTED, "parallel: MPI is not initialised");
    vv_parallel *p = calloc(1, sizeof *p);
    if (!p)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (opt)
        p->opt = *opt;
    else
        vv_parallel_options_init(&p->opt);
    if (p->opt.radix < 2)
        p->opt.radix = 2;
    MPI_Comm_rank(MPI_COMM_WORLD, &p->rank);
    MPI_Comm_size(MPI_COMM_WORLD, &p->size);
    if (ren) {
        p->ren = ren;
    } else {
        vv_status s = vv_renderer_new(&p->ren, "raycast");
        if (s != VV_OK) {
            free(p);
            return s;
        }
        p->owns_ren = 1;
    }
    *out = p;
    return VV_OK;
}

vv_renderer *
vv_parallel_renderer(vv_parallel *p) {
    return p->ren;
}

void
vv_parallel_free(vv_parallel *p) {
    if (!p)
        return;
    if (p->owns_ren)
        vv_renderer_free(p->ren);
    for (int c = 1; c < p->nb; c++)
        vv_volume_free(p->cbrick[c]);
    vv_volume_free(p->brick);
    vv_source_free(p->source);
    free(p);
}

/* ---------------------------------------------------------------------- */
/* Decomposition                                                            */

static void
plan_free(par_plan *pl) {
    for (int j = 0; j <= PAR_MAX_LEVELS; j++) {
        free(pl->lev[j].pos);
        free(pl->lev[j].axis);
    }
}

/* The rounds: binary swap over the largest power of two, or radix-k. */
static void
plan_rounds(par_plan *pl, int n, const vv_parallel_options *o) {
    pl->n = n;
    pl->m = 0;
    if (o->method == VV_COMPOSITING_BINARY_SWAP) {
        int R = 1;
        while (R * 2 <= n)
            R *= 2;
        pl->R = R;
        pl->extras = n - R;
        for (int r = R; r > 1; r /= 2)
            pl->k[pl->m++] = 2;
        return;
    }
    pl->R = n;
    pl->extras = 0;
    int rest = n;
    while (rest > 1 && pl->m < PAR_MAX_LEVELS) {
        int f = 0;
        for (int d = o->radix < rest ? o->radix : rest; d >= 2; d--)
            if (rest % d == 0) {
                f = d;
                break;
            }
        if (!f) /* a prime beyond the radix: its smallest prime factor */
            for (int d = 2; d <= rest; d++)
                if (rest % d == 0) {
                    f = d;
                    break;
                }
        pl->k[pl->m++] = f;
        rest /= f;
    }
}

static int
digit(const par_plan *pl, int core, int j) {
    for (int i = 0; i < j; i++)
        core /= pl->k[i];
    return core % pl->k[j];
}

static int
with_digit(const par_plan *pl, int core, int j, int d) {
    int mul = 1;
    for (int i = 0; i < j; i++)
        mul *= pl->k[i];
    return core - digit(pl, core, j) * mul + d * mul;
}

/* Ranks under the node whose digits above level j (j excluded) equal
 * core's, and whose digit j is d. */
static int
node_weight(const par_plan *pl, int core, int j, int d) {
    int w = 0;
    for (int c = 0; c < pl->R; c++) {
        int same = digit(pl, c, j) == d;
        for (int i = j + 1; i < pl->m && same; i++)
            same = digit(pl, c, i) == digit(pl, core, i);
        if (same)
            w += 1 + (c < pl->extras);
    }
    return w;
}

/* Cuts box [lo, hi] (voxel indices) for children c0 .. c1 - 1 with weights
 * wt: a k-d tree of cuts in two (children c0 .. cm - 1 below, cm .. c1 - 1
 * above, cm the middle), each along the longest axis that has a multiple of
 * PAR_ALIGN strictly inside, at the multiple nearest the weighted position.
 * Nodes go to lev in preorder; the box of child @p want goes to out_lo,
 * out_hi. */
static vv_status
cut_tree(const int lo[3], const int hi[3], int c0, int c1, const int *wt, par_level *lev, int want,
         int out_lo[3], int out_hi[3]) {
    if (c1 - c0 < 2) {
        if (c0 == want) {
            memcpy(out_lo, lo, sizeof(int) * 3);
            memcpy(out_hi, hi, sizeof(int) * 3);
        }
        return VV_OK;
    }
    const int cm = c0 + (c1 - c0) / 2;
    int best = -1, best_len = -1;
    for (int a = 0; a < 3; a++) {
        const int first = lo[a] / PAR_ALIGN + 1, last = (hi[a] - 1) / PAR_ALIGN;
        if (last >= first && hi[a] - lo[a] > best_len) {
            best = a;
            best_len = hi[a] - lo[a];
        }
    }
    if (best < 0)
        return vv_error_set(VV_ERR_LIMIT,
                            "parallel: the box %d..%d x %d..%d x %d..%d cannot be cut again "
                            "(bricks are cut at multiples of %d voxels): too many ranks for "
                            "this volume",
                            lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], PAR_ALIGN);
    const int a = best;
    int wl = 0, wa = 0;
    for (int c = c0; c < c1; c++) {
        wa += wt[c];
        wl += c < cm ? wt[c] : 0;
    }
    const double ideal = lo[a] + (double)(hi[a] - lo[a]) * wl / (wa > 0 ? wa : 1);
    const int first = lo[a] / PAR_ALIGN + 1, last = (hi[a] - 1) / PAR_ALIGN;
    int m = (int)floor(ideal / PAR_ALIGN + 0.5);
    m = m < first ? first : m > last ? last : m;
    const int node = lev->n_nodes++;
    lev->axis[node] = a;
    lev->pos[node] = m * PAR_ALIGN;
    int l[3], h[3];
    memcpy(l, lo, sizeof l);
    memcpy(h, hi, sizeof h);
    h[a] = m * PAR_ALIGN;
    vv_status s = cut_tree(l, h, c0, cm, wt, lev, want, out_lo, out_hi);
    if (s != VV_OK)
        return s;
    memcpy(h, hi, sizeof h);
    l[a] = m * PAR_ALIGN;
    return cut_tree(l, h, cm, c1, wt, lev, want, out_lo, out_hi);
}

static vv_status
cut(int lo[3], int hi[3], int k, const int *wt, par_level *lev, int want) {
    lev->k = k;
    lev->n_nodes = 0;
    lev->axis = malloc(sizeof(int) * (size_t)k);
    lev->pos = malloc(sizeof(int) * (size_t)k);
    if (!lev->axis || !lev->pos)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    int ol[3], oh[3];
    vv_status s = cut_tree(lo, hi, 0, k, wt, lev, want, ol, oh);
    if (s != VV_OK)
        return s;
    memcpy(lo, ol, sizeof ol);
    memcpy(hi, oh, sizeof oh);
    return VV_OK;
}

static vv_status
plan_build(par_plan *pl, int rank, int size, const int dims[3], const vv_parallel_options *o) {
    memset(pl, 0, sizeof *pl);
    plan_rounds(pl, size, o);
    pl->is_extra = rank >= pl->R;
    pl->core = pl->is_extra ? rank - pl->R : rank;
    int lo[3] = {0, 0, 0}, hi[3];
    for (int a = 0; a < 3; a++)
        hi[a] = dims[a] > 1 ? dims[a] - 1 : 1;
    for (int j = pl->m - 1; j >= 0; j--) {
        int wt[PAR_MAX_K];
        if (pl->k[j] > PAR_MAX_K)
            return vv_error_set(VV_ERR_LIMIT, "parallel: %d ranks in one round", pl->k[j]);
        for (int d = 0; d < pl->k[j]; d++)
            wt[d] = node_weight(pl, pl->core, j, d);
        vv_status s = cut(lo, hi, pl->k[j], wt, &pl->lev[j], digit(pl, pl->core, j));
        if (s != VV_OK)
            return s;
    }
    if (pl->core < pl->extras) {
        const int wt[2] = {1, 1};
        vv_status s = cut(lo, hi, 2, wt, &pl->lev[pl->m], pl->is_extra);
        if (s != VV_OK)
            return s;
        pl->has_fold = 1;
    }
    memcpy(pl->lo, lo, sizeof lo);
    memcpy(pl->hi, hi, sizeof hi);
    return VV_OK;
}

/* Front-to-back order of children c0 .. c1 - 1 under cut node n of @p lev
 * (preorder: the lower half's cm - c0 - 1 nodes follow n, then the upper
 * half's) for eye E (perspective: the half holding the eye first) or view
 * direction D (orthographic), whole-volume index space. */
static void
order_tree(const par_level *lev, int n, int c0, int c1, int ortho, const double E[3],
           const double D[3], int *order, int *count) {
    if (c1 - c0 < 2) {
        order[(*count)++] = c0;
        return;
    }
    const int cm = c0 + (c1 - c0) / 2, a = lev->axis[n];
    const int low_first = ortho ? D[a] >= 0 : E[a] < lev->pos[n];
    if (low_first) {
        order_tree(lev, n + 1, c0, cm, ortho, E, D, order, count);
        order_tree(lev, n + (cm - c0), cm, c1, ortho, E, D, order, count);
    } else {
        order_tree(lev, n + (cm - c0), cm, c1, ortho, E, D, order, count);
        order_tree(lev, n + 1, c0, cm, ortho, E, D, order, count);
    }
}

static void
visibility_order(const par_level *lev, int ortho, const double E[3], const double D[3],
                 int *order) {
    int count = 0;
    order_tree(lev, 0, 0, lev->k, ortho, E, D, order, &count);
}

/* ---------------------------------------------------------------------- */
/* Compositing                                                              */

/* dst = dst (front) combined with src (behind), npix records. */
static void
combine(float *dst, const float *src, size_t npix, vv_region_op op) {
    for (size_t i = 0; i < npix; i++) {
        float *f = dst + PAR_REC * i;
        const float *b = src + PAR_REC * i;
        vv_region_pixel_combine(op, f, &f[4], &f[5], b, b[4], b[5]);
    }
}

static void
piece(size_t a, size_t b, int k, int c, size_t *pa, size_t *pb) {
    *pa = a + (b - a) * (size_t)c / (size_t)k;
    *pb = a + (b - a) * (size_t)(c + 1) / (size_t)k;
}

/* The final pixel range of core rank @p core. */
static void
final_range(const par_plan *pl, int core, size_t P, size_t *a, size_t *b) {
    size_t x = 0, y = P;
    for (int j = 0; j < pl->m; j++)
        piece(x, y, pl->k[j], digit(pl, core, j), &x, &y);
    *a = x;
    *b = y;
}

static vv_status
mpi_fail(int rc, const char *what) {
    char msg[MPI_MAX_ERROR_STRING];
    int len = 0;
    MPI_Error_string(rc, msg, &len);
    return vv_error_set(VV_ERR_IO, "parallel: %s: %s", what, msg);
}

/* The compositing rounds on buffer img (P records; on return this rank's
 * final range holds the whole composite). */
static vv_status
composite(const par_plan *pl, float *img, size_t P, vv_region_op mode, int ortho, const double E[3],
          const double D[3]) {
    const int tag = 4242;
    if (pl->has_fold) {
        /* binary swap with a count that is not a power of two: the extra
         * rank hands its whole image to its core partner first */
        if (pl->is_extra) {
            int rc = MPI_Send(img, (int)(P * PAR_REC), MPI_FLOAT, pl->core, tag, MPI_COMM_WORLD);
            return rc == MPI_SUCCESS ? VV_OK : mpi_fail(rc, "send");
        }
        float *other = malloc(sizeof(float) * PAR_REC * P);
        if (!other)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        int rc = MPI_Recv(other, (int)(P * PAR_REC), MPI_FLOAT, pl->R + pl->core, tag,
                          MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (rc != MPI_SUCCESS) {
            free(other);
            return mpi_fail(rc, "receive");
        }
        int order[2];
        visibility_order(&pl->lev[pl->m], ortho, E, D, order);
        if (order[0] == 0) {
            combine(img, other, P, mode);
        } else {
            combine(other, img, P, mode);
            memcpy(img, other, sizeof(float) * PAR_REC * P);
        }
        free(other);
    } else if (pl->is_extra) {
        return VV_OK;
    }
    size_t a = 0, b = P;
    int kmax = 1;
    for (int j = 0; j < pl->m; j++)
        kmax = pl->k[j] > kmax ? pl->k[j] : kmax;
    /* k pieces of at most ceil(len / k) records each */
    float *recv = malloc(sizeof(float) * PAR_REC * (P + (size_t)kmax));
    float *acc = malloc(sizeof(float) * PAR_REC * (P + 1));
    MPI_Request *req = malloc(sizeof(MPI_Request) * 2 * PAR_MAX_K);
    if (!recv || !acc || !req) {
        free(recv);
        free(acc);
        free(req);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    vv_status s = VV_OK;
    for (int j = 0; j < pl->m && s == VV_OK; j++) {
        const int k = pl->k[j], d = digit(pl, pl->core, j);
        size_t ma, mb;
        piece(a, b, k, d, &ma, &mb);
        const size_t mlen = mb - ma;
        int nreq = 0;
        for (int c = 0; c < k; c++) {
            if (c == d)
                continue;
            const int peer = with_digit(pl, pl->core, j, c);
            size_t pa, pb;
            piece(a, b, k, c, &pa, &pb);
            int rc = MPI_Irecv(recv + PAR_REC * mlen * (size_t)c, (int)(PAR_REC * mlen), MPI_FLOAT,
                               peer, tag + 1 + j, MPI_COMM_WORLD, &req[nreq++]);
            if (rc == MPI_SUCCESS)
                rc = MPI_Isend(img + PAR_REC * pa, (int)(PAR_REC * (pb - pa)), MPI_FLOAT, peer,
                               tag + 1 + j, MPI_COMM_WORLD, &req[nreq++]);
            if (rc != MPI_SUCCESS) {
                s = mpi_fail(rc, "exchange");
                break;
            }
        }
        int rc = MPI_Waitall(nreq, req, MPI_STATUSES_IGNORE);
        if (s != VV_OK)
            break;
        if (rc != MPI_SUCCESS) {
            s = mpi_fail(rc, "exchange");
            break;
        }
        /* own piece in place among the received ones, then front to back */
        memcpy(recv + PAR_REC * mlen * (size_t)d, img + PAR_REC * ma,
               sizeof(float) * PAR_REC * mlen);
        int order[PAR_MAX_K];
        visibility_order(&pl->lev[j], ortho, E, D, order);
        memcpy(acc, recv + PAR_REC * mlen * (size_t)order[0], sizeof(float) * PAR_REC * mlen);
        for (int c = 1; c < k; c++)
            combine(acc, recv + PAR_REC * mlen * (size_t)order[c], mlen, mode);
        memcpy(img + PAR_REC * ma, acc, sizeof(float) * PAR_REC * mlen);
        a = ma;
        b = mb;
    }
    free(recv);
    free(acc);
    free(req);
    return s;
}

/* ---------------------------------------------------------------------- */
/* The brick                                                                */

/* Drops the bricks kept. */
static void
drop_bricks(vv_parallel *p) {
    for (int c = 1; c < p->nb; c++)
        vv_volume_free(p->cbrick[c]);
    memset(p->cbrick, 0, sizeof p->cbrick);
    vv_volume_free(p->brick);
    p->brick = NULL;
    p->nb = 0;
}

static vv_status make_brick_of(vv_parallel *p, const vv_volume *v, const par_plan *pl, int ghost,
                               int channel, vv_volume **out);

/* This rank's bricks of object @p obj: one, or one per channel of a
 * multi-channel object (every channel's box read at once: a pyramid's
 * chunks hold them all), kept while the box and the data stay. */
static vv_status
make_brick(vv_parallel *p, const vv_object *obj, const par_plan *pl, int ghost) {
    const vv_volume *v = obj->volume;
    const int n = obj->n_channels > 1 ? obj->n_channels : 1;
    const void *key = p->source ? (const void *)p->source : (const void *)v;
    const uint64_t mod = p->source ? 0 : v->modified;
    int same = p->brick && p->src == key && p->src_modified == mod && p->nb == n;
    same = same && p->ghost == ghost;
    for (int a = 0; a < 3 && same; a++)
        same = p->box_lo[a] == pl->lo[a] && p->box_hi[a] == pl->hi[a];
    for (int c = 1; c < n && same && !p->source; c++)
        same = p->cbrick[c] && obj->channels[c].volume &&
               p->cbrick[c]->modified == obj->channels[c].volume->modified;
    if (same)
        return VV_OK;
    drop_bricks(p);
    vv_status s = VV_OK;
    for (int c = 0; c < n && s == VV_OK; c++)
        s = make_brick_of(p, n > 1 ? obj->channels[c].volume : v, pl, ghost, n > 1 ? c : -1,
                          &p->cbrick[c]);
    if (s != VV_OK) {
        for (int c = 0; c < n; c++)
            vv_volume_free(p->cbrick[c]);
        memset(p->cbrick, 0, sizeof p->cbrick);
        return s;
    }
    p->brick = p->cbrick[0];
    p->nb = n;
    p->src = key;
    p->src_modified = mod;
    memcpy(p->box_lo, pl->lo, sizeof p->box_lo);
    p->ghost = ghost;
    memcpy(p->box_hi, pl->hi, sizeof p->box_hi);
    return VV_OK;
}

/* The brick of channel @p channel (-1: an object of one channel) cut from
 * @p v or read from the source into *out, and the region it is. */
static vv_status
make_brick_of(vv_parallel *p, const vv_volume *v, const par_plan *pl, int ghost, int channel,
              vv_volume **out) {
    const vv_volume *g = p->source ? &p->hdr : v;
    /* the box, @p ghost voxels beyond each face (within the volume) */
    int off[3], end[3], dims[3];
    for (int a = 0; a < 3; a++) {
        off[a] = pl->lo[a] > ghost ? pl->lo[a] - ghost : 0;
        end[a] = pl->hi[a] + ghost < g->dims[a] - 1 ? pl->hi[a] + ghost : g->dims[a] - 1;
        if (end[a] < off[a])
            end[a] = off[a];
        dims[a] = end[a] - off[a] + 1;
    }
    vv_volume *b = NULL;
    vv_status s;
    if (p->source) {
        /* only this rank's box is read from the file (a channel's: every
         * channel's chunks are read with the first, held in the cache) */
        s = channel >= 0 ? vv_source_channel_read_box(p->source, channel, p->level, off, end, &b)
                         : vv_source_read_box(p->source, p->level, off, end, &b);
        if (s != VV_OK)
            return vv_error_prefix(s, "parallel: brick %d..%d x %d..%d x %d..%d", off[0], end[0],
                                   off[1], end[1], off[2], end[2]);
    } else {
        s = vv_volume_new(&b, dims, v->type);
        if (s != VV_OK)
            return vv_error_prefix(s, "parallel: brick of %dx%dx%d voxels", dims[0], dims[1],
                                   dims[2]);
        const size_t vs = vv_voxel_type_size(v->type);
        const size_t row = vs * (size_t)dims[0];
        for (int k = 0; k < dims[2]; k++)
            for (int j = 0; j < dims[1]; j++) {
                const size_t src =
                    (((size_t)(k + off[2]) * (size_t)v->dims[1] + (size_t)(j + off[1])) *
                         (size_t)v->dims[0] +
                     (size_t)off[0]) *
                    vs;
                const size_t dst = ((size_t)k * (size_t)dims[1] + (size_t)j) * row;
                memcpy((char *)b->data + dst, (const char *)v->data + src, row);
            }
        /* the whole volume's frame and range: the brick's voxel (0, 0, 0) is
         * the whole volume's voxel off (a region's voxels, sys/renderer.h) */
        memcpy(b->spacing, v->spacing, sizeof b->spacing);
        memcpy(b->origin, v->origin, sizeof b->origin);
        memcpy(b->direction, v->direction, sizeof b->direction);
        b->range[0] = v->range[0];
        b->range[1] = v->range[1];
        b->unit = v->unit;
        b->space = v->space;
    }
    *out = b;
    memset(&p->rg, 0, sizeof p->rg);
    for (int a = 0; a < 3; a++) {
        p->rg.dims[a] = g->dims[a];
        p->rg.offset[a] = off[a];
        p->rg.lo[a] = pl->lo[a] > 0 ? pl->lo[a] : -INFINITY;
        p->rg.hi[a] = pl->hi[a] < g->dims[a] - 1 ? pl->hi[a] : INFINITY;
    }
    return VV_OK;
}

/* Reads bricks from @p obj's source (level @p level) from now on, or cuts
 * them from its volume again (no source): the brick kept is dropped when
 * the source or the level changes. */
static void
use_source(vv_parallel *p, const vv_object *obj, int level) {
    vv_source *src = obj->source;
    if (src) {
        level = level < vv_source_levels(src) ? level : vv_source_levels(src) - 1;
        level = level > 0 ? level : 0;
    }
    if (src == p->source && (!src || level == p->level))
        return;
    vv_source_free(p->source);
    p->source = vv_source_ref(src);
    p->level = level;
    memset(&p->hdr, 0, sizeof p->hdr);
    if (src) {
        p->hdr = *vv_source_level(src, level); /* geometry only: its voxels are never read */
        p->hdr.data = NULL;
    }
    /* a range of 0 .. 0: a file opened without its range; learnt from the bricks */
    p->range_done = !(p->hdr.range[0] == 0 && p->hdr.range[1] == 0);
    drop_bricks(p);
    p->src = NULL;
}

/* The one visible volume object of w, or -1 (with an error). */
static int
find_object(const vv_world *w) {
    int found = -1, n = 0;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (o->visible && o->type == VV_OBJECT_VOLUME && o->volume) {
            found = i;
            n++;
        } else if (o->visible && o->type != VV_OBJECT_VOLUME) {
            vv_error_set(VV_ERR_UNSUPPORTED,
                         "parallel: object '%s' is not a volume; distributed rendering draws "
                         "one volume object",
                         o->name);
            return -1;
        }
    }
    if (n != 1) {
        vv_error_set(VV_ERR_UNSUPPORTED,
                     "parallel: %d visible volume objects; distributed rendering draws one", n);
        return -1;
    }
    return found;
}

/* The passes an object is drawn in: one (every channel at once under the
 * composite rule), or a pass a drawn channel under the additive and
 * maximum rules (pass i draws channel ch[i]; their images are composited
 * over the ranks each, then added). Returns their count. */
static int
object_passes(const vv_object *obj, int ch[VV_MAX_CHANNELS]) {
    if (obj->n_channels < 2 || obj->blend == VV_BLEND_COMPOSITE)
        return 1;
    int n = 0;
    for (int c = 0; c < obj->n_channels; c++)
        if (obj->channels[c].visible && obj->channels[c].volume)
            ch[n++] = c;
    return n > 0 ? n : 1;
}

static vv_status render_pass(vv_parallel *p, const vv_world *w, const vv_view *view,
                             const vv_render_options *opt, const par_plan *pl, int oi, int pass,
                             float **img_out, vv_region_op *op, vv_region_image *classify,
                             vv_parallel_stats *st);

/* This rank's part: plan, bricks, the first pass's partial image (P records
 * in *img_out). */
static vv_status
render_part(vv_parallel *p, vv_status pre, const vv_world *w, const vv_view *view,
            const vv_render_options *opt, par_plan *pl, int *obj_index, float **img_out,
            vv_region_op *op, vv_region_image *classify, vv_parallel_stats *st, int *agreed) {
    /* collective: every rank calls this once a frame, whatever failed */
    vv_status s = pre;
    const int oi = s == VV_OK ? find_object(w) : -1;
    if (s == VV_OK && oi < 0)
        s = VV_ERR_UNSUPPORTED;
    *obj_index = oi;
    const vv_object *obj = oi >= 0 ? w->objects[oi] : NULL;
    if (obj)
        use_source(p, obj, opt->lod && opt->lod->level > 0 ? opt->lod->level : 0);
    if (s == VV_OK) {
        const int *dims = p->source ? p->hdr.dims : obj->volume->dims;
        s = plan_build(pl, p->rank, p->size, dims, &p->opt);
    }
    if (s == VV_OK)
        s = make_brick(p, obj, pl, obj->mode == VV_MODE_ISO && obj->n_channels < 2 ? 2 : 1);
    /* every rank learns of a failure to cut or read a brick here */
    s = vv_parallel_agree(s);
    *agreed = s != VV_OK; /* the same on every rank */
    if (s != VV_OK)
        return s;
    if (p->source && !p->range_done) {
        /* the value range of the whole volume: the union of the bricks' */
        vv_volume_update_range(p->brick);
        double mn = p->brick->range[0], mx = -p->brick->range[1], gmn = mn, gmx = mx;
        MPI_Allreduce(&mn, &gmn, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
        MPI_Allreduce(&mx, &gmx, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
        p->hdr.range[0] = gmn;
        p->hdr.range[1] = -gmx;
        p->range_done = 1;
    }
    if (p->source) {
        p->brick->range[0] = p->hdr.range[0];
        p->brick->range[1] = p->hdr.range[1];
    }
    return render_pass(p, w, view, opt, pl, oi, 0, img_out, op, classify, st);
}

/* Pass @p pass of this rank's part (object_passes): its partial image (P
 * records in *img_out). */
static vv_status
render_pass(vv_parallel *p, const vv_world *w, const vv_view *view, const vv_render_options *opt,
            const par_plan *pl, int oi, int pass, float **img_out, vv_region_op *op,
            vv_region_image *classify, vv_parallel_stats *st) {
    const vv_object *obj = w->objects[oi];
    vv_status s = VV_OK;
    /* the region: this rank's brick, seen where its box projects; the
     * World keeps the object's own volume (the whole one, or rank 0's
     * proxy when the ranks read by bricks) for effects that cross bricks */
    vv_render_region rg = p->rg;
    rg.object = oi;
    rg.voxels = p->brick;
    int ch[VV_MAX_CHANNELS];
    const int npass = object_passes(obj, ch);
    if (p->nb > 1 && npass > 1) { /* one channel alone */
        rg.voxels = p->cbrick[ch[pass]];
        rg.pass_channel = ch[pass] + 1;
    } else if (p->nb > 1) { /* every channel at once */
        for (int c = 0; c < p->nb; c++)
            if (obj->channels[c].visible && obj->channels[c].volume) {
                rg.voxels = p->cbrick[c];
                break;
            }
        rg.channel_voxels = (const vv_volume *const *)p->cbrick;
    }
    {
        const vv_volume *g = p->source ? &p->hdr : obj->volume;
        vv_object geo = *obj; /* shallow: nothing in it is released */
        geo.volume = (vv_volume *)g;
        int rlo[3], rhi[3];
        for (int a = 0; a < 3; a++) {
            rlo[a] = rg.offset[a];
            rhi[a] = rg.offset[a] + p->brick->dims[a] - 1;
        }
        vv_region_rect(&rg, vv_object_index_to_world(&geo), view, rlo, rhi);
    }
    const size_t P = (size_t)view->width * (size_t)view->height;
    vv_image *img = NULL;
    float *key = malloc(sizeof(float) * (P ? P : 1));
    s = key ? vv_image_new(&img, view->width, view->height)
            : vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_region_image ri = {.image = img, .key = key, .op = VV_REGION_OVER};
    double t0 = MPI_Wtime();
    struct timespec c0, c1;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
    /* rank 0 renders its region even off screen in xray and attenuated-mip
     * mode: the render gives the table that classifies the summed means (or
     * the attenuated maxima) at the end */
    const int sum =
        (obj->mode == VV_MODE_XRAY || obj->mode == VV_MODE_ATTENUATED_MIP) && p->rank == 0;
    if (s == VV_OK && rg.x1 > rg.x0 && rg.y1 <= rg.y0 && !sum) {
        vv_region_image_clear(&ri); /* off screen */
        ri.op = p->nb > 1
                    ? (npass > 1 && obj->blend == VV_BLEND_MAXIMUM ? VV_REGION_MAX : VV_REGION_OVER)
                    : vv_region_op_for(obj->mode);
    } else if (s == VV_OK) {
        s = vv_renderer_render_region(p->ren, w, view, &rg, opt, &ri);
    }
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
    st->render = MPI_Wtime() - t0;
    st->render_cpu = (double)(c1.tv_sec - c0.tv_sec) + 1e-9 * (double)(c1.tv_nsec - c0.tv_nsec);
    *op = ri.op;
    *classify = ri;
    float *buf = NULL;
    if (s == VV_OK) {
        buf = malloc(sizeof(float) * PAR_REC * (P ? P : 1));
        if (!buf)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        for (size_t i = 0; buf && i < P; i++) {
            memcpy(buf + PAR_REC * i, img->rgba + 4 * i, 4 * sizeof(float));
            buf[PAR_REC * i + 4] = img->depth[i];
            buf[PAR_REC * i + 5] = key[i];
        }
    }
    free(key);
    vv_image_free(img);
    *img_out = buf;
    st->brick_voxels =
        (size_t)p->brick->dims[0] * (size_t)p->brick->dims[1] * (size_t)p->brick->dims[2];
    memcpy(st->brick_lo, pl->lo, sizeof st->brick_lo);
    memcpy(st->brick_hi, pl->hi, sizeof st->brick_hi);
    return s;
}

static vv_status composite_pass(vv_parallel *p, par_plan *pl, float *img, size_t P, vv_region_op op,
                                int ortho, const double E[3], const double D[3],
                                vv_parallel_stats *stp, float *sum, const vv_world *w,
                                const vv_region_image *clsp, vv_image *out);

vv_status
vv_parallel_render(vv_parallel *p, const vv_world *w, const vv_view *view,
                   const vv_render_options *opt, vv_image *out, vv_parallel_stats *stats) {
    vv_parallel_stats st;
    memset(&st, 0, sizeof st);
    st.ranks = p->size;
    vv_render_options defo;
    if (!opt) {
        vv_render_options_init(&defo);
        opt = &defo;
    }
    par_plan pl;
    memset(&pl, 0, sizeof pl);
    float *img = NULL;
    int oi = -1;
    vv_status s = VV_OK;
    if (p->rank == 0 && (!out || out->width != view->width || out->height != view->height))
        s = vv_error_set(VV_ERR_INVALID, "parallel: the output image is not %dx%d", view->width,
                         view->height);
    int agreed = 0;
    vv_region_op op = VV_REGION_OVER;
    vv_region_image cls; /* its classify (xray, attenuated-mip), from rank 0's region render */
    memset(&cls, 0, sizeof cls);
    s = render_part(p, s, w, view, opt, &pl, &oi, &img, &op, &cls, &st, &agreed);
    /* every rank learns of any failure here, before the exchanges */
    if (!agreed)
        s = vv_parallel_agree(s);
    if (s != VV_OK) {
        free(img);
        plan_free(&pl);
        return s;
    }
    const size_t P = (size_t)view->width * (size_t)view->height;
    const vv_object *obj = w->objects[oi];
    /* the eye (or view direction) in the whole volume's index space: the
     * level's, whose voxels the bricks are (an object out of core shows a
     * coarse proxy, of other indices) */
    const int ortho = view->projection == VV_PROJECTION_ORTHOGRAPHIC;
    int ok = 0;
    vv_object geo = *obj; /* shallow: nothing in it is released */
    if (p->source)
        geo.volume = &p->hdr;
    const vv_mat4 w2i = vv_mat4_inverse(vv_object_index_to_world(&geo), &ok);
    const vv_vec3 e = vv_mat4_mul_point(w2i, view->eye);
    const vv_vec3 fwd = vv_vec3_sub(view->at, view->eye);
    double E[3] = {e.x, e.y, e.z}, D[3];
    for (int a = 0; a < 3; a++)
        D[a] = w2i.m[a][0] * fwd.x + w2i.m[a][1] * fwd.y + w2i.m[a][2] * fwd.z;
    /* the additive and maximum rules: a pass a channel, each composited
     * over the ranks and gathered, added on rank 0 (sums over black) */
    int chs[VV_MAX_CHANNELS];
    const int npass = object_passes(obj, chs);
    float *sum = NULL; /* rank 0, several passes: colour, transmittance, depth a pixel */
    if (npass > 1 && p->rank == 0 && !(sum = malloc(sizeof(float) * 5 * (P ? P : 1))))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t i = 0; sum && i < P; i++) {
        sum[5 * i] = sum[5 * i + 1] = sum[5 * i + 2] = 0;
        sum[5 * i + 3] = 1;
        sum[5 * i + 4] = INFINITY;
    }
    s = vv_parallel_agree(s);
    for (int pass = 0; pass < npass && s == VV_OK; pass++) {
        if (pass > 0) {
            free(img);
            img = NULL;
            s = render_pass(p, w, view, opt, &pl, oi, pass, &img, &op, &cls, &st);
            s = vv_parallel_agree(s);
            if (s != VV_OK)
                break;
        }
        s = composite_pass(p, &pl, img, P, op, ortho, E, D, &st, npass > 1 ? sum : NULL, w, &cls,
                           out);
    }
    free(sum);
    free(img);
    plan_free(&pl);
    if (stats)
        *stats = st;
    return s;
}

/* One pass's partial images (@p img, this rank's) composited over the
 * ranks and gathered to rank 0: finished over the background into @p out,
 * or with @p sum (several passes) added into it (colour, transmittance,
 * nearest depth; the last pass writes @p out). Collective. */
static vv_status
composite_pass(vv_parallel *p, par_plan *pl, float *img, size_t P, vv_region_op op, int ortho,
               const double E[3], const double D[3], vv_parallel_stats *stp, float *sum,
               const vv_world *w, const vv_region_image *clsp, vv_image *out) {
    vv_parallel_stats st = *stp;
    const vv_region_image cls = *clsp;
    vv_status s = VV_OK;
    double t0 = MPI_Wtime();
    if (p->opt.barrier)
        MPI_Barrier(MPI_COMM_WORLD);
    double t1 = MPI_Wtime();
    s = composite(pl, img, P, op, ortho, E, D);
    double t2 = MPI_Wtime();
    st.wait = t1 - t0;
    st.composite = t2 - t1;
    s = vv_parallel_agree(s);
    /* gather the final ranges to rank 0 */
    int *counts = NULL, *displs = NULL;
    float *whole = NULL;
    if (s == VV_OK && p->rank == 0) {
        counts = calloc((size_t)p->size, sizeof *counts);
        displs = calloc((size_t)p->size, sizeof *displs);
        whole = malloc(sizeof(float) * PAR_REC * (P ? P : 1));
        if (!counts || !displs || !whole)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        for (int r = 0; r < pl->R && s == VV_OK; r++) {
            size_t a, b;
            final_range(pl, r, P, &a, &b);
            counts[r] = (int)(PAR_REC * (b - a));
            displs[r] = (int)(PAR_REC * a);
        }
    }
    s = vv_parallel_agree(s);
    if (s == VV_OK) {
        size_t a = 0, b = 0;
        if (!pl->is_extra)
            final_range(pl, pl->core, P, &a, &b);
        int rc = MPI_Gatherv(img + PAR_REC * a, (int)(PAR_REC * (b - a)), MPI_FLOAT, whole, counts,
                             displs, MPI_FLOAT, 0, MPI_COMM_WORLD);
        if (rc != MPI_SUCCESS)
            s = mpi_fail(rc, "gather");
    }
    st.gather = MPI_Wtime() - t2;
    double mx[3] = {st.render, st.composite, st.render_cpu}, gmx[3] = {0, 0, 0};
    MPI_Reduce(mx, gmx, 3, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    st.max_render = gmx[0];
    st.max_composite = gmx[1];
    st.max_render_cpu = gmx[2];
    float *keys = NULL;
    if (s == VV_OK && p->rank == 0 && (op == VV_REGION_SUM || op == VV_REGION_ATTENUATED_MAX) &&
        !(keys = malloc(sizeof(float) * (P ? P : 1))))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s == VV_OK && p->rank == 0) {
        for (size_t i = 0; i < P; i++) {
            const float *r = whole + PAR_REC * i;
            memcpy(out->rgba + 4 * i, r, 4 * sizeof(float));
            out->depth[i] = r[4];
            if (keys)
                keys[i] = r[5];
        }
        /* the background once, as the whole render adds it (xray: the means
         * classified first; attenuated-mip: the attenuated maxima); a pass of
         * several over black, added to the others' */
        vv_region_image fin = {.image = out,
                               .key = keys,
                               .op = op,
                               .classify = cls.classify,
                               .classify_ctx = cls.classify_ctx};
        vv_region_image_finish(&fin, sum ? (vv_vec3){0, 0, 0} : w->background);
        for (size_t i = 0; sum && i < P; i++) {
            const float *px = out->rgba + 4 * i;
            float *q = sum + 5 * i;
            for (int k = 0; k < 3; k++)
                q[k] += px[k];
            q[3] *= 1 - (px[3] < 1 ? px[3] : 1);
            q[4] = out->depth[i] < q[4] ? out->depth[i] : q[4];
        }
        const float bg[3] = {(float)w->background.x, (float)w->background.y,
                             (float)w->background.z};
        for (size_t i = 0; sum && i < P; i++) { /* the sums so far over the background */
            const float *q = sum + 5 * i;
            for (int k = 0; k < 3; k++)
                out->rgba[4 * i + (size_t)k] = q[k] + q[3] * bg[k];
            out->rgba[4 * i + 3] = 1 - q[3];
            out->depth[i] = q[4];
        }
    }
    free(keys);
    free(counts);
    free(displs);
    free(whole);
    *stp = st;
    return s;
}
