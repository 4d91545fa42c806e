/*
 * JSON text helpers shared by the JSON readers of every layer (not
 * installed): src/core/json_text.c.
 */
#ifndef VOLVIS_CORE_JSON_INTERNAL_H
#define VOLVIS_CORE_JSON_INTERNAL_H

#include <jansson.h>
#include <stddef.h>

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

#endif
