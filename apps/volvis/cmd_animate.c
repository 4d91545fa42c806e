/*
 * volvis animate [INPUT] -o OUT: the Animator's final render from the
 * command line (VolVis paper, section 4): transformation sequences (--orbit,
 * --rotate-object, --fly, --sweep-cut) and keyframed animation files
 * (--animation), to a PNG sequence, an MP4 or a WebM video. The rendering
 * options and the World are those of `volvis render` (render_setup.c).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const cli_opt_spec animate_opts[] = {
    CLI_RENDER_OPT_SPECS,
    {"orbit", 0, "DEG"},
    {"rotate-object", 0, "NAME:AXIS:DEG"},
    {"fly", 0, "X,Y,Z"},
    {"sweep-cut", 0, "AXIS|PX,PY,PZ:NX,NY,NZ:DIST"},
    {"animation", 0, "FILE.json"},
    {"frames", 0, "N"},
    {"fps", 0, "F"},
    {"crf", 0, "Q"},
    {"no-resume", 0, NULL},
    {"save-animation", 0, "FILE.json"},
};
#define N_ANIMATE_OPTS ((int)(sizeof animate_opts / sizeof animate_opts[0]))

void
cli_animate_usage(FILE *out) {
    fprintf(out,
            "usage: volvis animate [OPTIONS] INPUT (--orbit DEG | --rotate-object NAME:AXIS:DEG |\n"
            "                      --fly X,Y,Z | --sweep-cut SPEC)... [--frames N] -o OUT\n"
            "       volvis animate [OPTIONS] [INPUT] --animation FILE.json -o OUT\n"
            "\n"
            "Renders an animation of INPUT (a scene file or a volume file, as for 'volvis\n"
            "render') frame by frame with any renderer and writes a PNG sequence, an MP4\n"
            "(H.264) or a WebM (VP9) video. Frame k of N is drawn at time k / FPS; the\n"
            "sequences run over the whole animation, so frame k of '--orbit DEG --frames N'\n"
            "is exactly the still 'volvis render INPUT --azimuth A' with A = DEG * k / N\n"
            "(frame 0 is the plain still; a 360-degree orbit does not repeat its first\n"
            "frame). An --azimuth, --elevation or --zoom given here is the start view: the\n"
            "orbit's azimuth is added to this --azimuth (frame k is 'volvis render INPUT\n"
            "--azimuth (AZIMUTH + DEG * k / N) --elevation ... --zoom ...').\n"
            "\n"
            "The run shows a progress bar with the time left; Ctrl-C stops it. An\n"
            "interrupted run resumes when run again: PNG frames that exist and are\n"
            "complete are kept; a video keeps its finished frames in the folder\n"
            "OUT.frames/ beside it, encodes them at the end and then deletes the folder.\n"
            "A video file is written atomically, only when complete.\n"
            "\n"
            "Animation options:\n"
            "  -o, --output OUT  OUT.mp4 (H.264), OUT.webm (VP9), a PNG pattern with one\n"
            "                   integer conversion (frames/f_%%04d.png) or an existing folder\n"
            "                   (frames written as frame_0000.png, ...); required\n"
            "  --orbit DEG      orbit the camera about the view's up axis by DEG degrees\n"
            "  --rotate-object NAME:AXIS:DEG\n"
            "                   turn object NAME (a volume file's object is called\n"
            "                   'volume') by DEG degrees about AXIS (x, y, z or X,Y,Z)\n"
            "                   through the centre of its box\n"
            "  --fly X,Y,Z      move the camera (eye and look-at point) by X,Y,Z world units\n"
            "  --sweep-cut AXIS|PX,PY,PZ:NX,NY,NZ:DIST\n"
            "                   add a cut plane and move it: AXIS (x, y, z, -x, -y, -z)\n"
            "                   sweeps a plane facing +AXIS across the World's bounds; or a\n"
            "                   point, a normal and the distance to travel along it\n"
            "  --animation FILE.json  keyframes and sequences from an animation file\n"
            "                   (docs/animation-format.md); INPUT may then be left out when\n"
            "                   the file names its scene; the sequences above are added\n"
            "  --frames N       number of frames (default 60, or the file's duration * fps)\n"
            "  --fps F          frames per second (default 30, or the file's)\n"
            "  --crf Q          video quality, lower is better: H.264 0..51 (default 20),\n"
            "                   VP9 0..63 (default 31)\n"
            "  --no-resume      render every frame again, ignoring frames of an earlier run\n"
            "  --save-animation FILE.json  also write the animation as a file\n"
            "\n"
            "Rendering options (as 'volvis render'):\n");
    cli_render_print_options(out);
    fprintf(out, "  -h, --help       show this help\n"
                 "\n"
                 "Renderers:\n");
    cli_render_print_renderers(out);
    fprintf(out,
            "\n"
            "Examples:\n"
            "  volvis animate ../shared/data/volumes/ct_head.nrrd --tf 100:1500 --orbit 360 \\\n"
            "      --frames 120 -o head.mp4\n"
            "  volvis animate scene.json --rotate-object head:z:90 --frames 30 -o frames/\n"
            "  volvis animate head.nrrd --sweep-cut x --frames 48 --renderer raytrace -o cut.webm\n"
            "  volvis animate --animation examples/head_flight.json -o flight.mp4\n");
}

/* Splits "NAME:AXIS:DEG" from the right (a name may hold ':'). */
static int
parse_rotate(const cli_args *a, const char *text, vv_anim_sequence *q) {
    const char *c2 = strrchr(text, ':');
    const char *c1 = NULL;
    for (const char *p = text; c2 && p < c2; p++)
        if (*p == ':')
            c1 = p;
    if (!c1 || c1 == text || (size_t)(c1 - text) >= VV_NAME_MAX)
        return cli_usage_error(
            a, "--rotate-object: expected NAME:AXIS:DEG such as head:z:90, got '%s'", text);
    memcpy(q->object, text, (size_t)(c1 - text));
    q->object[c1 - text] = '\0';
    char axis[128];
    size_t al = (size_t)(c2 - c1 - 1);
    if (al == 0 || al >= sizeof axis)
        return cli_usage_error(a, "--rotate-object: bad axis in '%s'", text);
    memcpy(axis, c1 + 1, al);
    axis[al] = '\0';
    if (strcmp(axis, "x") == 0)
        q->axis = vv_vec3_make(1, 0, 0);
    else if (strcmp(axis, "y") == 0)
        q->axis = vv_vec3_make(0, 1, 0);
    else if (strcmp(axis, "z") == 0)
        q->axis = vv_vec3_make(0, 0, 1);
    else {
        double v[3];
        int vox;
        if (cli_parse_point(a, "rotate-object", axis, v, &vox) || vox)
            return CLI_EXIT_USAGE;
        q->axis = vv_vec3_make(v[0], v[1], v[2]);
        if (!(vv_vec3_length(q->axis) > 0))
            return cli_usage_error(a, "--rotate-object: the axis must be non-zero in '%s'", text);
    }
    return cli_parse_double(a, "rotate-object", c2 + 1, -1e6, 1e6, &q->degrees);
}

