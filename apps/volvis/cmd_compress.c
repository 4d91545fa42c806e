/*
 * volvis compress IN OUT.vvc (--quality Q | --rate BITS) and
 * volvis decompress IN.vvc OUT: the .vvc codec (include/volvis/compress.h,
 * docs/file-formats.md) from the command line.
 */
#include <math.h>
#include <string.h>
#include <strings.h>

#include "cli.h"

static const cli_opt_spec compress_opts[] = {
    {"quality", 0, "Q"},     {"rate", 0, "BITS"},
    {"max-error", 0, "E"},   {"format", 0, "1|2"},
    {"block", 0, "8|16|32"}, {"slope", 0, "S"},
    {"threads", 0, "N"},     {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"},
    {"check", 0, NULL},      {"quiet", 'q', NULL},
};
#define N_COMPRESS_OPTS ((int)(sizeof compress_opts / sizeof compress_opts[0]))

void
cli_compress_usage(FILE *out) {
    fprintf(out, "usage: volvis compress [OPTIONS] IN OUT.vvc (--quality Q | --rate BITS |\n"
                 "                                               --max-error E)\n"
                 "\n"
                 "Compresses any readable volume to a .vvc file: a discrete Fourier\n"
                 "transform per M^3 subcube, a frequency-dependent quantisation table,\n"
                 "rate-distortion optimised quantisation and context-modelled arithmetic\n"
                 "coding (format 2; format 1 is the baseline-JPEG-like Huffman coding of\n"
                 "earlier versions; docs/file-formats.md). The `fourier` renderer renders\n"
                 "straight from it (volvis render --renderer fourier --set vvc=OUT.vvc).\n"
                 "Prints the size, the compression ratio, the bits per voxel, the quality\n"
                 "used and the time; with --check also the PSNR (peak = value range) and\n"
                 "the maximum error of the decompressed volume. Written atomically.\n"
                 "\n"
                 "Options:\n"
                 "  --quality Q     quality factor 0..100 (100: finest, lossless for integer\n"
                 "                  data within 16 bits; each 6 points less halve the\n"
                 "                  precision)\n"
                 "  --rate BITS     target file size in bits per voxel (> 0): the quality\n"
                 "                  is searched so that the file is at most that\n"
                 "  --max-error E   every decoded voxel within E of the original (> 0, in\n"
                 "                  the volume's values; voxel corrections where the\n"
                 "                  transform coding alone is off by more)\n"
                 "  --format 1|2    file format version (default 2; 1: the legacy Huffman\n"
                 "                  coding, readable by older builds, no --max-error)\n"
                 "  --block M       subcube side 8, 16 or 32 (default 16)\n"
                 "  --slope S       frequency dependence of the quantisation table, >= 0\n"
                 "                  (default 0.5; 0: flat)\n"
                 "  --threads N     threads, 0 = all cores (default 0)\n"
                 "  --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]\n"
                 "                  read IN as raw voxels (see 'volvis info --help')\n"
                 "  --check         decompress again and print PSNR and maximum error\n"
                 "  -q, --quiet     no output lines\n"
                 "  -h, --help      show this help\n"
                 "\n"
                 "Examples:\n"
                 "  volvis compress ../shared/data/volumes/ct_head.nrrd head.vvc --rate 1 --check\n"
                 "  volvis compress ../shared/data/volumes/neghip.slc neghip.vvc --quality 80\n");
}

void
cli_decompress_usage(FILE *out) {
    fprintf(out, "usage: volvis decompress [OPTIONS] IN.vvc OUT\n"
                 "\n"
                 "Decompresses a .vvc file to NRRD (.nrrd, .nhdr) or SLC (.slc), restoring\n"
                 "the voxel type, dimensions, spacing, origin and direction. A corrupt or\n"
                 "truncated file is refused (exit 1). Written atomically.\n"
                 "\n"
                 "Options:\n"
                 "  --threads N     threads, 0 = all cores (default 0)\n"
                 "  -q, --quiet     no 'wrote' line\n"
                 "  -h, --help      show this help\n"
                 "\n"
                 "Example:\n"
                 "  volvis decompress head.vvc head.nrrd\n");
}

int
cli_compress_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "compress", compress_opts, N_COMPRESS_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_compress_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos < 2)
        return cli_usage_error(&a, a.n_pos ? "missing OUT.vvc" : "missing IN and OUT.vvc");
    if (a.n_pos > 2)
        return cli_usage_error(&a, "expected IN and OUT.vvc, got %d arguments", a.n_pos);
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    const char *q = cli_get(&a, "quality"), *r = cli_get(&a, "rate"),
               *me = cli_get(&a, "max-error"), *s;
    if ((q != NULL) + (r != NULL) + (me != NULL) != 1)
        return cli_usage_error(&a,
                               "give exactly one of --quality Q, --rate BITS and --max-error E");
    if (q && (rc = cli_parse_double(&a, "quality", q, 0, 100, &p.quality)))
        return rc;
    if (r) {
        if ((rc = cli_parse_double(&a, "rate", r, 1e-6, 64, &p.rate)))
            return rc;
        p.target = VV_VVC_RATE;
    }
    if (me) {
        if ((rc = cli_parse_double(&a, "max-error", me, 0, 1e300, &p.max_error)))
            return rc;
        if (!(p.max_error > 0))
            return cli_usage_error(&a, "--max-error: expected a bound > 0, got '%s'", me);
        p.target = VV_VVC_MAX_ERROR;
    }
    if ((s = cli_get(&a, "format"))) {
        if ((rc = cli_parse_int(&a, "format", s, 1, 2, &p.version)))
            return rc;
        if (p.version == 1 && me)
            return cli_usage_error(&a, "--max-error needs format 2");
    }
    if ((s = cli_get(&a, "block"))) {
        if ((rc = cli_parse_int(&a, "block", s, 8, 32, &p.block)))
            return rc;
        if (p.block != 8 && p.block != 16 && p.block != 32)
            return cli_usage_error(&a, "--block: expected 8, 16 or 32, got '%s'", s);
    }
    if ((s = cli_get(&a, "slope")) && (rc = cli_parse_double(&a, "slope", s, 0, 100, &p.slope)))
        return rc;
    if ((s = cli_get(&a, "threads")) && (rc = cli_parse_int(&a, "threads", s, 0, 4096, &p.threads)))
        return rc;
    vv_raw_params raw;
    const char *raw_spec = cli_get(&a, "raw");
    if (raw_spec && (rc = cli_parse_raw(&a, "raw", raw_spec, &raw)))
        return rc;
    const int quiet = cli_count(&a, "quiet") > 0, check = cli_count(&a, "check") > 0;
    const char *in = a.pos[0], *out = a.pos[1];

    vv_volume *v;
    if ((rc = cli_load_volume(in, raw_spec ? &raw : NULL, &v)))
        return rc;
    cli_progress pr;
    cli_progress_begin(&pr, quiet);
    p.progress = pr.p;
    vv_vvc *c = NULL;
    vv_error_clear();
    const double t0 = cli_now();
    vv_status st = vv_vvc_compress(&c, v, &p);
    const double t1 = cli_now();
    cli_progress_end(&pr);
    if (st != VV_OK) {
        vv_volume_free(v);
        return cli_fail(st, in);
    }
    if ((st = vv_vvc_save(c, out)) != VV_OK) {
        vv_vvc_free(c);
        vv_volume_free(v);
        return cli_fail(st, out);
    }
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    if (!quiet) {
        printf("wrote %s (%llu bytes, ratio %.1f:1, %.4g bits per voxel, quality %.2f, block "
               "%d, %.2f s)\n",
               out, (unsigned long long)info.file_bytes, info.ratio, info.bits_per_voxel,
               info.quality, info.block, t1 - t0);
        if (me)
            printf("error bound %g on every voxel (format %d)\n", info.max_error, info.version);
        if (r && info.bits_per_voxel > p.rate * 1.0001)
            printf("note: the rate of %g bits per voxel is out of reach; the smallest file "
                   "(quality 0) has %.4g\n",
                   p.rate, info.bits_per_voxel);
    }
    if (check) {
        vv_volume *d = NULL;
        if ((st = vv_vvc_decompress(&d, c, p.threads, NULL)) != VV_OK) {
            vv_vvc_free(c);
            vv_volume_free(v);
            return cli_fail(st, out);
        }
        double psnr, rmse, maxe;
        vv_volume_compare(v, d, &psnr, &rmse, &maxe);
        if (!quiet)
            printf("check: PSNR %.2f dB (peak = value range %g), RMSE %.4g, maximum error %g\n",
                   psnr, v->range[1] - v->range[0], rmse, maxe);
        vv_volume_free(d);
    }
    vv_vvc_free(c);
    vv_volume_free(v);
    return CLI_EXIT_OK;
}

