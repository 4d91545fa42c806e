/*
 * Tests of `volvis isosurface` and `volvis measure`, run as a separate
 * process (posix_spawn, the helper of test_cli.c) with stdout and stderr
 * captured. The executable is $VV_CLI (set by CTest); output goes under
 * $VV_TEST_OUT/cli_surface. Numbers printed are checked against the library.
 */
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

typedef vt_run_result run_result;

/* Captured output and files of these tests go to build/.../test-out/cli_surface. */
#define outdir() vt_outdir("cli_surface")
#define out_file(name) vt_path(outdir(), name)
#define free_result vt_run_result_free
#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})

static int
file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static int
count_lines(const char *s) {
    int n = 0;
    for (; *s; s++)
        n += *s == '\n';
    return n;
}

/* The number after "KEY": in a JSON text (first occurrence after from). */
static double
json_number(const char *text, const char *key) {
    char pat[128];
    snprintf(pat, sizeof pat, "\"%s\": ", key);
    const char *p = strstr(text, pat);
    if (!p)
        fail_msg("no %s in %s", key, text);
    return strtod(p + strlen(pat), NULL);
}

static void
test_isosurface_files(void **state) {
    (void)state;
    const char *in = vt_data("volumes/neghip.slc");
    const char *ext[] = {"ply", "obj", "stl"};
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, in, NULL));
    vv_mesh *ref = NULL;
    vt_ok(vv_isosurface_extract(&ref, v, 60.5, NULL));
    for (int e = 0; e < 3; e++) {
        char name[64];
        snprintf(name, sizeof name, "neghip.%s", ext[e]);
        const char *out = out_file(name);
        run_result r = run_cli("isosurface", in, "--iso", "60.5", "-o", out);
        assert_int_equal(r.status, 0);
        assert_non_null(strstr(r.out, "wrote"));
        assert_string_equal(r.err, "");
        vv_mesh *m = NULL;
        vt_ok(vv_mesh_load(&m, out));
        assert_int_equal(m->n_triangles, ref->n_triangles);
        assert_near(vv_mesh_area(m), vv_mesh_area(ref), 1e-4 * vv_mesh_area(ref));
        vv_mesh_free(m);
        free_result(&r);
    }
    /* previews */
    run_result r =
        run_cli("isosurface", in, "--iso", "60.5", "--coarse", "1", "-o", out_file("coarse.ply"));
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "coarse Marching Cubes"));
    free_result(&r);
    r = run_cli("isosurface", in, "--iso", "60.5", "--parc", "3", "-o", out_file("parc.obj"));
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "PARC"));
    free_result(&r);
    /* region and cut plane */
    r = run_cli("isosurface", in, "--iso", "60.5", "--roi", "0,0,0:40,65,65", "--cut",
                "0,0,30:0,0,1", "-o", out_file("cut.ply"));
    assert_int_equal(r.status, 0);
    free_result(&r);
    vv_mesh_free(ref);
    vv_volume_free(v);
}

static void
test_isosurface_errors(void **state) {
    (void)state;
    const char *in = vt_data("volumes/neghip.slc");
    const char *out = out_file("never.ply");
    remove(out);
    struct {
        int status;
        const char *args[10];
    } cases[] = {
        {2, {"isosurface", in, "-o", "never.ply", NULL}},              /* no --iso */
        {2, {"isosurface", in, "--iso", "60.5", NULL}},                /* no -o */
        {2, {"isosurface", in, "--iso", "60.5", "-o", "x.vtk", NULL}}, /* format */
        {2, {"isosurface", in, "--iso", "6x", "-o", "x.ply", NULL}},   /* number */
        {2, {"isosurface", in, "--iso", "60.5", "--coarse", "1", "--parc", "1", "-o", "x.ply"}},
        {2, {"isosurface", in, "--iso", "60.5", "--roi", "0,0:1,1", "-o", "x.ply", NULL}},
        {1, {"isosurface", in, "--iso", "900", "-o", NULL, NULL}},                  /* range */
        {1, {"isosurface", "/nonexistent.slc", "--iso", "60.5", "-o", NULL, NULL}}, /* file */
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *args[12];
        int n = 0;
        for (int i = 0; i < 10 && cases[c].args[i]; i++)
            args[n++] = cases[c].args[i];
        if (cases[c].status == 1)
            args[n++] = out;
        args[n] = NULL;
        run_result r = vt_run_cli_v(outdir(), args);
        if (r.status != cases[c].status)
            fail_msg("case %zu: status %d, want %d; stderr: %s", c, r.status, cases[c].status,
                     r.err);
        assert_int_equal(count_lines(r.err), 1);
        assert_non_null(strstr(r.err, "volvis: "));
        free_result(&r);
    }
    assert_false(file_exists(out));
}

