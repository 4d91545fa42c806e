/*
 * `volvis render` under mpirun -np N: every rank builds the World from the
 * same command line (a file read by boxes opens out of core, each rank
 * reading its own box through the object's source), checks that it agrees
 * with rank 0 on the command line and the input file, and renders its brick; the partial images are
 * composited (binary swap or radix-k) and rank 0 writes the PNG and prints
 * the `wrote` line, which names the number of ranks. A failure on any rank
 * (an unreadable file, a bad option) stops every rank with that rank's
 * error, printed once by rank 0. `volvis animate` under mpirun renders each
 * frame the same way (cli_animate_parallel). docs/parallel.md.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* The bytes every rank must agree on: the command line, then the input
 * file (its first 64 KiB and its size: a scene file whole, a volume file's
 * header, not its voxels, which the ranks read by bricks). */
static vv_status
check_same_input(const cli_args *a, const cli_render_args *r) {
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    if (!buf)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < a->n_seen; i++) {
        const char *k = a->specs[a->seen[i].opt].name, *v = a->seen[i].value;
        n += (size_t)snprintf(buf + n, cap - n, "--%s=%s;", k, v ? v : "");
        if (n >= cap - 1)
            break;
    }
    vv_status s = vv_parallel_check_same(buf, n < cap ? n : cap, "the command line");
    free(buf);
    if (s != VV_OK || !r->input)
        return s;
    FILE *f = fopen(r->input, "rb");
    const size_t limit = (size_t)64 << 10;
    unsigned char *data = malloc(limit + 16);
    size_t got = 0;
    if (f && data) {
        got = fread(data, 1, limit, f);
        fseek(f, 0, SEEK_END);
        long size = ftell(f);
        memcpy(data + got, &size, sizeof size);
        got += sizeof size;
    }
    if (f)
        fclose(f);
    char what[1100];
    snprintf(what, sizeof what, "the input file %s", r->input);
    s = vv_parallel_check_same(data, data ? got : 0, what);
    free(data);
    return s;
}

/* A local failure rc (0: none) made collective: every rank returns the
 * same exit code; rank 0 prints the first failing rank's error unless it
 * printed its own. */
static int
agree(int rc) {
    vv_status local = VV_OK;
    if (rc) {
        const char *m = cli_last_error();
        local = vv_error_set(VV_ERR_INVALID, "%s", m && *m ? m : "failed");
    }
    vv_status s = vv_parallel_agree(local);
    if (s == VV_OK)
        return 0;
    if (!rc)
        cli_fail(s, NULL);
    return rc ? rc : CLI_EXIT_FAIL;
}

