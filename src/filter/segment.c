/*
 * Segmentation: threshold, window, Otsu's threshold (Otsu, IEEE SMC 1979),
 * connected components (runs of voxels joined by union-find, in parallel
 * slabs), largest components, region growing, binary morphology and hole
 * filling.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "filter/filter_internal.h"

/* ---- threshold and window ------------------------------------------------------------ */

typedef struct thr_ctx {
    const vv_volume *in;
    void *out;
    double lo, hi;
    int window;
} thr_ctx;

static void
thr_body(void *cp, long r0, long r1, int w) {
    (void)w;
    thr_ctx *C = cp;
    size_t n0 = (size_t)C->in->dims[0];
    for (size_t q = (size_t)r0 * n0; q < (size_t)r1 * n0; q++) {
        double v = vv_voxel_value(C->in->type, C->in->data, q);
        if (C->window) {
            double x = v != v ? v : v < C->lo ? 0 : v > C->hi ? 1 : (v - C->lo) / (C->hi - C->lo);
            ((float *)C->out)[q] = (float)x;
        } else {
            ((uint8_t *)C->out)[q] = (uint8_t)(v >= C->lo && v <= C->hi);
        }
    }
}

static vv_status
thr_run(const vv_volume *in, double lo, double hi, int window, const vv_filter_options *o,
        vv_volume **out) {
    const char *what = window ? "window" : "threshold";
    vv_status s = vf_check_io(in, out, what);
    if (s != VV_OK)
        return s;
    if (lo != lo || hi != hi || (window ? !(lo < hi) : lo > hi) ||
        (window && (!isfinite(lo) || !isfinite(hi))))
        return vv_error_set(VV_ERR_INVALID, "%s: range %g..%g: need %s", what, lo, hi,
                            window ? "finite lo < hi" : "lo <= hi");
    vv_volume *v;
    if ((s = vf_new_like(in, in->dims, window ? VV_F32 : VV_U8, &v)) != VV_OK)
        return s;
    thr_ctx C = {in, v->data, lo, hi, window};
    if ((s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 64, thr_body, &C, 0, 1)) != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

vv_status
vv_filter_threshold(const vv_volume *in, double lo, double hi, const vv_filter_options *o,
                    vv_volume **out) {
    return thr_run(in, lo, hi, 0, o, out);
}

vv_status
vv_filter_window(const vv_volume *in, double lo, double hi, const vv_filter_options *o,
                 vv_volume **out) {
    return thr_run(in, lo, hi, 1, o, out);
}

vv_status
vv_filter_otsu(const vv_volume *in, double *threshold) {
    if (!in || !in->data || !threshold)
        return vv_error_set(VV_ERR_INVALID, "otsu: NULL argument");
    size_t n = (size_t)vv_volume_voxel_count(in);
    double mn = INFINITY, mx = -INFINITY;
    for (size_t q = 0; q < n; q++) {
        double v = vv_voxel_value(in->type, in->data, q);
        if (isfinite(v)) {
            mn = v < mn ? v : mn;
            mx = v > mx ? v : mx;
        }
    }
    if (!(mx > mn))
        return vv_error_set(VV_ERR_INVALID,
                            "otsu: the volume has no two distinct finite values (range %g..%g)", mn,
                            mx);
    enum { NB = 1024 };
    static const int nb = NB;
    double *h = calloc(NB, sizeof *h);
    if (!h)
        return vv_error_set(VV_ERR_NOMEM, "otsu: out of memory");
    double wbin = (mx - mn) / nb;
    for (size_t q = 0; q < n; q++) {
        double v = vv_voxel_value(in->type, in->data, q);
        if (!isfinite(v))
            continue;
        int b = (int)((v - mn) / wbin);
        h[b < 0 ? 0 : b >= nb ? nb - 1 : b] += 1;
    }
    double total = 0, sum = 0;
    for (int b = 0; b < nb; b++) {
        total += h[b];
        sum += h[b] * (b + 0.5);
    }
    double w0 = 0, s0 = 0, best = -1;
    int first = 0, last = 0;
    for (int t = 0; t < nb - 1; t++) {
        w0 += h[t];
        s0 += h[t] * (t + 0.5);
        double w1 = total - w0;
        if (w0 == 0 || w1 == 0)
            continue;
        double m0 = s0 / w0, m1 = (sum - s0) / w1;
        double var = w0 * w1 * (m0 - m1) * (m0 - m1);
        if (var > best * (1 + 1e-12)) {
            best = var;
            first = last = t;
        } else if (var >= best * (1 - 1e-12)) {
            last = t;
        }
    }
    free(h);
    /* class 0 is bins 0..t: the threshold is the upper edge of bin t */
    *threshold = mn + ((first + last) / 2.0 + 1.0) * wbin;
    return VV_OK;
}

/* ---- connected components ---------------------------------------------------------------- */

typedef struct cc_ctx {
    const uint8_t *mask;
    int n[3];
    size_t *rowstart; /* runs of row r: rowstart[r] .. rowstart[r + 1] - 1 */
    int32_t *rs, *re; /* run start, end (exclusive) along i */
    size_t *parent;
    int conn;
    int nslab;
    int *slab_k0; /* slab s covers k in slab_k0[s] .. slab_k0[s + 1] - 1 */
    uint32_t *labels;
    uint32_t *run_label;
} cc_ctx;

/* Index of the first non-zero byte of m[i..n-1] (n if none), skipping zero
 * 8-byte words: masks are mostly background. */
static inline int
next_set(const uint8_t *m, int i, int n) {
    while (i < n && ((uintptr_t)(m + i) & 7))
        if (m[i])
            return i;
        else
            i++;
    while (i + 8 <= n) {
        uint64_t w;
        memcpy(&w, m + i, 8);
        if (w)
            break;
        i += 8;
    }
    while (i < n && !m[i])
        i++;
    return i;
}

static inline int
next_clear(const uint8_t *m, int i, int n) {
    while (i < n && m[i])
        i++;
    return i;
}

static void
cc_count(void *cp, long r0, long r1, int w) {
    (void)w;
    cc_ctx *C = cp;
    const int n0 = C->n[0];
    for (long r = r0; r < r1; r++) {
        const uint8_t *m = C->mask + (size_t)r * n0;
        size_t c = 0;
        int i = 0;
        while ((i = next_set(m, i, n0)) < n0) {
            c++;
            i = next_clear(m, i, n0);
        }
        C->rowstart[r + 1] = c;
    }
}

static void
cc_fill(void *cp, long r0, long r1, int w) {
    (void)w;
    cc_ctx *C = cp;
    const int n0 = C->n[0];
    for (long r = r0; r < r1; r++) {
        const uint8_t *m = C->mask + (size_t)r * n0;
        size_t q = C->rowstart[r];
        int i = 0;
        while ((i = next_set(m, i, n0)) < n0) {
            int s = i;
            i = next_clear(m, i, n0);
            C->rs[q] = s;
            C->re[q] = i;
            C->parent[q] = q;
            q++;
        }
    }
}

static inline size_t
uf_find(size_t *p, size_t a) {
    while (p[a] != a) {
        p[a] = p[p[a]];
        a = p[a];
    }
    return a;
}

static inline void
uf_union(size_t *p, size_t a, size_t b) {
    a = uf_find(p, a);
    b = uf_find(p, b);
    if (a < b)
        p[b] = a;
    else if (b < a)
        p[a] = b;
}

/* Joins the runs of row r with those of row q (an earlier row) that touch,
 * allowing a diagonal step along i when d = 1. */
static void
cc_join_rows(cc_ctx *C, size_t r, size_t q, int d) {
    size_t a = C->rowstart[r], ae = C->rowstart[r + 1];
    size_t b = C->rowstart[q], be = C->rowstart[q + 1];
    while (a < ae && b < be) {
        if (C->rs[a] < C->re[b] + d && C->rs[b] < C->re[a] + d)
            uf_union(C->parent, a, b);
        if (C->re[a] < C->re[b])
            a++;
        else
            b++;
    }
}

/* Unions of row (j, k) with its earlier neighbour rows; rows in slice k - 1
 * only when @p below. */
static void
cc_join(cc_ctx *C, int j, int k, int below) {
    const int n1 = C->n[1];
    size_t r = (size_t)k * n1 + j;
    int face = C->conn == 6 ? 0 : 1, edge = C->conn == 26 ? 1 : 0;
    if (j > 0)
        cc_join_rows(C, r, r - 1, face);
    if (below && k > 0) {
        cc_join_rows(C, r, r - n1, face);
        if (C->conn >= 18) {
            if (j > 0)
                cc_join_rows(C, r, r - n1 - 1, edge);
            if (j < n1 - 1)
                cc_join_rows(C, r, r - n1 + 1, edge);
        }
    }
}

static void
cc_slab(void *cp, long s0, long s1, int w) {
    (void)w;
    cc_ctx *C = cp;
    for (long s = s0; s < s1; s++)
        for (int k = C->slab_k0[s]; k < C->slab_k0[s + 1]; k++)
            for (int j = 0; j < C->n[1]; j++)
                cc_join(C, j, k, k > C->slab_k0[s]);
}

static void
cc_write(void *cp, long r0, long r1, int w) {
    (void)w;
    cc_ctx *C = cp;
    const int n0 = C->n[0];
    for (long r = r0; r < r1; r++) {
        uint32_t *d = C->labels + (size_t)r * n0; /* zeroed by the caller */
        for (size_t q = C->rowstart[r]; q < C->rowstart[r + 1]; q++)
            for (int i = C->rs[q]; i < C->re[q]; i++)
                d[i] = C->run_label[q];
    }
}

vv_status
vf_label_mask(const uint8_t *mask, const int dims[3], int connectivity, const vv_filter_options *o,
              double p0, double p1, uint32_t *labels, uint64_t **sizes, uint64_t *count) {
    if (connectivity != 6 && connectivity != 18 && connectivity != 26)
        return vv_error_set(VV_ERR_INVALID, "connectivity %d: must be 6, 18 or 26", connectivity);
    cc_ctx C = {.mask = mask, .conn = connectivity, .labels = labels};
    memcpy(C.n, dims, sizeof C.n);
    long rows = (long)dims[1] * dims[2];
    vv_status s = VV_OK;
    C.rowstart = malloc(((size_t)rows + 1) * sizeof *C.rowstart);
    if (!C.rowstart)
        return vv_error_set(VV_ERR_NOMEM, "components: out of memory");
    C.rowstart[0] = 0;
    double dp = (p1 - p0) / 4;
    s = vf_parallel(o, rows, 64, cc_count, &C, p0, p0 + dp);
    for (long r = 0; r < rows && s == VV_OK; r++)
        C.rowstart[r + 1] += C.rowstart[r];
    size_t nruns = s == VV_OK ? C.rowstart[rows] : 0;
    if (s == VV_OK) {
        C.rs = malloc((nruns ? nruns : 1) * sizeof *C.rs);
        C.re = malloc((nruns ? nruns : 1) * sizeof *C.re);
        C.parent = malloc((nruns ? nruns : 1) * sizeof *C.parent);
        C.run_label = malloc((nruns ? nruns : 1) * sizeof *C.run_label);
        if (!C.rs || !C.re || !C.parent || !C.run_label)
            s = vv_error_set(VV_ERR_NOMEM, "components: out of memory (%zu runs)", nruns);
    }
    if (s == VV_OK)
        s = vf_parallel(o, rows, 64, cc_fill, &C, p0 + dp, p0 + 2 * dp);
    /* slabs of whole slices, joined inside in parallel, then across their seams */
    int nt = vf_threads(o);
    int nslab = nt * 4 < dims[2] ? nt * 4 : dims[2];
    C.nslab = nslab;
    C.slab_k0 = malloc(((size_t)nslab + 1) * sizeof *C.slab_k0);
    if (s == VV_OK && !C.slab_k0)
        s = vv_error_set(VV_ERR_NOMEM, "components: out of memory");
    if (s == VV_OK) {
        for (int q = 0; q <= nslab; q++)
            C.slab_k0[q] = (int)((long)dims[2] * q / nslab);
        s = vf_parallel(o, nslab, 1, cc_slab, &C, p0 + 2 * dp, p0 + 3 * dp);
    }
    if (s == VV_OK)
        for (int q = 1; q < nslab; q++)
            for (int j = 0; j < dims[1]; j++)
                cc_join(&C, j, C.slab_k0[q], 1);
    /* the root of a component is its first run in raster order (unions keep
     * the smaller index), so numbering roots in run order numbers the
     * components by their first voxel */
    uint64_t nlab = 0;
    uint64_t *sz = NULL;
    if (s == VV_OK) {
        for (size_t q = 0; q < nruns; q++) {
            size_t root = uf_find(C.parent, q);
            if (root == q) {
                if (nlab >= UINT32_MAX) {
                    s = vv_error_set(VV_ERR_LIMIT, "components: more than %u components",
                                     UINT32_MAX - 1);
                    break;
                }
                C.run_label[q] = (uint32_t)++nlab;
            } else {
                C.run_label[q] = C.run_label[root];
            }
        }
    }
    if (s == VV_OK && sizes) {
        sz = calloc(nlab + 1, sizeof *sz);
        if (!sz)
            s = vv_error_set(VV_ERR_NOMEM, "components: out of memory");
        else {
            uint64_t fg = 0;
            for (size_t q = 0; q < nruns; q++) {
                sz[C.run_label[q]] += (uint64_t)(C.re[q] - C.rs[q]);
                fg += (uint64_t)(C.re[q] - C.rs[q]);
            }
            sz[0] = (uint64_t)rows * dims[0] - fg;
        }
    }
    if (s == VV_OK && labels)
        s = vf_parallel(o, rows, 64, cc_write, &C, p0 + 3 * dp, p1);
    free(C.rowstart);
    free(C.rs);
    free(C.re);
    free(C.parent);
    free(C.run_label);
    free(C.slab_k0);
    if (s != VV_OK) {
        free(sz);
        return s;
    }
    if (sizes)
        *sizes = sz;
    if (count)
        *count = nlab;
    return VV_OK;
}

typedef struct narrow_ctx {
    const uint32_t *l;
    void *d;
    vv_voxel_type t;
    size_t n0;
} narrow_ctx;

static void
narrow_body(void *cp, long r0, long r1, int w) {
    (void)w;
    narrow_ctx *C = cp;
    for (size_t q = (size_t)r0 * C->n0; q < (size_t)r1 * C->n0; q++) {
        if (C->t == VV_U8)
            ((uint8_t *)C->d)[q] = (uint8_t)C->l[q];
        else
            ((uint16_t *)C->d)[q] = (uint16_t)C->l[q];
    }
}

vv_status
vv_filter_components(const vv_volume *in, int connectivity, vv_voxel_type label_type,
                     const vv_filter_options *o, vv_volume **labels, uint64_t **sizes,
                     uint64_t *count) {
    vv_status s = vf_check_io(in, labels, "components");
    if (s != VV_OK)
        return s;
    if (label_type != VV_U8 && label_type != VV_U16 && label_type != VV_U32)
        return vv_error_set(VV_ERR_INVALID, "components: label type %s: must be u8, u16 or u32",
                            vv_voxel_type_name(label_type));
    if (connectivity != 6 && connectivity != 18 && connectivity != 26)
        return vv_error_set(VV_ERR_INVALID, "components: connectivity %d: must be 6, 18 or 26",
                            connectivity);
    uint8_t *mask = NULL;
    vv_volume *v = NULL;
    uint32_t *lab = NULL;
    uint64_t *sz = NULL, nlab = 0;
    /* a u8 volume is its own mask (non-zero = foreground) */
    if (in->type != VV_U8 && (s = vf_mask_u8(in, o, &mask)) != VV_OK)
        return s;
    if ((s = vf_new_like(in, in->dims, label_type, &v)) != VV_OK) {
        free(mask);
        return s;
    }
    if (label_type == VV_U32)
        lab = v->data;
    else if (!(lab = calloc((size_t)vv_volume_voxel_count(in), sizeof *lab)))
        s = vv_error_set(VV_ERR_NOMEM, "components: out of memory");
    if (s == VV_OK)
        s = vf_label_mask(mask ? mask : in->data, in->dims, connectivity, o, 0, 0.95, lab, &sz,
                          &nlab);
    free(mask);
    uint64_t maxl = label_type == VV_U8 ? 255 : label_type == VV_U16 ? 65535 : UINT32_MAX;
    if (s == VV_OK && nlab > maxl)
        s = vv_error_set(VV_ERR_LIMIT,
                         "components: %llu components do not fit %s labels (at most %llu); use "
                         "a wider label type",
                         (unsigned long long)nlab, vv_voxel_type_name(label_type),
                         (unsigned long long)maxl);
    if (s == VV_OK && label_type != VV_U32) {
        narrow_ctx N = {lab, v->data, label_type, (size_t)in->dims[0]};
        s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 64, narrow_body, &N, 0.95, 1);
    }
    if (label_type != VV_U32)
        free(lab);
    if (s != VV_OK) {
        free(sz);
        vv_volume_free(v);
        return s;
    }
    v->range[0] = 0;
    v->range[1] = (double)nlab;
    v->modified++;
    *labels = v;
    if (sizes)
        *sizes = sz;
    else
        free(sz);
    if (count)
        *count = nlab;
    return VV_OK;
}

