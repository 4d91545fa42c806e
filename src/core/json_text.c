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
 *
 * Writing: vv_json_write_text turns a Jansson tree into text a person can
 * read and edit (short arrays and objects on one line, numbers with as few
 * digits as read back to the same double), which Jansson's own dump cannot
 * do: it writes every real with a fixed precision (17 digits make 0.1 read
 * 0.10000000000000001; fewer lose values) and, indented, puts every array
 * element on its own line.
 */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
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

/* ---- writing ------------------------------------------------------------- */

#define WRITE_WIDTH 100

typedef struct jbuf {
    char *p;
    size_t n, cap;
    int nomem;
} jbuf;

static void
jb_put(jbuf *b, const char *s, size_t n) {
    if (b->nomem)
        return;
    if (b->n + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->n + n + 1)
            cap *= 2;
        char *p = realloc(b->p, cap);
        if (!p) {
            b->nomem = 1;
            return;
        }
        b->p = p;
        b->cap = cap;
    }
    memcpy(b->p + b->n, s, n);
    b->n += n;
    b->p[b->n] = '\0';
}

static void
jb_puts(jbuf *b, const char *s) {
    jb_put(b, s, strlen(s));
}

static void
jb_indent(jbuf *b, int n) {
    for (int i = 0; i < n; i++)
        jb_put(b, " ", 1);
}

/* A string as JSON text, escaped by Jansson. */
static void
jb_string(jbuf *b, const char *s, size_t len) {
    json_t *j = json_stringn_nocheck(s, len);
    char *t = j ? json_dumps(j, JSON_ENCODE_ANY) : NULL;
    json_decref(j);
    if (!t) {
        b->nomem = 1;
        return;
    }
    jb_puts(b, t);
    free(t);
}

/* The shortest of %.15g and %.17g that reads back as the same double. */
static void
jb_real(jbuf *b, double v) {
    char buf[64];
    if (!isfinite(v))
        v = 0.0; /* JSON has no NaN or infinity; json_real refuses them anyway */
    snprintf(buf, sizeof buf, "%.15g", v);
    if (strtod(buf, NULL) != v)
        snprintf(buf, sizeof buf, "%.17g", v);
    jb_puts(b, buf);
}

static void jb_value(jbuf *b, const json_t *v, int indent, int column, int force_lines);

/* @p v on one line. */
static void
jb_inline(jbuf *b, const json_t *v) {
    jb_value(b, v, 0, 0, -1);
}

/* Writes @p v: containers on one line when they fit in WRITE_WIDTH columns
 * from @p column (or always when @p force_lines < 0), else one member per
 * line indented by @p indent + 2 (always when @p force_lines > 0). */
static void
jb_value(jbuf *b, const json_t *v, int indent, int column, int force_lines) {
    char buf[64];
    switch (json_typeof(v)) {
    case JSON_OBJECT:
    case JSON_ARRAY: {
        const int is_obj = json_is_object(v);
        const size_t n = is_obj ? json_object_size(v) : json_array_size(v);
        if (n == 0) {
            jb_puts(b, is_obj ? "{}" : "[]");
            return;
        }
        if (force_lines == 0) {
            jbuf t = {0};
            jb_inline(&t, v);
            if (t.nomem)
                b->nomem = 1;
            else if ((size_t)column + t.n <= WRITE_WIDTH) {
                jb_put(b, t.p, t.n);
                free(t.p);
                return;
            }
            free(t.p);
        }
        const int lines = force_lines >= 0;
        jb_puts(b, is_obj ? "{" : "[");
        size_t i = 0;
        const char *key;
        json_t *e;
        void *it = is_obj ? json_object_iter((json_t *)v) : NULL;
        for (i = 0; i < n; i++) {
            if (i)
                jb_puts(b, ",");
            if (lines) {
                jb_puts(b, "\n");
                jb_indent(b, indent + 2);
            } else if (i) {
                jb_puts(b, " ");
            }
            int col = indent + 2;
            if (is_obj) {
                key = json_object_iter_key(it);
                e = json_object_iter_value(it);
                it = json_object_iter_next((json_t *)v, it);
                size_t before = b->n;
                jb_string(b, key, strlen(key));
                jb_puts(b, ": ");
                col += (int)(b->n - before);
            } else {
                e = json_array_get(v, i);
            }
            jb_value(b, e, indent + 2, col, lines ? 0 : -1);
        }
        if (lines) {
            jb_puts(b, "\n");
            jb_indent(b, indent);
        }
        jb_puts(b, is_obj ? "}" : "]");
        return;
    }
    case JSON_STRING:
        jb_string(b, json_string_value(v), json_string_length(v));
        return;
    case JSON_INTEGER:
        snprintf(buf, sizeof buf, "%" JSON_INTEGER_FORMAT, json_integer_value(v));
        jb_puts(b, buf);
        return;
    case JSON_REAL:
        jb_real(b, json_real_value(v));
        return;
    case JSON_TRUE:
        jb_puts(b, "true");
        return;
    case JSON_FALSE:
        jb_puts(b, "false");
        return;
    case JSON_NULL:
        jb_puts(b, "null");
        return;
    }
}

vv_status
vv_json_write_text(const json_t *root, char **out, size_t *len) {
    *out = NULL;
    *len = 0;
    jbuf b = {0};
    jb_value(&b, root, 0, 0, 1);
    jb_puts(&b, "\n");
    if (b.nomem) {
        free(b.p);
        return vv_error_set(VV_ERR_NOMEM, "json: out of memory");
    }
    *out = b.p;
    *len = b.n;
    return VV_OK;
}