static int
parse_sweep(const cli_args *a, const char *text, const vv_world *w, vv_anim_sequence *q) {
    static const char *const axes[] = {"x", "y", "z", "-x", "-y", "-z"};
    for (int i = 0; i < 6; i++) {
        if (strcmp(text, axes[i]) != 0)
            continue;
        vv_box b = vv_world_bounds(w);
        double lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
        double c[3], n[3] = {0, 0, 0};
        int ax = i % 3, neg = i >= 3;
        for (int k = 0; k < 3; k++)
            c[k] = 0.5 * (lo[k] + hi[k]);
        c[ax] = neg ? hi[ax] : lo[ax];
        n[ax] = neg ? -1 : 1;
        q->point = vv_vec3_make(c[0], c[1], c[2]);
        q->normal = vv_vec3_make(n[0], n[1], n[2]);
        q->distance = hi[ax] - lo[ax];
        return 0;
    }
    const char *last = strrchr(text, ':');
    char plane[256];
    if (!last || (size_t)(last - text) >= sizeof plane)
        return cli_usage_error(a,
                               "--sweep-cut: expected AXIS (x, y, z, -x, -y, -z) or "
                               "PX,PY,PZ:NX,NY,NZ:DIST, got '%s'",
                               text);
    memcpy(plane, text, (size_t)(last - text));
    plane[last - text] = '\0';
    vv_cut_plane pl;
    int rc;
    if ((rc = cli_parse_plane(a, "sweep-cut", plane, &pl)) ||
        (rc = cli_parse_double(a, "sweep-cut", last + 1, -1e12, 1e12, &q->distance)))
        return rc;
    q->point = pl.point;
    q->normal = pl.normal;
    return 0;
}

