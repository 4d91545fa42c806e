/*
 * Every refusal of the scene reader ("our own parsers under attack"): one
 * hostile scene file per error the reader can give, each checked for its
 * status, a phrase naming the field and the problem, the scene file's name
 * (every message starts with it) and a message of one printable line.
 * Wrong types for every field class, values out of range, unknown keys
 * (refused, with the closest key suggested), too many entries, missing
 * keys, files that cannot be read; what the reader allows is checked too:
 * a volume named by an absolute path or by one through "..", unknown keys
 * nowhere accepted, nesting as deep as Jansson takes it.
 */
#define _DEFAULT_SOURCE /* realpath */
#include "testutil.h"

#define check_message(st, want, needle, file, what) vt_expect_refusal(what, st, want, needle, file)

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "volvis/bricks.h"

static char g_dir[1024];

static void
write_text(const char *name, const char *text) {
    vt_write_file(vt_path(g_dir, name), text, strlen(text));
}

/* vol.mhd (4^3 u8), volf.mhd (4^3 f32), vol.vvb, grid.vtk (a tetrahedron
 * with the point field "t"), in the test's folder. */
static int
setup(void **state) {
    (void)state;
    snprintf(g_dir, sizeof g_dir, "%s", vt_outdir("scene_errors"));
    const int dims[3] = {4, 4, 4};
    for (int f = 0; f < 2; f++) {
        vv_volume *v = NULL;
        if (vv_volume_new(&v, dims, f ? VV_F32 : VV_U8) != VV_OK)
            return -1;
        for (int i = 0; i < 64; i++)
            vv_volume_set(v, i % 4, i / 4 % 4, i / 16, (double)(i * 3));
        vv_volume_update_range(v);
        vv_status s =
            vv_volume_save(v, vt_path(g_dir, f ? "volf.mhd" : "vol.mhd"), VV_FORMAT_MHD, 1);
        if (s == VV_OK && !f)
            s = vt_save(v, vt_path(g_dir, "vol.vvb"), VV_FORMAT_VVB, -1, 0);
        vv_volume_free(v);
        if (s != VV_OK)
            return -1;
    }
    write_text("grid.vtk", "# vtk DataFile Version 3.0\ng\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                           "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\n"
                           "CELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS t float 1\n"
                           "LOOKUP_TABLE default\n0 1 2 3\n");
    return 0;
}

typedef struct scene_case {
    const char *text;
    const char *needle;
    vv_status status; /* 0: VV_ERR_FORMAT */
} scene_case;

/* One volume object of vol.mhd with the keys @p k. */
#define VOL(k) "{\"objects\": [{\"type\": \"volume\", \"file\": \"vol.mhd\"" k "}]}"
/* One object of its own (@p o: its keys, type included). */
#define OBJ(o) "{\"objects\": [{" o "}]}"
#define TF2D(w) VOL(", \"tf2d\": {\"widgets\": [" w "]}")

