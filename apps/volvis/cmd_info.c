/*
 * volvis info FILE: header, value statistics and a histogram summary.
 *
 * Statistics are computed here from the voxels in their native type, in
 * double: mean and standard deviation exactly, percentiles exactly for
 * integer volumes with at most 65 536 distinct values (one histogram bin per
 * value) and to 1/65536 of the range otherwise.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const cli_opt_spec info_opts[] = {
    {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"},
    {"bins", 0, "N"},
    {"series", 0, "N"},
    {"channel", 0, "C"},
    {"time", 0, "T"},
    {"show-phi", 0, NULL},
    {"stats", 0, NULL},
    {"level", 0, "L"},
};

/* The most bytes of voxels `info` reads for a pyramid's statistics without
 * --level (also at most a quarter of the memory budget): of a local file,
 * and of a store named by URL (fetched over the network). */
#define INFO_STATS_BYTES ((uint64_t)256 << 20)
#define INFO_STATS_BYTES_URL ((uint64_t)32 << 20)
#define N_INFO_OPTS ((int)(sizeof info_opts / sizeof info_opts[0]))

void
cli_info_usage(FILE *out) {
    fprintf(out, "usage: volvis info [OPTIONS] FILE|FOLDER\n"
                 "\n"
                 "Prints a volume's format, dimensions, voxel type, voxel spacing, origin,\n"
                 "direction (when not identity), unit, data origin, value range, mean,\n"
                 "percentiles (1/5/50/95/99) and a text histogram.\n"
                 "Formats: those listed below, raw (with --raw), and .vvc (compressed: its\n"
                 "header alone, with the subcube size, quality, compressed size, compression\n"
                 "ratio and bits per voxel; the volume is decoded for statistics only with\n"
                 "--stats).\n"
                 "For DICOM, first lists the series found (number, modality, description,\n"
                 "size, x T time steps for a cine or 4-D series, files); the volume\n"
                 "follows when there is one series or --series\n"
                 "picks one. Patient names and IDs are printed only with --show-phi.\n"
                 "For an irregular grid (the grid formats below): its kind, point and cell\n"
                 "counts by cell type, blocks or axes, bounds, and each field with its range\n"
                 "and missing values.\n"
                 "For a pyramid (OME-Zarr, N5, precomputed, BigDataViewer, Imaris, an\n"
                 "OME-TIFF with SubIFD levels, .vvb with levels):\n"
                 "each level's dimensions and spacing (see --level).\n"
                 "For OME-Zarr: an image's label images (labels/NAME: dimensions, type,\n"
                 "levels, colours; each opens as a label volume by its path); an HCS plate's\n"
                 "rows x columns, wells and fields per well, and the path that opens one\n"
                 "field (PLATE/A/1/0); a well's fields; a labels group's label images.\n"
                 "\n"
                 "Options:\n"
                 "  --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]\n"
                 "                  read FILE as raw voxels: dimensions, voxel type (u8 i8 u16\n"
                 "                  i16 u32 i32 f32 f64), byte order (default le), voxel\n"
                 "                  spacing (default 1x1x1) and header bytes to skip (default 0)\n"
                 "  --bins N        histogram bins, 1..256 (default 16)\n"
                 "  --series N      DICOM: describe series N as listed\n"
                 "  --channel C     channel C, from 0 (default 0): TIFF, DICOM, NIfTI (dim[5]),\n"
                 "                  NRRD (an axis of kind RGB-color, vector, list, ...),\n"
                 "                  VTK legacy (a component of SCALARS)\n"
                 "  --time T        time step T, from 0 (default 0): OME-TIFF, ImageJ\n"
                 "                  hyperstacks, NIfTI (dim[4]), NRRD (an axis of kind time),\n"
                 "                  DICOM (images repeating at each position: cine, 4-D CT)\n"
                 "  --show-phi      DICOM: also print the patient's name and ID and the\n"
                 "                  study (protected health information)\n"
                 "  --stats         .vvc: decode the volume and print its statistics\n"
                 "                  (within the memory budget, see 'volvis --help')\n"
                 "  --level L       a multiresolution file (OME-Zarr, N5, precomputed,\n"
                 "                  BigDataViewer, Imaris, OME-TIFF, .vvb): the statistics\n"
                 "                  of level L, read whole (0: the\n"
                 "                  finest). Without it, a pyramid's header and levels are\n"
                 "                  level 0's and its statistics those of the finest level\n"
                 "                  of at most 256 MiB (32 MiB by URL; and a quarter of the\n"
                 "                  memory budget), named in the output: a 2048^3 store\n"
                 "                  (local or by URL) is described without reading level 0\n"
                 "  -h, --help      show this help\n"
                 "\n"
                 "Example:\n"
                 "  volvis info ../shared/data/volumes/nut.slc\n"
                 "  volvis info --raw 256x256x128:u16:be:0.9x0.9x2 scan.raw\n"
                 "  volvis info --series 2 ~/scans/CT_folder\n"
                 "  volvis info plate.ome.zarr\n"
                 "\n");
    cli_print_formats(out, 1);
}

