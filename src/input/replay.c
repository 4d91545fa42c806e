/*
 * The replay driver: a recording (docs/input.md, "Replay files") is read
 * and fully validated, then its events are fed on a virtual clock. Also the
 * event-line parser shared with the network driver.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "input_internal.h"

#define REPLAY_MAX_BYTES (64u << 20)
#define REPLAY_MAX_DEVICES 16
/* Seconds an event may be late before the rest of the replay is delayed: a
 * caller that stalled (a busy main loop) must not get a recorded motion
 * delivered all at once, which would collapse its duration to nothing. */
#define REPLAY_MAX_LAG 0.1

int
vv_input_tokenize(char *line, char **tok, int max) {
    int n = 0;
    char *p = line;
    while (*p) {
        while (*p == ' ' || *p == '\t' || *p == '\r')
            p++;
        if (!*p)
            break;
        if (n == max)
            return max + 1;
        tok[n++] = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\r')
            p++;
        if (*p)
            *p++ = '\0';
    }
    return n;
}

static int
parse_num(const char *s, double *out) {
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end)
        return 0;
    *out = v;
    return 1;
}

static int
parse_int(const char *s, long lo, long hi, int *out) {
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < lo || v > hi)
        return 0;
    *out = (int)v;
    return 1;
}

vv_status
vv_input_parse_event(char **tok, int ntok, vv_input_raw_event *ev, char *err, size_t errsz) {
    memset(ev, 0, sizeof *ev);
    int k;
    for (k = 0; k < VV_RAW_KIND_COUNT; k++)
        if (strcmp(tok[0], vv_input_raw_kind_name((vv_input_raw_kind)k)) == 0)
            break;
    if (k == VV_RAW_KIND_COUNT) {
        snprintf(err, errsz, "unknown event kind '%.32s'", tok[0]);
        return VV_ERR_FORMAT;
    }
    ev->kind = (vv_input_raw_kind)k;
    int nv = vv_input_raw_kind_values(ev->kind);
    if (ntok != 3 + nv) {
        snprintf(err, errsz, "'%s' takes a device, a code and %d value%s (got %d fields)", tok[0],
                 nv, nv == 1 ? "" : "s", ntok - 1);
        return VV_ERR_FORMAT;
    }
    if (!parse_int(tok[1], 1, 1000000, &ev->device)) {
        snprintf(err, errsz, "device '%.32s' is not an integer in 1..1000000", tok[1]);
        return VV_ERR_FORMAT;
    }
    if (!parse_int(tok[2], 0, 0x7fffffff, &ev->code)) {
        snprintf(err, errsz, "code '%.32s' is not a non-negative integer", tok[2]);
        return VV_ERR_FORMAT;
    }
    if ((ev->kind == VV_RAW_BUTTON && ev->code > 63) || (ev->kind == VV_RAW_AXIS && ev->code > 5)) {
        snprintf(err, errsz, "%s code %d out of range (%s)", tok[0], ev->code,
                 ev->kind == VV_RAW_AXIS ? "0..5" : "0..63");
        return VV_ERR_FORMAT;
    }
    for (int i = 0; i < nv; i++) {
        if (!parse_num(tok[3 + i], &ev->v[i])) {
            snprintf(err, errsz, "value %d '%.32s' is not a number", i + 1, tok[3 + i]);
            return VV_ERR_FORMAT;
        }
        if (!isfinite(ev->v[i])) {
            snprintf(err, errsz, "value %d '%.32s' is not finite", i + 1, tok[3 + i]);
            return VV_ERR_FORMAT;
        }
    }
    return VV_OK;
}

typedef struct replay_dev {
    int file_id;
    vv_input_kind kind;
    char name[VV_INPUT_NAME_MAX];
    int id; /* in the manager */
} replay_dev;

typedef struct replay {
    vv_input_raw_event *ev;
    size_t n, next;
    replay_dev dev[REPLAY_MAX_DEVICES];
    int n_dev;
    double start, speed, t0;
} replay;

