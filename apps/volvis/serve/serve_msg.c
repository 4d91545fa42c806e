/*
 * The messages a browser client sends (docs/serve-protocol.md): parsed with
 * Jansson, every field's type and range checked, paths confined to the
 * root. Pure: no libwebsockets, no session state (fuzzed by
 * tests/fuzz/fuzz_serve_msg.c).
 */
#define _GNU_SOURCE
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <limits.h>
#include <linux/openat2.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

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
    } else if (strcmp(type, "open") == 0) {
        static const char *const keys[] = {"type", "path", "url", NULL};
        m->type = SRV_OPEN;
        if (only_keys(o, keys, why, cap))
            return -1;
        int p = get_string(o, "path", 0, m->path, sizeof m->path, why, cap);
        int u = p < 0 ? -1 : get_string(o, "url", 0, m->url, sizeof m->url, why, cap);
        if (p < 0 || u < 0)
            return -1;
        if (p == u)
            return fail(why, cap, "'open' takes one of 'path' and 'url'");
    } else if (strcmp(type, "list") == 0 || strcmp(type, "save") == 0) {
        static const char *const keys[] = {"type", "path", NULL};
        m->type = type[0] == 'l' ? SRV_LIST : SRV_SAVE;
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

int srv_openat2_off;

int
srv_open_beneath(int dirfd, const char *rel, int flags) {
    if (!srv_openat2_off) {
        struct open_how how;
        memset(&how, 0, sizeof how);
        how.flags = (uint64_t)(unsigned)(flags | O_CLOEXEC);
        how.resolve = RESOLVE_BENEATH | RESOLVE_NO_MAGICLINKS;
        long fd = syscall(SYS_openat2, dirfd, *rel ? rel : ".", &how, sizeof how);
        if (fd >= 0 || errno != ENOSYS)
            return (int)fd;
    }
    /* no openat2: one component at a time, following no link */
    if (!*rel)
        return openat(dirfd, ".", flags | O_CLOEXEC);
    int cur = openat(dirfd, ".", O_PATH | O_DIRECTORY | O_CLOEXEC);
    if (cur < 0)
        return -1;
    for (const char *c = rel; *c;) {
        size_t n = strcspn(c, "/");
        const char *next = c + n;
        while (*next == '/')
            next++;
        char name[NAME_MAX + 1];
        if (n == 0 || n > NAME_MAX || (n == 2 && c[0] == '.' && c[1] == '.')) {
            close(cur);
            errno = n > NAME_MAX ? ENAMETOOLONG : EXDEV;
            return -1;
        }
        memcpy(name, c, n);
        name[n] = '\0';
        int last = *next == '\0';
        int fd = openat(cur, name,
                        last ? flags | O_NOFOLLOW | O_CLOEXEC
                             : O_PATH | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
        int e = errno;
        struct stat ls;
        if (fd < 0 && (e == ENOTDIR || e == ELOOP) &&
            fstatat(cur, name, &ls, AT_SYMLINK_NOFOLLOW) == 0 && S_ISLNK(ls.st_mode))
            e = ELOOP; /* a link (O_NOFOLLOW with O_DIRECTORY says ENOTDIR): refused as one */
        close(cur);
        if (fd < 0) {
            errno = e;
            return -1;
        }
        struct stat st;
        if (last && (flags & O_PATH) && fstat(fd, &st) == 0 && S_ISLNK(st.st_mode)) {
            close(fd); /* O_PATH | O_NOFOLLOW opens the link itself */
            errno = ELOOP;
            return -1;
        }
        if (last)
            return fd;
        cur = fd;
        c = next;
    }
    close(cur); /* not reached: the last component returned */
    errno = EINVAL;
    return -1;
}

/* The path of open @p fd (its /proc/self/fd link: no link left in it) into @p out, which
 * must lie inside @p root. 0 or -1. */
static int
fd_path(int fd, const char *root, char *out, size_t cap) {
    char proc[64];
    snprintf(proc, sizeof proc, "/proc/self/fd/%d", fd);
    ssize_t n = readlink(proc, out, cap - 1);
    if (n <= 0 || (size_t)n >= cap - 1)
        return -1;
    out[n] = '\0';
    return inside(root, out) ? 0 : -1;
}

/* The reason of a refused srv_open_beneath of @p rel. */
static int
beneath_fail(const char *rel, const char *what, char *why, size_t why_cap) {
    if (errno == EXDEV || errno == ELOOP)
        return fail(why, why_cap,
                    "'%s'%s leaves the root folder (a link out, or a link where "
                    "none may be)",
                    rel, what);
    return fail(why, why_cap, "'%s'%s: %s", rel, what, strerror(errno));
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
    char r[PATH_MAX];
    size_t rl = strlen(rel);
    if (rl >= sizeof r)
        return fail(why, why_cap, "'%s': path too long", rel);
    memcpy(r, rel, rl + 1);
    while (rl > 0 && r[rl - 1] == '/')
        r[--rl] = '\0';
    int rootfd = open(root, O_PATH | O_DIRECTORY | O_CLOEXEC);
    if (rootfd < 0)
        return fail(why, why_cap, "the root folder %s: %s", root, strerror(errno));
    int rc = 0;
    char real[PATH_MAX];
    if (kind == 2) {
        /* a file to write: its folder opened beneath the root; itself no link, no folder */
        char *slash = strrchr(r, '/');
        const char *base = slash ? slash + 1 : r;
        size_t bl = strlen(base);
        if (bl < 6 || strcmp(base + bl - 5, ".json") != 0) {
            close(rootfd);
            return fail(why, why_cap, "'%s': a session is saved as a .json file", rel);
        }
        if (slash)
            *slash = '\0';
        int dfd = srv_open_beneath(rootfd, slash ? r : "", O_PATH | O_DIRECTORY);
        if (dfd < 0) {
            rc = beneath_fail(rel, errno == ENOENT ? ": its folder" : "", why, why_cap);
        } else {
            struct stat st;
            if (fd_path(dfd, root, real, sizeof real))
                rc = fail(why, why_cap, "'%s' leaves the root folder", rel);
            else if (fstatat(dfd, base, &st, AT_SYMLINK_NOFOLLOW) == 0 && !S_ISREG(st.st_mode))
                rc = fail(why, why_cap, "'%s' exists and is not a regular file", rel);
            else if ((size_t)snprintf(out, cap, "%s/%s", strcmp(real, "/") ? real : "", base) >=
                     cap)
                rc = fail(why, why_cap, "'%s': path too long", rel);
            close(dfd);
        }
        close(rootfd);
        return rc;
    }
    int fd = srv_open_beneath(rootfd, r, O_PATH);
    close(rootfd);
    if (fd < 0)
        return beneath_fail(rel, "", why, why_cap);
    struct stat st;
    if (fstat(fd, &st) != 0)
        rc = fail(why, why_cap, "'%s': %s", rel, strerror(errno));
    else if (kind == 1 && !S_ISDIR(st.st_mode))
        rc = fail(why, why_cap, "'%s' is not a folder", rel);
    else if (kind == 0 && !S_ISDIR(st.st_mode) && !S_ISREG(st.st_mode))
        rc = fail(why, why_cap, "'%s' is not a regular file or a folder", rel);
    else if (fd_path(fd, root, real, sizeof real))
        rc = fail(why, why_cap, "'%s' leaves the root folder", rel);
    else if ((size_t)snprintf(out, cap, "%s", real) >= cap)
        rc = fail(why, why_cap, "'%s': path too long", rel);
    close(fd);
    return rc;
}

/* ---- a scene's files ---------------------------------------------------------------- */

/* Largest scene file checked, bytes (the scene loader's own limit is larger than any
 * real scene; a larger one is refused here). */
#define SCENE_MAX (64 << 20)

typedef struct scene_walk {
    const char *root;
    int rootfd;
    const char *scene_rel; /* the scene, relative to the root */
    char dir[PATH_MAX];    /* the scene's folder, relative to the root ("" the root) */
    char *const *urls, *const *prefixes; /* the URLs allowed */
    int n_urls, n_prefixes;
    char *why;
    size_t cap;
} scene_walk;

/* Lexically joins folder @p dir (relative to the root) and @p entry into @p out, resolving
 * "." and ".."; -1 when ".." climbs above the root. */
static int
join_inside(const char *dir, const char *entry, char *out, size_t cap) {
    char buf[2 * PATH_MAX];
    if ((size_t)snprintf(buf, sizeof buf, "%s/%s", dir, entry) >= sizeof buf)
        return -1;
    size_t n = 0;
    out[0] = '\0';
    for (char *save = NULL, *c = strtok_r(buf, "/", &save); c; c = strtok_r(NULL, "/", &save)) {
        if (strcmp(c, ".") == 0)
            continue;
        if (strcmp(c, "..") == 0) {
            if (n == 0)
                return -1;
            char *slash = strrchr(out, '/');
            n = slash ? (size_t)(slash - out) : 0;
            out[n] = '\0';
            continue;
        }
        size_t cl = strlen(c);
        if (n + cl + 2 > cap)
            return -1;
        if (n)
            out[n++] = '/';
        memcpy(out + n, c, cl + 1);
        n += cl;
    }
    return 0;
}

static int
check_entry(scene_walk *w, const char *key, const char *entry) {
    char rel[PATH_MAX];
    if (srv_is_url(entry)) {
        /* a URL (once the door reads them): only one the server was told */
        char norm[SRV_URL_MAX], why2[256];
        if (srv_url_normalize(entry, norm, sizeof norm, why2, sizeof why2) != 0 ||
            !srv_url_allowed(norm, w->urls, w->n_urls, w->prefixes, w->n_prefixes))
            return fail(w->why, w->cap,
                        "scene '%s': \"%s\" '%.200s' is not a URL the server was given",
                        w->scene_rel, key, entry);
        return 0;
    }
    if (entry[0] == '/') {
        size_t n = strlen(w->root);
        if (!inside(w->root, entry) ||
            join_inside("", entry + (n == 1 ? 0 : n), rel, sizeof rel) != 0)
            return fail(w->why, w->cap, "scene '%s': \"%s\" '%s' lies outside the root folder",
                        w->scene_rel, key, entry);
    } else if (join_inside(w->dir, entry, rel, sizeof rel) != 0) {
        return fail(w->why, w->cap, "scene '%s': \"%s\" '%s' leaves the root folder", w->scene_rel,
                    key, entry);
    }
    int fd = srv_open_beneath(w->rootfd, rel, O_PATH);
    if (fd < 0 && (errno == EXDEV || errno == ELOOP))
        return fail(w->why, w->cap, "scene '%s': \"%s\" '%s' leaves the root folder (a link out)",
                    w->scene_rel, key, entry);
    if (fd >= 0)
        close(fd);
    return 0; /* inside, or missing: the door says what is missing */
}

static int
walk_json(scene_walk *w, json_t *v, int depth) {
    if (depth > 64)
        return 0; /* the door refuses such nesting itself */
    if (json_is_array(v)) {
        size_t i;
        json_t *x;
        json_array_foreach(v, i, x) {
            if (walk_json(w, x, depth + 1))
                return -1;
        }
    } else if (json_is_object(v)) {
        const char *k;
        json_t *x;
        json_object_foreach(v, k, x) {
            /* the members the scene loader reads as paths (vv_path_join_dir): an
             * object's "file", a texture's "image" and a solid texture's "volume" */
            if ((strcmp(k, "file") == 0 || strcmp(k, "image") == 0 || strcmp(k, "volume") == 0) &&
                json_is_string(x)) {
                if (check_entry(w, k, json_string_value(x)))
                    return -1;
            } else if (walk_json(w, x, depth + 1)) {
                return -1;
            }
        }
    }
    return 0;
}

int
srv_scene_confined(const char *root, const char *scene, char *const *urls, int n_urls,
                   char *const *prefixes, int n_prefixes, char *why, size_t cap) {
    size_t n = strlen(root);
    if (!inside(root, scene) || !scene[n] || !scene[n + 1])
        return fail(why, cap, "scene '%s' lies outside the root folder", scene);
    scene_walk w = {.root = root,
                    .urls = urls,
                    .n_urls = n_urls,
                    .prefixes = prefixes,
                    .n_prefixes = n_prefixes,
                    .why = why,
                    .cap = cap};
    w.scene_rel = scene + (n == 1 ? 1 : n + 1);
    snprintf(w.dir, sizeof w.dir, "%s", w.scene_rel);
    char *slash = strrchr(w.dir, '/');
    if (slash)
        *slash = '\0';
    else
        w.dir[0] = '\0';
    w.rootfd = open(root, O_PATH | O_DIRECTORY | O_CLOEXEC);
    if (w.rootfd < 0)
        return fail(why, cap, "the root folder %s: %s", root, strerror(errno));
    int fd = srv_open_beneath(w.rootfd, w.scene_rel, O_RDONLY | O_NONBLOCK);
    if (fd < 0) {
        int rc = beneath_fail(w.scene_rel, "", why, cap);
        close(w.rootfd);
        return rc;
    }
    struct stat st;
    int rc = 0;
    /* a scene as the door tells one: a name ending in .json, or '{' after white space */
    size_t sl = strlen(scene);
    int is_scene = sl >= 5 && strcasecmp(scene + sl - 5, ".json") == 0;
    char head[4096];
    ssize_t got = is_scene ? 0 : pread(fd, head, sizeof head, 0);
    for (ssize_t i = 0; i < got && !is_scene; i++) {
        if (head[i] == '{')
            is_scene = 1;
        else if (!isspace((unsigned char)head[i]))
            break;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || !is_scene) {
        /* a folder or a volume file: nothing to check */
    } else if (st.st_size <= SCENE_MAX) {
        json_error_t err;
        json_t *j = json_loadfd(fd, 0, &err);
        if (j)
            rc = walk_json(&w, j, 0);
        json_decref(j);
    } else {
        rc = fail(why, cap, "scene '%s': larger than %d MiB", w.scene_rel, SCENE_MAX >> 20);
    }
    close(fd);
    close(w.rootfd);
    return rc;
}

/* ---- URLs ------------------------------------------------------------------------------ */

int
srv_is_url(const char *s) {
    size_t n = strspn(s, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789+-.");
    return n > 0 && isalpha((unsigned char)s[0]) && strncmp(s + n, "://", 3) == 0;
}

static int
hexval(int c) {
    return c >= '0' && c <= '9'   ? c - '0'
           : c >= 'a' && c <= 'f' ? c - 'a' + 10
           : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                  : -1;
}

/* Appends @p len bytes to out (at *n); -1 when full. */
static int
put(char *out, size_t cap, size_t *n, const char *s, size_t len) {
    if (*n + len + 1 > cap)
        return -1;
    memcpy(out + *n, s, len);
    *n += len;
    out[*n] = '\0';
    return 0;
}

int
srv_url_normalize(const char *in, char *out, size_t cap, char *why, size_t why_cap) {
    size_t len = strlen(in);
    if (len >= SRV_URL_MAX)
        return fail(why, why_cap, "a URL of %zu bytes (at most %d)", len, SRV_URL_MAX - 1);
    for (size_t i = 0; i < len; i++) {
        unsigned char c = (unsigned char)in[i];
        if (c <= 0x20 || c >= 0x7f)
            return fail(why, why_cap, "'%.200s': a space, control or non-ASCII byte in the URL",
                        in);
        if (c == '\\')
            return fail(why, why_cap, "'%.200s': a backslash in the URL", in);
    }
    if (!srv_is_url(in))
        return fail(why, why_cap, "'%.200s' is not a URL", in);
    const char *sep = strstr(in, "://");
    char scheme[8];
    size_t sl = (size_t)(sep - in);
    if (sl >= sizeof scheme)
        return fail(why, why_cap, "'%.200s': only http, https and s3 URLs", in);
    for (size_t i = 0; i < sl; i++)
        scheme[i] = (char)tolower((unsigned char)in[i]);
    scheme[sl] = '\0';
    int s3 = strcmp(scheme, "s3") == 0;
    int dflt = strcmp(scheme, "http") == 0 ? 80 : strcmp(scheme, "https") == 0 ? 443 : 0;
    if (!s3 && !dflt)
        return fail(why, why_cap, "'%.200s': only http, https and s3 URLs", in);
    const char *a = sep + 3;
    size_t al = strcspn(a, "/?#");
    if (memchr(a, '@', al))
        return fail(why, why_cap, "'%.200s': user information in a URL is refused", in);
    /* the host, and the port */
    char host[256];
    size_t hl;
    const char *after;
    if (a[0] == '[') {
        const char *close_b = memchr(a, ']', al);
        if (!close_b || close_b == a + 1)
            return fail(why, why_cap, "'%.200s': a malformed IPv6 address", in);
        hl = (size_t)(close_b - a) + 1;
        for (const char *p = a + 1; p < close_b; p++)
            if (!isxdigit((unsigned char)*p) && *p != ':' && *p != '.')
                return fail(why, why_cap, "'%.200s': a malformed IPv6 address", in);
        after = close_b + 1;
    } else {
        hl = strcspn(a, ":/?#");
        if (hl > al)
            hl = al;
        for (size_t i = 0; i < hl; i++)
            if (!isalnum((unsigned char)a[i]) && a[i] != '-' && a[i] != '.' && !(s3 && a[i] == '_'))
                return fail(why, why_cap, "'%.200s': a host of letters, digits, '-' and '.' only",
                            in);
        after = a + hl;
    }
    if (hl == 0 || hl >= sizeof host)
        return fail(why, why_cap, "'%.200s': no host%s", in, hl ? " of at most 255 bytes" : "");
    for (size_t i = 0; i < hl; i++)
        host[i] = (char)tolower((unsigned char)a[i]);
    host[hl] = '\0';
    if (host[0] == '.' || host[0] == '-' || strstr(host, ".."))
        return fail(why, why_cap, "'%.200s': a malformed host", in);
    int port = 0;
    if (after < a + al) {
        if (*after != ':' || after + 1 == a + al)
            return fail(why, why_cap, "'%.200s': a malformed port", in);
        if (s3)
            return fail(why, why_cap, "'%.200s': an s3:// URL names a bucket, not a port", in);
        long p = 0;
        for (const char *q = after + 1; q < a + al; q++) {
            if (!isdigit((unsigned char)*q) || (p = p * 10 + (*q - '0')) > 65535)
                return fail(why, why_cap, "'%.200s': a malformed port", in);
        }
        if (p == 0)
            return fail(why, why_cap, "'%.200s': port 0", in);
        port = (int)p;
    }
    size_t n = 0;
    char buf[32];
    out[0] = '\0';
    if (put(out, cap, &n, scheme, sl) || put(out, cap, &n, "://", 3) || put(out, cap, &n, host, hl))
        return fail(why, why_cap, "'%.200s': too long", in);
    if (port && port != dflt) {
        int k = snprintf(buf, sizeof buf, ":%d", port);
        if (put(out, cap, &n, buf, (size_t)k))
            return fail(why, why_cap, "'%.200s': too long", in);
    }
    /* the path, segment by segment */
    const char *p = a + al;
    size_t pl = strcspn(p, "?#");
    if (pl == 0 && put(out, cap, &n, "/", 1))
        return fail(why, why_cap, "'%.200s': too long", in);
    for (size_t i = 0; i < pl;) {
        /* p[i] == '/' */
        size_t seg_start = n;
        if (put(out, cap, &n, "/", 1))
            return fail(why, why_cap, "'%.200s': too long", in);
        i++;
        size_t j = i;
        while (j < pl && p[j] != '/') {
            char c = p[j];
            if (c == '%') {
                int h = j + 2 < pl ? hexval(p[j + 1]) : -1, l = h >= 0 ? hexval(p[j + 2]) : -1;
                if (h < 0 || l < 0)
                    return fail(why, why_cap, "'%.200s': a malformed percent-escape", in);
                int v = h * 16 + l;
                if (v == '/' || v == '\\' || v == 0)
                    return fail(why, why_cap,
                                "'%.200s': an encoded '/', '\\' or NUL in the path is refused", in);
                if (isalnum(v) || v == '-' || v == '.' || v == '_' || v == '~') {
                    buf[0] = (char)v;
                    if (put(out, cap, &n, buf, 1))
                        return fail(why, why_cap, "'%.200s': too long", in);
                } else {
                    snprintf(buf, sizeof buf, "%%%02X", v);
                    if (put(out, cap, &n, buf, 3))
                        return fail(why, why_cap, "'%.200s': too long", in);
                }
                j += 3;
                continue;
            }
            if (put(out, cap, &n, &c, 1))
                return fail(why, why_cap, "'%.200s': too long", in);
            j++;
        }
        const char *seg = out + seg_start + 1;
        size_t sn = n - seg_start - 1;
        int last = j == pl;
        if ((sn == 0 && !last) || (sn == 1 && seg[0] == '.') ||
            (sn == 2 && seg[0] == '.' && seg[1] == '.'))
            return fail(why, why_cap, "'%.200s': an empty, '.' or '..' path segment is refused",
                        in);
        i = j;
    }
    if (p[pl] == '?') {
        size_t ql = strcspn(p + pl, "#");
        if (ql > 1 && put(out, cap, &n, p + pl, ql))
            return fail(why, why_cap, "'%.200s': too long", in);
    }
    return 0;
}

/* The length of @p url's scheme and authority (up to its path's first '/'). */
static size_t
authority_len(const char *url) {
    const char *a = strstr(url, "://");
    return a ? (size_t)(a + 3 - url) + strcspn(a + 3, "/") : 0;
}

int
srv_url_allowed(const char *url, char *const *urls, int n_urls, char *const *prefixes,
                int n_prefixes) {
    for (int i = 0; i < n_urls; i++)
        if (strcmp(url, urls[i]) == 0)
            return 1;
    if (strchr(url, '?'))
        return 0;
    size_t ua = authority_len(url);
    for (int i = 0; i < n_prefixes; i++) {
        const char *pre = prefixes[i];
        size_t pa = authority_len(pre), pn = strlen(pre);
        if (!ua || pa != ua || strncmp(url, pre, pa) != 0 || strncmp(url, pre, pn) != 0)
            continue;
        if (pre[pn - 1] == '/' || url[pn] == '/' || url[pn] == '\0')
            return 1;
    }
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
