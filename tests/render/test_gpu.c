/*
 * The gpu renderer (src/render/gpu) against the CPU ray caster, on the
 * Vulkan device there is: in CI Mesa's lavapipe, which runs the same SPIR-V
 * on the CPU. Images of real data agree (MIP, MinIP and X-ray >= 60 dB,
 * composite and iso >= 45 dB; issue 64), with cut planes, point lights and
 * a 2-D transfer function, and three channels under each blend rule;
 * napari's attenuated MIP (issue 80) agrees with raycast's on real and
 * random 8-bit, 16-bit and float volumes (>= 60 dB, every channel within
 * 0.01), with napari's formula on a bright voxel behind a dimmer slab (to
 * one table entry), and at attenuation 0 is the gpu's MIP bit for bit;
 * empty-space skipping leaves the image bit for bit; what it does not draw
 * is refused in one line; out of core (the region contract: a .vvb of the
 * CT head (14 MB) 3.4 times the cache's budget of 4 MiB, paged brick by brick through the
 * device) it agrees with raycast out of core in every mode; the Vulkan
 * validation layers (VV_GPU_VALIDATION=1,
 * set before the first Vulkan call) report nothing during the run.
 * Where no Vulkan device exists the tests skip, saying why (CI installs
 * mesa-vulkan-drivers: scripts/install-deps.sh test).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/gpu/vk.h"
#include "testutil.h"

#define SIZE 160 /* pixels a side: lavapipe casts about 0.4 M rays a second here */

static int have_device;
static const char *no_device;

/*
 * Mesa 22.3's lavapipe keeps allocations of its JIT-compiled shaders (LLVM
 * 15) past vkDestroyDevice: LeakSanitizer is told so, for this process and
 * (LSAN_OPTIONS, set in setup) for the CLI it runs. Same list as
 * tests/lsan.supp.
 */
const char *__lsan_default_suppressions(void);
const char *
__lsan_default_suppressions(void) {
    return "leak:libvulkan_lvp.so\nleak:libLLVM-15.so\n";
}

static int
setup(void **state) {
    (void)state;
    setenv("VV_GPU_VALIDATION", "1", 0);
    setenv("LSAN_OPTIONS", "suppressions=" VV_SOURCE_DIR "/tests/lsan.supp:print_suppressions=0",
           0);
    vv_gpu_device d[4];
    have_device = vv_gpu_devices(d, 4, &no_device) > 0;
    if (have_device)
        printf("# gpu device 0: %s (%s); validation layers %s\n", d[0].name, d[0].kind,
               vv_gpu_validation_enabled() ? "on" : "not installed");
    return 0;
}

#define NEED_DEVICE()                                                                              \
    do {                                                                                           \
        if (!have_device)                                                                          \
            vt_skip("no Vulkan device: %s", no_device);                                            \
    } while (0)

/* Renders @p w with @p name (options "k=v" pairs, NULL-terminated). */
static vv_image *
render(const char *name, const vv_world *w, const char *const *opts) {
    vv_renderer *r;
    vt_ok(vv_renderer_new(&r, name));
    for (int i = 0; opts && opts[i]; i += 2)
        vt_ok(vv_renderer_set_option(r, opts[i], opts[i + 1]));
    vv_render_options o;
    vv_render_options_init(&o);
    vv_image *img;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    vv_renderer_free(r);
    return img;
}

/* raycast without adaptive refinement: one ray a pixel, as the gpu casts */
static const char *const raycast_plain[] = {"refinement", "off", NULL};