/* The animation file's scene, relative to the file. */
static char *
scene_beside(const char *anim_path, const char *scene) {
    const char *slash = strrchr(anim_path, '/');
    size_t dl = (scene[0] == '/' || !slash) ? 0 : (size_t)(slash - anim_path + 1);
    char *p = malloc(dl + strlen(scene) + 1);
    if (p) {
        memcpy(p, anim_path, dl);
        strcpy(p + dl, scene);
    }
    return p;
}

/* The animation: --animation FILE (its scene the INPUT when none is given:
 * *@p scene_path, malloc'ed), --fps and --frames overriding it; else a new
 * one of @p frames at @p fps. Returns 0 or an exit status. */
static int
animation_from_args(cli_args *a, cli_render_args *r, const char *anim_file, double fps, int frames,
                    vv_animation **anim_out, char **scene_path) {
    vv_animation *anim = NULL;
    vv_status st;
    int rc;
    if (!anim_file) {
        if ((st = vv_animation_new(&anim)) != VV_OK)
            return cli_fail(st, NULL);
        anim->fps = fps;
        anim->duration = frames / fps;
        *anim_out = anim;
        return 0;
    }
    vv_error_clear();
    if ((rc = cli_check_readable(anim_file)))
        return rc;
    if ((st = vv_animation_load(&anim, anim_file)) != VV_OK)
        return cli_fail(st, anim_file);
    if (!r->input) {
        if (!anim->scene) {
            vv_animation_free(anim);
            return cli_usage_error(a, "missing INPUT: %s names no scene", anim_file);
        }
        if (!(*scene_path = scene_beside(anim_file, anim->scene))) {
            vv_animation_free(anim);
            cli_error("out of memory");
            return CLI_EXIT_FAIL;
        }
        r->input = *scene_path;
    }
    if (cli_get(a, "fps"))
        anim->fps = fps;
    if (cli_get(a, "frames"))
        anim->duration = frames / anim->fps;
    *anim_out = anim;
    return 0;
}

/* The sequences: the start view (render's turn as an orbit of @p orbit
 * degrees, so that frame k draws exactly what `volvis render --azimuth
 * (AZIMUTH + DEG k / N)` draws), then --rotate-object, --fly and
 * --sweep-cut in the order given. */
static int
add_sequences(cli_args *a, const cli_render_args *r, double orbit, vv_world *w,
              vv_animation *anim) {
    vv_anim_sequence q;
    memset(&q, 0, sizeof q);
    q.type = VV_SEQ_ORBIT;
    q.degrees = orbit;
    q.azimuth = r->azimuth;
    q.elevation = r->elevation;
    q.zoom = r->zoom;
    if (r->ortho) /* --ortho framed the view already; its height holds the zoom */
        q.zoom = 1;
    vv_error_clear();
    vv_status st;
    if ((st = vv_animation_add_sequence(anim, &q)) != VV_OK)
        return cli_fail(st, NULL);
    for (int i = 0; i < a->n_seen; i++) {
        const char *name = a->specs[a->seen[i].opt].name, *v = a->seen[i].value;
        int rc;
        memset(&q, 0, sizeof q);
        q.zoom = 1;
        if (strcmp(name, "rotate-object") == 0) {
            q.type = VV_SEQ_ROTATE_OBJECT;
            rc = parse_rotate(a, v, &q);
        } else if (strcmp(name, "fly") == 0) {
            double d[3];
            int vox;
            q.type = VV_SEQ_FLY;
            rc = cli_parse_point(a, "fly", v, d, &vox);
            if (!rc && vox)
                rc = cli_usage_error(a, "--fly: expected X,Y,Z in world units, got '%s'", v);
            q.offset = vv_vec3_make(d[0], d[1], d[2]);
        } else if (strcmp(name, "sweep-cut") == 0) {
            q.type = VV_SEQ_SWEEP_CUT;
            rc = parse_sweep(a, v, w, &q);
        } else {
            continue;
        }
        if (rc)
            return rc;
        vv_error_clear();
        if ((st = vv_animation_add_sequence(anim, &q)) != VV_OK)
            return cli_fail(st, NULL);
    }
    return 0;
}

/* An object's ".time" track: each frame's snapshot gets the step its
 * object's time asks for, read through a time series of the file the object
 * came from (INPUT, or a scene object's file). */
