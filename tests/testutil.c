#include "testutil.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <spawn.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

extern char **environ;

/* Tests skipped in this program (cmocka runs its tests one after another
 * in one thread). */
static int g_skipped;

void
vt_skip_note(const char *file, int line, const char *fmt, ...) {
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    g_skipped++;
    const char *base = strrchr(file, '/');
    print_message("SKIPPED at %s:%d: %s\n", base ? base + 1 : file, line, msg);
}

int
vt_run_status(int failures) {
    if (failures == 0 && g_skipped > 0) {
        print_message("%d test(s) skipped: reported to CTest as skipped (exit %d)\n", g_skipped,
                      VT_SKIP_STATUS);
        return VT_SKIP_STATUS;
    }
    return failures;
}

int
vt_have_data(const char *rel) {
    FILE *f = fopen(vt_data(rel), "rb");
    if (!f)
        return 0;
    fclose(f);
    return 1;
}

const char *
vt_data(const char *rel) {
    static _Thread_local char buf[8][1024];
    static _Thread_local int slot;
    slot = (slot + 1) % 8;
    snprintf(buf[slot], sizeof buf[slot], "%s/%s", VV_DATA_DIR, rel);
    return buf[slot];
}

static void
mkdir_p(const char *path) {
    char tmp[1024];
    snprintf(tmp, sizeof tmp, "%s", path);
    for (char *p = tmp + 1; *p; p++) {
        if (*p == '/') {
            *p = 0;
            mkdir(tmp, 0755);
            *p = '/';
        }
    }
    mkdir(tmp, 0755);
}

#define VT_MAX_CACHES 256
static vv_cache *vt_caches[VT_MAX_CACHES];
static int vt_n_caches;

static void
vt_free_caches(void) {
    for (int i = 0; i < vt_n_caches; i++)
        vv_cache_free(vt_caches[i]);
    vt_n_caches = 0;
}

vv_cache *
vt_cache(uint64_t limit) {
    if (!limit)
        return NULL;
    if (vt_n_caches == 0)
        atexit(vt_free_caches);
    if (vt_n_caches == VT_MAX_CACHES)
        fail_msg("vt_cache: over %d caches", VT_MAX_CACHES);
    vv_cache *c = NULL;
    if (vv_cache_new(&c, limit) != VV_OK)
        fail_msg("vt_cache: %s", vv_error_message());
    vt_caches[vt_n_caches++] = c;
    return c;
}

char *
vt_mkdtemp(char *buf, size_t n, const char *prefix) {
    const char *tmp = getenv("TMPDIR");
    if (!tmp || !*tmp || (size_t)snprintf(buf, n, "%s/%sXXXXXX", tmp, prefix) >= n)
        tmp = "/tmp";
    if ((size_t)snprintf(buf, n, "%s/%sXXXXXX", tmp, prefix) >= n) {
        errno = ENAMETOOLONG;
        return NULL;
    }
    return mkdtemp(buf);
}

const char *
vt_outdir(const char *name) {
    static char buf[1024];
    snprintf(buf, sizeof buf, "%s/test-out/%s", VV_BINARY_DIR, name);
    mkdir_p(buf);
    return buf;
}

void
vt_write_file(const char *path, const void *data, size_t n) {
    FILE *f = fopen(path, "wb");
    if (!f)
        fail_msg("cannot write %s: %s", path, strerror(errno));
    if (n && fwrite(data, 1, n, f) != n)
        fail_msg("short write %s", path);
    fclose(f);
}

vv_status
vt_save(const vv_volume *v, const char *path, vv_format format, int compress, unsigned vvb_flags) {
    vv_save_options o;
    vv_save_options_init(&o);
    o.format = format;
    o.compress = compress;
    o.vvb_flags = vvb_flags;
    return vv_volume_save_with(v, path, &o);
}

