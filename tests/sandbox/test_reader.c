/*
 * The reader sandbox (issue 33; src/sandbox, a transport under the format
 * table): a file read through a
 * third-party parser comes back from volvis-reader with the same voxels and
 * geometry as read in-process; whatever the reader does wrong (an abort, a
 * crash, a file outside its folder, a socket, execve, fork, a write, an
 * endless loop, running out of memory, a reply cut short: injected with
 * VOLVIS_SANDBOX_INJECT)
 * is one line of error, the test process survives, no child is left and no
 * core file is written; the CLI exits 1 with that line and writes nothing;
 * every fuzz finding of the sandboxed formats goes through the sandbox;
 * meshes and grids come back the same as read in-process, and hostile
 * replies for each answer are refused.
 */
#define _GNU_SOURCE /* memfd_create, the seals */
#include "testutil.h"

#include "io/transport.h"
#include "sandbox/sandbox_internal.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/socket.h>
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

#if defined(__has_include)
#if __has_include(<netcdf.h>)
#include <netcdf.h>
#define HAVE_NETCDF_H 1
#endif
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
assert_same_as(const vv_volume *a, vv_volume *b) {
    assert_memory_equal(a->dims, b->dims, sizeof a->dims);
    assert_int_equal(a->type, b->type);
    assert_memory_equal(a->spacing, b->spacing, sizeof a->spacing);
    assert_memory_equal(a->origin, b->origin, sizeof a->origin);
    assert_memory_equal(a->direction, b->direction, sizeof a->direction);
    assert_memory_equal(a->range, b->range, sizeof a->range);
    assert_int_equal(a->unit, b->unit);
    assert_int_equal(a->space, b->space);
    assert_memory_equal(a->data, b->data, vv_volume_voxel_count(a) * vv_voxel_type_size(a->type));
    /* writable, as a volume's voxels are (a private mapping, or a copy) */
    vv_volume_set(b, 0, 0, 0, 7);
    assert_near(vv_volume_get(b, 0, 0, 0), 7, 0);
}

/* @p path read in-process, in the reader with its voxels copied out of it
 * (peek, where this process may: always as root, which may ptrace any
 * process), and in the reader with its voxels handed over in a memfd
 * (VOLVIS_SANDBOX_PEEK=0): the same volume three times. */
static void
assert_same(const char *path) {
    vv_volume *a = NULL, *b = NULL, *c = NULL;
    vt_ok(load(&a, path, 0));
    vt_ok(load(&b, path, 1));
    setenv("VOLVIS_SANDBOX_PEEK", "0", 1);
    vt_ok(load(&c, path, 1));
    unsetenv("VOLVIS_SANDBOX_PEEK");
    assert_null(a->release); /* in-process: the library's own memory */
    if (geteuid() == 0)
        assert_null(b->release); /* copied out of the reader into ours */
    assert_non_null(c->release); /* the child's memfd, mapped */
    assert_same_as(a, b);
    assert_same_as(a, c);
    vv_volume_free(a);
    vv_volume_free(b);
    vv_volume_free(c);
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
    /* and an OME-Zarr, whose reader leaves the range to the parent (two
     * 8 MiB pieces of the parent's populate-and-range pass, four 4 MiB
     * pieces of its copy) */
    vt_ok(vv_volume_save(v, vt_path(g_dir, "head.ome.zarr"), VV_FORMAT_OME_ZARR, 1));
    vv_volume_free(v);
    assert_same(vt_path(g_dir, "head.tif"));
    assert_same(vt_path(g_dir, "head.nii"));
    assert_same(vt_path(g_dir, "head.ome.zarr"));
    /* our own formats are read in-process */
    if (vt_have_data("volumes/nut.slc")) {
        setenv("VOLVIS_SANDBOX", "1", 1);
        vt_ok(vv_volume_load(&v, vt_data("volumes/nut.slc"), NULL));
        unsetenv("VOLVIS_SANDBOX");
        assert_null(v->release);
        vv_volume_free(v);
    }
}

/* VOLVIS_SANDBOX=all (issue 67): our own parsers read in the reader give the
 * volume they give in this process, and the same one-line refusal. */
