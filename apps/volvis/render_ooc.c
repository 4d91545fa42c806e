/*
 * `volvis render INPUT --memory-limit SIZE` (or a .vvb INPUT): a volume
 * larger than memory rendered brick by brick within the memory budget
 * (include/volvis/bricks.h) by any renderer with the region contract
 * (vv_renderer_render_bricks: raycast, raytrace). The World's defaults
 * (view framing, transfer function from the histogram) come from a coarse
 * proxy of the volume (vv_bricked_proxy), so the volume is never read
 * whole; the proxy stays the object's volume, through which a renderer
 * with global effects (raytrace's shadows) traces them.
 *
 * An OME-Zarr store is rendered from its pyramid (vv_pyramid) by level of
 * detail (vv_renderer_render_multires): --lod PIXELS, or --level L for
 * every node at one level; the proxy is its coarsest level, placed over the
 * box of level 0 (or of --level L), which the view frames.
 *
 * A scene has each of its volume files out of core in the same way, side
 * by side with those read whole. Every frame goes through
 * vv_renderer_render_sources (draw_frames), which for one object is the
 * brick or multiresolution driver's image.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"

/* The default transfer function's opacity is per smallest voxel spacing:
 * the volume's (@p whole), not its proxy's (@p proxy) that @p o was made
 * from. */
static void
object_opacity_unit(vv_object *o, const double whole[3], const double proxy[3]) {
    double ph = INFINITY, pp = INFINITY;
    for (int k = 0; k < 3; k++) {
        ph = whole[k] < ph ? whole[k] : ph;
        pp = proxy[k] < pp ? proxy[k] : pp;
    }
    if (fabs(o->tf.opacity_unit_distance - pp) <= 1e-12 * pp)
        o->tf.opacity_unit_distance = ph;
}

void
cli_proxy_opacity_unit(vv_world *w, const vv_volume *whole, const vv_volume *proxy) {
    for (int i = 0; i < w->n_objects; i++)
        object_opacity_unit(w->objects[i], whole->spacing, proxy->spacing);
}

/* The renderer of @p w (with --renderer, --set), the image of its view and
 * the options of the frame. 0 or an exit code. */
static int
frame_tools(cli_args *a, cli_render_args *r, const vv_world *w, vv_renderer **ren, vv_image **img,
            vv_render_options *ro) {
    int quality = 2;
    int rc = cli_render_renderer(a, r, w, ren, &quality);
    if (rc)
        return rc;
    vv_status s = vv_image_new(img, w->view.width, w->view.height);
    if (s != VV_OK)
        return cli_fail(s, NULL);
    if (r->threads > 0)
        vv_threads_set(r->threads);
    vv_render_options_init(ro);
    ro->threads = r->threads;
    ro->quality = quality;
    return 0;
}

/* The World from the proxy (its transfer function's opacity per @p whole's
 * voxel), turned; the renderer, the image and the options of the frame.
 * 0 or an exit code. */
static int
frame_setup(cli_args *a, cli_render_args *r, vv_volume *proxy, const vv_volume *whole, vv_world **w,
            vv_renderer **ren, vv_image **img, vv_render_options *ro) {
    int rc = cli_render_world_volume(r, proxy, w);
    if (rc)
        return rc;
    cli_proxy_opacity_unit(*w, whole, proxy);
    cli_render_turn(r, *w);
    return frame_tools(a, r, *w, ren, img, ro);
}

/* --lod, --level or --progressive: draw from a multiresolution file's
 * levels (a .vvb with levels is otherwise read by bricks). */
static int
wants_levels(const cli_render_args *r) {
    return r->has_lod || r->progressive > 0 || r->has_level;
}

/* The level of detail of --lod and --level (vv_renderer_render_multires;
 * a brick source ignores it). */
static void
frame_lod(const cli_render_args *r, vv_lod *lod) {
    vv_lod_init(lod);
    lod->level = r->has_level ? r->level : -1;
    lod->voxel_pixels = r->lod;
}

