/*
 * The reader sandbox (issue 33; src/io/sandbox.c): a file read through a
 * third-party parser comes back from volvis-reader with the same voxels and
 * geometry as read in-process; whatever the reader does wrong (an abort, a
 * crash, a file outside its folder, a socket, execve, fork, a write, an
 * endless loop, running out of memory, a reply cut short: injected with
 * VOLVIS_SANDBOX_INJECT)
 * is one line of error, the test process survives, no child is left and no
 * core file is written; the CLI exits 1 with that line and writes nothing;
 * every fuzz finding of the sandboxed formats goes through the sandbox.
 */
#include "testutil.h"

#include "io/sandbox.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SANITIZED 1
#endif
#endif
#ifndef SANITIZED
#define SANITIZED 0
#endif

static char g_dir[256];

/* No child of this process is left (running or a zombie). */
static void
assert_no_child(void) {
    vv_sandbox_release_spare(); /* the reader kept for the next load */
    errno = 0;
    pid_t p = waitpid(-1, NULL, WNOHANG);
    if (!(p == -1 && errno == ECHILD))
        fail_msg("a child process is left (waitpid gave %d, %s)", (int)p, strerror(errno));
}

static vv_status
load(vv_volume **v, const char *path, int sandbox) {
    setenv("VOLVIS_SANDBOX", sandbox ? "1" : "0", 1);
    vv_error_clear();
    vv_status s = vv_volume_load(v, path, NULL);
    unsetenv("VOLVIS_SANDBOX");
    return s;
}

static void
assert_same(const char *path) {
    vv_volume *a = NULL, *b = NULL;
    vt_ok(load(&a, path, 0));
    vt_ok(load(&b, path, 1));
    assert_null(a->release);     /* in-process: the library's own memory */
    assert_non_null(b->release); /* sandbox: the child's memfd, mapped */
    assert_memory_equal(a->dims, b->dims, sizeof a->dims);
    assert_int_equal(a->type, b->type);
    assert_memory_equal(a->spacing, b->spacing, sizeof a->spacing);
    assert_memory_equal(a->origin, b->origin, sizeof a->origin);
    assert_memory_equal(a->direction, b->direction, sizeof a->direction);
    assert_memory_equal(a->range, b->range, sizeof a->range);
    assert_int_equal(a->unit, b->unit);
    assert_int_equal(a->space, b->space);
    assert_memory_equal(a->data, b->data, vv_volume_voxel_count(a) * vv_voxel_type_size(a->type));
    /* the mapping is writable, as a volume's voxels are */
    vv_volume_set(b, 0, 0, 0, 7);
    assert_near(vv_volume_get(b, 0, 0, 0), 7, 0);
    vv_volume_free(a);
    vv_volume_free(b);
    assert_no_child();
}

static void
test_same_volume(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    assert_same(vt_data("volumes/ct_head.nrrd"));
    assert_same(vt_data("volumes/avg152T1_RL_nifti.nii.gz"));
    /* a TIFF stack and a NIfTI of 16-bit voxels, written here */
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    vt_ok(vv_volume_save(v, vt_path(g_dir, "head.tif"), VV_FORMAT_TIFF, 1));
    vt_ok(vv_volume_save(v, vt_path(g_dir, "head.nii"), VV_FORMAT_NIFTI, 1));
    vv_volume_free(v);
    assert_same(vt_path(g_dir, "head.tif"));
    assert_same(vt_path(g_dir, "head.nii"));
    /* our own formats are read in-process */
    if (vt_have_data("volumes/nut.slc")) {
        setenv("VOLVIS_SANDBOX", "1", 1);
        vt_ok(vv_volume_load(&v, vt_data("volumes/nut.slc"), NULL));
        unsetenv("VOLVIS_SANDBOX");
        assert_null(v->release);
        vv_volume_free(v);
    }
}

/* Loads the CT head with the reader told to do @p what; the error must be
 * one line holding @p expect (NULL: any). */
static void
injected(const char *what, const char *expect, vv_status code) {
    setenv("VOLVIS_SANDBOX_INJECT", what, 1);
    vv_volume *v = NULL;
    vv_status s = load(&v, vt_data("volumes/ct_head.nrrd"), 1);
    unsetenv("VOLVIS_SANDBOX_INJECT");
    const char *m = vv_error_message();
    printf("# %s: %s\n", what, m);
    assert_true(s < 0);
    assert_null(v);
    assert_null(strchr(m, '\n'));
    if (expect && !strstr(m, expect))
        fail_msg("%s: \"%s\" does not say \"%s\"", what, m, expect);
    if (code)
        assert_int_equal(s, code);
    assert_no_child();
}

