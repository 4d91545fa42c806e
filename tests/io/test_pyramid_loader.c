/*
 * The pyramid's asynchronous loader (vv_pyramid_request; issue 29): an
 * OME-Zarr pyramid of the real CT head (256 x 256 x 108, int16; levels of
 * 32, 4 and 1 chunks of 64^3) read in this process and through the
 * sandboxed readers.
 *
 * - Progressive frames that ask the loader for their pending chunks
 *   (vv_lod.background) and wait between frames get closer to the
 *   converged image frame by frame (PSNR non-decreasing) and end on it bit
 *   for bit; no chunk is read twice, and the last frame reads nothing.
 * - A frame drawn while the loader reads the chunks it needs waits for them
 *   instead of reading them again: the level-0 image is the cold one bit
 *   for bit, each chunk read once.
 * - A new request cancels what the old one left queued (counted), and
 *   chunks in flight finish: loaded + cancelled is what was asked.
 * - A cache too small for the request: the loader stops at the limit
 *   (load_stopped), the peak stays under it; progressive frames then
 *   report the loader stalled, and a converged frame streams the cold
 *   frame's image bit for bit.
 * - A chunk that does not decode: the loader counts it and goes on; the
 *   frame that needs it fails with the store's one-line error.
 * - The same store by URL from a loopback server that holds level 0's
 *   chunks: a request for nothing drops the fetches in flight (their
 *   connections closed, the server sees the client go) instead of waiting
 *   for them; asked again once the server answers, every chunk arrives and
 *   the level-0 frame is the local file's bit for bit.
 */
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"

#include "io/store/pyramid.h"
#include "render/drivers.h"
#include "volvis/volvis.h"

#define MIB (1024u * 1024u)

static char g_store[4096], g_broken[4096];

/* The CT head written as an OME-Zarr pyramid by the library's writer, and a
 * copy with one level-0 chunk overwritten with garbage. */
static int
setup(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        return 0;
    const char *dir = vt_outdir("pyramid_loader");
    snprintf(g_store, sizeof g_store, "%s/head.ome.zarr", dir);
    snprintf(g_broken, sizeof g_broken, "%s/broken.ome.zarr", dir);
    vv_volume *v = NULL;
    vv_status s = vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL);
    if (s == VV_OK)
        s = vt_save(v, g_store, VV_FORMAT_OME_ZARR, -1, 0);
    if (s == VV_OK)
        s = vt_save(v, g_broken, VV_FORMAT_OME_ZARR, -1, 0);
    vv_volume_free(v);
    if (s != VV_OK) {
        fprintf(stderr, "setup: %s\n", vv_error_message());
        return -1;
    }
    char chunk[4200];
    snprintf(chunk, sizeof chunk, "%s/0/c/1/1/1", g_broken); /* OME-NGFF 0.5: Zarr v3's key */
    FILE *f = fopen(chunk, "wb");
    if (!f)
        return -1;
    fputs("this is not a zstd frame", f);
    fclose(f);
    return 0;
}

/* A pyramid of @p path under @p limit bytes, through the sandbox or not. */
static vv_pyramid *
open_pyramid(const char *path, uint64_t limit, int sandbox) {
    setenv("VOLVIS_SANDBOX", sandbox ? "1" : "0", 1);
    vv_pyramid *p = NULL;
    vt_ok(vv_pyramid_open(&p, path, 0, -1, vt_cache(limit), NULL));
    unsetenv("VOLVIS_SANDBOX");
    return p;
}

/* The scene of `volvis render STORE`: the coarsest level as the proxy,
 * placed over level 0's box, 192 pixels square. */
static vv_world *
scene(vv_pyramid *p) {
    vv_volume *proxy = NULL;
    vt_ok(vv_pyramid_proxy(p, 0, &proxy));
    vv_default_scene_options so = vt_scene_options(192);
    so.has_tf_range = 1;
    so.tf_lo = 100;
    so.tf_hi = 1500;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, proxy, &so));
    vv_volume_free(proxy);
    return w;
}