static void
test_own_parsers_in_reader(void **state) {
    (void)state;
    if (!vt_have_data("volumes/nut.slc"))
        vt_skip("../shared/data/volumes/nut.slc is missing");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/nut.slc"), NULL));
    vt_ok(vt_save(v, vt_path(g_dir, "nut.vvb"), VV_FORMAT_VVB, -1, 0));
    vv_volume_free(v);
    const char *paths[] = {vt_data("volumes/nut.slc"), vt_data("volumes/HeadMRVolume.mhd"),
                           vt_data("volumes/ironProt.vtk"), vt_path(g_dir, "nut.vvb")};
    for (size_t i = 0; i < sizeof paths / sizeof paths[0]; i++) {
        vv_volume *a = NULL, *b = NULL;
        setenv("VOLVIS_SANDBOX", "1", 1);
        vt_ok(vv_volume_load(&a, paths[i], NULL));
        setenv("VOLVIS_SANDBOX", "all", 1);
        setenv("VOLVIS_SANDBOX_PEEK", "0", 1); /* a memfd: the mark of the reader */
        vt_ok(vv_volume_load(&b, paths[i], NULL));
        unsetenv("VOLVIS_SANDBOX_PEEK");
        unsetenv("VOLVIS_SANDBOX");
        assert_null(a->release);     /* ours, in this process */
        assert_non_null(b->release); /* the reader's memfd */
        assert_memory_equal(a->dims, b->dims, sizeof a->dims);
        assert_int_equal(a->type, b->type);
        assert_memory_equal(a->spacing, b->spacing, sizeof a->spacing);
        assert_memory_equal(a->data, b->data,
                            vv_volume_voxel_count(a) * vv_voxel_type_size(a->type));
        vv_volume_free(a);
        vv_volume_free(b);
    }
    /* a truncated SLC: the same refusal from either side */
    size_t n = 0;
    unsigned char *bytes = vt_read_file(vt_data("volumes/nut.slc"), &n);
    vt_write_file(vt_path(g_dir, "short.slc"), bytes, n / 2);
    free(bytes);
    char msg[2][1024];
    const char *ways[2] = {"1", "all"};
    for (int w = 0; w < 2; w++) {
        setenv("VOLVIS_SANDBOX", ways[w], 1);
        vv_error_clear();
        assert_int_equal(vv_volume_load(&v, vt_path(g_dir, "short.slc"), NULL), VV_ERR_FORMAT);
        unsetenv("VOLVIS_SANDBOX");
        assert_null(v);
        snprintf(msg[w], sizeof msg[w], "%s", vv_error_message());
        assert_null(strchr(msg[w], '\n'));
    }
    assert_non_null(strstr(msg[0], "short.slc"));
    assert_non_null(strstr(msg[1], "short.slc"));
    /* the reader's refusal is the parser's, word for word */
    assert_non_null(strstr(msg[1], strstr(msg[0], "short.slc")));
    assert_no_child();
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
    /* a reader that keeps a writable mapping of its memfd and writes to it
     * after handing it over: a memfd not sealed against writing is refused
     * (a well-behaved reader unmaps its voxels and seals them) */
    injected("scribble", "nrrd: ct_head.nrrd: the reader's voxels are not sealed against writing",
             VV_ERR_FORMAT);
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
    /* a grid read by libxml2: the same one line, no image */
    if (vt_have_data("grids/fire_ug.vtu")) {
        const char *png = vt_path(g_dir, "never.png");
        const char *ren[] = {"render", vt_data("grids/fire_ug.vtu"), "-o", png, "--size", "64x64",
                             NULL};
        unlink(png);
        setenv("VOLVIS_SANDBOX_INJECT", "abort", 1);
        r = vt_run_cli_v(g_dir, ren);
        unsetenv("VOLVIS_SANDBOX_INJECT");
        printf("# stderr: %s", r.err);
        assert_int_equal(r.status, 1);
        assert_string_equal(r.err, "volvis: vtu: fire_ug.vtu: the .vtu reader crashed (SIGABRT); "
                                   "the file is malformed\n");
        assert_int_not_equal(stat(png, &st), 0);
        vt_run_result_free(&r);
    }
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

/* This program as a reader of another build (VT_FAKE_READER set, started
 * by the loader with its socket on descriptor 3): a hello of protocol
 * VT_FAKE_READER, ("layout") of this protocol with another layout, or
 * ("junk") bytes that are no hello; then it waits for the loader to close. */
static int
fake_reader(const char *what) {
    char buf[64];
    if (!strcmp(what, "junk")) {
        if (send(SBX_FD, "junk", 4, MSG_NOSIGNAL) != 4)
            return 1;
    } else if (!strcmp(what, "layout")) {
        /* this protocol, structures of another build (the fingerprint of
         * a reader from before it: 0) */
        const sbx_hello h = {SBX_MAGIC, SBX_HELLO, VV_SANDBOX_PROTOCOL, 0};
        if (send(SBX_FD, &h, sizeof h, MSG_NOSIGNAL) != (ssize_t)sizeof h)
            return 1;
    } else {
        const sbx_hello h = {SBX_MAGIC, SBX_HELLO, (uint32_t)atoi(what), 0};
        if (send(SBX_FD, &h, sizeof h, MSG_NOSIGNAL) != (ssize_t)sizeof h)
            return 1;
    }
    while (recv(SBX_FD, buf, sizeof buf, 0) > 0)
        ;
    return 0;
}

/* The library starts its own reader and refuses one of another build: a
 * reader speaking another protocol, or bytes that are no hello, give one
 * line naming the reader and the way out (issue 62: an asan build's
 * library started the installed release reader). */
static void
test_reader_of_another_build(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    char self[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    assert_true(n > 0);
    self[n] = '\0';
    setenv("VOLVIS_READER", self, 1);
    setenv("VOLVIS_SANDBOX_SPARE", "0", 1); /* each load its own reader */
    vv_sandbox_release_spare();
    static const char *const cases[][2] = {{"99", "speaks protocol 99, this library"},
                                           {"junk", "does not speak protocol"},
                                           {"layout", "with structures of another layout"}};
    for (int i = 0; i < 3; i++) {
        setenv("VT_FAKE_READER", cases[i][0], 1);
        vv_volume *v = NULL;
        vv_status s = load(&v, vt_data("volumes/ct_head.nrrd"), 1);
        printf("# %s: %s\n", cases[i][0], vv_error_message());
        assert_int_equal(s, VV_ERR_IO);
        assert_null(v);
        assert_non_null(strstr(vv_error_message(), cases[i][1]));
        assert_non_null(strstr(vv_error_message(), "set VOLVIS_READER to this build's"));
        assert_non_null(strstr(vv_error_message(), "ct_head.nrrd"));
        assert_null(strchr(vv_error_message(), '\n'));
    }
    unsetenv("VT_FAKE_READER");
    unsetenv("VOLVIS_READER");
    unsetenv("VOLVIS_SANDBOX_SPARE");
    assert_no_child();
    /* this build's own reader again */
    vv_volume *v = NULL;
    vt_ok(load(&v, vt_data("volumes/ct_head.nrrd"), 1));
    vv_volume_free(v);
}

/* Every kept fuzz input of a sandboxed format, through the sandbox: an
 * error or a volume, never more. */
static void
test_fuzz_corpus(void **state) {
    (void)state;
    static const char *const dirs[] = {"nrrd", "nifti", "tiff", "dicom", "mesh", "grid"};
    int n = 0;
    for (size_t d = 0; d < sizeof dirs / sizeof dirs[0]; d++) {
        char dir[512];
        snprintf(dir, sizeof dir, "%s/tests/fuzz/corpus/%s", VV_SOURCE_DIR, dirs[d]);
        DIR *dp = opendir(dir);
        assert_non_null(dp);
        struct dirent *e;
        while ((e = readdir(dp))) {
            /* the findings (crash-, oom-, timeout-, leak-, slow-); the
             * seeds are well-formed files other tests read */
            static const char *const kinds[] = {"crash-", "oom-", "timeout-", "leak-", "slow-"};
            int finding = 0;
            for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++)
                finding |= !strncmp(e->d_name, kinds[k], strlen(kinds[k]));
            if (!finding)
                continue;
            char path[1024];
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
            vv_load_options o;
            vv_load_options_init(&o);
            vv_format_parse(dirs[d], &o.format);
            setenv("VOLVIS_SANDBOX", "1", 1);
            vv_volume *v = NULL;
            vv_mesh *m = NULL;
            vv_grid *g = NULL;
            vv_error_clear();
            vv_status s = d == 4   ? vv_mesh_load(&m, path)
                          : d == 5 ? vv_grid_load(&g, path)
                                   : vv_volume_load(&v, path, &o);
            unsetenv("VOLVIS_SANDBOX");
            if (s == VV_OK) {
                assert_true(v || m || g);
                if (v)
                    assert_non_null(v->release);
                vv_volume_free(v);
                vv_mesh_free(m);
                vv_grid_free(g);
            } else {
                assert_null(strchr(vv_error_message(), '\n'));
            }
            assert_no_child();
            n++;
        }
        closedir(dp);
    }
    printf("# %d fuzz findings read through the sandbox\n", n);
    assert_true(n >= 20); /* 22 at issue 33's end */
}

/* Meshes (Assimp) through the sandbox: the same vertices, triangles and
 * normals as read in this process; an abort in the reader is one line. */
static void
test_meshes(void **state) {
    (void)state;
    static const char *const files[] = {"meshes/bunny.ply", "meshes/cow.obj", "meshes/knot1.off",
                                        "meshes/propeller.stl", "meshes/42400-IDGH.stl"};
    int n = 0;
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        if (!vt_have_data(files[i]))
            continue;
        vv_mesh *a = NULL, *b = NULL;
        setenv("VOLVIS_SANDBOX", "0", 1);
        vt_ok(vv_mesh_load(&a, vt_data(files[i])));
        setenv("VOLVIS_SANDBOX", "1", 1);
        vt_ok(vv_mesh_load(&b, vt_data(files[i])));
        unsetenv("VOLVIS_SANDBOX");
        assert_int_equal(a->n_vertices, b->n_vertices);
        assert_int_equal(a->n_triangles, b->n_triangles);
        assert_memory_equal(a->positions, b->positions, a->n_vertices * 3 * sizeof(float));
        assert_memory_equal(a->triangles, b->triangles, a->n_triangles * 3 * sizeof(uint32_t));
        assert_non_null(b->normals);
        assert_memory_equal(a->normals, b->normals, a->n_vertices * 3 * sizeof(float));
        printf("# %s: %zu vertices, %zu triangles, the same\n", files[i], b->n_vertices,
               b->n_triangles);
        vv_mesh_free(a);
        vv_mesh_free(b);
        n++;
    }
    if (n == 0)
        vt_skip("../shared/data/meshes is missing");
    setenv("VOLVIS_SANDBOX_INJECT", "abort", 1);
    vv_mesh *m = NULL;
    vv_status s = vv_mesh_load(&m, vt_data(files[0]));
    unsetenv("VOLVIS_SANDBOX_INJECT");
    printf("# abort: %s\n", vv_error_message());
    assert_true(s < 0);
    assert_null(m);
    assert_null(strchr(vv_error_message(), '\n'));
    assert_non_null(
        strstr(vv_error_message(), "mesh: bunny.ply: the mesh reader crashed (SIGABRT)"));
    assert_no_child();
}

