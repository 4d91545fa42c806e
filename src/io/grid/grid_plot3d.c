/*
 * PLOT3D grid (.xyz, .bin) and solution (.q) files: whole-grid binary
 * ("PLOT3D User's Manual", NASA TM 101067, chapter 8), single or
 * multi-block, with or without Fortran record markers, either byte order,
 * single or double precision, with or without IBLANK. The layout is not
 * written in the file, so every combination is tried and the one whose
 * size equals the file's is taken (a solution may carry a few trailing
 * bytes, as bluntfinq.bin does); a file no layout fits is an error that
 * says so. The grid is curvilinear: each block's hexahedra are stored with
 * its dimensions; the solution adds the point fields density, momentum
 * (a vector), energy, and the derived velocity magnitude and pressure
 * (gamma 1.4); points blanked by IBLANK 0 are missing there.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/internal.h"
#include "io/grid/grid_io_internal.h"
#include "io/io_internal.h"
#include "volvis/grid.h"
#include "volvis/sys/format.h"

#define P3D_FILE_MAX (4ull << 30)
#define P3D_TRAILING_OK 1024 /* bytes a solution may carry beyond its records */

typedef struct p3d_layout {
    int big_endian, markers, multi, iblank, dbl;
    int nb;
    int (*dims)[3];
    size_t data_off; /* where the first block's record starts (after its marker) */
} p3d_layout;