static uint64_t
reads(vv_pyramid *p) {
    vv_pyramid_stats st;
    vv_pyramid_stats_get(p, &st);
    uint64_t n = 0;
    for (int l = 0; l < VV_PYRAMID_MAX_LEVELS; l++)
        n += st.chunk_reads[l];
    return n;
}

/* One frame of @p p (progressive with the loader when @p progressive). */
static vv_status
frame(vv_pyramid *p, vv_world *w, int level, int progressive, vv_lod *lod, vv_image *img) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    vv_multires_source src;
    vv_pyramid_source(p, &src);
    vv_lod_init(lod);
    lod->level = level;
    lod->progressive = progressive;
    lod->background = progressive;
    lod->load_budget = 0;
    vv_render_options ro;
    vv_render_options_init(&ro);
    const vv_status s = drv_render_multires(drv_renderer_of(r, &(drv_renderer){0}), w, 0, &src,
                                            &w->view, &ro, lod, img);
    vv_renderer_free(r);
    return s;
}

static int
same_image(const vv_image *a, const vv_image *b) {
    return a->width == b->width && a->height == b->height &&
           !memcmp(a->rgba, b->rgba, sizeof(float) * 4 * (size_t)a->width * (size_t)a->height);
}

/* The scene of a store, its cold frame from a fresh pyramid (every node at
 * level @p level, or by level of detail: -1), and an image for the test's. */
typedef struct fixture {
    vv_world *w;
    vv_image *ref, *img;
} fixture;

static void
fixture_init(fixture *fx, const char *path, uint64_t limit, int sandbox, int level) {
    vv_pyramid *p = open_pyramid(path, limit, sandbox);
    fx->w = scene(p);
    fx->ref = fx->img = NULL;
    vt_ok(vv_image_new(&fx->ref, 192, 192));
    vt_ok(vv_image_new(&fx->img, 192, 192));
    vv_lod lod;
    vt_ok(frame(p, fx->w, level, 0, &lod, fx->ref));
    vv_pyramid_free(p);
}

static void
fixture_free(fixture *fx) {
    vv_image_free(fx->ref);
    vv_image_free(fx->img);
    vv_world_free(fx->w);
}

/* Until the loader has nothing queued or in flight. */
static void
wait_idle(vv_pyramid *p) {
    while (vv_pyramid_loading(p) > 0)
        vv_pyramid_wait(p, 10.0);
}

static void
progressive_converges(int sandbox) {
    if (!g_store[0])
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    /* the converged frame, every node at its level, read as needed */
    fixture fx;
    fixture_init(&fx, g_store, 64 * MIB, sandbox, -1);
    vv_world *w = fx.w;
    vv_image *ref = fx.ref, *img = fx.img;
    vv_lod lod;
    vv_pyramid *p = open_pyramid(g_store, 64 * MIB, sandbox);
    double last = -1;
    int frames = 0, requested0 = 0, pending0 = 0;
    uint64_t frame_reads = 0;
    for (; frames < 400; frames++) {
        vv_pyramid_stats st0, st1;
        vv_pyramid_stats_get(p, &st0);
        const uint64_t r0 = reads(p);
        vt_ok(frame(p, w, -1, 1, &lod, img));
        vv_pyramid_stats_get(p, &st1);
        frame_reads = reads(p) - r0 - (st1.loaded - st0.loaded); /* the loader may still read */
        const double q = vv_image_psnr(img, ref);
        if (frames == 0) {
            requested0 = lod.requested;
            pending0 = lod.pending;
            printf("first frame: %d nodes pending, %d boxes requested, %.1f dB\n", lod.pending,
                   lod.requested, q);
        }
        assert_true(q >= last);
        last = q;
        if (lod.pending == 0)
            break;
        vv_pyramid_wait(p, 10.0);
    }
    vv_pyramid_stats st;
    vv_pyramid_stats_get(p, &st);
    printf("%s: %d frames; the loader read %llu chunks, %llu chunk reads in all, %llu "
           "cancelled\n",
           sandbox ? "sandboxed" : "in process", frames + 1, (unsigned long long)st.loaded,
           (unsigned long long)reads(p), (unsigned long long)st.cancelled);
    assert_true(pending0 > 0 && requested0 > 0);
    assert_int_equal(lod.pending, 0);
    assert_true(same_image(img, ref));
    assert_true(st.loaded > 0);
    assert_true(reads(p) <= 37); /* 32 + 4 + 1 chunks, none read twice */
    assert_int_equal(st.evictions, 0);
    assert_int_equal(frame_reads, 0); /* the last frame found everything resident */
    assert_int_equal(vv_pyramid_loading(p), 0);
    fixture_free(&fx);
    vv_pyramid_free(p);
}

