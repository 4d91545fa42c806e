/*
 * volvis slice INPUT -o OUT.png: one axial, coronal, sagittal or oblique
 * slice of a volume (multiplanar reconstruction, include/volvis/slice.h),
 * windowed to grey; the GUI's slice views sample through the same library.
 * --probe prints the voxel value at a point instead (or as well).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const cli_opt_spec slice_opts[] = {
    {"output", 'o', "OUT.png"},
    {"axis", 0, "axial|coronal|sagittal"},
    {"at", 0, "X,Y,Z|voxel:I,J,K"},
    {"plane", 0, "PX,PY,PZ:NX,NY,NZ"},
    {"size", 0, "WxH"},
    {"pixel", 0, "P"},
    {"window", 0, "W"},
    {"level", 0, "L"},
    {"probe", 0, "X,Y,Z|voxel:I,J,K"},
    {"object", 0, "N"},
    {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"},
    {"series", 0, "N"},
    {"channel", 0, "C"},
    {"time", 0, "T"},
    {"quiet", 'q', NULL},
};
#define N_SLICE_OPTS ((int)(sizeof slice_opts / sizeof slice_opts[0]))

void
cli_slice_usage(FILE *out) {
    fprintf(out,
            "usage: volvis slice [OPTIONS] INPUT -o OUT.png\n"
            "       volvis slice [OPTIONS] INPUT --probe X,Y,Z\n"
            "\n"
            "Writes one slice of a volume as a grey PNG: axial, coronal or sagittal in\n"
            "the volume's anatomical frame (RAS or LPS; radiological display: axial seen\n"
            "from the feet, coronal from the front, sagittal from the patient's left),\n"
            "or an oblique plane. INPUT is a volume file or a scene file (its volume\n"
            "object, filtered and placed as the scene says). Samples are trilinear at\n"
            "each pixel centre; outside the volume is black. The GUI's slice views show\n"
            "the same samples. Prints the plane, its edges' directions and the window.\n"
            "\n"
            "Options:\n"
            "  -o, --output OUT.png  output PNG (written atomically)\n"
            "  --axis A         axial (default), coronal or sagittal\n"
            "  --at POINT       the slice passes through POINT: world X,Y,Z or voxel:I,J,K\n"
            "                   (default: the volume's centre)\n"
            "  --plane P:N      an oblique plane through world point P with normal N\n"
            "  --size WxH       image size; the volume's cross-section is fitted into it\n"
            "                   (default: the cross-section at one pixel per smallest\n"
            "                   voxel spacing)\n"
            "  --pixel P        world units a pixel (with --size: centred, not fitted)\n"
            "  --window W, --level L  grey ramp from L - W/2 (black) to L + W/2 (white)\n"
            "                   (default: the 1st to the 99.5th percentile of the\n"
            "                   foreground, the background peak set aside)\n"
            "  --probe POINT    print the value at POINT (world X,Y,Z or voxel:I,J,K), its\n"
            "                   voxel index and world position; -o is then optional\n"
            "  --object N       a scene's volume object N, from 0 (default: the first)\n"
            "  --raw DESC       read INPUT as raw voxels (see 'volvis info --help')\n"
            "  --series N, --channel C, --time T  DICOM series, the file's channel and time\n"
            "                   step (from 0)\n"
            "  -q, --quiet      print nothing but errors (and --probe's line)\n"
            "  -h, --help       show this help\n"
            "\n"
            "Examples:\n"
            "  volvis slice ../shared/data/volumes/ct_head.nrrd --axis coronal -o cor.png\n"
            "  volvis slice head.nrrd --at voxel:128,128,54 --window 400 --level 40 -o ax.png\n"
            "  volvis slice head.nrrd --plane 0,0,80:0,1,1 --size 512x512 -o oblique.png\n"
            "  volvis slice head.nrrd --probe 120.5,98,60\n");
}

/* The World of INPUT (a scene or a volume shown as `volvis render` shows it)
 * and the volume object to slice. */
