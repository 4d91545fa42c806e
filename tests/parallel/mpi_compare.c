/*
 * Run under mpirun by tests/parallel/test_mpi.c: renders scenes both
 * distributed (vv_parallel_render, binary swap and radix-k, through the
 * region contract) and, on rank 0, in one process with the same renderer
 * (raycast; raytrace at quality 1 without adaptive refinement, one ray a
 * pixel with its shadows, which
 * every rank traces through the World's whole volume), and compares the
 * float images: maximum and minimum intensity projection, X-ray (raycast)
 * and the isosurface bit for bit, composite >= 50 dB PSNR. The volumes are a synthetic 70x66x60
 * u16 volume whose objects straddle the brick faces (they sit around the middle of every axis,
 * where the first cuts fall) and, when ../shared is there, the CT head. Then a World that one rank
 * cannot render (rank 1's object hidden) must fail on every rank with rank 1's error, without
 * hanging.
 *
 * usage: mpi_compare [DATA_DIR]; prints one line per case on rank 0 and
 * exits 0 when all pass (the same exit code on every rank).
 */
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "volvis/volvis.h"

static int rank, size, failures;

static vv_volume *
synthetic(void) {
    const int dims[3] = {70, 66, 60};
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, VV_U16) != VV_OK)
        return NULL;
    uint16_t *d = v->data;
    for (int k = 0; k < dims[2]; k++)
        for (int j = 0; j < dims[1]; j++)
            for (int i = 0; i < dims[0]; i++) {
                const double x = i - 34.3, y = j - 31.7, z = k - 29.1;
                const double r = sqrt(x * x + y * y + z * z);
                double val = 1000 * exp(-(r - 20) * (r - 20) / 18.0); /* a shell */
                val += 2500 * exp(-((x - 6) * (x - 6) + y * y + (z + 4) * (z + 4)) / 30.0);
                val += 300 * (0.5 + 0.5 * sin(0.4 * i) * cos(0.3 * j + 0.2 * k));
                d[((size_t)k * dims[1] + j) * dims[0] + i] = (uint16_t)val;
            }
    v->spacing[0] = 1.0;
    v->spacing[1] = 1.1;
    v->spacing[2] = 1.3;
    vv_volume_update_range(v);
    return v;
}

static double
psnr(const vv_image *a, const vv_image *b, int *identical) {
    const size_t n = 4 * (size_t)a->width * (size_t)a->height;
    double se = 0;
    *identical = memcmp(a->rgba, b->rgba, n * sizeof(float)) == 0;
    for (size_t i = 0; i < n; i++) {
        const double e = (double)a->rgba[i] - (double)b->rgba[i];
        se += e * e;
    }
    return se > 0 ? 10 * log10(1.0 / (se / (double)n)) : INFINITY;
}