static void
test_progressive_in_process(void **state) {
    (void)state;
    progressive_converges(0);
}

static void
test_progressive_sandboxed(void **state) {
    (void)state;
    progressive_converges(1);
}

/* Every level-0 chunk asked of the loader (32 boxes of one chunk each). */
static void
request_level0(vv_pyramid *p) {
    int lv[32], lo[96], hi[96], n = 0;
    for (int z = 0; z < 2; z++)
        for (int y = 0; y < 4; y++)
            for (int x = 0; x < 4; x++, n++) {
                lv[n] = 0;
                const int c[3] = {x, y, z};
                for (int k = 0; k < 3; k++) {
                    lo[3 * n + k] = 64 * c[k];
                    hi[3 * n + k] = 64 * c[k] + (k == 2 && c[k] == 1 ? 43 : 63);
                }
            }
    vt_ok(vv_pyramid_request(p, n, lv, lo, hi));
}

/* A level-0 frame while the loader reads the same chunks: it waits for them. */
static void
frame_during_loading(int sandbox) {
    if (!g_store[0])
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    fixture fx;
    fixture_init(&fx, g_store, 64 * MIB, sandbox, 0);
    vv_lod lod;
    vv_pyramid *p = open_pyramid(g_store, 64 * MIB, sandbox);
    const uint64_t opened = reads(p);
    request_level0(p);
    vt_ok(frame(p, fx.w, 0, 0, &lod, fx.img));
    wait_idle(p);
    vv_pyramid_stats st;
    vv_pyramid_stats_get(p, &st);
    printf("%s: the loader read %llu of the 32 level-0 chunks, the frame the rest\n",
           sandbox ? "sandboxed" : "in process", (unsigned long long)st.loaded);
    assert_true(same_image(fx.img, fx.ref));
    assert_int_equal(st.chunk_reads[0], 32);
    assert_int_equal(reads(p) - opened, 32);
    assert_true(st.max_reads_per_frame <= 1);
    fixture_free(&fx);
    vv_pyramid_free(p);
}

static void
test_frame_during_loading(void **state) {
    (void)state;
    frame_during_loading(0);
}

static void
test_frame_during_loading_sandboxed(void **state) {
    (void)state;
    frame_during_loading(1);
}

static void
test_cancel(void **state) {
    (void)state;
    if (!g_store[0])
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    vv_pyramid *p = open_pyramid(g_store, 64 * MIB, 0);
    request_level0(p);
    vt_ok(vv_pyramid_request(p, 0, NULL, NULL, NULL)); /* the view changed: nothing wanted */
    wait_idle(p);
    vv_pyramid_stats st;
    vv_pyramid_stats_get(p, &st);
    printf("cancelled %llu of 32 queued, %llu read (in flight)\n", (unsigned long long)st.cancelled,
           (unsigned long long)st.loaded);
    assert_int_equal(st.loaded + st.cancelled, 32);
    assert_true(st.cancelled >= 16);
    /* asked again: everything arrives, and the second request queues only
     * what is not held */
    request_level0(p);
    wait_idle(p);
    vv_pyramid_stats_get(p, &st);
    assert_int_equal(st.loaded, 32);
    assert_int_equal(st.chunk_reads[0], 32);
    assert_int_equal(st.load_errors, 0);
    /* bad requests */
    const int lv = 5, lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, big[3] = {0, 0, 200};
    assert_int_equal(vv_pyramid_request(p, 1, &lv, lo, hi), VV_ERR_INVALID);
    const int l0 = 0;
    assert_int_equal(vv_pyramid_request(p, 1, &l0, lo, big), VV_ERR_INVALID);
    vv_pyramid_free(p);
}

