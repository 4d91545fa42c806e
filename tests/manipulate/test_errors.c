/*
 * Every refusal of the animation reader (src/manipulate/animation_json.c,
 * "our own parsers under attack"): one hostile animation file per error,
 * each checked for its status, a phrase naming the field and the problem,
 * the file's name (every message starts with its path) and a message of one
 * printable line; the file missing, cut short, over its size, and saving
 * into a folder that is not there.
 */
#include "testutil.h"

#define check_message(st, want, needle, file, what) vt_expect_refusal(what, st, want, needle, file)

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define outdir() vt_outdir("animation_errors")

/* A track of @p prop with the keys @p keys, in an animation of 2 s. */
#define TRACK(prop, keys)                                                                          \
    "{\"duration\": 2, \"tracks\": [{\"property\": \"" prop "\", \"keys\": [" keys "]}]}"
#define EYE(k) TRACK("view.eye", k)
#define KEY0 "{\"time\": 0, \"value\": [0, 0, 1]}"
#define TF(tf) TRACK("objects[0].tf", "{\"time\": 0, \"value\": " tf "}")
#define ORI(v) TRACK("objects[0].orientation", "{\"time\": 0, \"value\": " v "}")
#define SEQ(s) "{\"duration\": 2, \"sequences\": [" s "]}"

