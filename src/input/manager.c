/*
 * The input manager: virtual devices, the simulation of raw events into
 * abstract actions, subscribers, the epoll set of the drivers, recording
 * (VolVis, Avila et al. 1994, sec. 6: the Device Unified Interface).
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <time.h>
#include <unistd.h>

#include "input_internal.h"

#define POS_LIMIT 1e6 /* positions are clamped to +-this (px, mm, ...) */
#define SCROLL_LIMIT 100
#define DT_MAX 0.25 /* a motion after a pause integrates at most this long */

double
vv_input_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void
vv_input_warn(vv_input_manager *m, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(m->last_warning, sizeof m->last_warning, fmt, ap);
    va_end(ap);
    /* a warning may quote what a network client or a replay file sent:
       one printable line */
    for (char *c = m->last_warning; *c; c++)
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            *c = '?';
    m->warnings++;
}

uint64_t
vv_input_manager_warning_count(const vv_input_manager *m) {
    return m ? m->warnings : 0;
}

const char *
vv_input_manager_last_warning(const vv_input_manager *m) {
    return m ? m->last_warning : "";
}

static input_device *
find_dev(const vv_input_manager *m, int id) {
    if (!m || id < 1 || id > m->n_dev)
        return NULL;
    return m->dev[id - 1];
}

/* ---- creation -------------------------------------------------------------- */

vv_status
vv_input_manager_new(vv_input_manager **out, const vv_input_devinfo_db *db) {
    *out = NULL;
    vv_input_manager *m = calloc(1, sizeof *m);
    if (!m)
        return vv_error_set(VV_ERR_NOMEM, "input: out of memory");
    if (db) {
        m->db = *db;
    } else {
        vv_input_devinfo_db *d = NULL;
        if (vv_input_devinfo_db_load(&d, NULL, 0) == VV_OK) {
            m->db = *d;
            vv_input_devinfo_db_free(d);
        } else {
            /* a broken user file must not stop input: built-in defaults */
            vv_input_warn(m, "%s", vv_error_message());
            vv_error_clear();
            const char *none = NULL;
            if (vv_input_devinfo_db_load(&d, &none, 1) == VV_OK) {
                m->db = *d;
                vv_input_devinfo_db_free(d);
            }
        }
    }
    m->epfd = epoll_create1(EPOLL_CLOEXEC);
    if (m->epfd < 0) {
        vv_status s = vv_error_set(VV_ERR_IO, "input: epoll_create1: %s", strerror(errno));
        free(m);
        return s;
    }
    int id;
    if (vv_input_manager_device_add(m, VV_INPUT_KEYBOARD, "keyboard", &id) != VV_OK ||
        vv_input_manager_device_add(m, VV_INPUT_MOUSE, "mouse", &id) != VV_OK) {
        vv_input_manager_free(m);
        return VV_ERR_NOMEM;
    }
    *out = m;
    return VV_OK;
}

void
vv_input_manager_free(vv_input_manager *m) {
    if (!m)
        return;
    for (int i = m->n_drivers - 1; i >= 0; i--)
        if (m->drivers[i].close)
            m->drivers[i].close(m, &m->drivers[i]);
    if (m->recording)
        vv_input_manager_record_stop(m);
    for (int i = 0; i < m->n_dev; i++) {
        free(m->dev[i]->features);
        free(m->dev[i]);
    }
    free(m->queue);
    if (m->epfd >= 0)
        close(m->epfd);
    free(m);
}