static void
run_case_with(const char *renderer, const char *name, vv_volume *vol, vv_render_mode mode,
              double azimuth, double elevation, int ortho, vv_compositing method, int radix) {
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.mode = mode;
    o.width = 96;
    o.height = 80;
    o.azimuth = azimuth * 3.14159265358979323846 / 180;
    o.elevation = elevation * 3.14159265358979323846 / 180;
    vv_world *w = NULL;
    vv_status s = vv_world_new_for_volume(&w, vol, &o);
    if (s == VV_OK && ortho)
        w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    if (s == VV_OK && mode == VV_MODE_ATTENUATED_MIP)
        w->objects[0]->attenuation = 0.3; /* far from MIP */
    vv_parallel_options po;
    vv_parallel_options_init(&po);
    po.method = method;
    po.radix = radix;
    vv_parallel *par = NULL;
    vv_renderer *dren = NULL;
    vv_image *dist = NULL, *one = NULL;
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.quality = strcmp(renderer, "raytrace") == 0 ? 1 : 2; /* regions: one ray a pixel */
    if (s == VV_OK)
        s = vv_renderer_new(&dren, renderer);
    if (s == VV_OK)
        s = vv_parallel_new(&par, dren, &po);
    if (s == VV_OK && rank == 0)
        s = vv_image_new(&dist, w->view.width, w->view.height);
    s = vv_parallel_agree(s);
    if (s == VV_OK)
        s = vv_parallel_render(par, w, &w->view, &ro, dist, NULL);
    if (rank == 0) {
        const char *what = mode == VV_MODE_MIP              ? "mip"
                           : mode == VV_MODE_MINIP          ? "minip"
                           : mode == VV_MODE_ISO            ? "iso"
                           : mode == VV_MODE_XRAY           ? "xray"
                           : mode == VV_MODE_ATTENUATED_MIP ? "attenuated-mip"
                                                            : "composite";
        const char *how = method == VV_COMPOSITING_BINARY_SWAP ? "binary-swap" : "radix-k";
        if (s != VV_OK) {
            printf("FAIL %s %s %s %s np %d: %s\n", renderer, name, what, how, size,
                   vv_error_message());
            failures++;
        } else {
            vv_renderer *ren = NULL;
            s = vv_renderer_new(&ren, renderer);
            /* regions cast every pixel: so does the one-process render */
            if (s == VV_OK)
                s = vv_renderer_set_option(ren, "refinement", "off");
            if (s == VV_OK)
                s = vv_image_new(&one, w->view.width, w->view.height);
            if (s == VV_OK)
                s = vv_renderer_render(ren, w, &w->view, &ro, one);
            vv_renderer_free(ren);
            int same = 0;
            const double db = s == VV_OK ? psnr(one, dist, &same) : 0;
            int lit = 0; /* an isosurface (an X-ray, attenuated-MIP image) that is there */
            const float seen =
                mode == VV_MODE_XRAY || mode == VV_MODE_ATTENUATED_MIP ? 0.02f : 0.5f;
            for (size_t i = 0; s == VV_OK && i < (size_t)one->width * one->height; i++)
                lit += one->rgba[4 * i + 3] > seen;
            /* attenuated MIP: the ranks' maxima scaled through the exponents in
             * front of them, up to the rounding of the products */
            const int ok =
                s == VV_OK &&
                (mode == VV_MODE_COMPOSITE || mode == VV_MODE_ATTENUATED_MIP ? db >= 50 : same) &&
                ((mode != VV_MODE_ISO && mode != VV_MODE_XRAY && mode != VV_MODE_ATTENUATED_MIP) ||
                 lit > 200);
            printf("%s %s %s %s %s%s np %d: %s, %.1f dB, %d pixels seen\n", ok ? "ok" : "FAIL",
                   renderer, name, what, how, ortho ? " ortho" : "", size,
                   same ? "bit-identical" : "differs", db, lit);
            failures += !ok;
        }
    } else if (s != VV_OK) {
        failures++;
    }
    vv_image_free(dist);
    vv_image_free(one);
    vv_parallel_free(par);
    vv_renderer_free(dren);
    vv_world_free(w);
}

static void
run_case(const char *name, vv_volume *vol, vv_render_mode mode, double azimuth, double elevation,
         int ortho, vv_compositing method, int radix) {
    run_case_with("raycast", name, vol, mode, azimuth, elevation, ortho, method, radix);
}

/* A World rank 1 cannot render: every rank must return rank 1's error. */
static void
run_failure(vv_volume *vol) {
    if (size < 2)
        return;
    vv_world *w = NULL;
    vv_status s = vv_world_new_for_volume(&w, vol, NULL);
    if (s == VV_OK && rank == 1)
        w->objects[0]->visible = 0;
    vv_parallel *par = NULL;
    vv_image *img = NULL;
    if (s == VV_OK)
        s = vv_parallel_new(&par, NULL, NULL);
    if (s == VV_OK && rank == 0)
        s = vv_image_new(&img, w->view.width, w->view.height);
    if (s == VV_OK)
        s = vv_parallel_render(par, w, &w->view, NULL, img, NULL);
    const int ok = s == VV_ERR_UNSUPPORTED && strncmp(vv_error_message(), "rank 1: ", 8) == 0;
    if (rank == 0)
        printf("%s failure on rank 1 np %d: every rank got: %s\n", ok ? "ok" : "FAIL", size,
               vv_error_message());
    failures += !ok;
    vv_image_free(img);
    vv_parallel_free(par);
    vv_world_free(w);
}