static vv_status
bad(const char *path, int line, const char *msg) {
    return vv_error_set(VV_ERR_FORMAT, "replay: %s: line %d: %s", path, line, msg);
}

static vv_status
parse_file(const char *path, char *text, uint64_t size, replay *r) {
    char msg[160];
    size_t cap = 0;
    int line = 0, have_header = 0;
    double last_t = -INFINITY;
    char *p = text, *end = text + size;
    if (memchr(text, '\0', size))
        return vv_error_set(VV_ERR_FORMAT, "replay: %s: contains NUL bytes (not a text file)",
                            path);
    while (p < end) {
        char *nl = memchr(p, '\n', (size_t)(end - p));
        char *le = nl ? nl : end;
        line++;
        if (le - p > VV_INPUT_LINE_MAX)
            return bad(path, line, "line longer than 1024 characters");
        char buf[VV_INPUT_LINE_MAX + 1];
        memcpy(buf, p, (size_t)(le - p));
        buf[le - p] = '\0';
        p = nl ? nl + 1 : end;
        char *hash = strchr(buf, '#');
        if (hash)
            *hash = '\0';
        char *tok[16];
        int nt = vv_input_tokenize(buf, tok, 15);
        if (nt == 0)
            continue;
        if (nt > 15)
            return bad(path, line, "too many fields");
        if (!have_header) {
            if (nt != 2 || strcmp(tok[0], "volvis-input") != 0)
                return bad(path, line, "expected the header 'volvis-input 1'");
            if (strcmp(tok[1], "1") != 0)
                return bad(path, line, "unsupported version (this build reads version 1)");
            have_header = 1;
            continue;
        }
        if (strcmp(tok[0], "device") == 0) {
            replay_dev *d = &r->dev[r->n_dev];
            if (nt < 4)
                return bad(path, line, "'device' takes an id, a kind and a name");
            if (r->n_dev >= REPLAY_MAX_DEVICES)
                return bad(path, line, "more than 16 devices");
            if (!parse_int(tok[1], 1, 1000000, &d->file_id))
                return bad(path, line, "device id is not an integer in 1..1000000");
            for (int i = 0; i < r->n_dev; i++)
                if (r->dev[i].file_id == d->file_id)
                    return bad(path, line, "device id declared twice");
            if (vv_input_kind_parse(tok[2], &d->kind) != VV_OK) {
                vv_error_clear();
                snprintf(msg, sizeof msg, "unknown device kind '%.32s'", tok[2]);
                return bad(path, line, msg);
            }
            /* the name is the rest of the line, single-spaced */
            d->name[0] = '\0';
            for (int i = 3; i < nt; i++) {
                size_t len = strlen(d->name);
                snprintf(d->name + len, sizeof d->name - len, "%s%s", i > 3 ? " " : "", tok[i]);
            }
            r->n_dev++;
            continue;
        }
        if (nt < 2)
            return bad(path, line, "expected 'device ...' or 'TIME KIND DEVICE CODE VALUES...'");
        double t;
        if (!parse_num(tok[0], &t) || !isfinite(t)) {
            snprintf(msg, sizeof msg, "time '%.32s' is not a finite number", tok[0]);
            return bad(path, line, msg);
        }
        if (t < last_t) {
            snprintf(msg, sizeof msg, "time %.17g goes backwards (previous %.17g)", t, last_t);
            return bad(path, line, msg);
        }
        last_t = t;
        vv_input_raw_event ev;
        if (vv_input_parse_event(tok + 1, nt - 1, &ev, msg, sizeof msg) != VV_OK)
            return bad(path, line, msg);
        int found = 0;
        for (int i = 0; i < r->n_dev; i++)
            found |= r->dev[i].file_id == ev.device;
        if (!found) {
            snprintf(msg, sizeof msg, "device %d was not declared", ev.device);
            return bad(path, line, msg);
        }
        ev.time = t;
        if (r->n == cap) {
            cap = cap ? 2 * cap : 256;
            vv_input_raw_event *ne = realloc(r->ev, cap * sizeof *ne);
            if (!ne)
                return vv_error_set(VV_ERR_NOMEM, "replay: %s: out of memory", path);
            r->ev = ne;
        }
        r->ev[r->n++] = ev;
    }
    if (!have_header)
        return vv_error_set(VV_ERR_FORMAT, "replay: %s: empty file (no 'volvis-input 1' header)",
                            path);
    if (r->n_dev == 0)
        return vv_error_set(VV_ERR_FORMAT, "replay: %s: declares no device", path);
    return VV_OK;
}