vv_status
vv_input_device_add_driver(vv_input_manager *m, vv_input_kind kind, const char *name,
                           const char *driver, int *id) {
    if (!m || (unsigned)kind >= VV_INPUT_KIND_COUNT)
        return vv_error_set(VV_ERR_INVALID, "input: device kind %d out of range", (int)kind);
    if (m->n_dev >= VV_INPUT_MAX_DEVICES)
        return vv_error_set(VV_ERR_LIMIT, "input: more than %d devices", VV_INPUT_MAX_DEVICES);
    input_device *d = calloc(1, sizeof *d);
    if (!d)
        return vv_error_set(VV_ERR_NOMEM, "input: out of memory");
    d->id = m->n_dev + 1;
    d->kind = kind;
    snprintf(d->name, sizeof d->name, "%s", name && *name ? name : vv_input_kind_name(kind));
    /* names are one token-free line in recordings, and printable: a name a
     * replay file or a network client gives may hold terminal escapes */
    for (char *c = d->name; *c; c++)
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            *c = ' ';
    snprintf(d->driver, sizeof d->driver, "%s", driver ? driver : "gui");
    d->info = &m->db.e[kind];
    d->method = d->info->method;
    d->st.orientation = vv_quat_identity();
    d->st.present = 1;
    d->last_motion = NAN;
    d->n_bindings = d->info->n_bindings;
    memcpy(d->bindings, d->info->bindings, sizeof d->info->bindings);
    m->dev[m->n_dev++] = d;
    if (m->recording)
        fprintf(m->rec.fp, "device %d %s %s\n", d->id, vv_input_kind_name(kind), d->name);
    if (id)
        *id = d->id;
    return VV_OK;
}

vv_status
vv_input_manager_device_add(vv_input_manager *m, vv_input_kind kind, const char *name, int *id) {
    return vv_input_device_add_driver(m, kind, name, "gui", id);
}

void
vv_input_device_set_driver(vv_input_manager *m, int id, const char *driver) {
    input_device *d = find_dev(m, id);
    if (d)
        snprintf(d->driver, sizeof d->driver, "%s", driver);
}

int
vv_input_manager_device_count(const vv_input_manager *m) {
    return m ? m->n_dev : 0;
}

vv_status
vv_input_manager_device_get(const vv_input_manager *m, int index, vv_input_device_desc *out) {
    if (!m || index < 0 || index >= m->n_dev)
        return vv_error_set(VV_ERR_INVALID, "input: device index %d out of range", index);
    const input_device *d = m->dev[index];
    memset(out, 0, sizeof *out);
    out->id = d->id;
    out->kind = d->kind;
    memcpy(out->name, d->name, sizeof out->name);
    memcpy(out->driver, d->driver, sizeof out->driver);
    memcpy(out->app, d->app, sizeof out->app);
    out->present = d->st.present;
    out->info = d->info;
    return VV_OK;
}

vv_status
vv_input_manager_state(const vv_input_manager *m, int id, vv_input_state *out) {
    const input_device *d = find_dev(m, id);
    if (!d)
        return vv_error_set(VV_ERR_INVALID, "input: no device %d", id);
    *out = d->st;
    return VV_OK;
}

/* ---- configuration ----------------------------------------------------------- */

vv_status
vv_input_manager_subscribe(vv_input_manager *m, const char *app, vv_input_action_fn fn, void *user,
                           int *sub_id) {
    if (!m || !fn)
        return vv_error_set(VV_ERR_INVALID, "input: subscribe needs a manager and a callback");
    for (int i = 0; i < VV_INPUT_MAX_SUBS; i++) {
        input_sub *s = &m->subs[i];
        if (s->id)
            continue;
        s->id = ++m->next_sub;
        snprintf(s->app, sizeof s->app, "%s", app ? app : "");
        s->fn = fn;
        s->user = user;
        if (sub_id)
            *sub_id = s->id;
        return VV_OK;
    }
    return vv_error_set(VV_ERR_LIMIT, "input: more than %d subscribers", VV_INPUT_MAX_SUBS);
}

void
vv_input_manager_unsubscribe(vv_input_manager *m, int sub_id) {
    for (int i = 0; m && sub_id > 0 && i < VV_INPUT_MAX_SUBS; i++)
        if (m->subs[i].id == sub_id)
            memset(&m->subs[i], 0, sizeof m->subs[i]);
}

vv_status
vv_input_manager_assign(vv_input_manager *m, int id, const char *app) {
    input_device *d = find_dev(m, id);
    if (!d)
        return vv_error_set(VV_ERR_INVALID, "input: no device %d", id);
    snprintf(d->app, sizeof d->app, "%s", app ? app : "");
    return VV_OK;
}