/* A NetCDF-4 file (HDF5 inside, deflated, read under HDF5's file lock):
 * 3 depths x 4 latitudes x 5 longitudes of TEMP. NULL without libnetcdf. */
static const char *
make_netcdf4(void) {
#ifdef HAVE_NETCDF_H
    const char *p = vt_path(g_dir, "t4.nc");
    int nc, d[3], v[4];
    assert_int_equal(nc_create(p, NC_NETCDF4 | NC_CLOBBER, &nc), NC_NOERR);
    static const char *const dims[3] = {"depth", "lat", "lon"};
    static const char *const units[3] = {"m", "degrees_north", "degrees_east"};
    static const size_t len[3] = {3, 4, 5};
    for (int i = 0; i < 3; i++) {
        nc_def_dim(nc, dims[i], len[i], &d[i]);
        nc_def_var(nc, dims[i], NC_DOUBLE, 1, &d[i], &v[i]);
        nc_put_att_text(nc, v[i], "units", strlen(units[i]), units[i]);
    }
    nc_def_var(nc, "TEMP", NC_FLOAT, 3, d, &v[3]);
    nc_def_var_deflate(nc, v[3], 1, 1, 4);
    assert_int_equal(nc_enddef(nc), NC_NOERR);
    static const double depth[3] = {0, 100, 200}, lat[4] = {-30, -10, 10, 30},
                        lon[5] = {0, 10, 20, 30, 40};
    float t[60];
    for (int i = 0; i < 60; i++)
        t[i] = (float)i;
    nc_put_var_double(nc, v[0], depth);
    nc_put_var_double(nc, v[1], lat);
    nc_put_var_double(nc, v[2], lon);
    nc_put_var_float(nc, v[3], t);
    assert_int_equal(nc_close(nc), NC_NOERR);
    return p;
#else
    return NULL;
#endif
}