/* "name" #rrggbb of a channel, as far as the file says. */
static void
print_channel_label(const vv_load_info *in) {
    if (in->channel_name[0])
        printf(" \"%s\"", in->channel_name);
    if (in->has_color)
        printf(" #%02x%02x%02x", (unsigned)lround(in->color[0] * 255),
               (unsigned)lround(in->color[1] * 255), (unsigned)lround(in->color[2] * 255));
}

/* The channels (each with its name, colour and value range at this time
 * step; each read from the file) and the time axis of a file of several. */
static int
print_axes(const char *path, const vv_raw_params *raw, int series, int channel, int time,
           const vv_load_info *axes, const vv_volume *v) {
    int ch = channel < 0 ? 0 : channel, tp = time < 0 ? 0 : time;
    if (axes->n_channels > 1) {
        printf("channels:     %d (this is channel %d)\n", axes->n_channels, ch);
        int listed = axes->n_channels <= VV_MAX_CHANNELS ? axes->n_channels : 0;
        for (int c = 0; c < listed; c++) {
            vv_load_info in = *axes;
            vv_volume *cv = NULL;
            if (c != ch) {
                int rc = cli_load_volume_sc(path, raw, series, c, time, &in, &cv);
                if (rc)
                    return rc;
            }
            const vv_volume *w = c == ch ? v : cv;
            printf("  channel %-3d", c);
            print_channel_label(&in);
            printf(" range %g .. %g\n", w->range[0], w->range[1]);
            vv_volume_free(cv);
        }
    } else {
        printf("channels:     1");
        print_channel_label(axes);
        printf("\n");
    }
    if (axes->n_times > 1) {
        printf("time steps:   %d (this is step %d)", axes->n_times, tp);
        if (axes->time_step > 0)
            printf(", %g s apart", axes->time_step);
        printf("\n");
    }
    return 0;
}

/* Lists the DICOM series of @p path; *@p n_out gets their count. */
static int
list_dicom(const char *path, int show_phi, int *n_out) {
    vv_dicom_series *ser = NULL;
    int n = 0;
    vv_error_clear();
    vv_status s = vv_dicom_list(&ser, &n, path);
    if (s != VV_OK)
        return cli_fail(s, path);
    printf("dicom:        %d series in %s\n", n, path);
    for (int i = 0; i < n; i++) {
        const vv_dicom_series *d = &ser[i];
        printf("series %d:     #%d %s \"%s\" %d x %d x %d", i + 1, d->number,
               d->modality[0] ? d->modality : "?", d->description, d->dims[0], d->dims[1],
               d->dims[2]);
        if (d->time_steps > 1)
            printf(" x %d time steps", d->time_steps);
        printf(" (%d file%s)\n", d->n_files, d->n_files == 1 ? "" : "s");
        if (show_phi)
            printf("              patient \"%s\" id \"%s\" study \"%s\" %s\n", d->patient_name,
                   d->patient_id, d->study_description, d->study_date);
    }
    free(ser);
    *n_out = n;
    return 0;
}