static vv_status
check_method(const vv_input_method *mt) {
    if (!mt || (unsigned)mt->kind > VV_METHOD_TWO_HAND)
        return vv_error_set(VV_ERR_INVALID, "input: unknown simulation method");
    if (!(mt->dead_zone >= 0 && mt->dead_zone < 1) || !(mt->exponent >= 1 && mt->exponent <= 10) ||
        !(mt->gain > 0 && mt->gain < 1e6) || !(mt->grid >= 0 && isfinite(mt->grid)) ||
        !(mt->feature_radius >= 0 && isfinite(mt->feature_radius)) ||
        !(mt->snap_angle >= 0 && mt->snap_angle <= VV_PI / 2))
        return vv_error_set(VV_ERR_INVALID,
                            "input: method parameters out of range (dead zone [0,1), exponent "
                            "[1,10], gain > 0, grid and radius >= 0, snap angle [0, pi/2])");
    return VV_OK;
}

vv_status
vv_input_manager_set_method(vv_input_manager *m, int id, const vv_input_method *method) {
    input_device *d = find_dev(m, id);
    if (!d)
        return vv_error_set(VV_ERR_INVALID, "input: no device %d", id);
    vv_status s = check_method(method);
    if (s != VV_OK)
        return s;
    d->method = *method;
    return VV_OK;
}

vv_status
vv_input_manager_get_method(const vv_input_manager *m, int id, vv_input_method *out) {
    const input_device *d = find_dev(m, id);
    if (!d)
        return vv_error_set(VV_ERR_INVALID, "input: no device %d", id);
    *out = d->method;
    return VV_OK;
}

vv_status
vv_input_manager_set_features(vv_input_manager *m, int id, const vv_vec3 *points, int n) {
    input_device *d = find_dev(m, id);
    if (!d || n < 0 || (n > 0 && !points) || n > 1000000)
        return vv_error_set(VV_ERR_INVALID, "input: bad device or feature points");
    vv_vec3 *copy = NULL;
    if (n > 0) {
        copy = malloc((size_t)n * sizeof *copy);
        if (!copy)
            return vv_error_set(VV_ERR_NOMEM, "input: out of memory");
        memcpy(copy, points, (size_t)n * sizeof *copy);
    }
    free(d->features);
    d->features = copy;
    d->n_features = n;
    return VV_OK;
}

vv_status
vv_input_manager_pair(vv_input_manager *m, int a, int b) {
    input_device *da = find_dev(m, a), *db = find_dev(m, b);
    if (!da || !db || a == b)
        return vv_error_set(VV_ERR_INVALID, "input: pairing needs two distinct devices");
    da->method.kind = db->method.kind = VV_METHOD_TWO_HAND;
    da->method.partner = b;
    db->method.partner = a;
    return VV_OK;
}

vv_status
vv_input_manager_bind(vv_input_manager *m, int id, vv_input_raw_kind kind, int code,
                      const char *command) {
    input_device *d = find_dev(m, id);
    if (!d || (kind != VV_RAW_KEY && kind != VV_RAW_BUTTON))
        return vv_error_set(VV_ERR_INVALID, "input: bind needs a device and a key or button");
    if (command && strlen(command) >= VV_INPUT_COMMAND_MAX)
        return vv_error_set(VV_ERR_INVALID, "input: command name longer than %d characters",
                            VV_INPUT_COMMAND_MAX - 1);
    int n = d->n_bindings;
    for (int i = 0; i < n; i++) {
        if (d->bindings[i].kind != (int)kind || d->bindings[i].code != code)
            continue;
        if (command) {
            snprintf(d->bindings[i].command, sizeof d->bindings[i].command, "%s", command);
        } else {
            d->bindings[i] = d->bindings[n - 1];
            d->n_bindings--;
        }
        return VV_OK;
    }
    if (!command)
        return VV_OK;
    if (n >= (int)(sizeof d->bindings / sizeof d->bindings[0]))
        return vv_error_set(VV_ERR_LIMIT, "input: too many bindings on device %d", id);
    d->bindings[n].kind = (int)kind;
    d->bindings[n].code = code;
    snprintf(d->bindings[n].command, sizeof d->bindings[n].command, "%s", command);
    d->n_bindings++;
    return VV_OK;
}

