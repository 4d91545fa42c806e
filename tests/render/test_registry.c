/*
 * The renderer framework (src/render/registry.c, src/render/frame.c;
 * include/volvis/render.h, include/volvis/sys/renderer.h):
 * - every renderer's table: the interface version, an option table whose
 *   every entry has a key, a type and a default that its own validator
 *   accepts (and that setting it on a new renderer is accepted), the region
 *   capability exactly when a region method exists;
 * - options are data: every row binds to a field of the renderer's state
 *   (inside it, of the size its store kind writes, no two rows the same
 *   field); a new renderer's bound fields hold the parsed defaults, setting
 *   a default again changes no byte of the state, another value lands in
 *   its field and the default puts it back; a clone's fields are its
 *   original's; radiosity's defaults are vv_radiosity_options_init's;
 * - an unknown key, a bad value and a refused value (a hook's error) give
 *   the one-line errors they gave before the tables were bound, and leave
 *   the field as it was;
 * - `volvis renderers --json` lists the same tables (parsed with Jansson):
 *   names, types, defaults, capabilities;
 * - option validation: types, ranges with open and closed ends, words,
 *   enumerations, unknown keys, one-line messages naming key and value;
 * - what a renderer draws: a World of grids with raycast, a volume with
 *   irregular, iso with splat are errors naming the object and the
 *   renderers that draw it; a mixed World draws what it can;
 * - the default renderer of a World (vv_world_renderer);
 * - the frame runner: every pixel once, the same image for 1, 2 and 3
 *   threads, restricted rectangles, bands, progress from 0 to 1, cancel,
 *   a tile's error with its message;
 * - the camera rays agree with vv_view_ray (perspective and parallel);
 * - the region compositing operators.
 */
#include "testutil.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <turbojpeg.h>

#include "render/registry.h"
#include "volvis/radiosity.h"
#include "volvis/sys/renderer.h"

static void
test_tables(void **state) {
    (void)state;
    const vv_renderer_ops *const *reg = vv_renderer_registry();
    assert_int_equal(vv_renderer_count() > 0, 1);
    int n = 0;
    for (; reg[n]; n++) {
        const vv_renderer_ops *ops = reg[n];
        const vv_renderer_info *in = &ops->info;
        assert_int_equal(ops->version, VV_RENDERER_OPS_VERSION);
        assert_ptr_equal(vv_renderer_info_at(n), in);
        assert_ptr_equal(vv_renderer_info_find(in->name), in);
        assert_non_null(in->description);
        assert_non_null(in->quality);
        assert_true(in->draws != 0);
        assert_true(ops->state_size > 0 && ops->render);
        /* the region capability exactly when a region method exists */
        assert_int_equal((in->caps & VV_RENDERER_REGION) != 0, ops->render_region != NULL);
        vv_renderer *r = NULL;
        vt_ok(vv_renderer_new(&r, in->name));
        assert_ptr_equal(vv_renderer_get_info(r), in);
        for (int k = 0; k < in->n_options; k++) {
            const vv_option_spec *o = &in->options[k];
            assert_non_null(o->key);
            assert_non_null(o->def);
            assert_non_null(o->doc);
            assert_true(o->type >= VV_OPTION_BOOL && o->type <= VV_OPTION_STRING);
            if (o->type == VV_OPTION_ENUM)
                assert_non_null(o->words);
            /* keys are distinct */
            for (int j = 0; j < k; j++)
                assert_string_not_equal(in->options[j].key, o->key);
            /* the default passes its own validator and the renderer takes it
             * (fourier's empty vvc: no file) */
            vv_option_value v;
            vt_ok(vv_option_parse(o, o->def, &v));
            vt_ok(vv_renderer_info_check_option(in, o->key, o->def));
            vt_ok(vv_renderer_set_option(r, o->key, o->def));
        }
        vv_renderer_free(r);
    }
    assert_int_equal(n, vv_renderer_count());
    assert_null(vv_renderer_info_at(n));
    assert_null(vv_renderer_info_find("no-such-renderer"));
}

/* `volvis renderers --json`: the same tables. */
static void
test_cli_json(void **state) {
    (void)state;
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "%s renderers --json", getenv("VV_CLI"));
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    json_error_t e;
    json_t *root = json_loadf(p, 0, &e);
    assert_int_equal(pclose(p), 0);
    if (!root)
        fail_msg("volvis renderers --json: %s at %d:%d", e.text, e.line, e.column);
    json_t *list = json_object_get(root, "renderers");
    assert_true(json_is_array(list));
    assert_int_equal((int)json_array_size(list), vv_renderer_count());
    for (int i = 0; i < vv_renderer_count(); i++) {
        const vv_renderer_info *in = vv_renderer_info_at(i);
        json_t *r = json_array_get(list, (size_t)i);
        assert_string_equal(json_string_value(json_object_get(r, "name")), in->name);
        json_t *opts = json_object_get(r, "options");
        assert_int_equal((int)json_array_size(opts), in->n_options);
        const int region = (in->caps & VV_RENDERER_REGION) != 0;
        const int channels = (in->caps & VV_RENDERER_CHANNELS) != 0;
        int listed = 0, listed_ch = 0;
        json_t *caps = json_object_get(r, "capabilities");
        for (size_t c = 0; c < json_array_size(caps); c++) {
            listed |= strcmp(json_string_value(json_array_get(caps, c)), "region") == 0;
            listed_ch |= strcmp(json_string_value(json_array_get(caps, c)), "channels") == 0;
        }
        assert_int_equal(listed, region);
        assert_int_equal(listed_ch, channels);
        for (int k = 0; k < in->n_options; k++) {
            json_t *o = json_array_get(opts, (size_t)k);
            const char *key = json_string_value(json_object_get(o, "key"));
            const char *type = json_string_value(json_object_get(o, "type"));
            const char *def = json_string_value(json_object_get(o, "default"));
            assert_non_null(key);
            assert_non_null(type);
            assert_non_null(def);
            assert_string_equal(key, in->options[k].key);
            assert_string_equal(type, vv_option_type_name(in->options[k].type));
            /* the default the JSON gives passes the option's validator */
            vt_ok(vv_renderer_info_check_option(in, key, def));
        }
    }
    json_decref(root);
}

static void
expect_invalid(const char *renderer, const char *key, const char *value, const char *says) {
    const vv_renderer_info *in = vv_renderer_info_find(renderer);
    vv_error_clear();
    vv_status s = vv_renderer_info_check_option(in, key, value);
    if (s != VV_ERR_INVALID)
        fail_msg("%s %s=%s: got %s", renderer, key, value, vv_status_name(s));
    const char *m = vv_error_message();
    if (!strstr(m, says) || strchr(m, '\n'))
        fail_msg("%s %s=%s: message '%s' does not say '%s' on one line", renderer, key, value, m,
                 says);
}