static double
due(const replay *r, size_t i) {
    if (isinf(r->speed))
        return -INFINITY;
    return r->start + (r->ev[i].time - r->t0) / r->speed;
}

static void
replay_poll(vv_input_manager *m, vv_input_driver *drv, double now) {
    replay *r = drv->self;
    double slack = 0;
    if (r->next < r->n && !isinf(r->speed)) {
        double late = now - due(r, r->next);
        if (late > REPLAY_MAX_LAG) {
            r->start += late; /* the rest keeps its recorded spacing from now on */
            slack = 1e-9;     /* the next event is due now, whatever the rounding */
        }
    }
    while (r->next < r->n && due(r, r->next) <= now + slack) {
        vv_input_raw_event ev = r->ev[r->next++];
        for (int i = 0; i < r->n_dev; i++)
            if (r->dev[i].file_id == ev.device) {
                ev.device = r->dev[i].id;
                break;
            }
        if (vv_input_manager_feed(m, &ev) != VV_OK)
            vv_error_clear(); /* counted as a warning by feed */
    }
}

static double
replay_timeout(const vv_input_manager *m, const vv_input_driver *drv, double now) {
    (void)m;
    const replay *r = drv->self;
    if (r->next >= r->n)
        return -1;
    double t = due(r, r->next) - now;
    return t > 0 ? t : 0;
}

static void
replay_close(vv_input_manager *m, vv_input_driver *drv) {
    (void)m;
    replay *r = drv->self;
    if (!r)
        return;
    free(r->ev);
    free(r);
    drv->self = NULL;
}

vv_status
vv_input_manager_open_replay(vv_input_manager *m, const char *path, double start, double speed,
                             int *first_id, int *n_devices) {
    if (!m || !path || !(speed > 0) || !isfinite(start))
        return vv_error_set(VV_ERR_INVALID, "replay: needs a file, a finite start and speed > 0");
    unsigned char *text = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, REPLAY_MAX_BYTES, &text, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "replay: %s", path);
    replay *r = calloc(1, sizeof *r);
    if (!r) {
        free(text);
        return vv_error_set(VV_ERR_NOMEM, "replay: out of memory");
    }
    s = parse_file(path, (char *)text, size, r);
    free(text);
    if (s == VV_OK && m->n_dev + r->n_dev > VV_INPUT_MAX_DEVICES)
        s = vv_error_set(VV_ERR_LIMIT, "replay: %s: too many devices for the manager", path);
    if (s != VV_OK) {
        free(r->ev);
        free(r);
        return s;
    }
    r->start = start;
    r->speed = speed;
    r->t0 = r->n ? r->ev[0].time : 0;
    vv_input_driver drv = {"replay", r, NULL, replay_poll, replay_timeout, replay_close};
    if (vv_input_driver_add(m, &drv) < 0) { /* its message: no driver left */
        replay_close(m, &drv);
        return vv_error_prefix(VV_ERR_LIMIT, "replay: %s", path);
    }
    for (int i = 0; i < r->n_dev; i++) {
        vv_input_device_add_driver(m, r->dev[i].kind, r->dev[i].name, "replay", &r->dev[i].id);
        if (i == 0 && first_id)
            *first_id = r->dev[i].id;
    }
    if (n_devices)
        *n_devices = r->n_dev;
    return VV_OK;
}

int
vv_input_manager_replay_pending(const vv_input_manager *m) {
    for (int i = 0; m && i < m->n_drivers; i++)
        if (m->drivers[i].poll == replay_poll) {
            const replay *r = m->drivers[i].self;
            if (r && r->next < r->n)
                return 1;
        }
    return 0;
}
