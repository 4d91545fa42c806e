/*
 * JSON text helpers shared by the JSON readers of every layer (not
 * installed): src/core/json_text.c.
 */
#ifndef VOLVIS_CORE_JSON_INTERNAL_H
#define VOLVIS_CORE_JSON_INTERNAL_H

#include <jansson.h>
#include <stddef.h>

#include "volvis/core.h"

/** What a JSON value is, for error messages: "an object", "a number", ... Thread-safe. */
const char *vv_json_kind(const json_t *v);

/**
 * Line and column (1-based) of the value at @p path ("tracks[2].keys[0].time")
 * in the JSON text @p text of @p len bytes: where its key starts, or for an
 * array element where its value starts; the nearest ancestor's position when
 * the path cannot be found (paths are truncated at 255 bytes). Used to place
 * schema errors (scene, model tree and animation files) after Jansson has
 * parsed the text. Thread-safe; never fails.
 */
void vv_json_locate(const char *text, size_t len, const char *path, int *line, int *col);

/**
 * @p root as UTF-8 JSON text ending in a newline: an object or array
 * (the root is always written one member per line) whose members are
 * written on one line when that line fits in 100 columns, else one member
 * per line, indented by two spaces; object keys in the tree's order; reals
 * as the shorter of %.15g and %.17g that reads back as the same double
 * (NaN and infinities as 0, which json_real never holds); strings escaped
 * by Jansson. *@p out is malloc'ed (free it), *@p len its length without
 * the NUL. Errors: VV_ERR_NOMEM. Thread-safe.
 */
vv_status vv_json_write_text(const json_t *root, char **out, size_t *len);

#endif