/* The frame of @p w's objects from @p src (vv_renderer_render_sources) into
 * @p img, timed in *@p seconds; with --progressive its steps too, each
 * written as OUT_pNNNN.png. 0 or an exit code (the
 * error printed). */
static int
draw_frames(const cli_render_args *r, vv_renderer *ren, const vv_world *w,
            const vv_object_source *src, int n_src, const vv_render_options *ro, vv_lod *lod,
            vv_image *img, double *seconds) {
    const double t0 = cli_now();
    vv_status s;
    int steps = 0;
    /* --progressive: step 0 from what is resident (the coarsest level), each
     * next step reading at most N chunks more, until nothing is pending */
    lod->progressive = r->progressive > 0;
    for (;;) {
        lod->load_budget = steps == 0 ? 0 : r->progressive;
        vv_error_clear();
        s = vv_renderer_render_sources(ren, w, src, n_src, &w->view, ro, lod, img);
        if (s != VV_OK || !lod->progressive)
            break;
        char step[4200];
        cli_numbered_path(r->output, 'p', steps, step, sizeof step);
        if ((s = vv_image_write_png(img, step, r->gamma, r->alpha)) != VV_OK)
            return cli_fail(s, step);
        steps++;
        if (lod->pending == 0)
            break;
    }
    *seconds = cli_now() - t0;
    if (s != VV_OK)
        return cli_fail(s, r->input);
    vv_error_clear();
    if ((s = vv_image_write_png(img, r->output, r->gamma, r->alpha)) != VV_OK)
        return cli_fail(s, r->output);
    if (steps > 0 && !r->quiet)
        printf("wrote %d progressive steps (_p0000 .. _p%04d)\n", steps, steps - 1);
    return 0;
}

static int
render_pyramid(cli_args *a, cli_render_args *r) {
    vv_pyramid *p = NULL;
    vv_world *w = NULL;
    vv_volume *proxy = NULL;
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    int rc;
    vv_error_clear();
    vv_status s = vv_pyramid_open(&p, r->input, r->channel, r->has_time ? r->time : -1,
                                  r->memory_limit, NULL);
    if (s != VV_OK) {
        rc = cli_fail(s, r->input);
        goto done;
    }
    if (r->has_level && r->level >= vv_pyramid_levels(p)) {
        cli_error("%s: level %d asked, the store has %d", r->input, r->level, vv_pyramid_levels(p));
        rc = CLI_EXIT_FAIL;
        goto done;
    }
    const int frame = r->has_level ? r->level : 0;
    if ((s = vv_pyramid_proxy(p, frame, &proxy)) != VV_OK) {
        rc = cli_fail(s, r->input);
        goto done;
    }
    vv_render_options ro;
    if ((rc = frame_setup(a, r, proxy, vv_pyramid_level(p, frame), &w, &ren, &img, &ro)))
        goto done;
    vv_lod lod;
    frame_lod(r, &lod);
    vv_multires_source ms;
    vv_pyramid_source(p, &ms);
    vv_object_source src;
    vv_object_source_init(&src, 0);
    src.multires = &ms;
    double seconds = 0;
    if ((rc = draw_frames(r, ren, w, &src, 1, &ro, &lod, img, &seconds)))
        goto done;
    if (!r->quiet) {
        vv_pyramid_stats st;
        vv_pyramid_stats_get(p, &st);
        char levels[512] = "";
        int len = 0;
        for (int l = 0; l < vv_pyramid_levels(p) && len < (int)sizeof levels - 64; l++)
            len += snprintf(levels + len, sizeof levels - (size_t)len, "%s%d: %d nodes %llu chunks",
                            l ? ", " : "", l, lod.nodes[l], (unsigned long long)st.chunk_reads[l]);
        printf("wrote %s (%dx%d, %.2f s; out of core from %d levels: %s; %d nodes skipped, "
               "%.1f MiB read, peak cache %.1f MiB, a chunk read at most %d times a frame)\n",
               r->output, img->width, img->height, seconds, vv_pyramid_levels(p), levels,
               lod.skipped, (double)st.bytes_read / 1048576.0, (double)st.peak_bytes / 1048576.0,
               st.max_reads_per_frame);
    }
    rc = CLI_EXIT_OK;
done:
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    vv_volume_free(proxy);
    vv_pyramid_free(p);
    return rc;
}