static void
save(const vv_image *img, const char *name) {
    char path[512];
    snprintf(path, sizeof path, "%s/%s.png", vt_outdir("render_gpu"), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* Compares gpu and raycast on @p w in @p mode: at least @p min_db, and no
 * channel of a pixel more than @p max_abs apart; writes both images
 * (label.png, label_raycast.png). Returns the PSNR. */
static double
agree_within(vv_world *w, vv_render_mode mode, double min_db, double max_abs, const char *label) {
    for (int i = 0; i < w->n_objects; i++)
        w->objects[i]->mode = mode;
    vv_image *a = render("raycast", w, raycast_plain);
    vv_image *b = render("gpu", w, NULL);
    double lit = 0;
    for (size_t i = 0; i < (size_t)SIZE * SIZE; i++)
        lit += b->rgba[4 * i + 3] > 0.05;
    const double db = vt_image_psnr(a, b, NULL);
    double mean;
    const double most = vt_image_diff(a, b, &mean);
    printf("# %s: gpu against raycast %.1f dB, |difference| at most %.3g, mean %.3g (%.0f%% of "
           "the pixels seen)\n",
           label, db, most, mean, 100 * lit / ((double)SIZE * SIZE));
    save(b, label);
    char name[128];
    snprintf(name, sizeof name, "%s_raycast", label);
    save(a, name);
    if (!(db >= min_db))
        fail_msg("%s: %.2f dB < %.0f dB", label, db, min_db);
    if (!(most <= max_abs))
        fail_msg("%s: a pixel differs by %.3g > %.3g", label, most, max_abs);
    /* not an empty image agreeing with another */
    assert_true(lit > 0.05 * SIZE * SIZE);
    vv_image_free(a);
    vv_image_free(b);
    return db;
}

/* agree_within without a bound on single pixels. */
static double
agree(vv_world *w, vv_render_mode mode, double min_db, const char *label) {
    return agree_within(w, mode, min_db, INFINITY, label);
}

/*
 * How far gpu's attenuated MIP may be from raycast's. Both take the same
 * samples and the same table; they differ in float rounding only: sample
 * points (float t on the device, double on the host), the trilinear
 * weights' arithmetic, exp in float against double, and the running sum
 * (a compensated float sum against a double). That moves a scaled value by
 * about 1e-6 of itself, which changes the pixel only where the value sits
 * at the edge of one of the transfer-function table's 4096 entries (then
 * by one entry) or where two samples' scaled values tie to that precision
 * (then the other one wins, of nearly the same colour). So: 60 dB (a mean
 * square error of 1e-6), and no channel of any pixel more than 0.01 apart
 * (2.6 steps of an 8-bit PNG; one entry of a ramp over a quarter of the
 * table is 0.001).
 */
#define ATT_DB 60
#define ATT_MAX_ABS 0.01

/* A volume's worth of napari's attenuated MIP: gpu against raycast at
 * attenuation @p att (label_att.png and its raycast twin). */
static double
agree_attenuated(vv_world *w, double att, const char *label) {
    char name[128];
    snprintf(name, sizeof name, "%s_att%.2f", label, att);
    for (int i = 0; i < w->n_objects; i++)
        w->objects[i]->attenuation = att;
    return agree_within(w, VV_MODE_ATTENUATED_MIP, ATT_DB, ATT_MAX_ABS, name);
}

/* Projections seen through an opaque grey ramp over [lo, hi]: every ray
 * that meets the volume gives an opaque pixel of its projected value. */
static void
grey_tf(vv_world *w, double lo, double hi) {
    vt_tf_grey(&w->objects[0]->tf, lo, hi);
}

static void
test_ct_head_modes(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/ct_head.nrrd", SIZE, &vol);
    agree(w, VV_MODE_COMPOSITE, 45, "ct_head_composite");
    agree(w, VV_MODE_MIP, 60, "ct_head_mip");
    w->objects[0]->isovalue = 0.5 * (vol->range[0] + vol->range[1]) * 0.3;
    agree(w, VV_MODE_ISO, 45, "ct_head_iso");
    grey_tf(w, vol->range[0], 0.3 * vol->range[1]);
    agree(w, VV_MODE_XRAY, 60, "ct_head_xray");
    agree(w, VV_MODE_MIP, 60, "ct_head_mip_grey");
    vv_world_free(w);
    vv_volume_free(vol);
}

/* neghip: 8-bit, 64^3, a small volume magnified (many samples a voxel) */
static void
test_neghip_modes(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/neghip.slc", SIZE, &vol);
    agree(w, VV_MODE_COMPOSITE, 45, "neghip_composite");
    agree(w, VV_MODE_MIP, 60, "neghip_mip");
    w->objects[0]->isovalue = 0.4 * (vol->range[0] + vol->range[1]);
    agree(w, VV_MODE_ISO, 45, "neghip_iso");
    grey_tf(w, vol->range[0], vol->range[1]);
    agree(w, VV_MODE_XRAY, 60, "neghip_xray");
    vv_world_free(w);
    vv_volume_free(vol);
}

/* A float volume, anisotropic voxels: the values go up as R32 float; its
 * minimum along a ray lies where the ray enters (MinIP). */
static void
test_float_anisotropic(void **state) {
    (void)state;
    NEED_DEVICE();
    const int dims[3] = {40, 48, 24};
    vv_volume *v;
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    for (int k = 0; k < dims[2]; k++)
        for (int j = 0; j < dims[1]; j++)
            for (int i = 0; i < dims[0]; i++) {
                const double x = i / 19.5 - 1, y = j / 23.5 - 1, z = k / 11.5 - 1;
                vv_volume_set(v, i, j, k, 1.5 - sqrt(x * x + y * y + z * z) + 0.1 * sin(9 * x));
            }
    v->spacing[2] = 2.5;
    vv_volume_update_range(v);
    vv_default_scene_options so = vt_scene_options(SIZE);
    vv_world *w;
    vt_ok(vv_world_new_for_volume(&w, v, &so));
    agree(w, VV_MODE_COMPOSITE, 45, "float_composite");
    agree(w, VV_MODE_MIP, 60, "float_mip");
    grey_tf(w, v->range[0], v->range[1]);
    agree(w, VV_MODE_MINIP, 60, "float_minip");
    agree(w, VV_MODE_XRAY, 60, "float_xray");
    agree_attenuated(w, 0.3, "float");
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---- napari's attenuated MIP against raycast ------------------------------ */

/* Real data: the CT head (16-bit) at napari's default 0.05 and a strong
 * 1.0, far from MIP (the gpu's MIP more than 10 dB away), and neghip
 * (8-bit), against raycast. */
static void
test_attenuated_mip_real(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/ct_head.nrrd", SIZE, &vol);
    grey_tf(w, 100, 1500); /* the contrast limits 100 .. 1500 */
    agree_attenuated(w, 0.05, "ct_head");
    agree_attenuated(w, 1.0, "ct_head");
    vv_image *att = render("gpu", w, NULL);
    w->objects[0]->mode = VV_MODE_MIP;
    vv_image *mip = render("gpu", w, NULL);
    save(mip, "ct_head_mip_for_att");
    const double db = vt_image_psnr(att, mip, NULL);
    printf("# ct_head: gpu attenuated MIP (1.0) against gpu MIP %.1f dB\n", db);
    assert_true(db < 30); /* the attenuation shows */
    vv_image_free(att);
    vv_image_free(mip);
    vv_world_free(w);
    vv_volume_free(vol);
    w = vt_volume_scene("volumes/neghip.slc", SIZE, &vol);
    agree_attenuated(w, 0.2, "neghip");
    vv_world_free(w);
    vv_volume_free(vol);
}

/* An orthographic view down -z from z = 64 onto the centre of an n x n
 * face: one ray a voxel column, samples at whole and half voxels. */
static vv_view
down_z(int n) {
    vv_view v;
    memset(&v, 0, sizeof v);
    v.eye = vv_vec3_make(0.5 * (n - 1), 0.5 * (n - 1), 64);
    v.at = vv_vec3_make(0.5 * (n - 1), 0.5 * (n - 1), 63);
    v.up = vv_vec3_make(0, 1, 0);
    v.fov = vv_deg_to_rad(30);
    v.ortho_height = n;
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    v.width = v.height = n;
    return v;
}

/* A bright voxel (value 1 at z = 5) behind a dimmer slab (0.6, z = 14..21)
 * in every column of a 16 x 16 x 24 volume, float and 16-bit (values times
 * 1000), seen down -z through a grey ramp over the contrast limits: every
 * pixel is napari's value computed here (vt_napari_attenuated_mip) to one
 * entry of the 4096-entry table, as raycast's is (test_raycast); a small
 * attenuation lets the bright voxel win, napari's default and a large one
 * hide it behind the slab. */
static void
test_attenuated_mip_analytic(void **state) {
    (void)state;
    NEED_DEVICE();
    const int n = 16, d = 24;
    double col[24];
    for (int k = 0; k < d; k++)
        col[k] = k == 5 ? 1.0 : k >= 14 && k <= 21 ? 0.6 : 0.0;
    /* the samples along a column: z = d - 1 down to 0 by half a voxel */
    double unit[2 * 24];
    int ns = 0;
    for (int h = 2 * (d - 1); h >= 0; h--)
        unit[ns++] = h % 2 ? 0.5 * (col[h / 2] + col[h / 2 + 1]) : col[h / 2];
    const vv_voxel_type types[2] = {VV_F32, VV_U16};
    const double scales[2] = {1, 1000};
    const double atts[3] = {0.01, 0.05, 0.5};
    for (int t = 0; t < 2; t++) {
        const int dims[3] = {n, n, d};
        vv_volume *v;
        vt_ok(vv_volume_new(&v, dims, types[t]));
        for (int k = 0; k < d; k++)
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++)
                    vv_volume_set(v, i, j, k, scales[t] * col[k]);
        vv_volume_update_range(v);
        const double lo = 0.1 * scales[t], hi = scales[t], step = 0.5;
        double samples[2 * 24];
        for (int i = 0; i < ns; i++)
            samples[i] = scales[t] * unit[i];
        for (int a = 0; a < 3; a++) {
            vv_world *w;
            vt_ok(vv_world_new(&w));
            w->background = vv_vec3_make(0, 0, 0);
            w->view = down_z(n);
            vv_object *o;
            vt_ok(vv_object_new_volume(&o, v, NULL));
            o->mode = VV_MODE_ATTENUATED_MIP;
            o->shading = 0;
            o->step = step;
            o->attenuation = atts[a];
            vt_tf_grey(&o->tf, lo, hi);
            vt_ok(vv_world_add_object(w, o));
            int at = -1;
            const double want = vt_napari_attenuated_mip(samples, ns, lo, hi, atts[a], step, &at);
            double grey = (want - lo) / (hi - lo);
            grey = grey < 0 ? 0 : grey > 1 ? 1 : grey;
            const int bright = at == 2 * (d - 1 - 5); /* the bright voxel's sample */
            assert_true(a == 0 ? bright : !bright);
            vv_image *g = render("gpu", w, NULL), *c = render("raycast", w, raycast_plain);
            char name[64];
            snprintf(name, sizeof name, "analytic_%s_att%.2f", vv_voxel_type_name(types[t]),
                     atts[a]);
            save(g, name);
            const double tol = 1.0 / 4095 + 1e-5; /* one entry of the table over [lo, hi] */
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    const float *p = g->rgba + 4 * ((size_t)y * n + (size_t)x);
                    if (!(fabs(p[0] - grey) <= tol))
                        fail_msg("%s pixel (%d, %d): napari's value %.6f (grey %.6f, sample %d), "
                                 "gpu's grey %.6f",
                                 name, x, y, want, grey, at, (double)p[0]);
                    assert_float_equal(p[3], 1.0, 0);
                }
            double mean;
            const double most = vt_image_diff(g, c, &mean);
            printf("# %s: napari's value %.5f at sample %d (%s), gpu grey %.5f; against raycast "
                   "|difference| at most %.3g, mean %.3g\n",
                   name, want, at, bright ? "the bright voxel" : "the slab", (double)g->rgba[0],
                   most, mean);
            assert_true(most <= tol);
            vv_image_free(g);
            vv_image_free(c);
            vv_world_free(w);
        }
        vv_volume_free(v);
    }
}

/* Attenuation 0 scales every sample by exactly 1: the gpu's image of MIP
 * bit for bit (colour and opacity; MIP's depth may name an earlier sample
 * of the same colour), for 8-bit, 16-bit and float volumes and a ramp with
 * flat ends (MIP starts at one and stops at the other), in a turned view. */
static void
test_attenuated_mip_zero_is_mip(void **state) {
    (void)state;
    NEED_DEVICE();
    const vv_voxel_type types[3] = {VV_U8, VV_U16, VV_F32};
    for (int t = 0; t < 3; t++) {
        const int dims[3] = {32, 32, 24};
        vv_volume *v;
        vt_ok(vv_volume_new(&v, dims, types[t]));
        uint64_t seed = 0x243f6a8885a308d3ULL + (uint64_t)t;
        for (int k = 0; k < dims[2]; k++)
            for (int j = 0; j < dims[1]; j++)
                for (int i = 0; i < dims[0]; i++) {
                    double x = vt_rnd(&seed, 0, 1);
                    if (k > 8 && k < 16 && i > 16)
                        x *= 0.3;
                    vv_volume_set(v, i, j, k,
                                  types[t] == VV_F32  ? 1000 * x - 200
                                  : types[t] == VV_U8 ? floor(255 * x)
                                                      : floor(4000 * x));
                }
        vv_volume_update_range(v);
        vv_default_scene_options so = vt_scene_options(SIZE);
        vv_world *w;
        vt_ok(vv_world_new_for_volume(&w, v, &so));
        vv_object *o = w->objects[0];
        o->attenuation = 0;
        vt_tf_flat_ends(&o->tf, v->range[0], v->range[1]);
        o->mode = VV_MODE_MIP;
        vv_image *mip = render("gpu", w, NULL);
        o->mode = VV_MODE_ATTENUATED_MIP;
        vv_image *att = render("gpu", w, NULL);
        int same = 0;
        const double db = vt_image_psnr(mip, att, &same);
        char name[64];
        snprintf(name, sizeof name, "zero_att_%s", vv_voxel_type_name(types[t]));
        save(att, name);
        double lit = 0;
        for (size_t i = 0; i < (size_t)SIZE * SIZE; i++)
            lit += att->rgba[4 * i + 3] > 0;
        printf("# %s: attenuation 0 against MIP on the gpu: %s (%.1f dB), %.0f%% seen\n", name,
               same ? "bit for bit" : "DIFFERENT", db, 100 * lit / ((double)SIZE * SIZE));
        if (!same)
            fail_msg("%s: attenuation 0 differs from MIP by up to %.3g", name,
                     vt_image_diff(mip, att, NULL));
        assert_true(lit > 0.2 * SIZE * SIZE); /* not an empty image */
        /* and against raycast, attenuated (0.3) */
        agree_attenuated(w, 0.3, name);
        vv_image_free(mip);
        vv_image_free(att);
        vv_world_free(w);
        vv_volume_free(v);
    }
}

/* Cut planes (a global one and the object's own) and a point light. */
static void
test_cut_planes_point_light(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/ct_head.nrrd", SIZE, &vol);
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(0, 0, 0), vv_vec3_make(1, 0.3, 0)));
    vv_object *o = w->objects[0];
    o->n_cut_planes = 1;
    o->cut_planes[0].point = vv_vec3_make(0, 0, 10);
    o->cut_planes[0].normal = vv_vec3_make(0, 0, -1);
    vv_light l;
    memset(&l, 0, sizeof l);
    l.type = VV_LIGHT_POINT;
    l.position = vv_vec3_make(200, -300, 150);
    l.color = vv_vec3_make(1, 0.8, 0.6);
    l.intensity = 1;
    vt_ok(vv_world_add_light(w, &l));
    agree(w, VV_MODE_COMPOSITE, 45, "ct_head_cut_composite");
    agree(w, VV_MODE_MIP, 60, "ct_head_cut_mip");
    vv_world_free(w);
    vv_volume_free(vol);
}