typedef struct time_frames {
    const cli_render_args *r;
    int volume_file;      /* INPUT is a volume file (else a scene: each object's own file) */
    const vv_world *base; /* the World the frames come from: the steps its objects hold */
    int n;                /* objects of base */
    int *opened;          /* per object: src[i] is open */
    vv_time_steps **src;  /* per object */
} time_frames;

static void
time_frames_close(time_frames *tf) {
    for (int i = 0; i < tf->n && tf->opened; i++)
        if (tf->opened[i])
            vv_time_steps_free(tf->src[i]);
    free(tf->opened);
    free(tf->src);
    tf->opened = NULL;
    tf->src = NULL;
}

static vv_status
prepare_time_step(void *user, int frame, vv_world *w) {
    (void)frame;
    time_frames *tf = user;
    for (int i = 0; i < w->n_objects && i < tf->n; i++) {
        vv_object *o = w->objects[i];
        if (o->type != VV_OBJECT_VOLUME || o->time == tf->base->objects[i]->time)
            continue;
        vv_status s;
        if (!tf->volume_file && !o->geometry.source)
            return vv_error_set(VV_ERR_INVALID,
                                "object '%s': a time track on a volume needs the volume read "
                                "from a file",
                                o->name);
        if (!tf->opened[i]) {
            s = tf->volume_file ? cli_time_steps_open(tf->r, NULL, o, &tf->src[i])
                                : cli_time_steps_open(NULL, o->geometry.source, o, &tf->src[i]);
            if (s != VV_OK)
                return vv_error_prefix(s, "object '%s'", o->name);
            tf->opened[i] = 1;
        }
        int next = o->time + 1 < vv_time_steps_count(tf->src[i]) ? o->time + 1 : -1;
        if ((s = vv_time_steps_show(tf->src[i], o, o->time, next)) != VV_OK)
            return vv_error_prefix(s, "object '%s': time %d", o->name, o->time);
    }
    return VV_OK;
}

/* 1 when a track of @p anim animates an object's time step. */
static int
has_time_track(const vv_animation *anim) {
    for (int i = 0; i < anim->n_tracks; i++) {
        const char *p = anim->tracks[i].property;
        size_t n = strlen(p);
        if (n > 5 && !strcmp(p + n - 5, ".time") && !strncmp(p, "objects", 7))
            return 1;
    }
    return 0;
}

/* Renders every frame (under mpirun through cli_animate_parallel) and
 * prints what was written. */
static int
render_frames(cli_args *a, const cli_render_args *r, vv_animation *anim, vv_world *w,
              vv_renderer *ren, int quality, int crf, int scene) {
    vv_anim_render_options o;
    vv_anim_render_options_init(&o);
    o.output = r->output;
    o.render.threads = r->threads;
    o.render.quality = quality;
    o.gamma = r->gamma;
    o.alpha = r->alpha;
    o.resume = cli_count(a, "no-resume") == 0;
    o.video.crf = crf;
    cli_progress pr;
    cli_progress_begin(&pr, r->quiet);
    o.progress = pr.p;
    vv_anim_render_stats stats;
    vv_status st;
    vv_error_clear();
    /* a volume file's time steps, when a track animates them (a grid's
     * time is its field NAME<T>, a scene's volumes have no file axes here) */
    time_frames tf = {.r = r, .base = w, .n = w->n_objects};
    tf.volume_file = r->input && !scene && w->n_objects > 0 &&
                     w->objects[0]->type == VV_OBJECT_VOLUME; /* the World of a volume file */
    if (has_time_track(anim)) {
        for (int i = 0; i < w->n_objects && tf.volume_file; i++)
            if (w->objects[i]->type == VV_OBJECT_VOLUME)
                w->objects[i]->time = r->has_time ? r->time : 0;
        tf.opened = calloc((size_t)(tf.n > 0 ? tf.n : 1), sizeof *tf.opened);
        tf.src = calloc((size_t)(tf.n > 0 ? tf.n : 1), sizeof *tf.src);
        if (!tf.opened || !tf.src) {
            time_frames_close(&tf);
            cli_progress_end(&pr);
            return cli_fail(vv_error_set(VV_ERR_NOMEM, "animate: out of memory"), r->input);
        }
        o.prepare_frame = prepare_time_step;
        o.prepare_frame_user = &tf;
        cli_time_steps_gradients(a, ren);
    }
    if (vv_parallel_launched()) {
        /* under mpirun: rank 0 runs the Animator, the others render with it */
        int mrank = 0, msize = 1;
        vv_parallel_init(NULL, NULL, &mrank, &msize);
        int rc = cli_animate_parallel(r, anim, w, ren, &o, &stats, &st);
        cli_progress_end(&pr);
        time_frames_close(&tf);
        if (rc || mrank != 0)
            return rc;
        if (!r->quiet)
            printf("wrote %s (%d frames at %g fps, %dx%d; %d rendered, %d reused; %.2f s on %d "
                   "rank%s)\n",
                   r->output, stats.frames, anim->fps, w->view.width, w->view.height,
                   stats.rendered, stats.reused, stats.total_s, msize, msize == 1 ? "" : "s");
        return CLI_EXIT_OK;
    }
    st = vv_animation_render(anim, w, ren, &o, &stats);
    cli_progress_end(&pr);
    time_frames_close(&tf);
    if (st == VV_ERR_CANCELLED) {
        cli_error("animate: interrupted after %d of %d frames; run the same command again to "
                  "resume",
                  stats.rendered + stats.reused, stats.frames);
        return CLI_EXIT_CANCEL;
    }
    if (st != VV_OK)
        return cli_fail(st, NULL);
    if (!r->quiet)
        printf("wrote %s (%d frames at %g fps, %dx%d; %d rendered, %d reused; %.2f s)\n", r->output,
               stats.frames, anim->fps, w->view.width, w->view.height, stats.rendered, stats.reused,
               stats.total_s);
    return CLI_EXIT_OK;
}