/* ---- actions -------------------------------------------------------------------- */

static vv_input_action
new_action(vv_input_action_kind kind, const input_device *d, double t) {
    vv_input_action a;
    memset(&a, 0, sizeof a);
    a.kind = kind;
    a.device = d->id;
    a.time = t;
    a.rotation = vv_quat_identity();
    a.scale = 1;
    a.feature = -1;
    return a;
}

static void
push(vv_input_manager *m, const vv_input_action *a) {
    if (m->n_queue == m->cap_queue) {
        size_t cap = m->cap_queue ? 2 * m->cap_queue : 64;
        vv_input_action *q = realloc(m->queue, cap * sizeof *q);
        if (!q) {
            vv_input_warn(m, "input: out of memory, action dropped");
            return;
        }
        m->queue = q;
        m->cap_queue = cap;
    }
    m->queue[m->n_queue++] = *a;
}

static int
deliver(vv_input_manager *m) {
    if (m->delivering)
        return 0;
    m->delivering = 1;
    int n = 0;
    /* subscribers may feed more events: the queue can grow while we walk it */
    for (size_t i = 0; i < m->n_queue; i++) {
        vv_input_action a = m->queue[i];
        const input_device *d = find_dev(m, a.device);
        const char *app = d ? d->app : "";
        for (int s = 0; s < VV_INPUT_MAX_SUBS; s++) {
            input_sub *sub = &m->subs[s];
            if (!sub->id)
                continue;
            if (app[0] && sub->app[0] && strcmp(app, sub->app) != 0)
                continue;
            sub->fn(sub->user, &a);
        }
        n++;
    }
    m->n_queue = 0;
    m->delivering = 0;
    return n;
}

/* ---- simulation -------------------------------------------------------------------- */

static double
clampd(double x, double lo, double hi) {
    return x < lo ? lo : x > hi ? hi : x;
}

static double
motion_dt(input_device *d, double t, double fallback) {
    double dt = isnan(d->last_motion) ? fallback : t - d->last_motion;
    d->last_motion = t;
    return clampd(dt, 0, DT_MAX);
}

/* The direct mapping of normalized axes, then a MOTION action, state integrated. */
static void
emit_motion(vv_input_manager *m, input_device *d, const double in[6], double t, double dt_hint) {
    double v[6];
    const vv_input_method *mt = &d->method;
    for (int i = 0; i < 6; i++)
        v[i] = clampd(in[i], -1, 1);
    if (mt->dominant_axis)
        vv_input_dominant_axis(v);
    for (int i = 0; i < 6; i++)
        v[i] = clampd(mt->gain * vv_input_response(v[i], mt->dead_zone, mt->exponent), -1, 1);
    double dt = motion_dt(d, t, dt_hint);
    vv_input_action a = new_action(VV_ACTION_MOTION, d, t);
    memcpy(a.motion, v, sizeof v);
    a.dt = dt;
    vv_vec3 w = vv_vec3_make(v[3], v[4], v[5]);
    double wl = vv_vec3_length(w);
    if (wl > 0 && dt > 0)
        a.rotation = vv_quat_from_axis_angle(w, wl * dt);
    memcpy(d->st.axes, v, sizeof v);
    if (d->kind != VV_INPUT_MOUSE) {
        d->st.velocity = vv_vec3_make(v[0], v[1], v[2]);
        d->st.angular_velocity = w;
        d->st.position = vv_vec3_add(d->st.position, vv_vec3_scale(d->st.velocity, dt));
        d->st.orientation = vv_quat_normalize(vv_quat_mul(a.rotation, d->st.orientation));
    }
    push(m, &a);
}

