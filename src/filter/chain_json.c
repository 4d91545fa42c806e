/* A scene object's "filters" value (JSON) as a filter chain. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "filter/filter_scene.h"

vv_status
vf_chain_from_json(const json_t *j, vv_filter_chain **out, int *bad_item) {
    *bad_item = -1;
    if (json_is_string(j))
        return vv_filter_chain_parse(json_string_value(j), out);
    if (!json_is_array(j))
        return vv_error_set(VV_ERR_INVALID,
                            "expected a string (\"--gaussian 1.5 --median 1\") or an array of "
                            "{\"filter\": argument} objects");
    vv_filter_chain *c;
    vv_status s = vv_filter_chain_new(&c);
    if (s != VV_OK)
        return s;
    size_t i;
    json_t *e;
    json_array_foreach(j, i, e) {
        *bad_item = (int)i;
        if (!json_is_object(e) || json_object_size(e) != 1) {
            s = vv_error_set(VV_ERR_INVALID,
                             "expected an object with one key, the filter's name, e.g. "
                             "{\"gaussian\": 1.5}");
            break;
        }
        const char *name = json_object_iter_key(json_object_iter((json_t *)e));
        json_t *v = json_object_iter_value(json_object_iter((json_t *)e));
        char arg[256];
        const char *a = arg;
        if (json_is_string(v)) {
            a = json_string_value(v);
        } else if (json_is_integer(v)) {
            snprintf(arg, sizeof arg, "%lld", (long long)json_integer_value(v));
        } else if (json_is_real(v)) {
            snprintf(arg, sizeof arg, "%.15g", json_real_value(v));
        } else if (json_is_true(v) || json_is_null(v)) {
            a = NULL;
        } else {
            s = vv_error_set(VV_ERR_INVALID, "\"%s\": expected a string or a number argument",
                             name);
            break;
        }
        if ((s = vv_filter_chain_add(c, name, a)) != VV_OK)
            break;
    }
    if (s != VV_OK) {
        vv_filter_chain_free(c);
        return s;
    }
    *bad_item = -1;
    *out = c;
    return VV_OK;
}