/* Grids (libxml2's .vtu, libnetcdf's NetCDF classic and NetCDF-4) through
 * the sandbox: the same points, cells, blocks, axes and fields as read in
 * this process; an abort in the reader is one line. */
static void
test_grids(void **state) {
    (void)state;
    static const char *const files[] = {"grids/fire_ug.vtu", "grids/levitus_climatology.cdf"};
    const char *paths[3] = {NULL, NULL, make_netcdf4()};
    for (size_t i = 0; i < 2; i++)
        if (vt_have_data(files[i]))
            paths[i] = vt_data(files[i]);
    int n = 0;
    for (size_t i = 0; i < 3; i++) {
        if (!paths[i])
            continue;
        vv_grid *a = NULL, *b = NULL;
        setenv("VOLVIS_SANDBOX", "0", 1);
        vt_ok(vv_grid_load(&a, paths[i]));
        setenv("VOLVIS_SANDBOX", "1", 1);
        vv_status sb = vv_grid_load(&b, paths[i]);
        unsetenv("VOLVIS_SANDBOX");
        if (sb != VV_OK)
            fail_msg("%s through the sandbox: %s", paths[i], vv_error_message());
        assert_int_equal(a->kind, b->kind);
        assert_int_equal(a->n_points, b->n_points);
        assert_int_equal(a->n_cells, b->n_cells);
        assert_memory_equal(a->points, b->points, a->n_points * 3 * sizeof(double));
        assert_memory_equal(a->cell_types, b->cell_types, a->n_cells);
        assert_memory_equal(a->cell_offsets, b->cell_offsets, (a->n_cells + 1) * sizeof(size_t));
        assert_memory_equal(a->connectivity, b->connectivity,
                            a->cell_offsets[a->n_cells] * sizeof(uint32_t));
        assert_int_equal(a->n_blocks, b->n_blocks);
        for (int k = 0; k < 3; k++) {
            assert_int_equal(a->sph_dims[k], b->sph_dims[k]);
            if (a->sph_dims[k])
                assert_memory_equal(a->sph_axes[k], b->sph_axes[k],
                                    (size_t)a->sph_dims[k] * sizeof(double));
        }
        assert_int_equal(a->n_fields, b->n_fields);
        for (int f = 0; f < a->n_fields; f++) {
            const vv_grid_field *fa = &a->fields[f], *fb = &b->fields[f];
            assert_string_equal(fa->name, fb->name);
            assert_int_equal(fa->cell_data, fb->cell_data);
            assert_int_equal(fa->n_components, fb->n_components);
            assert_int_equal(fa->n_tuples, fb->n_tuples);
            assert_int_equal(fa->has_fill, fb->has_fill);
            assert_memory_equal(fa->values, fb->values,
                                fa->n_tuples * (size_t)fa->n_components * sizeof(float));
            assert_memory_equal(fa->range, fb->range, sizeof fa->range);
        }
        printf("# %s: %s, %zu points, %zu cells, %d fields, the same\n", strrchr(paths[i], '/') + 1,
               vv_grid_kind_name(b->kind), b->n_points, b->n_cells, b->n_fields);
        vv_grid_free(a);
        vv_grid_free(b);
        n++;
    }
    if (n == 0)
        vt_skip("../shared/data/grids is missing and the build has no libnetcdf");
    static const char *const expect[] = {"vtu: fire_ug.vtu: the .vtu reader crashed (SIGABRT)",
                                         "netcdf: levitus_climatology.cdf: the NetCDF reader "
                                         "crashed (SIGABRT)"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        if (!vt_have_data(files[i]))
            continue;
        setenv("VOLVIS_SANDBOX_INJECT", "abort", 1);
        vv_grid *g = NULL;
        vv_status s = vv_grid_load(&g, vt_data(files[i]));
        unsetenv("VOLVIS_SANDBOX_INJECT");
        printf("# abort: %s\n", vv_error_message());
        assert_true(s < 0);
        assert_null(g);
        assert_null(strchr(vv_error_message(), '\n'));
        assert_non_null(strstr(vv_error_message(), expect[i]));
    }
    /* VTK legacy is our own parser: read in this process, abort or not */
    if (vt_have_data("grids/blow.vtk")) {
        setenv("VOLVIS_SANDBOX_INJECT", "abort", 1);
        vv_grid *g = NULL;
        vt_ok(vv_grid_load(&g, vt_data("grids/blow.vtk")));
        unsetenv("VOLVIS_SANDBOX_INJECT");
        vv_grid_free(g);
    }
    assert_no_child();
}