static const scene_case cases[] = {
    /* the top level, the syntax */
    {"[1, 2]", "expected a JSON object at the top level, got an array", 0},
    {"{\"view\": ", "end of file", 0},
    {"{\"view\": {\"fov\": 1e400}}", "overflow", 0},
    {"{\"view\": {\"fov\": NaN}}", "invalid token", 0},
    {"{\"view\": {\"fov\": -Infinity}}", "invalid token", 0},
    {"{\"view\": {}, \"view\": {}}", "duplicate", 0},
    {"{\"veiw\": {}}", "veiw: unknown key (did you mean view?)", 0},
    {"{\"zzzzzzzzzz\": {}}", "unknown key; expected one of: view, lights", 0},
    {"{\"view\": []}", "view: expected an object, got an array", 0},
    {"{\"lights\": {}}", "lights: expected an array, got an object", 0},
    /* view: every field class */
    {"{\"view\": {\"fov\": \"wide\"}}", "view.fov: expected a number, got a string", 0},
    {"{\"view\": {\"fov\": 190}}", "view.fov: 190 is outside (0, 180)", 0},
    {"{\"view\": {\"ortho_height\": -1}}", "view.ortho_height: -1 is outside (0, inf)", 0},
    {"{\"view\": {\"width\": 1.5}}", "view.width: expected an integer, got 1.5", 0},
    {"{\"view\": {\"width\": 0}}", "view.width: 0 is outside 1..32768", 0},
    {"{\"view\": {\"eye\": 3}}", "view.eye: expected an array of 3 numbers, got a number", 0},
    {"{\"view\": {\"eye\": [1, 2]}}", "got an array of another length", 0},
    {"{\"view\": {\"eye\": [1, \"2\", 3]}}", "view.eye[1]: expected a number, got a string", 0},
    {"{\"view\": {\"up\": [0, 0, 0]}}", "view.up: must not be the zero vector", 0},
    {"{\"view\": {\"background\": [2, 0, 0]}}", "colour component 2 is outside [0, 1]", 0},
    {"{\"view\": {\"projection\": 1}}", "view.projection: expected a string, got a number", 0},
    {"{\"view\": {\"projection\": \"fisheye\"}}", "unknown projection \"fisheye\"", 0},
    {"{\"view\": {\"eye\": [1, 1, 1], \"at\": [1, 1, 1]}}",
     "the eye and the point looked at are the same", 0},
    {"{\"view\": {\"eye\": [0, 0, 5], \"at\": [0, 0, 0], \"up\": [0, 0, 1]}}",
     "up is parallel to the viewing direction", 0},
    {"{\"view\": {\"background\": [0, 0, 0]}, \"shading\": {\"background\": [0, 0, 0]}}",
     "shading.background: the background is also given in view.background", 0},
    {"{\"shading\": {\"ambient\": [0, 0, -1]}}", "colour component -1", 0},
    /* lights */
    {"{\"lights\": [7]}", "lights[0]: expected an object, got a number", 0},
    {"{\"lights\": [{\"type\": \"directional\", \"position\": [0, 0, 0]}]}",
     "a directional light has no position", 0},
    {"{\"lights\": [{\"type\": \"point\", \"direction\": [0, 0, 1]}]}",
     "a point light has no direction", 0},
    {"{\"lights\": [{\"type\": \"point\"}]}", "missing required key \"position\"", 0},
    {"{\"lights\": [{\"type\": \"laser\"}]}", "unknown light type \"laser\"", 0},
    {"{\"lights\": [{\"intensity\": -1}]}", "lights[0].intensity: -1 is outside [0, inf)", 0},
    /* cut planes */
    {"{\"cut_planes\": [1]}", "cut_planes[0]: expected an object {\"point\", \"normal\"}", 0},
    {"{\"cut_planes\": [{\"normal\": [0, 0, 1]}]}", "missing required key \"point\"", 0},
    {"{\"cut_planes\": [{\"point\": [0, 0, 1]}]}", "missing required key \"normal\"", 0},
    {"{\"cut_planes\": [{\"point\": [0, 0, 1], \"normall\": [0, 0, 1]}]}", "did you mean normal?",
     0},
    /* render */
    {"{\"render\": {\"renderer\": \"\"}}", "render.renderer: the renderer name is empty", 0},
    {"{\"render\": {\"renderer\": \"r23456789012345678901234567890123\"}}", "renderer name \"r2345",
     0},
    {"{\"render\": {\"quality\": 3}}", "render.quality: 3 is outside 0..2", 0},
    {"{\"render\": {\"options\": {\"\": 1}}}", "the option name is empty", 0},
    {"{\"render\": {\"options\": {\"k23456789012345678901234567890123\": 1}}}",
     "option name is 33 bytes; at most 31", 0},
    {"{\"render\": {\"options\": {\"k\": [1]}}}",
     "render.options.k: expected a string, a number or a boolean, got an array", 0},
    {"{\"render\": {\"options\": {\"k\": \"a\\u0000b\"}}}", "is not allowed without JSON_ALLOW_NUL",
     0},
    /* objects: the kinds */
    {"{\"objects\": [3]}", "objects[0]: expected an object, got a number", 0},
    {"{\"objects\": [\"sphere\"]}", "objects[0]: expected an object, got a string", 0},
    {OBJ("\"type\": \"volumex\", \"file\": \"vol.mhd\""), "unsupported object type \"volumex\"", 0},
    {OBJ("\"type\": 5, \"file\": \"vol.mhd\""), "objects[0].type: expected a string", 0},
    {OBJ("\"type\": \"volume\""), "objects[0]: missing required key \"file\"", 0},
    {VOL(", \"nmae\": \"x\""), "objects[0].nmae: unknown key (did you mean name?)", 0},
    {VOL(", \"name\": \"n234567890123456789012345678901234567890123456789012345678901234\""),
     "objects[0].name: longer than 63 bytes", 0},
    /* volume objects */
    {OBJ("\"type\": \"volume\", \"file\": \"\""), "objects[0].file: empty file name", 0},
    {OBJ("\"file\": \"missing.mhd\""), "objects[0].file: ", VV_ERR_IO},
    {OBJ("\"file\": \"errors.json\""), "objects[0].file", VV_ERR_FORMAT},
    {VOL(", \"spacing\": [1, 0, 1]"), "objects[0].spacing: voxel spacing must be > 0", 0},
    {VOL(", \"spacing\": [1, 1, -2]"), "voxel spacing must be > 0", 0},
    {VOL(", \"origin\": [1, 1]"), "objects[0].origin: expected an array of 3 numbers", 0},
    {VOL(", \"time\": 2, \"filters\": \"--median 1\""),
     "objects[0].time: \"filters\" apply to time step 0", 0},
    {VOL(", \"time\": -1"), "objects[0].time: -1 is outside 0..1000000", 0},
    {VOL(", \"time\": 3"), "objects[0].time", VV_ERR_INVALID},
    {VOL(", \"filters\": 5"), "objects[0].filters: expected a string", 0},
    {VOL(", \"filters\": [1]"), "objects[0].filters[0]: expected an object with one key", 0},
    {VOL(", \"filters\": [{\"median\": 1}, {\"gaussian\": false}]"),
     "objects[0].filters[1]: \"gaussian\": expected a string or a number argument", 0},
    {VOL(", \"filters\": [{\"no-such-filter\": 1}]"), "objects[0].filters[0]: ", 0},
    {VOL(", \"filters\": \"--no-such-filter\""), "objects[0].filters: ", 0},
    /* what every object carries */
    {VOL(", \"mode\": \"sum\""), "objects[0].mode: unknown mode \"sum\"", 0},
    {VOL(", \"mode\": \"iso\", \"transfer_function\": {\"opacity\": []}"),
     "objects[0].mode: mode \"iso\" needs an \"isovalue\"", 0},
    {VOL(", \"step\": 0"), "objects[0].step: 0 is outside (0, inf)", 0},
    {VOL(", \"shading\": 1"), "objects[0].shading: expected true or false, got a number", 0},
    {VOL(", \"casts_shadows\": \"yes\""), "objects[0].casts_shadows: expected true or false", 0},
    {VOL(", \"rotation\": {\"axis\": [0, 0, 1], \"angle\": 5}, \"orientation\": [1, 0, 0, 0]"),
     "give either \"rotation\" or \"orientation\", not both", 0},
    {VOL(", \"rotation\": {\"angle\": 5}"), "objects[0].rotation: missing required key \"axis\"",
     0},
    {VOL(", \"rotation\": {\"axis\": [0, 0, 1]}"), "missing required key \"angle\"", 0},
    {VOL(", \"rotation\": [0, 0, 1]"), "objects[0].rotation: expected an object", 0},
    {VOL(", \"orientation\": [1, 0, 0]"), "expected a quaternion [w, x, y, z], got an array", 0},
    {VOL(", \"orientation\": [1, 0, \"0\", 0]"), "objects[0].orientation[2]: expected a number", 0},
    {VOL(", \"orientation\": [0, 0, 0, 0]"), "the zero quaternion is not a rotation", 0},
    {VOL(", \"scale\": 0"), "objects[0].scale: scale factors must be > 0", 0},
    {VOL(", \"scale\": [1, 1, -1]"), "scale factors must be > 0", 0},
    {VOL(", \"scale\": \"big\""), "objects[0].scale: expected an array of 3 numbers", 0},
    {VOL(", \"segmentation\": 5"), "expected {\"threshold\": value}", 0},
    {VOL(", \"segmentation\": \"tf2d\""), "segmentation \"tf2d\" needs a \"tf2d\" object", 0},
    {VOL(", \"segmentation\": \"watershed\""), "unknown segmentation \"watershed\"", 0},
    {VOL(", \"segmentation\": {}"), "missing required key \"threshold\"", 0},
    {VOL(", \"segmentation\": {\"threshold\": 1}, \"transfer_function\": {\"opacity\": []}"),
     "give either \"transfer_function\" or \"segmentation\", not both", 0},
    {VOL(", \"material\": {\"shininess\": -1}"), "objects[0].material.shininess: -1 is outside", 0},
    {VOL(", \"material\": {\"ior\": 0}"), "objects[0].material.ior: 0 is outside (0, inf)", 0},
    {VOL(", \"material\": {\"emission\": [0, -1, 0]}"),
     "objects[0].material.emission: expected three finite numbers >= 0", 0},
    {VOL(", \"material\": {\"colour\": [0, 1, 0]}"), "did you mean color?", 0},
    {VOL(", \"cut_planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 0, 0]}]"),
     "objects[0].cut_planes[0].normal: must not be the zero vector", 0},
    /* transfer functions */
    {VOL(", \"transfer_function\": {\"color\": []}"),
     "objects[0].transfer_function: missing required key \"opacity\"", 0},
    {VOL(", \"transfer_function\": {\"opacity\": [1]}"),
     "transfer_function.opacity[0]: expected a pair [value, opacity], got a number", 0},
    {VOL(", \"transfer_function\": {\"opacity\": [[0, 2]]}"),
     "transfer_function.opacity[0][1]: opacity 2 is outside [0, 1]", 0},
    {VOL(", \"transfer_function\": {\"opacity\": [[\"a\", 1]]}"),
     "transfer_function.opacity[0][0]: expected a number", 0},
    {VOL(", \"transfer_function\": {\"opacity\": [[0, \"a\"]]}"),
     "transfer_function.opacity[0][1]: expected a number", 0},
    {VOL(", \"transfer_function\": {\"opacity\": [], \"color\": [[0, [1, 1]]]}"),
     "transfer_function.color[0][1]: expected an array of 3 numbers", 0},
    {VOL(", \"transfer_function\": {\"opacity\": [], \"color\": [[0, 1, 1]]}"),
     "expected a pair [value, [r, g, b]], got an array", 0},
    {VOL(", \"transfer_function\": {\"opacity\": [], \"opacity_unit_distance\": 0}"),
     "transfer_function.opacity_unit_distance: 0 is outside (0, inf)", 0},
    /* 2-D transfer functions */
    {VOL(", \"tf2d\": {}"), "objects[0].tf2d: missing required key \"widgets\"", 0},
    {TF2D("3"), "objects[0].tf2d.widgets[0]: expected a widget object, got a number", 0},
    {TF2D("{}"), "missing required key \"shape\"", 0},
    {TF2D("{\"shape\": \"circle\"}"), "tf2d.widgets[0].shape: unknown widget shape \"circle\"", 0},
    {TF2D("{\"shape\": \"rectangle\", \"gradient\": [0, 1]}"), "missing required key \"value\"", 0},
    {TF2D("{\"shape\": \"rectangle\", \"value\": [0, 1]}"), "missing required key \"gradient\"", 0},
    {TF2D("{\"shape\": \"rectangle\", \"value\": 1, \"gradient\": [0, 1]}"),
     "tf2d.widgets[0].value: expected an array of 2 numbers, got a number", 0},
    {TF2D("{\"shape\": \"rectangle\", \"value\": [0, \"1\"], \"gradient\": [0, 1]}"),
     "tf2d.widgets[0].value[1]: expected a number", 0},
    {TF2D("{\"shape\": \"rectangle\", \"value\": [5, 1], \"gradient\": [0, 1]}"),
     "objects[0].tf2d.widgets[0]: ", 0},
    {TF2D("{\"shape\": \"triangle\", \"width\": 1, \"gradient\": [0, 1]}"),
     "missing required key \"center\"", 0},
    {TF2D("{\"shape\": \"triangle\", \"center\": 1, \"gradient\": [0, 1]}"),
     "missing required key \"width\"", 0},
    {TF2D("{\"shape\": \"triangle\", \"center\": 1, \"width\": 1}"),
     "missing required key \"gradient\"", 0},
    {TF2D("{\"shape\": \"triangle\", \"center\": 1, \"width\": 1, \"gradient\": [0, 1], "
          "\"value\": [0, 1]}"),
     "tf2d.widgets[0].value: unknown key", 0},
    /* textures */
    {VOL(", \"texture\": {}"), "objects[0].texture: missing required key \"image\"", 0},
    {VOL(", \"texture\": {\"image\": \"a.png\", \"projection\": \"conic\"}"),
     "unknown projection \"conic\"; expected planar, cylindrical or spherical", 0},
    {VOL(", \"texture\": {\"image\": \"a.png\", \"scale\": [0, 1]}"),
     "objects[0].texture.scale: scale factors must not be 0", 0},
    {VOL(", \"texture\": {\"image\": \"\"}"), "objects[0].texture.image: empty file name", 0},
    {VOL(", \"texture\": {\"image\": \"missing.png\"}"), "objects[0].texture.image", VV_ERR_IO},
    {VOL(", \"solid_texture\": {}"), "give exactly one of \"procedural\"", 0},
    {VOL(", \"solid_texture\": {\"procedural\": \"wood\", \"volume\": \"vol.mhd\"}"),
     "give exactly one of", 0},
    {VOL(", \"solid_texture\": {\"procedural\": \"granite\"}"),
     "unknown procedural texture \"granite\"", 0},
    {VOL(", \"solid_texture\": {\"procedural\": \"wood\", \"seed\": 1.5}"),
     "objects[0].solid_texture.seed: expected an integer, got 1.5", 0},
    {VOL(", \"solid_texture\": {\"procedural\": \"wood\", \"seed\": -1}"),
     "objects[0].solid_texture.seed: -1 is outside", 0},
    {VOL(", \"solid_texture\": {\"volume\": \"\"}"), "solid_texture.volume: empty file name", 0},
    {VOL(", \"solid_texture\": {\"volume\": \"missing.mhd\"}"), "solid_texture.volume", VV_ERR_IO},
    /* channels */
    {VOL(", \"blend\": \"maximum\""), "objects[0].blend: \"blend\" needs \"channels\"", 0},
    {VOL(", \"blend\": \"max\", \"channels\": [{\"channel\": 0}, {\"channel\": 0}]"),
     "unknown blend \"max\"", 0},
    {VOL(", \"channels\": [{\"channel\": 0}]"), "objects[0].channels: 1 channels (2..16)", 0},
    {VOL(", \"channels\": [{\"channel\": 0}, {\"channel\": 0}], \"filters\": \"--median 1\""),
     "\"filters\" apply to an object of one channel", 0},
    {VOL(", \"channels\": [1, 2]"), "objects[0].channels[0]: expected an object, got a number", 0},
    {VOL(", \"channels\": [{\"channel\": 0}, {\"name\": \"b\"}]"),
     "objects[0].channels[1]: missing required key \"channel\"", 0},
    {VOL(", \"channels\": [{\"channel\": 0}, {\"channel\": 0, \"colour\": 1}]"),
     "channels[1].colour: unknown key; expected one of: channel, name", 0},
    {VOL(", \"channels\": [{\"channel\": 0}, {\"channel\": 0.5}]"),
     "channels[1].channel: expected an integer", 0},
    {OBJ("\"file\": \"vol.vvb\", \"channels\": [{\"channel\": 0}, {\"channel\": 1}]"),
     "objects[0].channels[1].channel: ", VV_ERR_INVALID},
    {OBJ("\"file\": \"volf.mhd\", \"channels\": [{\"channel\": 0, \"labels\": true}, {\"channel\": "
         "0}]"),
     "objects[0].channels[0].labels: channel 0 of the file holds f32 voxels", 0},
    {VOL(", \"channels\": [{\"channel\": 0}, {\"channel\": 0, \"transfer_function\": {}}]"),
     "objects[0].channels[1].transfer_function: missing required key \"opacity\"", 0},
    /* geometric objects */
    {OBJ("\"type\": \"box\", \"min\": [0, 0, 0], \"max\": [1, 0, 1]"),
     "objects[0].max: each coordinate must be greater than in \"min\"", 0},
    {OBJ("\"type\": \"cylinder\", \"base\": [0, 0, 0], \"top\": [0, 0, 0]"),
     "objects[0].top: the cylinder's top must differ from its base", 0},
    {OBJ("\"type\": \"sphere\", \"radius\": 0"), "objects[0].radius: 0 is outside (0, inf)", 0},
    {OBJ("\"type\": \"sphere\", \"file\": \"vol.mhd\""), "objects[0].file: unknown key", 0},
    {OBJ("\"type\": \"polygon\""), "objects[0]: missing required key \"vertices\"", 0},
    {OBJ("\"type\": \"polygon\", \"vertices\": [[0, 0, 0], [1, 0, 0]]"),
     "objects[0].vertices: expected 3 to 100000 vertices, got 2", 0},
    {OBJ("\"type\": \"polygon\", \"vertices\": [[0, 0, 0], [1, 0, 0], 5]"),
     "objects[0].vertices[2]: expected an array of 3 numbers", 0},
    {OBJ("\"type\": \"polygon\", \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1]]"),
     "objects[0].vertices", 0},
    {OBJ("\"type\": \"mesh\""), "objects[0]: missing required key \"file\"", 0},
    {OBJ("\"type\": \"mesh\", \"file\": \"\""), "objects[0].file: empty file name", 0},
    {OBJ("\"type\": \"mesh\", \"file\": \"missing.obj\""), "objects[0].file", VV_ERR_IO},
    {OBJ("\"type\": \"plane\", \"name\": \"n234567890123456789012345678901234567890123456789012345"
         "678901234\""),
     "objects[0].name: longer than 63 bytes", 0},
    /* geometry objects (voxelized) */
    {OBJ("\"type\": \"geometry\", \"primitive\": {\"type\": \"sphere\"}, \"csg\": {}"),
     "objects[0].csg: give either \"primitive\" or \"csg\", not both", 0},
    {OBJ("\"type\": \"geometry\""), "objects[0]: missing required key \"primitive\"", 0},
    {OBJ("\"type\": \"geometry\", \"csg\": {\"children\": []}"),
     "objects[0].csg: expected a CSG operation", 0},
    {OBJ("\"type\": \"geometry\", \"primitive\": {\"type\": \"sphere\", \"radius\": 1}, "
         "\"resolution\": 1"),
     "objects[0].resolution", 0},
    {OBJ("\"type\": \"geometry\", \"primitive\": {\"type\": \"blob\"}"), "objects[0].primitive", 0},
    {OBJ("\"type\": \"geometry\", \"nmae\": 1, \"primitive\": {}"), "did you mean name?", 0},
    /* grids */
    {OBJ("\"type\": \"grid\""), "objects[0]: missing required key \"file\"", 0},
    {OBJ("\"type\": \"grid\", \"file\": \"\""), "objects[0].file: empty file name", 0},
    {OBJ("\"type\": \"grid\", \"file\": \"missing.vtk\""), "objects[0].file", VV_ERR_IO},
    {OBJ("\"type\": \"grid\", \"file\": \"grid.vtk\", \"component\": 9"),
     "objects[0].component: 9 is outside -1..8", 0},
    {OBJ("\"type\": \"grid\", \"file\": \"grid.vtk\", \"field\": \"pressure\""),
     "objects[0].field: ", 0},
};