static void
test_full_cache(void **state) {
    (void)state;
    if (!g_store[0])
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    const uint64_t limit = 8 * MIB; /* level 0 alone is 13.5 MiB */
    vv_pyramid *p = open_pyramid(g_store, limit, 0);
    request_level0(p);
    wait_idle(p);
    vv_pyramid_stats st;
    vv_pyramid_stats_get(p, &st);
    printf("limit 8 MiB: the loader read %llu chunks and stopped with %llu left; peak %.1f MiB\n",
           (unsigned long long)st.loaded, (unsigned long long)st.load_stopped,
           (double)st.peak_bytes / MIB);
    assert_true(st.loaded > 0 && st.loaded < 32);
    assert_int_equal(st.loaded + st.load_stopped, 32);
    assert_true(st.peak_bytes <= limit);
    assert_int_equal(st.stalled, 1);
    /* a new request clears it until the loader stops again */
    vt_ok(vv_pyramid_request(p, 0, NULL, NULL, NULL));
    vv_pyramid_stats_get(p, &st);
    assert_int_equal(st.stalled, 0);
    vv_pyramid_free(p);
}

/* Level 0 everywhere within 8 MiB: the view needs more than the cache
 * holds, the frames report the loader stalled, and a converged frame then
 * streams the image of a cold converged frame, bit for bit. */
static void
test_progressive_stalls(void **state) {
    (void)state;
    if (!g_store[0])
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    fixture fx;
    fixture_init(&fx, g_store, 8 * MIB, 0, 0);
    vv_lod lod;
    vv_pyramid *p = open_pyramid(g_store, 8 * MIB, 0);
    int frames = 0;
    for (; frames < 100; frames++) {
        vt_ok(frame(p, fx.w, 0, 1, &lod, fx.img));
        if (lod.pending == 0 || lod.stalled)
            break;
        vv_pyramid_wait(p, 10.0);
    }
    printf("stalled after %d frames with %d nodes pending\n", frames + 1, lod.pending);
    assert_int_equal(lod.stalled, 1);
    assert_true(lod.pending > 0);
    vt_ok(frame(p, fx.w, 0, 0, &lod, fx.img));
    assert_int_equal(lod.pending, 0);
    assert_true(same_image(fx.img, fx.ref));
    fixture_free(&fx);
    vv_pyramid_free(p);
}

static void
test_broken_chunk(void **state) {
    (void)state;
    if (!g_store[0])
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    vv_pyramid *p = open_pyramid(g_broken, 64 * MIB, 0);
    vv_world *w = scene(p);
    request_level0(p);
    wait_idle(p);
    vv_pyramid_stats st;
    vv_pyramid_stats_get(p, &st);
    assert_int_equal(st.load_errors, 1);
    assert_int_equal(st.loaded, 31);
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 192, 192));
    vv_lod lod;
    const vv_status s = frame(p, w, 0, 0, &lod, img);
    printf("the frame: %s\n", vv_error_message());
    assert_int_equal(s, VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "broken.ome.zarr"));
    assert_non_null(strstr(vv_error_message(), "1/1/1"));
    assert_null(strchr(vv_error_message(), '\n'));
    vv_image_free(img);
    vv_world_free(w);
    vv_pyramid_free(p);
}

/* ---- the store by URL, from a server that holds level 0's chunks ---------- */

/* A loopback HTTP server of the files beneath root, one request a
 * connection (Connection: close), a thread each; a request for a level-0
 * chunk ("/0/c/" in its path) is held until release, and counted
 * abandoned when the client closes its connection meanwhile. */
