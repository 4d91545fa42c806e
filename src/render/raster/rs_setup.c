/*
 * The rasterizer's stage 2: triangles in contiguous chunks, trivially
 * rejected by their outcodes or clipped (Sutherland-Hodgman in homogeneous
 * clip space, cut planes in world space), culled by their snapped screen
 * area, and binned into tiles.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "render/raster/rs_internal.h"
#include "volvis/raster.h"

/* ---------------------------------------------------------------------- */
/* Triangle set-up and binning                                              */

/* Culls and bins one screen triangle. lam (may be NULL: the identity) gives
 * each vertex's barycentric coordinates in the original triangle; edges:
 * bit i for the edge v_i -> v_(i+1). */
static void
emit_triangle(const rs_setup *s, rs_chunk *ch, const rs_svert *v0, const rs_svert *v1,
              const rs_svert *v2, float lam[3][3], uint32_t prim, uint32_t edges) {
    const vv_raster *r = s->r;
    /* pixels whose centres (p + 1/2) lie in the bounding box (arithmetic
     * shifts floor); most triangles of a fine mesh have none */
    int32_t minx = v0->X < v1->X ? v0->X : v1->X, maxx = v0->X > v1->X ? v0->X : v1->X;
    int32_t miny = v0->Y < v1->Y ? v0->Y : v1->Y, maxy = v0->Y > v1->Y ? v0->Y : v1->Y;
    minx = v2->X < minx ? v2->X : minx;
    maxx = v2->X > maxx ? v2->X : maxx;
    miny = v2->Y < miny ? v2->Y : miny;
    maxy = v2->Y > maxy ? v2->Y : maxy;
    int px0 = (minx - RS_SUB / 2 + RS_SUB - 1) >> 8, px1 = (maxx - RS_SUB / 2) >> 8;
    int py0 = (miny - RS_SUB / 2 + RS_SUB - 1) >> 8, py1 = (maxy - RS_SUB / 2) >> 8;
    if (s->wire) {
        px0--;
        py0--;
        px1++;
        py1++;
    }
    px0 = px0 < 0 ? 0 : px0;
    py0 = py0 < 0 ? 0 : py0;
    px1 = px1 > r->w - 1 ? r->w - 1 : px1;
    py1 = py1 > r->h - 1 ? r->h - 1 : py1;
    if (px0 > px1 || py0 > py1)
        return;
    const int64_t A = ((int64_t)v1->X - v0->X) * ((int64_t)v2->Y - v0->Y) -
                      ((int64_t)v1->Y - v0->Y) * ((int64_t)v2->X - v0->X);
    if (A == 0)
        return;
    /* y points down on screen: a triangle counter-clockwise in the image
     * (front facing) has a negative area here */
    const int front = A < 0;
    if ((front && s->cull_front) || (!front && s->cull_back))
        return;
    const uint32_t back = front == s->flip ? RS_BACK : 0;
    prim |= back;
    rs_stri t;
    const rs_svert *v[3] = {v0, v1, v2};
    int order[3] = {0, 1, 2};
    t.flags = edges;
    if (A < 0) {
        order[1] = 2;
        order[2] = 1;
        /* edges v0->v1, v1->v2, v2->v0 become v0->v2 (old bit 2), v2->v1 (1), v1->v0 (0) */
        t.flags = ((edges & 1u) << 2) | (edges & 2u) | ((edges >> 2) & 1u);
        if (!lam)
            t.flags |= RS_SWAPPED;
    }
    for (int i = 0; i < 3; i++) {
        const rs_svert *q = v[order[i]];
        t.X[i] = q->X;
        t.Y[i] = q->Y;
        t.key[i] = q->key;
        t.iw[i] = q->iw;
    }
    t.px0 = (int16_t)px0;
    t.px1 = (int16_t)px1;
    t.py0 = (int16_t)py0;
    t.py1 = (int16_t)py1;
    t.prim = prim;
    t.lam = RS_NONE;
    if (!s->wire && px0 == px1 && py0 == py1) {
        /* one candidate pixel centre: test and interpolate it now */
        const int64_t Px = (int64_t)px0 * RS_SUB + RS_SUB / 2,
                      Py = (int64_t)py0 * RS_SUB + RS_SUB / 2;
        int64_t E[3];
        for (int e = 0; e < 3; e++) {
            const int a = (e + 1) % 3, b = (e + 2) % 3;
            const int64_t dx = (int64_t)t.X[b] - t.X[a], dy = (int64_t)t.Y[b] - t.Y[a];
            E[e] = -dy * (Px - t.X[a]) + dx * (Py - t.Y[a]);
            if (E[e] < 0 || (E[e] == 0 && !top_left(dx, dy)))
                return;
        }
        const float invA = 1.0f / (float)(A < 0 ? -A : A);
        const float b0 = (float)E[0] * invA, b1 = (float)E[1] * invA, b2 = (float)E[2] * invA;
        float L[9];
        if (lam)
            for (int i = 0; i < 3; i++)
                for (int k = 0; k < 3; k++)
                    L[3 * i + k] = lam[order[i]][k];
        rs_pix f;
        store_fragment(&f, &t, lam ? L : NULL, b0 * t.key[0] + b1 * t.key[1] + b2 * t.key[2], b0,
                       b1, b2, prim);
        if (!grow_buf((void **)&ch->frags, &ch->cap_frags, ch->n_frags + 1, sizeof *ch->frags) ||
            !grow_buf((void **)&ch->ent, &ch->cap_ent, 2 * (ch->n_ent + 1), sizeof(uint32_t))) {
            ch->err = 1;
            return;
        }
        rs_frag *fr = &ch->frags[ch->n_frags];
        fr->pixel = (uint32_t)py0 * (uint32_t)r->w + (uint32_t)px0;
        fr->key = f.key;
        fr->prim = prim;
        fr->l1 = f.l1;
        fr->l2 = f.l2;
        ch->ent[2 * ch->n_ent] = (uint32_t)((py0 / RS_TILE) * r->tx + px0 / RS_TILE);
        ch->ent[2 * ch->n_ent + 1] = (uint32_t)ch->n_frags | RS_FRAG;
        ch->n_ent++;
        ch->n_frags++;
        return;
    }
    if (lam) {
        if (!grow_buf((void **)&ch->lams, &ch->cap_lams, ch->n_lams + 9, sizeof(float))) {
            ch->err = 1;
            return;
        }
        t.lam = (uint32_t)(ch->n_lams / 9);
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                ch->lams[ch->n_lams + 3 * (size_t)i + (size_t)k] = lam[order[i]][k];
        ch->n_lams += 9;
    }
    const int tx0 = px0 / RS_TILE, tx1 = px1 / RS_TILE;
    const int ty0 = py0 / RS_TILE, ty1 = py1 / RS_TILE;
    const size_t nent = (size_t)(tx1 - tx0 + 1) * (size_t)(ty1 - ty0 + 1);
    if (!grow_buf((void **)&ch->tris, &ch->cap_tris, ch->n_tris + 1, sizeof *ch->tris) ||
        !grow_buf((void **)&ch->ent, &ch->cap_ent, 2 * (ch->n_ent + nent), sizeof(uint32_t))) {
        ch->err = 1;
        return;
    }
    const uint32_t idx = (uint32_t)ch->n_tris;
    ch->tris[ch->n_tris++] = t;
    for (int ty = ty0; ty <= ty1; ty++)
        for (int tx = tx0; tx <= tx1; tx++) {
            ch->ent[2 * ch->n_ent] = (uint32_t)(ty * r->tx + tx);
            ch->ent[2 * ch->n_ent + 1] = idx;
            ch->n_ent++;
        }
}

