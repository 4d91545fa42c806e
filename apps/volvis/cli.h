/*
 * Shared pieces of the `volvis` command-line tool: the subcommand table, a
 * small long-option parser, number parsing with full validation, one-line
 * error reporting, volume loading (with --raw descriptions) and a progress
 * bar for terminals.
 *
 * Exit status: CLI_EXIT_OK (0) success, CLI_EXIT_FAIL (1) bad input (file,
 * format or render errors), CLI_EXIT_USAGE (2) bad usage (unknown option,
 * missing argument, unparsable number, unknown mode), CLI_EXIT_CANCEL (130)
 * interrupted with Ctrl-C.
 *
 * Output rules: stdout carries only the command's real output; every error is
 * ONE line on stderr, "volvis: <message>".
 */
#ifndef VOLVIS_CLI_H
#define VOLVIS_CLI_H

#include <stdint.h>
#include <stdio.h>

#include "volvis/volvis.h"

enum {
    CLI_EXIT_OK = 0,
    CLI_EXIT_FAIL = 1,
    CLI_EXIT_USAGE = 2,
    CLI_EXIT_CANCEL = 130,
    /** Returned by cli_parse when --help/-h was given: print usage, exit 0. */
    CLI_HELP = -1
};

/** One subcommand: argv[0] is the subcommand's name. */
typedef struct cli_command {
    const char *name;
    const char *summary; /**< one line for `volvis --help` */
    int (*run)(int argc, char **argv);
    void (*usage)(FILE *out);
} cli_command;

int cli_info_main(int argc, char **argv);
void cli_info_usage(FILE *out);
int cli_render_main(int argc, char **argv);
void cli_render_usage(FILE *out);
int cli_convert_main(int argc, char **argv);
void cli_convert_usage(FILE *out);
int cli_voxelize_main(int argc, char **argv);
void cli_voxelize_usage(FILE *out);
int cli_compress_main(int argc, char **argv);
void cli_compress_usage(FILE *out);
int cli_decompress_main(int argc, char **argv);
void cli_decompress_usage(FILE *out);
int cli_measure_main(int argc, char **argv);
void cli_measure_usage(FILE *out);
int cli_isosurface_main(int argc, char **argv);
void cli_isosurface_usage(FILE *out);
int cli_devices_main(int argc, char **argv);
void cli_devices_usage(FILE *out);
int cli_animate_main(int argc, char **argv);
void cli_animate_usage(FILE *out);
int cli_filter_main(int argc, char **argv);
void cli_filter_usage(FILE *out);
int cli_slice_main(int argc, char **argv);
void cli_slice_usage(FILE *out);
int cli_serve_main(int argc, char **argv);
void cli_serve_usage(FILE *out);

/* ---- option parsing ------------------------------------------------------ */

/** One accepted option. */
typedef struct cli_opt_spec {
    const char *name;    /**< long name without the leading "--" */
    char short_name;     /**< single-letter alias ('o' for -o), 0 for none */
    const char *metavar; /**< NULL: a flag without a value */
} cli_opt_spec;

#define CLI_MAX_ARGS 128

typedef struct cli_seen {
    int opt;           /**< index into specs */
    const char *value; /**< NULL for flags */
} cli_seen;

/** The result of parsing: positionals and every option occurrence in order. */
typedef struct cli_args {
    const char *cmd; /**< subcommand name, for messages */
    const cli_opt_spec *specs;
    int n_specs;
    int n_pos;
    const char *pos[CLI_MAX_ARGS];
    int n_seen;
    cli_seen seen[CLI_MAX_ARGS];
} cli_args;

/**
 * Parses argv[1..argc-1] against @p specs (n_specs entries). Accepts
 * "--name VALUE", "--name=VALUE", "-x VALUE", "-xVALUE", flags "--name" and
 * "-x", and "--" to end the options. --help and -h anywhere before "--"
 * return CLI_HELP. Returns 0, CLI_HELP, or CLI_EXIT_USAGE after printing one
 * error line.
 */