/* A caller's file-size limit (ulimit -f) does not cut the reader's memfd:
 * the CT head (13.5 MiB of voxels) loads under a soft limit of 4 KiB. */
static void
test_file_size_limit(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    struct rlimit old, lim;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    lim = old;
    lim.rlim_cur = 4096;
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    vv_volume *v = NULL;
    vv_status s = load(&v, vt_data("volumes/ct_head.nrrd"), 1);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
    if (s != VV_OK)
        fail_msg("under a file-size limit: %s", vv_error_message());
    assert_int_equal(v->dims[2], 108);
    vv_volume_free(v);
    assert_no_child();
}

/* A memfd holding @p n bytes of @p d, sealed with @p seals. */
static int
memfd_with(const void *d, size_t n, int seals) {
    int fd = memfd_create("test-voxels", MFD_CLOEXEC | MFD_ALLOW_SEALING);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, d, n), (ssize_t)n);
    if (seals)
        assert_int_equal(fcntl(fd, F_ADD_SEALS, seals), 0);
    return fd;
}

static uint16_t g_vox[64];

/* Hands @p r (@p len bytes, with a memfd of @p fd_bytes voxel bytes sealed
 * with @p seals, or none when @p fd_bytes is 0) to the parent: it must
 * answer @p expect_k, and for a result no volume but an error holding
 * @p expect (NULL: the well-formed case, a volume). */
static void
hostile(const char *what, const sbx_reply *r, size_t len, size_t fd_bytes, int seals, int expect_k,
        const char *expect) {
    char name[VV_SANDBOX_NAME_MAX] = "nrrd", title[64] = "NRRD";
    vv_error_clear();
    int fd = fd_bytes ? memfd_with(g_vox, fd_bytes, seals) : -1;
    vv_sandbox_result a;
    vv_status s = VV_OK;
    int k = sbx_take_message(VV_SANDBOX_VOLUME, r, len, fd, name, title, "a.nrrd", &a, &s);
    vv_volume *v = a.volume;
    printf("# %s: %d %s\n", what, k, k > 0 && s != VV_OK ? vv_error_message() : "");
    if (k != expect_k)
        fail_msg("%s: %d, not %d", what, k, expect_k);
    if (k <= 0 || !expect) {
        if (k > 0) {
            vt_ok(s);
            assert_non_null(v);
            vv_volume_free(v);
        }
        return;
    }
    assert_null(v);
    assert_true(s < 0);
    if (!strstr(vv_error_message(), expect))
        fail_msg("%s: \"%s\" does not say \"%s\"", what, vv_error_message(), expect);
}

/* What a broken or hostile reader could send: the parent makes an error or
 * "malformed" of each, never a volume that does not hold its voxels
 * (tests/fuzz/fuzz_sandbox.c explores the rest). */