/* An irregular grid: kind, counts of points and cells by type, bounds, fields. */
static int
info_grid(const char *path) {
    vv_grid *g = NULL;
    vv_error_clear();
    vv_status s = vv_grid_load(&g, path);
    if (s != VV_OK)
        return cli_fail(s, NULL);
    printf("file:        %s\n", path);
    printf("grid:        %s\n", vv_grid_kind_name(g->kind));
    printf("points:      %zu\n", g->n_points);
    printf("cells:       %zu\n", g->n_cells);
    static const int types[] = {VV_CELL_TETRA,   VV_CELL_HEXAHEDRON, VV_CELL_WEDGE,
                                VV_CELL_PYRAMID, VV_CELL_TRIANGLE,   VV_CELL_QUAD,
                                VV_CELL_POLYGON, VV_CELL_LINE,       VV_CELL_VERTEX};
    for (size_t t = 0; t < sizeof types / sizeof types[0]; t++) {
        size_t n = 0;
        for (size_t c = 0; c < g->n_cells; c++)
            n += g->cell_types[c] == types[t];
        if (n)
            printf("  %-11s %zu\n", vv_cell_type_name(types[t]), n);
    }
    for (int b = 0; b < g->n_blocks; b++)
        printf("block %d:     %d x %d x %d points\n", b, g->block_dims[b][0], g->block_dims[b][1],
               g->block_dims[b][2]);
    if (g->kind == VV_GRID_SPHERICAL) {
        static const char *ax[3] = {"r", "theta", "phi"};
        for (int a = 0; a < 3; a++)
            printf("axis %-6s  %d values, %g .. %g\n", ax[a], g->sph_dims[a], g->sph_axes[a][0],
                   g->sph_axes[a][g->sph_dims[a] - 1]);
    }
    vv_box b = vv_grid_bounds(g);
    printf("bounds:      [%g, %g] x [%g, %g] x [%g, %g]\n", b.min.x, b.max.x, b.min.y, b.max.y,
           b.min.z, b.max.z);
    printf("fields:      %d\n", g->n_fields);
    for (int i = 0; i < g->n_fields; i++) {
        const vv_grid_field *f = &g->fields[i];
        size_t missing = 0;
        for (size_t k = 0; k < f->n_tuples; k++)
            missing += vv_grid_field_missing(f, k);
        printf("  %-16s %s, %d component%s, range %g .. %g%s", f->name,
               f->cell_data ? "cell data" : "point data", f->n_components,
               f->n_components > 1 ? "s (range of the magnitude)" : "", f->range[0], f->range[1],
               missing ? "" : "\n");
        if (missing)
            printf(", %zu missing\n", missing);
    }
    vv_grid_free(g);
    return CLI_EXIT_OK;
}

static const char *
data_origin_name(vv_data_origin o) {
    switch (o) {
    case VV_ORIGIN_BIORAD_CONFOCAL:
        return "Bio-Rad confocal";
    case VV_ORIGIN_MRI:
        return "MRI";
    case VV_ORIGIN_CT:
        return "CT";
    case VV_ORIGIN_SIMULATION:
        return "simulation";
    case VV_ORIGIN_BINARY_VOXELIZED:
        return "binary voxelized";
    case VV_ORIGIN_FUZZY_VOXELIZED:
        return "fuzzy voxelized";
    case VV_ORIGIN_FUNCTION_VOXELIZED:
        return "function voxelized";
    default:
        return "other";
    }
}

static const char *
modification_name(vv_modification m) {
    switch (m) {
    case VV_MOD_ORIGINAL:
        return "original";
    case VV_MOD_RESAMPLED:
        return "resampled";
    case VV_MOD_RESAMPLED_FILTERED:
        return "resampled and filtered";
    case VV_MOD_FILTERED:
        return "filtered";
    default:
        return "other";
    }
}

static int
is_integer_type(vv_voxel_type t) {
    return t != VV_F32 && t != VV_F64;
}

typedef struct stats {
    uint64_t n;         /* finite voxels */
    uint64_t nonfinite; /* NaN and infinite voxels */
    double min, max, mean, stddev;
    double pct[5];
} stats;

static const double pct_q[5] = {0.01, 0.05, 0.50, 0.95, 0.99};

