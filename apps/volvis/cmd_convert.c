/*
 * volvis convert IN OUT: any readable volume to any format that writes, atomically.
 */
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "volvis/sys/format.h"

static const cli_opt_spec convert_opts[] = {
    {"format", 0, "nrrd|slc|vvb"},
    {"no-coarse", 0, NULL},
    {"no-levels", 0, NULL},
    {"strict", 0, NULL},
    {"label", 0, NULL},
    {"nifti2", 0, NULL},
    {"no-compress", 0, NULL},
    {"codec", 0, "NAME"},
    {"bigtiff", 0, NULL},
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
                 "either; OME-Zarr (.ome.zarr, .zarr: a Zarr v2 folder with a pyramid of\n"
                 "2x2x2 means, labels by nearest, and each level's scale and translation;\n"
                 "read back at any level with --level) has none either; it is written\n"
                 "chunk by chunk, with memory bounded by a row of 64^3 chunks, when IN is raw,\n"
                 "an uncompressed NRRD or a pyramid (OME-Zarr, BigDataViewer, Imaris), and\n"
                 "by 64 slices when IN is a TIFF stack or a gzip or bzip2 NRRD (slab by slab);\n"
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
                 "slab of 66 slices at a time (a layer of bricks); other formats are read whole\n"
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
            "  --format %s|vvb  output format (default: from OUT's extension)\n"
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
            "                     multiscales, BigDataViewer, Imaris; from 0, the\n"
            "                     finest; default 0)\n"
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
                 "  volvis convert --raw 64x64x64:f32 field.raw field.nrrd\n"
                 "  volvis convert --raw 2048x2048x2048:u8 big.raw big.vvb\n");
}

/* IN (of format @p f, detected) as a vv_slabs when it reads slab by slab:
 * a TIFF stack (at @p channel and @p time), or a gzip or bzip2 NRRD of one 3-D
 * volume. *@p out stays NULL for other input (an NRRD neither raw nor gzip
 * among them: read whole). Errors: a TIFF stack's, for the caller to report. */
static vv_status
open_slabs(const char *in, vv_format f, int channel, int time, vv_slabs **out) {
    *out = NULL;
    if (f != VV_FORMAT_TIFF && (f != VV_FORMAT_NRRD || channel > 0 || time > 0))
        return VV_OK;
    vv_load_options lo;
    vv_load_options_init(&lo);
    lo.format = f;
    lo.channel = channel;
    lo.time = time;
    vv_error_clear();
    vv_status s = vv_slabs_open(out, in, &lo);
    if (s != VV_OK && f == VV_FORMAT_NRRD) {
        vv_error_clear();
        s = VV_OK;
    }
    return s;
}

/* IN to OUT.vvb (@p flags: VV_VVB_COARSE, VV_VVB_ZSTD, VV_VVB_LEVELS): by
 * bricks when IN is raw or uncompressed NRRD, slab by slab when it is a
 * TIFF stack or a gzip NRRD (vv_slabs), by boxes of level 0 when it is a
 * pyramid, else read whole first. */