static const struct {
    const char *text, *needle;
} cases[] = {
    /* the top level */
    {"[]", "expected an object at the top, got an array"},
    {"{\"tracks\": [], \"frames\": 3}", "frames: unknown key; expected one of: volvis_animation"},
    {"{\"volvis_animation\": 2}", "volvis_animation: unsupported version (this build reads 1)"},
    {"{\"volvis_animation\": \"1\"}", "volvis_animation: unsupported version"},
    {"{\"scene\": 5}", "scene: expected a file name, got a number"},
    {"{\"fps\": \"fast\"}", "fps: expected a number, got a string"},
    {"{\"fps\": 0}", "fps: 0 is outside (0, 1000]"},
    {"{\"tracks\": {}}", "tracks: expected an array, got an object"},
    {"{\"sequences\": 1}", "sequences: expected an array, got a number"},
    {"{\"tracks\": []}", "nothing to animate: no tracks and no sequences"},
    {"{\"duration\": true, \"sequences\": [{\"type\": \"orbit\"}]}",
     "duration: expected a number, got a boolean"},
    {"{\"duration\": -1, \"sequences\": [{\"type\": \"orbit\"}]}",
     "duration: -1 s must be > 0 and under 10^7 frames"},
    {"{\"duration\": 1e9, \"sequences\": [{\"type\": \"orbit\"}]}", "under 10^7 frames"},
    {"{\"sequences\": [{\"type\": \"orbit\"}]}", "missing key 'duration' (seconds)"},
    {"{\"tracks\": [{\"property\": \"view.fov\", \"keys\": [{\"time\": 0, \"value\": 30}]}]}",
     "missing key 'duration' (seconds): the keys do not give one"},
    /* tracks */
    {"{\"duration\": 2, \"tracks\": [3]}", "tracks[0]: expected a track object, got a number"},
    {"{\"duration\": 2, \"tracks\": [{\"property\": \"view.eye\", \"kyes\": []}]}",
     "tracks[0].kyes: unknown key; expected one of: property"},
    {"{\"duration\": 2, \"tracks\": [{\"keys\": []}]}", "tracks[0]: missing key 'property'"},
    {"{\"duration\": 2, \"tracks\": [{\"property\": 3, \"keys\": []}]}",
     "tracks[0].property: expected a string, got a number"},
    {TRACK("view.nose", KEY0), "tracks[0].property: unknown property 'view.nose'"},
    {"{\"duration\": 2, \"tracks\": [{\"property\": \"view.eye\", \"interpolation\": \"cubic\", "
     "\"keys\": [" KEY0 "]}]}",
     "tracks[0].interpolation: expected \"spline\", \"linear\" or \"step\""},
    {"{\"duration\": 2, \"tracks\": [{\"property\": \"objects[0].orientation\", "
     "\"interpolation\": 3, \"keys\": []}]}",
     "(or \"squad\", \"slerp\")"},
    {"{\"duration\": 2, \"tracks\": [{\"property\": \"view.eye\", \"closed\": 1, \"keys\": []}]}",
     "tracks[0].closed: expected true or false, got a number"},
    {"{\"duration\": 2, \"tracks\": [{\"property\": \"view.eye\"}]}",
     "tracks[0]: missing key 'keys' (track view.eye)"},
    {"{\"duration\": 2, \"tracks\": [{\"property\": \"view.eye\", \"keys\": {}}]}",
     "tracks[0].keys: expected an array of keys, got an object"},
    {EYE(""), "tracks[0].keys: no keys: track view.eye needs at least one"},
    /* keys */
    {EYE("5"), "tracks[0].keys[0]: expected a key {\"time\": ..., \"value\": ...}, got a number"},
    {EYE("{\"time\": 0, \"value\": [0, 0, 1], \"tension\": 0, \"speed\": 1}"),
     "tracks[0].keys[0].speed: unknown key; expected one of: time, value"},
    {EYE("{\"value\": [0, 0, 1]}"), "tracks[0].keys[0]: missing key 'time' (track view.eye)"},
    {EYE("{\"time\": 0}"), "tracks[0].keys[0]: missing key 'value'"},
    {EYE("{\"time\": \"0\", \"value\": [0, 0, 1]}"),
     "tracks[0].keys[0].time: expected a number, got a string"},
    {EYE(KEY0 ", " KEY0), "tracks[0].keys[1].time: time 0 is not after 0: keys out of order"},
    {EYE("{\"time\": 0, \"value\": [0, 0]}"),
     "tracks[0].keys[0].value: expected an array of 3 numbers, got an array of another length"},
    {EYE("{\"time\": 0, \"value\": [0, null, 0]}"),
     "tracks[0].keys[0].value[1]: expected a number, got null"},
    {TRACK("view.fov", "{\"time\": 0, \"value\": \"30\"}"),
     "tracks[0].keys[0].value: expected a number, got a string"},
    {EYE("{\"time\": 0, \"value\": [0, 0, 1], \"bias\": 2}"),
     "tracks[0].keys[0].bias: 2 is outside [-1, 1]"},
    {EYE("{\"time\": 0, \"value\": [0, 0, 1], \"tension\": \"x\"}"),
     "tracks[0].keys[0].tension: expected a number"},
    {EYE("{\"time\": 0, \"value\": [0, 0, 1], \"easing\": \"bounce\"}"),
     "tracks[0].keys[0].easing: expected \"linear\", \"ease-in\", \"ease-out\" or"},
    /* finite components whose norm overflows: normalised to zero, refused by the validation */
    {ORI("[1e308, 1e308, 1e308, 1e308]"),
     "tracks[0].keys[0]: the zero quaternion is not a rotation (track objects[0].orientation)"},
    /* orientations */
    {ORI("{\"axis\": [0, 0, 1], \"turns\": 1}"), "keys[0].value.turns: unknown key"},
    {ORI("{\"angle\": 5}"), "tracks[0].keys[0].value: missing key 'axis' ([x, y, z])"},
    {ORI("{\"axis\": [0, 0, 1], \"angle\": \"5\"}"), "keys[0].value.angle: expected a number"},
    {ORI("{\"axis\": [0, 0, 0], \"angle\": 5}"), "the rotation axis must be non-zero"},
    {ORI("{\"axis\": [0, 1], \"angle\": 5}"), "keys[0].value.axis: expected an array of 3"},
    {ORI("[1, 0, 0]"), "keys[0].value: expected an array of 4 numbers"},
    {ORI("[0, 0, 0, 0]"), "keys[0].value: the zero quaternion is not a rotation"},
    /* transfer functions */
    {TF("[1]"), "keys[0].value: expected a transfer function {\"opacity\""},
    {TF("{\"opacity\": [], \"colour\": []}"), "keys[0].value.colour: unknown key"},
    {TF("{\"color\": []}"), "keys[0].value: missing key 'opacity'"},
    {TF("{\"opacity\": 1}"), "keys[0].value.opacity: expected an array, got a number"},
    {TF("{\"opacity\": [1]}"), "keys[0].value.opacity[0]: expected a pair [value, opacity]"},
    {TF("{\"opacity\": [[\"a\", 1]]}"), "keys[0].value.opacity[0][0]: expected a number"},
    {TF("{\"opacity\": [[0, true]]}"), "keys[0].value.opacity[0][1]: expected a number"},
    {TF("{\"opacity\": [[0, 1.5]]}"), "keys[0].value.opacity[0][1]: opacity 1.5 is outside [0, 1]"},
    {TF("{\"opacity\": [], \"color\": [[0, [1, 1]]]}"),
     "keys[0].value.color[0][1]: expected an array of 3 numbers"},
    {TF("{\"opacity\": [], \"color\": [[0, [2, 1, 1]]]}"),
     "keys[0].value.color[0]: colour outside [0, 1]"},
    {TF("{\"opacity\": [], \"opacity_unit_distance\": 0}"),
     "keys[0].value: opacity_unit_distance 0 must be > 0"},
    {TF("{\"opacity\": [], \"opacity_unit_distance\": \"1\"}"),
     "keys[0].value.opacity_unit_distance: expected a number"},
    /* sequences */
    {SEQ("7"), "sequences[0]: expected a sequence object, got a number"},
    {SEQ("{\"type\": \"orbit\", \"speed\": 1}"), "sequences[0].speed: unknown key"},
    {SEQ("{\"type\": \"spin\"}"), "sequences[0]: 'type' must be \"orbit\", \"rotate_object\""},
    {SEQ("{\"type\": \"rotate_object\", \"object\": 3, \"axis\": [0, 0, 1]}"),
     "sequences[0]: 'object' must be an object name (a string)"},
    {SEQ("{\"type\": \"rotate_object\", \"object\": "
         "\"o234567890123456789012345678901234567890123456789012345678901234\", \"axis\": [0, 0, "
         "1]}"),
     "'object' must be an object name"},
    {SEQ("{\"type\": \"orbit\", \"zoom\": 0}"), "sequences[0]: orbit: zoom 0 must be > 0"},
    {SEQ("{\"type\": \"orbit\", \"degrees\": \"x\"}"), "sequences[0].degrees: expected a number"},
    {SEQ("{\"type\": \"rotate_object\", \"object\": \"o\"}"),
     "sequences[0]: missing key 'axis' ([x, y, z])"},
    {SEQ("{\"type\": \"fly\"}"), "sequences[0]: missing key 'offset'"},
    {SEQ("{\"type\": \"sweep_cut\", \"point\": [0, 0, 0]}"), "sequences[0]: missing key 'normal'"},
};