static void
test_validation(void **state) {
    (void)state;
    /* open and closed ends */
    expect_invalid("raycast", "early_termination", "0", "is not real in (0, 1]");
    vt_ok(
        vv_renderer_info_check_option(vv_renderer_info_find("raycast"), "early_termination", "1"));
    expect_invalid("raycast", "early_termination", "1.0001", "(0, 1]");
    expect_invalid("raycast", "early_termination", "nan", "early_termination: 'nan'");
    expect_invalid("raycast", "early_termination", "0.5x", "'0.5x'");
    expect_invalid("raycast", "early_termination", "", "''");
    expect_invalid("radiosity", "tolerance", "1", "(0, 1)");
    /* integers */
    expect_invalid("raytrace", "samples", "17", "integer in 1..16");
    expect_invalid("raytrace", "samples", "2.5", "'2.5'");
    expect_invalid("raytrace", "max_depth", "-1", "0..64");
    /* booleans: 0 or 1 */
    expect_invalid("raytrace", "shadows", "yes", "0|1");
    /* words beside numbers */
    vt_ok(vv_renderer_info_check_option(vv_renderer_info_find("raycast"), "gradient_budget_mb",
                                        "auto"));
    expect_invalid("raycast", "gradient_budget_mb", "-1", "or auto");
    vt_ok(vv_renderer_info_check_option(vv_renderer_info_find("fourier"), "quality", "exact"));
    vt_ok(vv_renderer_info_check_option(vv_renderer_info_find("fourier"), "quality", "75"));
    /* enumerations */
    expect_invalid("raster", "shading", "smooth", "one of flat|gouraud|phong");
    expect_invalid("splat", "classification", "both", "post|pre");
    expect_invalid("fourier", "block", "12", "8|16|32");
    /* unknown keys list the known ones */
    expect_invalid("irregular", "samples", "2", "early_termination, empty_space_skipping");
    /* through a renderer: the same check, prefixed with its name */
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raytrace"));
    assert_int_equal(vv_renderer_set_option(r, "samples", "0"), VV_ERR_INVALID);
    assert_non_null(strstr(vv_error_message(), "raytrace: samples: '0'"));
    vt_ok(vv_renderer_set_option(r, "samples", "3"));
    vv_renderer_free(r);
    char buf[128];
    const vv_option_spec *o = vv_renderer_info_option(vv_renderer_info_find("splat"), "radius");
    assert_string_equal(vv_option_describe(o, buf, sizeof buf), "real in (0, 8]");
}

/* ---- options are data: the bindings ------------------------------------------- */

/* The bytes the binding of @p o stores for @p text into @p buf (this
 * test's own reading of vv_option_binding); 0 when it stores nothing (a
 * word left to the hook, or no field). */
static int
expected_field(const vv_option_spec *o, const char *text, unsigned char *buf) {
    const vv_option_binding *b = o->bind;
    vv_option_value v;
    vt_ok(vv_option_parse(o, text, &v));
    const int word = v.word >= 0;
    if (b->store == VV_OPTION_STORE_NONE ||
        (word && !b->word_values && b->store != VV_OPTION_STORE_INT))
        return 0;
    const double x = word && b->word_values      ? b->word_values[v.word]
                     : o->type == VV_OPTION_BOOL ? v.b
                                                 : v.r;
    switch (b->store) {
    case VV_OPTION_STORE_DOUBLE: {
        const double d = x * b->scale;
        memcpy(buf, &d, sizeof d);
        return 1;
    }
    case VV_OPTION_STORE_FLOAT: {
        const float f = (float)(x * b->scale);
        memcpy(buf, &f, sizeof f);
        return 1;
    }
    case VV_OPTION_STORE_INT: {
        const int i = word ? (b->word_values ? (int)b->word_values[v.word] : v.word) : (int)v.i;
        memcpy(buf, &i, sizeof i);
        return 1;
    }
    case VV_OPTION_STORE_UINT64: {
        const uint64_t u = (uint64_t)(x * b->scale);
        memcpy(buf, &u, sizeof u);
        return 1;
    }
    case VV_OPTION_STORE_CHARS:
        memset(buf, 0, b->size);
        memcpy(buf, text, strlen(text));
        return 1;
    default:
        fail_msg("%s: store kind %d", o->key, (int)b->store);
    }
    return 0;
}

/* A valid value of @p o other than its default, into buf; 0 when there is
 * none to try (a string: a file name). */
static int
other_value(const vv_option_spec *o, char *buf, size_t cap) {
    switch (o->type) {
    case VV_OPTION_BOOL:
        snprintf(buf, cap, "%s", strcmp(o->def, "1") == 0 ? "0" : "1");
        break;
    case VV_OPTION_INT:
        snprintf(buf, cap, "%.17g", strtod(o->def, NULL) != o->min ? o->min : o->max);
        break;
    case VV_OPTION_REAL:
        snprintf(buf, cap, "%.17g", o->max == INFINITY ? o->min + 1 : (o->min + o->max) / 2);
        break;
    case VV_OPTION_ENUM:
        snprintf(buf, cap, "%s", strcmp(o->def, o->words[0]) == 0 ? o->words[1] : o->words[0]);
        break;
    case VV_OPTION_STRING:
        return 0;
    }
    vv_option_value v;
    vt_ok(vv_option_parse(o, buf, &v));
    assert_string_not_equal(buf, o->def);
    return 1;
}

/* The binding of row @p o of @p ops agrees with the row and the state. */
static void
check_binding(const vv_renderer_ops *ops, const vv_option_spec *o) {
    const vv_option_binding *b = o->bind;
    const char *name = ops->info.name;
    if (!b)
        fail_msg("%s %s: no binding", name, o->key);
    assert_true(b->scale > 0);
    int nw = 0;
    while (o->words && o->words[nw])
        nw++;
    size_t size = 0;
    int ok = 0;
    switch (b->store) {
    case VV_OPTION_STORE_NONE:
        ok = b->hook != NULL;
        break;
    case VV_OPTION_STORE_DOUBLE:
        size = sizeof(double);
        ok = o->type != VV_OPTION_STRING && (o->type != VV_OPTION_ENUM || b->word_values);
        break;
    case VV_OPTION_STORE_FLOAT:
        size = sizeof(float);
        ok = o->type != VV_OPTION_STRING && (o->type != VV_OPTION_ENUM || b->word_values);
        break;
    case VV_OPTION_STORE_INT:
        size = sizeof(int);
        ok = o->type != VV_OPTION_STRING && o->type != VV_OPTION_REAL && b->scale == 1;
        break;
    case VV_OPTION_STORE_UINT64:
        size = sizeof(uint64_t);
        ok = (o->type == VV_OPTION_INT || o->type == VV_OPTION_REAL) && o->min >= 0;
        break;
    case VV_OPTION_STORE_CHARS:
        size = b->size;
        ok = o->type == VV_OPTION_STRING && b->size >= VV_RENDER_OPTION_VALUE_MAX && b->scale == 1;
        break;
    }
    if (!ok)
        fail_msg("%s %s: a %s option cannot be stored as kind %d", name, o->key,
                 vv_option_type_name(o->type), (int)b->store);
    if (b->store != VV_OPTION_STORE_NONE &&
        (b->size != size || b->offset + b->size > ops->state_size))
        fail_msg("%s %s: field of %zu bytes at %zu (kind %d: %zu bytes; state %zu)", name, o->key,
                 b->size, b->offset, (int)b->store, size, ops->state_size);
    /* word values: one per word, and only where there are words */
    if (b->word_values && !nw)
        fail_msg("%s %s: word values without words", name, o->key);
    /* a number's word without a value of its own is the hook's */
    if (nw && !b->word_values && o->type != VV_OPTION_ENUM && !b->hook)
        fail_msg("%s %s: its words store nothing and no hook takes them", name, o->key);
}