static const char *
binding_for(const input_device *d, int kind, int code) {
    for (int i = 0; i < d->n_bindings; i++)
        if (d->bindings[i].kind == kind && d->bindings[i].code == code)
            return d->bindings[i].command;
    return NULL;
}

/* "axis:+tx" -> axis 0, sign +1 */
static int
parse_axis_binding(const char *cmd, int *axis, double *sign) {
    static const char *const names[6] = {"tx", "ty", "tz", "rx", "ry", "rz"};
    if (strncmp(cmd, "axis:", 5) != 0 || (cmd[5] != '+' && cmd[5] != '-'))
        return 0;
    for (int i = 0; i < 6; i++)
        if (strcmp(cmd + 6, names[i]) == 0) {
            *axis = i;
            *sign = cmd[5] == '+' ? 1 : -1;
            return 1;
        }
    return 0;
}

static void
on_button(vv_input_manager *m, input_device *d, int kind, int code, int down, double t) {
    const char *cmd = binding_for(d, kind, code);
    int axis;
    double sign;
    if (cmd && parse_axis_binding(cmd, &axis, &sign)) {
        d->key_axes[axis] = down ? sign : 0;
        emit_motion(m, d, d->key_axes, t, 0);
        return;
    }
    if (kind == VV_RAW_BUTTON) {
        uint64_t bit = (uint64_t)1 << code;
        int was = (d->st.buttons & bit) != 0;
        if (down == was)
            return; /* repeated press or stray release */
        vv_input_action a =
            new_action(down ? VV_ACTION_BUTTON_PRESS : VV_ACTION_BUTTON_RELEASE, d, t);
        a.button = code;
        push(m, &a);
        if (down) {
            d->st.buttons |= bit;
            d->press_time[code] = t;
            if (!d->dragging) {
                d->dragging = 1;
                d->drag_start = d->st.position;
            }
        } else {
            d->st.buttons &= ~bit;
            if (!d->st.buttons)
                d->dragging = 0;
            if (t - d->press_time[code] <= d->info->click_time) {
                a.kind = VV_ACTION_BUTTON_CLICK;
                push(m, &a);
            }
        }
    }
    if (cmd && down) {
        vv_input_action a = new_action(VV_ACTION_COMMAND, d, t);
        snprintf(a.command, sizeof a.command, "%s", cmd);
        a.button = code;
        push(m, &a);
    }
}

/* A new position of a pointer or a pose: snap-drag, two-hand, or a plain pose. */
static int
on_position(vv_input_manager *m, input_device *d, vv_vec3 p, double t) {
    vv_vec3 old = d->st.position;
    int had = d->has_pos;
    double dt = t - d->st.time;
    if (had && dt > 0)
        d->st.velocity = vv_vec3_scale(vv_vec3_sub(p, old), 1 / dt);
    d->st.position = p;
    d->has_pos = 1;
    if (d->method.kind == VV_METHOD_TWO_HAND) {
        input_device *o = find_dev(m, d->method.partner);
        if (o && o->has_pos && o->st.present && had) {
            input_device *first = d->id < o->id ? d : o;
            vv_vec3 a0 = d == first ? old : o->st.position;
            vv_vec3 b0 = d == first ? o->st.position : old;
            vv_vec3 a1 = d == first ? p : o->st.position;
            vv_vec3 b1 = d == first ? o->st.position : p;
            vv_input_two_hand r = vv_input_two_hand_solve(a0, b0, a1, b1);
            vv_input_action a = new_action(VV_ACTION_TWO_HAND, first, t);
            a.translation = r.translation;
            a.rotation = r.rotation;
            a.scale = r.scale;
            a.position = r.center;
            push(m, &a);
        }
        return 1;
    }
    if (d->method.kind == VV_METHOD_SNAP_DRAG && d->dragging) {
        vv_input_snap_params sp = {d->method.snap_axes,      d->method.snap_angle, d->method.grid,
                                   d->method.feature_radius, d->features,          d->n_features};
        vv_input_action a = new_action(VV_ACTION_SNAP_DRAG, d, t);
        a.position = vv_input_snap(&sp, d->drag_start, p, &a.snap, &a.feature);
        push(m, &a);
        return 1;
    }
    return 0;
}