/* A 2-D transfer function (value x gradient magnitude, Kniss et al.): the
 * boundaries of bone and of skin, as the GUI's editor makes them. */
static void
test_tf2d(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/ct_head.nrrd", SIZE, &vol);
    vv_object *o = w->objects[0];
    vv_tf2d_init(&o->tf2d);
    o->tf2d.opacity_unit_distance = 1;
    vv_tf2d_widget wd;
    vv_tf2d_widget_init_triangle(&wd, 700, 1400, 1500, vv_vec3_make(1, 0.95, 0.85), 0.9);
    wd.gradient[0] = 150;
    vt_ok(vv_tf2d_add_widget(&o->tf2d, &wd));
    vv_tf2d_widget_init_rectangle(&wd, 80, 300, 20, 400, vv_vec3_make(0.9, 0.5, 0.4), 0.05);
    wd.ramp = 30;
    vt_ok(vv_tf2d_add_widget(&o->tf2d, &wd));
    o->segmentation = VV_SEG_TRANSFER_FUNCTION_2D;
    agree(w, VV_MODE_COMPOSITE, 45, "ct_head_tf2d");
    vv_world_free(w);
    vv_volume_free(vol);
}

/* Three channels of one object (blobs of their own, overlapping; 8-bit,
 * 16-bit and float), under the three blend rules. */
