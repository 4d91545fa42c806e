/*
 * volvis filter IN OUT --FILTER ARG ...: the Filtering component
 * (include/volvis/filter.h) from the command line. The filters run in the
 * order given; the result is written atomically in any format that writes
 * (from OUT's extension, as volvis convert).
 */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "volvis/sys/format.h"

/* the filters' own options come from the library's table, after these */
static const cli_opt_spec base_opts[] = {
    {"format", 0, "NAME"},
    {"threads", 0, "N"},
    {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"},
    {"series", 0, "N"},
    {"channel", 0, "C"},
    {"time", 0, "T"},
    {"quiet", 'q', NULL},
};
#define N_BASE ((int)(sizeof base_opts / sizeof base_opts[0]))
#define MAX_SPECS 64

static int
build_specs(cli_opt_spec *specs) {
    int n = 0;
    for (int i = 0; i < N_BASE; i++)
        specs[n++] = base_opts[i];
    for (int i = 0; i < vv_filter_info_count() && n < MAX_SPECS; i++) {
        const vv_filter_info *f = vv_filter_info_get(i);
        specs[n].name = f->name;
        specs[n].short_name = 0;
        specs[n].metavar = f->metavar[0] ? f->metavar : NULL;
        n++;
    }
    return n;
}

void
cli_filter_usage(FILE *out) {
    fprintf(out, "usage: volvis filter [OPTIONS] IN OUT --FILTER ARG [--FILTER ARG ...]\n"
                 "\n"
                 "Filters a volume: smoothing, resampling, derivatives, segmentation. The\n"
                 "filters run in the order given on the command line; each reads the\n"
                 "previous one's output. OUT is written atomically in the format its\n"
                 "extension names, as 'volvis convert' writes it: NRRD, NIfTI, MetaImage,\n"
                 "VTK XML (.vti) keep the voxel type, spacing, origin and orientation; VTK\n"
                 "legacy drops the orientation and SLC (8-bit) rescales, each with a\n"
                 "warning. World units are the volume's (usually mm).\n"
                 "Results are identical for every thread count.\n"
                 "\n"
                 "Filters (output type after ->):\n");
    for (int i = 0; i < vv_filter_info_count(); i++) {
        const vv_filter_info *f = vv_filter_info_get(i);
        char head[64];
        snprintf(head, sizeof head, "--%s %s", f->name, f->metavar);
        fprintf(out, "  %s\n", head);
        /* the help line, wrapped at 78 columns under a 6-space indent */
        const char *p = f->help;
        while (*p) {
            int n = (int)strlen(p);
            if (n > 72) {
                n = 72;
                while (n > 0 && p[n] != ' ')
                    n--;
                if (n == 0)
                    n = 72;
            }
            fprintf(out, "      %.*s\n", n, p);
            p += n;
            while (*p == ' ')
                p++;
        }
    }
    fprintf(out,
            "\n"
            "Options:\n"
            "  --format NAME      output format: nrrd, slc, nifti, mhd, vtk or vti\n"
            "                     (default: from OUT's extension, as volvis convert)\n"
            "  --threads N        threads (default: all cores)\n"
            "  --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]\n"
            "                     read IN as raw voxels (see 'volvis info --help')\n"
            "  --series N         DICOM: series N; --channel C, --time T  the file's channel\n"
            "                     and time step (from 0)\n"
            "  -q, --quiet        no progress bar and no 'wrote' line\n"
            "  -h, --help         show this help\n"
            "\n"
            "Examples:\n"
            "  volvis filter ct_head.nrrd smooth.nrrd --gaussian 1.5 --median 1\n"
            "  volvis filter ct_head.nrrd iso.nrrd --resample 1x1x1:bspline\n"
            "  volvis filter ct_head.nrrd bone.nrrd --gaussian 1 --threshold 300: --largest 1\n"
            "  volvis filter ct_head.nrrd labels.nrrd --threshold otsu --components 26\n"
            "  volvis filter mra.nii.gz vessels.nrrd --vesselness 1,2,3\n");
}

int
cli_filter_main(int argc, char **argv) {
    cli_opt_spec specs[MAX_SPECS];
    int n_specs = build_specs(specs);
    cli_args a;
    int rc = cli_parse(&a, "filter", specs, n_specs, argc, argv);
    if (rc == CLI_HELP) {
        cli_filter_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos < 2)
        return cli_usage_error(&a, a.n_pos ? "missing OUT" : "missing IN and OUT");
    if (a.n_pos > 2)
        return cli_usage_error(&a, "expected IN and OUT, got %d arguments", a.n_pos);
    const char *in = a.pos[0], *out = a.pos[1];
    /* the format: --format NAME (one that writes), else OUT's extension:
     * the writers of the format table, as volvis convert */
    vv_format format;
    const char *s = cli_get(&a, "format");
    char names[128], exts[128];
    cli_writable_formats(names, sizeof names, ", ", 0);
    cli_writable_formats(exts, sizeof exts, "/", 1);
    if (s) {
        vv_error_clear();
        if (vv_format_parse(s, &format) != VV_OK || format == VV_FORMAT_AUTO ||
            !vv_format_record_of(format)->write)
            return cli_usage_error(&a, "--format: cannot write '%s' (%s)", s, names);
    } else if ((format = vv_format_from_extension(out)) == VV_FORMAT_UNKNOWN) {
        cli_writable_formats(names, sizeof names, "|", 0);
        return cli_usage_error(&a,
                               "cannot tell the output format from '%s'; use --format "
                               "%s or a %s extension",
                               out, names, exts);
    }
    int threads = 0, quiet = cli_count(&a, "quiet") > 0;
    if ((s = cli_get(&a, "threads")) && (rc = cli_parse_int(&a, "threads", s, 0, 4096, &threads)))
        return rc;
    vv_raw_params raw;
    const char *raw_spec = cli_get(&a, "raw");
    if (raw_spec && (rc = cli_parse_raw(&a, "raw", raw_spec, &raw)))
        return rc;
    int series = 0, channel = -1, time = -1;
    if ((rc = cli_parse_series_channel(&a, &series, &channel, &time)))
        return rc;

    /* the chain, in command-line order, checked before anything is read */
    vv_filter_chain *chain = NULL;
    if (vv_filter_chain_new(&chain) != VV_OK)
        return cli_fail(VV_ERR_NOMEM, NULL);
    for (int i = 0; i < a.n_seen; i++) {
        const cli_opt_spec *sp = &specs[a.seen[i].opt];
        if (a.seen[i].opt < N_BASE)
            continue;
        if (vv_filter_chain_add(chain, sp->name, a.seen[i].value) != VV_OK) {
            rc = cli_usage_error(&a, "%s", vv_error_message());
            vv_filter_chain_free(chain);
            return rc;
        }
    }
    if (vv_filter_chain_length(chain) == 0) {
        vv_filter_chain_free(chain);
        return cli_usage_error(&a, "no filter given (e.g. --gaussian 1.5; see --help)");
    }

    vv_volume *v = NULL, *f = NULL;
    if ((rc = cli_load_volume_sc(in, raw_spec ? &raw : NULL, series, channel, time, NULL, &v))) {
        vv_filter_chain_free(chain);
        return rc;
    }
    cli_progress pr;
    cli_progress_begin(&pr, quiet);
    vv_filter_options o;
    vv_filter_options_init(&o);
    o.threads = threads;
    o.progress = pr.p;
    vv_error_clear();
    vv_status st = vv_filter_chain_apply(chain, v, &o, &f);
    cli_progress_end(&pr);
    vv_volume_free(v);
    if (st != VV_OK) {
        rc = cli_fail(st, in);
        vv_filter_chain_free(chain);
        return rc;
    }
    const vv_format_record *rec = vv_format_record_of(format);
    char why[256];
    if (!quiet && rec->fits && !rec->fits(f, why, sizeof why))
        cli_error("warning: %s: %s", out, why);
    vv_error_clear();
    st = vv_volume_save(f, out, format, 0);
    if (st != VV_OK) {
        rc = cli_fail(st, out);
    } else {
        rc = CLI_EXIT_OK;
        if (!quiet)
            printf("wrote %s (%s, %d x %d x %d, %s, spacing %g x %g x %g) after %s\n", out,
                   vv_format_name(format), f->dims[0], f->dims[1], f->dims[2],
                   format == VV_FORMAT_SLC ? "u8" : vv_voxel_type_name(f->type), f->spacing[0],
                   f->spacing[1], f->spacing[2], vv_filter_chain_text(chain));
    }
    vv_volume_free(f);
    vv_filter_chain_free(chain);
    return rc;
}