/* 1 when rows @p a and @p b bind overlapping bytes. */
static int
overlap(const vv_option_binding *a, const vv_option_binding *b) {
    if (a->store == VV_OPTION_STORE_NONE || b->store == VV_OPTION_STORE_NONE)
        return 0;
    return a->offset < b->offset + b->size && b->offset < a->offset + a->size;
}

/* Compares the field of @p o in two states. */
static void
expect_field(const vv_option_spec *o, const unsigned char *st, const unsigned char *want,
             const char *what, const char *value) {
    const vv_option_binding *b = o->bind;
    if (memcmp(st + b->offset, want, b->size) != 0)
        fail_msg("%s=%s: the field is not %s", o->key, value, what);
}

static void
test_bindings(void **state) {
    (void)state;
    const vv_renderer_ops *const *reg = vv_renderer_registry();
    for (int n = 0; reg[n]; n++) {
        const vv_renderer_ops *ops = reg[n];
        const vv_renderer_info *in = &ops->info;
        for (int k = 0; k < in->n_options; k++) {
            check_binding(ops, &in->options[k]);
            for (int j = 0; j < k; j++)
                if (overlap(in->options[j].bind, in->options[k].bind))
                    fail_msg("%s: %s and %s bind the same bytes", in->name, in->options[j].key,
                             in->options[k].key);
        }
        vv_renderer *r = NULL;
        vt_ok(vv_renderer_new(&r, in->name));
        unsigned char *st = vv_renderer_state(r);
        unsigned char *fresh = malloc(ops->state_size);
        assert_non_null(fresh);
        memcpy(fresh, st, ops->state_size);
        unsigned char want[VV_RENDER_OPTION_VALUE_MAX + 64];
        /* a new renderer's fields hold the parsed defaults */
        for (int k = 0; k < in->n_options; k++) {
            const vv_option_spec *o = &in->options[k];
            assert_true(o->bind->size <= sizeof want);
            if (expected_field(o, o->def, want))
                expect_field(o, st, want, "the default's", o->def);
        }
        /* the default set again changes no byte of the state */
        for (int k = 0; k < in->n_options; k++)
            vt_ok(vv_renderer_set_option(r, in->options[k].key, in->options[k].def));
        for (size_t i = 0; i < ops->state_size; i++)
            if (st[i] != fresh[i])
                fail_msg("%s: setting the defaults changed byte %zu of the state", in->name, i);
        /* another value lands in its field; the default puts it back */
        for (int k = 0; k < in->n_options; k++) {
            const vv_option_spec *o = &in->options[k];
            char other[64];
            if (!other_value(o, other, sizeof other))
                continue;
            vt_ok(vv_renderer_set_option(r, o->key, other));
            if (expected_field(o, other, want))
                expect_field(o, st, want, "the value's", other);
            vt_ok(vv_renderer_set_option(r, o->key, o->def));
            expect_field(o, st, fresh + o->bind->offset, "the default's again", o->def);
        }
        if (memcmp(st, fresh, ops->state_size) != 0)
            fail_msg("%s: the defaults again do not give a new renderer's state", in->name);
        free(fresh);
        vv_renderer_free(r);
    }
}

/* vv_renderer_clone: the options set so far, in the clone's fields. */
static void
test_clone_fields(void **state) {
    (void)state;
    for (int n = 0; n < vv_renderer_count(); n++) {
        const vv_renderer_info *in = vv_renderer_info_at(n);
        vv_renderer *r = NULL, *c = NULL;
        vt_ok(vv_renderer_new(&r, in->name));
        for (int k = 0; k < in->n_options; k++) {
            char other[64];
            if (other_value(&in->options[k], other, sizeof other))
                vt_ok(vv_renderer_set_option(r, in->options[k].key, other));
        }
        vt_ok(vv_renderer_clone(&c, r));
        const unsigned char *a = vv_renderer_state(r), *b = vv_renderer_state(c);
        for (int k = 0; k < in->n_options; k++) {
            const vv_option_binding *bd = in->options[k].bind;
            if (bd->store != VV_OPTION_STORE_NONE &&
                memcmp(a + bd->offset, b + bd->offset, bd->size) != 0)
                fail_msg("%s clone: option %s differs", in->name, in->options[k].key);
        }
        vv_renderer_free(c);
        vv_renderer_free(r);
    }
}

/* The radiosity renderer's defaults (its table) are the solver's own. */
static void
test_radiosity_defaults(void **state) {
    (void)state;
    const vv_renderer_info *in = vv_renderer_info_find("radiosity");
    const vv_option_spec *tol = vv_renderer_info_option(in, "tolerance");
    assert_non_null(tol);
    /* the rows bind into a vv_radiosity_options member of the state */
    const size_t at = tol->bind->offset - offsetof(vv_radiosity_options, tolerance);
    vv_radiosity_options want;
    vv_radiosity_options_init(&want);
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "radiosity"));
    const unsigned char *st = vv_renderer_state(r);
    assert_memory_equal(st + at, &want, sizeof want);
    vv_renderer_free(r);
}

/* Expects vv_renderer_set_option(r, key, value) to fail with exactly @p says. */
static void
expect_refused(vv_renderer *r, const char *key, const char *value, vv_status status,
               const char *says) {
    vv_error_clear();
    assert_int_equal(vv_renderer_set_option(r, key, value), status);
    assert_string_equal(vv_error_message(), says);
}

/* Unknown keys, bad values and values a hook refuses: the one-line errors
 * of before, and nothing changed. */
static void
test_option_errors(void **state) {
    (void)state;
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    expect_refused(r, "no_such", "1", VV_ERR_INVALID,
                   "raycast: unknown option 'no_such' (early_termination, gradient_budget_mb, "
                   "empty_space_skipping, simd, refinement, refinement_tolerance, "
                   "preintegration, shading)");
    expect_refused(r, "early_termination", "2", VV_ERR_INVALID,
                   "raycast: early_termination: '2' is not real in (0, 1]");
    expect_refused(r, "refinement", "sometimes", VV_ERR_INVALID,
                   "raycast: refinement: 'sometimes' is not one of auto|on|off");
    expect_refused(r, "gradient_budget_mb", "-1", VV_ERR_INVALID,
                   "raycast: gradient_budget_mb: '-1' is not real >= 0 or auto");
    vv_renderer_free(r);
    vt_ok(vv_renderer_new(&r, "irregular"));
    expect_refused(r, "samples", "2", VV_ERR_INVALID,
                   "irregular: unknown option 'samples' (early_termination, "
                   "empty_space_skipping)");
    vv_renderer_free(r);

    /* a hook's refusal: the field keeps its value */
    vt_ok(vv_renderer_new(&r, "splat"));
    const vv_option_spec *o = vv_renderer_info_option(vv_renderer_get_info(r), "sheet_spacing");
    const unsigned char *st = vv_renderer_state(r);
    vt_ok(vv_renderer_set_option(r, "sheet_spacing", "2"));
    double was, now;
    memcpy(&was, st + o->bind->offset, sizeof was);
    assert_true(was == 2);
    expect_refused(r, "sheet_spacing", "0.1", VV_ERR_INVALID,
                   "splat: sheet_spacing must be 0 (by quality) or in [0.25, 8] steps");
    memcpy(&now, st + o->bind->offset, sizeof now);
    assert_true(now == 2);
    vv_renderer_free(r);

    vt_ok(vv_renderer_new(&r, "fourier"));
    o = vv_renderer_info_option(vv_renderer_get_info(r), "vvc");
    st = vv_renderer_state(r);
    vv_error_clear();
    assert_int_equal(vv_renderer_set_option(r, "vvc", "/nonexistent.vvc"), VV_ERR_IO);
    assert_non_null(strstr(vv_error_message(), "fourier: vvc: /nonexistent.vvc: "));
    assert_null(strchr(vv_error_message(), '\n'));
    assert_int_equal(st[o->bind->offset], 0); /* still none */
    /* a clone re-applies only what was accepted */
    vv_renderer *c = NULL;
    vt_ok(vv_renderer_clone(&c, r));
    vv_renderer_free(c);
    vv_renderer_free(r);
}