static void
test_channels(void **state) {
    (void)state;
    NEED_DEVICE();
    const int dims[3] = {48, 40, 36};
    const vv_voxel_type types[3] = {VV_U8, VV_U16, VV_F32};
    const double cx[3] = {18, 28, 24}, cy[3] = {18, 20, 24}, scale[3] = {200, 40000, 1.5};
    vv_volume *vols[3];
    for (int c = 0; c < 3; c++) {
        vt_ok(vv_volume_new(&vols[c], dims, types[c]));
        for (int k = 0; k < dims[2]; k++)
            for (int j = 0; j < dims[1]; j++)
                for (int i = 0; i < dims[0]; i++) {
                    const double d2 = (i - cx[c]) * (i - cx[c]) + (j - cy[c]) * (j - cy[c]) +
                                      (k - 18.0) * (k - 18.0);
                    vv_volume_set(vols[c], i, j, k,
                                  scale[c] * exp(-d2 / 90.0) * (0.8 + 0.2 * sin(0.7 * i)));
                }
        vv_volume_update_range(vols[c]);
    }
    vv_default_scene_options so = vt_scene_options(SIZE);
    vv_world *w;
    vt_ok(vv_world_new_for_volume(&w, vols[0], &so));
    vv_object *o = w->objects[0];
    vt_ok(vv_object_set_channels(o, 3, vols, NULL));
    static const vv_vec3 rgb[3] = {{1, 0.2, 0.2}, {0.2, 1, 0.2}, {0.3, 0.4, 1}};
    for (int c = 0; c < 3; c++)
        vt_ok(vv_tf_set_contrast(&o->channels[c].tf, 0.25 * scale[c], 0.9 * scale[c], 1.0, 0.6,
                                 rgb[c], 1.0));
    static const vv_channel_blend rules[3] = {VV_BLEND_COMPOSITE, VV_BLEND_ADDITIVE,
                                              VV_BLEND_MAXIMUM};
    static const char *const names[3] = {"channels_composite", "channels_additive",
                                         "channels_maximum"};
    for (int r = 0; r < 3; r++) {
        o->blend = rules[r];
        agree(w, o->mode, r == 2 ? 60 : 45, names[r]);
    }
    /* a hidden channel is left out, as raycast leaves it out */
    o->channels[1].visible = 0;
    o->blend = VV_BLEND_COMPOSITE;
    agree(w, o->mode, 45, "channels_two_of_three");
    vv_world_free(w);
    for (int c = 0; c < 3; c++)
        vv_volume_free(vols[c]);
}

