/*
 * Volumetric ray tracing: shadow grids kept between frames. A volume
 * sample's shadow comes from a grid of shadow rays, one every RT_SGRID
 * voxels of the volume (rt_shade.c): a lazily filled one, or one swept from
 * the light's side (shadow_grid=2). A grid point's transmittance depends on
 * the point (the receiving volume's transform), the light, and everything
 * that casts shadows, but not on the view: the renderer state keeps the
 * grids of the last frame, keyed on exactly that, so that a new view of the
 * same World reuses the shadow rays traced before and traces only the grid
 * points it newly needs. The key is the bytes of every input of a shadow
 * ray (geometry, transforms, volumes by address and modification count,
 * with a reference held, their transfer-function tables, cut planes, the
 * step), compared whole: an entry is reused only for the same rays.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "render/raytrace/rt_internal.h"
#include "volvis/mesh.h"

/* ---------------------------------------------------------------------- */
/* Keys                                                                      */

typedef struct rt_key {
    unsigned char *b;
    size_t n, cap;
    int nomem;
} rt_key;

static void
key_put(rt_key *k, const void *p, size_t n) {
    if (k->nomem || !n)
        return;
    if (k->n + n > k->cap) {
        size_t cap = k->cap ? k->cap : 4096;
        while (cap < k->n + n)
            cap *= 2;
        unsigned char *b = realloc(k->b, cap);
        if (!b) {
            k->nomem = 1;
            return;
        }
        k->b = b;
        k->cap = cap;
    }
    memcpy(k->b + k->n, p, n);
    k->n += n;
}

#define KEY(k, x) key_put((k), &(x), sizeof(x))

/* A 64-bit fingerprint of a mesh's vertices and triangles (meshes carry no
 * modification count): multiply-xorshift over 8-byte words. */
static uint64_t
mesh_fingerprint(const vv_mesh *m) {
    uint64_t h = 0x9E3779B97F4A7C15ull ^ m->n_vertices ^ (m->n_triangles << 32);
    const struct {
        const void *p;
        size_t n;
    } parts[2] = {{m->positions, 3 * m->n_vertices * sizeof(float)},
                  {m->triangles, 3 * m->n_triangles * sizeof(uint32_t)}};
    for (int i = 0; i < 2; i++) {
        const unsigned char *p = parts[i].p;
        size_t n = p ? parts[i].n : 0, j = 0;
        for (; j + 8 <= n; j += 8) {
            uint64_t w;
            memcpy(&w, p + j, 8);
            h = (h ^ w) * 0xBF58476D1CE4E5B9ull;
            h ^= h >> 31;
        }
        for (; j < n; j++)
            h = (h ^ p[j]) * 0x94D049BB133111EBull;
    }
    return h;
}

static void
key_geometry(rt_key *k, const rt_gobj *g) {
    const vv_geometry *ge = &g->obj->geometry;
    KEY(k, g->type);
    KEY(k, g->w2o);
    KEY(k, g->kt);
    KEY(k, ge->center);
    KEY(k, ge->radius);
    KEY(k, ge->point);
    KEY(k, ge->normal);
    KEY(k, ge->box);
    KEY(k, ge->base);
    KEY(k, ge->top);
    KEY(k, ge->capped);
    KEY(k, ge->n_vertices);
    if (ge->vertices && ge->n_vertices > 0)
        key_put(k, ge->vertices, (size_t)ge->n_vertices * sizeof *ge->vertices);
    const uint64_t mf = ge->mesh ? mesh_fingerprint(ge->mesh) : 0;
    KEY(k, mf);
}

/* What a shadow ray reads of a volume (volume_transmittance): the volume
 * itself (by address and modification count; the entry holds a reference),
 * its placement, cut planes, mode and tables, and its light volumes. */
static void
key_volume(rt_key *k, const rt_frame *fr, const rt_vobj *ob) {
    const vv_volume *v = ob->obj->volume;
    KEY(k, v);
    KEY(k, v->modified);
    KEY(k, ob->mode);
    KEY(k, ob->w2i);
    KEY(k, ob->dims);
    KEY(k, ob->vox);
    KEY(k, ob->iso);
    KEY(k, ob->n_planes);
    key_put(k, ob->planes, (size_t)ob->n_planes * sizeof *ob->planes);
    KEY(k, ob->tab.lut_lo);
    KEY(k, ob->tab.lut_scale);
    unsigned lv = 0;
    for (int l = 0; l < fr->n_lights; l++)
        lv |= ob->lvol[l] ? 1u << l : 0u;
    KEY(k, lv);
    const size_t nb = (size_t)ob->bx * (size_t)ob->by * (size_t)ob->bz;
    const int has[4] = {ob->ext != NULL, ob->lut != NULL, ob->bvis != NULL, ob->bdist != NULL};
    KEY(k, has);
    if (ob->ext)
        key_put(k, ob->ext, VV_VC_LUT * sizeof *ob->ext);
    if (ob->lut)
        key_put(k, ob->lut, 4 * VV_VC_LUT * sizeof *ob->lut);
    if (ob->bvis)
        key_put(k, ob->bvis, nb);
    if (ob->bdist)
        key_put(k, ob->bdist, nb);
}

