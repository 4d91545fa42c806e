/*
 * libFuzzer harness: what a front end does with a file it is given --
 * vv_world_open (src/scene/world_open.c, src/io/open.c), out of core where
 * the file can be read so, then a tiny image rendered from it -- so that
 * the paths only a render drives are fuzzed too: a .vvb's bricks and
 * pyramid levels read by the level-of-detail driver (src/io/store/bricked.c,
 * pyramid.c, and pyramid_load.c: the frame's plan, its boxes' ranges, the
 * missing chunks, the background loader of progressive frames), a raw
 * file's layout scanned into bricks, and the whole-file readers of our own
 * formats (SLC, MetaImage, VTK legacy) opened the way the CLI opens
 * them.
 *
 * The input: a first line naming the file and the options, then the file;
 * for a MetaImage header with a detached file, a line --DATA-- then the
 * data file (data.raw). The first line's words:
 *   vvb | raw | slc | mha | mhd | vtk   the format, and the file's name in.<word>
 *   raw=DESC          the raw file's --raw description (WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N])
 *   whole             read into memory (default: out of core where able)
 *   levels            a pyramid by its levels (level of detail)
 *   level=N           that level (out of core: every node at it)
 *   mip | minip | xray | iso   the mode (default: composite)
 *   progressive       frames drawn progressively, the rest asked of the background
 *                     loader, waited for, drawn again
 *   limit=K           the process cache's budget in KiB (default 16384)
 *   lod=X             the screen-space error's voxel_pixels (default 1)
 * Only our own parsers are named: no third-party library is called in the
 * fuzzing process. Volumes of more than 2^21 voxels (at the level drawn)
 * are opened but not drawn, so that one input takes milliseconds.
 */
#include "cli.h"
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define MAX_DRAWN ((uint64_t)1 << 21)
#define IMAGE_W 12
#define IMAGE_H 10

static const struct {
    const char *word;
    vv_format format;
} formats[] = {
    {"vvb", VV_FORMAT_VVB}, {"raw", VV_FORMAT_RAW}, {"slc", VV_FORMAT_SLC},
    {"mha", VV_FORMAT_MHD}, {"mhd", VV_FORMAT_MHD}, {"vtk", VV_FORMAT_VTK},
};

typedef struct opts {
    int fmt; /* index in formats */
    int has_raw;
    vv_raw_params raw;
    int whole, levels, level, mode, progressive;
    uint64_t limit;
    double lod;
} opts;

/* Parses the first line (NUL-terminated, at most 255 bytes); 0 when it is
 * not one this harness takes. */
static int
parse_line(char *line, opts *o) {
    memset(o, 0, sizeof *o);
    o->fmt = -1;
    o->level = -1;
    o->limit = (uint64_t)16 << 20;
    o->lod = 1;
    vv_raw_params_init(&o->raw);
    for (char *save = NULL, *w = strtok_r(line, " ", &save); w; w = strtok_r(NULL, " ", &save)) {
        int known = 0;
        for (int i = 0; i < (int)(sizeof formats / sizeof *formats); i++)
            if (!strcmp(w, formats[i].word)) {
                o->fmt = i;
                known = 1;
            }
        if (known)
            continue;
        if (!strncmp(w, "raw=", 4)) {
            if (cli_parse_raw(NULL, "raw", w + 4, &o->raw) != 0)
                return 0;
            o->has_raw = 1;
        } else if (!strcmp(w, "whole")) {
            o->whole = 1;
        } else if (!strcmp(w, "levels")) {
            o->levels = 1;
        } else if (!strncmp(w, "level=", 6)) {
            o->level = atoi(w + 6);
            if (o->level < 0 || o->level > 16)
                return 0;
        } else if (!strcmp(w, "mip")) {
            o->mode = VV_MODE_MIP;
        } else if (!strcmp(w, "minip")) {
            o->mode = VV_MODE_MINIP;
        } else if (!strcmp(w, "xray")) {
            o->mode = VV_MODE_XRAY;
        } else if (!strcmp(w, "iso")) {
            o->mode = VV_MODE_ISO;
        } else if (!strcmp(w, "progressive")) {
            o->progressive = 1;
        } else if (!strncmp(w, "limit=", 6)) {
            const long k = atol(w + 6);
            if (k < 1 || k > 65536)
                return 0;
            o->limit = (uint64_t)k << 10;
        } else if (!strncmp(w, "lod=", 4)) {
            o->lod = atof(w + 4);
            if (!(o->lod >= 0.25 && o->lod <= 64))
                return 0;
        } else {
            return 0;
        }
    }
    return o->fmt >= 0;
}