/* Leaping over hidden subvolumes skips only samples that add nothing. */
static void
test_skipping_same_image(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/ct_head.nrrd", SIZE, &vol);
    static const char *const off[] = {"empty_space_skipping", "0", NULL};
    const vv_render_mode modes[] = {VV_MODE_COMPOSITE, VV_MODE_MIP};
    for (int m = 0; m < 2; m++) {
        w->objects[0]->mode = modes[m];
        vv_image *a = render("gpu", w, NULL), *b = render("gpu", w, off);
        int same = 0;
        const double db = vt_image_psnr(a, b, &same);
        printf("# mode %d: skipping on against off: %s (%.1f dB)\n", (int)modes[m],
               same ? "bit for bit" : "differs", db);
        assert_true(db >= 80);
        vv_image_free(a);
        vv_image_free(b);
    }
    vv_world_free(w);
    vv_volume_free(vol);
}

/* What it does not draw, and a device it does not have, in one line each. */
static void
test_refusals(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/neghip.slc", 32, &vol);
    vv_renderer *r;
    vt_ok(vv_renderer_new(&r, "gpu"));
    vv_image *img;
    vt_ok(vv_image_new(&img, 32, 32));
    vv_render_options o;
    vv_render_options_init(&o);
    vv_object *second;
    vt_ok(vv_object_clone(&second, w->objects[0]));
    vt_ok(vv_world_add_object(w, second));
    vt_expect_refusal("two objects", vv_renderer_render(r, w, &w->view, &o, img),
                      VV_ERR_UNSUPPORTED, "one volume object", "gpu");
    w->objects[1]->visible = 0;
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    vt_ok(vv_renderer_set_option(r, "device", "15"));
    vt_expect_refusal("device 15", vv_renderer_render(r, w, &w->view, &o, img), VV_ERR_INVALID,
                      "no Vulkan device 15", NULL);
    vt_ok(vv_renderer_set_option(r, "device", "auto"));
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    /* attenuated MIP is drawn; a bad attenuation is refused as raycast refuses it */
    w->objects[0]->mode = VV_MODE_ATTENUATED_MIP;
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    w->objects[0]->attenuation = -1;
    vt_expect_refusal("attenuation -1", vv_renderer_render(r, w, &w->view, &o, img), VV_ERR_INVALID,
                      "attenuation must be >= 0", NULL);
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(vol);
}

