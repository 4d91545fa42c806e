/*
 * Internals of the input component: the manager's structure and the driver
 * interface shared by the drivers (spnav.c, sdl.c, replay.c, net.c).
 */
#ifndef VV_INPUT_INTERNAL_H
#define VV_INPUT_INTERNAL_H

#include <stdio.h>

#include "core/internal.h"
#include "volvis/input.h"

#define VV_INPUT_MAX_DEVICES 64
#define VV_INPUT_MAX_SUBS 32
#define VV_INPUT_MAX_DRIVERS 8
/** Longest line of a replay file or of the network protocol (bytes, without newline). */
#define VV_INPUT_LINE_MAX 1024

struct vv_input_driver;
typedef struct vv_input_driver vv_input_driver;

/**
 * A driver: fds it watches go into the manager's epoll set with
 * vv_input_watch(); ready() is called with the ready fd, poll() on every
 * dispatch (timer-driven drivers), timeout() says when poll() is next
 * needed (-1: never), close() releases everything.
 */
struct vv_input_driver {
    const char *name;
    void *self;
    void (*ready)(vv_input_manager *m, vv_input_driver *d, int fd, double now);
    void (*poll)(vv_input_manager *m, vv_input_driver *d, double now);
    double (*timeout)(const vv_input_manager *m, const vv_input_driver *d, double now);
    void (*close)(vv_input_manager *m, vv_input_driver *d);
};

typedef struct input_device {
    int id;
    vv_input_kind kind;
    char name[VV_INPUT_NAME_MAX];
    char driver[16];
    char app[VV_INPUT_NAME_MAX];
    const vv_input_devinfo *info;
    vv_input_method method;
    vv_vec3 *features;
    int n_features;
    vv_input_state st;
    double raw_axes[6]; /* absolute axis state (controllers, network axis events) */
    double key_axes[6]; /* keyboard axis keys held */
    double last_motion; /* time of the last MOTION, or NAN */
    double press_time[64];
    int has_pos;        /* a position was seen (two-hand) */
    vv_vec3 drag_start; /* snap-drag start */
    int dragging;
    int n_bindings;
    vv_input_binding bindings[VV_INPUT_MAX_BINDINGS + 16];
} input_device;

typedef struct input_sub {
    int id; /* 0: free slot */
    char app[VV_INPUT_NAME_MAX];
    vv_input_action_fn fn;
    void *user;
} input_sub;

struct vv_input_devinfo_db {
    vv_input_devinfo e[VV_INPUT_KIND_COUNT];
};

struct vv_input_manager {
    vv_input_devinfo_db db;
    input_device *dev[VV_INPUT_MAX_DEVICES];
    int n_dev;
    input_sub subs[VV_INPUT_MAX_SUBS];
    int next_sub;
    vv_input_driver drivers[VV_INPUT_MAX_DRIVERS];
    int n_drivers;
    int epfd;
    vv_input_action *queue;
    size_t n_queue, cap_queue;
    int delivering;
    uint64_t warnings;
    char last_warning[256];
    /* recording */
    vv_atomic_file rec;
    int recording;
    /* replay state lives in its driver; these let the public query see it */
    int spnav_open;
    int sdl_open;
    int listening;
};

/** Registers a driver (copied); returns its index or -1 (too many, with a trace). */
int vv_input_driver_add(vv_input_manager *m, const vv_input_driver *d);
/** Adds / removes @p fd in the manager's epoll set, tagged with driver @p index. */
vv_status vv_input_watch(vv_input_manager *m, int index, int fd);
void vv_input_unwatch(vv_input_manager *m, int fd);
/** Counts a warning and keeps its text (never printed). */
void vv_input_warn(vv_input_manager *m, const char *fmt, ...) VV_PRINTF(2, 3);
/** Adds a device with the given driver name (*id may be NULL). */
vv_status vv_input_device_add_driver(vv_input_manager *m, vv_input_kind kind, const char *name,
                                     const char *driver, int *id);
/** Marks device @p id as driven by @p driver (name shown by the CLI). */
void vv_input_device_set_driver(vv_input_manager *m, int id, const char *driver);

/**
 * Parses the event fields of a replay line or a network line: tokens
 * "KIND DEVICE CODE V..." (tok[0] is the kind). Fills ev (device = the
 * number as written). On error returns VV_ERR_FORMAT with a message in
 * @p err (no trace change).
 */
vv_status vv_input_parse_event(char **tok, int ntok, vv_input_raw_event *ev, char *err,
                               size_t errsz);
/** Splits @p line in place at blanks; returns the number of tokens (at most max). */
int vv_input_tokenize(char *line, char **tok, int max);

/** Number of values a raw event of kind @p k carries (0..7). */
int vv_input_raw_kind_values(vv_input_raw_kind k);

#endif