static void
test_injected_faults(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    char cwd[1024];
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(g_dir), 0); /* a core file would land here */
    injected("abort", "nrrd: ct_head.nrrd: the NRRD reader crashed (SIGABRT)", VV_ERR_FORMAT);
    /* under ASan its SEGV handler reports and exits (or is stopped when it
     * starts the symbolizer) */
    injected("segv", SANITIZED ? "the NRRD reader" : "the NRRD reader crashed (SIGSEGV)",
             VV_ERR_FORMAT);
    injected("open", "cannot open /etc/passwd: Permission denied", VV_ERR_IO);
    const char *forbids = "the NRRD reader made a system call the sandbox forbids (SIGSYS)";
    injected("write", forbids, VV_ERR_FORMAT);
    injected("socket", forbids, VV_ERR_FORMAT);
    injected("execve", forbids, VV_ERR_FORMAT);
    injected("fork", forbids, VV_ERR_FORMAT);
    injected("reply", "the NRRD reader sent a malformed reply and was stopped", VV_ERR_FORMAT);
    setenv("VOLVIS_SANDBOX_TIMEOUT", "1", 1);
    injected("loop", "the NRRD reader used more than 1 s of CPU time; stopped", VV_ERR_LIMIT);
    unsetenv("VOLVIS_SANDBOX_TIMEOUT");
    if (!SANITIZED) { /* no address-space limit under ASan (its shadow) */
        uint64_t budget = vv_memory_budget_get();
        vv_memory_budget_set((uint64_t)64 << 20);
        injected("oom", "the NRRD reader ran out of memory", VV_ERR_LIMIT);
        vv_memory_budget_set(budget);
    }
    struct stat st;
    assert_int_not_equal(stat("core", &st), 0);
    assert_int_not_equal(stat("volvis-sandbox-escape", &st), 0);
    assert_int_equal(chdir(cwd), 0);
    /* the loads after all that still work */
    assert_same(vt_data("volumes/ct_head.nrrd"));
}

static void
test_cli(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    const char *out = vt_path(g_dir, "never.nii");
    const char *conv[] = {"convert", vt_data("volumes/ct_head.nrrd"), out, NULL};
    unlink(out); /* from an earlier run */
    setenv("VOLVIS_SANDBOX_INJECT", "abort", 1);
    vt_run_result r = vt_run_cli_v(g_dir, conv);
    unsetenv("VOLVIS_SANDBOX_INJECT");
    printf("# stderr: %s", r.err);
    assert_int_equal(r.status, 1);
    assert_string_equal(r.err, "volvis: nrrd: ct_head.nrrd: the NRRD reader crashed (SIGABRT); the "
                               "file is malformed\n");
    struct stat st;
    assert_int_not_equal(stat(out, &st), 0);
    vt_run_result_free(&r);
    /* and without the fault the same command writes the file */
    r = vt_run_cli_v(g_dir, conv);
    assert_int_equal(r.status, 0);
    assert_int_equal(stat(out, &st), 0);
    vt_run_result_free(&r);
}

static void
test_reader_alone_and_missing(void **state) {
    (void)state;
    /* run by hand, volvis-reader says what it is for */
    char cmd[512];
    snprintf(cmd, sizeof cmd, "%s/volvis-reader 2>/dev/null", VV_BINARY_DIR);
    int st = system(cmd);
    assert_true(WIFEXITED(st));
    assert_int_equal(WEXITSTATUS(st), 2);
    /* a reader that is not there: an error naming the way out */
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    setenv("VOLVIS_READER", "/nonexistent/volvis-reader", 1);
    vv_volume *v = NULL;
    vv_status s = load(&v, vt_data("volumes/ct_head.nrrd"), 1);
    unsetenv("VOLVIS_READER");
    assert_int_equal(s, VV_ERR_IO);
    assert_non_null(strstr(vv_error_message(), "VOLVIS_SANDBOX=0"));
    assert_no_child();
}

/* Every kept fuzz input of a sandboxed format, through the sandbox: an
 * error or a volume, never more. */
static void
test_fuzz_corpus(void **state) {
    (void)state;
    static const char *const dirs[] = {"nrrd", "nifti", "tiff", "dicom"};
    int n = 0;
    for (size_t d = 0; d < sizeof dirs / sizeof dirs[0]; d++) {
        char dir[512];
        snprintf(dir, sizeof dir, "%s/tests/fuzz/corpus/%s", VV_SOURCE_DIR, dirs[d]);
        DIR *dp = opendir(dir);
        assert_non_null(dp);
        struct dirent *e;
        while ((e = readdir(dp))) {
            if (e->d_name[0] == '.')
                continue;
            char path[1024];
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
            vv_load_options o;
            vv_load_options_init(&o);
            vv_format_parse(dirs[d], &o.format);
            setenv("VOLVIS_SANDBOX", "1", 1);
            vv_volume *v = NULL;
            vv_error_clear();
            vv_status s = vv_volume_load(&v, path, &o);
            unsetenv("VOLVIS_SANDBOX");
            if (s == VV_OK) {
                assert_non_null(v->release);
                vv_volume_free(v);
            } else {
                assert_null(strchr(vv_error_message(), '\n'));
            }
            assert_no_child();
            n++;
        }
        closedir(dp);
    }
    printf("# %d fuzz inputs read through the sandbox\n", n);
    assert_true(n >= 20);
}

int
main(void) {
    snprintf(g_dir, sizeof g_dir, "%s", vt_outdir("sandbox"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_volume), cmocka_unit_test(test_injected_faults),
        cmocka_unit_test(test_cli),         cmocka_unit_test(test_reader_alone_and_missing),
        cmocka_unit_test(test_fuzz_corpus),
    };
    return vt_run_tests(tests, NULL, NULL);
}