/* An empty World is the background; a renderer survives its volume changing. */
static void
test_background_and_new_volume(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/neghip.slc", 48, &vol);
    w->background = vv_vec3_make(0.25, 0.5, 0.75);
    vv_renderer *r;
    vt_ok(vv_renderer_new(&r, "gpu"));
    vv_image *img;
    vt_ok(vv_image_new(&img, 48, 48));
    vv_render_options o;
    vv_render_options_init(&o);
    w->objects[0]->visible = 0;
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    for (int i = 0; i < 48 * 48; i++) {
        assert_near(img->rgba[4 * i + 0], 0.25, 1e-6);
        assert_near(img->rgba[4 * i + 2], 0.75, 1e-6);
        assert_true(img->depth[i] == INFINITY);
    }
    w->objects[0]->visible = 1;
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    const float before = img->rgba[4 * (24 * 48 + 24)];
    /* the voxels change: the renderer uploads them again */
    for (size_t i = 0; i < (size_t)vol->dims[0] * vol->dims[1] * vol->dims[2]; i++)
        ((uint8_t *)vol->data)[i] = (uint8_t)(255 - ((uint8_t *)vol->data)[i]);
    vol->modified++;
    vv_volume_update_range(vol);
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    vv_image *ref = render("raycast", w, raycast_plain);
    const double db = vt_image_psnr(ref, img, NULL);
    printf("# after the voxels changed: %.1f dB against raycast (centre %.3f -> %.3f)\n", db,
           before, img->rgba[4 * (24 * 48 + 24)]);
    assert_true(db >= 45);
    vv_image_free(ref);
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(vol);
}

#define run_cli(...) vt_run_cli_v(vt_outdir("render_gpu"), (const char *const[]){__VA_ARGS__, NULL})

