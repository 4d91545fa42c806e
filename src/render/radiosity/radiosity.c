/*
 * Volumetric radiosity: elements, hierarchies and the progressive
 * hierarchical solver (Sobierajski and Kaufman 1994; Cohen et al. 1988;
 * Hanrahan, Salzman and Aupperle 1991). See include/volvis/radiosity.h.
 *
 * Power bookkeeping: every shot of a candidate cluster sends its unshot
 * power; what its receivers intercept is split into absorbed (1 - rho) and
 * scattered (rho, unshot again); the rest is counted as escaped. Deposits of
 * one shot are scaled down if the approximate form factors add up to more
 * than the power shot, so the solver never creates energy.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom.h"
#include "render/radiosity/radiosity_internal.h"
#include "volvis/sys/geometry.h"

void
vv_radiosity_options_init(vv_radiosity_options *o) {
    memset(o, 0, sizeof *o);
    o->tolerance = 1e-3;
    o->error = 1e-4;
    o->near = 0.5;
    o->patch_size = 0;
    o->grid = 128;
    o->diffuse_voxels = 1;
    o->max_shots = 20000;
}

static vv_status
check_reflectance(const vv_object *o, vv_vec3 col) {
    const double kd = o->material.diffuse;
    const double v[3] = {kd * col.x, kd * col.y, kd * col.z};
    for (int c = 0; c < 3; c++)
        if (!(v[c] >= 0 && v[c] <= 1))
            return vv_error_set(VV_ERR_INVALID,
                                "object '%s': reflectance (material.diffuse %g * colour %g) = %g "
                                "is outside [0, 1]",
                                o->name, kd, (&col.x)[c], v[c]);
    const double *em = &o->material.emission.x;
    for (int c = 0; c < 3; c++)
        if (!(isfinite(em[c]) && em[c] >= 0))
            return vv_error_set(VV_ERR_INVALID, "object '%s': emission %g is not a power >= 0",
                                o->name, em[c]);
    return VV_OK;
}

static vv_status
check_options(const vv_radiosity_options *o) {
    if (!(o->tolerance > 0 && o->tolerance < 1))
        return vv_error_set(VV_ERR_INVALID, "tolerance %g is not in (0, 1)", o->tolerance);
    if (!(o->error >= 0 && isfinite(o->error)))
        return vv_error_set(VV_ERR_INVALID, "error %g is not a number >= 0", o->error);
    if (!(o->near > 0 && isfinite(o->near)))
        return vv_error_set(VV_ERR_INVALID, "near %g is not a number > 0", o->near);
    if (!(o->patch_size >= 0 || o->patch_size < 0) || !isfinite(o->patch_size))
        return vv_error_set(VV_ERR_INVALID, "patch_size %g is not finite", o->patch_size);
    if (o->grid < 2 || o->grid > 1024)
        return vv_error_set(VV_ERR_INVALID, "grid %d is not in 2..1024", o->grid);
    if (o->max_shots < 1)
        return vv_error_set(VV_ERR_INVALID, "max_shots %d is not >= 1", o->max_shots);
    if (o->levels < 0 || o->levels > 30)
        return vv_error_set(VV_ERR_INVALID, "levels %d is not in 0..30", o->levels);
    return VV_OK;
}

void
vv_radiosity_free(vv_radiosity *r) {
    if (!r)
        return;
    for (int i = 0; i < r->n_vols; i++) {
        free(r->vols[i].sigma);
        free(r->vols[i].rc);
        free(r->vols[i].bmax);
    }
    free(r->vols);
    free(r->elems);
    free(r->nodes);
    free(r->roots);
    free(r);
}

void
vv_radiosity_get_stats(const vv_radiosity *r, vv_radiosity_stats *s) {
    *s = r->stats;
}

vv_status
vv_radiosity_object_power(const vv_radiosity *r, int index, double absorbed[3],
                          double radiated[3]) {
    if (!r || index < 0 || index >= r->n_objects)
        return vv_error_set(VV_ERR_INVALID, "radiosity: object %d out of range", index);
    double a[3] = {0, 0, 0}, t[3] = {0, 0, 0};
    for (int i = 0; i < r->n_elems; i++) {
        const rad_elem *e = &r->elems[i];
        if (e->obj != index)
            continue;
        for (int c = 0; c < 3; c++) {
            a[c] += e->absorbed[c];
            t[c] += (double)e->total[0][c] + e->total[1][c];
        }
    }
    if (absorbed)
        memcpy(absorbed, a, sizeof a);
    if (radiated)
        memcpy(radiated, t, sizeof t);
    return VV_OK;
}

vv_status
vv_radiosity_patch_at(const vv_radiosity *r, int index, vv_vec3 p, vv_vec3 side_normal,
                      double radiosity[3]) {
    int best = -1;
    double bd = INFINITY;
    for (int i = 0; r && i < r->n_elems; i++) {
        const rad_elem *e = &r->elems[i];
        if (e->obj != index || e->kind != RAD_PATCH)
            continue;
        double d = vv_vec3_length(vv_vec3_sub(f3(e->p), p));
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    if (best < 0)
        return vv_error_set(VV_ERR_INVALID, "radiosity: object %d has no patches", index);
    const rad_elem *e = &r->elems[best];
    int side = vv_vec3_dot(f3(e->n), side_normal) < 0;
    for (int c = 0; c < 3; c++)
        radiosity[c] = e->total[side][c] / e->area;
    return VV_OK;
}

/* The World's lights, materials and level option, checked before any work;
 * *n_emit: lights and objects that emit. */