typedef struct hold_srv {
    int fd, port;
    char root[4096];
    atomic_int release, stop, held, abandoned, live;
    pthread_t th;
} hold_srv;

typedef struct hold_conn {
    hold_srv *s;
    int c;
} hold_conn;

static void
send_all(int c, const void *buf, size_t n) {
    const char *p = buf;
    while (n > 0) {
        const ssize_t w = send(c, p, n, MSG_NOSIGNAL);
        if (w <= 0)
            return;
        p += w;
        n -= (size_t)w;
    }
}

static void *
hold_conn_main(void *u) {
    hold_conn *hc = u;
    hold_srv *s = hc->s;
    const int c = hc->c;
    free(hc);
    char req[8192];
    vt_read_request_head(c, req, sizeof req);
    char path[2048] = "";
    int gone = 0;
    if (sscanf(req, "GET %2047s", path) == 1 && strstr(path, "/0/c/")) {
        atomic_fetch_add(&s->held, 1);
        while (!atomic_load(&s->release) && !gone) {
            struct pollfd pf = {.fd = c, .events = POLLIN};
            char b;
            if (poll(&pf, 1, 20) > 0 && recv(c, &b, 1, MSG_PEEK | MSG_DONTWAIT) <= 0)
                gone = 1; /* the client closed it: the request abandoned */
        }
        atomic_fetch_sub(&s->held, 1);
        if (gone)
            atomic_fetch_add(&s->abandoned, 1);
    }
    char file[6200];
    snprintf(file, sizeof file, "%s%s", s->root, path);
    const int fd = gone ? -1 : open(file, O_RDONLY);
    struct stat sb;
    if (fd >= 0 && fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode)) {
        char head[200];
        snprintf(head, sizeof head,
                 "HTTP/1.1 200 OK\r\nContent-Length: %lld\r\nConnection: close\r\n\r\n",
                 (long long)sb.st_size);
        send_all(c, head, strlen(head));
        char buf[65536];
        ssize_t r;
        while ((r = read(fd, buf, sizeof buf)) > 0)
            send_all(c, buf, (size_t)r);
    } else if (!gone) {
        const char *nf = "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n";
        send_all(c, nf, strlen(nf));
    }
    if (fd >= 0)
        close(fd);
    close(c);
    atomic_fetch_sub(&s->live, 1);
    return NULL;
}

static void *
hold_accept(void *u) {
    hold_srv *s = u;
    while (!atomic_load(&s->stop)) {
        struct pollfd pf = {.fd = s->fd, .events = POLLIN};
        if (poll(&pf, 1, 50) <= 0)
            continue;
        const int c = accept(s->fd, NULL, NULL);
        hold_conn *hc = c >= 0 ? malloc(sizeof *hc) : NULL;
        pthread_t t;
        if (!hc) {
            if (c >= 0)
                close(c);
            continue;
        }
        *hc = (hold_conn){s, c};
        atomic_fetch_add(&s->live, 1);
        if (pthread_create(&t, NULL, hold_conn_main, hc) != 0) {
            atomic_fetch_sub(&s->live, 1);
            close(c);
            free(hc);
            continue;
        }
        pthread_detach(t);
    }
    return NULL;
}

static void
hold_start(hold_srv *s, const char *root) {
    memset(s, 0, sizeof *s);
    snprintf(s->root, sizeof s->root, "%s", root);
    s->fd = vt_listen_loopback(64, &s->port);
    assert_int_equal(pthread_create(&s->th, NULL, hold_accept, s), 0);
}

static void
nap(void) {
    const struct timespec ts = {0, 10000000};
    nanosleep(&ts, NULL);
}

static void
hold_stop(hold_srv *s) {
    atomic_store(&s->release, 1);
    atomic_store(&s->stop, 1);
    pthread_join(s->th, NULL);
    while (atomic_load(&s->live) > 0)
        nap();
    close(s->fd);
}