/* The voxels of the level the frame draws most finely. */
static uint64_t
voxels_drawn(const vv_object *ob, int level) {
    const vv_volume *h = ob->volume;
    if (ob->source) {
        const int n = vv_source_levels(ob->source);
        h = vv_source_level(ob->source, level < 0 ? 0 : level < n ? level : n - 1);
    }
    if (!h)
        return UINT64_MAX;
    return (uint64_t)h->dims[0] * (uint64_t)h->dims[1] * (uint64_t)h->dims[2];
}

static void
render(vv_renderer *r, vv_world *w, const opts *o) {
    static vv_image *img;
    if (!img && vv_image_new(&img, IMAGE_W, IMAGE_H) != VV_OK)
        __builtin_trap();
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = 1;
    ro.quality = 0;
    ro.proxy_fallback = 1;
    vv_lod lod;
    ro.lod = &lod;
    const vv_object *ob = w->n_objects > 0 ? w->objects[0] : NULL;
    if (o->progressive && ob && ob->source) {
        /* progressive, the chunks not yet read: one a frame, the rest asked
         * of the loader, waited for, drawn again */
        for (int frame = 0; frame < 3; frame++) {
            vv_lod_init(&lod);
            lod.level = o->level;
            lod.voxel_pixels = o->lod;
            lod.progressive = 1;
            lod.load_budget = 1;
            lod.background = 1;
            fuzz_check_status(vv_renderer_render(r, w, &w->view, &ro, img));
            if (lod.pending == 0)
                break;
            if (vv_source_loading(ob->source) > 0)
                vv_source_wait(ob->source, 0.5);
        }
    }
    /* the converged frame: every node at its level, read as the plan says */
    vv_lod_init(&lod);
    lod.level = o->level;
    lod.voxel_pixels = o->lod;
    fuzz_check_status(vv_renderer_render(r, w, &w->view, &ro, img));
    if (ob && ob->source) {
        vv_source_stats st;
        vv_source_stats_get(ob->source, &st);
    }
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static vv_renderer *raycast;
    if (!raycast && vv_renderer_new(&raycast, "raycast") != VV_OK)
        __builtin_trap();
    const uint8_t *h, *rest, *file, *det;
    size_t nh, nrest, nfile, ndet;
    fuzz_split(data, size, "\n", &h, &nh, &rest, &nrest);
    if (nh > 255)
        return 0;
    char line[256];
    memcpy(line, h, nh);
    line[nh] = '\0';
    if (strlen(line) != nh)
        return 0;
    opts o;
    if (!parse_line(line, &o))
        return 0;
    fuzz_split(rest, nrest, "\n--DATA--\n", &file, &nfile, &det, &ndet);
    char name[16];
    snprintf(name, sizeof name, "in.%s", formats[o.fmt].word);
    const char *path = fuzz_write(name, file, nfile);
    if (ndet > 0 || !strcmp(formats[o.fmt].word, "mhd"))
        fuzz_write("data.raw", det, ndet);
    vv_world_open_options wo;
    vv_world_open_options_init(&wo);
    wo.load.format = formats[o.fmt].format;
    wo.load.has_raw = o.has_raw;
    wo.load.raw = o.raw;
    wo.memory = o.whole ? VV_WORLD_IN_MEMORY : VV_WORLD_OUT_OF_CORE_IF_ABLE;
    wo.memory_limit = o.limit;
    wo.levels = o.levels;
    wo.level = o.level;
    wo.has_mode = o.mode != 0;
    wo.view.mode = (vv_render_mode)o.mode;
    wo.has_size = 1;
    wo.view.width = IMAGE_W;
    wo.view.height = IMAGE_H;
    vv_world *w = NULL;
    vv_world_open_info info;
    const vv_status s = vv_world_open(&w, path, &wo, &info);
    fuzz_check_status(s);
    if (s != VV_OK)
        return 0;
    if (w->n_objects > 0 && voxels_drawn(w->objects[0], o.level) <= MAX_DRAWN)
        render(raycast, w, &o);
    vv_world_free(w);
    return 0;
}