int cli_parse(cli_args *a, const char *cmd, const cli_opt_spec *specs, int n_specs, int argc,
              char **argv);

/** The value of the last occurrence of option @p name, or NULL. */
const char *cli_get(const cli_args *a, const char *name);

/** Number of occurrences of option @p name. */
int cli_count(const cli_args *a, const char *name);

/* ---- number parsing: each prints one error line and returns CLI_EXIT_USAGE on bad text ---- */

/** A finite double in [lo, hi]. */
int cli_parse_double(const cli_args *a, const char *opt, const char *text, double lo, double hi,
                     double *out);
/** An integer in [lo, hi]. */
int cli_parse_int(const cli_args *a, const char *opt, const char *text, long lo, long hi, int *out);
/** A size in bytes, with a K, M or G suffix (1024-based): "512M", "1.5G". */
int cli_parse_bytes(const cli_args *a, const char *opt, const char *text, uint64_t *out);
/** "WxH" with each side in 1..VV_IMAGE_MAX_SIDE. */
int cli_parse_size(const cli_args *a, const char *opt, const char *text, int *w, int *h);
/** "LO:HI", finite, LO < HI. */
int cli_parse_range(const cli_args *a, const char *opt, const char *text, double *lo, double *hi);
/**
 * A raw-volume description "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]" into
 * @p p (initialised here).
 */
int cli_parse_raw(const cli_args *a, const char *opt, const char *text, vv_raw_params *p);

/**
 * A point "X,Y,Z" (world) or "voxel:I,J,K" (voxel indices, fractional allowed; "world:"
 * may prefix a world point); *is_voxel says which.
 */
int cli_parse_point(const cli_args *a, const char *opt, const char *text, double out[3],
                    int *is_voxel);
/** A voxel box "I0,J0,K0:I1,J1,K1", inclusive (checked against a volume by the caller). */
int cli_parse_roi(const cli_args *a, const char *opt, const char *text, int lo[3], int hi[3]);
/** A cut plane "PX,PY,PZ:NX,NY,NZ" (world point and normal; the normal's side is kept). */
int cli_parse_plane(const cli_args *a, const char *opt, const char *text, vv_cut_plane *pl);

/** 1 when @p s ends with @p suffix, ignoring ASCII case (file extensions). */
int cli_ends_with(const char *s, const char *suffix);

/** Prints the volume formats (and with @p grids the grid formats) of the
 *  format tables, one entry each with what it reads and writes. */
void cli_print_formats(FILE *out, int grids);
/** The names (or with @p extensions the ".ext"s) of the formats that write,
 *  joined by @p sep, into @p buf. */
void cli_writable_formats(char *buf, size_t cap, const char *sep, int extensions);

/* ---- errors ---------------------------------------------------------------- */

/** Prints "volvis: <formatted>" as one line on stderr (newlines become "; "). */
void cli_error(const char *fmt, ...) VV_PRINTF(1, 2);
/** The last error line cli_error (or a usage error) wrote, without "volvis: ". */
const char *cli_last_error(void);
/** 1: error lines are kept for cli_last_error but not printed (MPI ranks > 0). */
void cli_errors_quiet(int quiet);

/** Prints a usage error "volvis: CMD: <formatted> (see 'volvis CMD --help')"; returns 2. */
int cli_usage_error(const cli_args *a, const char *fmt, ...) VV_PRINTF(2, 3);

/**
 * Reports a failed library call: prints vv_error_message() (prefixed with
 * @p path when the message does not name it; @p path may be NULL) and
 * returns CLI_EXIT_FAIL, or CLI_EXIT_CANCEL for VV_ERR_CANCELLED.
 */
int cli_fail(vv_status s, const char *path);

/* ---- rendering options shared by render and animate (render_setup.c) ---- */