/* Keeps the labels with keep[label] set, as a u8 mask. */
typedef struct keep_ctx {
    const uint32_t *l;
    const uint8_t *keep;
    uint8_t *d;
    const uint8_t *also; /* or NULL: voxels set here are kept too */
    size_t n0;
} keep_ctx;

static void
keep_body(void *cp, long r0, long r1, int w) {
    (void)w;
    keep_ctx *C = cp;
    for (size_t q = (size_t)r0 * C->n0; q < (size_t)r1 * C->n0; q++)
        C->d[q] = (uint8_t)(C->keep[C->l[q]] || (C->also && C->also[q]));
}

/* Labels of the mask @p mask (of in's dims) into a fresh array; keep[] from @p pick. */
static vv_status
label_and_keep(const vv_volume *in, const uint8_t *mask, int connectivity,
               const vv_filter_options *o,
               vv_status (*pick)(void *u, const uint32_t *lab, const uint64_t *sz, uint64_t n,
                                 uint8_t *keep),
               void *u, const uint8_t *also, vv_volume **out) {
    size_t nv = (size_t)vv_volume_voxel_count(in);
    uint32_t *lab = calloc(nv, sizeof *lab);
    uint64_t *sz = NULL, nlab = 0;
    uint8_t *keep = NULL;
    vv_volume *v = NULL;
    vv_status s = lab ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s == VV_OK)
        s = vf_label_mask(mask, in->dims, connectivity, o, 0, 0.9, lab, &sz, &nlab);
    if (s == VV_OK && !(keep = calloc(nlab + 1, 1)))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s == VV_OK)
        s = pick(u, lab, sz, nlab, keep);
    if (s == VV_OK) {
        keep[0] = 0;
        s = vf_new_like(in, in->dims, VV_U8, &v);
    }
    if (s == VV_OK) {
        keep_ctx K = {lab, keep, v->data, also, (size_t)in->dims[0]};
        s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 64, keep_body, &K, 0.9, 1);
    }
    free(lab);
    free(sz);
    free(keep);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

