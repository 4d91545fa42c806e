/*
 * The messages a browser client sends (docs/serve-protocol.md): parsed with
 * Jansson, every field's type and range checked, paths confined to the
 * root. Pure: no libwebsockets, no session state (fuzzed by
 * tests/fuzz/fuzz_serve_msg.c).
 */
#define _GNU_SOURCE
#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "serve.h"

/* Formats the reason as one printable line: the parser's messages quote
 * the client's bytes, and the reason is logged and sent back. */
static int
fail(char *why, size_t cap, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, cap, fmt, ap);
    va_end(ap);
    for (char *p = why; *p; p++)
        if ((unsigned char)*p < 0x20 || *p == 0x7f)
            *p = '?';
    return -1;
}

/* A number field: required unless @p dflt is given (has_dflt). */
static int
get_number(json_t *o, const char *key, int required, double lo, double hi, double *out, char *why,
           size_t cap) {
    json_t *v = json_object_get(o, key);
    if (!v) {
        if (required)
            return fail(why, cap, "'%s' is missing", key);
        return 1; /* absent */
    }
    if (!json_is_number(v))
        return fail(why, cap, "'%s' is not a number", key);
    double d = json_number_value(v);
    if (!isfinite(d) || d < lo || d > hi)
        return fail(why, cap, "'%s' is %g, outside [%g, %g]", key, d, lo, hi);
    *out = d;
    return 0;
}

static int
get_int(json_t *o, const char *key, int required, long lo, long hi, int *out, char *why,
        size_t cap) {
    json_t *v = json_object_get(o, key);
    if (!v) {
        if (required)
            return fail(why, cap, "'%s' is missing", key);
        return 1;
    }
    if (!json_is_integer(v))
        return fail(why, cap, "'%s' is not an integer", key);
    json_int_t i = json_integer_value(v);
    if (i < lo || i > hi)
        return fail(why, cap, "'%s' is %lld, outside [%ld, %ld]", key, (long long)i, lo, hi);
    *out = (int)i;
    return 0;
}

static int
get_bool(json_t *o, const char *key, int *out, char *why, size_t cap) {
    json_t *v = json_object_get(o, key);
    if (!v)
        return 1;
    if (!json_is_boolean(v))
        return fail(why, cap, "'%s' is not true or false", key);
    *out = json_is_true(v);
    return 0;
}

static int
get_string(json_t *o, const char *key, int required, char *out, size_t out_cap, char *why,
           size_t cap) {
    json_t *v = json_object_get(o, key);
    if (!v) {
        if (required)
            return fail(why, cap, "'%s' is missing", key);
        return 1;
    }
    if (!json_is_string(v))
        return fail(why, cap, "'%s' is not a string", key);
    size_t n = json_string_length(v);
    const char *s = json_string_value(v);
    if (n >= out_cap)
        return fail(why, cap, "'%s' is longer than %zu bytes", key, out_cap - 1);
    if (memchr(s, '\0', n))
        return fail(why, cap, "'%s' holds a NUL byte", key);
    for (size_t i = 0; i < n; i++)
        if ((unsigned char)s[i] < 0x20 || s[i] == 0x7f)
            return fail(why, cap, "'%s' holds a control byte", key);
    memcpy(out, s, n);
    out[n] = '\0';
    return 0;
}

/* Every key of @p o must be one of @p keys (NULL-terminated). */
static int
only_keys(json_t *o, const char *const *keys, char *why, size_t cap) {
    const char *k;
    json_t *v;
    json_object_foreach(o, k, v) {
        int known = 0;
        for (const char *const *p = keys; *p && !known; p++)
            known = strcmp(*p, k) == 0;
        if (!known)
            return fail(why, cap, "unknown field '%.40s'", k);
    }
    return 0;
}

static int
axis_of(json_t *o, vv_slice_axis *axis, char *why, size_t cap) {
    char name[32];
    if (get_string(o, "axis", 1, name, sizeof name, why, cap))
        return -1;
    if (strcmp(name, "axial") == 0)
        *axis = VV_SLICE_AXIAL;
    else if (strcmp(name, "coronal") == 0)
        *axis = VV_SLICE_CORONAL;
    else if (strcmp(name, "sagittal") == 0)
        *axis = VV_SLICE_SAGITTAL;
    else
        return fail(why, cap, "'axis' is '%s', not axial, coronal or sagittal", name);
    return 0;
}