/* ---- a scene out of core: each volume file by bricks or by its pyramid ---------- */

/* A scene's volume file read out of core. */
typedef struct ooc_file {
    vv_bricked *b; /* or */
    vv_pyramid *p;
    const vv_volume *proxy;       /* the object's volume once loaded (borrowed) */
    double origin[3], spacing[3]; /* the proxy's, as the loader gave it */
} ooc_file;

/* What the scene's loader opened (scene_file). */
typedef struct ooc_scene {
    const cli_render_args *r;
    uint64_t limit; /* each file's share of --memory-limit */
    int multires;   /* --lod, --level or --progressive: a .vvb's levels */
    ooc_file f[VV_SOURCES_MAX];
    int n;
} ooc_scene;

static void
ooc_scene_free(ooc_scene *sc) {
    for (int i = 0; i < sc->n; i++) {
        vv_bricked_free(sc->f[i].b);
        vv_pyramid_free(sc->f[i].p);
    }
    sc->n = 0;
}

/* The scene's loader (vv_scene_load_with): a multiresolution file by its
 * pyramid, a .vvb, raw-layout NRRD by bricks, each under its share of the
 * memory limit, a coarse proxy standing in as the object's volume; any
 * other file (compressed NRRD, TIFF, NIfTI, ...) is read whole, in memory. */
static vv_status
scene_file(void *user, const char *path, int time, vv_scene_volume *out) {
    ooc_scene *sc = user;
    const int vvb = cli_ends_with(path, ".vvb");
    const int pyr = vv_pyramid_probe(path) && (sc->multires || !vvb);
    if (!pyr && time > 0)
        return VV_ERR_UNSUPPORTED; /* a time step: read whole */
    if (sc->n == VV_SOURCES_MAX)
        return vv_error_set(VV_ERR_LIMIT, "%s: more than %d volume files out of core", path,
                            VV_SOURCES_MAX);
    ooc_file *f = &sc->f[sc->n];
    memset(f, 0, sizeof *f);
    vv_volume *proxy = NULL;
    const vv_volume *h = NULL;
    vv_status s;
    if (pyr) {
        const int level = sc->r->has_level ? sc->r->level : 0;
        s = vv_pyramid_open(&f->p, path, 0, time > 0 ? time : -1, sc->limit, NULL);
        if (s == VV_OK && level >= vv_pyramid_levels(f->p))
            s = vv_error_set(VV_ERR_INVALID, "%s: level %d asked, the store has %d", path, level,
                             vv_pyramid_levels(f->p));
        if (s == VV_OK && (s = vv_pyramid_proxy(f->p, level, &proxy)) == VV_OK)
            h = vv_pyramid_level(f->p, 0);
    } else {
        s = vv_bricked_open(&f->b, path, NULL, sc->limit);
        if (s == VV_ERR_FORMAT && !vvb) { /* not readable by bricks: whole */
            vv_error_clear();
            return VV_ERR_UNSUPPORTED;
        }
        if (s == VV_OK && (s = vv_bricked_proxy(f->b, 128, &proxy)) == VV_OK)
            h = vv_bricked_header(f->b);
    }
    if (s != VV_OK) {
        vv_bricked_free(f->b);
        vv_pyramid_free(f->p);
        return s;
    }
    out->volume = proxy;
    for (int k = 0; k < 3; k++) {
        out->scale[k] = proxy->spacing[k] / h->spacing[k];
        f->origin[k] = proxy->origin[k];
        f->spacing[k] = proxy->spacing[k];
    }
    f->proxy = proxy;
    sc->n++;
    return VV_OK;
}