unsigned char *
vt_read_file(const char *path, size_t *n) {
    FILE *f = fopen(path, "rb");
    if (!f)
        fail_msg("cannot read %s: %s", path, strerror(errno));
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)len + 1);
    assert_non_null(buf);
    if (len && fread(buf, 1, (size_t)len, f) != (size_t)len)
        fail_msg("short read %s", path);
    buf[len] = 0;
    fclose(f);
    *n = (size_t)len;
    return buf;
}

const char *
vt_path(const char *dir, const char *name) {
    static _Thread_local char buf[8][1200];
    static _Thread_local int slot;
    slot = (slot + 1) % 8;
    snprintf(buf[slot], sizeof buf[slot], "%s/%s", dir, name);
    return buf[slot];
}

vt_run_result
vt_run_cli_v(const char *dir, const char *const *args) {
    char *argv[64];
    int n = 0;
    const char *cli = getenv("VV_CLI");
    argv[n++] = (char *)(cli && *cli ? cli : VV_BINARY_DIR "/volvis");
    for (int i = 0; args[i]; i++) {
        assert_true(n < 63);
        argv[n++] = (char *)args[i];
    }
    argv[n] = NULL;
    /* own buffers: the caller's paths may sit in vt_path's rotating ones */
    char out_path[1200], err_path[1200];
    snprintf(out_path, sizeof out_path, "%s/.stdout", dir);
    snprintf(err_path, sizeof err_path, "%s/.stderr", dir);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid;
    int rc = posix_spawn(&pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0)
        fail_msg("cannot run %s: %s (set VV_CLI)", argv[0], strerror(rc));
    int st;
    while (waitpid(pid, &st, 0) < 0)
        assert_int_equal(errno, EINTR);
    vt_run_result r;
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    size_t len;
    r.out = (char *)vt_read_file(out_path, &len);
    r.err = (char *)vt_read_file(err_path, &len);
    return r;
}

void
vt_run_cli_expect(const char *dir, int status, const char *err_has, const char *const *args) {
    vt_run_result r = vt_run_cli_v(dir, args);
    if (r.status != status || (err_has && !strstr(r.err, err_has)))
        fail_msg("volvis %s: exit %d (expected %d), stderr: %s", args[0], r.status, status, r.err);
    vt_run_result_free(&r);
}

void
vt_run_result_free(vt_run_result *r) {
    free(r->out);
    free(r->err);
    r->out = r->err = NULL;
}

vv_mesh *
vt_sphere_mesh(double r, int levels) {
    vv_mesh *m = NULL;
    vt_ok(vv_mesh_new(&m));
    const vv_vec3 p[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int i = 0; i < 6; i++)
        vt_ok(vv_mesh_add_vertex(m, vv_vec3_scale(p[i], r), NULL));
    const uint32_t f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                              {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (int i = 0; i < 8; i++)
        vt_ok(vv_mesh_add_triangle(m, f[i][0], f[i][1], f[i][2]));
    for (int l = 0; l < levels; l++) {
        /* split each triangle in four; edge midpoints shared through a table */
        size_t nt = m->n_triangles, nv = m->n_vertices;
        uint32_t *mid = malloc(nv * nv * sizeof *mid);
        assert_non_null(mid);
        memset(mid, 0xff, nv * nv * sizeof *mid);
        uint32_t *old = malloc(nt * 3 * sizeof *old);
        assert_non_null(old);
        memcpy(old, m->triangles, nt * 3 * sizeof *old);
        m->n_triangles = 0;
        for (size_t t = 0; t < nt; t++) {
            uint32_t v[3] = {old[3 * t], old[3 * t + 1], old[3 * t + 2]}, e[3];
            for (int k = 0; k < 3; k++) {
                uint32_t a = v[k], b = v[(k + 1) % 3];
                uint32_t *slot = &mid[(size_t)(a < b ? a : b) * nv + (a < b ? b : a)];
                if (*slot == UINT32_MAX) {
                    vv_vec3 c = vv_vec3_add(vv_mesh_vertex(m, a), vv_mesh_vertex(m, b));
                    vt_ok(vv_mesh_add_vertex(m, vv_vec3_scale(vv_vec3_normalize(c), r), slot));
                }
                e[k] = *slot;
            }
            vt_ok(vv_mesh_add_triangle(m, v[0], e[0], e[2]));
            vt_ok(vv_mesh_add_triangle(m, e[0], v[1], e[1]));
            vt_ok(vv_mesh_add_triangle(m, e[2], e[1], v[2]));
            vt_ok(vv_mesh_add_triangle(m, e[0], e[1], e[2]));
        }
        free(mid);
        free(old);
    }
    return m;
}

double
vt_rnd(uint64_t *s, double lo, double hi) {
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) / 9007199254740992.0;
}

