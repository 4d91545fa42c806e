/*
 * volvis voxelize SCENE_OR_MESH -o OUT.(nrrd|slc): volume-samples a
 * geometric model (the geometry objects of a scene file, or a triangle mesh
 * file) into a volume (Modeling, include/volvis/modeling.h).
 */
#include <string.h>
#include <strings.h>

#include "cli.h"

static const cli_opt_spec voxelize_opts[] = {
    {"output", 'o', "OUT"}, {"size", 0, "N"},
    {"spacing", 0, "S"},    {"filter", 0, "box|tent|gauss"},
    {"radius", 0, "R"},     {"margin", 0, "M"},
    {"type", 0, "u8|f32"},  {"mesh-mode", 0, "auto|solid|shell"},
    {"thickness", 0, "T"},  {"threads", 0, "N"},
    {"quiet", 'q', NULL},
};
#define N_VOXELIZE_OPTS ((int)(sizeof voxelize_opts / sizeof voxelize_opts[0]))

void
cli_voxelize_usage(FILE *out) {
    fprintf(
        out,
        "usage: volvis voxelize [OPTIONS] SCENE_OR_MESH -o OUT.(nrrd|slc)\n"
        "\n"
        "Volume-samples a geometric model into a volume (Wang and Kaufman's volume\n"
        "sampling: each voxel's density is a filter weight of its distance to the\n"
        "surface, 1 inside, 0 outside, 0.5 on the surface; CSG on the densities).\n"
        "The input is a scene file (.json), whose objects of type \"geometry\" are\n"
        "placed by their transforms and united, or a triangle mesh (OBJ, PLY, STL,\n"
        "OFF, anything Assimp reads): a closed mesh, or one with a few small holes,\n"
        "becomes a solid (by the generalized winding number), a more open one a thin\n"
        "shell. The grid covers the model's bounding box plus a margin. For a\n"
        "scene, the first geometry object's resolution, filter, etc. are the\n"
        "defaults; the options below override them. u8 output holds 255 * density\n"
        "(the surface is at 127.5), f32 the density. Written atomically; prints what\n"
        "was written and the time taken.\n"
        "\n"
        "Options:\n"
        "  -o, --output OUT    output volume, .nrrd (or .nhdr) or .slc (required)\n"
        "  --size N            voxels along the longest axis (default 128)\n"
        "  --spacing S         isotropic voxel spacing in world units (instead of --size)\n"
        "  --filter F          box, tent (default) or gauss\n"
        "  --radius R          filter radius in voxels, 0.25..16 (default 1.5)\n"
        "  --margin M          empty voxels around the model (default radius + 1)\n"
        "  --type u8|f32       voxel type (default u8; SLC holds u8 only)\n"
        "  --mesh-mode MODE    meshes: auto (default: solid when closed or nearly), solid, shell\n"
        "  --thickness T       shell thickness in world units (default two voxels)\n"
        "  --threads N         worker threads (default: all cores)\n"
        "  -q, --quiet         no progress bar and no 'wrote' line\n"
        "  -h, --help          show this help\n"
        "\n"
        "Examples:\n"
        "  volvis voxelize examples/nut_bolt.json -o nut_bolt.nrrd --size 256\n"
        "  volvis voxelize ../shared/data/meshes/knot1.off -o knot.slc --filter gauss\n");
}