static void
test_refusals(void **state) {
    (void)state;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const scene_case *tc = &cases[i];
        char name[64], what[96];
        snprintf(name, sizeof name, "errors%03zu.json", i);
        snprintf(what, sizeof what, "case %zu (%s)", i, tc->needle);
        /* a case naming errors.json names a scene file, not a volume */
        write_text("errors.json", "{}");
        const char *path = vt_path(g_dir, name);
        vt_write_file(path, tc->text, strlen(tc->text));
        vv_world *w = (vv_world *)1;
        vv_error_clear();
        vv_status st = vv_scene_load(&w, path);
        if (st == VV_OK)
            fail_msg("%s: the scene loaded", what);
        assert_null(w);
        check_message(st, tc->status ? tc->status : VV_ERR_FORMAT, tc->needle, name, what);
        /* every message starts with the scene file's path */
        if (strncmp(vv_error_message(), path, strlen(path)) != 0)
            fail_msg("%s: message '%s' does not start with the path", what, vv_error_message());
    }
}

/* Lists past their bounds: more cut planes, lights, options, points and
 * widgets than a World holds. */
static void
test_too_many(void **state) {
    (void)state;
    static const struct {
        const char *head, *item, *tail;
        int n;
        const char *needle;
    } lists[] = {
        {"{\"cut_planes\": [", "{\"point\": [0, 0, 0], \"normal\": [0, 0, 1]}", "]}",
         VV_MAX_CUT_PLANES + 1, "cut_planes[8]: more than 8 cut planes"},
        {"{\"lights\": [", "{}", "]}", VV_MAX_LIGHTS + 1, "lights[16]: more than 16 lights"},
        {"{\"objects\": [{\"file\": \"vol.mhd\", \"transfer_function\": {\"opacity\": [", "[0, 0]",
         "]}}]}", VV_TF_MAX_POINTS + 1, "transfer_function.opacity: more than 256 points"},
        {"{\"objects\": [{\"file\": \"vol.mhd\", \"tf2d\": {\"widgets\": [",
         "{\"shape\": \"triangle\", \"center\": 1, \"width\": 1, \"gradient\": [0, 1]}", "]}}]}",
         VV_TF2D_MAX_WIDGETS + 1, "tf2d.widgets: more than 16 widgets"},
        {"{\"objects\": [{\"file\": \"vol.mhd\", \"channels\": [", "{\"channel\": 0}", "]}]}",
         VV_MAX_CHANNELS + 1, "channels: 17 channels (2..16)"},
    };
    for (size_t l = 0; l < sizeof lists / sizeof lists[0]; l++) {
        size_t cap = strlen(lists[l].head) + strlen(lists[l].tail) +
                     (size_t)lists[l].n * (strlen(lists[l].item) + 2) + 1;
        char *text = malloc(cap);
        assert_non_null(text);
        strcpy(text, lists[l].head);
        for (int i = 0; i < lists[l].n; i++) {
            if (i)
                strcat(text, ", ");
            strcat(text, lists[l].item);
        }
        strcat(text, lists[l].tail);
        const char *path = vt_path(g_dir, "many.json");
        vt_write_file(path, text, strlen(text));
        free(text);
        vv_world *w = NULL;
        vv_error_clear();
        check_message(vv_scene_load(&w, path), VV_ERR_FORMAT, lists[l].needle, "many.json",
                      lists[l].needle);
        assert_null(w);
    }
    /* 33 renderer options */
    char text[4096] = "{\"render\": {\"options\": {";
    for (int i = 0; i <= VV_MAX_RENDER_OPTIONS; i++) {
        char kv[32];
        snprintf(kv, sizeof kv, "%s\"o%d\": %d", i ? ", " : "", i, i);
        strcat(text, kv);
    }
    strcat(text, "}}}");
    const char *path = vt_path(g_dir, "options.json");
    vt_write_file(path, text, strlen(text));
    vv_world *w = NULL;
    check_message(vv_scene_load(&w, path), VV_ERR_FORMAT, "more than 32 options", "options.json",
                  "options");
    /* an option value of 256 bytes */
    char big[400] = "{\"render\": {\"options\": {\"k\": \"";
    for (int i = 0; i < 256; i++)
        strcat(big, "v");
    strcat(big, "\"}}}");
    vt_write_file(path, big, strlen(big));
    check_message(vv_scene_load(&w, path), VV_ERR_FORMAT,
                  "render.options.k: value is 256 bytes; at most 255", "options.json", "value");
    assert_null(w);
}

