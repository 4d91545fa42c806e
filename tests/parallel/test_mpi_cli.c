/*
 * The CLI under mpirun (src/parallel, apps/volvis/render_parallel.c):
 * `volvis render` on 3 ranks: rank 0 writes the PNG and prints "on 3
 * ranks"; `volvis animate` likewise, frame by frame, and resumes; a .vvb read
 * by bricks (each rank its own box) gives the one-process MIP image, and so
 * does an OME-Zarr pyramid at levels 0 and 1 (each rank its box of the
 * level, through its own chunk cache); a rank that
 * cannot read the input (or its .vvb is cut short) and ranks that read different scene
 * files stop every
 * rank with one clear error and no output; the ray tracer gives the
 * one-process image at quality 1 (MIP bit for bit, composite >= 50 dB on
 * the PNGs); a renderer without the region contract is refused.
 * Every run has a time limit (timeout), so a hang fails instead of blocking.
 * Skipped when the build has no MPI.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

#define outdir() vt_outdir("parallel")

/* Runs a shell command line, output (stdout and stderr) into *out. */
static int
run(const char *cmd, char **out) {
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    assert_non_null(buf);
    size_t got;
    while ((got = fread(buf + n, 1, cap - 1 - n, p)) > 0) {
        n += got;
        if (n + 1 >= cap) {
            cap *= 2;
            buf = realloc(buf, cap);
            assert_non_null(buf);
        }
    }
    buf[n] = 0;
    int st = pclose(p);
    *out = buf;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
}

/* Runs @p cmd, which must exit 0; when @p needle is given, its output must
 * hold it. */
static void
run_ok(const char *cmd, const char *needle) {
    char *out = NULL;
    int rc = run(cmd, &out);
    if (rc != 0)
        fail_msg("%s\n%s", cmd, out);
    if (needle && !strstr(out, needle))
        fail_msg("%s: no '%s' in\n%s", cmd, needle, out);
    free(out);
}