typedef struct largest_arg {
    int k;
} largest_arg;

static vv_status
pick_largest(void *u, const uint32_t *lab, const uint64_t *sz, uint64_t n, uint8_t *keep) {
    (void)lab;
    int k = ((largest_arg *)u)->k;
    /* k rounds of "largest not yet kept" keep ties on the lower label; k is
     * small in practice, and when k >= n everything is kept */
    if ((uint64_t)k >= n) {
        memset(keep, 1, n + 1);
        return VV_OK;
    }
    for (int r = 0; r < k; r++) {
        uint64_t best = 0;
        for (uint64_t l = 1; l <= n; l++)
            if (!keep[l] && (best == 0 || sz[l] > sz[best]))
                best = l;
        keep[best] = 1;
    }
    return VV_OK;
}

vv_status
vv_filter_largest(const vv_volume *in, int k, int connectivity, const vv_filter_options *o,
                  vv_volume **out) {
    vv_status s = vf_check_io(in, out, "largest");
    if (s != VV_OK)
        return s;
    if (k < 1)
        return vv_error_set(VV_ERR_INVALID, "largest: %d components: must be >= 1", k);
    if (connectivity != 6 && connectivity != 18 && connectivity != 26)
        return vv_error_set(VV_ERR_INVALID, "largest: connectivity %d: must be 6, 18 or 26",
                            connectivity);
    uint8_t *mask;
    if ((s = vf_mask_u8(in, o, &mask)) != VV_OK)
        return s;
    largest_arg A = {k};
    s = label_and_keep(in, mask, connectivity, o, pick_largest, &A, NULL, out);
    free(mask);
    return s;
}