static vv_status
check_world(const vv_world *w, const vv_radiosity_options *opt, int *n_emit) {
    *n_emit = 0;
    for (int i = 0; i < w->n_lights; i++) {
        const vv_light *l = &w->lights[i];
        if (l->headlight)
            continue;
        const double p[3] = {l->intensity * l->color.x, l->intensity * l->color.y,
                             l->intensity * l->color.z};
        for (int c = 0; c < 3; c++)
            if (!(isfinite(p[c]) && p[c] >= 0))
                return vv_error_set(VV_ERR_INVALID,
                                    "radiosity: light %d: power (intensity %g * colour) is %g, "
                                    "not a finite number >= 0",
                                    i, l->intensity, p[c]);
        *n_emit += maxc(p) > 0;
    }
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o->visible)
            continue;
        vv_vec3 col = o->material.color;
        if (o->type == VV_OBJECT_VOLUME && o->segmentation != VV_SEG_THRESHOLD)
            col = vv_vec3_make(1, 1, 1); /* transfer function colours are in [0, 1] */
        vv_status s = check_reflectance(o, col);
        if (s != VV_OK)
            return vv_error_prefix(s, "radiosity");
        if (o->material.emission.x > 0 || o->material.emission.y > 0 || o->material.emission.z > 0)
            (*n_emit)++;
        if (o->type == VV_OBJECT_VOLUME && opt->levels > 0) {
            int dmax = 1;
            for (int a = 0; a < 3; a++)
                dmax = o->volume->dims[a] > dmax ? o->volume->dims[a] : dmax;
            dmax = dmax < opt->grid ? dmax : opt->grid;
            int lv = 1;
            while ((1 << (lv - 1)) < dmax)
                lv++;
            if (opt->levels > lv)
                return vv_error_set(VV_ERR_INVALID,
                                    "radiosity: levels %d is beyond the %d levels of object "
                                    "'%s' (%d voxels along its longest axis)",
                                    opt->levels, lv, o->name, dmax);
        }
    }
    if (*n_emit == 0)
        return vv_error_set(VV_ERR_INVALID,
                            "radiosity: the World has no emitter (no point or directional light "
                            "other than a headlight, no object with material.emission)");
    return VV_OK;
}

/* The elements of the World, their trees (one root per object), the
 * patches split at shadow boundaries, and the counts and input power in
 * r->stats. */
static vv_status
build_scene(vv_radiosity *r, const vv_world *w, double diag) {
    builder b;
    memset(&b, 0, sizeof b);
    int *obj_lo = calloc((size_t)w->n_objects + 1, sizeof *obj_lo);
    r->vols = calloc((size_t)w->n_objects + 1, sizeof *r->vols);
    r->roots = calloc((size_t)w->n_objects + 1, sizeof *r->roots);
    vv_status s = VV_OK;
    if (!obj_lo || !r->vols || !r->roots)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    const double psize = r->opt.patch_size > 0 ? r->opt.patch_size : diag / 48;
    if (s == VV_OK)
        s = rad_build_elements(&b, r, w, &r->opt, psize, obj_lo);
    for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
        if (obj_lo[i + 1] == obj_lo[i])
            continue;
        int root = rad_build_tree(&b, obj_lo[i], obj_lo[i + 1]);
        if (root < 0)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        else
            r->roots[r->n_roots++] = root;
    }
    r->elems = b.e;
    r->n_elems = b.n;
    r->nodes = b.nodes;
    r->n_nodes = b.n_nodes;
    if (s == VV_OK)
        s = rad_shadow_split(r, w, 4 * diag + 1e-9, obj_lo);
    free(obj_lo);
    if (s != VV_OK)
        return s;
    r->stats.n_nodes = r->n_nodes;
    int n_emitters = 0;
    for (int i = 0; i < r->n_elems; i++) {
        if (r->elems[i].kind == RAD_PATCH)
            r->stats.n_patches++;
        else
            r->stats.n_voxels++;
        for (int c = 0; c < 3; c++)
            r->stats.power_in[c] += (double)r->elems[i].unshot[0][c] + r->elems[i].unshot[1][c];
    }
    for (int i = 0; i < w->n_lights; i++)
        n_emitters += !w->lights[i].headlight;
    const double ne = (double)r->n_elems + n_emitters;
    r->stats.pairwise = ne * ne;
    return VV_OK;
}