/* What is not a scene file's doing, what the reader allows and where its
 * files may be. */
static void
test_policy(void **state) {
    (void)state;
    vv_world *w = NULL;
    check_message(vv_scene_load(NULL, "x.json"), VV_ERR_INVALID, "scene: NULL output", NULL,
                  "NULL out");
    check_message(vv_scene_load(&w, NULL), VV_ERR_INVALID, "scene: NULL path", NULL, "NULL path");
    check_message(vv_scene_load(&w, vt_path(g_dir, "absent.json")), VV_ERR_IO, "scene",
                  "absent.json", "missing scene");
    /* a scene naming itself as its volume */
    write_text("self.json", "{\"objects\": [{\"file\": \"self.json\"}]}");
    vv_error_clear();
    vv_status st = vv_scene_load(&w, vt_path(g_dir, "self.json"));
    assert_int_not_equal(st, VV_OK);
    check_message(st, st, "objects[0].file", "self.json", "self");
    assert_null(w);
    /* the documented policy (docs/scene-format.md, "Paths"): a volume is
     * named relative to the scene's folder, through ".." too, or by an
     * absolute path used as it is; the scene's author is trusted there */
    char sub[1100];
    snprintf(sub, sizeof sub, "%s/sub", g_dir);
    mkdir(sub, 0755);
    vt_write_file(vt_path(sub, "up.json"), "{\"objects\": [{\"file\": \"../vol.mhd\"}]}",
                  strlen("{\"objects\": [{\"file\": \"../vol.mhd\"}]}"));
    vt_ok(vv_scene_load(&w, vt_path(sub, "up.json")));
    vv_world_free(w);
    char abs[2048], text[2300];
    assert_non_null(realpath(vt_path(g_dir, "vol.mhd"), abs));
    snprintf(text, sizeof text, "{\"objects\": [{\"file\": \"%s\"}]}", abs);
    vt_write_file(vt_path(sub, "abs.json"), text, strlen(text));
    vt_ok(vv_scene_load(&w, vt_path(sub, "abs.json")));
    vv_world_free(w);
    /* nesting: Jansson refuses past its depth limit; inside a value the
     * reader does not walk, it is only a value of the wrong type */
    char *deep = malloc(2 * 5000 + 64);
    assert_non_null(deep);
    strcpy(deep, "{\"view\": ");
    size_t o = strlen(deep);
    for (int i = 0; i < 5000; i++)
        deep[o++] = '[';
    for (int i = 0; i < 5000; i++)
        deep[o++] = ']';
    strcpy(deep + o, "}");
    vt_write_file(vt_path(g_dir, "deep.json"), deep, strlen(deep));
    check_message(vv_scene_load(&w, vt_path(g_dir, "deep.json")), VV_ERR_FORMAT,
                  "deep.json:1:", "deep.json", "deep");
    strcpy(deep, "{\"view\": ");
    o = strlen(deep);
    for (int i = 0; i < 500; i++)
        deep[o++] = '[';
    for (int i = 0; i < 500; i++)
        deep[o++] = ']';
    strcpy(deep + o, "}");
    vt_write_file(vt_path(g_dir, "deep.json"), deep, strlen(deep));
    check_message(vv_scene_load(&w, vt_path(g_dir, "deep.json")), VV_ERR_FORMAT,
                  "view: expected an object, got an array", "deep.json", "deep value");
    free(deep);
    /* a key with a control byte is quoted escaped, on one line */
    write_text("ctl.json", "{\"vi\\u001bew\\n\": {}}");
    check_message(vv_scene_load(&w, vt_path(g_dir, "ctl.json")), VV_ERR_FORMAT, "unknown key",
                  "ctl.json", "control bytes");
}