/* A World of one volume (neghip-like sphere), one grid, or both. */
static vv_world *
world_of(int volume, int grid, int plane) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    if (volume) {
        const int dims[3] = {16, 16, 16};
        vv_volume *v = NULL;
        vt_ok(vv_volume_new(&v, dims, VV_U8));
        for (int k = 0; k < 16; k++)
            for (int j = 0; j < 16; j++)
                for (int i = 0; i < 16; i++)
                    ((uint8_t *)v->data)[(k * 16 + j) * 16 + i] =
                        (uint8_t)(255 * (((i - 8) * (i - 8) + (j - 8) * (j - 8) +
                                          (k - 8) * (k - 8)) < 30));
        vv_volume_update_range(v);
        vv_object *o = NULL;
        vt_ok(vv_object_new_volume(&o, v, "head"));
        vv_volume_free(v);
        vt_ok(vv_world_add_object(w, o));
    }
    if (grid) {
        vv_grid *g = NULL;
        vt_ok(vv_grid_load(&g, vt_data("grids/fire_ug.vtu")));
        vv_world *gw = NULL;
        vt_ok(vv_world_new_for_grid(&gw, g, NULL, 0, NULL));
        vv_grid_free(g);
        vv_object *o = NULL;
        vt_ok(vv_object_clone(&o, gw->objects[0]));
        snprintf(o->name, sizeof o->name, "fire");
        vv_world_free(gw);
        vt_ok(vv_world_add_object(w, o));
    }
    if (plane) {
        vv_object *o = NULL;
        vt_ok(vv_object_new_geometry(&o, VV_OBJECT_PLANE, "floor"));
        o->geometry.normal = vv_vec3_make(0, 0, 1);
        vt_ok(vv_world_add_object(w, o));
    }
    return w;
}

static void
test_world_checks(void **state) {
    (void)state;
    vv_world *g = world_of(0, 1, 0), *v = world_of(1, 0, 0), *vp = world_of(1, 0, 1),
             *vg = world_of(1, 1, 0), *e = world_of(0, 0, 0);
    /* grids only: raycast draws nothing of it */
    assert_int_equal(vv_renderer_check_world(vv_renderer_info_find("raycast"), g),
                     VV_ERR_UNSUPPORTED);
    const char *m = vv_error_message();
    assert_non_null(strstr(m, "object 'fire' is a grid object, which raycast does not draw"));
    assert_non_null(strstr(m, "drawn by irregular, raster"));
    /* a volume: irregular draws nothing of it */
    assert_int_equal(vv_renderer_check_world(vv_renderer_info_find("irregular"), v),
                     VV_ERR_UNSUPPORTED);
    assert_non_null(strstr(vv_error_message(), "object 'head' is a volume object"));
    /* a mode the renderer does not draw */
    v->objects[0]->mode = VV_MODE_ISO;
    assert_int_equal(vv_renderer_check_world(vv_renderer_info_find("splat"), v),
                     VV_ERR_UNSUPPORTED);
    assert_non_null(strstr(vv_error_message(), "object 'head': iso mode is not drawn by splat"));
    v->objects[0]->mode = VV_MODE_COMPOSITE;
    /* a mixed World: what it can (the plane is left out) */
    vt_ok(vv_renderer_check_world(vv_renderer_info_find("raycast"), vp));
    vt_ok(vv_renderer_check_world(vv_renderer_info_find("raycast"), e));
    /* and through vv_renderer_render: an error, not a blank image */
    vv_renderer *r = NULL;
    vv_image *img = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    vt_ok(vv_image_new(&img, g->view.width, g->view.height));
    assert_int_equal(vv_renderer_render(r, g, &g->view, NULL, img), VV_ERR_UNSUPPORTED);
    assert_non_null(strstr(vv_error_message(), "raycast: object 'fire'"));
    vv_image_free(img);
    vv_renderer_free(r);
    /* the default renderer */
    assert_string_equal(vv_world_renderer(v), "raycast");
    assert_string_equal(vv_world_renderer(g), "irregular");
    assert_string_equal(vv_world_renderer(vp), "raytrace");
    assert_string_equal(vv_world_renderer(vg), "raster");
    assert_string_equal(vv_world_renderer(e), "raycast");
    snprintf(vp->render.renderer, sizeof vp->render.renderer, "splat");
    assert_string_equal(vv_world_renderer(vp), "splat");
    /* a method's old name: "surface" is the raster renderer */
    snprintf(vp->render.renderer, sizeof vp->render.renderer, "surface");
    assert_string_equal(vv_world_renderer(vp), "raster");
    snprintf(vp->render.renderer, sizeof vp->render.renderer, "splat");
    assert_string_equal(vv_renderer_info_find("surface")->name, "raster");
    vv_renderer *d = NULL;
    vt_ok(vv_renderer_new_for_world(&d, g));
    assert_string_equal(vv_renderer_name(d), "irregular");
    vv_renderer_free(d);
    vv_world_free(g);
    vv_world_free(v);
    vv_world_free(vp);
    vv_world_free(vg);
    vv_world_free(e);
}

/* ---- the frame runner --------------------------------------------------- */

typedef struct paint {
    vv_image *img;
    int *count;  /* per pixel */
    int fail_at; /* tile index that fails, or -1 */
} paint;

static vv_status
paint_tile(void *user, const vv_frame_tile *t) {
    paint *p = user;
    if (t->index == p->fail_at)
        return vv_error_set(VV_ERR_IO, "tile %d could not read its data", t->index);
    assert_non_null(t->scratch);
    for (int y = t->y0; y < t->y1; y++)
        for (int x = t->x0; x < t->x1; x++) {
            const size_t i = (size_t)y * (size_t)p->img->width + (size_t)x;
            p->img->rgba[4 * i] = (float)sin(0.1 * x + 0.07 * y * y);
            __atomic_add_fetch(&p->count[i], 1, __ATOMIC_RELAXED);
        }
    return VV_OK;
}

typedef struct prog {
    double last;
    int calls, cancel_after;
} prog;

static int
on_progress(void *user, double f) {
    prog *p = user;
    assert_true(f >= p->last && f <= 1.0);
    p->last = f;
    p->calls++;
    return p->cancel_after > 0 && p->calls >= p->cancel_after;
}