typedef struct seed_arg {
    const int (*seeds)[3];
    int n;
    const int *dims;
} seed_arg;

static vv_status
pick_seeds(void *u, const uint32_t *lab, const uint64_t *sz, uint64_t n, uint8_t *keep) {
    (void)sz;
    (void)n;
    seed_arg *A = u;
    for (int q = 0; q < A->n; q++) {
        const int *p = A->seeds[q];
        keep[lab[((size_t)p[2] * A->dims[1] + p[1]) * A->dims[0] + p[0]]] = 1;
    }
    return VV_OK;
}

vv_status
vv_filter_region_grow(const vv_volume *in, const int (*seeds)[3], int n_seeds, double lo, double hi,
                      int connectivity, const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "region growing");
    if (s != VV_OK)
        return s;
    if (!seeds || n_seeds < 1)
        return vv_error_set(VV_ERR_INVALID, "region growing: no seed voxels");
    if (connectivity != 6 && connectivity != 18 && connectivity != 26)
        return vv_error_set(VV_ERR_INVALID, "region growing: connectivity %d: must be 6, 18 or 26",
                            connectivity);
    if (lo != lo || hi != hi || lo > hi)
        return vv_error_set(VV_ERR_INVALID, "region growing: range %g..%g: need lo <= hi", lo, hi);
    for (int q = 0; q < n_seeds; q++) {
        const int *p = seeds[q];
        if (p[0] < 0 || p[1] < 0 || p[2] < 0 || p[0] >= in->dims[0] || p[1] >= in->dims[1] ||
            p[2] >= in->dims[2])
            return vv_error_set(VV_ERR_INVALID,
                                "region growing: seed %d (%d, %d, %d) is outside the volume "
                                "(%d x %d x %d voxels)",
                                q + 1, p[0], p[1], p[2], in->dims[0], in->dims[1], in->dims[2]);
        double v = vv_volume_get(in, p[0], p[1], p[2]);
        if (!(v >= lo && v <= hi))
            return vv_error_set(VV_ERR_INVALID,
                                "region growing: seed %d (%d, %d, %d) has value %g, outside the "
                                "range %g..%g",
                                q + 1, p[0], p[1], p[2], v, lo, hi);
    }
    vv_volume *m;
    if ((s = vv_filter_threshold(in, lo, hi, o, &m)) != VV_OK)
        return s;
    seed_arg A = {seeds, n_seeds, in->dims};
    s = label_and_keep(in, m->data, connectivity, o, pick_seeds, &A, NULL, out);
    vv_volume_free(m);
    return s;
}

