/* A subscriber that keeps every action it receives (for the input tests). */
#ifndef VV_TEST_INPUT_COLLECT_H
#define VV_TEST_INPUT_COLLECT_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "volvis/input.h"

/* The device information shipped with VolVis (share/devices). */
#define DEVDIR VV_SOURCE_DIR "/share/devices"

/* A manager over the shipped device information (the caller frees it). */
static inline vv_input_manager *
new_manager(void) {
    const char *dirs[] = {DEVDIR};
    vv_input_devinfo_db *db = NULL;
    vt_ok(vv_input_devinfo_db_load(&db, dirs, 1));
    vv_input_manager *m = NULL;
    vt_ok(vv_input_manager_new(&m, db));
    vv_input_devinfo_db_free(db);
    return m;
}

/* This program's fresh temporary folder for sockets ("" until the first
 * temp_socket; short: sun_path is 108 bytes). The test removes it. */
static inline char *
socket_dir(void) {
    static char dir[64];
    return dir;
}

/* The path of socket @p name in socket_dir(), made on the first call
 * (static storage, overwritten by the next call). */
static inline const char *
temp_socket(const char *name) {
    static char path[96];
    char *dir = socket_dir();
    if (!dir[0]) {
        /* a socket's path is short: $TMPDIR when it leaves room, else /tmp */
        assert_non_null(vt_mkdtemp(dir, 41, "vv-input-"));
    }
    snprintf(path, sizeof path, "%.40s/%.40s", dir, name);
    return path;
}

typedef struct collect {
    vv_input_action *a;
    int n, cap;
} collect;

static inline void
collect_fn(void *user, const vv_input_action *a) {
    collect *c = user;
    if (c->n == c->cap) {
        c->cap = c->cap ? 2 * c->cap : 64;
        c->a = realloc(c->a, (size_t)c->cap * sizeof *c->a);
    }
    c->a[c->n++] = *a;
}

/* Index of the first action of @p kind at or after @p from, -1 none. */
static inline int
collect_find(const collect *c, vv_input_action_kind kind, int from) {
    for (int i = from; i < c->n; i++)
        if (c->a[i].kind == kind)
            return i;
    return -1;
}

static inline int
collect_count(const collect *c, vv_input_action_kind kind) {
    int n = 0;
    for (int i = 0; i < c->n; i++)
        n += c->a[i].kind == kind;
    return n;
}

static inline void
collect_free(collect *c) {
    free(c->a);
    memset(c, 0, sizeof *c);
}

static inline vv_input_raw_event
raw(int dev, double t, vv_input_raw_kind kind, int code, double v0, double v1) {
    vv_input_raw_event e;
    memset(&e, 0, sizeof e);
    e.device = dev;
    e.time = t;
    e.kind = kind;
    e.code = code;
    e.v[0] = v0;
    e.v[1] = v1;
    return e;
}

#endif
