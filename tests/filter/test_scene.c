/*
 * A scene object's filter chain ("filters", docs/scene-format.md): applied
 * at load, in both spellings; cached (a second load shares the volume);
 * errors located by line and column; kept when the scene is saved again.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static const char *
write_volume(void) {
    const char *p = vt_path(vt_outdir("filter_scene"), "v.nrrd");
    vv_volume *v;
    vt_ok(vv_volume_new(&v, (int[]){16, 14, 12}, VV_I16));
    v->spacing[0] = 0.5;
    for (int k = 0; k < 12; k++)
        for (int j = 0; j < 14; j++)
            for (int i = 0; i < 16; i++)
                vv_volume_set(v, i, j, k,
                              (i - 8) * (i - 8) + (j - 7) * (j - 7) + (k - 6) * (k - 6) < 16 ? 800
                                                                                             : i);
    vt_ok(vv_volume_save(v, p, VV_FORMAT_NRRD, 0));
    vv_volume_free(v);
    return p;
}

static const char *
write_scene(const char *name, const char *filters) {
    const char *p = vt_path(vt_outdir("filter_scene"), name);
    char text[2048];
    snprintf(text, sizeof text,
             "{\n  \"objects\": [{\n    \"type\": \"volume\", \"file\": \"v.nrrd\",\n"
             "    \"origin\": [1, 2, 3],\n    \"filters\": %s\n  }]\n}\n",
             filters);
    vt_write_file(p, text, strlen(text));
    return p;
}

static void
test_filters_at_load(void **state) {
    (void)state;
    write_volume();
    vv_filter_cache *cache = NULL;
    vt_ok(vv_filter_cache_new(&cache, 8));
    vv_world *a, *b, *c;
    vt_ok(vv_scene_load_cached(&a, write_scene("a.json", "\"--threshold 500: --dilate 1\""), NULL,
                               cache));
    vt_ok(vv_scene_load_cached(
        &b, write_scene("b.json", "[{\"threshold\": \"500:\"}, {\"dilate\": 1}]"), NULL, cache));
    const vv_volume *va = a->objects[0]->volume, *vb = b->objects[0]->volume;
    assert_int_equal(va->type, VV_U8);
    assert_int_equal(vv_volume_get(va, 8, 7, 6), 1);
    assert_int_equal(vv_volume_get(va, 8, 7, 10), 1); /* dilated: radius 4 -> 4 */
    assert_int_equal(vv_volume_get(va, 0, 0, 0), 0);
    /* the same chain and file: one cached volume shared by both; without
     * the cache, filtered again */
    assert_ptr_equal(va, vb);
    vv_world *d = NULL;
    vt_ok(vv_scene_load(&d, write_scene("a.json", "\"--threshold 500: --dilate 1\"")));
    assert_ptr_not_equal(d->objects[0]->volume, va);
    assert_memory_equal(d->objects[0]->volume->data, va->data, 16 * 14 * 12);
    vv_world_free(d);
    assert_near(va->origin[1], 2, 0);
    assert_string_equal(a->objects[0]->geometry.filters, "--threshold 500: --dilate 1");
    /* saved and loaded again: the chain is kept */
    const char *saved = vt_path(vt_outdir("filter_scene"), "saved.json");
    vt_ok(vv_scene_save(a, saved, NULL));
    vt_ok(vv_scene_load(&c, saved));
    assert_string_equal(c->objects[0]->geometry.filters, "--threshold 500: --dilate 1");
    assert_int_equal(c->objects[0]->volume->type, VV_U8);
    assert_memory_equal(c->objects[0]->volume->data, va->data, 16 * 14 * 12);
    vv_world_free(a);
    vv_world_free(b);
    vv_world_free(c);
    /* a resampling chain: the saved spacing is the filtered volume's */
    vt_ok(vv_scene_load(&a, write_scene("r.json", "\"--resize 31x14x12\"")));
    assert_near(a->objects[0]->volume->spacing[0], 0.25, 1e-12);
    vt_ok(vv_scene_save(a, saved, NULL));
    vt_ok(vv_scene_load(&c, saved));
    assert_int_equal(c->objects[0]->volume->dims[0], 31);
    assert_near(c->objects[0]->volume->spacing[0], 0.25, 1e-12);
    vv_world_free(a);
    vv_world_free(c);
    vv_filter_cache_free(cache);
}

static void
test_filter_errors(void **state) {
    (void)state;
    write_volume();
    vv_world *w = NULL;
    vt_err(vv_scene_load(&w, write_scene("e1.json", "[{\"gaussian\": 1}, {\"median\": -3}]")));
    print_message("%s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "filters[1]"));
    assert_non_null(strstr(vv_error_message(), ":5:"));
    assert_non_null(strstr(vv_error_message(), "median"));
    vt_err(vv_scene_load(&w, write_scene("e2.json", "\"--blur 3\"")));
    assert_non_null(strstr(vv_error_message(), "unknown filter"));
    vt_err(vv_scene_load(&w, write_scene("e3.json", "42")));
    /* valid text, failing on the data: a seed outside the volume */
    vt_err(vv_scene_load(&w, write_scene("e4.json", "\"--grow 99,0,0:0:10\"")));
    assert_non_null(strstr(vv_error_message(), "outside the volume"));
    assert_null(w);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_filters_at_load),
        cmocka_unit_test(test_filter_errors),
    };
    return vt_run_tests(tests, NULL, NULL);
}