static int
load(const cli_args *a, const char *input, vv_world **w, const vv_object **obj) {
    int rc, obj_index = -1;
    const char *t = cli_get(a, "object");
    if (t && (rc = cli_parse_int(a, "object", t, 0, 1 << 20, &obj_index)))
        return rc;
    /* through the door, every voxel at hand: a scene, or a volume file's
     * channel and step as `volvis render` shows it */
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    o.memory = VV_WORLD_IN_MEMORY;
    if (cli_get(a, "raw")) {
        if ((rc = cli_parse_raw(a, "raw", cli_get(a, "raw"), &o.load.raw)))
            return rc;
        o.load.format = VV_FORMAT_RAW;
        o.load.has_raw = 1;
    }
    if ((rc = cli_parse_series_channel(a, &o.load.series, &o.load.channel, &o.load.time)))
        return rc;
    vv_error_clear();
    vv_status s = vv_world_open(w, input, &o, NULL);
    if (s != VV_OK)
        return cli_fail(s, input);
    *obj = NULL;
    for (int i = 0, k = 0; i < (*w)->n_objects && !*obj; i++)
        if ((*w)->objects[i]->volume && (obj_index < 0 || k++ == obj_index))
            *obj = (*w)->objects[i];
    if (!*obj) {
        cli_error("slice: %s: no volume object%s", input, obj_index >= 0 ? " of that number" : "");
        return CLI_EXIT_FAIL;
    }
    return CLI_EXIT_OK;
}

/* A point option as a world point of @p obj (voxel:I,J,K through its transform). */
static int
point_of(const cli_args *a, const char *opt, const vv_object *obj, vv_vec3 *out) {
    double p[3];
    int is_voxel = 0, rc;
    if ((rc = cli_parse_point(a, opt, cli_get(a, opt), p, &is_voxel)))
        return rc;
    *out = vv_vec3_make(p[0], p[1], p[2]);
    if (is_voxel)
        *out = vv_mat4_mul_point(vv_object_index_to_world(obj), *out);
    return CLI_EXIT_OK;
}

static int
probe(const cli_args *a, const vv_object *obj) {
    vv_vec3 p;
    int rc = point_of(a, "probe", obj, &p);
    if (rc)
        return rc;
    double ijk[3];
    double v = vv_slice_probe(obj, p, ijk);
    const char *unit =
        obj->volume->unit == VV_UNIT_UNKNOWN ? "world units" : vv_unit_name(obj->volume->unit);
    if (isnan(v)) {
        cli_error("slice: --probe %s: outside the volume (voxel %.6g, %.6g, %.6g)",
                  cli_get(a, "probe"), ijk[0], ijk[1], ijk[2]);
        return CLI_EXIT_FAIL;
    }
    printf("value %.9g at voxel (%.6g, %.6g, %.6g), world (%.6g, %.6g, %.6g) %s\n", v, ijk[0],
           ijk[1], ijk[2], p.x, p.y, p.z, unit);
    return CLI_EXIT_OK;
}

/* The plane from --axis, --at, --plane, --size and --pixel. */
static int
plane_of(const cli_args *a, const vv_object *obj, vv_slice_plane *pl) {
    int rc, w = 0, h = 0;
    vv_box box = vv_object_world_box(obj);
    vv_vec3 at = vv_vec3_scale(vv_vec3_add(box.min, box.max), 0.5);
    if (cli_get(a, "at") && (rc = point_of(a, "at", obj, &at)))
        return rc;
    if (cli_get(a, "size") && (rc = cli_parse_size(a, "size", cli_get(a, "size"), &w, &h)))
        return rc;
    const vv_volume *v = obj->volume;
    double px = fmin(v->spacing[0], fmin(v->spacing[1], v->spacing[2]));
    if (cli_get(a, "pixel") &&
        (rc = cli_parse_double(a, "pixel", cli_get(a, "pixel"), 1e-9, 1e9, &px)))
        return rc;
    vv_status s;
    if (cli_get(a, "plane")) {
        vv_cut_plane cp;
        if ((rc = cli_parse_plane(a, "plane", cli_get(a, "plane"), &cp)))
            return rc;
        s = vv_slice_plane_oblique(pl, v->space, cp.point, cp.normal, 1, 1, px);
    } else {
        vv_slice_axis axis = VV_SLICE_AXIAL;
        const char *t = cli_get(a, "axis");
        if (t && (vv_slice_axis_parse(t, &axis) != VV_OK || axis == VV_SLICE_OBLIQUE))
            return cli_usage_error(a, "--axis: '%s' is not axial, coronal or sagittal", t);
        s = vv_slice_plane_standard(pl, axis, v->space, at, 1, 1, px);
    }
    if (s != VV_OK)
        return cli_fail(s, NULL);
    if (w > 0 && !cli_get(a, "pixel")) {
        pl->width = w;
        pl->height = h;
        vv_slice_plane_fit(pl, box, 0.0);
        return CLI_EXIT_OK;
    }
    /* the cross-section at this pixel size (or the size given), centred */
    vv_slice_plane_fit(pl, box, 0.0); /* centres it; the pixel is set again below */
    double lo = INFINITY, hi = -INFINITY, lo2 = INFINITY, hi2 = -INFINITY;
    for (int c = 0; c < 8; c++) {
        vv_vec3 q = vv_vec3_make(c & 1 ? box.max.x : box.min.x, c & 2 ? box.max.y : box.min.y,
                                 c & 4 ? box.max.z : box.min.z);
        vv_vec3 d = vv_vec3_sub(q, pl->center);
        lo = fmin(lo, vv_vec3_dot(d, pl->right));
        hi = fmax(hi, vv_vec3_dot(d, pl->right));
        lo2 = fmin(lo2, vv_vec3_dot(d, pl->up));
        hi2 = fmax(hi2, vv_vec3_dot(d, pl->up));
    }
    pl->pixel = px;
    pl->width = w > 0 ? w : (int)fmin(16384, fmax(1, ceil((hi - lo) / px + 1)));
    pl->height = h > 0 ? h : (int)fmin(16384, fmax(1, ceil((hi2 - lo2) / px + 1)));
    return CLI_EXIT_OK;
}

