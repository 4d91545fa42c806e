/*
 * A scene object's "filters" value as a filter chain (used by
 * src/model/scene.c; not installed). See docs/scene-format.md.
 */
#ifndef VV_FILTER_SCENE_H
#define VV_FILTER_SCENE_H

#include <jansson.h>

#include "volvis/filter.h"

/**
 * Builds a chain from @p j: a string in command-line syntax
 * ("--gaussian 1.5 --median 1") or an array of one-key objects
 * ({"gaussian": 1.5}, {"threshold": "300:"}, {"fill-holes": true}): the key
 * names the filter, the value is its argument (a string, a number, or
 * true/null for a filter without one). On error *@p bad_item is the array
 * index at fault (-1: the value itself) and the message says why.
 * Errors: VV_ERR_INVALID, VV_ERR_NOMEM.
 */
vv_status vf_chain_from_json(const json_t *j, vv_filter_chain **out, int *bad_item);

#endif
