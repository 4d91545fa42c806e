/*
 * JSON text helpers shared by every JSON reader (scene files, model trees,
 * animation files): what kind of value a node is, for error messages, and
 * where a path ("objects[0].transfer_function") lies in the raw text.
 *
 * Jansson reports line:column for syntax errors but keeps no positions for
 * values, so a schema error is located by a second, lazy pass over the raw
 * text that walks to the offending path and reports where its key (or, for
 * an array element, its value) starts. This pass runs only when there is an
 * error to report.
 */
#include <jansson.h>
#include <stdio.h>
#include <string.h>

#include "core/json_internal.h"

#define PATH_MAX_LEN 256

typedef struct scan {
    const char *s;
    size_t n, i;
    int line, col;
    const char *target;
    int found, fline, fcol;
} scan;

static int
sc_peek(const scan *sc) {
    return sc->i < sc->n ? (unsigned char)sc->s[sc->i] : -1;
}

static void
sc_adv(scan *sc) {
    if (sc->i >= sc->n)
        return;
    unsigned char ch = (unsigned char)sc->s[sc->i++];
    if (ch == '\n') {
        sc->line++;
        sc->col = 1;
    } else if ((ch & 0xC0) != 0x80) {
        /* columns count characters: UTF-8 continuation bytes add nothing */
        sc->col++;
    }
}

static void
sc_ws(scan *sc) {
    for (;;) {
        int ch = sc_peek(sc);
        if (ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r')
            sc_adv(sc);
        else
            return;
    }
}

/* Consumes a string at the cursor, copying its (roughly decoded) text. */
static void
sc_string(scan *sc, char *buf, size_t cap) {
    size_t k = 0;
    sc_adv(sc); /* opening quote */
    while (sc->i < sc->n) {
        int ch = sc_peek(sc);
        if (ch == '"') {
            sc_adv(sc);
            break;
        }
        if (ch == '\\') {
            sc_adv(sc);
            ch = sc_peek(sc);
            if (ch < 0)
                break;
        }
        if (buf && k + 1 < cap)
            buf[k++] = (char)ch;
        sc_adv(sc);
    }
    if (buf && cap)
        buf[k] = '\0';
}

/* Skips one value without recursion. */
static void
sc_skip(scan *sc) {
    int depth = 0;
    do {
        sc_ws(sc);
        int ch = sc_peek(sc);
        if (ch < 0)
            return;
        if (ch == '"') {
            sc_string(sc, NULL, 0);
        } else if (ch == '{' || ch == '[') {
            depth++;
            sc_adv(sc);
        } else if (ch == '}' || ch == ']') {
            depth--;
            sc_adv(sc);
        } else if (ch == ',' || ch == ':') {
            sc_adv(sc);
        } else {
            while (sc->i < sc->n) {
                ch = sc_peek(sc);
                if (ch == ',' || ch == ']' || ch == '}' || ch == ' ' || ch == '\n' || ch == '\t' ||
                    ch == '\r')
                    break;
                sc_adv(sc);
            }
        }
    } while (depth > 0 && sc->i < sc->n);
}

static int
path_is_prefix(const char *path, const char *target) {
    size_t l = strlen(path);
    if (l == 0)
        return 1;
    return strncmp(path, target, l) == 0 && (target[l] == '.' || target[l] == '[');
}

static void
sc_found(scan *sc) {
    sc->found = 1;
    sc->fline = sc->line;
    sc->fcol = sc->col;
}

/* Walks the value at the cursor whose path is @p path, descending only
 * towards the target; the recursion depth is the target's depth. */
static void
sc_value(scan *sc, const char *path) {
    sc_ws(sc);
    if (strcmp(path, sc->target) == 0) {
        sc_found(sc);
        return;
    }
    int ch = sc_peek(sc);
    if (!path_is_prefix(path, sc->target) || (ch != '{' && ch != '[')) {
        sc_skip(sc);
        return;
    }
    char child[2 * PATH_MAX_LEN + 32];
    if (ch == '{') {
        sc_adv(sc);
        for (;;) {
            sc_ws(sc);
            ch = sc_peek(sc);
            if (ch != '"') {
                if (ch == '}')
                    sc_adv(sc);
                return;
            }
            int kl = sc->line, kc = sc->col;
            char key[PATH_MAX_LEN];
            sc_string(sc, key, sizeof key);
            if (path[0])
                snprintf(child, sizeof child, "%s.%s", path, key);
            else
                snprintf(child, sizeof child, "%s", key);
            sc_ws(sc);
            if (sc_peek(sc) == ':')
                sc_adv(sc);
            if (strcmp(child, sc->target) == 0) {
                sc->found = 1;
                sc->fline = kl;
                sc->fcol = kc;
                return;
            }
            sc_value(sc, child);
            if (sc->found)
                return;
            sc_ws(sc);
            if (sc_peek(sc) == ',')
                sc_adv(sc);
            else {
                if (sc_peek(sc) == '}')
                    sc_adv(sc);
                return;
            }
        }
    } else {
        sc_adv(sc);
        for (int idx = 0;; idx++) {
            sc_ws(sc);
            ch = sc_peek(sc);
            if (ch < 0 || ch == ']') {
                sc_adv(sc);
                return;
            }
            snprintf(child, sizeof child, "%s[%d]", path, idx);
            sc_value(sc, child);
            if (sc->found)
                return;
            sc_ws(sc);
            if (sc_peek(sc) == ',')
                sc_adv(sc);
            else {
                if (sc_peek(sc) == ']')
                    sc_adv(sc);
                return;
            }
        }
    }
}

/* Strips the last ".key" or "[i]" of a path in place; 0 when nothing is left. */
static int
path_parent(char *p) {
    size_t l = strlen(p);
    if (l == 0)
        return 0;
    while (l > 0 && p[l - 1] != '.' && p[l - 1] != '[')
        l--;
    if (l == 0) {
        p[0] = '\0';
        return 1;
    }
    p[l - 1] = '\0';
    return 1;
}

void
vv_json_locate(const char *text, size_t len, const char *path, int *line, int *col) {
    char p[PATH_MAX_LEN];
    snprintf(p, sizeof p, "%s", path ? path : "");
    for (;;) {
        scan sc = {text, len, 0, 1, 1, p, 0, 1, 1};
        sc_value(&sc, "");
        if (sc.found) {
            *line = sc.fline;
            *col = sc.fcol;
            return;
        }
        if (!path_parent(p))
            break;
    }
    *line = 1;
    *col = 1;
}

const char *
vv_json_kind(const json_t *v) {
    switch (json_typeof(v)) {
    case JSON_OBJECT:
        return "an object";
    case JSON_ARRAY:
        return "an array";
    case JSON_STRING:
        return "a string";
    case JSON_INTEGER:
    case JSON_REAL:
        return "a number";
    case JSON_TRUE:
    case JSON_FALSE:
        return "a boolean";
    case JSON_NULL:
        break;
    }
    return "null";
}