static void
on_pointer(vv_input_manager *m, input_device *d, double x, double y, double t) {
    vv_vec3 old = d->st.position;
    int had = d->has_pos;
    if (on_position(m, d, vv_vec3_make(x, y, 0), t))
        return;
    if (had && d->st.buttons) {
        double s = 1 / d->info->pixels_per_unit;
        double dx = (x - old.x) * s, dy = (y - old.y) * s;
        double v[6] = {0};
        if (d->st.buttons & 2) { /* left: rotate like a trackball */
            v[4] = dx;
            v[3] = dy;
        } else if (d->st.buttons & 8) { /* right: pan (screen y points down) */
            v[0] = dx;
            v[1] = -dy;
        } else if (d->st.buttons & 4) { /* middle: dolly */
            v[2] = dy;
        }
        emit_motion(m, d, v, t, 0);
        return;
    }
    vv_input_action a = new_action(VV_ACTION_POSE, d, t);
    a.position = d->st.position;
    a.rotation = d->st.orientation;
    push(m, &a);
}

/* Non-finite values drop the event; out-of-range ones are clamped. 0: drop. */
static int
sanitize(vv_input_manager *m, const input_device *d, vv_input_raw_event *e) {
    int nv = vv_input_raw_kind_values(e->kind);
    for (int i = 0; i < nv; i++)
        if (!isfinite(e->v[i])) {
            vv_input_warn(m, "input: device %d: %s event with a non-finite value dropped", d->id,
                          vv_input_raw_kind_name(e->kind));
            return 0;
        }
    for (int i = nv; i < VV_INPUT_RAW_VALUES; i++)
        e->v[i] = 0;
    if (!isfinite(e->time)) {
        vv_input_warn(m, "input: device %d: event with a non-finite time dropped", d->id);
        return 0;
    }
    int clamped = 0;
#define CLAMP(x, lo, hi)                                                                           \
    do {                                                                                           \
        double c_ = clampd((x), (lo), (hi));                                                       \
        clamped |= c_ != (x);                                                                      \
        (x) = c_;                                                                                  \
    } while (0)
    switch (e->kind) {
    case VV_RAW_KEY:
    case VV_RAW_BUTTON:
        if (e->code < 0 || (e->kind == VV_RAW_BUTTON && e->code > 63)) {
            vv_input_warn(m, "input: device %d: %s code %d out of range, dropped", d->id,
                          vv_input_raw_kind_name(e->kind), e->code);
            return 0;
        }
        e->v[0] = e->v[0] != 0;
        break;
    case VV_RAW_POINTER:
        CLAMP(e->v[0], -POS_LIMIT, POS_LIMIT);
        CLAMP(e->v[1], -POS_LIMIT, POS_LIMIT);
        break;
    case VV_RAW_SCROLL:
        CLAMP(e->v[0], -SCROLL_LIMIT, SCROLL_LIMIT);
        CLAMP(e->v[1], -SCROLL_LIMIT, SCROLL_LIMIT);
        break;
    case VV_RAW_AXIS:
        if (e->code < 0 || e->code > 5) {
            vv_input_warn(m, "input: device %d: axis %d out of range 0..5, dropped", d->id,
                          e->code);
            return 0;
        }
        CLAMP(e->v[0], -1, 1);
        break;
    case VV_RAW_MOTION6:
        for (int i = 0; i < 6; i++) {
            double r = d->info->n_dof > i && d->info->dof[i].max > 0 ? d->info->dof[i].max : 350;
            CLAMP(e->v[i], -r, r);
        }
        CLAMP(e->v[6], 0, 1000);
        break;
    case VV_RAW_POSE:
        for (int i = 0; i < 3; i++)
            CLAMP(e->v[i], -POS_LIMIT, POS_LIMIT);
        for (int i = 3; i < 7; i++)
            CLAMP(e->v[i], -1e3, 1e3);
        break;
    default:
        break;
    }
#undef CLAMP
    if (clamped)
        vv_input_warn(m, "input: device %d: %s event clamped to the device's range", d->id,
                      vv_input_raw_kind_name(e->kind));
    return 1;
}