/* Until @p ok(s) or @p seconds pass; 1 when it held. */
static int
wait_for(hold_srv *s, int (*ok)(hold_srv *s), double seconds) {
    const double t0 = vt_now();
    while (!ok(s) && vt_now() - t0 < seconds)
        nap();
    return ok(s);
}

static int
all_held(hold_srv *s) {
    return atomic_load(&s->held) >= 32;
}

static int
all_abandoned(hold_srv *s) {
    return atomic_load(&s->abandoned) >= 32;
}

static void
test_cancel_in_flight_remote(void **state) {
    (void)state;
    if (!g_store[0])
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    fixture fx; /* the local store's level-0 frame */
    fixture_init(&fx, g_store, 64 * MIB, 0, 0);
    hold_srv *srv = calloc(1, sizeof *srv);
    assert_non_null(srv);
    hold_start(srv, vt_outdir("pyramid_loader"));
    char url[128];
    snprintf(url, sizeof url, "http://127.0.0.1:%d/head.ome.zarr", srv->port);
    vv_pyramid *p = open_pyramid(url, 64 * MIB, 1); /* a URL is read in this process */
    vv_remote_stats r0, r1;
    vv_remote_stats_get(&r0);
    /* every level-0 chunk in flight at once (two loaders, a window of 16
     * each), the server holding them */
    request_level0(p);
    if (!wait_for(srv, all_held, 30.0))
        fail_msg("the server holds %d of 32 requests", atomic_load(&srv->held));
    /* the view moves on: nothing wanted; the loader is idle as soon as
     * the fetches are dropped, not when the server answers */
    const double t0 = vt_now();
    vt_ok(vv_pyramid_request(p, 0, NULL, NULL, NULL));
    while (vv_pyramid_loading(p) > 0 && vt_now() - t0 < 30.0)
        vv_pyramid_wait(p, 0.1);
    const double idle = vt_now() - t0;
    assert_int_equal(vv_pyramid_loading(p), 0);
    assert_true(wait_for(srv, all_abandoned, 10.0)); /* their connections closed */
    vv_pyramid_stats st;
    vv_pyramid_stats_get(p, &st);
    vv_remote_stats_get(&r1);
    printf("dropped in flight: %llu chunks in %.3f s (the server saw %d requests abandoned); "
           "remote reads cancelled %llu\n",
           (unsigned long long)st.cancelled_in_flight, idle, atomic_load(&srv->abandoned),
           (unsigned long long)(r1.cancelled - r0.cancelled));
    assert_int_equal(st.cancelled_in_flight, 32);
    assert_int_equal(st.loaded, 0);
    assert_int_equal(st.load_errors, 0);
    assert_int_equal(r1.cancelled - r0.cancelled, 32);
    assert_int_equal(r1.failed, r0.failed);
    assert_int_equal(r1.pending, 0);
    /* asked again with the server answering: all of them arrive, and the
     * level-0 frame is the local file's bit for bit */
    atomic_store(&srv->release, 1);
    request_level0(p);
    wait_idle(p);
    vv_pyramid_stats_get(p, &st);
    assert_int_equal(st.loaded, 32);
    assert_int_equal(st.load_errors, 0);
    vv_lod lod;
    vt_ok(frame(p, fx.w, 0, 0, &lod, fx.img));
    assert_true(same_image(fx.img, fx.ref));
    vv_pyramid_free(p);
    hold_stop(srv);
    free(srv);
    fixture_free(&fx);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_progressive_in_process),
        cmocka_unit_test(test_progressive_sandboxed),
        cmocka_unit_test(test_frame_during_loading),
        cmocka_unit_test(test_frame_during_loading_sandboxed),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test(test_full_cache),
        cmocka_unit_test(test_progressive_stalls),
        cmocka_unit_test(test_broken_chunk),
        cmocka_unit_test(test_cancel_in_flight_remote),
    };
    return vt_run_tests(tests, setup, NULL);
}
