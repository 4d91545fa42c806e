/*
 * Helpers shared by the cmocka tests. Tests run from the project root, so
 * the shared data is at ../shared/data (VV_DATA_DIR).
 */
#ifndef VV_TESTUTIL_H
#define VV_TESTUTIL_H

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "volvis/volvis.h"

#define VV_DATA_DIR VV_SOURCE_DIR "/../shared/data"

/*
 * The environment of every mpiexec the tests run (a command-line prefix):
 * no X display for the launcher or the ranks. Open MPI's hwloc probes the X
 * servers :0 to :9 for GPUs (its "gl" component) in the launcher, whatever
 * DISPLAY says, and a server that dies during the probe (another program's
 * Xvfb) ends the launcher with "XIO: fatal IO error" (docs/parallel.md).
 * tests/parallel/mpi_display.py checks that nothing connects.
 */
#define VT_MPI_ENV "env -u DISPLAY HWLOC_COMPONENTS=-gl"

/*
 * Skipping honestly. Every test program exits through vt_run_tests, which
 * returns VT_SKIP_STATUS (CTest's SKIP_RETURN_CODE, set for every test in
 * tests/CMakeLists.txt) when a test was skipped and none failed, so CTest
 * reports the program "Skipped", never "Passed"; CI (scripts/test.sh) fails
 * on any skip. A test skips with vt_skip("why"), never with cmocka's bare
 * skip(), which is disabled below so that no skip goes uncounted.
 */
#define VT_SKIP_STATUS 77