static int
parse_color(const char *s, vv_vec3 *out) {
    if (strlen(s) != 7 || s[0] != '#' || strspn(s + 1, "0123456789abcdefABCDEF") != 6)
        return -1;
    double c[3];
    for (int k = 0; k < 3; k++) {
        char hex[3] = {s[1 + 2 * k], s[2 + 2 * k], '\0'};
        c[k] = (double)strtol(hex, NULL, 16) / 255.0;
    }
    *out = vv_vec3_make(c[0], c[1], c[2]);
    return 0;
}

static int
parse_object(json_t *o, srv_msg *m, char *why, size_t cap) {
    char type[32];
    if (get_string(o, "type", 1, type, sizeof type, why, cap))
        return -1;
    int rc = 0;
    if (strcmp(type, "hello") == 0 || strcmp(type, "resize") == 0) {
        static const char *const keys[] = {"type", "width", "height", NULL};
        m->type = type[0] == 'h' ? SRV_HELLO : SRV_RESIZE;
        if (only_keys(o, keys, why, cap) ||
            get_int(o, "width", 1, SRV_VIEW_MIN, SRV_VIEW_MAX, &m->width, why, cap) ||
            get_int(o, "height", 1, SRV_VIEW_MIN, SRV_VIEW_MAX, &m->height, why, cap))
            return -1;
    } else if (strcmp(type, "nav") == 0) {
        static const char *const keys[] = {"type",   "motion", "dx",     "dy",
                                           "factor", "seq",    "moving", NULL};
        char motion[16];
        m->type = SRV_NAV;
        if (only_keys(o, keys, why, cap) ||
            get_string(o, "motion", 1, motion, sizeof motion, why, cap))
            return -1;
        if (strcmp(motion, "rotate") == 0)
            m->motion = VV_NAV_ROTATE;
        else if (strcmp(motion, "pan") == 0)
            m->motion = VV_NAV_PAN;
        else if (strcmp(motion, "zoom") == 0)
            m->motion = VV_NAV_ZOOM;
        else
            return fail(why, cap, "'motion' is '%s', not rotate, pan or zoom", motion);
        m->factor = 1;
        if (get_number(o, "dx", 0, -VV_NAV_MAX_PIXELS, VV_NAV_MAX_PIXELS, &m->dx, why, cap) < 0 ||
            get_number(o, "dy", 0, -VV_NAV_MAX_PIXELS, VV_NAV_MAX_PIXELS, &m->dy, why, cap) < 0 ||
            get_number(o, "factor", m->motion == VV_NAV_ZOOM, 1.0 / 16, 16, &m->factor, why, cap) <
                0 ||
            get_bool(o, "moving", &m->moving, why, cap) < 0)
            return -1;
        json_t *seq = json_object_get(o, "seq");
        if (seq) {
            if (!json_is_integer(seq) || json_integer_value(seq) < 0)
                return fail(why, cap, "'seq' is not an integer >= 0");
            m->seq = (long long)json_integer_value(seq);
        }
    } else if (strcmp(type, "reset_view") == 0 || strcmp(type, "png") == 0) {
        static const char *const keys[] = {"type", NULL};
        m->type = type[0] == 'r' ? SRV_RESET_VIEW : SRV_PNG;
        if (only_keys(o, keys, why, cap))
            return -1;
    } else if (strcmp(type, "mode") == 0) {
        static const char *const keys[] = {"type", "mode", "isovalue", NULL};
        char mode[16];
        m->type = SRV_MODE;
        if (only_keys(o, keys, why, cap) || get_string(o, "mode", 1, mode, sizeof mode, why, cap))
            return -1;
        if (strcmp(mode, "composite") == 0)
            m->mode = VV_MODE_COMPOSITE;
        else if (strcmp(mode, "mip") == 0)
            m->mode = VV_MODE_MIP;
        else if (strcmp(mode, "iso") == 0)
            m->mode = VV_MODE_ISO;
        else
            return fail(why, cap, "'mode' is '%s', not composite, mip or iso", mode);
        rc = get_number(o, "isovalue", 0, -1e300, 1e300, &m->isovalue, why, cap);
        if (rc < 0)
            return -1;
        m->has_isovalue = rc == 0;
    } else if (strcmp(type, "preset") == 0) {
        static const char *const keys[] = {"type", "name", NULL};
        m->type = SRV_PRESET;
        if (only_keys(o, keys, why, cap) ||
            get_string(o, "name", 1, m->name, sizeof m->name, why, cap))
            return -1;
        if (!vv_tf_preset_description(m->name))
            return fail(why, cap, "'name': no preset '%s'", m->name);
    } else if (strcmp(type, "channel") == 0) {
        static const char *const keys[] = {"type", "index", "visible", "color", NULL};
        char color[16];
        m->type = SRV_CHANNEL;
        if (only_keys(o, keys, why, cap) ||
            get_int(o, "index", 1, 0, VV_MAX_CHANNELS - 1, &m->index, why, cap))
            return -1;
        if ((rc = get_bool(o, "visible", &m->visible, why, cap)) < 0)
            return -1;
        m->has_visible = rc == 0;
        if ((rc = get_string(o, "color", 0, color, sizeof color, why, cap)) < 0)
            return -1;
        if (rc == 0) {
            if (parse_color(color, &m->color))
                return fail(why, cap, "'color' is '%s', not #rrggbb", color);
            m->has_color = 1;
        }
    } else if (strcmp(type, "time") == 0) {
        static const char *const keys[] = {"type", "step", NULL};
        m->type = SRV_TIME;
        if (only_keys(o, keys, why, cap) || get_int(o, "step", 1, 0, 1000000, &m->index, why, cap))
            return -1;
    } else if (strcmp(type, "slice") == 0) {
        static const char *const keys[] = {"type",   "axis",   "index", "width",
                                           "height", "window", "level", NULL};
        m->type = SRV_SLICE;
        if (only_keys(o, keys, why, cap) || axis_of(o, &m->axis, why, cap) ||
            get_int(o, "index", 1, 0, 1 << 20, &m->index, why, cap) ||
            get_int(o, "width", 1, SRV_VIEW_MIN, SRV_SLICE_MAX, &m->width, why, cap) ||
            get_int(o, "height", 1, SRV_VIEW_MIN, SRV_SLICE_MAX, &m->height, why, cap))
            return -1;
        int w = get_number(o, "window", 0, 1e-300, 1e300, &m->window, why, cap);
        int l = get_number(o, "level", 0, -1e300, 1e300, &m->level, why, cap);
        if (w < 0 || l < 0)
            return -1;
        if (w != l)
            return fail(why, cap, "'window' and 'level' go together");
        m->has_window = w == 0;
    } else if (strcmp(type, "probe") == 0) {
        static const char *const keys[] = {"type",   "axis", "index", "width",
                                           "height", "x",    "y",     NULL};
        m->type = SRV_PROBE;
        if (only_keys(o, keys, why, cap) || axis_of(o, &m->axis, why, cap) ||
            get_int(o, "index", 1, 0, 1 << 20, &m->index, why, cap) ||
            get_int(o, "width", 1, SRV_VIEW_MIN, SRV_SLICE_MAX, &m->width, why, cap) ||
            get_int(o, "height", 1, SRV_VIEW_MIN, SRV_SLICE_MAX, &m->height, why, cap) ||
            get_number(o, "x", 1, -1e6, 1e6, &m->x, why, cap) ||
            get_number(o, "y", 1, -1e6, 1e6, &m->y, why, cap))
            return -1;
    } else if (strcmp(type, "thumbnails") == 0) {
        static const char *const keys[] = {"type", "size", NULL};
        m->type = SRV_THUMBNAILS;
        m->size = 96;
        if (only_keys(o, keys, why, cap) || get_int(o, "size", 0, 16, 256, &m->size, why, cap) < 0)
            return -1;
    } else if (strcmp(type, "list") == 0 || strcmp(type, "open") == 0 ||
               strcmp(type, "save") == 0) {
        static const char *const keys[] = {"type", "path", NULL};
        m->type = type[0] == 'l' ? SRV_LIST : type[0] == 'o' ? SRV_OPEN : SRV_SAVE;
        if (only_keys(o, keys, why, cap) ||
            get_string(o, "path", 1, m->path, sizeof m->path, why, cap))
            return -1;
    } else {
        return fail(why, cap, "unknown message type '%s'", type);
    }
    return 0;
}