static void
record(vv_input_manager *m, const vv_input_raw_event *e) {
    FILE *fp = m->rec.fp;
    fprintf(fp, "%.17g %s %d %d", e->time, vv_input_raw_kind_name(e->kind), e->device, e->code);
    for (int i = 0; i < vv_input_raw_kind_values(e->kind); i++)
        fprintf(fp, " %.17g", e->v[i]);
    fputc('\n', fp);
}

static void
process(vv_input_manager *m, input_device *d, const vv_input_raw_event *e) {
    double t = e->time;
    switch (e->kind) {
    case VV_RAW_KEY:
    case VV_RAW_BUTTON:
        on_button(m, d, e->kind, e->code, e->v[0] != 0, t);
        break;
    case VV_RAW_POINTER:
        on_pointer(m, d, e->v[0], e->v[1], t);
        break;
    case VV_RAW_SCROLL: {
        double v[6] = {0, 0, clampd(0.1 * e->v[1], -1, 1), 0, 0, 0};
        emit_motion(m, d, v, t, 0);
        break;
    }
    case VV_RAW_AXIS:
        d->raw_axes[e->code] = e->v[0];
        emit_motion(m, d, d->raw_axes, t, 0);
        break;
    case VV_RAW_MOTION6: {
        double v[6];
        for (int i = 0; i < 6; i++) {
            double r = d->info->n_dof > i && d->info->dof[i].max > 0 ? d->info->dof[i].max : 350;
            v[i] = e->v[i] / r;
        }
        emit_motion(m, d, v, t, e->v[6] / 1000);
        break;
    }
    case VV_RAW_POSE: {
        vv_quat q = vv_quat_normalize((vv_quat){e->v[3], e->v[4], e->v[5], e->v[6]});
        d->st.orientation = q;
        if (!on_position(m, d, vv_vec3_make(e->v[0], e->v[1], e->v[2]), t)) {
            vv_input_action a = new_action(VV_ACTION_POSE, d, t);
            a.position = d->st.position;
            a.rotation = q;
            push(m, &a);
        }
        break;
    }
    case VV_RAW_ADDED: {
        d->st.present = 1;
        vv_input_action a = new_action(VV_ACTION_DEVICE_ADDED, d, t);
        push(m, &a);
        break;
    }
    case VV_RAW_REMOVED: {
        d->st.present = 0;
        d->st.buttons = 0;
        d->dragging = 0;
        memset(d->st.axes, 0, sizeof d->st.axes);
        memset(d->raw_axes, 0, sizeof d->raw_axes);
        memset(d->key_axes, 0, sizeof d->key_axes);
        d->st.velocity = d->st.angular_velocity = vv_vec3_make(0, 0, 0);
        vv_input_action a = new_action(VV_ACTION_DEVICE_REMOVED, d, t);
        push(m, &a);
        break;
    }
    default:
        break;
    }
    d->st.time = t;
}

vv_status
vv_input_manager_feed(vv_input_manager *m, const vv_input_raw_event *ev) {
    if (!m || !ev)
        return vv_error_set(VV_ERR_INVALID, "input: feed needs a manager and an event");
    input_device *d = find_dev(m, ev->device);
    if (!d || (unsigned)ev->kind >= VV_RAW_KIND_COUNT) {
        vv_input_warn(m, "input: event for unknown device %d or of unknown kind %d dropped",
                      ev->device, (int)ev->kind);
        return vv_error_set(VV_ERR_INVALID, "input: unknown device %d or event kind %d", ev->device,
                            (int)ev->kind);
    }
    vv_input_raw_event e = *ev;
    if (!sanitize(m, d, &e))
        return VV_OK;
    if (!d->st.present && e.kind != VV_RAW_ADDED) {
        vv_input_warn(m, "input: event for removed device %d dropped", d->id);
        return VV_OK;
    }
    if (m->recording)
        record(m, &e);
    process(m, d, &e);
    deliver(m);
    return VV_OK;
}