static void
test_measure_volume(void **state) {
    (void)state;
    const char *in = vt_data("volumes/ct_head.nrrd");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, in, NULL));
    vv_isosurface_measure mc, vx;
    vv_isosurface_measure_options o;
    vv_isosurface_measure_options_init(&o);
    vt_ok(vv_measure_isosurface(&mc, v, 300, &o));
    o.method = VV_MEASURE_VOXEL;
    vt_ok(vv_measure_isosurface(&vx, v, 300, &o));
    run_result r = run_cli("measure", in, "--iso", "300");
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "surface area"));
    assert_non_null(strstr(r.out, "enclosed volume"));
    assert_non_null(strstr(r.out, "Marching Cubes"));
    free_result(&r);
    r = run_cli("measure", in, "--iso", "300", "--json");
    assert_int_equal(r.status, 0);
    assert_near(json_number(r.out, "area"), mc.area, 1e-6 * mc.area);
    assert_near(json_number(r.out, "volume"), mc.volume, 1e-6 * mc.volume);
    free_result(&r);
    r = run_cli("measure", in, "--iso", "300", "--method", "voxel", "--json");
    assert_int_equal(r.status, 0);
    assert_near(json_number(r.out, "volume"), vx.volume, 1e-6 * vx.volume);
    assert_near(json_number(r.out, "voxels"), (double)vx.voxels, 0.5);
    free_result(&r);
    /* Marching Cubes with a cut plane: the two sides add up to the whole */
    double side_v[2], side_a[2];
    for (int h = 0; h < 2; h++) {
        r = run_cli("measure", in, "--iso", "300", "--cut", h ? "122,0,0:-1,0,0" : "122,0,0:1,0,0",
                    "--json");
        assert_int_equal(r.status, 0);
        side_v[h] = json_number(r.out, "volume");
        side_a[h] = json_number(r.out, "area");
        assert_true(side_v[h] > 0.3 * mc.volume && side_v[h] < 0.7 * mc.volume);
        free_result(&r);
    }
    assert_near(side_v[0] + side_v[1], mc.volume, 1e-6 * mc.volume);
    assert_near(side_a[0] + side_a[1], mc.area, 1e-6 * mc.area);
    /* histogram with a plot, distance in voxel coordinates */
    const char *png = out_file("hist.png");
    remove(png);
    r = run_cli("measure", in, "--histogram", "--bins", "16", "--plot", png, "--log", "--json",
                "--distance", "voxel:0,0,0", "voxel:10,0,0");
    assert_int_equal(r.status, 0);
    assert_true(file_exists(png));
    assert_near(json_number(r.out, "total"), 256.0 * 256 * 108, 0.5);
    assert_near(json_number(r.out, "value"), 10 * v->spacing[0], 1e-6);
    free_result(&r);
    /* geodesic across the sphere phantom: half a great circle of the measured sphere */
    r = run_cli("measure", vt_data("volumes/sphere.slc"), "--iso", "127.5", "--geodesic", "0,0,0",
                "49,49,49", "--json");
    assert_int_equal(r.status, 0);
    {
        double area = json_number(r.out, "area"), rad = sqrt(area / (4 * VV_PI));
        const char *g = strstr(r.out, "\"geodesic\"");
        assert_non_null(g);
        double geo = json_number(g, "value");
        assert_true(fabs(geo / (VV_PI * rad) - 1) < 0.01);
    }
    free_result(&r);
    r = run_cli("measure", in, "--histogram", "--bins", "4");
    assert_int_equal(r.status, 0);
    assert_int_equal(count_lines(r.out), 2 + 4);
    free_result(&r);
    vv_volume_free(v);
}

