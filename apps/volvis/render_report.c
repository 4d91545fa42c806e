/*
 * The `wrote` line of `volvis render` (cli_render_report): the frame's
 * size and time, and for a World drawn out of core what each object's
 * source read -- a bricked file's bricks, a pyramid's nodes and chunks by
 * level -- and the cache's peak, from the sources' own counts
 * (vv_source_stats_get); objects that share a source (one file named
 * twice in a scene) are counted once.
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"

#define MIB(x) ((double)(x) / 1048576.0)

/* A bricked file's counts: "N of M bricks read, K skipped, X MiB read". */
static void
bricks_phrase(const vv_source_stats *st, char *buf, size_t cap) {
    snprintf(buf, cap, "%llu of %d bricks read, %llu skipped, %.1f MiB read",
             (unsigned long long)st->loads, st->n_bricks, (unsigned long long)st->skipped,
             MIB(st->bytes_read));
}

/* The single file's line: its bricks or its levels, as it always read. */
static void
report_one(const cli_render_args *r, const vv_object *o, const vv_image *img, double seconds,
           const vv_lod *lod) {
    vv_source_stats st;
    vv_source_stats_get(o->source, &st);
    char what[512];
    if (st.kind == VV_SOURCE_BRICKS) {
        bricks_phrase(&st, what, sizeof what);
        printf("wrote %s (%dx%d, %.2f s; out of core: %s, peak cache %.1f MiB)\n", r->output,
               img->width, img->height, seconds, what, MIB(st.peak_bytes));
        return;
    }
    const int nl = vv_source_levels(o->source);
    char levels[512] = "";
    int len = 0;
    for (int l = 0; l < nl && len < (int)sizeof levels - 64; l++)
        len += snprintf(levels + len, sizeof levels - (size_t)len, "%s%d: %d nodes %llu chunks",
                        l ? ", " : "", l, lod->nodes[l], (unsigned long long)st.chunk_reads[l]);
    printf("wrote %s (%dx%d, %.2f s; out of core from %d levels: %s; %d nodes skipped, "
           "%.1f MiB read, peak cache %.1f MiB, a chunk read at most %d times a frame)\n",
           r->output, img->width, img->height, seconds, nl, levels, lod->skipped,
           MIB(st.bytes_read), MIB(st.peak_bytes), st.max_reads_per_frame);
}

void
cli_render_report(const cli_render_args *r, const vv_world *w, const vv_image *img, double seconds,
                  const vv_lod *lod, int scene) {
    if (r->quiet)
        return;
    if (!cli_world_out_of_core(w)) {
        printf("wrote %s (%dx%d, %.2f s)\n", r->output, img->width, img->height, seconds);
        return;
    }
    int n = 0, visible = 0;
    const vv_object *one = NULL;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o->visible || o->type != VV_OBJECT_VOLUME)
            continue;
        visible++;
        if (o->source) {
            n++;
            one = o;
        }
    }
    if (!scene && n == 1 && visible == 1) {
        report_one(r, one, img, seconds, lod);
        return;
    }
    vv_cache_stats cs;
    vv_cache_stats_get(vv_cache_process(), &cs);
    printf("wrote %s (%dx%d, %.2f s; %d objects out of core in one cache of %.1f MiB, peak "
           "%.1f MiB):\n",
           r->output, img->width, img->height, seconds, n, MIB(cs.limit), MIB(cs.peak));
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o->visible || o->type != VV_OBJECT_VOLUME)
            continue;
        if (!o->source) {
            printf("  %s: in memory\n", o->name);
            continue;
        }
        /* objects naming one file out of core share its source (the
         * scene's table): its counts are the file's, printed once */
        const vv_object *first = NULL;
        for (int j = 0; j < i && !first; j++)
            if (w->objects[j]->visible && w->objects[j]->source == o->source)
                first = w->objects[j];
        if (first) {
            printf("  %s: the file of %s, one source (counted there)\n", o->name, first->name);
            continue;
        }
        vv_source_stats st;
        vv_source_stats_get(o->source, &st);
        char what[512];
        if (st.kind == VV_SOURCE_BRICKS) {
            bricks_phrase(&st, what, sizeof what);
            printf("  %s: %s\n", o->name, what);
        } else {
            unsigned long long chunks = 0;
            for (int l = 0; l < vv_source_levels(o->source); l++)
                chunks += st.chunk_reads[l];
            printf("  %s: %llu chunks read from %d levels, %.1f MiB read\n", o->name, chunks,
                   vv_source_levels(o->source), MIB(st.bytes_read));
        }
    }
}