static void
test_refusals(void **state) {
    (void)state;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char name[64], what[128];
        snprintf(name, sizeof name, "anim%03zu.json", i);
        snprintf(what, sizeof what, "case %zu (%s)", i, cases[i].needle);
        const char *path = vt_path(outdir(), name);
        vt_write_file(path, cases[i].text, strlen(cases[i].text));
        vv_animation *a = (vv_animation *)1;
        vv_error_clear();
        vv_status st = vv_animation_load(&a, path);
        if (st == VV_OK)
            fail_msg("%s: the animation loaded", what);
        assert_null(a);
        check_message(st, VV_ERR_FORMAT, cases[i].needle, name, what);
        if (strncmp(vv_error_message(), path, strlen(path)) != 0)
            fail_msg("%s: message '%s' does not start with the path", what, vv_error_message());
    }
}

static void
test_files(void **state) {
    (void)state;
    vv_animation *a = NULL;
    check_message(vv_animation_load(&a, vt_path(outdir(), "absent.json")), VV_ERR_IO, "animation",
                  "absent.json", "missing");
    assert_null(a);
    const char *path = vt_path(outdir(), "cut.json");
    vt_write_file(path, "{\"tracks\": [", 12);
    check_message(vv_animation_load(&a, path), VV_ERR_FORMAT, "cut.json:1:", "cut.json", "cut");
    vt_write_file(path, "{\"fps\": 1, \"fps\": 2}", 20);
    check_message(vv_animation_load(&a, path), VV_ERR_FORMAT, "duplicate", "cut.json", "duplicate");
    assert_null(a);
    /* more than 256 opacity points */
    char *big = malloc(300 * 16 + 200);
    assert_non_null(big);
    strcpy(big, "{\"duration\": 2, \"tracks\": [{\"property\": \"objects[0].tf\", \"keys\": "
                "[{\"time\": 0, \"value\": {\"opacity\": [");
    for (int i = 0; i < 257; i++)
        sprintf(big + strlen(big), "%s[%d, 0]", i ? ", " : "", i);
    strcat(big, "]}}]}]}");
    path = vt_path(outdir(), "many.json");
    vt_write_file(path, big, strlen(big));
    free(big);
    check_message(vv_animation_load(&a, path), VV_ERR_FORMAT,
                  "keys[0].value.opacity: more than 256 points", "many.json", "points");
    /* saving into a folder that is not there */
    vv_animation *ok = NULL;
    vt_ok(vv_animation_new(&ok));
    check_message(vv_animation_save(ok, vt_path(outdir(), "no/such/dir/a.json")), VV_ERR_IO,
                  "animation", "a.json", "save");
    vv_animation_free(ok);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_files),
    };
    return vt_run_tests(tests, NULL, NULL);
}