static void
test_measure_sections_and_meshes(void **state) {
    (void)state;
    /* two spheres: the section of each */
    const int n = 40;
    const int dims[3] = {n, n, n};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double a =
                    7 - sqrt((i - 10.) * (i - 10.) + (j - 10.) * (j - 10.) + (k - 10.) * (k - 10.));
                double b =
                    9 - sqrt((i - 28.) * (i - 28.) + (j - 27.) * (j - 27.) + (k - 26.) * (k - 26.));
                vv_volume_set(v, i, j, k, a > b ? a : b);
            }
    vv_volume_update_range(v);
    const char *nrrd = out_file("spheres.nrrd");
    vt_ok(vv_volume_save(v, nrrd, VV_FORMAT_NRRD, 0));
    run_result r = run_cli("measure", nrrd, "--iso", "0", "--seed", "voxel:10,10,17", "--json");
    assert_int_equal(r.status, 0);
    double v0 = 4.0 / 3 * VV_PI * 343;
    assert_true(fabs(json_number(r.out, "volume") / v0 - 1) < 0.02);
    free_result(&r);
    r = run_cli("measure", nrrd, "--iso", "0", "--seed", "28,27,35", "--method", "voxel");
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "surface-tracked section"));
    free_result(&r);
    /* a closed mesh: its volume; the distance to another */
    vv_mesh *m = NULL;
    vt_ok(vv_isosurface_extract(&m, v, 0, NULL));
    const char *ply = out_file("spheres.ply");
    vt_ok(vv_mesh_save(m, ply));
    r = run_cli("measure", ply, "--volume", "--json");
    assert_int_equal(r.status, 0);
    assert_near(json_number(r.out, "volume"), vv_mesh_signed_volume(m),
                1e-5 * vv_mesh_signed_volume(m));
    free_result(&r);
    r = run_cli("measure", ply, "--to", vt_data("meshes/bunny.ply"));
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "minimum distance"));
    free_result(&r);
    /* an open mesh asked for its volume */
    r = run_cli("measure", vt_data("meshes/bunny.ply"), "--volume");
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "boundary edges"));
    free_result(&r);
    /* bad input */
    struct {
        int status;
        const char *args[8];
    } cases[] = {
        {1, {"measure", nrrd, "--iso", "100", NULL}},                    /* outside range */
        {1, {"measure", nrrd, "--iso", "0", "--seed", "voxel:-9,0,0"}},  /* seed outside */
        {1, {"measure", nrrd, "--iso", "0", "--seed", "voxel:0,0,39"}},  /* not near */
        {2, {"measure", nrrd, NULL}},                                    /* nothing asked */
        {2, {"measure", nrrd, "--iso", "0", "--method", "cubes", NULL}}, /* method */
        {2, {"measure", nrrd, "--seed", "1,2,3", NULL}},                 /* seed, no iso */
        {2, {"measure", nrrd, "--distance", "1,2", NULL}},               /* one point */
        {2, {"measure", nrrd, "--plot", "x.png", NULL}},                 /* plot alone */
        {2, {"measure", ply, "--iso", "3", NULL}},                       /* iso on mesh */
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        run_result q = vt_run_cli_v(outdir(), cases[c].args);
        if (q.status != cases[c].status)
            fail_msg("case %zu: status %d, want %d; stderr: %s", c, q.status, cases[c].status,
                     q.err);
        assert_int_equal(count_lines(q.err), 1);
        free_result(&q);
    }
    vv_mesh_free(m);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_isosurface_files),
        cmocka_unit_test(test_isosurface_errors),
        cmocka_unit_test(test_measure_volume),
        cmocka_unit_test(test_measure_sections_and_meshes),
    };
    return vt_run_tests(tests, NULL, NULL);
}