int
cli_voxelize_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "voxelize", voxelize_opts, N_VOXELIZE_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_voxelize_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos < 1)
        return cli_usage_error(&a, "missing SCENE_OR_MESH");
    if (a.n_pos > 1)
        return cli_usage_error(&a, "expected one input, got %d arguments", a.n_pos);
    const char *in = a.pos[0], *out = cli_get(&a, "output");
    if (!out)
        return cli_usage_error(&a, "missing -o OUT.(nrrd|slc)");
    vv_format format;
    if (cli_ends_with(out, ".slc"))
        format = VV_FORMAT_SLC;
    else if (cli_ends_with(out, ".nrrd") || cli_ends_with(out, ".nhdr"))
        format = VV_FORMAT_NRRD;
    else
        return cli_usage_error(&a, "cannot tell the output format from '%s'; use .nrrd or .slc",
                               out);
    const char *s;
    if (cli_get(&a, "size") && cli_get(&a, "spacing"))
        return cli_usage_error(&a, "give either --size or --spacing, not both");
    vv_mesh_mode mode = VV_MESH_AUTO;
    if ((s = cli_get(&a, "mesh-mode"))) {
        if (strcmp(s, "auto") == 0)
            mode = VV_MESH_AUTO;
        else if (strcmp(s, "solid") == 0)
            mode = VV_MESH_SOLID;
        else if (strcmp(s, "shell") == 0)
            mode = VV_MESH_SHELL;
        else
            return cli_usage_error(&a, "--mesh-mode: unknown mode '%s' (auto, solid or shell)", s);
    }
    double thickness = 0;
    if ((s = cli_get(&a, "thickness")) &&
        (rc = cli_parse_double(&a, "thickness", s, 0, 1e300, &thickness)))
        return rc;
    if ((rc = cli_check_readable(in)))
        return rc;

    /* the model, with the scene's own settings as defaults */
    vv_voxelize_options o;
    vv_voxelize_options_init(&o);
    vv_shape *shape = NULL;
    vv_status st;
    vv_error_clear();
    int is_scene = cli_ends_with(in, ".json");
    if (is_scene)
        st = vv_shape_load(&shape, in, &o);
    else
        st = vv_shape_mesh_load(&shape, in, mode, thickness);
    if (st != VV_OK)
        return cli_fail(st, in);
    if (is_scene && (cli_get(&a, "mesh-mode") || cli_get(&a, "thickness")))
        cli_error("note: --mesh-mode and --thickness apply to mesh files; the scene's "
                  "\"mode\" and \"thickness\" keys are used");

    int n;
    double d;
    if ((s = cli_get(&a, "size"))) {
        if ((rc = cli_parse_int(&a, "size", s, 2, 1000000, &n)))
            goto fail_usage;
        o.size = n;
        o.voxel_spacing = 0;
    }
    if ((s = cli_get(&a, "spacing"))) {
        if ((rc = cli_parse_double(&a, "spacing", s, 1e-300, 1e300, &d)))
            goto fail_usage;
        o.voxel_spacing = d;
    }
    if ((s = cli_get(&a, "filter")) && vv_sampling_kernel_parse(s, &o.kernel) != VV_OK) {
        rc = cli_usage_error(&a, "--filter: unknown filter '%s' (box, tent or gauss)", s);
        goto fail_usage;
    }
    if ((s = cli_get(&a, "radius"))) {
        if ((rc = cli_parse_double(&a, "radius", s, 0.25, 16, &o.radius)))
            goto fail_usage;
    }
    if ((s = cli_get(&a, "margin"))) {
        if ((rc = cli_parse_double(&a, "margin", s, 0, 10000, &o.margin)))
            goto fail_usage;
    }
    if ((s = cli_get(&a, "type"))) {
        if (strcmp(s, "u8") == 0)
            o.type = VV_U8;
        else if (strcmp(s, "f32") == 0)
            o.type = VV_F32;
        else {
            rc = cli_usage_error(&a, "--type: expected u8 or f32, got '%s'", s);
            goto fail_usage;
        }
    }
    if (format == VV_FORMAT_SLC && o.type != VV_U8) {
        rc = cli_usage_error(&a, "SLC holds 8-bit voxels only; use --type u8 or a .nrrd output");
        goto fail_usage;
    }
    if ((s = cli_get(&a, "threads")) && (rc = cli_parse_int(&a, "threads", s, 1, 4096, &n)))
        goto fail_usage;
    if (s)
        o.threads = n;

    cli_progress pr;
    int quiet = cli_count(&a, "quiet") > 0;
    cli_progress_begin(&pr, quiet);
    o.progress = pr.p;
    vv_volume *v = NULL;
    double t0 = cli_now();
    vv_error_clear();
    st = vv_voxelize(&v, shape, &o);
    double seconds = cli_now() - t0;
    cli_progress_end(&pr);
    vv_shape_free(shape);
    if (st == VV_OK && cli_interrupted())
        st = vv_error_set(VV_ERR_CANCELLED, "interrupted");
    if (st != VV_OK) {
        vv_volume_free(v);
        if (st == VV_ERR_CANCELLED && cli_interrupted()) {
            cli_error("voxelize: interrupted; %s not written", out);
            return CLI_EXIT_CANCEL;
        }
        return cli_fail(st, in);
    }
    vv_error_clear();
    st = vv_volume_save(v, out, format, 1);
    if (st != VV_OK) {
        vv_volume_free(v);
        return cli_fail(st, out);
    }
    if (!quiet)
        printf("wrote %s (%s, %d x %d x %d, %s, spacing %g, %s filter radius %g, %.3f s)\n", out,
               vv_format_name(format), v->dims[0], v->dims[1], v->dims[2],
               vv_voxel_type_name(v->type), v->spacing[0], vv_sampling_kernel_name(o.kernel),
               o.radius, seconds);
    vv_volume_free(v);
    return CLI_EXIT_OK;
fail_usage:
    vv_shape_free(shape);
    return rc;
}
