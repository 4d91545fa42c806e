/*
 * Distributed rendering over MPI (src/parallel), run through mpirun:
 * mpi_compare (tests/parallel/mpi_compare.c) on 1, 2, 3, 4 and 7 ranks (the
 * CT head on 3 and 7 only, to keep the test short): the distributed image
 * equals the one-process image (MIP and MinIP bit for bit, composite >= 50
 * dB), by binary swap and radix-k, with the cuts through the objects; a rank
 * that cannot render fails every rank. Every run has a time limit (timeout),
 * so a hang fails instead of blocking. Skipped when the build has no MPI.
 */
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

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

static int
have_mpi(void) {
#ifdef VV_MPI_COMPARE
    return 1;
#else
    return 0;
#endif
}

/* Under ASan, MPIRUN_LEAKS runs the ranks' leak check, which skips Open
 * MPI's own allocations (tests/parallel/mpi_lsan.supp) and needs full stack
 * unwinding on every malloc (about 13 times slower for three ranks); the
 * run on 3 ranks has it, the run on 7 (the same cases, radix-k's other
 * rounds) ASan's other checks. Both are harmless without ASan. */
#define MPIRUN_BASE "timeout 300 " VT_MPI_ENV " " VV_MPIEXEC " --allow-run-as-root --oversubscribe"
#define MPIRUN_LEAKS                                                                               \
    MPIRUN_BASE " -x ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:fast_unwind_on_malloc=0"         \
                " -x LSAN_OPTIONS=suppressions=" VV_SOURCE_DIR "/tests/parallel/mpi_lsan.supp"
#define MPIRUN MPIRUN_BASE " -x ASAN_OPTIONS=detect_leaks=0:abort_on_error=1"

static void
test_compare(void **state) {
    (void)state;
    if (!have_mpi())
        vt_skip("the build has no MPI (libopenmpi-dev, openmpi-bin)");
#ifdef VV_MPI_COMPARE
#ifdef __SANITIZE_ADDRESS__
    /* under ASan (several times slower) the two counts that exercise most:
     * the fold and radix-k 7 */
    const int counts[] = {3, 7};
#else
    const int counts[] = {1, 2, 3, 4, 7};
#endif
    struct stat st;
    const int data = stat(VV_DATA_DIR "/volumes/ct_head.nrrd", &st) == 0;
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
        char cmd[4096], *out = NULL;
        snprintf(cmd, sizeof cmd, "%s -np %d %s %s 2>&1", counts[i] == 3 ? MPIRUN_LEAKS : MPIRUN,
                 counts[i], VV_MPI_COMPARE,
                 data && (counts[i] == 3 || counts[i] == 7) ? VV_DATA_DIR : "");
        const int rc = run(cmd, &out);
        printf("%s", out);
        if (rc != 0)
            fail_msg("mpi_compare on %d ranks: exit %d\n%s", counts[i], rc, out);
        /* every case ran and passed */
        assert_null(strstr(out, "FAIL"));
        assert_non_null(strstr(out, "ok raycast synthetic mip binary-swap"));
        assert_non_null(strstr(out, "ok raycast synthetic composite radix-k"));
        /* the ray tracer through the same region contract */
        assert_non_null(strstr(out, "ok raytrace synthetic composite binary-swap"));
        assert_non_null(strstr(out, "ok raytrace synthetic mip binary-swap"));
        if (data && (counts[i] == 3 || counts[i] == 7))
            assert_non_null(strstr(out, "ok raytrace ct_head composite binary-swap"));
        if (counts[i] > 1)
            assert_non_null(strstr(out, "ok failure on rank 1"));
        free(out);
    }
    if (!data)
        vt_skip("the synthetic cases passed; the CT head cases need ../shared/data");
#endif
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compare),
    };
    return vt_run_tests(tests, NULL, NULL);
}