/* The file an object of the World shows, or NULL (in memory). */
static ooc_file *
object_file(ooc_scene *sc, const vv_object *o) {
    for (int i = 0; i < sc->n; i++)
        if (o->type == VV_OBJECT_VOLUME && o->volume == sc->f[i].proxy)
            return &sc->f[i];
    return NULL;
}

/* `volvis render SCENE --memory-limit SIZE`: every volume object from its
 * file out of core (vv_renderer_render_sources). */
static int
render_scene(cli_args *a, cli_render_args *r) {
    ooc_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.r = r;
    sc.multires = wants_levels(r);
    const int nf = vv_scene_loader_files(r->input);
    const uint64_t limit = r->memory_limit ? r->memory_limit : (uint64_t)1 << 30;
    sc.limit = limit / (uint64_t)(nf > 1 ? nf : 1);
    vv_world *w = NULL;
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    vv_object_source src[VV_SOURCES_MAX];
    vv_brick_source bs[VV_SOURCES_MAX];
    vv_multires_source ms[VV_SOURCES_MAX];
    int n_src = 0;
    int rc = cli_render_scene_world(r, scene_file, &sc, &w);
    if (rc)
        goto done;
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        ooc_file *f = object_file(&sc, o);
        if (!f)
            continue;
        for (int k = 0; k < 3; k++)
            /* (a saved session gives the file's own values back: equal up
             * to the rounding of the loader's scale) */
            if (fabs(o->volume->origin[k] - f->origin[k]) >
                    1e-9 * (fabs(f->origin[k]) + f->spacing[k]) ||
                fabs(o->volume->spacing[k] - f->spacing[k]) > 1e-9 * f->spacing[k]) {
                cli_error("%s: object '%s': out of core its file's own origin and spacing place "
                          "it; leave out \"origin\" and \"spacing\" (\"position\" and "
                          "\"scale\" move it)",
                          r->input, o->name);
                rc = CLI_EXIT_FAIL;
                goto done;
            }
        vv_object_source_init(&src[n_src], i);
        const vv_volume *h;
        if (f->p) {
            vv_pyramid_source(f->p, &ms[n_src]);
            src[n_src].multires = &ms[n_src];
            h = vv_pyramid_level(f->p, r->has_level ? r->level : 0);
        } else {
            vv_bricked_source(f->b, &bs[n_src]);
            src[n_src].bricks = &bs[n_src];
            h = vv_bricked_header(f->b);
        }
        object_opacity_unit(o, h->spacing, f->spacing);
        n_src++;
    }
    cli_render_turn(r, w);
    vv_render_options ro;
    if ((rc = frame_tools(a, r, w, &ren, &img, &ro)))
        goto done;
    vv_lod lod;
    frame_lod(r, &lod);
    double seconds = 0;
    if ((rc = draw_frames(r, ren, w, src, n_src, &ro, &lod, img, &seconds)))
        goto done;
    if (!r->quiet) {
        printf("wrote %s (%dx%d, %.2f s; %d objects out of core, %.1f MiB each):\n", r->output,
               img->width, img->height, seconds, sc.n, (double)sc.limit / 1048576.0);
        for (int i = 0; i < w->n_objects; i++) {
            const vv_object *o = w->objects[i];
            if (!o->visible || o->type != VV_OBJECT_VOLUME)
                continue;
            const ooc_file *f = object_file(&sc, o);
            if (f && f->b) {
                vv_bricked_stats st;
                vv_bricked_stats_get(f->b, &st);
                printf("  %s: %llu of %d bricks read, %llu skipped, %.1f MiB read\n", o->name,
                       (unsigned long long)st.loads, vv_bricked_count(f->b),
                       (unsigned long long)st.skipped, (double)st.bytes_read / 1048576.0);
            } else if (f) {
                vv_pyramid_stats st;
                vv_pyramid_stats_get(f->p, &st);
                unsigned long long chunks = 0;
                for (int l = 0; l < vv_pyramid_levels(f->p); l++)
                    chunks += st.chunk_reads[l];
                printf("  %s: %llu chunks read from %d levels, %.1f MiB read\n", o->name, chunks,
                       vv_pyramid_levels(f->p), (double)st.bytes_read / 1048576.0);
            } else {
                printf("  %s: in memory\n", o->name);
            }
        }
    }
    rc = CLI_EXIT_OK;