double
vt_image_psnr(const vv_image *a, const vv_image *b, int *identical) {
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    const size_t n = 4 * (size_t)a->width * (size_t)a->height;
    if (identical)
        *identical = memcmp(a->rgba, b->rgba, n * sizeof(float)) == 0;
    double se = 0;
    for (size_t i = 0; i < n; i++) {
        const double e = (double)a->rgba[i] - (double)b->rgba[i];
        se += e * e;
    }
    return se > 0 ? 10 * log10(1.0 / (se / (double)n)) : INFINITY;
}

double
vt_image_diff(const vv_image *a, const vv_image *b, double *mean) {
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    const size_t n = 4 * (size_t)a->width * (size_t)a->height;
    double m = 0, sum = 0;
    for (size_t i = 0; i < n; i++) {
        const double d = fabs((double)a->rgba[i] - (double)b->rgba[i]);
        m = d > m ? d : m;
        sum += d;
    }
    if (mean)
        *mean = n ? sum / (double)n : 0;
    return m;
}

void
vt_tf_grey(vv_tf *tf, double lo, double hi) {
    vv_tf_init(tf);
    vt_ok(vv_tf_add_opacity(tf, lo, 1.0));
    vt_ok(vv_tf_add_opacity(tf, hi, 1.0));
    vt_ok(vv_tf_add_color(tf, lo, vv_vec3_make(0, 0, 0)));
    vt_ok(vv_tf_add_color(tf, hi, vv_vec3_make(1, 1, 1)));
}

void
vt_tf_flat_ends(vv_tf *tf, double lo, double hi) {
    vv_tf_init(tf);
    vt_ok(vv_tf_add_opacity(tf, lo + 0.3 * (hi - lo), 0.2));
    vt_ok(vv_tf_add_opacity(tf, lo + 0.97 * (hi - lo), 1.0));
    vt_ok(vv_tf_add_color(tf, lo, vv_vec3_make(0, 0, 1)));
    vt_ok(vv_tf_add_color(tf, hi, vv_vec3_make(1, 1, 0)));
}

double
vt_napari_attenuated_mip(const double *vals, int n, double lo, double hi, double att, double step,
                         int *at) {
    double sum = 0, best = -INFINITY;
    for (int i = 0; i < n; i++) {
        const double u = (vals[i] - lo) / (hi - lo);
        sum += u < 0 ? 0 : u > 1 ? 1 : u;
        const double x = vals[i] * exp(-att * (sum - 1) / step);
        if (x > best) {
            best = x;
            *at = i;
        }
    }
    return best;
}

double
vt_png_psnr(const char *a, const char *b) {
    vv_image *x = NULL, *y = NULL;
    vt_ok(vv_image_read_png(&x, a));
    vt_ok(vv_image_read_png(&y, b));
    const double db = vt_image_psnr(x, y, NULL);
    vv_image_free(x);
    vv_image_free(y);
    return db;
}

vv_image *
vt_render_q(vv_renderer *r, const vv_world *w, int quality, int threads, vv_render_stats *st) {
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = threads;
    opt.quality = quality;
    opt.stats = st;
    vt_ok(vv_renderer_render(r, w, &w->view, &opt, img));
    return img;
}