/** The option specs of `volvis render`, for an initializer list. */
#define CLI_RENDER_OPT_SPECS                                                                       \
    {"output", 'o', "OUT"}, {"mode", 0, "composite|mip|minip|xray|iso|attenuated-mip"},            \
        {"iso", 0, "V"}, {"attenuation", 0, "A"}, {"tf", 0, "LO:HI"}, {"size", 0, "WxH"},          \
        {"azimuth", 0, "DEG"}, {"elevation", 0, "DEG"}, {"zoom", 0, "F"}, {"threads", 0, "N"},     \
        {"renderer", 0, "NAME"}, {"step", 0, "S"},                                                 \
        {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"}, {"gamma", 0, "G"},                   \
        {"quality", 0, "0|1|2"}, {"set", 0, "KEY=VALUE"}, {"alpha", 0, NULL}, {"ortho", 0, NULL},  \
        {"labels", 0, NULL}, {"field", 0, "NAME"}, {"time", 0, "T"}, {"series", 0, "N"},           \
        {"channel", 0, "C"}, {"channels", 0, "C,C,..."}, {"colors", 0, "COLOR,..."},               \
        {"blend", 0, "composite|additive|maximum"}, {"contrast", 0, "LO:HI,..."},                  \
        {"label-channels", 0, "C,C,..."}, {"compositing", 0, "binary-swap|radix-k[:K]"},           \
        {"memory-limit", 0, "BYTES[K|M|G]"}, {"level", 0, "L"}, {"lod", 0, "PIXELS"},              \
        {"progressive", 0, "CHUNKS"}, {                                                            \
        "quiet", 'q', NULL                                                                         \
    }

/** The rendering options as parsed (angles in degrees). */
typedef struct cli_render_args {
    const char *input, *output;
    const char *renderer; /**< --renderer, or NULL: the scene's, else raycast */
    int input_optional;   /**< set by the caller before cli_render_parse: INPUT may be absent */
    int has_mode;
    vv_render_mode mode;
    int has_iso;
    double iso;
    int has_tf;
    double tf_lo, tf_hi;
    int has_size, width, height;
    double azimuth, elevation, zoom; /**< degrees for the angles */
    int has_view;                    /**< azimuth, elevation or zoom given */
    int threads;
    int has_step;
    double step;
    int has_attenuation;
    double attenuation;
    int has_raw;
    vv_raw_params raw;
    int series;  /**< --series N (DICOM), 0: the only series */
    int channel; /**< --channel C (TIFF, DICOM), -1: channel 0 */
    /* --channels: the file's channels shown as one multi-channel object */
    int n_channels;                      /**< 0: not given */
    int channels[VV_MAX_CHANNELS];       /**< their indices in the file */
    int n_colors;                        /**< --colors given for the first n_colors */
    vv_vec3 colors[VV_MAX_CHANNELS];     /**< RGB in [0, 1] */
    int n_contrast;                      /**< --contrast given for the first n_contrast */
    double contrast[VV_MAX_CHANNELS][2]; /**< lower and upper limits, data values */
    int has_blend;                       /**< --blend given */
    int label_channel[VV_MAX_CHANNELS];  /**< --label-channels: 1 where channels[i] holds labels */
    int all_channels; /**< --colors, --contrast or --blend without --channels: every channel of
                           the file in order (their count known once it is open) */
    vv_channel_blend blend;
    double gamma;
    int has_quality, quality; /**< --quality given, and its value */
    const char *field;        /**< --field: a grid's field (NULL: the first scalar field) */
    int has_time, time;       /**< --time given, and a grid's or a volume file's time step */
    int time_range;           /**< 1: `render --time-range` (a volume file's steps) */
    int alpha, quiet, ortho;
    int labels; /**< --labels: volumes are label volumes (VV_SEG_LABELS) */
    /* under mpirun: --compositing (vv_parallel_options) */
    int compositing, radix;
    uint64_t memory_limit; /**< --memory-limit in bytes (0: not given): out of core */
    int has_level, level;  /**< --level: a multiresolution file's level (every node at it) */
    int has_lod;           /**< --lod given: a pyramid by level of detail */
    double lod;            /**< --lod: pixels a voxel may cover (default 1) */
    int progressive;       /**< --progressive CHUNKS: chunks read a step (0: not given) */
    /** Out, when not NULL: the channels of a volume file cli_render_world opened (1 for a
        scene, a grid or a file of one; `volvis serve` shows them all). */
    int *file_channels;
} cli_render_args;

/** Parses the shared options of @p a (one INPUT, -o); 0 or a usage error. */
/**
 * Under mpirun (vv_parallel_launched): `volvis render` of one frame over all
 * ranks (docs/parallel.md); rank 0 writes and prints. Returns the exit code,
 * the same on every rank.
 */
int cli_render_parallel(cli_args *a, cli_render_args *r);
/**
 * Under mpirun: `volvis animate` with every frame rendered over all ranks;
 * rank 0 runs vv_animation_render with @p o (writes, resumes), the others
 * render the frames it announces. *st: rank 0's status. Returns the exit
 * code, the same on every rank.
 */
int cli_animate_parallel(const cli_render_args *r, const vv_animation *anim, const vv_world *w,
                         vv_renderer *ren, vv_anim_render_options *o, vv_anim_render_stats *stats,
                         vv_status *st);
int cli_render_parse(cli_args *a, cli_render_args *r);
/** The level of detail of --lod, --level and --progressive (vv_render_options.lod). */
void cli_render_lod(const cli_render_args *r, vv_lod *lod);
/** 1 when a visible volume object of @p w shows a file out of core. */
int cli_world_out_of_core(const vv_world *w);
/**
 * The `wrote` line of a frame of @p w drawn out of core (what each object's
 * source read: bricks, or chunks by level, and the cache's peak), or the
 * plain one; @p lod what the frame used, @p scene 1 for a scene's World. Not printed
 * with -q.
 */
void cli_render_report(const cli_render_args *r, const vv_world *w, const vv_image *img,
                       double seconds, const vv_lod *lod, int scene);
/**
 * The World for r->input through the door (vv_world_open: a scene file, a
 * volume file, folder or store, a grid) with the overrides of the options
 * (mode, iso, tf, size, step, channels) but not yet turned: see
 * cli_render_turn. What the door found in *@p info (may be NULL); a switch
 * to out of core is said in one line unless -q. 0, CLI_EXIT_USAGE (options
 * that do not fit the input) or CLI_EXIT_FAIL after printing the error.
 */
int cli_render_world(const cli_render_args *r, vv_world **out, vv_world_open_info *info);
/**
 * Opens the time steps of r->input (or @p path when not NULL: a scene
 * object's geometry.source, read with neither @p r's series nor channel)
 * for volume object @p o (vv_time_steps_open with @p r's series, channel
 * and raw description; @p r may be NULL with a @p path).
 */
vv_status cli_time_steps_open(const cli_render_args *r, const char *path, const vv_object *o,
                              vv_time_steps **out);
/**
 * Time steps are drawn once each: gradients at the samples drawn cost less
 * than a gradient cache of every voxel of every step (docs/rendering.md,
 * "Time steps", has the figures). Sets
 * gradient_budget_mb=0 on @p ren unless a --set of @p a names it; a
 * renderer without the option is left as it is.
 */
void cli_time_steps_gradients(const cli_args *a, vv_renderer *ren);

/** The view turn of --azimuth, --elevation, --zoom (vv_anim_view_turn), then cli_render_ortho. */
void cli_render_turn(const cli_render_args *r, vv_world *w);
/** --ortho: parallel projection framed on the World (the height divided by --zoom). */
void cli_render_ortho(const cli_render_args *r, vv_world *w);
/**
 * Creates the renderer for @p w and sets its options: the World's render
 * settings (a scene's "render" section) give the defaults, the command line
 * overrides: --renderer replaces the scene's renderer (and, naming another
 * one, drops the scene's options, which belong to the other), --quality the
 * scene's quality, and every --set is applied after the scene's options.
 * *@p quality gets the quality to render at. 0 or an error exit status
 * after printing.
 */
int cli_render_renderer(const cli_args *a, const cli_render_args *r, const vv_world *w,
                        vv_renderer **out, int *quality);
/** The registered renderers' names, comma-separated, into @p buf; returns it. */
const char *cli_renderer_names(char *buf, size_t cap);
/** The object kinds in a vv_renderer_info.draws mask ("volume, plane"), into @p buf. */
const char *cli_renderer_kinds(unsigned draws, char *buf, size_t cap);
/** The modes in a vv_renderer_info.modes mask ("composite, mip"), into @p buf. */
const char *cli_renderer_modes(unsigned modes, char *buf, size_t cap);
/**
 * Prints on stderr which visible objects of @p w the renderer leaves out
 * (kinds it does not draw; vv_renderer_check_world), if any.
 */
void cli_render_note_left_out(const vv_renderer *ren, const vv_world *w);
/** `volvis renderers`: lists the renderers, their capabilities and options. */
int cli_renderers_main(int argc, char **argv);
void cli_renderers_usage(FILE *out);
/** The --help lines of the shared options (from --mode to --quiet). */
void cli_render_print_options(FILE *out);
/** The registry's renderers with their --set options, for --help. */
void cli_render_print_renderers(FILE *out);

/* ---- input ------------------------------------------------------------------ */

/**
 * Checks that @p path names a readable regular file; prints "volvis: PATH:
 * reason" and returns CLI_EXIT_FAIL otherwise, 0 when fine.
 */
int cli_check_readable(const char *path);
/** Like cli_check_readable, also accepting a readable folder (DICOM series, TIFF stacks). */
int cli_check_readable_input(const char *path);

/**
 * Parses --series N (1..), --channel C (0..) and --time T (0..) of @p a when
 * given into *@p series (else 0), *@p channel and *@p time (else -1). 0 or a
 * usage error.
 */
int cli_parse_series_channel(const cli_args *a, int *series, int *channel, int *time);

/**
 * Loads a volume: as raw when @p raw is non-NULL, else any detected format.
 * Returns 0, or CLI_EXIT_FAIL after printing the error.
 */
int cli_load_volume(const char *path, const vv_raw_params *raw, vv_volume **out);
/** cli_load_volume with a DICOM series (1.., 0: the only one), a channel and a time step
 * (-1: 0); the file's channels and time steps in *@p info when it is not NULL. */
int cli_load_volume_sc(const char *path, const vv_raw_params *raw, int series, int channel,
                       int time, vv_load_info *info, vv_volume **out);
/** OUT with _TNNNN before its .png (or at its end): T the tag ('t' time steps, 'p'
 *  progressive steps), NNNN @p n. */
void cli_numbered_path(const char *out, char tag, int n, char *buf, size_t cap);
/** cli_load_volume_sc of resolution level @p level (OME-Zarr multiscales; 0 the finest). */
int cli_load_volume_level(const char *path, const vv_raw_params *raw, int series, int channel,
                          int time, int level, vv_load_info *info, vv_volume **out);

/* ---- progress ----------------------------------------------------------------- */

/** Progress bar state; see cli_progress_begin. */
typedef struct cli_progress {
    int draw;      /**< 1 when a bar is drawn (stderr is a terminal and not quiet) */
    int last_pct;  /**< last percentage drawn, -1 at the start */
    int drawn;     /**< 1 once something was drawn */
    double start;  /**< cli_now() at cli_progress_begin, for the time-left estimate */
    int last_left; /**< seconds left last drawn, -1 none */
    vv_progress p; /**< pass this to the library */
} cli_progress;

/**
 * Prepares a progress bar on stderr when it is a terminal and @p quiet is 0,
 * and installs a SIGINT handler so Ctrl-C cancels the operation through the
 * callback (which is set either way).
 */
void cli_progress_begin(cli_progress *pr, int quiet);
/** Erases the bar and restores the SIGINT handler. */
void cli_progress_end(cli_progress *pr);
/** 1 after Ctrl-C was pressed during an operation. */
int cli_interrupted(void);

/** Monotonic wall-clock time in seconds. */
double cli_now(void);

#endif