static void
test_frame_runner(void **state) {
    (void)state;
    const int W = 83, H = 61;
    vv_image *ref = NULL;
    for (int threads = 1; threads <= 3; threads++) {
        vv_image *img = NULL;
        vt_ok(vv_image_new(&img, W, H));
        int *count = calloc((size_t)W * H, sizeof *count);
        paint p = {img, count, -1};
        vv_frame_job job;
        vv_frame_job_init(&job, W, H, paint_tile, &p);
        job.scratch_bytes = 100;
        vv_render_options o;
        vv_render_options_init(&o);
        o.threads = threads;
        prog pr = {0, 0, 0};
        o.progress.fn = on_progress;
        o.progress.user = &pr;
        vt_ok(vv_frame_run(&job, &o));
        assert_true(pr.last == 1.0);
        assert_int_equal(pr.calls, ((W + 15) / 16) * ((H + 15) / 16));
        for (int i = 0; i < W * H; i++)
            assert_int_equal(count[i], 1);
        if (!ref)
            ref = img;
        else
            assert_memory_equal(ref->rgba, img->rgba, sizeof(float) * 4 * W * H);
        /* a rectangle and bands of rows: only those pixels, once */
        memset(count, 0, sizeof(int) * (size_t)W * H);
        job.x0 = 10;
        job.y0 = 5;
        job.x1 = 50;
        job.y1 = 40;
        job.tile = W;
        job.tile_h = 7;
        pr = (prog){0, 0, 0};
        vt_ok(vv_frame_run(&job, &o));
        assert_true(pr.last == 1.0);
        assert_int_equal(pr.calls, (H + 6) / 7);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                assert_int_equal(count[y * W + x], x >= 10 && x < 50 && y >= 5 && y < 40);
        /* cancel after the second tile; an error in a tile with its message */
        vv_frame_job_init(&job, W, H, paint_tile, &p);
        job.scratch_bytes = 100;
        pr = (prog){0, 0, 2};
        assert_int_equal(vv_frame_run(&job, &o), VV_ERR_CANCELLED);
        pr = (prog){0, 0, 0};
        p.fail_at = 3;
        assert_int_equal(vv_frame_run(&job, &o), VV_ERR_IO);
        assert_non_null(strstr(vv_error_message(), "tile 3 could not read its data"));
        free(count);
        if (img != ref)
            vv_image_free(img);
    }
    vv_image_free(ref);
}

static void
test_camera_rays(void **state) {
    (void)state;
    vv_view v;
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    v = w->view;
    v.width = 97;
    v.height = 55;
    v.eye = vv_vec3_make(10, -300, 40);
    v.at = vv_vec3_make(-3, 2, 5);
    for (int ortho = 0; ortho < 2; ortho++) {
        v.projection = ortho ? VV_PROJECTION_ORTHOGRAPHIC : VV_PROJECTION_PERSPECTIVE;
        vv_camera_rays c;
        vv_camera_rays_init(&c, &v);
        assert_int_equal(c.ortho, ortho);
        const double px[4][2] = {{0, 0}, {96, 54}, {13.25, 40.5}, {50, 0}};
        for (int i = 0; i < 4; i++) {
            const vv_ray a = vv_camera_ray(&c, px[i][0], px[i][1]);
            const vv_ray b = vv_view_ray(&v, px[i][0], px[i][1]);
            assert_true(fabs(a.origin.x - b.origin.x) < 1e-9 &&
                        fabs(a.origin.y - b.origin.y) < 1e-9 &&
                        fabs(a.origin.z - b.origin.z) < 1e-9);
            assert_true(fabs(a.dir.x - b.dir.x) < 1e-12 && fabs(a.dir.y - b.dir.y) < 1e-12 &&
                        fabs(a.dir.z - b.dir.z) < 1e-12);
        }
    }
    vv_world_free(w);
}

static void
test_region_ops(void **state) {
    (void)state;
    /* over: front 0.5 opaque red over back green */
    float f[4] = {0.5f, 0, 0, 0.5f}, b[4] = {0, 0.8f, 0, 0.8f};
    float fd = 3, fk = NAN;
    vv_region_pixel_combine(VV_REGION_OVER, f, &fd, &fk, b, 7, NAN);
    assert_true(f[0] == 0.5f && fabsf(f[1] - 0.4f) < 1e-7f && fabsf(f[3] - 0.9f) < 1e-7f);
    assert_true(fd == 3);
    /* max: the larger key wins, ties keep the front */
    float m[4] = {1, 1, 1, 1}, n[4] = {2, 2, 2, 2};
    float md = 5, mk = 10;
    vv_region_pixel_combine(VV_REGION_MAX, m, &md, &mk, n, 9, 10);
    assert_true(m[0] == 1 && md == 5 && mk == 10);
    vv_region_pixel_combine(VV_REGION_MAX, m, &md, &mk, n, 9, 11);
    assert_true(m[0] == 2 && md == 9 && mk == 11);
    vv_region_pixel_combine(VV_REGION_MIN, m, &md, &mk, n, 9, NAN); /* nothing behind */
    assert_true(mk == 11);
    float z[4] = {0, 0, 0, 0}, zd = INFINITY, zk = NAN;
    vv_region_pixel_combine(VV_REGION_MIN, z, &zd, &zk, n, 4, 3); /* nothing in front */
    assert_true(zk == 3 && zd == 4 && z[0] == 2);
    /* attenuated max, napari's formula on one ray of three samples, values
     * 50, 200, 120 (real), normalised 0.25, 1, 0.6, k = 0.5: the whole ray's
     * maximum of v exp(k - E) against the front sample alone combined with
     * the back two, and the back two split again (associativity) */
    const double k = 0.5, v[3] = {50, 200, 120}, nv[3] = {0.25, 1, 0.6};
    double E = 0, want = -INFINITY;
    int at = -1;
    for (int i = 0; i < 3; i++) {
        E += k * nv[i];
        const double x = v[i] * exp(k - E);
        if (x > want) {
            want = x;
            at = i;
        }
    }
    float parts[3][4], pd[3], pk[3];
    for (int i = 0; i < 3; i++) { /* each sample a region of its own */
        parts[i][0] = (float)(k * nv[i]);
        parts[i][1] = parts[i][2] = parts[i][3] = 0;
        pd[i] = (float)(10 + i);
        pk[i] = (float)(v[i] * exp(k - k * nv[i]));
    }
    /* ((0, 1), 2) and (0, (1, 2)) */
    float a[4], ad = pd[0], ak = pk[0], c[4], cd = pd[1], ck = pk[1];
    memcpy(a, parts[0], sizeof a);
    memcpy(c, parts[1], sizeof c);
    vv_region_pixel_combine(VV_REGION_ATTENUATED_MAX, a, &ad, &ak, parts[1], pd[1], pk[1]);
    vv_region_pixel_combine(VV_REGION_ATTENUATED_MAX, a, &ad, &ak, parts[2], pd[2], pk[2]);
    vv_region_pixel_combine(VV_REGION_ATTENUATED_MAX, c, &cd, &ck, parts[2], pd[2], pk[2]);
    float g[4], gd = pd[0], gk = pk[0];
    memcpy(g, parts[0], sizeof g);
    vv_region_pixel_combine(VV_REGION_ATTENUATED_MAX, g, &gd, &gk, c, cd, ck);
    assert_int_equal(at, 1); /* the bright middle sample wins, scaled */
    assert_true(fabs(ak - want) < 1e-4 * want && fabs(gk - want) < 1e-4 * want);
    assert_true(ad == 11 && gd == 11);
    assert_true(fabsf(a[0] - (float)E) < 1e-6f && fabsf(g[0] - (float)E) < 1e-6f);
    /* nothing behind, or nothing in front */
    float h[4] = {0.3f, 0, 0, 0}, hd = 2, hk = 7;
    vv_region_pixel_combine(VV_REGION_ATTENUATED_MAX, h, &hd, &hk, z, 1, NAN);
    assert_true(hk == 7 && hd == 2 && h[0] == 0.3f);
    float e0[4] = {0, 0, 0, 0}, ed = INFINITY, ek = NAN;
    vv_region_pixel_combine(VV_REGION_ATTENUATED_MAX, e0, &ed, &ek, h, hd, hk);
    assert_true(ek == 7 && ed == 2 && e0[0] == 0.3f);
}