static void
test_hostile_replies(void **state) {
    (void)state;
    sbx_reply ok;
    memset(&ok, 0, sizeof ok);
    ok.magic = SBX_MAGIC;
    ok.kind = SBX_RESULT;
    ok.dims[0] = ok.dims[1] = ok.dims[2] = 4;
    ok.type = VV_U16;
    ok.bytes = sizeof g_vox;
    for (int i = 0; i < 3; i++) {
        ok.spacing[i] = 0.5;
        ok.direction[4 * i] = 1;
    }
    for (int i = 0; i < 64; i++)
        g_vox[i] = (uint16_t)(1000 + i);
    const size_t len = offsetof(sbx_reply, err), all = sizeof g_vox;
    const int sealed = F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_WRITE;

    /* the well-formed result: the voxels, their range computed again */
    char name[VV_SANDBOX_NAME_MAX] = "nrrd", title[64] = "NRRD";
    vv_sandbox_result a;
    vv_status s;
    assert_int_equal(sbx_take_message(VV_SANDBOX_VOLUME, &ok, len, memfd_with(g_vox, all, sealed),
                                      name, title, "a.nrrd", &a, &s),
                     1);
    vv_volume *v = a.volume;
    vt_ok(s);
    assert_non_null(v);
    assert_int_equal(((uint16_t *)v->data)[63], 1063);
    assert_true(v->range[0] == 1000 && v->range[1] == 1063);
    assert_true(v->spacing[1] == 0.5);
    vv_volume_free(v);

    sbx_reply r = ok;
    hostile("cut short", &r, 12, all, sealed, -1, NULL);
    hostile("unsealed memfd", &r, len, all, 0, 1, "does not hold the 128 bytes");
    hostile("writable memfd", &r, len, all, F_SEAL_SHRINK | F_SEAL_GROW, 1,
            "voxels are not sealed against writing");
    hostile("memfd too small", &r, len, all / 2, sealed, 1, "does not hold the 128 bytes");
    hostile("no memfd", &r, len, 0, 0, 1, "has no voxels");

    /* a reply asked with peek names where its voxels are (here: this
     * process's, copied with process_vm_readv as a reader's are) */
    r = ok;
    r.addr = (uint64_t)(uintptr_t)g_vox;
    assert_int_equal(sbx_take_message_peer(VV_SANDBOX_VOLUME, &r, len, -1, getpid(), name, title,
                                           "a.nrrd", &a, &s),
                     1);
    vt_ok(s);
    v = a.volume;
    assert_non_null(v);
    assert_null(v->release); /* our own copy */
    assert_memory_equal(v->data, g_vox, all);
    assert_true(v->range[0] == 1000 && v->range[1] == 1063);
    assert_true(v->spacing[1] == 0.5);
    vv_volume_free(v);
    /* an address not mapped there, one whose bytes would wrap around, and
     * an address where no peek was asked: errors, never a volume */
    const struct {
        uint64_t addr;
        pid_t peer;
        const char *expect;
    } peeks[] = {{1, getpid(), "cannot copy the reader's 128 bytes of voxels"},
                 {UINT64_MAX - 8, getpid(), "does not hold the 128 bytes"},
                 {(uint64_t)(uintptr_t)g_vox, 0, "has no voxels"}};
    for (size_t i = 0; i < sizeof peeks / sizeof peeks[0]; i++) {
        r.addr = peeks[i].addr;
        vv_error_clear();
        assert_int_equal(sbx_take_message_peer(VV_SANDBOX_VOLUME, &r, len, -1, peeks[i].peer, name,
                                               title, "a.nrrd", &a, &s),
                         1);
        assert_null(a.volume);
        assert_true(s < 0);
        if (!strstr(vv_error_message(), peeks[i].expect))
            fail_msg("peek %zu: \"%s\" does not say \"%s\"", i, vv_error_message(),
                     peeks[i].expect);
    }
    r.bytes = 64;
    hostile("byte count wrong", &r, len, all, sealed, 1, "does not hold");
    r = ok;
    r.dims[0] = r.dims[1] = r.dims[2] = 1 << 30;
    hostile("huge dims", &r, len, all, sealed, 1, "the reader's result");
    r = ok;
    r.dims[1] = -4;
    hostile("negative dims", &r, len, all, sealed, 1, "the reader's result");
    r = ok;
    r.spacing[1] = NAN;
    hostile("NaN spacing", &r, len, all, sealed, 1, "broken geometry");
    r = ok;
    r.spacing[2] = 0;
    hostile("zero spacing", &r, len, all, sealed, 1, "broken geometry");
    r = ok;
    r.type = 99;
    hostile("unknown voxel type", &r, len, all, sealed, 1, "has no voxels");
    r = ok;
    r.magic = 1;
    hostile("bad magic", &r, len, all, sealed, -1, NULL);
    r = ok;
    r.kind = 7;
    hostile("unknown kind", &r, len, all, sealed, -1, NULL);
    r = ok;
    r.err_len = 100;
    hostile("error text past the message", &r, len, all, sealed, -1, NULL);
    r.err_len = SBX_MAX_ERROR;
    hostile("error text too long", &r, sizeof r, all, sealed, -1, NULL);
    r = ok;
    r.status = VV_ERR_FORMAT;
    hostile("an error without text", &r, len, all, sealed, 1, "without a message");
    r.status = 12345;
    hostile("a status out of range", &r, len, 0, 0, 1, "nrrd: a.nrrd: the reader failed without");
    const char *lines = "nrrd: a.nrrd: first\nsecond\r\x1b[2J";
    r.err_len = (uint32_t)strlen(lines);
    memcpy(r.err, lines, r.err_len);
    hostile("an error of several lines", &r, len + r.err_len, 0, 0, 1,
            "nrrd: a.nrrd: first second  [2J");
    /* the row a reader names: taken when printable and ended in its field */
    r = ok;
    r.kind = SBX_FORMAT;
    snprintf(r.format, sizeof r.format, "tiff");
    snprintf(r.title, sizeof r.title, "TIFF");
    assert_int_equal(
        sbx_take_message(VV_SANDBOX_VOLUME, &r, len, -1, name, title, "a.nrrd", &a, &s), 0);
    assert_string_equal(name, "tiff");
    assert_string_equal(title, "TIFF");
    memset(r.format, 'x', sizeof r.format); /* not ended: not taken */
    assert_int_equal(
        sbx_take_message(VV_SANDBOX_VOLUME, &r, len, -1, name, title, "a.nrrd", &a, &s), 0);
    assert_string_equal(name, "tiff");
    snprintf(r.format, sizeof r.format, "a\nb");
    assert_int_equal(
        sbx_take_message(VV_SANDBOX_VOLUME, &r, len, -1, name, title, "a.nrrd", &a, &s), 0);
    assert_string_equal(name, "a b"); /* one printable line */
    snprintf(name, sizeof name, "nrrd");

    /* a mesh: a well-formed one (a tetrahedron), an index past the
     * vertices, a vertex that is not finite, counts past the memfd */
    typedef struct {
        float p[12];
        uint32_t t[12];
    } tet_t;
    const tet_t tet = {{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}};
    sbx_reply mr = ok;
    mr.n_vertices = 4;
    mr.n_triangles = 4;
    mr.bytes = sizeof tet;
    const char *expect[] = {NULL, "names a vertex >= 4",
                            "the reader's result: vertex 1 is not finite", "malformed"};
    for (int c = 0; c < 4; c++) {
        tet_t t = tet;
        sbx_reply q = mr;
        if (c == 1)
            t.t[7] = 4;
        if (c == 2)
            t.p[5] = NAN;
        if (c == 3)
            q.n_vertices = 1u << 20;
        int k = sbx_take_message(VV_SANDBOX_MESH, &q, len, memfd_with(&t, sizeof t, sealed), name,
                                 title, "t.ply", &a, &s);
        printf("# mesh case %d: %d %s\n", c, k, s ? vv_error_message() : "");
        assert_int_equal(k, 1);
        if (!expect[c]) {
            vt_ok(s);
            assert_int_equal(a.mesh->n_triangles, 4);
            assert_non_null(a.mesh->normals);
            vv_mesh_free(a.mesh);
        } else {
            assert_null(a.mesh);
            assert_non_null(strstr(vv_error_message(), expect[c]));
        }
    }
    /* a series list: the listing's bytes come back as they are (their
     * memfd checked), then each entry is checked by the format's side
     * (io_dicom_series_from_wire): strings without their end are ended in
     * their field, a negative size refused */
    vv_dicom_series list[2];
    memset(list, 'x', sizeof list);
    list[0].number = 1;
    list[0].dims[0] = list[0].dims[1] = list[0].dims[2] = list[0].n_files = 4;
    list[0].time_steps = 1;
    list[1] = list[0];
    sbx_reply lr = ok;
    lr.bytes = sizeof list;
    assert_int_equal(sbx_take_message(VV_SANDBOX_LIST, &lr, len,
                                      memfd_with(list, sizeof list, sealed), name, title, "ct", &a,
                                      &s),
                     1);
    vt_ok(s);
    assert_int_equal(a.blob_len, sizeof list);
    vv_dicom_series *got = NULL;
    int n_got = 0;
    vt_ok(io_dicom_series_from_wire(&got, &n_got, a.blob, a.blob_len, "ct"));
    assert_int_equal(n_got, 2);
    assert_int_equal(strlen(got[1].uid), sizeof got[1].uid - 1);
    assert_int_equal(strlen(got[1].patient_id), sizeof got[1].patient_id - 1);
    free(got);
    lr.bytes = 3 * sizeof list[0]; /* more than the memfd holds */
    assert_int_equal(sbx_take_message(VV_SANDBOX_LIST, &lr, len,
                                      memfd_with(list, sizeof list, sealed), name, title, "ct", &a,
                                      &s),
                     1);
    assert_null(a.blob);
    assert_non_null(strstr(vv_error_message(), "the reader's listing is malformed"));
    list[1].n_files = -1;
    void *bytes = malloc(sizeof list);
    memcpy(bytes, list, sizeof list);
    assert_int_equal(io_dicom_series_from_wire(&got, &n_got, bytes, sizeof list, "ct"),
                     VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "the reader's list of series is malformed"));
    bytes = malloc(sizeof list - 1); /* not whole entries */
    memcpy(bytes, list, sizeof list - 1);
    assert_int_equal(io_dicom_series_from_wire(&got, &n_got, bytes, sizeof list - 1, "ct"),
                     VV_ERR_FORMAT);
    assert_no_child();
}