/* Fine histogram for percentiles: one bin per integer value when possible. */
static int
compute_stats(const vv_volume *v, stats *st) {
    uint64_t count = vv_volume_voxel_count(v);
    memset(st, 0, sizeof *st);
    st->min = INFINITY;
    st->max = -INFINITY;
    double sum = 0;
    for (uint64_t i = 0; i < count; i++) {
        double x = vv_voxel_value(v->type, v->data, (size_t)i);
        if (!isfinite(x)) {
            st->nonfinite++;
            continue;
        }
        st->n++;
        sum += x;
        if (x < st->min)
            st->min = x;
        if (x > st->max)
            st->max = x;
    }
    if (st->n == 0)
        return 0;
    st->mean = sum / (double)st->n;
    double ss = 0; /* second pass: numerically stable variance */
    for (uint64_t i = 0; i < count; i++) {
        double x = vv_voxel_value(v->type, v->data, (size_t)i);
        if (isfinite(x))
            ss += (x - st->mean) * (x - st->mean);
    }
    st->stddev = sqrt(ss / (double)st->n);

    double span = st->max - st->min;
    int exact = is_integer_type(v->type) && span < 65536;
    size_t nbins = exact ? (size_t)span + 1 : 65536;
    uint64_t *bins = calloc(nbins, sizeof *bins);
    if (!bins) {
        cli_error("out of memory computing the histogram");
        return CLI_EXIT_FAIL;
    }
    double scale = span > 0 ? (double)nbins / span : 0;
    for (uint64_t i = 0; i < count; i++) {
        double x = vv_voxel_value(v->type, v->data, (size_t)i);
        if (!isfinite(x))
            continue;
        size_t b = exact ? (size_t)(x - st->min) : (size_t)((x - st->min) * scale);
        if (b >= nbins)
            b = nbins - 1;
        bins[b]++;
    }
    for (int q = 0; q < 5; q++) {
        /* Smallest value with at least a fraction q of the voxels at or below it. */
        double target = pct_q[q] * (double)st->n;
        uint64_t cum = 0;
        size_t b = 0;
        for (; b < nbins; b++) {
            if ((double)(cum + bins[b]) >= target && bins[b] > 0)
                break;
            cum += bins[b];
        }
        if (b >= nbins)
            b = nbins - 1;
        if (exact) {
            st->pct[q] = st->min + (double)b;
        } else {
            double frac = bins[b] ? (target - (double)cum) / (double)bins[b] : 0;
            if (frac < 0)
                frac = 0;
            if (frac > 1)
                frac = 1;
            st->pct[q] = st->min + ((double)b + frac) / scale;
        }
    }
    free(bins);
    return 0;
}

static int
print_histogram(const vv_volume *v, const stats *st, int nbins) {
    double lo = st->min, hi = st->max;
    if (!(hi > lo)) {
        printf("histogram:    all %llu voxels are %g\n", (unsigned long long)st->n, lo);
        return 0;
    }
    /* Integer volumes with few distinct values: no more bins than values. */
    if (is_integer_type(v->type) && hi - lo + 1 < nbins)
        nbins = (int)(hi - lo + 1);
    uint64_t *bins = calloc((size_t)nbins, sizeof *bins);
    if (!bins) {
        cli_error("out of memory computing the histogram");
        return CLI_EXIT_FAIL;
    }
    /* Integer data: bin b holds [lo + b*w, lo + (b+1)*w) with w over the span + 1. */
    double width = is_integer_type(v->type) ? (hi - lo + 1) / nbins : (hi - lo) / nbins;
    uint64_t count = vv_volume_voxel_count(v), peak = 0;
    for (uint64_t i = 0; i < count; i++) {
        double x = vv_voxel_value(v->type, v->data, (size_t)i);
        if (!isfinite(x))
            continue;
        long b = (long)floor((x - lo) / width);
        if (b < 0)
            b = 0;
        if (b >= nbins)
            b = nbins - 1;
        bins[b]++;
    }
    for (int b = 0; b < nbins; b++)
        if (bins[b] > peak)
            peak = bins[b];
    printf("histogram:    %d bins over [%g, %g], bars on a log scale\n", nbins, lo, hi);
    const int bar_max = 40;
    for (int b = 0; b < nbins; b++) {
        double b0 = lo + b * width, b1 = lo + (b + 1) * width;
        int len = bins[b] ? (int)ceil(bar_max * log1p((double)bins[b]) / log1p((double)peak)) : 0;
        char bar[64];
        memset(bar, '#', (size_t)len);
        bar[len] = '\0';
        if (is_integer_type(v->type)) {
            b0 = ceil(b0);
            b1 = ceil(b1) - 1;
        }
        printf("  %12.6g .. %-12.6g %12llu %6.2f%% %s\n", b0, b1, (unsigned long long)bins[b],
               100.0 * (double)bins[b] / (double)st->n, bar);
    }
    free(bins);
    return 0;
}