/* Signed distance of a polygon vertex to clip plane k (>= 0: kept). */
static inline double
plane_dist(const vv_raster *r, int k, const rs_cvert *v) {
    const double *c = v->c;
    const double g = r->gb;
    switch (k) {
    case 0:
        return c[2] + c[3]; /* near */
    case 1:
        return c[3] - c[2]; /* far */
    case 2:
        return g * c[3] - c[0];
    case 3:
        return g * c[3] + c[0];
    case 4:
        return g * c[3] - c[1];
    case 5:
        return g * c[3] + c[1];
    default: {
        const double *pl = r->oplanes[k - 6];
        return pl[0] * v->p[0] + pl[1] * v->p[1] + pl[2] * v->p[2] + pl[3];
    }
    }
}

/* Clips the triangle against the planes in @p mask and emits the fan. */
static void
clip_triangle(const rs_setup *s, rs_chunk *ch, const uint32_t vi[3], uint32_t prim, uint32_t mask) {
    const vv_raster *r = s->r;
    rs_cvert buf[2][RS_MAX_POLY];
    rs_cvert *in = buf[0], *out = buf[1];
    int n = 3;
    for (int i = 0; i < 3; i++) {
        const float *cc = r->clip + 4 * (size_t)vi[i];
        const float *p = s->d->mesh->positions + 3 * (size_t)vi[i];
        for (int k = 0; k < 4; k++)
            in[i].c[k] = cc[k];
        for (int k = 0; k < 3; k++) {
            in[i].p[k] = p[k];
            in[i].lam[k] = k == i ? 1.0f : 0.0f;
        }
        in[i].edge = 1;
    }
    for (int k = 0; k < 6 + r->n_planes && n >= 3; k++) {
        if (!(mask & (1u << k)))
            continue;
        double dist[RS_MAX_POLY];
        for (int i = 0; i < n; i++)
            dist[i] = plane_dist(r, k, &in[i]);
        int m = 0;
        for (int i = 0; i < n; i++) {
            const rs_cvert *a = &in[i], *b = &in[(i + 1) % n];
            const double da = dist[i], db = dist[(i + 1) % n];
            const int ain = da >= 0, bin = db >= 0;
            if (ain)
                out[m++] = *a;
            if (ain != bin) {
                const double t = da / (da - db);
                rs_cvert *v = &out[m++];
                for (int q = 0; q < 4; q++)
                    v->c[q] = a->c[q] + t * (b->c[q] - a->c[q]);
                for (int q = 0; q < 3; q++) {
                    v->p[q] = a->p[q] + t * (b->p[q] - a->p[q]);
                    v->lam[q] = (float)(a->lam[q] + t * (b->lam[q] - a->lam[q]));
                }
                /* entering: I -> b is part of a -> b; leaving: I runs along the plane */
                v->edge = ain ? 0 : a->edge;
            }
        }
        rs_cvert *tmp = in;
        in = out;
        out = tmp;
        n = m;
    }
    rs_svert sv[RS_MAX_POLY];
    for (int i = 0; i < n; i++)
        project(r, in[i].c, &sv[i]);
    for (int i = 1; i + 1 < n; i++) {
        float lam[3][3];
        const rs_cvert *v[3] = {&in[0], &in[i], &in[i + 1]};
        for (int j = 0; j < 3; j++)
            memcpy(lam[j], v[j]->lam, sizeof lam[j]);
        uint32_t edges = (uint32_t)in[i].edge << 1;
        if (i == 1)
            edges |= (uint32_t)in[0].edge;
        if (i + 2 == n)
            edges |= (uint32_t)in[n - 1].edge << 2;
        emit_triangle(s, ch, &sv[0], &sv[i], &sv[i + 1], lam, prim, edges);
    }
}