/* One tetrahedron with a point field "f" (4 values), laid out as the
 * reader lays out a grid (sbx_grid_head). */
typedef struct {
    sbx_grid_head h;
    double p[12];
    uint8_t types[8];
    uint64_t offsets[2];
    uint32_t conn[4];
    sbx_grid_field fh;
    float values[4];
} tet_grid;

/* The parent given @p t (@p bytes of it named, the memfd holding all of
 * it): a grid when @p expect is NULL, else no grid and an error holding
 * @p expect. */
static void
hostile_grid(const char *what, const tet_grid *t, uint64_t bytes, const char *expect) {
    sbx_reply r;
    memset(&r, 0, sizeof r);
    r.magic = SBX_MAGIC;
    r.kind = SBX_RESULT;
    r.bytes = bytes;
    char name[VV_SANDBOX_NAME_MAX] = "vtu", title[64] = ".vtu";
    vv_sandbox_result a;
    vv_status st = VV_OK;
    vv_error_clear();
    int k = sbx_take_message(VV_SANDBOX_GRID, &r, offsetof(sbx_reply, err),
                             memfd_with(t, sizeof *t, F_SEAL_SHRINK | F_SEAL_GROW), name, title,
                             "t.vtu", &a, &st);
    printf("# grid, %s: %d %s\n", what, k, st ? vv_error_message() : "");
    assert_int_equal(k, 1);
    if (!expect) {
        vt_ok(st);
        assert_non_null(a.grid);
        assert_int_equal(a.grid->n_cells, 1);
        assert_true(a.grid->fields[0].range[0] == 1 && a.grid->fields[0].range[1] == 4);
        vv_grid_free(a.grid);
        return;
    }
    assert_null(a.grid);
    assert_true(st < 0);
    assert_null(strchr(vv_error_message(), '\n'));
    if (!strstr(vv_error_message(), expect))
        fail_msg("grid, %s: \"%s\" does not say \"%s\"", what, vv_error_message(), expect);
}