static int
is_identity(const double d[9]) {
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            if (fabs(d[3 * r + c] - (r == c ? 1.0 : 0.0)) > 1e-12)
                return 0;
    return 1;
}

/* An OME-Zarr image's label images, one line each, and how to open one. */
static void
print_ome_zarr_labels(const char *path, const vv_ome_zarr_contents *c) {
    const char *sub = c->kind == VV_OME_ZARR_LABELS ? "" : "/labels";
    for (int i = 0; i < c->n_labels; i++) {
        const vv_ome_zarr_label *L = &c->labels[i];
        printf("%s %s: %d x %d x %d %s, %d level%s", i ? "             " : "label images:", L->name,
               L->dims[0], L->dims[1], L->dims[2], vv_voxel_type_name(L->type), L->n_levels,
               L->n_levels == 1 ? "" : "s");
        if (L->n_colors)
            printf(", %d colour%s", L->n_colors, L->n_colors == 1 ? "" : "s");
        printf("\n");
    }
    if (c->n_labels)
        printf("              (open one: volvis render %s%s/%s)\n", path, sub, c->labels[0].name);
}

/* An OME-Zarr plate, well or labels group: what it holds, which path opens an image. */
static void
print_ome_zarr_group(const char *path, const vv_ome_zarr_contents *c) {
    printf("file:         %s\n", path);
    printf("format:       %s\n", vv_format_name(VV_FORMAT_OME_ZARR));
    if (c->kind == VV_OME_ZARR_LABELS) {
        printf("group:        labels (%d label image%s)\n", c->n_labels,
               c->n_labels == 1 ? "" : "s");
        print_ome_zarr_labels(path, c);
        return;
    }
    if (c->kind == VV_OME_ZARR_PLATE) {
        printf("plate:        %s%s%s%d rows x %d columns, %d well%s", c->plate_name[0] ? "\"" : "",
               c->plate_name, c->plate_name[0] ? "\", " : "", c->n_rows, c->n_columns, c->n_wells,
               c->n_wells == 1 ? "" : "s");
        if (c->field_count)
            printf(", at most %d field%s per well", c->field_count, c->field_count == 1 ? "" : "s");
        if (c->n_acquisitions)
            printf(", %d acquisition%s", c->n_acquisitions, c->n_acquisitions == 1 ? "" : "s");
        printf("\n");
    } else {
        printf("well:         an HCS plate's well\n");
    }
    const char *first = NULL, *first_well = NULL;
    for (int i = 0; i < c->n_wells; i++) {
        const vv_ome_zarr_well *w = &c->wells[i];
        if (c->kind == VV_OME_ZARR_PLATE)
            printf("%s %s: %d field%s\n", i ? "             " : "wells:       ", w->path,
                   w->n_fields, w->n_fields == 1 ? "" : "s");
        else
            printf("fields:       %d\n", w->n_fields);
        if (!first && w->first_field[0]) {
            first = w->first_field;
            first_well = w->path;
        }
    }
    if (first)
        printf("open a field: volvis render %s/%s%s%s (each field is an image)\n", path, first_well,
               first_well[0] ? "/" : "", first);
}