vv_image *
vt_converged_reference(vv_renderer *r, const vv_world *world, int step_div, int k) {
    vv_world *w = NULL;
    vt_ok(vv_world_clone(&w, world));
    for (int i = 0; i < w->n_objects; i++)
        w->objects[i]->step /= step_div;
    w->view.width *= k;
    w->view.height *= k;
    vv_image *big = vt_render_q(r, w, 2, 0, NULL), *img = NULL;
    vt_ok(vv_image_new(&img, world->view.width, world->view.height));
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++)
            for (int c = 0; c < 4; c++) {
                double sum = 0;
                for (int j = 0; j < k; j++)
                    for (int i = 0; i < k; i++)
                        sum += big->rgba[4 * ((size_t)(y * k + j) * (size_t)big->width +
                                              (size_t)(x * k + i)) +
                                         (size_t)c];
                img->rgba[4 * ((size_t)y * (size_t)img->width + (size_t)x) + (size_t)c] =
                    (float)(sum / (k * k));
            }
    vv_image_free(big);
    vv_world_free(w);
    return img;
}

vv_default_scene_options
vt_scene_options(int size) {
    vv_default_scene_options so;
    vv_default_scene_options_init(&so);
    so.width = so.height = size;
    so.azimuth = vv_deg_to_rad(30);
    so.elevation = vv_deg_to_rad(20);
    return so;
}

vv_world *
vt_volume_scene(const char *rel, int size, vv_volume **vol) {
    vt_ok(vv_volume_load(vol, vt_data(rel), NULL));
    vv_default_scene_options so = vt_scene_options(size);
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, *vol, &so));
    return w;
}

void
vt_expect_refusal(const char *label, vv_status got, vv_status want, const char *needle,
                  const char *name) {
    const char *msg = vv_error_message();
    const char *l = label ? label : "refusal";
    if (got != want)
        fail_msg("%s: got %s, expected %s: %s", l, vv_status_name(got), vv_status_name(want), msg);
    if (needle && !strstr(msg, needle))
        fail_msg("%s: message '%s' does not mention '%s'", l, msg, needle);
    if (name && !strstr(msg, name))
        fail_msg("%s: message '%s' does not name '%s'", l, msg, name);
    for (const unsigned char *c = (const unsigned char *)msg; *c; c++)
        if (*c < 0x20 || *c == 0x7f)
            fail_msg("%s: message '%s' is not one printable line (byte 0x%02x)", l, msg, *c);
}

vv_image *
vt_render_reference(vv_world *w) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    vt_ok(vv_renderer_set_option(r, "refinement", "off"));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vt_ok(vv_renderer_render(r, w, &w->view, NULL, img));
    vv_renderer_free(r);
    return img;
}

void
vt_save_png(const vv_image *img, const char *dir, const char *prefix, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s%s.png", dir, prefix, name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

vv_source *
vt_open_ooc(const char *path, int levels, vv_cache *cache) {
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE;
    oo.levels = levels;
    oo.cache = cache;
    vv_opened od;
    vt_ok(vv_open(&od, path, &oo));
    assert_int_equal(vv_source_get_kind(od.source), levels ? VV_SOURCE_PYRAMID : VV_SOURCE_BRICKS);
    vv_source *s = vv_source_ref(od.source);
    vv_opened_clear(&od);
    return s;
}

int
vt_listen_loopback(int backlog, int *port) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
    socklen_t len = sizeof a;
    assert_int_equal(getsockname(fd, (struct sockaddr *)&a, &len), 0);
    *port = ntohs(a.sin_port);
    assert_int_equal(listen(fd, backlog), 0);
    return fd;
}

double
vt_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

size_t
vt_read_request_head(int fd, char *buf, size_t cap) {
    size_t n = 0;
    buf[0] = '\0';
    while (n + 1 < cap) {
        const ssize_t r = read(fd, buf + n, cap - 1 - n);
        if (r <= 0)
            break;
        n += (size_t)r;
        buf[n] = '\0';
        if (strstr(buf, "\r\n\r\n"))
            break;
    }
    return n;
}