done:
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    ooc_scene_free(&sc);
    return rc;
}

int
cli_render_out_of_core(cli_args *a, cli_render_args *r) {
    if (vv_parallel_launched()) {
        int rank = 0, size = 1;
        vv_parallel_init(NULL, NULL, &rank, &size);
        if (size > 1) {
            cli_error("render: --memory-limit (out of core) runs on one rank, not under mpirun "
                      "-np %d",
                      size);
            return CLI_EXIT_USAGE;
        }
    }
    int rc = cli_check_readable_input(r->input);
    if (rc)
        return rc;
    if (!r->has_raw && cli_is_scene_file(r->input))
        return render_scene(a, r);
    /* a .vvb with pyramid levels reads by bricks unless asked for its levels */
    const int multires = wants_levels(r);
    if (!r->has_raw && vv_pyramid_probe(r->input) && (multires || !cli_ends_with(r->input, ".vvb")))
        return render_pyramid(a, r);
    if (multires && (r->has_lod || r->progressive > 0 || r->level > 0)) {
        cli_error("%s: --lod, --level and --progressive need a multiresolution file (OME-Zarr, "
                  "BigDataViewer or Imaris HDF5, or a .vvb with pyramid levels)",
                  r->input);
        return CLI_EXIT_USAGE;
    }
    vv_bricked *b = NULL;
    vv_world *w = NULL;
    vv_volume *proxy = NULL;
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    vv_error_clear();
    vv_status s = vv_bricked_open(&b, r->input, r->has_raw ? &r->raw : NULL, r->memory_limit);
    if (s != VV_OK) {
        rc = cli_fail(s, r->input);
        goto done;
    }
    if ((s = vv_bricked_proxy(b, 128, &proxy)) != VV_OK) {
        rc = cli_fail(s, r->input);
        goto done;
    }
    vv_render_options ro;
    if ((rc = frame_setup(a, r, proxy, vv_bricked_header(b), &w, &ren, &img, &ro)))
        goto done;
    vv_brick_source bs;
    vv_bricked_source(b, &bs);
    vv_object_source src;
    vv_object_source_init(&src, 0);
    src.bricks = &bs;
    vv_lod lod;
    frame_lod(r, &lod);
    double seconds = 0;
    if ((rc = draw_frames(r, ren, w, &src, 1, &ro, &lod, img, &seconds)))
        goto done;
    if (!r->quiet) {
        vv_bricked_stats st;
        vv_bricked_stats_get(b, &st);
        int nb[3];
        vv_bricked_grid(b, nb);
        printf("wrote %s (%dx%d, %.2f s; out of core: %llu of %d bricks read, %llu skipped, "
               "%.1f MiB read, peak cache %.1f MiB)\n",
               r->output, img->width, img->height, seconds, (unsigned long long)st.loads,
               nb[0] * nb[1] * nb[2], (unsigned long long)st.skipped,
               (double)st.bytes_read / 1048576.0, (double)st.peak_bytes / 1048576.0);
    }
    rc = CLI_EXIT_OK;
done:
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    vv_volume_free(proxy);
    vv_bricked_free(b);
    return rc;
}