/* vv_renderer_ops.stand_in: a method that names another draws the frame
 * with it, from the World it hands over; one that names itself is refused. */
typedef struct {
    double unused;
} standin_state;

static const char *standin_target;

static vv_status
standin_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
               vv_image *out) {
    (void)state, (void)w, (void)view, (void)opt, (void)out;
    return vv_error_set(VV_ERR_INVALID, "render called: the stand-in was not used");
}

static vv_status
standin_hook(void *state, const vv_world *w, const vv_render_options *opt, const char **stand_in,
             const vv_world **draw) {
    (void)state, (void)opt;
    *stand_in = standin_target;
    *draw = w;
    return VV_OK;
}

static const vv_renderer_ops standin_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info = {.name = "test_standin",
             .description = "draws every frame by another method",
             .draws = VV_DRAWS(VV_OBJECT_VOLUME),
             .modes = VV_MODES_ALL},
    .state_size = sizeof(standin_state),
    .render = standin_render,
    .stand_in = standin_hook,
};

static void
test_stand_in(void **state) {
    (void)state;
    vt_ok(vv_renderer_register(&standin_ops));
    vv_volume *v = NULL;
    const int dims[3] = {12, 10, 8};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    unsigned char *d = v->data;
    for (size_t i = 0; i < 12 * 10 * 8; i++)
        d[i] = (unsigned char)((i * 37u) % 251u);
    vv_volume_update_range(v);
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.mode = VV_MODE_MIP;
    o.width = 40;
    o.height = 32;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &o));
    vv_image *a = NULL, *b = NULL;
    vt_ok(vv_image_new(&a, 40, 32));
    vt_ok(vv_image_new(&b, 40, 32));
    vv_renderer *ray = NULL, *sub = NULL;
    vt_ok(vv_renderer_new(&ray, "raycast"));
    vt_ok(vv_renderer_new(&sub, "test_standin"));
    vt_ok(vv_renderer_render(ray, w, &w->view, NULL, a));
    standin_target = "raycast";
    vt_ok(vv_renderer_render(sub, w, &w->view, NULL, b));
    assert_memory_equal(a->rgba, b->rgba, sizeof(float) * 4 * 40 * 32);
    standin_target = "test_standin";
    assert_int_equal(vv_renderer_render(sub, w, &w->view, NULL, b), VV_ERR_INVALID);
    assert_non_null(strstr(vv_error_message(), "stands in for itself"));
    standin_target = "no_such_method";
    assert_int_not_equal(vv_renderer_render(sub, w, &w->view, NULL, b), VV_OK);
    vv_renderer_free(ray);
    vv_renderer_free(sub);
    vv_image_free(a);
    vv_image_free(b);
    vv_world_free(w);
    vv_volume_free(v);
}

/* The frame in 8 bits (vv_pixels8): the ray caster's tiles convert what they
 * drew, other methods' frames are converted after them; either way the
 * bytes are the float frame's, rounded half up. */
static void
expect_rgbx(const vv_image *img, const uint8_t *rgbx) {
    for (size_t i = 0; i < 4 * (size_t)img->width * img->height; i++) {
        float v = img->rgba[i];
        int want = v <= 0 ? 0 : v >= 1 ? 255 : (int)floorf(v * 255.0f + 0.5f);
        if (rgbx[i] != want)
            fail_msg("byte %zu: %d, want %d (%.6f)", i, rgbx[i], want, v);
    }
}

/* The 8-bit frames' volume: a ball of 24 x 20 x 16 u8 voxels, 250 at its
 * centre falling to 0 at radius 9 (the caller frees it). */
static vv_volume *
pixels8_ball(void) {
    vv_volume *v = NULL;
    const int dims[3] = {24, 20, 16};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    unsigned char *d = v->data;
    for (int k = 0; k < 16; k++)
        for (int j = 0; j < 20; j++)
            for (int i = 0; i < 24; i++) {
                double r =
                    sqrt((i - 12.0) * (i - 12.0) + (j - 10.0) * (j - 10.0) + (k - 8.0) * (k - 8.0));
                d[(k * 20 + j) * 24 + i] = (unsigned char)(r < 9 ? 250 - 25 * r : 0);
            }
    vv_volume_update_range(v);
    return v;
}

static void
test_pixels8(void **state) {
    (void)state;
    vv_volume *v = pixels8_ball();
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.mode = VV_MODE_COMPOSITE;
    o.width = 70; /* tiles cut at the edges */
    o.height = 45;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &o));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 70, 45));
    uint8_t *rgbx = malloc(4 * 70 * 45);
    assert_non_null(rgbx);
    const char *methods[] = {"raycast", "splat", "raytrace"};
    for (int m = 0; m < 3; m++)
        for (int q = 0; q <= 2; q += 2) { /* draft and final quality */
            vv_renderer *r = NULL;
            vt_ok(vv_renderer_new(&r, methods[m]));
            vv_pixels8 p8 = {.rgbx = rgbx, .width = 70, .height = 45, .converted_in_tiles = -1};
            vv_render_options ro;
            vv_render_options_init(&ro);
            ro.quality = q;
            ro.pixels8 = &p8;
            memset(rgbx, 0x5a, 4 * 70 * 45);
            vt_ok(vv_renderer_render(r, w, &w->view, &ro, img));
            /* only the ray caster's own tiles convert */
            assert_int_equal(p8.converted_in_tiles, m == 0);
            expect_rgbx(img, rgbx);
            /* the same frame without 8 bits: the same float pixels */
            vv_image *plain = NULL;
            vt_ok(vv_image_new(&plain, 70, 45));
            ro.pixels8 = NULL;
            vt_ok(vv_renderer_render(r, w, &w->view, &ro, plain));
            assert_memory_equal(plain->rgba, img->rgba, sizeof(float) * 4 * 70 * 45);
            vv_image_free(plain);
            /* a buffer of another size is refused */
            vv_pixels8 bad = {.rgbx = rgbx, .width = 69, .height = 45};
            ro.pixels8 = &bad;
            assert_int_equal(vv_renderer_render(r, w, &w->view, &ro, img), VV_ERR_INVALID);
            assert_non_null(strstr(vv_error_message(), "8-bit pixels"));
            vv_renderer_free(r);
        }
    free(rgbx);
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(v);
}