static int
write_slice(const cli_args *a, const vv_object *obj, const char *output) {
    vv_slice_plane pl;
    int rc = plane_of(a, obj, &pl);
    if (rc)
        return rc;
    double win, lev;
    vv_slice_auto_window(obj->volume, &win, &lev);
    if (cli_get(a, "window") &&
        (rc = cli_parse_double(a, "window", cli_get(a, "window"), 1e-300, 1e300, &win)))
        return rc;
    if (cli_get(a, "level") &&
        (rc = cli_parse_double(a, "level", cli_get(a, "level"), -1e300, 1e300, &lev)))
        return rc;
    size_t n = (size_t)pl.width * pl.height;
    float *values = malloc(n * sizeof *values);
    uint8_t *rgba = malloc(n * 4);
    vv_image *img = NULL;
    vv_status s = values && rgba ? vv_image_new(&img, pl.width, pl.height)
                                 : vv_error_set(VV_ERR_NOMEM, "slice: out of memory");
    if (s == VV_OK)
        s = vv_slice_sample(obj, &pl, values);
    if (s == VV_OK) {
        vv_slice_window_level(values, n, win, lev, vv_vec3_make(0, 0, 0), rgba);
        for (size_t i = 0; i < 4 * n; i++)
            img->rgba[i] = rgba[i] / 255.0f;
        s = vv_image_write_png(img, output, 1.0, 0);
    }
    rc = s == VV_OK ? CLI_EXIT_OK : cli_fail(s, s == VV_ERR_IO ? output : NULL);
    if (s == VV_OK && !cli_count(a, "quiet")) {
        vv_vec3 nn = vv_slice_plane_normal(&pl);
        printf("wrote %s (%dx%d): %s slice through (%.6g, %.6g, %.6g), normal (%.4g, %.4g, "
               "%.4g), %.6g world units a pixel; right %s, left %s, top %s, bottom %s; window %.6g "
               "level %.6g\n",
               output, pl.width, pl.height, vv_slice_axis_name(pl.axis), pl.center.x, pl.center.y,
               pl.center.z, nn.x, nn.y, nn.z, pl.pixel, pl.edge[0], pl.edge[1], pl.edge[2],
               pl.edge[3], win, lev);
    }
    free(values);
    free(rgba);
    vv_image_free(img);
    return rc;
}

int
cli_slice_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "slice", slice_opts, N_SLICE_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_slice_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos != 1)
        return cli_usage_error(&a, "expected one INPUT, got %d", a.n_pos);
    const char *output = cli_get(&a, "output");
    if (!output && !cli_get(&a, "probe"))
        return cli_usage_error(&a, "-o OUT.png (or --probe) is required");
    if (cli_get(&a, "plane") && (cli_get(&a, "axis") || cli_get(&a, "at")))
        return cli_usage_error(&a, "--plane is an oblique plane: not with --axis or --at");
    vv_world *w = NULL;
    const vv_object *obj = NULL;
    if ((rc = load(&a, a.pos[0], &w, &obj)))
        goto done;
    if (cli_get(&a, "probe") && (rc = probe(&a, obj)))
        goto done;
    if (output)
        rc = write_slice(&a, obj, output);
done:
    vv_world_free(w);
    return rc;
}