/* What a hostile reader could send for a grid: every count, offset, index,
 * point and field is checked on the parent's copy. */
static void
test_hostile_grids(void **state) {
    (void)state;
    tet_grid ok;
    memset(&ok, 0, sizeof ok);
    ok.h.kind = VV_GRID_UNSTRUCTURED;
    ok.h.n_fields = 1;
    ok.h.n_points = 4;
    ok.h.n_cells = 1;
    ok.h.n_conn = 4;
    const double p[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(ok.p, p, sizeof p);
    ok.types[0] = VV_CELL_TETRA;
    ok.offsets[1] = 4;
    for (uint32_t i = 0; i < 4; i++) {
        ok.conn[i] = i;
        ok.values[i] = (float)(i + 1);
    }
    snprintf(ok.fh.name, sizeof ok.fh.name, "f");
    ok.fh.n_components = 1;
    ok.fh.n_tuples = 4;
    hostile_grid("well-formed", &ok, sizeof ok, NULL);
    tet_grid t = ok;
    hostile_grid("cut short", &t, sizeof t - 4, "field 'f' past its end");
    hostile_grid("no head", &t, 8, "malformed");
    t.conn[2] = 4;
    hostile_grid("an index past the points", &t, sizeof t, "uses point 4 but there are 4");
    t = ok;
    t.p[4] = NAN;
    hostile_grid("a point not finite", &t, sizeof t, "point 1 is not finite");
    t = ok;
    t.offsets[1] = 5;
    hostile_grid("an offset past the indices", &t, sizeof t,
                 "cell offset 1 is past the 4 point indices");
    t = ok;
    t.offsets[1] = 3;
    hostile_grid("indices left over", &t, sizeof t, "the cells use 3 of 4 point indices");
    t = ok;
    t.types[0] = 200;
    hostile_grid("an unknown cell type", &t, sizeof t, "unsupported cell type 200");
    t = ok;
    t.h.n_points = (uint64_t)1 << 40;
    hostile_grid("a huge point count", &t, sizeof t, "points (at most");
    t = ok;
    t.h.n_cells = (uint64_t)1 << 27;
    hostile_grid("more cells than the memfd", &t, sizeof t, "past its end");
    t = ok;
    t.fh.n_tuples = 5;
    hostile_grid("a field's tuples", &t, sizeof t, "field 'f' has 5 tuples for 4");
    t = ok;
    t.fh.n_components = 10;
    hostile_grid("a field of 10 components", &t, sizeof t, "10 components");
    t = ok;
    t.h.n_fields = -1;
    hostile_grid("a negative field count", &t, sizeof t, "a grid head out of range");
    t = ok;
    t.h.kind = VV_GRID_CURVILINEAR;
    hostile_grid("curvilinear without blocks", &t, sizeof t, "a grid head out of range");
    t = ok;
    t.h.kind = VV_GRID_SPHERICAL;
    t.h.sph_dims[0] = t.h.sph_dims[1] = t.h.sph_dims[2] = 2;
    hostile_grid("spherical axes past the points", &t, sizeof t,
                 "spherical axes of 2 x 2 x 2 values for 4 points");
    t = ok;
    memset(t.fh.name, 'x', sizeof t.fh.name);
    t.fh.name[1] = '\n';
    hostile_grid("a name without its end", &t, sizeof t, NULL);
    assert_no_child();
}

int
main(void) {
    const char *fake = getenv("VT_FAKE_READER");
    if (fake && fcntl(SBX_FD, F_GETFD) >= 0)
        return fake_reader(fake);
    snprintf(g_dir, sizeof g_dir, "%s", vt_outdir("sandbox"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_volume),
        cmocka_unit_test(test_own_parsers_in_reader),
        cmocka_unit_test(test_injected_faults),
        cmocka_unit_test(test_cli),
        cmocka_unit_test(test_reader_alone_and_missing),
        cmocka_unit_test(test_reader_of_another_build),
        cmocka_unit_test(test_fuzz_corpus),
        cmocka_unit_test(test_hostile_replies),
        cmocka_unit_test(test_meshes),
        cmocka_unit_test(test_grids),
        cmocka_unit_test(test_hostile_grids),
        cmocka_unit_test(test_file_size_limit),
    };
    return vt_run_tests(tests, NULL, NULL);
}