/* JFIF's YCbCr of 8-bit RGB in double precision, rounded (ITU-T T.871's
 * formulas and coefficients: independent of libjpeg's fixed point) */
static double
jfif_clamp(double v) {
    return v < 0 ? 0 : v > 255 ? 255 : v;
}

static void
jfif_ycc(const int rgb[3], double ycc[3]) {
    const double r = rgb[0], g = rgb[1], b = rgb[2];
    ycc[0] = jfif_clamp(0.299 * r + 0.587 * g + 0.114 * b);
    ycc[1] = jfif_clamp(128 - 0.168736 * r - 0.331264 * g + 0.5 * b);
    ycc[2] = jfif_clamp(128 + 0.5 * r - 0.418688 * g - 0.081312 * b);
}

/* vv_image_rect_to_yuv420 of @p img, in 2-row bands (the server's
 * fallback), into a new buffer of vv_pixels8_bytes */
static uint8_t *
yuv_of(const vv_image *img) {
    size_t n = vv_pixels8_bytes(VV_PIXELS8_YUV420, img->width, img->height);
    uint8_t *yuv = malloc(n);
    assert_non_null(yuv);
    memset(yuv, 0x5a, n);
    for (int y = 0; y < img->height; y += 2)
        vv_image_rect_to_yuv420(img, 0, y, img->width, y + 2 < img->height ? y + 2 : img->height,
                                yuv);
    return yuv;
}

/* The planes equal libjpeg-turbo's own conversion of the RGBX frame
 * (tjEncodeYUV3: the colour pass and downsampling tjCompress2 does), byte
 * for byte, layout included. */
static void
expect_turbojpeg_planes(const vv_image *img, const uint8_t *yuv) {
    const int W = img->width, H = img->height;
    uint8_t *rgbx = malloc(4 * (size_t)W * H);
    assert_non_null(rgbx);
    vv_image_rect_to_rgbx8(img, 0, 0, W, H, rgbx);
    size_t n = vv_pixels8_bytes(VV_PIXELS8_YUV420, W, H);
    assert_int_equal(n, tjBufSizeYUV2(W, 1, H, TJSAMP_420));
    uint8_t *ref = malloc(n);
    assert_non_null(ref);
    tjhandle tj = tjInitCompress();
    assert_non_null(tj);
    assert_int_equal(tjEncodeYUV3(tj, rgbx, W, 0, H, TJPF_RGBX, ref, 1, TJSAMP_420, 0), 0);
    tjDestroy(tj);
    for (size_t i = 0; i < n; i++)
        if (yuv[i] != ref[i])
            fail_msg("%d x %d: byte %zu of %zu: %d, libjpeg-turbo %d", W, H, i, n, yuv[i], ref[i]);
    /* the JPEG of the planes (the server's tjCompressFromYUVPlanes) is the
     * JPEG of the RGBX (tjCompress2) when the sides are whole MCUs (16
     * pixels); otherwise only the padding of the last MCUs differs (libjpeg
     * pads the full-size Cb, Cr and subsamples them, TurboJPEG repeats the
     * subsampled ones), which the quantization carries into those blocks'
     * pixels */
    tjhandle c = tjInitCompress(), dc = tjInitDecompress();
    assert_true(c && dc);
    unsigned char *ja = NULL, *jb = NULL;
    unsigned long na = 0, nb = 0;
    assert_int_equal(
        tjCompress2(c, rgbx, W, 0, H, TJPF_RGBX, &ja, &na, TJSAMP_420, 60, TJFLAG_FASTDCT), 0);
    const unsigned char *planes[3] = {yuv, yuv + tjPlaneSizeYUV(0, W, 0, H, TJSAMP_420),
                                      yuv + tjPlaneSizeYUV(0, W, 0, H, TJSAMP_420) +
                                          tjPlaneSizeYUV(1, W, 0, H, TJSAMP_420)};
    assert_int_equal(
        tjCompressFromYUVPlanes(c, planes, W, NULL, H, TJSAMP_420, &jb, &nb, 60, TJFLAG_FASTDCT),
        0);
    uint8_t *da = malloc(3 * (size_t)W * H), *db = malloc(3 * (size_t)W * H);
    assert_true(da && db);
    assert_int_equal(tjDecompress2(dc, ja, na, da, W, 0, H, TJPF_RGB, 0), 0);
    assert_int_equal(tjDecompress2(dc, jb, nb, db, W, 0, H, TJPF_RGB, 0), 0);
    double se = 0;
    for (size_t i = 0; i < 3 * (size_t)W * H; i++)
        se += ((double)da[i] - db[i]) * ((double)da[i] - db[i]);
    double psnr = se == 0 ? INFINITY : 10 * log10(255.0 * 255.0 * 3 * W * H / se);
    print_message(
        "%d x %d: the JPEGs of the RGBX and of the planes %zu, %zu bytes, %.1f dB apart\n", W, H,
        (size_t)na, (size_t)nb, psnr);
    if (W % 16 == 0 && H % 16 == 0) { /* no padding: the same JPEG */
        if (na != nb || memcmp(ja, jb, na) != 0)
            fail_msg("%d x %d: whole MCUs, yet the JPEGs differ", W, H);
    } else if (!(psnr >= 45)) /* noise in the edge blocks is the worst case */
        fail_msg("%d x %d: the two JPEGs decode %.1f dB apart", W, H, psnr);
    tjFree(ja);
    tjFree(jb);
    free(da);
    free(db);
    tjDestroy(c);
    tjDestroy(dc);
    free(ref);
    free(rgbx);
}

/* YUV 4:2:0 (vv_pixels8's VV_PIXELS8_YUV420): analytic values of pure
 * colours; random images of odd and even sides within rounding of the
 * double-precision JFIF formulas and equal to libjpeg-turbo's planes;
 * renders whose tiles convert, equal to the conversion of the frame. */