/* Each light (but headlights) shoots once, first, refined against every
 * tree; the world box @p wb and its diagonal set the refinement bound. */
static vv_status
shoot_lights(solver *sv, const vv_world *w, vv_box wb, double diag, double *cand_unshot) {
    vv_radiosity *r = sv->r;
    for (int i = 0; i < w->n_lights && sv->status == VV_OK; i++) {
        const vv_light *l = &w->lights[i];
        if (l->headlight)
            continue;
        shooter sh;
        memset(&sh, 0, sizeof sh);
        sh.kind = l->type == VV_LIGHT_POINT ? SH_POINT : SH_DIRECTIONAL;
        sh.pos = l->position;
        sh.dir = vv_vec3_normalize(l->direction);
        sh.I[0] = l->intensity * l->color.x;
        sh.I[1] = l->intensity * l->color.y;
        sh.I[2] = l->intensity * l->color.z;
        if (!(maxc(sh.I) > 0))
            continue;
        if (sh.kind == SH_DIRECTIONAL && !(vv_vec3_length(sh.dir) > 0))
            continue;
        {
            /* refinement bound: relative to what reaches the scene */
            double R = 0.5 * diag;
            vv_vec3 cen = vv_vec3_scale(vv_vec3_add(wb.min, wb.max), 0.5);
            double d = vv_vec3_length(vv_vec3_sub(sh.pos, cen));
            double om = d > R ? fmin(4 * RAD_PI, RAD_PI * R * R / (d * d)) : 4 * RAD_PI;
            sv->eps_power = r->opt.error * maxc(sh.I) * (sh.kind == SH_POINT ? om : RAD_PI * R * R);
        }
        for (int j = 0; j < r->n_roots; j++)
            rad_refine(sv, &sh, -1, r->roots[j]);
        double shot[3];
        for (int c = 0; c < 3; c++) {
            shot[c] = sh.kind == SH_POINT ? 4 * RAD_PI * sh.I[c] : -1;
            if (sh.kind == SH_POINT)
                r->stats.power_in[c] += shot[c];
        }
        rad_apply_deposits(sv, shot, cand_unshot);
    }
    return sv->status;
}

/* The candidates shoot their unshot power, the largest first, until what is
 * left is below the tolerance of @p pin (the power the scene holds) or the
 * shots run out. */
static vv_status
shoot_candidates(solver *sv, const vv_progress *progress, const int *cands, int n_cands,
                 double *cand_unshot, double pin) {
    vv_radiosity *r = sv->r;
    const vv_radiosity_options *opt = &r->opt;
    shooter cl;
    memset(&cl, 0, sizeof cl);
    cl.kind = SH_CLUSTER;
    for (;;) {
        double left = 0;
        int best = -1;
        for (int i = 0; i < n_cands; i++) {
            left += cand_unshot[i];
            if (best < 0 || cand_unshot[i] > cand_unshot[best])
                best = i;
        }
        if (!(pin > 0) || best < 0 || left <= opt->tolerance * pin || !(cand_unshot[best] > 0)) {
            r->stats.converged = 1;
            return VV_OK;
        }
        if (r->stats.n_shots >= opt->max_shots)
            return VV_OK;
        if (progress && progress->fn && (r->stats.n_shots & 7) == 0) {
            double f = log(left / pin) / log(opt->tolerance);
            f = f < 0 ? 0 : f > 1 ? 1 : f;
            if (vv_progress_report(progress, f))
                return vv_error_set(VV_ERR_CANCELLED,
                                    "radiosity: cancelled with %.3g %% of the power left unshot",
                                    100 * left / pin);
        }
        int S = cands[best];
        rad_unshot_moments(sv, S);
        double shot[3] = {0, 0, 0};
        const rad_node *Sn = &r->nodes[S];
        for (int i = Sn->lo; i < Sn->hi; i++)
            for (int c = 0; c < 3; c++)
                shot[c] += (double)r->elems[i].unshot[0][c] + r->elems[i].unshot[1][c];
        for (int j = 0; j < r->n_roots; j++)
            rad_refine(sv, &cl, S, r->roots[j]);
        if (sv->status != VV_OK)
            return sv->status;
        /* the candidate's power is shot: clear it before its receivers
         * (itself among them) get theirs */
        for (int i = Sn->lo; i < Sn->hi; i++)
            memset(r->elems[i].unshot, 0, sizeof r->elems[i].unshot);
        cand_unshot[best] = 0;
        rad_apply_deposits(sv, shot, cand_unshot);
        r->stats.n_shots++;
    }
}