static int
convert_vvb(const char *in, const char *out, const vv_raw_params *raw, int series, int channel,
            int time, unsigned flags, int quiet) {
    vv_bricked *b = NULL;
    vv_slabs *sl = NULL;
    vv_pyramid *p = NULL;
    vv_error_clear();
    vv_status s = VV_ERR_FORMAT;
    const vv_format f = raw ? VV_FORMAT_RAW : vv_format_detect(in);
    /* the header only: the writer takes each brick's range as it reads it (a
     * .vvb: its bricks one by one) */
    if ((raw || f == VV_FORMAT_NRRD || cli_ends_with(in, ".vvb")) && channel <= 0 && time <= 0)
        s = vv_bricked_open_header(&b, in, raw, 0);
    if (s != VV_OK && !raw) {
        const vv_status so = open_slabs(in, f, channel, time, &sl);
        if (so != VV_OK)
            return cli_fail(so, in);
        if (!sl && vv_pyramid_probe(in) &&
            (s = vv_pyramid_open(&p, in, channel, time, (uint64_t)256 << 20, NULL)) != VV_OK)
            return cli_fail(s, in);
    }
    int dims[3];
    const char *type;
    char slabs[64] = "";
    if (sl || p) { /* a box reader: slabs of slices, or level 0 of a pyramid */
        const vv_volume *hdr = sl ? vv_slabs_header(sl) : vv_pyramid_level(p, 0);
        cli_progress pr;
        cli_progress_begin(&pr, quiet);
        s = sl ? vv_boxes_write_vvb(hdr, vv_slabs_read_box, sl, out, flags, &pr.p)
               : vv_boxes_write_vvb(hdr, vv_pyramid_level0_box, p, out, flags, &pr.p);
        cli_progress_end(&pr);
        memcpy(dims, hdr->dims, sizeof dims);
        type = vv_voxel_type_name(hdr->type);
        if (sl)
            snprintf(slabs, sizeof slabs, ", from %llu slabs of slices",
                     (unsigned long long)vv_slabs_loads(sl));
        vv_slabs_free(sl);
        vv_pyramid_free(p);
        if (s != VV_OK)
            return cli_fail(s, out);
    } else if (s == VV_OK) {
        cli_progress pr;
        cli_progress_begin(&pr, quiet);
        s = vv_bricked_write_vvb(b, out, flags, &pr.p);
        cli_progress_end(&pr);
        memcpy(dims, vv_bricked_header(b)->dims, sizeof dims);
        type = vv_voxel_type_name(vv_bricked_header(b)->type);
        vv_bricked_free(b);
        if (s != VV_OK)
            return cli_fail(s, out);
    } else {
        /* not readable by bricks (compressed NRRD, other formats): whole */
        vv_volume *v = NULL;
        int rc = cli_load_volume_sc(in, raw, series, channel, time, NULL, &v);
        if (rc)
            return rc;
        vv_error_clear();
        s = vv_volume_write_vvb(v, out, flags);
        memcpy(dims, v->dims, sizeof dims);
        type = vv_voxel_type_name(v->type);
        vv_volume_free(v);
        if (s != VV_OK)
            return cli_fail(s, out);
    }
    if (!quiet) {
        char levels[64] = "";
        vv_bricked *w = NULL;
        if ((flags & VV_VVB_LEVELS) && vv_bricked_open_header(&w, out, NULL, 0) == VV_OK &&
            vv_bricked_levels(w) > 1)
            snprintf(levels, sizeof levels, ", %d pyramid levels", vv_bricked_levels(w));
        vv_bricked_free(w);
        vv_error_clear();
        printf("wrote %s (vvb, %d x %d x %d, %s, bricks of %d^3 cells%s%s%s)\n", out, dims[0],
               dims[1], dims[2], type, VV_BRICK_CELLS, flags & VV_VVB_ZSTD ? ", zstd" : "", levels,
               slabs);
    }
    return CLI_EXIT_OK;
}

/* IN to OUT.zarr chunk by chunk (vv_ome_zarr_write_boxes), never holding
 * IN whole: raw or uncompressed NRRD (read by rows, vv_bricked), TIFF
 * stacks and gzip NRRD (a slab of a row of chunks' slices at a time,
 * vv_slabs) and
 * pyramids (OME-Zarr, BigDataViewer, Imaris: level 0 through the chunk
 * cache). -1: IN is none of these (the caller reads it whole). */