int
cli_render_parallel(cli_args *a, cli_render_args *r) {
    int rank = 0, size = 1, rc;
    vv_world *w = NULL;
    vv_renderer *ren = NULL;
    vv_parallel *par = NULL;
    vv_image *img = NULL;
    vv_status s = vv_parallel_init(NULL, NULL, &rank, &size);
    if (s != VV_OK)
        return cli_fail(s, NULL);
    /* every rank builds the same World; a file read by boxes out of core
     * (vv_world_open_options.distributed: the range left to the ranks) is read by
     * each rank box by box, its own only, through the object's source */
    rc = agree(cli_render_world(r, &w, NULL));
    if (rc)
        goto done;
    vv_error_clear();
    s = check_same_input(a, r);
    if (s != VV_OK) {
        /* every rank has the error already */
        rc = cli_fail(s, NULL);
        goto done;
    }
    cli_render_turn(r, w);
    int quality = 2;
    rc = cli_render_renderer(a, r, w, &ren, &quality);
    vv_parallel_options po;
    vv_parallel_options_init(&po);
    po.method = (vv_compositing)r->compositing;
    po.radix = r->radix;
    if (!rc && (s = vv_parallel_new(&par, ren, &po)) != VV_OK)
        rc = cli_fail(s, NULL);
    if (!rc && rank == 0 && (s = vv_image_new(&img, w->view.width, w->view.height)) != VV_OK)
        rc = cli_fail(s, NULL);
    if ((rc = agree(rc)))
        goto done;
    if (r->threads > 0)
        vv_threads_set(r->threads);
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = r->threads;
    ro.quality = quality;
    vv_lod lod; /* --level: the pyramid's level the ranks read */
    cli_render_lod(r, &lod);
    ro.lod = &lod;
    double t0 = cli_now();
    vv_error_clear();
    vv_parallel_stats st;
    s = vv_parallel_render(par, w, &w->view, &ro, img, &st);
    double seconds = cli_now() - t0;
    if (s != VV_OK) {
        /* already agreed: the same error on every rank, printed by rank 0 */
        rc = cli_fail(s, NULL);
        goto done;
    }
    if (rank == 0) {
        vv_error_clear();
        if ((s = vv_image_write_png(img, r->output, r->gamma, r->alpha)) != VV_OK)
            rc = cli_fail(s, r->output);
    }
    if ((rc = agree(rc)))
        goto done;
    if (!r->quiet)
        printf("wrote %s (%dx%d, %.2f s on %d rank%s)\n", r->output, w->view.width, w->view.height,
               seconds, size, size == 1 ? "" : "s");
    rc = CLI_EXIT_OK;
done:
    vv_image_free(img);
    vv_parallel_free(par);
    vv_renderer_free(ren);
    vv_world_free(w);
    return rc;
}

/* What rank 0's Animator hands to the frame renderer. */
typedef struct anim_ctx {
    vv_parallel *par;
} anim_ctx;

/* Rank 0: announce frame k to the other ranks, then render it with them. */
static vv_status
render_frame0(void *user, int frame, const vv_world *w, const vv_view *view,
              const vv_render_options *ro, vv_image *out) {
    anim_ctx *c = user;
    int k = frame;
    vv_status s = vv_parallel_broadcast(&k, sizeof k);
    if (s != VV_OK)
        return s;
    return vv_parallel_render(c->par, w, view, ro, out, NULL);
}

int
cli_animate_parallel(const cli_render_args *r, const vv_animation *anim, const vv_world *w,
                     vv_renderer *ren, vv_anim_render_options *o, vv_anim_render_stats *stats,
                     vv_status *st) {
    int rank = 0, size = 1;
    vv_parallel *par = NULL;
    vv_status s = vv_parallel_init(NULL, NULL, &rank, &size);
    int rc = 0;
    vv_parallel_options po;
    vv_parallel_options_init(&po);
    po.method = (vv_compositing)r->compositing;
    po.radix = r->radix;
    if (!rc && (s = vv_parallel_new(&par, ren, &po)) != VV_OK)
        rc = cli_fail(s, NULL);
    if ((rc = agree(rc))) {
        vv_parallel_free(par);
        return rc;
    }
    vv_status mine = VV_OK;
    if (rank == 0) {
        anim_ctx c = {par};
        o->render_frame = render_frame0;
        o->render_frame_user = &c;
        mine = vv_animation_render(anim, w, ren, o, stats);
        int done = -1;
        vv_parallel_broadcast(&done, sizeof done);
    } else {
        /* render what rank 0 announces until it says -1 */
        for (;;) {
            int k = -1;
            if (vv_parallel_broadcast(&k, sizeof k) != VV_OK || k < 0)
                break;
            vv_world *snap = NULL;
            vv_status es = vv_animation_eval_frame(anim, w, k, &snap);
            vv_render_options ro = o->render;
            ro.progress.fn = NULL;
            /* a failure is agreed inside: rank 0 stops and says -1 */
            vv_parallel_render(par, es == VV_OK ? snap : w, es == VV_OK ? &snap->view : &w->view,
                               &ro, NULL, NULL);
            vv_world_free(snap);
        }
    }
    *st = mine;
    if (mine != VV_OK)
        rc = cli_fail(mine, NULL);
    vv_parallel_free(par);
    return agree(rc);
}