static void
test_pixels8_yuv420(void **state) {
    (void)state;
    /* pure colours, 2 x 2 pixels each: JFIF's values (Y = 0.299 R + ..., rounded;
     * Cb, Cr = 128 + ..., rounded, 255.5 kept at 255) */
    static const struct {
        float rgb[3];
        int y, cb, cr;
    } pure[] = {
        {{1, 1, 1}, 255, 128, 128},
        {{0, 0, 0}, 0, 128, 128},
        {{1, 0, 0}, 76, 85, 255},
        {{0, 1, 0}, 150, 44, 21},
        {{0, 0, 1}, 29, 255, 107},
        {{0.5f, 0.5f, 0.5f}, 128, 128, 128},
        /* Cb 128 - 127.5: libjpeg rounds by 1/2 - epsilon, so 0 (not 1) */
        {{1, 1, 0}, 226, 0, 149},
        {{2, -1, 0.5f}, 91, 149, 245}, /* clamped to 255, 0, 128 */
    };
    for (size_t c = 0; c < sizeof pure / sizeof pure[0]; c++) {
        vv_image *img = NULL;
        vt_ok(vv_image_new(&img, 2, 2));
        vv_image_clear(img, pure[c].rgb[0], pure[c].rgb[1], pure[c].rgb[2], 1);
        uint8_t *yuv = yuv_of(img);
        for (int i = 0; i < 4; i++)
            assert_int_equal(yuv[i], pure[c].y);
        assert_int_equal(yuv[4], pure[c].cb);
        assert_int_equal(yuv[5], pure[c].cr);
        expect_turbojpeg_planes(img, yuv);
        free(yuv);
        vv_image_free(img);
    }
    assert_int_equal(vv_pixels8_bytes(VV_PIXELS8_YUV420, 999, 799), 1000 * 800 + 2 * 500 * 400);
    assert_int_equal(vv_pixels8_bytes(VV_PIXELS8_RGBX, 3, 2), 24);
    assert_int_equal(vv_pixels8_bytes(7, 3, 2), 0);
    /* random images: odd and even sides, the browser's odd frame included */
    const int sizes[][2] = {{1, 1}, {3, 5}, {16, 16}, {17, 9}, {999, 799}, {1000, 800}};
    unsigned seed = 12345;
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        const int W = sizes[k][0], H = sizes[k][1];
        vv_image *img = NULL;
        vt_ok(vv_image_new(&img, W, H));
        for (size_t i = 0; i < 4 * (size_t)W * H; i++) {
            seed = seed * 1103515245u + 12345u;
            img->rgba[i] =
                (float)((seed >> 8) & 0xffff) / 60000.0f - 0.05f; /* a little out of [0, 1] */
        }
        uint8_t *yuv = yuv_of(img);
        const size_t pw = (size_t)(W + (W & 1)), ph = (size_t)(H + (H & 1));
        const uint8_t *cb = yuv + pw * ph, *cr = cb + (pw / 2) * (ph / 2);
        for (int y = 0; y < (int)ph; y++)
            for (int x = 0; x < (int)pw; x++) {
                int xs = x < W ? x : W - 1, ys = y < H ? y : H - 1; /* the padding repeats */
                int rgb[3];
                for (int ch = 0; ch < 3; ch++) {
                    float v = img->rgba[4 * ((size_t)ys * W + xs) + ch];
                    rgb[ch] = v <= 0 ? 0 : v >= 1 ? 255 : (int)floorf(v * 255.0f + 0.5f);
                }
                double ycc[3];
                jfif_ycc(rgb, ycc);
                double d = fabs(yuv[(size_t)y * pw + x] - ycc[0]);
                if (d > 0.51)
                    fail_msg("%d x %d: Y at (%d, %d) is %d, JFIF %.3f", W, H, x, y,
                             yuv[(size_t)y * pw + x], ycc[0]);
                if ((x | y) & 1)
                    continue;
                double sum[3] = {0, 0, 0}; /* the 2 x 2 block's mean Cb, Cr */
                for (int dy = 0; dy < 2; dy++)
                    for (int dx = 0; dx < 2; dx++) {
                        int xx = x + dx < W ? x + dx : W - 1, yy = y + dy < H ? y + dy : H - 1;
                        int p[3];
                        for (int ch = 0; ch < 3; ch++) {
                            float v = img->rgba[4 * ((size_t)yy * W + xx) + ch];
                            p[ch] = v <= 0 ? 0 : v >= 1 ? 255 : (int)floorf(v * 255.0f + 0.5f);
                        }
                        double c[3];
                        jfif_ycc(p, c);
                        sum[1] += c[1] / 4;
                        sum[2] += c[2] / 4;
                    }
                /* libjpeg rounds each pixel's Cb, Cr, then the mean, biased: within 1 */
                size_t ci = (size_t)(y / 2) * (pw / 2) + (size_t)(x / 2);
                if (fabs(cb[ci] - sum[1]) > 1.05 || fabs(cr[ci] - sum[2]) > 1.05)
                    fail_msg("%d x %d: Cb, Cr at (%d, %d) are %d, %d; JFIF %.3f, %.3f", W, H, x, y,
                             cb[ci], cr[ci], sum[1], sum[2]);
            }
        expect_turbojpeg_planes(img, yuv);
        /* a rectangle that would split a 2 x 2 block is ignored */
        if (W > 2 && H > 2) {
            const uint8_t flipped = (uint8_t)(yuv[1] ^ 0xff);
            yuv[1] = flipped;
            vv_image_rect_to_yuv420(img, 1, 0, W, H, yuv);
            vv_image_rect_to_yuv420(img, 0, 0, 1, 2, yuv);
            assert_int_equal(yuv[1], flipped);
        }
        free(yuv);
        vv_image_free(img);
    }
    /* renders: the ray caster's tiles convert, the others after the frame */
    vv_volume *v = pixels8_ball();
    const int views[][2] = {{71, 45}, {64, 48}};
    for (int s = 0; s < 2; s++) {
        vv_default_scene_options o;
        vv_default_scene_options_init(&o);
        o.mode = VV_MODE_COMPOSITE;
        o.width = views[s][0];
        o.height = views[s][1];
        vv_world *w = NULL;
        vt_ok(vv_world_new_for_volume(&w, v, &o));
        vv_image *img = NULL;
        vt_ok(vv_image_new(&img, o.width, o.height));
        size_t n = vv_pixels8_bytes(VV_PIXELS8_YUV420, o.width, o.height);
        uint8_t *yuv = malloc(n);
        assert_non_null(yuv);
        const char *methods[] = {"raycast", "splat"};
        for (int m = 0; m < 2; m++) {
            vv_renderer *r = NULL;
            vt_ok(vv_renderer_new(&r, methods[m]));
            vv_pixels8 p8 = {.yuv = yuv,
                             .width = o.width,
                             .height = o.height,
                             .format = VV_PIXELS8_YUV420,
                             .converted_in_tiles = -1};
            vv_render_options ro;
            vv_render_options_init(&ro);
            ro.pixels8 = &p8;
            memset(yuv, 0x5a, n);
            vt_ok(vv_renderer_render(r, w, &w->view, &ro, img));
            assert_int_equal(p8.converted_in_tiles, m == 0);
            uint8_t *want = yuv_of(img);
            assert_memory_equal(yuv, want, n);
            expect_turbojpeg_planes(img, yuv);
            free(want);
            /* no buffer for the format asked: refused */
            vv_pixels8 bad = {
                .rgbx = yuv, .width = o.width, .height = o.height, .format = VV_PIXELS8_YUV420};
            ro.pixels8 = &bad;
            assert_int_equal(vv_renderer_render(r, w, &w->view, &ro, img), VV_ERR_INVALID);
            assert_non_null(strstr(vv_error_message(), "8-bit pixels"));
            vv_renderer_free(r);
        }
        free(yuv);
        vv_image_free(img);
        vv_world_free(w);
    }
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tables),        cmocka_unit_test(test_cli_json),
        cmocka_unit_test(test_validation),    cmocka_unit_test(test_bindings),
        cmocka_unit_test(test_clone_fields),  cmocka_unit_test(test_radiosity_defaults),
        cmocka_unit_test(test_option_errors), cmocka_unit_test(test_world_checks),
        cmocka_unit_test(test_frame_runner),  cmocka_unit_test(test_camera_rays),
        cmocka_unit_test(test_region_ops),    cmocka_unit_test(test_stand_in),
        cmocka_unit_test(test_pixels8),       cmocka_unit_test(test_pixels8_yuv420),
    };
    return vt_run_tests(tests, NULL, NULL);
}