/* Out of core (vv_scene_load_open): a grid where a volume is named, an
 * origin that the file's own contradicts. */
static void
test_out_of_core(void **state) {
    (void)state;
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE;
    vv_world *w = NULL;
    write_text("ooc_grid.json", "{\"objects\": [{\"file\": \"grid.vtk\"}]}");
    check_message(vv_scene_load_open(&w, vt_path(g_dir, "ooc_grid.json"), NULL, NULL, &oo),
                  VV_ERR_FORMAT, "not a volume file", "ooc_grid.json", "grid");
    assert_null(w);
    write_text("ooc_origin.json",
               "{\"objects\": [{\"name\": \"b\", \"file\": \"vol.vvb\", \"origin\": [9, 9, 9]}]}");
    check_message(vv_scene_load_open(&w, vt_path(g_dir, "ooc_origin.json"), NULL, NULL, &oo),
                  VV_ERR_FORMAT,
                  "objects[0].origin: object 'b': out of core its file's own origin and spacing",
                  "ooc_origin.json", "origin");
    assert_null(w);
    write_text("ooc_spacing.json",
               "{\"objects\": [{\"file\": \"vol.vvb\", \"spacing\": [2, 2, 2]}]}");
    check_message(vv_scene_load_open(&w, vt_path(g_dir, "ooc_spacing.json"), NULL, NULL, &oo),
                  VV_ERR_FORMAT, "objects[0].spacing: object 'vol.vvb'", "ooc_spacing.json",
                  "spacing");
    assert_null(w);
}