/* ---- morphology ------------------------------------------------------------------------- */

typedef struct morph_ctx {
    const uint8_t *m;
    uint8_t *d;
    int n[3];
    int noff;
    const int (*off)[3];
    int erode;
} morph_ctx;

static void
morph_body(void *cp, long r0, long r1, int w) {
    (void)w;
    morph_ctx *C = cp;
    const int n0 = C->n[0], n1 = C->n[1], n2 = C->n[2];
    for (long r = r0; r < r1; r++) {
        int j = (int)(r % n1), k = (int)(r / n1);
        for (int i = 0; i < n0; i++) {
            int res = C->erode;
            for (int q = 0; q < C->noff; q++) {
                int x = i + C->off[q][0], y = j + C->off[q][1], z = k + C->off[q][2];
                int set = x >= 0 && y >= 0 && z >= 0 && x < n0 && y < n1 && z < n2 &&
                          C->m[((size_t)z * n1 + y) * n0 + x];
                if (C->erode ? !set : set) {
                    res = !C->erode;
                    break;
                }
            }
            C->d[(size_t)r * n0 + i] = (uint8_t)res;
        }
    }
}

static vv_status
morph_pass(const uint8_t *m, uint8_t *d, const int dims[3], const int (*off)[3], int noff,
           int erode, const vv_filter_options *o, double p0, double p1) {
    morph_ctx C = {.m = m, .d = d, .noff = noff, .off = off, .erode = erode};
    memcpy(C.n, dims, sizeof C.n);
    return vf_parallel(o, (long)dims[1] * dims[2], 16, morph_body, &C, p0, p1);
}