/* Out of core: the drivers hand the gpu renderer one brick (region) at a
 * time; the bricks' partial images combine into raycast's image. */
static void
test_out_of_core(void **state) {
    (void)state;
    NEED_DEVICE();
    const char *dir = vt_outdir("render_gpu");
    char vvb[512];
    snprintf(vvb, sizeof vvb, "%s/ct_head.vvb", dir);
    vt_run_result r = run_cli("convert", "-q", vt_data("volumes/ct_head.nrrd"), vvb);
    if (r.status != 0)
        fail_msg("convert: %s", r.err);
    vt_run_result_free(&r);
    /* attenuated-mip: far from MIP at 0.5, combined by VV_REGION_ATTENUATED_MAX */
    static const char *const modes[] = {"composite", "mip", "minip",
                                        "xray",      "iso", "attenuated-mip"};
    for (int m = 0; m < 6; m++) {
        char g[512], c[512];
        snprintf(g, sizeof g, "%s/ooc_gpu_%s.png", dir, modes[m]);
        snprintf(c, sizeof c, "%s/ooc_raycast_%s.png", dir, modes[m]);
        const char *tf = m == 4 ? "--iso" : "--tf", *tfv = m == 4 ? "600" : "100:1500";
        r = run_cli("render", vvb, "--renderer", "gpu", "--memory-limit", "4M", "--mode", modes[m],
                    tf, tfv, "--attenuation", "0.5", "--azimuth", "30", "--elevation", "20",
                    "--size", "200x200", "-o", g);
        if (r.status != 0) {
            char why[512];
            snprintf(why, sizeof why, "%s", r.err);
            vt_run_result_free(&r);
            fail_msg("gpu out of core %s: %s", modes[m], why);
        }
        const int said = strstr(r.out, "out of core") != NULL;
        vt_run_result_free(&r);
        assert_true(said);
        r = run_cli("render", vvb, "--renderer", "raycast", "--set", "refinement=off",
                    "--memory-limit", "4M", "--mode", modes[m], tf, tfv, "--attenuation", "0.5",
                    "--azimuth", "30", "--elevation", "20", "--size", "200x200", "-o", c);
        const int ok = r.status == 0;
        vt_run_result_free(&r);
        if (!ok)
            fail_msg("raycast out of core %s failed", modes[m]);
        const double db = vt_png_psnr(g, c);
        printf("# out of core, %s: gpu against raycast %.1f dB\n", modes[m], db);
        if (!(db >= (m == 0 || m == 4 ? 50 : 60)))
            fail_msg("out of core %s: %.1f dB", modes[m], db);
    }
    /* the .vvb's pyramid by level of detail (the multiresolution driver):
     * nodes of level 1 and 2 as regions; attenuated MIP's exponents
     * weighed by the nodes' step_scale */
    static const char *const lod_modes[2] = {"composite", "attenuated-mip"};
    for (int m = 0; m < 2; m++) {
        char g[512], c[512];
        snprintf(g, sizeof g, "%s/lod_gpu%s.png", dir, m ? "_attenuated" : "");
        snprintf(c, sizeof c, "%s/lod_raycast%s.png", dir, m ? "_attenuated" : "");
        static const char *const rc[2][3] = {{"gpu", "--set", "early_termination=0.99"},
                                             {"raycast", "--set", "refinement=off"}};
        for (int k = 0; k < 2; k++) {
            r = run_cli("render", vvb, "--renderer", rc[k][0], rc[k][1], rc[k][2], "--lod", "2",
                        "--mode", lod_modes[m], "--attenuation", "0.5", "--tf", "100:1500",
                        "--azimuth", "30", "--elevation", "20", "--size", "200x200", "-o",
                        k ? c : g);
            const int ok = r.status == 0 && strstr(r.out, "levels") != NULL;
            vt_run_result_free(&r);
            if (!ok)
                fail_msg("%s --lod 2 --mode %s failed or drew no levels", rc[k][0], lod_modes[m]);
        }
        const double db = vt_png_psnr(g, c);
        printf("# by level of detail (--lod 2), %s: gpu against raycast %.1f dB\n", lod_modes[m],
               db);
        assert_true(db >= (m ? 60 : 50));
    }
}

/* One renderer, the transfer function changed between frames: the
 * subvolumes it shows go up again. A radial field, a band of low values
 * (an outer shell: the core's subvolumes hidden) then of high ones (the
 * core): a stale upload would leap over the core. */