/** Records and prints why the running test is skipped (use vt_skip). */
void vt_skip_note(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/** Skips the running test, printing the reason (printf format). */
#define vt_skip(...)                                                                               \
    do {                                                                                           \
        vt_skip_note(__FILE__, __LINE__, __VA_ARGS__);                                             \
        _skip(__FILE__, __LINE__);                                                                 \
    } while (0)

#undef skip
#define skip() vt_skip_needs_a_reason_use_vt_skip

/** The exit status of a test program: 0, VT_SKIP_STATUS, or @p failures. */
int vt_run_status(int failures);

/** Runs a cmocka group (as cmocka_run_group_tests) and returns vt_run_status. */
#define vt_run_tests(tests, setup, teardown)                                                       \
    vt_run_status(cmocka_run_group_tests(tests, setup, teardown))

/** 1 when the shared data file @p rel (as for vt_data) can be opened. */
int vt_have_data(const char *rel);

/** Path of a shared data file, e.g. vt_data("volumes/nut.slc"); static buffer per call site. */
const char *vt_data(const char *rel);

/** A directory for this test's output, build/test-out/<name>, created if needed
 * (not emptied: tests name their files and overwrite them). Static buffer. */
const char *vt_outdir(const char *name);

/**
 * Makes a new private directory @p prefix followed by six random
 * characters under $TMPDIR (under /tmp when TMPDIR is unset, empty, or
 * too long for @p n bytes, as a socket's short path may need), writes its
 * path into @p buf (@p n bytes) and returns @p buf; NULL when it cannot
 * be made (errno set). The caller removes it.
 */
char *vt_mkdtemp(char *buf, size_t n, const char *prefix);

/**
 * A cache of its own with a budget of @p limit bytes for the out-of-core
 * readers a test opens (freed when the test program ends); NULL for 0:
 * the process's cache (1 GiB).
 */
vv_cache *vt_cache(uint64_t limit);

/** Writes @p n bytes to @p path (overwrites); fails the test on error. */
void vt_write_file(const char *path, const void *data, size_t n);

/**
 * Writes @p v to @p path through the format table (vv_volume_save_with) as
 * @p format, compressed as @p compress says (-1: the format's default, 0:
 * none, 1: compressed), a .vvb with @p vvb_flags: how a test writes a file
 * it then reads. Returns the writer's status.
 */
vv_status vt_save(const vv_volume *v, const char *path, vv_format format, int compress,
                  unsigned vvb_flags);

/**
 * The in-memory ray-cast render of @p w at its view, every pixel cast (the
 * adaptive refinement off): the reference a test compares other roads
 * with. The caller frees the image; fails the test on error.
 */
vv_image *vt_render_reference(vv_world *w);

/**
 * @p path opened out of core (vv_open, VV_OPEN_OUT_OF_CORE) in @p cache, by
 * its levels when @p levels (then a pyramid, else bricks: the test fails
 * otherwise). A new source reference; fails the test on error.
 */
vv_source *vt_open_ooc(const char *path, int levels, vv_cache *cache);

/** Writes @p img to @p dir/@p prefix@p name.png (gamma 1); fails the test on error. */
void vt_save_png(const vv_image *img, const char *dir, const char *prefix, const char *name);

/** Reads a whole file (malloc'ed, caller frees); fails the test on error. */
unsigned char *vt_read_file(const char *path, size_t *n);

/** Asserts that status is VV_OK, printing the error trace otherwise. */
#define vt_ok(expr)                                                                                \
    do {                                                                                           \
        vv_status vt_s_ = (expr);                                                                  \
        if (vt_s_ != VV_OK)                                                                        \
            fail_msg("%s -> %s: %s", #expr, vv_status_name(vt_s_), vv_error_message());            \
    } while (0)

/**
 * A sphere of radius @p r centred on the origin: an octahedron subdivided
 * @p levels times (8 * 4^levels triangles), vertices pushed onto the sphere;
 * closed, shared vertices, counter-clockwise from outside. Caller frees.
 */
vv_mesh *vt_sphere_mesh(double r, int levels);

/** Deterministic uniform numbers in [lo, hi) from the state @p s (splitmix64). */
double vt_rnd(uint64_t *s, double lo, double hi);

/** What a run of the volvis command-line tool did (vt_run_cli_v). */
typedef struct vt_run_result {
    int status; /**< exit status, or 128 + signal number */
    char *out;  /**< stdout, NUL-terminated, malloc'ed */
    char *err;  /**< stderr, likewise */
} vt_run_result;

/**
 * Runs the CLI ($VV_CLI, set by CTest, else the build's volvis) with the
 * NULL-terminated @p args (argv[0] is added) as a separate process, stdin
 * from /dev/null, stdout and stderr captured through files in @p dir.
 */
vt_run_result vt_run_cli_v(const char *dir, const char *const *args);
/** Frees the captured output. */
void vt_run_result_free(vt_run_result *r);

/**
 * Asserts a refusal (issue 67): @p got is @p want, the last error message
 * (vv_error_message) holds @p needle and names @p name (each unless NULL),
 * and it is one line of printable bytes (no control byte, no 0x7f).
 * @p label (may be NULL) begins each failure's text.
 */
void vt_expect_refusal(const char *label, vv_status got, vv_status want, const char *needle,
                       const char *name);
/**
 * vt_run_cli_v, then asserts that it exited with @p status and, when
 * @p err_has is not NULL, that its stderr contains @p err_has; frees the
 * output (for runs whose output the test does not read further).
 */
void vt_run_cli_expect(const char *dir, int status, const char *err_has, const char *const *args);
/** "@p dir/@p name" in one of 8 rotating buffers. */
const char *vt_path(const char *dir, const char *name);

/** PSNR in dB of two PNG files of one size over their RGBA channels in
 * [0, 1] (INFINITY when identical); asserts both read and match in size. */
double vt_png_psnr(const char *a, const char *b);
/** PSNR in dB of two images of one size over their float RGBA channels
 * (INFINITY when equal); *@p identical (may be NULL): 1 when bit for bit. */
double vt_image_psnr(const vv_image *a, const vv_image *b, int *identical);
/** The largest and the mean absolute difference of two images of one size
 * over their float RGBA channels (*@p mean may be NULL); returns the largest. */
double vt_image_diff(const vv_image *a, const vv_image *b, double *mean);

/**
 * napari's attenuated MIP of one ray, computed from its formula (VisPy's
 * volume shader), independently of the renderers: the @p n sample values
 * @p vals front to back, S the running sum of clamp((v - lo) / (hi - lo),
 * 0, 1), each value scaled by exp(-att (S - 1) / step); returns the largest
 * scaled value, *@p at the index of its sample (the first of equals).
 */
/** @p tf made an opaque grey ramp over [@p lo, @p hi]: opacity 1 at both
 * ends (napari's contrast limits for attenuated MIP), colour black at lo to
 * white at hi, so a projection's pixel is its value's grey; fails the test
 * on error. */
void vt_tf_grey(vv_tf *tf, double lo, double hi);

/** @p tf made a ramp with flat ends over a volume's range [@p lo, @p hi]:
 * opacity 0.2 at 30 % of it rising to 1 at 97 %, colour blue at lo to
 * yellow at hi (MIP then starts at one flat end and stops at the other);
 * fails the test on error. */
void vt_tf_flat_ends(vv_tf *tf, double lo, double hi);

double vt_napari_attenuated_mip(const double *vals, int n, double lo, double hi, double att,
                                double step, int *at);

/** Default-scene options (vv_world_new_for_volume, _for_grid) of a
 * @p size x @p size view from azimuth 30 and elevation 20 degrees, the
 * renderer tests' usual view. */
vv_default_scene_options vt_scene_options(int size);

/** The default scene (vv_world_new_for_volume, vt_scene_options) of the
 * shared volume @p rel (under ../shared/data, as vt_data), @p size pixels
 * square; *vol gets the volume (freed by the caller, after the World). */
vv_world *vt_volume_scene(const char *rel, int size, vv_volume **vol);

/**
 * The converged reference of a renderer's image (issue 32's accuracy
 * check): @p r renders a copy of @p w with every object's step divided by
 * @p step_div, at @p k times the view's width and height, quality 2, one
 * thread count of the machine's; the result is box-filtered (k x k pixels
 * a pixel, RGBA averaged) to the view's size. The caller sets @p r's
 * options (no refinement, one sample a pixel). Returns a new image.
 */
vv_image *vt_converged_reference(vv_renderer *r, const vv_world *w, int step_div, int k);

/** Renders @p w's own view with @p r at @p quality on @p threads (0: all);
 * @p st (may be NULL) gets the work counted. Returns a new image. */
vv_image *vt_render_q(vv_renderer *r, const vv_world *w, int quality, int threads,
                      vv_render_stats *st);

/** A TCP socket listening on 127.0.0.1 at a free port (*port), @p backlog
 * connections; asserts on failure. For the tests' loopback servers. */
int vt_listen_loopback(int backlog, int *port);

/** Reads an HTTP request's head from @p fd into @p buf (@p cap bytes, NUL
 * terminated) up to its blank line, the peer's end or a full buffer;
 * returns the bytes read. */
size_t vt_read_request_head(int fd, char *buf, size_t cap);

/** Seconds of CLOCK_MONOTONIC (for the tests' waits). */
double vt_now(void);

/** Asserts |a - b| <= eps, printing both values on failure. */
#define assert_near(a, b, eps)                                                                     \
    do {                                                                                           \
        double a_ = (a), b_ = (b);                                                                 \
        if (!(fabs(a_ - b_) <= (eps)))                                                             \
            fail_msg("%s = %.17g, expected %.17g (+-%g)", #a, a_, b_, (double)(eps));              \
    } while (0)

/** Asserts an error (status < 0) with a non-empty message. */
#define vt_err(expr)                                                                               \
    do {                                                                                           \
        vv_error_clear();                                                                          \
        vv_status vt_s_ = (expr);                                                                  \
        if (vt_s_ >= 0)                                                                            \
            fail_msg("%s unexpectedly succeeded", #expr);                                          \
        assert_true(vv_error_message()[0] != '\0');                                                \
    } while (0)

#endif