/* Files @p a and @p b hold the same bytes. */
static void
same_bytes(const char *a, const char *b) {
    size_t na, nb;
    unsigned char *pa = vt_read_file(a, &na), *pb = vt_read_file(b, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(pa, pb, na);
    free(pa);
    free(pb);
}

static const char *
cli(void) {
    const char *c = getenv("VV_CLI");
    return c && *c ? c : VV_BINARY_DIR "/volvis";
}

static int
have_mpi(void) {
#ifdef VV_MPI_COMPARE
    return 1;
#else
    return 0;
#endif
}

/* Under ASan, MPIRUN_LEAKS runs the ranks' leak check, which skips Open
 * MPI's own allocations (tests/parallel/mpi_lsan.supp); it needs full stack
 * unwinding on every malloc, which makes a run of three ranks about 13 times
 * slower (20 s against 1.5 s: Open MPI's start-up allocates a lot), so it is
 * used on the runs whose paths differ most (a render, a .vvb read by boxes,
 * the ray tracer's regions, a rank's failed read) and MPIRUN, with ASan's
 * other checks, on the rest. Both are harmless without ASan. */
#define MPIRUN_BASE "timeout 300 " VT_MPI_ENV " " VV_MPIEXEC " --allow-run-as-root --oversubscribe"
#define MPIRUN_LEAKS                                                                               \
    MPIRUN_BASE " -x ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:fast_unwind_on_malloc=0"         \
                " -x LSAN_OPTIONS=suppressions=" VV_SOURCE_DIR "/tests/parallel/mpi_lsan.supp"
#define MPIRUN MPIRUN_BASE " -x ASAN_OPTIONS=detect_leaks=0:abort_on_error=1"

static void
test_cli(void **state) {
    (void)state;
    if (!have_mpi())
        vt_skip("the build has no MPI (libopenmpi-dev, openmpi-bin)");
#ifdef VV_MPI_COMPARE
    const char *dir = outdir();
    /* two scene folders with a scene of the same name and different content,
     * and a wrapper that runs rank 2 in another folder than the others */
    char a[1200], b[1200], path[1300], wrap[1300];
    snprintf(a, sizeof a, "%s/a", dir);
    snprintf(b, sizeof b, "%s/b", dir);
    mkdir(a, 0755);
    mkdir(b, 0755);
    char scene[1400];
    snprintf(scene, sizeof scene,
             "{\"objects\": [{\"file\": \"%s\"}], \"view\": {\"width\": 64, \"height\": 48}}\n",
             vt_data("volumes/neghip.slc"));
    snprintf(path, sizeof path, "%s/s.json", a);
    vt_write_file(path, scene, strlen(scene));
    snprintf(scene, sizeof scene,
             "{\"objects\": [{\"file\": \"%s\", \"mode\": \"mip\"}], \"view\": {\"width\": 64, "
             "\"height\": 48}}\n",
             vt_data("volumes/neghip.slc"));
    snprintf(path, sizeof path, "%s/s.json", b);
    vt_write_file(path, scene, strlen(scene));
    snprintf(wrap, sizeof wrap, "%s/wrap.sh", dir);
    const char *w = "#!/bin/sh\n"
                    "if [ \"$OMPI_COMM_WORLD_RANK\" = 2 ]; then cd \"$2\"; else cd \"$1\"; fi\n"
                    "shift 2\nexec \"$@\"\n";
    vt_write_file(wrap, w, strlen(w));
    chmod(wrap, 0755);
    struct stat st;
    if (stat(vt_data("volumes/neghip.slc"), &st) != 0)
        vt_skip("../shared/data/volumes/neghip.slc is missing");

    char cmd[8192], *out = NULL, png[1400];
    /* the same scene everywhere: rank 0 writes and names the rank count */
    snprintf(png, sizeof png, "%s/three.png", dir);
    remove(png);
    snprintf(cmd, sizeof cmd, MPIRUN_LEAKS " -np 3 %s %s %s %s render s.json -o %s 2>&1", wrap, a,
             a, cli(), png);
    int rc = run(cmd, &out);
    if (rc != 0)
        fail_msg("%s\n%s", cmd, out);
    assert_non_null(strstr(out, "on 3 ranks)"));
    /* one wrote line: the other ranks print nothing */
    assert_non_null(strstr(out, "wrote"));
    assert_null(strstr(strstr(out, "wrote") + 5, "wrote"));
    assert_int_equal(stat(png, &st), 0);
    free(out);

    /* rank 2 reads another scene file of the same name */
    snprintf(png, sizeof png, "%s/disagree.png", dir);
    remove(png);
    snprintf(cmd, sizeof cmd, MPIRUN " -np 4 %s %s %s %s render s.json -o %s 2>&1", wrap, a, b,
             cli(), png);
    rc = run(cmd, &out);
    assert_int_not_equal(rc, 0);
    assert_int_not_equal(rc, 124); /* not the time limit */
    assert_non_null(strstr(out, "volvis: ranks disagree on the input file s.json"));
    assert_int_not_equal(stat(png, &st), 0);
    free(out);

    /* rank 2 cannot read its input: every rank stops with rank 2's error */
    snprintf(png, sizeof png, "%s/missing.png", dir);
    remove(png);
    snprintf(cmd, sizeof cmd, MPIRUN_LEAKS " -np 4 %s %s /nonexistent %s render s.json -o %s 2>&1",
             wrap, a, cli(), png);
    rc = run(cmd, &out);
    assert_int_not_equal(rc, 0);
    assert_int_not_equal(rc, 124);
    assert_non_null(strstr(out, "volvis: rank 2: s.json: No such file or directory"));
    assert_int_not_equal(stat(png, &st), 0);
    free(out);

    /* volvis animate: every frame over the ranks; a second run resumes
     * (rank 0 reuses the frames, the other ranks follow it) */
    char frames[1100];
    snprintf(frames, sizeof frames, "%s/frames", dir);
    mkdir(frames, 0755);
    for (int i = 0; i < 3; i++) {
        snprintf(png, sizeof png, "%s/frame_%04d.png", frames, i);
        remove(png);
    }
    for (int pass = 0; pass < 2; pass++) {
        snprintf(cmd, sizeof cmd,
                 MPIRUN " -np 2 %s %s %s %s animate s.json --orbit 90 --frames 3 -o %s 2>&1", wrap,
                 a, a, cli(), frames);
        rc = run(cmd, &out);
        if (rc != 0)
            fail_msg("%s\n%s", cmd, out);
        assert_non_null(strstr(out, pass == 0 ? "3 rendered, 0 reused" : "0 rendered, 3 reused"));
        assert_non_null(strstr(out, "on 2 ranks)"));
        free(out);
    }
    for (int i = 0; i < 3; i++) {
        snprintf(png, sizeof png, "%s/frame_%04d.png", frames, i);
        assert_int_equal(stat(png, &st), 0);
    }

    /* a .vvb: every rank reads only its own box; MIP equals one process's
     * image; a copy cut short in rank 2's folder stops every rank with rank
     * 2's error */
    {
        char vvb[1300], cut[1300], one[1400], three[1400];
        snprintf(vvb, sizeof vvb, "%s/v.vvb", a);
        snprintf(cut, sizeof cut, "%s/v.vvb", b);
        snprintf(one, sizeof one, "%s/vvb1.png", dir);
        snprintf(three, sizeof three, "%s/vvb3.png", dir);
        vv_volume *v = NULL;
        vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
        vt_ok(vt_save(v, vvb, VV_FORMAT_VVB, -1, 1));
        vv_volume_free(v);
        size_t len;
        unsigned char *bytes = vt_read_file(vvb, &len);
        vt_write_file(cut, bytes, len - 1000);
        free(bytes);
        snprintf(cmd, sizeof cmd, "%s render %s --mode mip --size 64x48 -q -o %s 2>&1", cli(), vvb,
                 one);
        run_ok(cmd, NULL);
        snprintf(cmd, sizeof cmd,
                 MPIRUN_LEAKS " -np 3 %s %s %s %s render v.vvb --mode mip --size 64x48 -o %s 2>&1",
                 wrap, a, a, cli(), three);
        run_ok(cmd, "on 3 ranks)");
        same_bytes(one, three);
        snprintf(png, sizeof png, "%s/cut.png", dir);
        remove(png);
        snprintf(cmd, sizeof cmd, MPIRUN " -np 4 %s %s %s %s render v.vvb -o %s 2>&1", wrap, a, b,
                 cli(), png);
        rc = run(cmd, &out);
        assert_int_not_equal(rc, 0);
        assert_int_not_equal(rc, 124);
        assert_non_null(strstr(out, "volvis: rank 2: bricks: v.vvb: "));
        assert_non_null(strstr(out, "past the end of the file"));
        assert_int_not_equal(stat(png, &st), 0);
        free(out);
    }

    /* an OME-Zarr pyramid: every rank reads only its box of the level
     * through its own chunk cache; MIP at levels 0 and 1 equals one
     * process's in-memory image of that level (an explicit transfer
     * function: the default one comes from the coarsest level's histogram
     * on the ranks) */
    {
        char store[1300], one[1400], three[1400];
        snprintf(store, sizeof store, "%s/n.zarr", a);
        snprintf(cmd, sizeof cmd, "%s convert %s %s -q 2>&1", cli(), vt_data("volumes/neghip.slc"),
                 store);
        run_ok(cmd, NULL);
        for (int level = 0; level < 2; level++) {
            snprintf(one, sizeof one, "%s/zarr1_%d.png", dir, level);
            snprintf(three, sizeof three, "%s/zarr3_%d.png", dir, level);
            snprintf(cmd, sizeof cmd,
                     "%s render %s --level %d --mode mip --tf 20:200 --size 64x48 -q -o %s 2>&1",
                     cli(), store, level, one);
            run_ok(cmd, NULL);
            snprintf(cmd, sizeof cmd,
                     MPIRUN " -np 3 %s %s %s %s render n.zarr --level %d --mode mip --tf 20:200 "
                            "--size 64x48 -o %s 2>&1",
                     wrap, a, a, cli(), level, three);
            run_ok(cmd, "on 3 ranks)");
            same_bytes(one, three);
        }
    }

    /* the ray tracer: the one-process image at quality 1 without adaptive
     * refinement (regions trace one ray a pixel); MIP byte for byte,
     * composite >= 50 dB */
    for (int m = 0; m < 2; m++) {
        char one[1400], three[1400];
        snprintf(one, sizeof one, "%s/rt1_%d.png", dir, m);
        snprintf(three, sizeof three, "%s/rt3_%d.png", dir, m);
        const char *mode = m ? "--mode mip" : "";
        snprintf(cmd, sizeof cmd,
                 "%s render %s --renderer raytrace --quality 1 --set refinement=off %s -q -o %s "
                 "2>&1",
                 cli(), vt_data("volumes/neghip.slc"), mode, one);
        rc = run(cmd, &out);
        if (rc != 0)
            fail_msg("%s\n%s", cmd, out);
        free(out);
        snprintf(cmd, sizeof cmd,
                 "%s -np 3 %s %s %s %s render %s --renderer raytrace --quality 1 %s -o %s 2>&1",
                 m ? MPIRUN : MPIRUN_LEAKS, wrap, a, a, cli(), vt_data("volumes/neghip.slc"), mode,
                 three);
        rc = run(cmd, &out);
        if (rc != 0)
            fail_msg("%s\n%s", cmd, out);
        assert_non_null(strstr(out, "on 3 ranks)"));
        free(out);
        const double db = vt_png_psnr(one, three);
        printf("mpirun -np 3 raytrace %s: %.1f dB against one process\n", m ? "mip" : "composite",
               db);
        if (m)
            assert_true(isinf(db));
        else
            assert_true(db >= 50);
    }

    /* a renderer without the region contract is refused on every rank */
    snprintf(cmd, sizeof cmd,
             MPIRUN " -np 2 %s %s %s %s render s.json --renderer splat -o %s/splat.png 2>&1", wrap,
             a, a, cli(), dir);
    rc = run(cmd, &out);
    assert_int_not_equal(rc, 0);
    assert_int_not_equal(rc, 124);
    assert_non_null(strstr(out, "splat renders no regions"));
    free(out);
#endif
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cli),
    };
    return vt_run_tests(tests, NULL, NULL);
}