static void
test_tf_change(void **state) {
    (void)state;
    NEED_DEVICE();
    const int dims[3] = {48, 48, 48};
    vv_volume *v;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int k = 0; k < 48; k++)
        for (int j = 0; j < 48; j++)
            for (int i = 0; i < 48; i++) {
                const double r = sqrt((i - 23.5) * (i - 23.5) + (j - 23.5) * (j - 23.5) +
                                      (k - 23.5) * (k - 23.5));
                vv_volume_set(v, i, j, k, r < 24 ? 250 - 10 * r : 10);
            }
    vv_volume_update_range(v);
    vv_default_scene_options so = vt_scene_options(SIZE);
    vv_world *w;
    vt_ok(vv_world_new_for_volume(&w, v, &so));
    vv_tf *tf = &w->objects[0]->tf;
    vv_renderer *r;
    vt_ok(vv_renderer_new(&r, "gpu"));
    vv_image *img;
    vt_ok(vv_image_new(&img, SIZE, SIZE));
    vv_render_options o;
    vv_render_options_init(&o);
    static const double bands[2][2] = {{40, 90}, {180, 250}};
    for (int b = 0; b < 2; b++) {
        vv_tf_init(tf);
        tf->opacity_unit_distance = 1;
        vt_ok(vv_tf_add_opacity(tf, bands[b][0], 0));
        vt_ok(vv_tf_add_opacity(tf, 0.5 * (bands[b][0] + bands[b][1]), 0.3));
        vt_ok(vv_tf_add_opacity(tf, bands[b][1], 0));
        vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
        vv_image *ref = render("raycast", w, raycast_plain);
        const double db = vt_image_psnr(ref, img, NULL);
        printf("# transfer function %d of one renderer: %.1f dB against raycast\n", b, db);
        assert_true(db >= 45);
        vv_image_free(ref);
    }
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* A volume over the device's memory budget (option device_memory_mb) is
 * drawn brick by brick through the region contract: the whole render's
 * image (composite up to re-associating over, MIP to rounding). */
static void
test_over_device_budget(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_volume *vol;
    vv_world *w = vt_volume_scene("volumes/ct_head.nrrd", SIZE, &vol);
    static const char *const paged[] = {"device_memory_mb", "2", NULL};
    /* attenuated MIP (0.5): the bricks' maxima and exponents combined
     * front to back (VV_REGION_ATTENUATED_MAX), up to the rounding of the
     * products, as raycast's regions (test_attenuated_regions: >= 50 dB) */
    const vv_render_mode modes[] = {VV_MODE_COMPOSITE, VV_MODE_MIP, VV_MODE_ATTENUATED_MIP};
    static const char *const names[] = {"ct_head_paged_composite", "ct_head_paged_mip",
                                        "ct_head_paged_attenuated"};
    w->objects[0]->attenuation = 0.5;
    for (int m = 0; m < 3; m++) {
        w->objects[0]->mode = modes[m];
        vv_image *a = render("gpu", w, NULL), *b = render("gpu", w, paged);
        const double db = vt_image_psnr(a, b, NULL);
        printf("# mode %d: bricks within 2 MiB of the device against the whole: %.1f dB\n",
               (int)modes[m], db);
        /* composite: the samples of the whole render, its early ray
         * termination carried across the bricks (vv_render_region.front;
         * without it 58 dB) */
        assert_true(db >= (m == 0 ? 100 : m == 1 ? 60 : 50));
        save(b, names[m]);
        vv_image_free(a);
        vv_image_free(b);
    }
    vv_world_free(w);
    vv_volume_free(vol);
}

/* Last: the validation layers saw nothing wrong in the whole run. */
static void
test_validation_quiet(void **state) {
    (void)state;
    NEED_DEVICE();
    if (!vv_gpu_validation_enabled())
        vt_skip("the Vulkan validation layers are not installed (vulkan-validationlayers)");
    const int n = vv_gpu_validation_messages();
    printf("# validation messages: %d\n", n);
    assert_int_equal(n, 0);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ct_head_modes),
        cmocka_unit_test(test_neghip_modes),
        cmocka_unit_test(test_float_anisotropic),
        cmocka_unit_test(test_attenuated_mip_real),
        cmocka_unit_test(test_attenuated_mip_analytic),
        cmocka_unit_test(test_attenuated_mip_zero_is_mip),
        cmocka_unit_test(test_cut_planes_point_light),
        cmocka_unit_test(test_tf2d),
        cmocka_unit_test(test_channels),
        cmocka_unit_test(test_skipping_same_image),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_background_and_new_volume),
        cmocka_unit_test(test_tf_change),
        cmocka_unit_test(test_over_device_budget),
        cmocka_unit_test(test_out_of_core),
        cmocka_unit_test(test_validation_quiet),
    };
    return vt_run_tests(tests, setup, NULL);
}