/* What vv_scene_save checks before it writes (a World the loader would
 * not read back), each refusal naming the file. */
static void
test_save_checks(void **state) {
    (void)state;
    const char *path = vt_path(g_dir, "saved.json");
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    check_message(vv_scene_save(NULL, path, NULL), VV_ERR_INVALID, "scene: NULL world", NULL,
                  "NULL world");
    check_message(vv_scene_save(w, NULL, NULL), VV_ERR_INVALID, "scene: NULL path", NULL,
                  "NULL path");
    vv_render_settings *rs = &w->render;
    memset(rs->renderer, 'r', sizeof rs->renderer);
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID, "renderer name not terminated",
                  "saved.json", "renderer");
    rs->renderer[0] = '\0';
    rs->quality = 3;
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID, "quality 3 outside -1..2",
                  "saved.json", "quality");
    rs->quality = -1;
    rs->n_options = VV_MAX_RENDER_OPTIONS + 1;
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID, "33 options outside 0..32",
                  "saved.json", "options");
    rs->n_options = 2;
    memset(rs->option_keys[0], 'k', sizeof rs->option_keys[0]);
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID, "option 0 not terminated",
                  "saved.json", "key");
    strcpy(rs->option_keys[0], "");
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID, "option 0 has an empty key",
                  "saved.json", "empty key");
    strcpy(rs->option_keys[0], "k");
    strcpy(rs->option_keys[1], "k");
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID, "option k given twice",
                  "saved.json", "twice");
    strcpy(rs->option_keys[1], "\xff");
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID,
                  "renderer option 1: the key is not valid UTF-8", "saved.json", "UTF-8 key");
    strcpy(rs->option_keys[1], "j");
    strcpy(rs->option_values[1], "\xc3");
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID,
                  "a renderer option is not valid UTF-8", "saved.json", "UTF-8 value");
    rs->n_options = 0;
    w->view.width = 0;
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID, "view size 0x", "saved.json",
                  "view");
    w->view.width = 64;
    /* objects without the files a scene names them by */
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_MESH, "m"));
    vt_ok(vv_world_add_object(w, o));
    check_message(vv_scene_save(w, path, NULL), VV_ERR_INVALID, "object 0: a mesh without a file",
                  "saved.json", "mesh");
    const char *files[2] = {"m.obj", NULL};
    const int dims[3] = {2, 2, 2};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    vt_ok(vv_object_new_volume(&o, v, "v"));
    vv_volume_free(v);
    vt_ok(vv_world_add_object(w, o));
    check_message(vv_scene_save(w, path, files), VV_ERR_INVALID, "object 1: no volume file name",
                  "saved.json", "volume");
    files[1] = "v.nrrd";
    /* a NULL object, a volume object without its volume (Worlds made by hand) */
    vv_object *keep = w->objects[1];
    w->objects[1] = NULL;
    check_message(vv_scene_save(w, path, files), VV_ERR_INVALID, "object 1 is NULL", "saved.json",
                  "NULL object");
    w->objects[1] = keep;
    vv_volume *kv = o->volume;
    o->volume = NULL;
    check_message(vv_scene_save(w, path, files), VV_ERR_INVALID, "object 1 has no volume",
                  "saved.json", "no volume");
    o->volume = kv;
    /* textures without the files they came from */
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 2, 2));
    vv_texture_image *ti = NULL;
    vt_ok(vv_texture_image_new(&ti, img, NULL)); /* the image's ownership taken */
    o->texture.image = ti;
    check_message(vv_scene_save(w, path, files), VV_ERR_INVALID,
                  "object 1: a texture image without a file name", "saved.json", "texture");
    o->texture.image = NULL;
    vv_texture_image_free(ti);
    o->solid_texture.kind = VV_SOLID_TEXTURE_VOLUME;
    check_message(vv_scene_save(w, path, files), VV_ERR_INVALID,
                  "object 1: a solid-texture volume without a file name", "saved.json", "solid");
    o->solid_texture.kind = VV_SOLID_TEXTURE_NONE;
    snprintf(o->name, sizeof o->name, "\xff\xfe");
    check_message(vv_scene_save(w, path, files), VV_ERR_INVALID, "object 1: ", "saved.json",
                  "UTF-8 name");
    snprintf(o->name, sizeof o->name, "v");
    check_message(vv_scene_save(w, vt_path(g_dir, "no/such/dir/s.json"), files), VV_ERR_IO, "scene",
                  "s.json", "folder");
    vt_ok(vv_scene_save(w, path, files));
    vv_world_free(w);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_refusals),    cmocka_unit_test(test_too_many),
        cmocka_unit_test(test_policy),      cmocka_unit_test(test_out_of_core),
        cmocka_unit_test(test_save_checks),
    };
    return vt_run_tests(tests, setup, NULL);
}