/* The part of the key every grid of the frame shares: the step, the
 * light-volume switch and every object that casts shadows. */
static vv_status
scene_key(rt_frame *fr) {
    rt_key k = {0};
    const int lvs = fr->st->light_volumes;
    KEY(&k, fr->dt);
    KEY(&k, lvs);
    KEY(&k, fr->n_lights);
    for (int i = 0; i < fr->n_gobj; i++)
        if (fr->gobjs[i].obj->casts_shadows)
            key_geometry(&k, &fr->gobjs[i]);
    const int sep = -1;
    KEY(&k, sep);
    fr->n_svols = 0;
    for (int i = 0; i < fr->n_vobj; i++) {
        const rt_vobj *ob = &fr->vobjs[i];
        if (!ob->obj->casts_shadows || ob->region)
            continue;
        key_volume(&k, fr, ob);
        fr->svols[fr->n_svols++] = ob->obj->volume;
    }
    if (k.nomem) {
        free(k.b);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a shadow-grid key");
    }
    fr->skey = k.b;
    fr->skey_len = k.n;
    return VV_OK;
}

/* The part of one grid: where its points are and which light it answers. */
static void
grid_key(rt_key *k, const rt_frame *fr, const rt_vobj *ob, int l, int swept) {
    const rt_light *lt = &fr->lights[l];
    KEY(k, swept);
    KEY(k, ob->i2w);
    KEY(k, ob->w2i);
    KEY(k, ob->dims);
    KEY(k, ob->gdim);
    KEY(k, ob->vox);
    KEY(k, lt->point);
    KEY(k, lt->dir);
    KEY(k, lt->pos);
}

/* ---------------------------------------------------------------------- */
/* The cache                                                                 */

void
rt_sg_release(rt_sg *e) {
    for (int i = 0; i < e->n_vols; i++)
        vv_volume_free(e->vols[i]);
    free(e->vols);
    free(e->grid);
    free(e->key);
    memset(e, 0, sizeof *e);
}

/* The grid's whole key (its own part, then the frame's shadow-casting
 * content) in *key; 0 (key->b NULL) when the frame keeps nothing (a region
 * render: its part is not the World's object) or memory ran out. */
static int
whole_key(rt_frame *fr, const rt_vobj *ob, int l, int swept, rt_sgkey *key) {
    memset(key, 0, sizeof *key);
    if (fr->region || fr->skey_failed)
        return 0;
    if (!fr->skey && scene_key(fr) != VV_OK) {
        vv_error_clear();
        fr->skey_failed = 1;
        return 0;
    }
    rt_key k;
    memset(&k, 0, sizeof k);
    grid_key(&k, fr, ob, l, swept);
    key_put(&k, fr->skey, fr->skey_len);
    if (k.nomem) {
        free(k.b);
        return 0;
    }
    key->b = k.b;
    key->n = k.n;
    return 1;
}

void *
rt_sgrid_find(rt_frame *fr, const rt_vobj *ob, int l, int swept, rt_sgkey *key) {
    if (!whole_key(fr, ob, l, swept, key))
        return NULL;
    rt_state *st = fr->st;
    for (int i = 0; i < RT_SG_CACHE; i++) {
        rt_sg *e = &st->sg[i];
        if (e->grid && e->key_len == key->n && memcmp(e->key, key->b, key->n) == 0) {
            e->used = st->frame;
            return e->grid;
        }
    }
    return NULL;
}

void
rt_sgkey_free(rt_sgkey *key) {
    free(key->b);
    memset(key, 0, sizeof *key);
}

int
rt_sgrid_keep(rt_frame *fr, rt_sgkey *key, void *grid) {
    rt_state *st = fr->st;
    const int slot = key->b ? RT_CACHE_SLOT(rt_sg, st->sg, grid, RT_SG_CACHE, st->frame) : -1;
    vv_volume **vols =
        slot >= 0 ? malloc((fr->n_svols ? (size_t)fr->n_svols : 1) * sizeof *vols) : NULL;
    if (!vols) {
        rt_sgkey_free(key);
        return 0;
    }
    rt_sg *e = &st->sg[slot];
    rt_sg_release(e);
    e->key = key->b; /* the entry owns the key now */
    e->key_len = key->n;
    memset(key, 0, sizeof *key);
    for (int i = 0; i < fr->n_svols; i++)
        vols[i] = vv_volume_ref(fr->svols[i]);
    e->vols = vols;
    e->n_vols = fr->n_svols;
    e->grid = grid;
    e->used = st->frame;
    return 1;
}