/* ---- drivers and the main loop ------------------------------------------------------ */

int
vv_input_driver_add(vv_input_manager *m, const vv_input_driver *d) {
    if (m->n_drivers >= VV_INPUT_MAX_DRIVERS) {
        vv_error_set(VV_ERR_LIMIT, "input: more than %d drivers", VV_INPUT_MAX_DRIVERS);
        return -1;
    }
    m->drivers[m->n_drivers] = *d;
    return m->n_drivers++;
}

vv_status
vv_input_watch(vv_input_manager *m, int index, int fd) {
    struct epoll_event ev;
    memset(&ev, 0, sizeof ev);
    ev.events = EPOLLIN;
    ev.data.u64 = ((uint64_t)(uint32_t)index << 32) | (uint32_t)fd;
    if (epoll_ctl(m->epfd, EPOLL_CTL_ADD, fd, &ev) != 0)
        return vv_error_set(VV_ERR_IO, "input: epoll_ctl: %s", strerror(errno));
    return VV_OK;
}

void
vv_input_unwatch(vv_input_manager *m, int fd) {
    epoll_ctl(m->epfd, EPOLL_CTL_DEL, fd, NULL);
}

int
vv_input_manager_fd(const vv_input_manager *m) {
    return m ? m->epfd : -1;
}

double
vv_input_manager_timeout(const vv_input_manager *m, double now) {
    double best = -1;
    for (int i = 0; m && i < m->n_drivers; i++) {
        const vv_input_driver *d = &m->drivers[i];
        if (!d->timeout)
            continue;
        double t = d->timeout(m, d, now);
        if (t >= 0 && (best < 0 || t < best))
            best = t;
    }
    return best;
}

int
vv_input_manager_dispatch(vv_input_manager *m, double now) {
    if (!m)
        return 0;
    struct epoll_event evs[32];
    int n;
    /* a bounded number of rounds so a flooding peer cannot starve the UI */
    for (int round = 0; round < 16; round++) {
        n = epoll_wait(m->epfd, evs, 32, 0);
        if (n <= 0)
            break;
        for (int i = 0; i < n; i++) {
            int idx = (int)(evs[i].data.u64 >> 32);
            int fd = (int)(uint32_t)evs[i].data.u64;
            if (idx >= 0 && idx < m->n_drivers && m->drivers[idx].ready)
                m->drivers[idx].ready(m, &m->drivers[idx], fd, now);
        }
        if (n < 32)
            break;
    }
    for (int i = 0; i < m->n_drivers; i++)
        if (m->drivers[i].poll)
            m->drivers[i].poll(m, &m->drivers[i], now);
    return deliver(m);
}

/* ---- recording ---------------------------------------------------------------------- */

vv_status
vv_input_manager_record_start(vv_input_manager *m, const char *path) {
    if (!m || !path)
        return vv_error_set(VV_ERR_INVALID, "input: record needs a manager and a path");
    if (m->recording)
        return vv_error_set(VV_ERR_INVALID, "input: already recording");
    vv_status s = vv_atomic_file_open(&m->rec, path);
    if (s != VV_OK)
        return vv_error_prefix(s, "record: %s", path);
    m->recording = 1;
    fprintf(m->rec.fp, "volvis-input 1\n");
    for (int i = 0; i < m->n_dev; i++)
        fprintf(m->rec.fp, "device %d %s %s\n", m->dev[i]->id, vv_input_kind_name(m->dev[i]->kind),
                m->dev[i]->name);
    return VV_OK;
}

vv_status
vv_input_manager_record_stop(vv_input_manager *m) {
    if (!m || !m->recording)
        return vv_error_set(VV_ERR_INVALID, "input: not recording");
    m->recording = 0;
    vv_status s = vv_atomic_file_commit(&m->rec);
    return s == VV_OK ? s : vv_error_prefix(s, "record");
}
