/*
 * A toy rendering method in one file: the whole of what a new renderer
 * takes (include/volvis/sys/renderer.h). "toymip" draws the maximum
 * intensity along each primary ray through the first visible volume
 * object, sampling the nearest voxel every half voxel, as grey scaled by
 * its one option "gain" (value / 255 * gain, clamped to 1; alpha 1 where a
 * ray met a voxel above zero). The registry allocates its state, sets
 * the option from the table's default and later values, and the frame
 * runner owns the tile loop. The test registers it (vv_renderer_register)
 * and renders through vv_renderer_render (tests/plugins/test_toy.c).
 */
#include <math.h>
#include <stddef.h>

#include "toy.h"
#include "volvis/sys/renderer.h"

typedef struct toy_state {
    double gain; /* option gain */
} toy_state;

/* One frame's work, shared by the tiles. */
typedef struct toy_frame {
    const toy_state *st;
    const vv_volume *v;
    vv_mat4 to_index; /* world to the volume's index space */
    vv_camera_rays rays;
    vv_image *out;
} toy_frame;

/* The maximum voxel along @p r (world space), 0 when it misses the volume. */
static double
ray_max(const toy_frame *f, vv_ray r) {
    const vv_volume *v = f->v;
    const vv_vec3 a = vv_mat4_mul_point(f->to_index, r.origin);
    const vv_vec3 far = {r.origin.x + r.dir.x, r.origin.y + r.dir.y, r.origin.z + r.dir.z};
    const vv_vec3 b = vv_mat4_mul_point(f->to_index, far);
    const double o[3] = {a.x, a.y, a.z}, d[3] = {b.x - a.x, b.y - a.y, b.z - a.z};
    double t0 = 0, t1 = INFINITY;
    for (int k = 0; k < 3; k++) { /* the box of voxel centres, half a voxel out */
        const double lo = -0.5, hi = v->dims[k] - 0.5;
        if (fabs(d[k]) < 1e-12) {
            if (o[k] < lo || o[k] > hi)
                return 0;
            continue;
        }
        double ta = (lo - o[k]) / d[k], tb = (hi - o[k]) / d[k];
        if (ta > tb) {
            const double t = ta;
            ta = tb;
            tb = t;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
    }
    if (!(t0 < t1))
        return 0;
    const double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double dt = 0.5 / len; /* half a voxel in index units */
    const unsigned char *vox = v->data;
    double best = 0;
    for (double t = t0 + dt / 2; t < t1; t += dt) {
        int i[3];
        for (int k = 0; k < 3; k++) {
            i[k] = (int)floor(o[k] + t * d[k] + 0.5);
            i[k] = i[k] < 0 ? 0 : i[k] >= v->dims[k] ? v->dims[k] - 1 : i[k];
        }
        const double x =
            vox[((size_t)i[2] * (size_t)v->dims[1] + (size_t)i[1]) * (size_t)v->dims[0] + i[0]];
        best = x > best ? x : best;
    }
    return best;
}

static vv_status
toy_tile(void *user, const vv_frame_tile *t) {
    const toy_frame *f = user;
    for (int y = t->y0; y < t->y1; y++)
        for (int x = t->x0; x < t->x1; x++) {
            const double m = ray_max(f, vv_camera_ray(&f->rays, x, y));
            float *px = f->out->rgba + 4 * ((size_t)y * (size_t)f->out->width + (size_t)x);
            const double g = fmin(1.0, m / 255.0 * f->st->gain);
            px[0] = px[1] = px[2] = (float)g;
            px[3] = m > 0 ? 1.0f : 0.0f;
        }
    return VV_OK;
}

static vv_status
toy_render(void *state, const vv_world *world, const vv_view *view, const vv_render_options *opt,
           vv_image *out) {
    toy_frame f = {.st = state, .out = out};
    for (int i = 0; i < world->n_objects && !f.v; i++) {
        const vv_object *o = world->objects[i];
        if (o->visible && o->type == VV_OBJECT_VOLUME && o->volume)
            f.v = o->volume;
        if (f.v) {
            int ok = 0;
            f.to_index = vv_mat4_inverse(vv_object_index_to_world(o), &ok);
            if (!ok)
                return vv_error_set(VV_ERR_INVALID, "toymip: a singular object matrix");
        }
    }
    if (!f.v || f.v->type != VV_U8)
        return vv_error_set(VV_ERR_UNSUPPORTED, "toymip: draws one 8-bit volume object");
    vv_camera_rays_init(&f.rays, view);
    vv_frame_job job;
    vv_frame_job_init(&job, out->width, out->height, toy_tile, &f);
    return vv_frame_run(&job, opt);
}

static const vv_option_spec toy_options[] = {
    {"gain", VV_OPTION_REAL, "1", 0, 100, VV_OPTION_MIN_OPEN, NULL,
     "grey = maximum / 255 * gain, clamped to 1", VV_OPTION_BIND(toy_state, gain, DOUBLE)},
};

const vv_renderer_ops toy_renderer = {
    .version = VV_RENDERER_OPS_VERSION,
    .info = {.name = "toymip",
             .description = "maximum intensity of the nearest voxels (a test's renderer)",
             .draws = VV_DRAWS(VV_OBJECT_VOLUME),
             .modes = VV_MODES_ALL,
             .caps = 0,
             .quality = "ignored",
             .options = toy_options,
             .n_options = (int)(sizeof toy_options / sizeof toy_options[0])},
    .state_size = sizeof(toy_state),
    .render = toy_render,
};