int
main(int argc, char **argv) {
    vv_parallel_init(&argc, &argv, &rank, &size);
    vv_threads_set(1);
    vv_volume *syn = synthetic();
    const vv_render_mode modes[3] = {VV_MODE_COMPOSITE, VV_MODE_MIP, VV_MODE_MINIP};
    for (int m = 0; m < 3; m++) {
        run_case("synthetic", syn, modes[m], 30, 20, 0, VV_COMPOSITING_BINARY_SWAP, 4);
        run_case("synthetic", syn, modes[m], 30, 20, 0, VV_COMPOSITING_RADIX_K, 4);
        run_case("synthetic", syn, modes[m], 110, -35, 1, VV_COMPOSITING_RADIX_K, 2);
        run_case_with("raytrace", "synthetic", syn, modes[m], 30, 20, 0, VV_COMPOSITING_BINARY_SWAP,
                      4);
    }
    /* isosurfaces: each rank's crossings, the nearest kept (two ghost voxels) */
    run_case("synthetic", syn, VV_MODE_ISO, 30, 20, 0, VV_COMPOSITING_BINARY_SWAP, 4);
    run_case("synthetic", syn, VV_MODE_ISO, 110, -35, 1, VV_COMPOSITING_RADIX_K, 2);
    run_case_with("raytrace", "synthetic", syn, VV_MODE_ISO, 30, 20, 0, VV_COMPOSITING_BINARY_SWAP,
                  4);
    /* X-ray: the ranks' sums and counts add up, rank 0 classifies the means */
    run_case("synthetic", syn, VV_MODE_XRAY, 30, 20, 0, VV_COMPOSITING_BINARY_SWAP, 4);
    run_case("synthetic", syn, VV_MODE_XRAY, 110, -35, 1, VV_COMPOSITING_RADIX_K, 2);
    /* attenuated MIP: each rank's maxima and exponent sums, combined front
     * to back through the exponents in front (VV_REGION_ATTENUATED_MAX) */
    run_case("synthetic", syn, VV_MODE_ATTENUATED_MIP, 30, 20, 0, VV_COMPOSITING_BINARY_SWAP, 4);
    run_case("synthetic", syn, VV_MODE_ATTENUATED_MIP, 110, -35, 1, VV_COMPOSITING_RADIX_K, 2);
    if (argc > 1) {
        char path[4096];
        snprintf(path, sizeof path, "%s/volumes/ct_head.nrrd", argv[1]);
        vv_volume *head = NULL;
        if (vv_volume_load(&head, path, NULL) == VV_OK) {
            run_case("ct_head", head, VV_MODE_COMPOSITE, 200, 15, 0, VV_COMPOSITING_BINARY_SWAP, 4);
            run_case("ct_head", head, VV_MODE_MIP, 200, 15, 0, VV_COMPOSITING_RADIX_K, 3);
            run_case("ct_head", head, VV_MODE_ISO, 200, 15, 0, VV_COMPOSITING_RADIX_K, 3);
            run_case("ct_head", head, VV_MODE_XRAY, 200, 15, 0, VV_COMPOSITING_BINARY_SWAP, 4);
            run_case("ct_head", head, VV_MODE_ATTENUATED_MIP, 200, 15, 0, VV_COMPOSITING_RADIX_K,
                     3);
            run_case_with("raytrace", "ct_head", head, VV_MODE_COMPOSITE, 200, 15, 0,
                          VV_COMPOSITING_BINARY_SWAP, 4);
            run_case_with("raytrace", "ct_head", head, VV_MODE_MIP, 200, 15, 0,
                          VV_COMPOSITING_RADIX_K, 3);
        } else if (rank == 0) {
            printf("skip ct_head: %s\n", vv_error_message());
        }
        vv_volume_free(head);
    }
    run_failure(syn);
    vv_volume_free(syn);
    int all = 0;
    MPI_Allreduce(&failures, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    vv_parallel_finalize();
    return all ? 1 : 0;
}
