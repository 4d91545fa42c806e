/*
 * Temporaries named by their writer (src/core/tmpfiles.c): a name made by
 * vv_tmp_name parses back to its owner; vv_tmp_sweep removes the
 * temporaries (files, and folders with all they hold) of writers that are
 * gone -- a child that exited, a process id given to another process
 * since -- and keeps those of running writers (this process, a live
 * child), of another host, names that do not parse, and symbolic links;
 * it never follows a link out of a folder it removes. vv_atomic_file_open
 * sweeps the target it opens.
 */
#include "testutil.h"

#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/internal.h"

/* A fresh, empty folder under the test output. */
static const char *
fresh_dir(const char *name) {
    static char dir[1024];
    snprintf(dir, sizeof dir, "%s/%s", vt_outdir("tmpfiles"), name);
    char cmd[2200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
    assert_int_equal(system(cmd), 0);
    return dir;
}

static int
exists(const char *path) {
    struct stat st;
    return lstat(path, &st) == 0;
}

/* The temporary of @p target that process @p pid would make. */
static char *
name_of(const char *target, long pid) {
    static char buf[8][1200];
    static int next;
    char *b = buf[next++ % 8];
    assert_int_equal(vv_tmp_name(b, sizeof buf[0], target, pid, 0), 0);
    return b;
}

/* Temporary @p name of target base name @p base with its start time
 * field replaced by @p start (a process id reused) and its random part by
 * @p random. */
static char *
with_start(const char *name, const char *base, unsigned long long start, const char *random) {
    static char buf[1200];
    uint32_t host;
    long pid;
    unsigned long long st;
    assert_true(vv_tmp_parse(vv_path_basename(name), base, &host, &pid, &st));
    size_t dn = (size_t)(vv_path_basename(name) - name);
    snprintf(buf, sizeof buf, "%.*s%s.tmp-%08x-%ld-%llu-%s", (int)dn, name, base, (unsigned)host,
             pid, start, random);
    return buf;
}

/* A child that made a temporary file and a temporary folder (with nested
 * folders, files and a symbolic link to @p outside) of @p target, then
 * ended without removing them; their names into @p file and @p folder. */
static void
dead_writer(const char *target, const char *outside, char *file, char *folder, size_t cap) {
    int fds[2];
    assert_int_equal(pipe(fds), 0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        close(fds[0]);
        char f[1200], d[1200], p[1400];
        if (vv_tmp_name(f, sizeof f, target, (long)getpid(), 0) != 0 ||
            vv_tmp_name(d, sizeof d, target, (long)getpid(), 1) != 0)
            _exit(2);
        FILE *fp = fopen(f, "wb");
        if (!fp || fputs("half written\n", fp) < 0 || fclose(fp) != 0 || mkdir(d, 0777) != 0)
            _exit(3);
        snprintf(p, sizeof p, "%s/0", d);
        if (mkdir(p, 0777) != 0)
            _exit(4);
        snprintf(p, sizeof p, "%s/0/c", d);
        if (mkdir(p, 0777) != 0)
            _exit(4);
        snprintf(p, sizeof p, "%s/0/c/chunk", d);
        fp = fopen(p, "wb");
        if (!fp || fclose(fp) != 0)
            _exit(5);
        snprintf(p, sizeof p, "%s/zarr.json", d);
        fp = fopen(p, "wb");
        if (!fp || fclose(fp) != 0)
            _exit(5);
        snprintf(p, sizeof p, "%s/0/out", d);
        if (symlink(outside, p) != 0)
            _exit(6);
        if (write(fds[1], f, strlen(f) + 1) < 0 || write(fds[1], d, strlen(d) + 1) < 0)
            _exit(7);
        _exit(0);
    }
    close(fds[1]);
    char buf[2 * 1200];
    size_t n = 0;
    ssize_t r;
    while ((r = read(fds[0], buf + n, sizeof buf - 1 - n)) > 0)
        n += (size_t)r;
    close(fds[0]);
    buf[n] = '\0';
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    const size_t fn = strlen(buf);
    assert_true(fn < cap && n > fn && strlen(buf + fn + 1) < cap);
    memcpy(file, buf, fn + 1);
    memcpy(folder, buf + fn + 1, strlen(buf + fn + 1) + 1);
}

static void
test_name_parses_back(void **state) {
    (void)state;
    const char *dir = fresh_dir("names");
    char target[1100];
    snprintf(target, sizeof target, "%s/volume.ome.zarr", dir);
    const char *mine = name_of(target, (long)getpid());
    uint32_t host;
    long pid;
    unsigned long long start;
    assert_true(vv_tmp_parse(vv_path_basename(mine), "volume.ome.zarr", &host, &pid, &start));
    assert_int_equal(pid, (long)getpid());
    assert_true(start > 0); /* /proc is there on Linux */
    /* another target's temporaries, and names that are not temporaries */
    assert_false(vv_tmp_parse(vv_path_basename(mine), "volume.ome", &host, &pid, &start));
    assert_false(vv_tmp_parse(vv_path_basename(mine), "volume", &host, &pid, &start));
    static const char *const bad[] = {"v.tmp-",
                                      "v.tmp-abcdef",
                                      "v.tmp-12345678-1-2-abcdef0",
                                      "v.tmp-1234567-1-2-abcdef",
                                      "v.tmp-12345678--2-abcdef",
                                      "v.tmp-12345678-0-2-abcdef",
                                      "v.tmp-12345678-1-2-abcdeg",
                                      "v.tmp-12345678-1-2-abcdef.x",
                                      "v.tmp-12345678-99999999999-2-abcdef",
                                      "v.tmp1234"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        if (vv_tmp_parse(bad[i], "v", &host, &pid, &start))
            fail_msg("'%s' parsed as a temporary", bad[i]);
    assert_true(vv_tmp_parse("v.tmp-0123abCD-42-0-00ff00", "v", &host, &pid, &start));
    assert_int_equal(host, 0x0123abcd);
    assert_int_equal(pid, 42);
    assert_int_equal(start, 0);
    char small[16];
    assert_int_equal(vv_tmp_name(small, sizeof small, target, 1, 0), -1);
}

static void
test_sweep(void **state) {
    (void)state;
    char dir[1024], target[1100], outside[1100], keep_file[1200], other[1100];
    snprintf(dir, sizeof dir, "%s", fresh_dir("sweep"));
    snprintf(target, sizeof target, "%s/out.ome.zarr", dir);
    snprintf(other, sizeof other, "%s/other.nrrd", dir);
    /* what a link inside a dead writer's folder points to: must survive */
    snprintf(outside, sizeof outside, "%s/outside", fresh_dir("sweep_outside"));
    assert_int_equal(mkdir(outside, 0777), 0);
    snprintf(keep_file, sizeof keep_file, "%s/precious", outside);
    vt_write_file(keep_file, "keep\n", 5);

    char dead_file[1200], dead_folder[1200];
    dead_writer(target, outside, dead_file, dead_folder, sizeof dead_file);
    assert_true(exists(dead_file) && exists(dead_folder));
    /* another target's temporary of a dead writer: not this sweep's */
    char other_file[1200], other_folder[1200];
    dead_writer(other, outside, other_file, other_folder, sizeof other_file);

    /* a live writer: a child that waits until told to end */
    int go[2];
    assert_int_equal(pipe(go), 0);
    pid_t live = fork();
    assert_true(live >= 0);
    if (live == 0) {
        close(go[1]);
        char c;
        while (read(go[0], &c, 1) < 0)
            ;
        _exit(0);
    }
    close(go[0]);
    char live_file[1200], live_folder[1200], own[1200], reused[1200], foreign[1200];
    snprintf(live_file, sizeof live_file, "%s", name_of(target, (long)live));
    snprintf(own, sizeof own, "%s", name_of(target, (long)getpid()));
    uint32_t host;
    long pid;
    unsigned long long start;
    assert_true(vv_tmp_parse(vv_path_basename(live_file), "out.ome.zarr", &host, &pid, &start));
    snprintf(live_folder, sizeof live_folder, "%s",
             with_start(live_file, "out.ome.zarr", start, "f0f0f0"));
    vt_write_file(live_file, "x", 1);
    assert_int_equal(mkdir(live_folder, 0777), 0);
    vt_write_file(own, "x", 1);
    /* the live child's id with another start time: its writer is gone */
    snprintf(reused, sizeof reused, "%s",
             with_start(live_file, "out.ome.zarr", start + 1, "abcdef"));
    vt_write_file(reused, "x", 1);
    /* a dead writer's id on another host: not ours to judge */
    snprintf(foreign, sizeof foreign, "%s/out.ome.zarr.tmp-%08x-%s", dir, (unsigned)(host ^ 1u),
             strchr(strchr(vv_path_basename(dead_file), '-') + 1, '-') + 1);
    vt_write_file(foreign, "x", 1);
    /* names that do not parse, and a link named as a dead writer's file */
    const char *odd = vt_path(dir, "out.ome.zarr.tmp-abc123");
    vt_write_file(odd, "x", 1);
    char link[1300];
    snprintf(link, sizeof link, "%s", with_start(dead_file, "out.ome.zarr", 7, "123456"));
    assert_int_equal(symlink(outside, link), 0);

    assert_int_equal(vv_tmp_sweep(target), 3); /* the dead file, folder and reused id */
    assert_false(exists(dead_file));
    assert_false(exists(dead_folder));
    assert_false(exists(reused));
    assert_true(exists(keep_file)); /* the link in the folder was not followed */
    assert_true(exists(outside));
    assert_true(exists(live_file) && exists(live_folder) && exists(own));
    assert_true(exists(foreign) && exists(odd) && exists(link));
    assert_true(exists(other_file) && exists(other_folder));
    assert_int_equal(vv_tmp_sweep(target), 0);

    /* the live writer ends (and is reaped): its temporaries go next time */
    close(go[1]);
    int status;
    assert_int_equal(waitpid(live, &status, 0), live);
    assert_int_equal(vv_tmp_sweep(target), 2);
    assert_false(exists(live_file) || exists(live_folder));
    assert_true(exists(own)); /* still this process's */
    unlink(own);
    unlink(foreign);
    unlink(odd);
    unlink(link);
    assert_int_equal(vv_tmp_sweep(other), 2);
    DIR *d = opendir(dir);
    assert_non_null(d);
    struct dirent *e;
    int n = 0;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) {
            printf("left behind: %s\n", e->d_name);
            n++;
        }
    closedir(d);
    assert_int_equal(n, 0);
}

/* A zombie (ended, not yet reaped) writes no more: its temporary goes. */
static void
test_zombie_writer(void **state) {
    (void)state;
    const char *dir = fresh_dir("zombie");
    char target[1100];
    snprintf(target, sizeof target, "%s/image.png", dir);
    int fds[2];
    assert_int_equal(pipe(fds), 0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        char f[1200];
        if (vv_tmp_name(f, sizeof f, target, (long)getpid(), 0) != 0)
            _exit(2);
        FILE *fp = fopen(f, "wb");
        if (!fp || fclose(fp) != 0)
            _exit(3);
        _exit(write(fds[1], "x", 1) == 1 ? 0 : 4);
    }
    close(fds[1]);
    char c;
    assert_int_equal(read(fds[0], &c, 1), 1);
    close(fds[0]);
    /* wait until it is a zombie: waitid with WNOWAIT leaves it unreaped */
    siginfo_t si;
    memset(&si, 0, sizeof si);
    assert_int_equal(waitid(P_PID, (id_t)pid, &si, WEXITED | WNOWAIT), 0);
    assert_int_equal(kill(pid, 0), 0); /* the id still exists */
    assert_int_equal(vv_tmp_sweep(target), 1);
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
}

/* vv_atomic_file_open sweeps its target's folder; the file it writes is
 * complete, and a running writer's temporary stays. */
static void
test_atomic_file_sweeps(void **state) {
    (void)state;
    const char *dir = fresh_dir("atomic");
    char target[1100];
    snprintf(target, sizeof target, "%s/volume.raw", dir);
    char dead_file[1200], dead_folder[1200];
    dead_writer(target, dir, dead_file, dead_folder, sizeof dead_file);
    char own[1200];
    snprintf(own, sizeof own, "%s", name_of(target, (long)getpid()));
    vt_write_file(own, "x", 1);
    vv_atomic_file af;
    vt_ok(vv_atomic_file_open(&af, target));
    assert_false(exists(dead_file) || exists(dead_folder));
    assert_true(exists(own));
    fputs("new\n", af.fp);
    vt_ok(vv_atomic_file_commit(&af));
    size_t n = 0;
    unsigned char *got = vt_read_file(target, &n);
    assert_int_equal(n, 4);
    assert_memory_equal(got, "new\n", 4);
    free(got);
    unlink(own);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_name_parses_back),
        cmocka_unit_test(test_sweep),
        cmocka_unit_test(test_zombie_writer),
        cmocka_unit_test(test_atomic_file_sweeps),
    };
    return vt_run_tests(tests, NULL, NULL);
}