/* Triangles [t0, t1) of the draw into chunk @p ch, then its entries sorted by tile. */
void
rs_setup_chunk(const rs_setup *s, rs_chunk *ch, size_t t0, size_t t1) {
    const vv_raster *r = s->r;
    ch->n_tris = ch->n_frags = ch->n_lams = ch->n_ent = 0;
    ch->err = 0;
    for (size_t t = t0; t < t1 && !ch->err; t++) {
        const uint32_t vi[3] = {s->tri[3 * t], s->tri[3 * t + 1], s->tri[3 * t + 2]};
        if (vi[0] >= s->n_vertices || vi[1] >= s->n_vertices || vi[2] >= s->n_vertices) {
            ch->err = 2;
            return;
        }
        const int32_t *A = r->sxy + 2 * (size_t)vi[0], *B = r->sxy + 2 * (size_t)vi[1],
                      *C = r->sxy + 2 * (size_t)vi[2];
        if (A[0] == RS_OFF || B[0] == RS_OFF || C[0] == RS_OFF) {
            const uint32_t o0 = r->oc[vi[0]], o1 = r->oc[vi[1]], o2 = r->oc[vi[2]];
            const uint32_t any = o0 | o1 | o2;
            if ((o0 & o1 & o2) || (any & RS_OC_BAD))
                continue; /* outside one plane, or a vertex that is not a finite point */
            clip_triangle(s, ch, vi, (uint32_t)t, any);
            continue;
        }
        if (!s->wire) {
            /* the common case of a fine mesh, without a call: no pixel
             * centre between the extreme x (or y) of the vertices */
            int32_t lo = A[0] < B[0] ? A[0] : B[0], hi = A[0] > B[0] ? A[0] : B[0];
            lo = C[0] < lo ? C[0] : lo;
            hi = C[0] > hi ? C[0] : hi;
            if (((lo - RS_SUB / 2 + RS_SUB - 1) >> 8) > ((hi - RS_SUB / 2) >> 8))
                continue;
            lo = A[1] < B[1] ? A[1] : B[1];
            hi = A[1] > B[1] ? A[1] : B[1];
            lo = C[1] < lo ? C[1] : lo;
            hi = C[1] > hi ? C[1] : hi;
            if (((lo - RS_SUB / 2 + RS_SUB - 1) >> 8) > ((hi - RS_SUB / 2) >> 8))
                continue;
        }
        rs_svert v[3];
        for (int k = 0; k < 3; k++) {
            const size_t q = 2 * (size_t)vi[k];
            v[k].X = r->sxy[q];
            v[k].Y = r->sxy[q + 1];
            v[k].key = r->skw[q];
            v[k].iw = r->skw[q + 1];
        }
        emit_triangle(s, ch, &v[0], &v[1], &v[2], NULL, (uint32_t)t, 7u);
    }
    if (ch->err)
        return;
    /* counting sort of the entries by tile (stable: draw order within a tile) */
    const int nt = r->n_tiles;
    if (!grow_buf((void **)&ch->sorted, &ch->cap_sorted, ch->n_ent + 1, sizeof(uint32_t))) {
        ch->err = 1;
        return;
    }
    memset(ch->off, 0, ((size_t)nt + 1) * sizeof *ch->off);
    for (size_t e = 0; e < ch->n_ent; e++)
        ch->off[ch->ent[2 * e] + 1]++;
    for (int i = 0; i < nt; i++)
        ch->off[i + 1] += ch->off[i];
    for (size_t e = 0; e < ch->n_ent; e++)
        ch->sorted[ch->off[ch->ent[2 * e]]++] = ch->ent[2 * e + 1];
    /* off[i] now ends tile i; shift back so that tile i is [off[i], off[i + 1]) */
    for (int i = nt; i > 0; i--)
        ch->off[i] = ch->off[i - 1];
    ch->off[0] = 0;
}
