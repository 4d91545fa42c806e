/*
 * Nothing is lost when a write fails: every command that writes (images,
 * volumes, meshes, compressed volumes, videos) run against an existing
 * output file with a file size limit (RLIMIT_FSIZE, what `prlimit --fsize`
 * sets: the writes fail as on a full disk) exits non-zero with a one-line
 * error naming the file, leaves the old file byte for byte, and leaves no
 * temporary file. A process killed mid-write (SIGKILL during an atomic
 * file, and during a scene save) leaves the old file and nothing else
 * either.
 */
#include "testutil.h"

#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/internal.h"
#include "volvis/model.h"
#include "volvis/scene.h"

static const char *
outdir(void) {
    return vt_outdir("atomic_writes");
}

/* A fresh, empty folder under the test output. */
static const char *
fresh_dir(const char *name) {
    static char dir[1024];
    snprintf(dir, sizeof dir, "%s/%s", outdir(), name);
    char cmd[2200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
    assert_int_equal(system(cmd), 0);
    return dir;
}

/* Number of entries in @p dir besides . and .. */
static int
count_entries(const char *dir) {
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return n;
}

static const char OLD[] = "the previous contents, which must survive\n";

static void
check_old(const char *path) {
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char buf[256] = {0};
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    assert_int_equal(n, strlen(OLD));
    assert_string_equal(buf, OLD);
}

/* Runs the CLI with a file size limit of @p limit bytes on @p out, which
 * holds OLD before. The CLI's own stdout and stderr go to files in another
 * folder, under the same limit (they stay small). */
static void
limited_run(const char *dir, const char *out, rlim_t limit, const char *const *args) {
    vt_write_file(out, OLD, strlen(OLD));
    struct rlimit old, lim;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    lim = old;
    lim.rlim_cur = limit;
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    vt_run_result r = vt_run_cli_v(outdir(), args);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
    const char *base = strrchr(out, '/') + 1;
    if (r.status == 0 || !strstr(r.err, base) || strchr(r.err, '\n') != r.err + strlen(r.err) - 1)
        fail_msg("%s %s: status %d, stderr '%s' (expected one line naming %s)", args[0], out,
                 r.status, r.err, base);
    vt_run_result_free(&r);
    check_old(out);
    assert_int_equal(count_entries(dir), 1);
}

static void
test_file_size_limit(void **state) {
    (void)state;
    const char *vol = vt_data("volumes/neghip.slc");
    const char *dir = fresh_dir("limit");
    char out[1200];
    snprintf(out, sizeof out, "%s/image.png", dir);
    limited_run(dir, out, 4096,
                (const char *const[]){"render", vol, "--size", "256x256", "-o", out, "-q", NULL});
    snprintf(out, sizeof out, "%s/volume.nrrd", dir);
    dir = fresh_dir("limit");
    limited_run(dir, out, 4096, (const char *const[]){"convert", vol, out, NULL});
    dir = fresh_dir("limit");
    snprintf(out, sizeof out, "%s/surface.ply", dir);
    limited_run(dir, out, 4096,
                (const char *const[]){"isosurface", vol, "--iso", "100", "-o", out, "-q", NULL});
    dir = fresh_dir("limit");
    snprintf(out, sizeof out, "%s/compressed.vvc", dir);
    limited_run(dir, out, 4096, (const char *const[]){"compress", vol, out, "--rate", "4", NULL});
    dir = fresh_dir("limit");
    snprintf(out, sizeof out, "%s/solid.nrrd", dir);
    limited_run(dir, out, 4096,
                (const char *const[]){"voxelize", vt_data("meshes/knot1.off"), "--size", "48", "-o",
                                      out, "-q", NULL});
    dir = fresh_dir("limit");
    snprintf(out, sizeof out, "%s/orbit.mp4", dir);
    limited_run(dir, out, 2048,
                (const char *const[]){"animate", vol, "--size", "64x64", "--orbit", "90",
                                      "--frames", "4", "-o", out, "-q", NULL});
}

/* A child killed while it writes @p path through an atomic file. */
static void
killed_mid_write(const char *dir, const char *path) {
    vt_write_file(path, OLD, strlen(OLD));
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        vv_atomic_file af;
        if (vv_atomic_file_open(&af, path) != VV_OK)
            _exit(3);
        static char block[1 << 16];
        memset(block, 'x', sizeof block);
        for (int i = 0; i < 16; i++)
            fwrite(block, 1, sizeof block, af.fp);
        fflush(af.fp);
        raise(SIGKILL);
        _exit(4);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    check_old(path);
    assert_int_equal(count_entries(dir), 1);
}

/* A scene saved by a child that dies in the middle (its file size limit
 * raises SIGXFSZ, whose default action ends the process). */
static void
scene_killed(const char *dir, const char *path) {
    vt_write_file(path, OLD, strlen(OLD));
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, VV_SOURCE_DIR "/examples/ct_head.json"));
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        signal(SIGXFSZ, SIG_DFL);
        struct rlimit lim;
        getrlimit(RLIMIT_FSIZE, &lim);
        lim.rlim_cur = 200;
        setrlimit(RLIMIT_FSIZE, &lim);
        const char *files[] = {"ct_head.nrrd", NULL};
        vv_scene_save(w, path, files);
        _exit(5); /* the save must not have succeeded */
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 5));
    vv_world_free(w);
    check_old(path);
    assert_int_equal(count_entries(dir), 1);
}

static void
test_killed_mid_write(void **state) {
    (void)state;
    const char *dir = fresh_dir("killed");
    char path[1200];
    snprintf(path, sizeof path, "%s/volume.raw", dir);
    killed_mid_write(dir, path);
    dir = fresh_dir("killed");
    snprintf(path, sizeof path, "%s/scene.json", dir);
    scene_killed(dir, path);
    /* and a normal write still replaces the file, with the usual permissions */
    vv_atomic_file af;
    vt_ok(vv_atomic_file_open(&af, path));
    fputs("new\n", af.fp);
    vt_ok(vv_atomic_file_commit(&af));
    assert_int_equal(count_entries(dir), 1);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char buf[16] = {0};
    assert_int_equal(fread(buf, 1, sizeof buf, f), 4);
    fclose(f);
    assert_string_equal(buf, "new\n");
    mode_t um = umask(022);
    umask(um);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0666 & ~um);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_file_size_limit),
        cmocka_unit_test(test_killed_mid_write),
    };
    return vt_run_tests(tests, NULL, NULL);
}