static int
convert_zarr_boxes(const char *in, const char *out, const vv_raw_params *raw, int channel, int time,
                   const vv_save_options *so, int strict, int quiet) {
    vv_bricked *b = NULL;
    vv_pyramid *p = NULL;
    vv_slabs *sl = NULL;
    vv_error_clear();
    const vv_format f = raw ? VV_FORMAT_RAW : vv_format_detect(in);
    vv_status s = VV_ERR_FORMAT;
    if ((raw || f == VV_FORMAT_NRRD || cli_ends_with(in, ".vvb")) && channel <= 0 && time <= 0)
        s = vv_bricked_open_header(&b, in, raw, 0);
    vv_error_clear(); /* a bricked reader's refusal: a gzip NRRD reads by slabs */
    if (s != VV_OK && !raw) {
        if ((s = open_slabs(in, f, channel, time, &sl)) != VV_OK)
            return cli_fail(s, in);
        if (!sl && vv_pyramid_probe(in) &&
            (s = vv_pyramid_open(&p, in, channel, time, (uint64_t)256 << 20, NULL)) != VV_OK)
            return cli_fail(s, in);
    }
    if (!b && !sl && !p)
        return -1;
    const vv_volume *hdr = b    ? vv_bricked_header(b)
                           : sl ? vv_slabs_header(sl)
                                : vv_pyramid_level(p, 0);
    const vv_volume_format *rec = vv_volume_format_table(NULL)[VV_FORMAT_OME_ZARR - 1];
    char why[256];
    const int convert = rec->fits && !rec->fits(hdr, why, sizeof why);
    int rc = CLI_EXIT_OK;
    if (convert && strict) {
        cli_error("%s: %s; refusing to convert it (--strict)", out, why);
        rc = CLI_EXIT_FAIL;
    } else {
        s = b    ? vv_ome_zarr_write_boxes(hdr, vv_bricked_box, b, out, so)
            : sl ? vv_ome_zarr_write_boxes(hdr, vv_slabs_read_box, sl, out, so)
                 : vv_ome_zarr_write_boxes(hdr, vv_pyramid_level0_box, p, out, so);
        if (s != VV_OK)
            rc = cli_fail(s, out);
        else if (!quiet) {
            if (convert)
                cli_error("warning: %s: %s", out, why);
            char slabs[64] = "";
            if (sl)
                snprintf(slabs, sizeof slabs, " from %llu slabs of slices",
                         (unsigned long long)vv_slabs_loads(sl));
            printf("wrote %s (%s, %d x %d x %d, %s, chunk by chunk%s)\n", out,
                   vv_format_name(VV_FORMAT_OME_ZARR), hdr->dims[0], hdr->dims[1], hdr->dims[2],
                   vv_voxel_type_name(hdr->type), slabs);
        }
    }
    vv_bricked_free(b);
    vv_pyramid_free(p);
    vv_slabs_free(sl);
    return rc;
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

    /* the format: --format NAME (one that writes, or vvb), else OUT's extension;
     * VV_FORMAT_AUTO stands for .vvb below */
    vv_format format;
    const char *s = cli_get(&a, "format");
    char names[128], exts[128];
    cli_writable_formats(names, sizeof names, ", ", 0);
    cli_writable_formats(exts, sizeof exts, "/", 1);
    if (s) {
        vv_error_clear();
        if (strcmp(s, "vvb") == 0)
            format = VV_FORMAT_AUTO;
        else if (vv_format_parse(s, &format) != VV_OK || format == VV_FORMAT_AUTO ||
                 !vv_volume_format_table(NULL)[format - 1]->write)
            return cli_usage_error(&a, "--format: cannot write '%s' (%s or vvb)", s, names);
    } else if (cli_ends_with(out, ".vvb")) {
        format = VV_FORMAT_AUTO;
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
    if (format == VV_FORMAT_AUTO && level > 0)
        return cli_usage_error(&a, "--level: a .vvb is written from level 0");
    if (format == VV_FORMAT_AUTO) {
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
    vv_save_options so;
    vv_save_options_init(&so);
    so.format = format;
    so.strict = strict;
    so.label = cli_count(&a, "label") > 0;
    so.nifti_version = cli_count(&a, "nifti2") > 0 ? 2 : 0;
    if (cli_count(&a, "no-compress") > 0)
        so.compress = 0;
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
    const vv_volume_format *rec = vv_volume_format_table(NULL)[format - 1];
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