/* Prints a .vvc's header (vv_vvc_get_info) without decoding the volume. */
static int
info_vvc_header(const char *path, const vv_vvc_info *vi) {
    const char *unit = vv_unit_name(vi->unit);
    printf("file:         %s\n", path);
    printf("format:       vvc\n");
    printf("dimensions:   %d x %d x %d (%llu voxels)\n", vi->dims[0], vi->dims[1], vi->dims[2],
           (unsigned long long)vi->dims[0] * (unsigned long long)vi->dims[1] *
               (unsigned long long)vi->dims[2]);
    printf("vvc:          version %d, subcubes %d^3 (%d x %d x %d), quality %.2f, slope %g\n",
           vi->version, vi->block, vi->subcubes[0], vi->subcubes[1], vi->subcubes[2], vi->quality,
           vi->slope);
    printf("compressed:   %llu bytes of %llu (ratio %.2f:1, %.4g bits per voxel)\n",
           (unsigned long long)vi->file_bytes, (unsigned long long)vi->raw_bytes, vi->ratio,
           vi->bits_per_voxel);
    if (vi->max_error > 0)
        printf("error bound:  %g on every voxel (corrections in steps of %g)\n", vi->max_error,
               vi->corr_step);
    printf("voxel type:   %s (%zu byte%s)\n", vv_voxel_type_name(vi->type),
           vv_voxel_type_size(vi->type), vv_voxel_type_size(vi->type) == 1 ? "" : "s");
    printf("spacing:      %g x %g x %g%s%s\n", vi->spacing[0], vi->spacing[1], vi->spacing[2],
           vi->unit == VV_UNIT_UNKNOWN ? "" : " ", vi->unit == VV_UNIT_UNKNOWN ? "" : unit);
    printf("origin:       %g %g %g\n", vi->origin[0], vi->origin[1], vi->origin[2]);
    if (!is_identity(vi->direction))
        printf("direction:    [%g %g %g; %g %g %g; %g %g %g] (columns: i, j, k axes)\n",
               vi->direction[0], vi->direction[1], vi->direction[2], vi->direction[3],
               vi->direction[4], vi->direction[5], vi->direction[6], vi->direction[7],
               vi->direction[8]);
    printf("unit:         %s\n", unit);
    printf("data origin:  %s\n", data_origin_name(vi->data_origin));
    printf("modification: %s\n", modification_name(vi->modification));
    printf("range:        %g .. %g (recorded by the encoder)\n", vi->range[0], vi->range[1]);
    printf("statistics:   not computed (header only; --stats decodes the volume)\n");
    return CLI_EXIT_OK;
}

/* A multiresolution file's levels (vv_open out of core by levels): a new
 * source in *src when @p path is a pyramid of several levels (NULL
 * otherwise: `info` reads it as before), and the level whose statistics
 * `info` prints: @p asked when >= 0, else the finest whose voxels take at
 * most INFO_STATS_BYTES and a quarter of the memory budget (the coarsest
 * when none does). */
static int
pyramid_levels(const char *path, int channel, int time, int asked, vv_source **src) {
    *src = NULL;
    vv_open_options o;
    vv_open_options_init(&o);
    o.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    o.levels = 1;
    o.header_only = 1; /* a raw or NRRD file: no pass over its voxels (one level anyway) */
    o.load.channel = channel;
    o.load.time = time;
    vv_opened op;
    vv_error_clear();
    if (vv_open(&op, path, &o) != VV_OK) {
        vv_error_clear(); /* not a pyramid, or broken: the whole read says why */
        return asked > 0 ? asked : 0;
    }
    vv_source *x = op.kind == VV_DATA_VOLUME && op.source ? vv_source_ref(op.source) : NULL;
    vv_opened_clear(&op);
    const int n = x ? vv_source_levels(x) : 0;
    if (n < 2) {
        vv_source_free(x);
        return asked > 0 ? asked : 0;
    }
    *src = x;
    if (asked >= 0)
        return asked;
    const uint64_t most = vv_path_is_url(path) ? INFO_STATS_BYTES_URL : INFO_STATS_BYTES;
    uint64_t cap = vv_memory_budget_get() / 4;
    cap = cap < most ? cap : most;
    for (int L = 0; L < n; L++) {
        const vv_volume *h = vv_source_level(x, L);
        const uint64_t bytes = (uint64_t)h->dims[0] * (uint64_t)h->dims[1] * (uint64_t)h->dims[2] *
                               vv_voxel_type_size(h->type);
        if (bytes <= cap)
            return L;
    }
    return n - 1;
}

/* A pyramid's levels, one line each. */
static void
print_levels(const vv_source *src, int stats_level) {
    const int n = vv_source_levels(src);
    printf("levels:       %d (a multiresolution pyramid: volvis render --lod, --level L)\n", n);
    for (int L = 0; L < n; L++) {
        const vv_volume *h = vv_source_level(src, L);
        printf("              level %d: %d x %d x %d, spacing %g x %g x %g%s\n", L, h->dims[0],
               h->dims[1], h->dims[2], h->spacing[0], h->spacing[1], h->spacing[2],
               L == stats_level ? " (the statistics below)" : "");
    }
}

