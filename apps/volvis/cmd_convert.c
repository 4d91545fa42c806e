/*
 * volvis convert IN OUT: any readable volume to any format that writes, atomically.
 */
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "volvis/sys/format.h"

static const cli_opt_spec convert_opts[] = {
    {"format", 0, "nrrd|slc|..."},
    {"no-coarse", 0, NULL},
    {"no-levels", 0, NULL},
    {"strict", 0, NULL},
    {"label", 0, NULL},
    {"nifti2", 0, NULL},
    {"no-compress", 0, NULL},
    {"codec", 0, "NAME"},
    {"bigtiff", 0, NULL},
    {"ngff", 0, "0.4|0.5"},
    {"chunk", 0, "N|XxYxZ"},
    {"shard", 0, "N|XxYxZ"},
    {"compress", 0, "zstd|blosc|gzip|zlib|none"},
    {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"},
    {"series", 0, "N"},
    {"channel", 0, "C"},
    {"time", 0, "T"},
    {"level", 0, "L"},
    {"quiet", 'q', NULL},
};
#define N_CONVERT_OPTS ((int)(sizeof convert_opts / sizeof convert_opts[0]))

void
cli_convert_usage(FILE *out) {
    char names[128];
    cli_writable_formats(names, sizeof names, "|", 0);
    fprintf(out, "usage: volvis convert [OPTIONS] IN OUT\n"
                 "\n"
                 "Converts any readable volume (the formats below, or raw with --raw) to one\n"
                 "of the formats that write (below), chosen from OUT's extension or --format.\n"
                 "NRRD (.nrrd, .nhdr), NIfTI (.nii, .nii.gz), MetaImage (.mha, .mhd) and\n"
                 "VTK XML image data (.vti) keep the voxel type, spacing, origin and\n"
                 "direction (NIfTI in RAS, MetaImage in LPS: the frame is converted);\n"
                 "VTK legacy (.vtk) has no direction matrix: an oblique volume is written\n"
                 "axis-aligned, with a warning; TIFF (.tif, .tiff: one page per slice in\n"
                 "the voxel type, ImageJ's spacing, unit and origin; .ome.tif, .ome.tiff:\n"
                 "OME-XML with physical sizes and plane positions) has no direction matrix\n"
                 "either; OME-Zarr (.ome.zarr, .zarr: OME-NGFF 0.5, a Zarr v3 folder, or\n"
                 "with --ngff 0.4 a Zarr v2 folder, with a pyramid of 2x2x2 means, labels\n"
                 "by nearest, and each level's scale and translation; read back at any\n"
                 "level with --level) has none either; it is written chunk by chunk,\n"
                 "with memory bounded by a row of chunks (or shards), when IN is raw,\n"
                 "an uncompressed NRRD or a pyramid (OME-Zarr, N5, Neuroglancer precomputed,\n"
                 "BigDataViewer, Imaris; a TIFF whose 66 slices take over 512 MiB: tile by\n"
                 "tile), and by 64 slices when IN is another TIFF stack or a gzip or bzip2\n"
                 "NRRD (slab by slab);\n"
                 "SLC (.slc; VolVis's own 8-bit format)\n"
                 "holds 8-bit data only: other voxel types are rescaled from the value\n"
                 "range to 0..255, with a note on stderr. What a format cannot hold is\n"
                 "never changed silently (--strict: an error instead). The output is\n"
                 "written atomically: on failure an existing OUT is left untouched. Prints\n"
                 "what was written. No patient identifier of a DICOM series is written (a\n"
                 "volume keeps none).\n"
                 "\n"
                 "OUT.vvb is VolVis's bricked format for volumes larger than memory\n"
                 "(docs/file-formats.md; rendered with 'volvis render --memory-limit'):\n"
                 "raw input (--raw) and uncompressed NRRD are read a brick at a time by\n"
                 "pread, so memory stays bounded by a brick; TIFF stacks and gzip/bzip2 NRRD a\n"
                 "slab of 66 slices at a time (a layer of bricks; a TIFF of larger slices tile\n"
                 "by tile); other formats are read whole\n"
                 "first (a pyramid -- OME-Zarr, BigDataViewer, Imaris -- by boxes of its\n"
                 "level 0). Each brick is one zstd frame unless --no-compress, and gets a\n"
                 "coarse level (every 4th voxel) unless --no-coarse (zstd bricks always\n"
                 "keep it). After the bricks come the pyramid levels unless --no-levels:\n"
                 "each half the one before (2x2x2 means, OME-Zarr's levels) until it fits\n"
                 "one 64^3 chunk, written from the bricks read back, so memory stays\n"
                 "bounded; 'volvis render --lod' and the GUI read them.\n"
                 "\n");
    fprintf(out,
            "Options:\n"
            "  --format %s  output format (default: from OUT's extension)\n"
            "  --no-coarse        .vvb: no coarse level per brick\n"
            "  --no-levels        .vvb: no pyramid levels after the bricks\n"
            "  --strict           refuse what the format cannot hold as it is (SLC: a\n"
            "                     voxel type other than 8 bits; VTK legacy: a direction\n"
            "                     matrix) instead of converting it (exit 1)\n"
            "  --no-compress      NRRD, MetaImage, .vti, TIFF, OME-Zarr, .vvb: write the\n"
            "                     voxels uncompressed\n"
            "                     (NIfTI follows the name: .nii or .nii.gz)\n"
            "  --label            the voxels are labels (segment ids): NIfTI intent\n"
            "                     NIFTI_INTENT_LABEL, OME-Zarr levels by nearest (never\n"
            "                     averaged) and image-label; an integer voxel type is\n"
            "                     required\n"
            "  --nifti2           NIfTI-2 (default NIfTI-1, or NIfTI-2 when an axis is\n"
            "                     longer than 32767 voxels)\n"
            "  --codec NAME       TIFF: deflate (default), lzw, zstd, packbits or none\n"
            "  --bigtiff          TIFF: write BigTIFF (64-bit offsets) whatever the size\n"
            "                     (default: only when the voxels reach 3.75 GiB)\n"
            "  --ngff 0.4|0.5     OME-Zarr: OME-NGFF 0.5 (Zarr v3, zarr.json; default) or\n"
            "                     0.4 (Zarr v2, .zgroup/.zattrs/.zarray)\n"
            "  --chunk N|XxYxZ    OME-Zarr: the chunk shape in voxels, clipped to each\n"
            "                     level (default 64)\n"
            "  --shard N|XxYxZ    OME-Zarr 0.5: shards of this shape in voxels, a multiple\n"
            "                     of the chunk on each axis (sharding_indexed, the index\n"
            "                     at the end with its crc32c; default: not sharded)\n"
            "  --compress NAME    OME-Zarr: zstd (0.5's default), blosc (lz4, shuffle),\n"
            "                     gzip, none, or at 0.4 zlib (0.4's default)\n"
            "  --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]\n"
            "                     read IN as raw voxels (see 'volvis info --help')\n"
            "  --series N         DICOM: series N as 'volvis info' lists them\n"
            "  --channel C        channel C, from 0 (default 0): TIFF, DICOM, NIfTI (dim[5]),\n"
            "                     NRRD (an axis of kind RGB-color, vector, list, ...),\n"
            "                     VTK legacy (a component of SCALARS)\n"
            "  --time T           time step T, from 0 (default 0): OME-TIFF, ImageJ\n"
            "                     hyperstacks, NIfTI (dim[4]), NRRD (an axis of kind time),\n"
            "                     DICOM (images repeating at each position: cine, 4-D CT)\n"
            "  --level L          resolution level L of a multiresolution IN (OME-Zarr\n"
            "                     multiscales, N5, precomputed, BigDataViewer, Imaris,\n"
            "                     an OME-TIFF's SubIFD levels, reduced in z too; from\n"
            "                     0, the finest; default 0)\n"
            "  -q, --quiet        no 'wrote' line and no conversion note\n"
            "  -h, --help         show this help\n"
            "\n",
            names);
    cli_print_formats(out, 0);
    fprintf(out, "\n"
                 "Examples:\n"
                 "  volvis convert ../shared/data/volumes/nut.slc nut.nrrd\n"
                 "  volvis convert ../shared/data/volumes/ct_head.nrrd head.slc\n"
                 "  volvis convert ../shared/data/volumes/ct_head.nrrd head.nii.gz\n"
                 "  volvis convert ../shared/data/volumes/ct_head.nrrd head.vti\n"
                 "  volvis convert ../shared/data/volumes/ct_head.nrrd head.ome.tif\n"
                 "  volvis convert ../shared/data/volumes/ct_head.nrrd head.ome.zarr\n"
                 "  volvis convert --shard 256 ../shared/data/volumes/ct_head.nrrd head.ome.zarr\n"
                 "  volvis convert --ngff 0.4 ../shared/data/volumes/ct_head.nrrd head.ome.zarr\n"
                 "  volvis convert --raw 64x64x64:f32 field.raw field.nrrd\n"
                 "  volvis convert --raw 2048x2048x2048:u8 big.raw big.vvb\n");
}

/* IN read box by box: out of core (raw, uncompressed NRRD and .vvb by
 * bricks, a pyramid by level 0's chunks: vv_open), or slab by slab (TIFF
 * stacks, gzip and bzip2 NRRD: vv_slabs). */
typedef struct box_input {
    vv_opened od;
    vv_slabs *sl;
    const vv_volume *hdr; /* the volume's dims, type and geometry */
    vv_box_reader read;
    void *ctx;
} box_input;

static void
box_input_close(box_input *bi) {
    vv_opened_clear(&bi->od);
    vv_slabs_free(bi->sl);
    memset(bi, 0, sizeof *bi);
}

/* A slab of slices (vv_slabs: 64 slices and the 2 its bricks share) read
 * at once at most; a stack of larger slices is read by its store. */
#define CONVERT_SLAB_MAX ((uint64_t)512 << 20)

/* The bytes of a slab of 66 slices of volume @p h. */
static uint64_t
slab_bytes(const vv_volume *h) {
    return h ? (uint64_t)h->dims[0] * (uint64_t)h->dims[1] * 66u * vv_voxel_type_size(h->type) : 0;
}

/* Opens IN as a box reader when it can be one: 0 and bi->read set; -1 when
 * it reads whole only (the caller reads it so); else an exit code. */
static int
open_boxes(const char *in, const vv_raw_params *raw, int channel, int time, box_input *bi) {
    memset(bi, 0, sizeof *bi);
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    oo.header_only = 1; /* the writers take each box's range as they read it */
    oo.load.channel = channel;
    oo.load.time = time;
    if (raw) {
        oo.load.format = VV_FORMAT_RAW;
        oo.load.has_raw = 1;
        oo.load.raw = *raw;
    }
    vv_error_clear();
    vv_status s = vv_open(&bi->od, in, &oo);
    const vv_format_record *row = vv_format_record_of(bi->od.format);
    if (s == VV_OK && bi->od.kind == VV_DATA_VOLUME && row &&
        (row->flags & VV_FORMAT_FLAG_SLICES) && !raw &&
        slab_bytes(vv_source_level(bi->od.source, 0)) <= CONVERT_SLAB_MAX) {
        /* a stack whose slabs fit: slab by slab, each slice decoded once
         * (its store, tile by tile, would decode a strip once a chunk) */
        vv_opened_clear(&bi->od);
        s = VV_ERR_UNSUPPORTED;
    }
    if (s == VV_OK && bi->od.kind == VV_DATA_VOLUME) {
        bi->hdr = vv_source_level(bi->od.source, 0);
        bi->read = vv_source_box;
        bi->ctx = bi->od.source;
        return 0;
    }
    if (s != VV_OK && s != VV_ERR_UNSUPPORTED)
        return cli_fail(s, in);
    vv_opened_clear(&bi->od);
    if (raw)
        return -1;
    vv_load_options lo;
    vv_load_options_init(&lo);
    lo.channel = channel;
    lo.time = time;
    vv_error_clear();
    s = vv_slabs_open(&bi->sl, in, &lo);
    if (s == VV_ERR_UNSUPPORTED) { /* a format read whole only */
        vv_error_clear();
        return -1;
    }
    if (s != VV_OK)
        return cli_fail(s, in);
    bi->hdr = vv_slabs_header(bi->sl);
    bi->read = vv_slabs_read_box;
    bi->ctx = bi->sl;
    return 0;
}

/* IN to OUT.vvb (@p flags: VV_VVB_COARSE, VV_VVB_ZSTD, VV_VVB_LEVELS) box
 * by box when IN reads so (open_boxes), else read whole first. */
static int
convert_vvb(const char *in, const char *out, const vv_raw_params *raw, int series, int channel,
            int time, unsigned flags, int quiet) {
    box_input bi;
    int rc = open_boxes(in, raw, channel, time, &bi);
    if (rc > 0)
        return rc;
    vv_save_options so;
    vv_save_options_init(&so);
    so.format = VV_FORMAT_VVB;
    so.vvb_flags = flags;
    int dims[3];
    const char *type;
    char slabs[64] = "";
    vv_status s;
    if (rc == 0) {
        cli_progress pr;
        cli_progress_begin(&pr, quiet);
        so.progress = pr.p;
        s = vv_volume_save_boxes(bi.hdr, bi.read, bi.ctx, out, &so);
        cli_progress_end(&pr);
        memcpy(dims, bi.hdr->dims, sizeof dims);
        type = vv_voxel_type_name(bi.hdr->type);
        if (bi.sl)
            snprintf(slabs, sizeof slabs, ", from %llu slabs of slices",
                     (unsigned long long)vv_slabs_loads(bi.sl));
        box_input_close(&bi);
        if (s != VV_OK)
            return cli_fail(s, out);
    } else {
        /* not readable by boxes (compressed NRRD, other formats): whole */
        vv_volume *v = NULL;
        if ((rc = cli_load_volume_sc(in, raw, series, channel, time, NULL, &v)))
            return rc;
        vv_error_clear();
        s = vv_volume_save_with(v, out, &so);
        memcpy(dims, v->dims, sizeof dims);
        type = vv_voxel_type_name(v->type);
        vv_volume_free(v);
        if (s != VV_OK)
            return cli_fail(s, out);
    }
    if (!quiet) {
        char levels[64] = "";
        vv_open_options oo;
        vv_open_options_init(&oo);
        oo.mode = VV_OPEN_OUT_OF_CORE;
        oo.levels = 1;
        vv_opened w = {0};
        if ((flags & VV_VVB_LEVELS) && vv_open(&w, out, &oo) == VV_OK && w.info.n_levels > 1)
            snprintf(levels, sizeof levels, ", %d pyramid levels", w.info.n_levels);
        vv_opened_clear(&w);
        vv_error_clear();
        printf("wrote %s (vvb, %d x %d x %d, %s, bricks of %d^3 cells%s%s%s)\n", out, dims[0],
               dims[1], dims[2], type, VV_BRICK_CELLS, flags & VV_VVB_ZSTD ? ", zstd" : "", levels,
               slabs);
    }
    return CLI_EXIT_OK;
}

/* IN to OUT.zarr chunk by chunk (vv_volume_save_boxes), never holding IN
 * whole, when IN reads box by box (open_boxes). -1: it does not (the
 * caller reads it whole). */
static int
convert_zarr_boxes(const char *in, const char *out, const vv_raw_params *raw, int channel, int time,
                   const vv_save_options *so, int strict, int quiet) {
    box_input bi;
    int rc = open_boxes(in, raw, channel, time, &bi);
    if (rc < 0)
        return -1;
    if (rc)
        return rc;
    const vv_format_record *rec = vv_format_record_of(VV_FORMAT_OME_ZARR);
    char why[256];
    const int convert = rec->fits && !rec->fits(bi.hdr, why, sizeof why);
    if (convert && strict) {
        cli_error("%s: %s; refusing to convert it (--strict)", out, why);
        rc = CLI_EXIT_FAIL;
    } else {
        vv_save_options o = *so;
        o.format = VV_FORMAT_OME_ZARR;
        vv_status s = vv_volume_save_boxes(bi.hdr, bi.read, bi.ctx, out, &o);
        if (s != VV_OK)
            rc = cli_fail(s, out);
        else if (!quiet) {
            if (convert)
                cli_error("warning: %s: %s", out, why);
            char slabs[64] = "";
            if (bi.sl)
                snprintf(slabs, sizeof slabs, " from %llu slabs of slices",
                         (unsigned long long)vv_slabs_loads(bi.sl));
            printf("wrote %s (%s, %d x %d x %d, %s, chunk by chunk%s)\n", out,
                   vv_format_name(VV_FORMAT_OME_ZARR), bi.hdr->dims[0], bi.hdr->dims[1],
                   bi.hdr->dims[2], vv_voxel_type_name(bi.hdr->type), slabs);
        }
    }
    box_input_close(&bi);
    return rc;
}

/* --OPT N or XxYxZ (voxels, 1 .. 4096 each) into @p out; 0 or CLI_EXIT_USAGE. */
static int
parse_shape(const cli_args *a, const char *opt, const char *text, int out[3]) {
    char part[3][32];
    int n = 0;
    const char *p = text;
    for (;;) {
        const size_t len = strcspn(p, "x");
        if (n == 3 || len == 0 || len >= sizeof part[0])
            return cli_usage_error(a, "--%s: expected N or XxYxZ, got '%s'", opt, text);
        memcpy(part[n], p, len);
        part[n++][len] = '\0';
        if (!p[len])
            break;
        p += len + 1;
    }
    if (n == 2)
        return cli_usage_error(a, "--%s: expected N or XxYxZ, got '%s'", opt, text);
    for (int i = 0; i < n; i++) {
        int rc = cli_parse_int(a, opt, part[i], 1, 4096, &out[i]);
        if (rc)
            return rc;
    }
    if (n == 1)
        out[1] = out[2] = out[0];
    return 0;
}

/* The OME-Zarr options (--ngff, --chunk, --shard, --compress) into @p so;
 * 0 or CLI_EXIT_USAGE (one line). */
static int
parse_zarr_options(const cli_args *a, vv_format format, vv_save_options *so) {
    const char *ngff = cli_get(a, "ngff"), *chunk = cli_get(a, "chunk"),
               *shard = cli_get(a, "shard"), *comp = cli_get(a, "compress");
    if (format != VV_FORMAT_OME_ZARR) {
        if (ngff || chunk || shard || comp)
            return cli_usage_error(a, "--ngff, --chunk, --shard and --compress are for OME-Zarr "
                                      "output");
        return 0;
    }
    int rc;
    if (ngff) {
        if (!strcmp(ngff, "0.4"))
            so->ngff_version = 4;
        else if (!strcmp(ngff, "0.5"))
            so->ngff_version = 5;
        else
            return cli_usage_error(a, "--ngff: '%s' is not written (0.4 or 0.5)", ngff);
    }
    const int v3 = (so->ngff_version ? so->ngff_version : VV_OME_ZARR_DEFAULT_NGFF) == 5;
    if (chunk && (rc = parse_shape(a, "chunk", chunk, so->chunk)))
        return rc;
    if (shard) {
        if (!v3)
            return cli_usage_error(a, "--shard: sharding needs --ngff 0.5 (Zarr v3)");
        if ((rc = parse_shape(a, "shard", shard, so->shard)))
            return rc;
        for (int i = 0; i < 3; i++) {
            const int c = so->chunk[i] ? so->chunk[i] : 64;
            if (so->shard[i] % c)
                return cli_usage_error(a, "--shard: %d is not a multiple of the chunk's %d",
                                       so->shard[i], c);
        }
    }
    if (comp) {
        if (strcmp(comp, "zstd") && strcmp(comp, "blosc") && strcmp(comp, "gzip") &&
            strcmp(comp, "none") && (v3 || strcmp(comp, "zlib")))
            return cli_usage_error(
                a, "--compress: '%s' is not a codec of OME-Zarr %s (zstd, blosc, gzip%s or none)",
                comp, v3 ? "0.5" : "0.4", v3 ? "" : ", zlib");
        if (cli_count(a, "no-compress") > 0 && strcmp(comp, "none"))
            return cli_usage_error(a, "--compress %s and --no-compress", comp);
        so->codec = comp;
    }
    return 0;
}

int
cli_convert_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "convert", convert_opts, N_CONVERT_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_convert_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos < 2)
        return cli_usage_error(&a, a.n_pos ? "missing OUT" : "missing IN and OUT");
    if (a.n_pos > 2)
        return cli_usage_error(&a, "expected IN and OUT, got %d arguments", a.n_pos);
    const char *in = a.pos[0], *out = a.pos[1];

    /* the format: --format NAME (one that writes), else OUT's extension */
    vv_format format;
    const char *s = cli_get(&a, "format");
    char names[128], exts[128];
    cli_writable_formats(names, sizeof names, ", ", 0);
    cli_writable_formats(exts, sizeof exts, "/", 1);
    if (s) {
        vv_error_clear();
        if (vv_format_parse(s, &format) != VV_OK || format == VV_FORMAT_AUTO ||
            !vv_format_record_of(format)->write ||
            vv_format_record_of(format)->holds != VV_DATA_VOLUME)
            return cli_usage_error(&a, "--format: cannot write '%s' (%s)", s, names);
    } else if ((format = vv_format_from_extension(out)) == VV_FORMAT_UNKNOWN) {
        cli_writable_formats(names, sizeof names, "|", 0);
        return cli_usage_error(&a,
                               "cannot tell the output format from '%s'; use --format "
                               "%s or a %s extension",
                               out, names, exts);
    }
    int strict = cli_count(&a, "strict") > 0;
    int quiet = cli_count(&a, "quiet") > 0;
    if ((cli_get(&a, "codec") || cli_count(&a, "bigtiff") > 0) && format != VV_FORMAT_TIFF)
        return cli_usage_error(&a, "--codec and --bigtiff are for TIFF output");
    vv_raw_params raw;
    const char *raw_spec = cli_get(&a, "raw");
    if (raw_spec && (rc = cli_parse_raw(&a, "raw", raw_spec, &raw)))
        return rc;

    vv_volume *v;
    int series = 0, channel = -1, time = -1;
    if ((rc = cli_parse_series_channel(&a, &series, &channel, &time)))
        return rc;
    int level = 0;
    const char *ls = cli_get(&a, "level");
    if (ls && (rc = cli_parse_int(&a, "level", ls, 0, 64, &level)))
        return rc;
    vv_save_options so;
    vv_save_options_init(&so);
    if ((rc = parse_zarr_options(&a, format, &so)))
        return rc;
    if (format == VV_FORMAT_VVB && level > 0)
        return cli_usage_error(&a, "--level: a .vvb is written from level 0");
    if (format == VV_FORMAT_VVB) {
        const int zstd = cli_count(&a, "no-compress") == 0;
        if (zstd && cli_count(&a, "no-coarse") > 0 && !quiet)
            cli_error("note: %s: zstd bricks keep their coarse levels (--no-coarse takes effect "
                      "with --no-compress)",
                      out);
        const unsigned flags = (zstd ? VV_VVB_ZSTD : 0u) |
                               (cli_count(&a, "no-coarse") == 0 ? VV_VVB_COARSE : 0u) |
                               (cli_count(&a, "no-levels") == 0 ? VV_VVB_LEVELS : 0u);
        return convert_vvb(in, out, raw_spec ? &raw : NULL, series, channel, time, flags, quiet);
    }
    so.format = format;
    so.strict = strict;
    so.label = cli_count(&a, "label") > 0;
    so.nifti_version = cli_count(&a, "nifti2") > 0 ? 2 : 0;
    if (cli_count(&a, "no-compress") > 0)
        so.compress = 0;
    if (format == VV_FORMAT_TIFF)
        so.codec = cli_get(&a, "codec");
    so.bigtiff = cli_count(&a, "bigtiff") > 0;
    if (format == VV_FORMAT_OME_ZARR && level == 0 && series == 0 &&
        (rc = convert_zarr_boxes(in, out, raw_spec ? &raw : NULL, channel, time, &so, strict,
                                 quiet)) >= 0)
        return rc;
    if ((rc = cli_load_volume_level(in, raw_spec ? &raw : NULL, series, channel, time, level, NULL,
                                    &v)))
        return rc;
    /* what the format cannot hold as it is (SLC: 8 bits only) is refused with
     * --strict, else converted with a note */
    const vv_format_record *rec = vv_format_record_of(format);
    char why[256];
    const int convert = rec->fits && !rec->fits(v, why, sizeof why);
    if (convert && strict) {
        cli_error("%s: %s; refusing to convert it (--strict)", out, why);
        vv_volume_free(v);
        return CLI_EXIT_FAIL;
    }
    vv_error_clear();
    vv_status st = vv_volume_save_with(v, out, &so);
    if (st != VV_OK) {
        rc = cli_fail(st, out);
        vv_volume_free(v);
        return rc;
    }
    vv_volume *back = NULL;
    if (convert && !quiet && format == VV_FORMAT_SLC)
        cli_error("note: %s: %s: rescaled values %g..%g to fit", out, why, v->range[0],
                  v->range[1]);
    else if (convert && !quiet)
        cli_error("warning: %s: %s", out, why);
    if (!quiet) {
        /* the voxel type written: what the file holds now */
        vv_load_options lo;
        vv_load_options_init(&lo);
        lo.format = format;
        const char *type = vv_voxel_type_name(v->type);
        if (convert && vv_volume_load(&back, out, &lo) == VV_OK)
            type = vv_voxel_type_name(back->type);
        printf("wrote %s (%s, %d x %d x %d, %s)\n", out, vv_format_name(format), v->dims[0],
               v->dims[1], v->dims[2], type);
        vv_volume_free(back);
    }
    vv_volume_free(v);
    return CLI_EXIT_OK;
}