static uint32_t
u32(const unsigned char *p, int be) {
    return be ? (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]
              : (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

/* Reads the block count and dimensions for one guess of byte order,
 * markers and block structure; 0 when they are implausible. */
static int
p3d_dims(const unsigned char *d, size_t size, int be, int markers, int multi, p3d_layout *L) {
    size_t o = 0;
    const size_t mk = markers ? 4 : 0;
    int nb = 1;
    if (multi) {
        if (size < o + mk + 4 + mk)
            return 0;
        if (markers && u32(d, be) != 4)
            return 0;
        nb = (int)u32(d + mk, be);
        o += mk + 4 + mk;
        if (nb < 1 || nb > VV_GRID_MAX_BLOCKS)
            return 0;
    }
    const size_t dl = 12 * (size_t)nb;
    if (size < o + mk + dl + mk)
        return 0;
    if (markers && (u32(d + o, be) != dl || u32(d + o + mk + dl, be) != dl))
        return 0;
    int(*dims)[3] = malloc((size_t)nb * sizeof *dims);
    if (!dims)
        return 0;
    /* at most VV_GRID_MAX_POINTS points in all, so that p3d_size cannot
       wrap (2^20 cubed with IBLANK needed 16 * 2^60 bytes: 0 modulo 2^64) */
    uint64_t points = 0;
    for (int b = 0; b < nb; b++) {
        uint64_t n = 1;
        for (int a = 0; a < 3; a++) {
            const uint32_t v = u32(d + o + mk + 12 * (size_t)b + 4 * (size_t)a, be);
            if (v < 1 || v > (1u << 20)) {
                free(dims);
                return 0;
            }
            dims[b][a] = (int)v;
            n *= v;
            if (n > VV_GRID_MAX_POINTS) {
                free(dims);
                return 0;
            }
        }
        if ((points += n) > VV_GRID_MAX_POINTS) {
            free(dims);
            return 0;
        }
    }
    o += mk + dl + mk;
    L->big_endian = be;
    L->markers = markers;
    L->multi = multi;
    L->nb = nb;
    L->dims = dims;
    L->data_off = o;
    return 1;
}

/* Bytes of the file under layout L with per-block records of
 * (nvals * n + extra) values. */
static size_t
p3d_size(const p3d_layout *L, int nvals, int iblank, size_t header_vals, int ps) {
    size_t t = L->data_off;
    for (int b = 0; b < L->nb; b++) {
        const size_t n = (size_t)L->dims[b][0] * (size_t)L->dims[b][1] * (size_t)L->dims[b][2];
        if (header_vals)
            t += (L->markers ? 8 : 0) + header_vals * (size_t)ps;
        t += (L->markers ? 8 : 0) + (size_t)nvals * n * (size_t)ps + (iblank ? 4 * n : 0);
    }
    return t;
}

/* Finds the layout of a grid (is_q 0: 3 values + optional iblank per point)
 * or solution (is_q 1: 4 header values, then 5 per point). */
static vv_status
p3d_layout_find(const unsigned char *d, size_t size, const char *path, int is_q, p3d_layout *out) {
    int found = 0;
    size_t expect_any = 0;
    for (int exact = 1; exact >= 0 && !found; exact--)
        for (int be = 1; be >= 0 && !found; be--)
            for (int markers = 0; markers < 2 && !found; markers++)
                for (int multi = 0; multi < 2 && !found; multi++) {
                    p3d_layout L;
                    memset(&L, 0, sizeof L);
                    if (!p3d_dims(d, size, be, markers, multi, &L))
                        continue;
                    for (int dbl = 0; dbl < 2 && !found; dbl++)
                        for (int ib = 0; ib < (is_q ? 1 : 2) && !found; ib++) {
                            const size_t t =
                                p3d_size(&L, is_q ? 5 : 3, ib, is_q ? 4 : 0, dbl ? 8 : 4);
                            expect_any = t;
                            if (t == size ||
                                (!exact && is_q && t < size && size - t <= P3D_TRAILING_OK)) {
                                L.iblank = ib;
                                L.dbl = dbl;
                                *out = L;
                                found = 1;
                            }
                        }
                    if (!found)
                        free(L.dims);
                }
    if (!found)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: no PLOT3D layout (byte order, record markers, blocks, "
                            "precision, IBLANK) fits its %zu bytes (the last guess needed %zu)",
                            path, size, expect_any);
    return VV_OK;
}

static double
p3d_val(const unsigned char *p, const p3d_layout *L) {
    return vv_gtype_get(p, L->dbl ? VV_GT_F64 : VV_GT_F32, L->big_endian);
}

vv_status
vv_grid_read_plot3d(vv_grid **out, const char *xyz_path, const char *q_path) {
    *out = NULL;
    unsigned char *d = NULL, *qd = NULL;
    uint64_t size = 0, qsize = 0;
    vv_status s = vv_read_file(xyz_path, P3D_FILE_MAX, &d, &size);
    if (s != VV_OK)
        return s; /* the message names the file */
    p3d_layout L, Q;
    memset(&L, 0, sizeof L);
    memset(&Q, 0, sizeof Q);
    vv_grid *g = NULL;
    double *xyz = NULL;
    unsigned char *blank = NULL; /* IBLANK == 0 per point */
    if ((s = p3d_layout_find(d, (size_t)size, xyz_path, 0, &L)) != VV_OK)
        goto done;
    if ((s = vv_grid_new(&g, VV_GRID_CURVILINEAR)) != VV_OK)
        goto done;
    const int ps = L.dbl ? 8 : 4;
    size_t o = L.data_off, total_points = 0;
    for (int b = 0; b < L.nb; b++)
        total_points += (size_t)L.dims[b][0] * (size_t)L.dims[b][1] * (size_t)L.dims[b][2];
    if (L.iblank && !(blank = calloc(total_points ? total_points : 1, 1))) {
        s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", xyz_path);
        goto done;
    }
    for (int b = 0; b < L.nb; b++) {
        const size_t n = (size_t)L.dims[b][0] * (size_t)L.dims[b][1] * (size_t)L.dims[b][2];
        xyz = malloc(3 * n * sizeof *xyz);
        if (!xyz) {
            s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", xyz_path);
            goto done;
        }
        o += L.markers ? 4 : 0;
        for (size_t i = 0; i < n; i++)
            for (int a = 0; a < 3; a++)
                xyz[3 * i + (size_t)a] = p3d_val(d + o + ((size_t)a * n + i) * (size_t)ps, &L);
        /* IBLANK 0: a blanked point (a hole, or overlapped by another block) */
        for (size_t i = 0; L.iblank && i < n; i++)
            blank[g->n_points + i] =
                vv_gtype_get(d + o + 3 * n * (size_t)ps + 4 * i, VV_GT_I32, L.big_endian) == 0;
        o += 3 * n * (size_t)ps + (L.iblank ? 4 * n : 0) + (L.markers ? 4 : 0);
        if (L.dims[b][0] < 2 || L.dims[b][1] < 2 || L.dims[b][2] < 2) {
            s = vv_error_set(VV_ERR_UNSUPPORTED,
                             "%s: block %d is %dx%dx%d (2-D blocks are not "
                             "supported)",
                             xyz_path, b, L.dims[b][0], L.dims[b][1], L.dims[b][2]);
            goto done;
        }
        if ((s = vv_grid_add_block(g, L.dims[b], xyz)) != VV_OK)
            goto done;
        free(xyz);
        xyz = NULL;
    }
    if (q_path) {
        if ((s = vv_read_file(q_path, P3D_FILE_MAX, &qd, &qsize)) != VV_OK)
            goto done; /* the message names the file */
        if ((s = p3d_layout_find(qd, (size_t)qsize, q_path, 1, &Q)) != VV_OK)
            goto done;
        int same = Q.nb == L.nb;
        for (int b = 0; same && b < L.nb; b++)
            same = !memcmp(Q.dims[b], L.dims[b], sizeof L.dims[b]);
        if (!same) {
            s = vv_error_set(VV_ERR_FORMAT, "%s: the solution's blocks differ from the grid's",
                             q_path);
            goto done;
        }
        static const char *names[] = {"density", "momentum", "energy", "velocity_magnitude",
                                      "pressure"};
        vv_grid_field *f[5];
        const int nc[5] = {1, 3, 1, 1, 1};
        const int base = g->n_fields;
        for (int k = 0; k < 5; k++)
            if ((s = vv_grid_add_field(g, names[k], 0, nc[k], &f[k])) != VV_OK)
                goto done;
        /* adding a field may move the others: take the pointers now */
        for (int k = 0; k < 5; k++)
            f[k] = &g->fields[base + k];
        const int qs = Q.dbl ? 8 : 4;
        size_t qo = Q.data_off, p0 = 0;
        for (int b = 0; b < Q.nb; b++) {
            const size_t n = (size_t)Q.dims[b][0] * (size_t)Q.dims[b][1] * (size_t)Q.dims[b][2];
            qo += (Q.markers ? 8 : 0) + 4 * (size_t)qs; /* fsmach, alpha, re, time */
            qo += Q.markers ? 4 : 0;
            for (size_t i = 0; i < n; i++) {
                double q[5];
                for (int k = 0; k < 5; k++) {
                    q[k] = vv_gtype_get(qd + qo + ((size_t)k * n + i) * (size_t)qs,
                                        Q.dbl ? VV_GT_F64 : VV_GT_F32, Q.big_endian);
                }
                const size_t p = p0 + i;
                f[0]->values[p] = (float)q[0];
                for (int a = 0; a < 3; a++)
                    f[1]->values[3 * p + (size_t)a] = (float)q[1 + a];
                f[2]->values[p] = (float)q[4];
                const double rho = q[0];
                const double v2 =
                    rho != 0 ? (q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) / (rho * rho) : 0;
                f[3]->values[p] = (float)sqrt(v2);
                f[4]->values[p] = (float)(0.4 * (q[4] - 0.5 * rho * v2));
            }
            qo += 5 * n * (size_t)qs + (Q.markers ? 4 : 0);
            p0 += n;
        }
        /* blanked points carry no data: missing, transparent */
        for (size_t p = 0; blank && p < g->n_points; p++)
            if (blank[p])
                for (int k = 0; k < 5; k++)
                    for (int c = 0; c < f[k]->n_components; c++)
                        f[k]->values[p * (size_t)f[k]->n_components + (size_t)c] = NAN;
    }
done:
    free(xyz);
    free(blank);
    free(L.dims);
    free(Q.dims);
    free(d);
    free(qd);
    if (s != VV_OK) {
        vv_grid_free(g);
        return s;
    }
    return vv_grid_finish(g, xyz_path, out);
}

/* ---- the format record ------------------------------------------------------ */

/* PLOT3D has no signature: a grid named *.xyz or *xyz.bin, asked only
 * after every format with one said no. */
static int
plot3d_looks_like(const vv_format_probe *p, int deep) {
    const size_t n = strlen(p->path);
    return deep && ((n >= 4 && !strcasecmp(p->path + n - 4, ".xyz")) ||
                    (n >= 7 && !strcasecmp(p->path + n - 7, "xyz.bin")));
}

/* The grid with its solution beside it when there is one: xxxxyz.bin ->
 * xxxq.bin, x.xyz -> x.q. */
static vv_status
plot3d_read_record(vv_grid **out, const char *path) {
    char q[4096];
    snprintf(q, sizeof q, "%s", path);
    size_t n = strlen(q);
    int have = 0;
    if (n >= 7 && !strcasecmp(q + n - 7, "xyz.bin")) {
        snprintf(q + n - 7, sizeof q - (n - 7), "q.bin");
        have = 1;
    } else if (n >= 4 && !strcasecmp(q + n - 4, ".xyz")) {
        snprintf(q + n - 4, sizeof q - (n - 4), ".q");
        have = 1;
    }
    FILE *fp = have ? fopen(q, "rb") : NULL;
    if (fp)
        fclose(fp);
    return vv_grid_read_plot3d(out, path, fp ? q : NULL);
}

static const char *const plot3d_extensions[] = {"xyz", "bin", NULL};

const vv_format_record vv_format_plot3d = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "plot3d",
    .title = "PLOT3D",
    .extensions = plot3d_extensions,
    .doc = "PLOT3D grid with its solution beside it (*.q, *q.bin): blocks, IBLANK",
    .holds = VV_DATA_GRID,
    .looks_like = plot3d_looks_like,
    .read_grid = plot3d_read_record,
};