int
cli_animate_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "animate", animate_opts, N_ANIMATE_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_animate_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    const char *anim_file = cli_get(&a, "animation");
    cli_render_args r;
    memset(&r, 0, sizeof r);
    r.input_optional = anim_file != NULL;
    if ((rc = cli_render_parse(&a, &r)))
        return rc;
    const char *s;
    double orbit = 0, fps = 30;
    int frames = 60, crf = -1;
    int has_orbit = 0;
    if ((s = cli_get(&a, "orbit"))) {
        if ((rc = cli_parse_double(&a, "orbit", s, -1e6, 1e6, &orbit)))
            return rc;
        has_orbit = 1;
    }
    if ((s = cli_get(&a, "frames")) && (rc = cli_parse_int(&a, "frames", s, 1, 1000000, &frames)))
        return rc;
    if ((s = cli_get(&a, "fps")) && (rc = cli_parse_double(&a, "fps", s, 0.001, 1000, &fps)))
        return rc;
    if ((s = cli_get(&a, "crf")) && (rc = cli_parse_int(&a, "crf", s, 0, 63, &crf)))
        return rc;
    int n_seq = has_orbit + cli_count(&a, "rotate-object") + cli_count(&a, "fly") +
                cli_count(&a, "sweep-cut");
    if (!anim_file && n_seq == 0)
        return cli_usage_error(&a, "nothing to animate: give --orbit, --rotate-object, --fly, "
                                   "--sweep-cut or --animation");

    vv_animation *anim = NULL;
    vv_world *w = NULL;
    vv_renderer *ren = NULL;
    char *scene_path = NULL;
    vv_status st;
    if ((rc = animation_from_args(&a, &r, anim_file, fps, frames, &anim, &scene_path)))
        return rc;
    vv_world_open_info opened = {0};
    if ((rc = cli_render_world(&r, &w, &opened)))
        goto done;
    cli_render_ortho(&r, w);
    if ((rc = add_sequences(&a, &r, orbit, w, anim)))
        goto done;
    vv_error_clear();
    if ((st = vv_animation_validate(anim)) != VV_OK ||
        (st = vv_animation_check_world(anim, w)) != VV_OK) {
        rc = cli_fail(st, anim_file);
        goto done;
    }
    if ((s = cli_get(&a, "save-animation"))) {
        vv_error_clear();
        if ((st = vv_animation_save(anim, s)) != VV_OK) {
            rc = cli_fail(st, s);
            goto done;
        }
    }
    int quality = 2;
    if ((rc = cli_render_renderer(&a, &r, w, &ren, &quality)))
        goto done;
    if (r.threads > 0)
        vv_threads_set(r.threads);
    rc = render_frames(&a, &r, anim, w, ren, quality, crf, opened.input == VV_INPUT_SCENE);
done:
    vv_renderer_free(ren);
    vv_world_free(w);
    vv_animation_free(anim);
    free(scene_path);
    return rc;
}