int
srv_msg_parse(const char *text, size_t len, srv_msg *out, char *why, size_t cap) {
    memset(out, 0, sizeof *out);
    if (len > SRV_MSG_MAX)
        return fail(why, cap, "message of %zu bytes (at most %d)", len, SRV_MSG_MAX);
    json_error_t err;
    json_t *o = json_loadb(text, len, JSON_REJECT_DUPLICATES, &err);
    if (!o)
        return fail(why, cap, "not JSON: line %d, column %d: %.80s", err.line, err.column,
                    err.text);
    int rc =
        json_is_object(o) ? parse_object(o, out, why, cap) : fail(why, cap, "not a JSON object");
    json_decref(o);
    return rc;
}

/* ---- paths ---------------------------------------------------------------------------- */

/* 1 when real path @p p is @p root or inside it. */
static int
inside(const char *root, const char *p) {
    size_t n = strlen(root);
    if (strncmp(p, root, n) != 0)
        return 0;
    return p[n] == '\0' || p[n] == '/' || (n == 1 && root[0] == '/');
}

int
srv_path_resolve(const char *root, const char *rel, int kind, char *out, size_t cap, char *why,
                 size_t why_cap) {
    if (rel[0] == '/')
        return fail(why, why_cap, "'%s': an absolute path (paths are relative to the root)", rel);
    /* every component: not empty (but a trailing one), not "." or ".." */
    for (const char *c = rel; *c;) {
        size_t n = strcspn(c, "/");
        if ((n == 1 && c[0] == '.') || (n == 2 && c[0] == '.' && c[1] == '.'))
            return fail(why, why_cap, "'%s': '.' and '..' are not allowed", rel);
        if (n == 0 && c[1] != '\0')
            return fail(why, why_cap, "'%s': an empty path component", rel);
        for (size_t i = 0; i < n; i++)
            if ((unsigned char)c[i] < 0x20 || c[i] == 0x7f)
                return fail(why, why_cap, "a control byte in the path");
        c += n;
        if (*c == '/')
            c++;
    }
    char full[PATH_MAX + 8];
    int k = snprintf(full, sizeof full, "%s%s%s", root, *rel ? "/" : "", rel);
    if (k < 0 || (size_t)k >= sizeof full)
        return fail(why, why_cap, "'%s': path too long", rel);
    size_t fl = strlen(full);
    while (fl > 1 && full[fl - 1] == '/')
        full[--fl] = '\0';
    char real[PATH_MAX];
    if (kind == 2) {
        /* a file to write: its folder must be real and inside; itself no link, no folder */
        char *slash = strrchr(full, '/');
        const char *base = slash + 1;
        size_t bl = strlen(base);
        if (bl < 6 || strcmp(base + bl - 5, ".json") != 0)
            return fail(why, why_cap, "'%s': a session is saved as a .json file", rel);
        *slash = '\0';
        if (!realpath(full[0] ? full : "/", real))
            return fail(why, why_cap, "'%s': its folder: %s", rel, strerror(errno));
        *slash = '/';
        if (!inside(root, real))
            return fail(why, why_cap, "'%s' leaves the root folder", rel);
        struct stat st;
        if (lstat(full, &st) == 0 && !S_ISREG(st.st_mode))
            return fail(why, why_cap, "'%s' exists and is not a regular file", rel);
        k = snprintf(out, cap, "%s/%s", real, base);
        if (k < 0 || (size_t)k >= cap)
            return fail(why, why_cap, "'%s': path too long", rel);
        return 0;
    }
    if (!realpath(full, real))
        return fail(why, why_cap, "'%s': %s", rel, strerror(errno));
    if (!inside(root, real))
        return fail(why, why_cap, "'%s' leaves the root folder", rel);
    struct stat st;
    if (stat(real, &st) != 0)
        return fail(why, why_cap, "'%s': %s", rel, strerror(errno));
    if (kind == 1 && !S_ISDIR(st.st_mode))
        return fail(why, why_cap, "'%s' is not a folder", rel);
    if (kind == 0 && !S_ISDIR(st.st_mode) && !S_ISREG(st.st_mode))
        return fail(why, why_cap, "'%s' is not a regular file or a folder", rel);
    if ((size_t)snprintf(out, cap, "%s", real) >= cap)
        return fail(why, why_cap, "'%s': path too long", rel);
    return 0;
}

int
srv_folder_is_store(const char *path) {
    size_t n = strlen(path);
    while (n > 1 && path[n - 1] == '/')
        n--;
    if (n >= 5 && strncmp(path + n - 5, ".zarr", 5) == 0)
        return 1;
    static const char *const marks[] = {".zgroup", ".zarray", ".zattrs"};
    for (int i = 0; i < 3; i++) {
        char p[PATH_MAX + 16];
        struct stat st;
        if ((size_t)snprintf(p, sizeof p, "%.*s/%s", (int)n, path, marks[i]) < sizeof p &&
            stat(p, &st) == 0 && S_ISREG(st.st_mode))
            return 1;
    }
    return 0;
}