vv_status
vv_filter_morphology(const vv_volume *in, vv_morphology op, int radius, const vv_filter_options *o,
                     vv_volume **out) {
    vv_status s = vf_check_io(in, out, "morphology");
    if (s != VV_OK)
        return s;
    if ((int)op < VV_MORPH_ERODE || op > VV_MORPH_CLOSE)
        return vv_error_set(VV_ERR_INVALID, "morphology: unknown operation %d", (int)op);
    if (radius < 1 || radius > VV_FILTER_MAX_RADIUS)
        return vv_error_set(VV_ERR_INVALID, "morphology: radius %d voxels: must be 1..%d", radius,
                            VV_FILTER_MAX_RADIUS);
    int side = 2 * radius + 1;
    int(*off)[3] = malloc((size_t)side * side * side * sizeof *off);
    uint8_t *mask = NULL, *tmp = NULL;
    vv_volume *v = NULL;
    if (!off)
        return vv_error_set(VV_ERR_NOMEM, "morphology: out of memory");
    int noff = 0;
    /* the centre first: it decides most voxels at once */
    off[noff][0] = off[noff][1] = off[noff][2] = 0;
    noff++;
    for (int z = -radius; z <= radius; z++)
        for (int y = -radius; y <= radius; y++)
            for (int x = -radius; x <= radius; x++)
                if ((x || y || z) && x * x + y * y + z * z <= radius * radius) {
                    off[noff][0] = x;
                    off[noff][1] = y;
                    off[noff][2] = z;
                    noff++;
                }
    if ((s = vf_mask_u8(in, o, &mask)) == VV_OK)
        s = vf_new_like(in, in->dims, VV_U8, &v);
    if (s == VV_OK && (op == VV_MORPH_OPEN || op == VV_MORPH_CLOSE) &&
        !(tmp = malloc((size_t)vv_volume_voxel_count(in))))
        s = vv_error_set(VV_ERR_NOMEM, "morphology: out of memory");
    if (s == VV_OK) {
        if (op == VV_MORPH_ERODE || op == VV_MORPH_DILATE) {
            s = morph_pass(mask, v->data, in->dims, (const int(*)[3])off, noff,
                           op == VV_MORPH_ERODE, o, 0, 1);
        } else {
            int first_erode = op == VV_MORPH_OPEN;
            s = morph_pass(mask, tmp, in->dims, (const int(*)[3])off, noff, first_erode, o, 0, 0.5);
            if (s == VV_OK)
                s = morph_pass(tmp, v->data, in->dims, (const int(*)[3])off, noff, !first_erode, o,
                               0.5, 1);
        }
    }
    free(off);
    free(mask);
    free(tmp);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

typedef struct border_arg {
    const int *dims;
} border_arg;

/* keeps the background components that do NOT touch a face */
static vv_status
pick_enclosed(void *u, const uint32_t *lab, const uint64_t *sz, uint64_t n, uint8_t *keep) {
    (void)sz;
    const int *d = ((border_arg *)u)->dims;
    memset(keep, 1, n + 1);
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++) {
            size_t row = ((size_t)k * d[1] + j) * d[0];
            if (k == 0 || k == d[2] - 1 || j == 0 || j == d[1] - 1) {
                for (int i = 0; i < d[0]; i++)
                    keep[lab[row + i]] = 0;
            } else {
                keep[lab[row]] = 0;
                keep[lab[row + d[0] - 1]] = 0;
            }
        }
    return VV_OK;
}

vv_status
vv_filter_fill_holes(const vv_volume *in, const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "fill holes");
    if (s != VV_OK)
        return s;
    uint8_t *mask;
    if ((s = vf_mask_u8(in, o, &mask)) != VV_OK)
        return s;
    size_t nv = (size_t)vv_volume_voxel_count(in);
    uint8_t *bg = malloc(nv);
    if (!bg) {
        free(mask);
        return vv_error_set(VV_ERR_NOMEM, "fill holes: out of memory");
    }
    for (size_t q = 0; q < nv; q++)
        bg[q] = !mask[q];
    border_arg A = {in->dims};
    s = label_and_keep(in, bg, 6, o, pick_enclosed, &A, mask, out);
    free(bg);
    free(mask);
    return s;
}