vv_status
vv_radiosity_solve(vv_radiosity **out, const vv_world *w, const vv_radiosity_options *opt_in,
                   const vv_progress *progress) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "radiosity: NULL output");
    *out = NULL;
    if (!w)
        return vv_error_set(VV_ERR_INVALID, "radiosity: NULL World");
    vv_radiosity_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        vv_radiosity_options_init(&opt);
    vv_status s = check_options(&opt);
    if (s != VV_OK)
        return vv_error_prefix(s, "radiosity");
    /* emitters and materials first: bad input is refused before any work */
    int n_emit = 0;
    if ((s = check_world(w, &opt, &n_emit)) != VV_OK)
        return s;
    vv_box wb = vv_world_bounds(w);
    double diag = vv_vec3_length(vv_vec3_sub(wb.max, wb.min));
    if (!(diag > 0))
        diag = 1;
    vv_radiosity *r = calloc(1, sizeof *r);
    if (!r)
        return vv_error_set(VV_ERR_NOMEM, "radiosity: out of memory");
    r->opt = opt;
    r->n_objects = w->n_objects;
    solver sv;
    memset(&sv, 0, sizeof sv);
    int *cands = NULL;
    double *cand_unshot = NULL;
    if ((s = build_scene(r, w, diag)) != VV_OK)
        goto done;
    /* shooting candidates: a cut through the hierarchies, about 256 clusters */
    cands = malloc(((size_t)r->n_elems + 1) * sizeof *cands);
    cand_unshot = calloc((size_t)r->n_elems + 1, sizeof *cand_unshot);
    sv.u = calloc(RAD_U * ((size_t)r->n_nodes + 1), sizeof *sv.u);
    if (!cands || !cand_unshot || !sv.u) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    int K = r->n_elems / 256 > 1 ? r->n_elems / 256 : 1;
    int n_cands = 0;
    for (int i = 0; i < r->n_roots; i++)
        n_cands = rad_candidate_cut(r, r->roots[i], K, cands, n_cands);
    for (int i = 0; i < r->n_elems; i++)
        cand_unshot[r->elems[i].cand] += rad_elem_unshot(&r->elems[i]);
    sv.r = r;
    sv.status = VV_OK;
    sv.far_t = 4 * diag + 1e-9;
    {
        /* levels: clusters of at most 8^(levels-1) elements interact */
        double mc = opt.levels > 0 ? pow(8.0, opt.levels - 1) : 2e9;
        sv.max_cluster = mc > 2e9 ? 2000000000 : (int)mc;
    }
    if ((s = shoot_lights(&sv, w, wb, diag, cand_unshot)) != VV_OK)
        goto done;
    /* the power the scene holds after the lights shot: tolerance and
     * refinement are relative to it (most of a light's power may miss) */
    double pin =
        r->stats.power_absorbed[0] + r->stats.power_absorbed[1] + r->stats.power_absorbed[2];
    for (int i = 0; i < n_cands; i++)
        pin += cand_unshot[i];
    sv.eps_power = opt.error * pin;
    if ((s = shoot_candidates(&sv, progress, cands, n_cands, cand_unshot, pin)) != VV_OK)
        goto done;
    for (int i = 0; i < r->n_elems; i++)
        for (int c = 0; c < 3; c++)
            r->stats.power_unshot[c] += (double)r->elems[i].unshot[0][c] + r->elems[i].unshot[1][c];
    s = rad_prepare_render(r);
done:
    free(cands);
    free(cand_unshot);
    free(sv.u);
    free(sv.dep);
    if (s != VV_OK) {
        vv_radiosity_free(r);
        return s;
    }
    *out = r;
    return VV_OK;
}