static const cli_opt_spec decompress_opts[] = {
    {"threads", 0, "N"},
    {"quiet", 'q', NULL},
};
#define N_DECOMPRESS_OPTS ((int)(sizeof decompress_opts / sizeof decompress_opts[0]))

int
cli_decompress_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "decompress", decompress_opts, N_DECOMPRESS_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_decompress_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos < 2)
        return cli_usage_error(&a, a.n_pos ? "missing OUT" : "missing IN.vvc and OUT");
    if (a.n_pos > 2)
        return cli_usage_error(&a, "expected IN.vvc and OUT, got %d arguments", a.n_pos);
    const char *in = a.pos[0], *out = a.pos[1], *s;
    int threads = 0;
    if ((s = cli_get(&a, "threads")) && (rc = cli_parse_int(&a, "threads", s, 0, 4096, &threads)))
        return rc;
    vv_format format;
    if (cli_ends_with(out, ".slc"))
        format = VV_FORMAT_SLC;
    else if (cli_ends_with(out, ".nrrd") || cli_ends_with(out, ".nhdr"))
        format = VV_FORMAT_NRRD;
    else
        return cli_usage_error(&a, "cannot tell the output format from '%s'; use .nrrd or .slc",
                               out);
    const int quiet = cli_count(&a, "quiet") > 0;
    if ((rc = cli_check_readable(in)))
        return rc;
    vv_vvc *c = NULL;
    vv_error_clear();
    vv_status st = vv_vvc_load(&c, in);
    if (st != VV_OK)
        return cli_fail(st, in);
    vv_volume *v = NULL;
    cli_progress pr;
    cli_progress_begin(&pr, quiet);
    st = vv_vvc_decompress(&v, c, threads, &pr.p);
    cli_progress_end(&pr);
    vv_vvc_free(c);
    if (st != VV_OK)
        return cli_fail(st, in);
    if ((st = vv_volume_save(v, out, format, 0)) != VV_OK) {
        vv_volume_free(v);
        return cli_fail(st, out);
    }
    if (!quiet)
        printf("wrote %s (%s, %d x %d x %d, %s)\n", out, vv_format_name(format), v->dims[0],
               v->dims[1], v->dims[2],
               format == VV_FORMAT_SLC ? "u8" : vv_voxel_type_name(v->type));
    vv_volume_free(v);
    return CLI_EXIT_OK;
}