int
cli_info_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "info", info_opts, N_INFO_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_info_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos == 0)
        return cli_usage_error(&a, "missing FILE");
    if (a.n_pos > 1)
        return cli_usage_error(&a, "expected one FILE, got %d arguments", a.n_pos);
    int nbins = 16;
    const char *s;
    if ((s = cli_get(&a, "bins")) && (rc = cli_parse_int(&a, "bins", s, 1, 256, &nbins)))
        return rc;
    vv_raw_params raw;
    const char *raw_spec = cli_get(&a, "raw");
    if (raw_spec && (rc = cli_parse_raw(&a, "raw", raw_spec, &raw)))
        return rc;
    int series = 0, channel = -1, time = -1, level = -1;
    if ((rc = cli_parse_series_channel(&a, &series, &channel, &time)))
        return rc;
    if ((s = cli_get(&a, "level")) && (rc = cli_parse_int(&a, "level", s, 0, 63, &level)))
        return rc;

    const char *path = a.pos[0];
    if (!raw_spec && (rc = cli_check_readable_input(path)))
        return rc;
    if (!raw_spec && vv_grid_file_detect(path, NULL))
        return info_grid(path);
    if (!raw_spec && vv_format_detect(path) == VV_FORMAT_DICOM) {
        int n_series = 0;
        if ((rc = list_dicom(path, cli_count(&a, "show-phi") > 0, &n_series)))
            return rc;
        if (n_series > 1 && series == 0)
            return CLI_EXIT_OK; /* the list is the answer; --series N for one */
        printf("\n");
    }
    /* an OME-Zarr group: a plate, a well or a labels group is listed (not
     * an image); an image's label images follow its statistics */
    vv_ome_zarr_contents zc;
    memset(&zc, 0, sizeof zc);
    if (!raw_spec && vv_format_detect(path) == VV_FORMAT_OME_ZARR) {
        vv_error_clear();
        vv_status zs = vv_ome_zarr_contents_get(path, &zc);
        if (zs != VV_OK)
            return cli_fail(zs, path);
        if (zc.kind != VV_OME_ZARR_IMAGE) {
            print_ome_zarr_group(path, &zc);
            vv_ome_zarr_contents_clear(&zc);
            return CLI_EXIT_OK;
        }
    }
    vv_volume *v;
    vv_vvc_info vinfo;
    vv_load_info axes = {.n_channels = 1, .n_times = 1};
    const int is_vvc = !raw_spec && vv_vvc_detect(path);
    if (is_vvc) {
        /* a .vvc: its header, then the statistics of the decompressed volume */
        vv_vvc *c = NULL;
        vv_error_clear();
        vv_status s2 = vv_vvc_load(&c, path);
        if (s2 == VV_OK) {
            vv_vvc_get_info(c, &vinfo);
            if (!cli_count(&a, "stats")) {
                /* the header only: a small file may decode to gigabytes */
                vv_vvc_free(c);
                return info_vvc_header(path, &vinfo);
            }
            s2 = vv_vvc_decompress(&v, c, 0, NULL);
        }
        vv_vvc_free(c);
        if (s2 != VV_OK)
            return cli_fail(s2, path);
    }
    /* a pyramid: level 0's header, the statistics of a level that fits */
    vv_source *pyr = NULL;
    int slevel = level > 0 ? level : 0;
    if (!is_vvc && !raw_spec)
        slevel = pyramid_levels(path, channel, time, level, &pyr);
    if (!is_vvc && (rc = cli_load_volume_level(path, raw_spec ? &raw : NULL, series, channel, time,
                                               slevel, &axes, &v))) {
        vv_ome_zarr_contents_clear(&zc);
        vv_source_free(pyr);
        return rc;
    }
    /* the header printed: level 0's (the levels' own in the list) */
    const vv_volume *hd = pyr && slevel > 0 ? vv_source_level(pyr, 0) : v;

    stats st;
    if ((rc = compute_stats(v, &st))) {
        vv_volume_free(v);
        vv_source_free(pyr);
        return rc;
    }
    const char *format = raw_spec ? "raw" : is_vvc ? "vvc" : vv_format_name(axes.format);
    uint64_t count = (uint64_t)hd->dims[0] * (uint64_t)hd->dims[1] * (uint64_t)hd->dims[2];
    const char *unit = vv_unit_name(hd->unit);
    printf("file:         %s\n", path);
    printf("format:       %s\n", format);
    printf("dimensions:   %d x %d x %d (%llu voxels)\n", hd->dims[0], hd->dims[1], hd->dims[2],
           (unsigned long long)count);
    if (is_vvc) {
        printf("vvc:          version %d, subcubes %d^3 (%d x %d x %d), quality %.2f, slope %g\n",
               vinfo.version, vinfo.block, vinfo.subcubes[0], vinfo.subcubes[1], vinfo.subcubes[2],
               vinfo.quality, vinfo.slope);
        printf("compressed:   %llu bytes of %llu (ratio %.2f:1, %.4g bits per voxel)\n",
               (unsigned long long)vinfo.file_bytes, (unsigned long long)vinfo.raw_bytes,
               vinfo.ratio, vinfo.bits_per_voxel);
        if (vinfo.max_error > 0)
            printf("error bound:  %g on every voxel (corrections in steps of %g)\n",
                   vinfo.max_error, vinfo.corr_step);
    }
    if (pyr)
        print_levels(pyr, slevel);
    else if (axes.n_levels > 1)
        printf("levels:       %d (a multiresolution pyramid: volvis render --lod, --level L)\n",
               axes.n_levels);
    if (axes.n_channels > 1 || axes.n_times > 1) {
        rc = print_axes(path, raw_spec ? &raw : NULL, series, channel, time, &axes, v);
        if (rc) {
            vv_volume_free(v);
            vv_source_free(pyr);
            return rc;
        }
    }
    printf("voxel type:   %s (%zu byte%s)\n", vv_voxel_type_name(v->type),
           vv_voxel_type_size(v->type), vv_voxel_type_size(v->type) == 1 ? "" : "s");
    if (zc.is_label || axes.is_label)
        printf("labels:       a label image (OME-Zarr image-label, a precomputed segmentation): "
               "rendered as a label volume\n");
    print_ome_zarr_labels(path, &zc);
    vv_ome_zarr_contents_clear(&zc);
    printf("spacing:      %g x %g x %g%s%s\n", hd->spacing[0], hd->spacing[1], hd->spacing[2],
           hd->unit == VV_UNIT_UNKNOWN ? "" : " ", hd->unit == VV_UNIT_UNKNOWN ? "" : unit);
    printf("origin:       %g %g %g\n", hd->origin[0], hd->origin[1], hd->origin[2]);
    if (!is_identity(hd->direction))
        printf("direction:    [%g %g %g; %g %g %g; %g %g %g] (columns: i, j, k axes)\n",
               hd->direction[0], hd->direction[1], hd->direction[2], hd->direction[3],
               hd->direction[4], hd->direction[5], hd->direction[6], hd->direction[7],
               hd->direction[8]);
    vv_box box = vv_volume_world_box(hd);
    printf("extent:       %g x %g x %g%s%s\n", box.max.x - box.min.x, box.max.y - box.min.y,
           box.max.z - box.min.z, hd->unit == VV_UNIT_UNKNOWN ? " (world units)" : " ",
           hd->unit == VV_UNIT_UNKNOWN ? "" : unit);
    printf("unit:         %s\n", unit);
    printf("data origin:  %s\n", data_origin_name(v->data_origin));
    printf("modification: %s\n", modification_name(v->modification));
    if (pyr && slevel > 0)
        printf("statistics:   of level %d (%d x %d x %d)%s\n", slevel, v->dims[0], v->dims[1],
               v->dims[2],
               level >= 0 ? ""
               : vv_path_is_url(path)
                   ? ": level 0 is more than info reads by URL (32 MiB, or a quarter of the "
                     "memory budget); --level 0 reads it whole"
                   : ": level 0 is more than info reads (256 MiB, or a quarter of the memory "
                     "budget); --level 0 reads it whole");
    vv_source_free(pyr);
    if (st.n == 0) {
        printf("range:        none (no finite voxels)\n");
    } else {
        printf("range:        %g .. %g\n", st.min, st.max);
        printf("mean:         %g (standard deviation %g)\n", st.mean, st.stddev);
        if (st.nonfinite)
            printf("non-finite:   %llu voxels (NaN or infinite; left out of the statistics)\n",
                   (unsigned long long)st.nonfinite);
        printf("percentiles:  1%%: %g  5%%: %g  50%%: %g  95%%: %g  99%%: %g\n", st.pct[0],
               st.pct[1], st.pct[2], st.pct[3], st.pct[4]);
        rc = print_histogram(v, &st, nbins);
    }
    vv_volume_free(v);
    return rc;
}
