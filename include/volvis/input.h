/*
 * VolVis input devices: the Device Unified Interface (DUI) of Avila et al.,
 * "VolVis: A Diversified Volume Visualization System", IEEE Vis '94, sec. 6.
 *
 * Raw data from a keyboard, a mouse, a 3-D mouse (Spaceball, SpaceNavigator
 * through spacenavd), a game controller (SDL2), a replayed recording or a
 * network peer become one VIRTUAL INPUT DEVICE per physical device: a
 * position, an orientation, velocities, buttons, and a stream of abstract
 * ACTIONS with timestamps (6-DOF navigation motion, button press / release /
 * click, named commands, snap-drag and two-hand results, device added /
 * removed). Applications (the Navigator, the Animator's flight-path
 * recorder, the GUI's commands) subscribe to actions, never to raw devices.
 * How raw data become actions is a SIMULATION METHOD (direct mapping with a
 * dead zone and a response curve, snap-dragging, two-hand), swappable per
 * device at run time without touching the application.
 *
 * A DEVICE INFORMATION BASE (one JSON file per device kind, share/devices/)
 * keeps each kind's facts: degrees of freedom with ranges and units, whether
 * they are coupled, what the device is good for, its default simulation
 * method and bindings. See docs/input.md for the file formats (information
 * base, replay files, the network protocol).
 *
 * Main-loop integration: vv_input_manager_fd() is ONE file descriptor (an
 * epoll set of every driver's descriptor) that becomes readable when some
 * device has data; vv_input_manager_timeout() says when the manager next
 * needs a call without any descriptor being ready (the replay clock, the SDL
 * controller poll). The caller then calls vv_input_manager_dispatch(now),
 * which reads what is ready and calls the subscribers. Nothing spins: with
 * no input the process sleeps.
 *
 * Units: times are seconds on the caller's monotonic clock (for replay, the
 * recording's own times); angles radians; pointer positions pixels;
 * normalized axes are in [-1, 1].
 *
 * Thread-safety: a manager is used from one thread (the UI thread); distinct
 * managers are independent, except that the 3-D mouse driver (libspnav keeps
 * one global connection) can be open in one manager per process at a time.
 * Subscriber callbacks run on the thread that calls feed or dispatch.
 */
#ifndef VOLVIS_INPUT_H
#define VOLVIS_INPUT_H

#include <stdint.h>

#include "core.h"
#include "math.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- device kinds and the information base --------------------------------- */

/** Kind of a physical (or simulated) device; the information base has one entry per kind. */
typedef enum vv_input_kind {
    VV_INPUT_KEYBOARD = 0,
    VV_INPUT_MOUSE,
    VV_INPUT_SPACEBALL,      /**< any 3-D mouse served by spacenavd */
    VV_INPUT_GAMECONTROLLER, /**< an SDL2 game controller */
    VV_INPUT_DATAGLOVE,      /**< poses only; served by replay and the network driver */
    VV_INPUT_NETWORK,        /**< a generic device driven over the network socket */
    VV_INPUT_KIND_COUNT
} vv_input_kind;

/** "keyboard", "mouse", "spaceball", "gamecontroller", "dataglove", "network". */
const char *vv_input_kind_name(vv_input_kind k);
/** Kind from its name; VV_ERR_INVALID for an unknown name. */
vv_status vv_input_kind_parse(const char *name, vv_input_kind *out);

#define VV_INPUT_MAX_DOF 8
#define VV_INPUT_NAME_MAX 64

/** Simulation methods (how raw data become actions). */
typedef enum vv_input_method_kind {
    VV_METHOD_DIRECT = 0, /**< dead zone + response curve, optional dominant-axis filter */
    VV_METHOD_SNAP_DRAG,  /**< positions snap to axes, a grid and feature points */
    VV_METHOD_TWO_HAND    /**< two paired devices give translate / rotate / scale */
} vv_input_method_kind;

/** A simulation method and its parameters (a plain value; feature points are copied). */
typedef struct vv_input_method {
    vv_input_method_kind kind;
    /* direct mapping (normalized axes) */
    double dead_zone;  /**< |x| below this reads 0; in [0, 1) */
    double exponent;   /**< response curve |x|^exponent (1 linear, 2 quadratic, 3 cubic); >= 1 */
    int dominant_axis; /**< 1: keep only the largest of the six axes (coupled 3-D mice) */
    double gain;       /**< multiplies the result (then clamped to [-1, 1]); default 1 */
    /* snap-dragging (positions, the device's units) */
    int snap_axes;         /**< 1: constrain the drag to the nearest coordinate axis ... */
    double snap_angle;     /**< ... when within this angle of it (radians) */
    double grid;           /**< > 0: round the snapped position to this grid spacing */
    double feature_radius; /**< > 0: snap to a feature point within this distance */
    /* two-hand: the other device of the pair (set by vv_input_manager_pair) */
    int partner;
} vv_input_method;

/** Direct mapping, no dead zone, linear, gain 1. */
vv_input_method vv_input_method_default(void);
/** Method name "direct", "snap-drag", "two-hand". */
const char *vv_input_method_name(vv_input_method_kind k);

/** One degree of freedom of a device kind. */
typedef struct vv_input_dof {
    char name[VV_INPUT_NAME_MAX]; /**< "tx", "pointer-x", "left-x" ... */
    double min, max;              /**< raw range in the device's units */
    char unit[24];                /**< "counts", "px", "normalized", "mm" ... */
} vv_input_dof;

#define VV_INPUT_MAX_BINDINGS 24

/** A key or button bound to a named command (or "axis:+tx" .. "axis:-rz"). */
typedef struct vv_input_binding {
    int kind; /**< VV_RAW_KEY or VV_RAW_BUTTON (vv_input_raw_kind) */
    int code;
    char command[48];
} vv_input_binding;

/** One entry of the information base: what is known about a kind of device. */
typedef struct vv_input_devinfo {
    vv_input_kind kind;
    char name[VV_INPUT_NAME_MAX]; /**< human name ("Spaceball / SpaceNavigator") */
    int n_dof;
    vv_input_dof dof[VV_INPUT_MAX_DOF];
    int coupled;            /**< 1: the axes move together (one puck); 0: independent */
    int n_buttons;          /**< typical number of buttons (0 unknown) */
    char good_for[256];     /**< comma-separated uses ("navigation,object rotation") */
    vv_input_method method; /**< the default simulation method */
    double click_time;      /**< press-to-release time that still counts as a click, s */
    double pixels_per_unit; /**< mouse: drag distance giving a full (1.0) motion */
    int n_bindings;
    vv_input_binding bindings[VV_INPUT_MAX_BINDINGS]; /**< default bindings */
    char source[512]; /**< the file it was read from ("" for built-in defaults) */
} vv_input_devinfo;

/** The information base: one entry per kind (built-in defaults where no file says more). */
typedef struct vv_input_devinfo_db vv_input_devinfo_db;

/**
 * Loads the information base. Each directory in @p dirs (n_dirs entries, may
 * be 0; NULL entries skipped) is read in order for "<kind>.json" files; a
 * later directory overrides an earlier one kind by kind. With @p n_dirs == 0
 * the default search is used: the installed share/volvis/devices (the
 * configured one, then ../share/volvis/devices from the library's or the
 * program's own folder, so a moved install such as the pip wheel finds its
 * own), then ~/.config/volvis/devices, then $VOLVIS_DEVICE_DIR (missing directories are
 * skipped). Errors: VV_ERR_FORMAT for a malformed file (with file, line and
 * column), VV_ERR_NOMEM. The caller frees with vv_input_devinfo_db_free.
 */
vv_status vv_input_devinfo_db_load(vv_input_devinfo_db **out, const char *const *dirs, int n_dirs);
void vv_input_devinfo_db_free(vv_input_devinfo_db *db);
/** The entry for @p kind (never NULL for a valid kind; borrowed from @p db). */
const vv_input_devinfo *vv_input_devinfo_db_get(const vv_input_devinfo_db *db, vv_input_kind kind);
/** Reads one information-base file into @p out. Errors: VV_ERR_IO, VV_ERR_FORMAT. */
vv_status vv_input_devinfo_load(const char *path, vv_input_devinfo *out);

/* ---- raw events ---------------------------------------------------------------- */

/** What a raw event carries; the meaning of code and values per kind. */
typedef enum vv_input_raw_kind {
    VV_RAW_KEY = 0, /**< code: key (GDK keyval = X keysym); v[0]: 1 press, 0 release */
    VV_RAW_BUTTON,  /**< code: button number (mouse 1 left, 2 middle, 3 right); v[0]: 1/0 */
    VV_RAW_POINTER, /**< v[0], v[1]: pointer position, pixels */
    VV_RAW_SCROLL,  /**< v[0], v[1]: scroll dx, dy (steps) */
    VV_RAW_AXIS,    /**< code: navigation axis 0..5 (tx ty tz rx ry rz); v[0]: value in [-1, 1] */
    VV_RAW_MOTION6, /**< v[0..5]: tx ty tz rx ry rz in device counts; v[6]: period, ms */
    VV_RAW_POSE,    /**< v[0..2]: position; v[3..6]: orientation quaternion w x y z */
    VV_RAW_ADDED,   /**< the device appeared */
    VV_RAW_REMOVED, /**< the device is gone (unplugged, socket closed) */
    VV_RAW_KIND_COUNT
} vv_input_raw_kind;

#define VV_INPUT_RAW_VALUES 7

/** A toolkit-independent raw event (what the GUI builds from a GTK event). */
typedef struct vv_input_raw_event {
    int device;  /**< manager device id */
    double time; /**< seconds (monotonic clock, or the recording's clock) */
    vv_input_raw_kind kind;
    int code; /**< key, button or axis number (see the kind) */
    double v[VV_INPUT_RAW_VALUES];
} vv_input_raw_event;

/** "key", "button", "pointer", "scroll", "axis", "motion6", "pose", "added", "removed". */
const char *vv_input_raw_kind_name(vv_input_raw_kind k);

/* ---- the virtual device and actions ---------------------------------------- */

/** The state of one virtual device after simulation. */
typedef struct vv_input_state {
    vv_vec3 position;         /**< pointer (px), pose position, or integrated motion */
    vv_quat orientation;      /**< pose, or integrated rotation (unit) */
    vv_vec3 velocity;         /**< position units per second */
    vv_vec3 angular_velocity; /**< radians per second (normalized rate for 6-DOF devices) */
    double axes[6];           /**< the last normalized navigation axes, [-1, 1] */
    uint64_t buttons;         /**< bit b set while button b (0..63) is down */
    double time;              /**< time of the last event */
    int present;              /**< 0 once the device was removed */
} vv_input_state;

typedef enum vv_input_action_kind {
    VV_ACTION_MOTION = 0,     /**< 6-DOF navigation: motion[6] normalized, rotation, dt */
    VV_ACTION_BUTTON_PRESS,   /**< button */
    VV_ACTION_BUTTON_RELEASE, /**< button */
    VV_ACTION_BUTTON_CLICK,   /**< button pressed and released within the click time */
    VV_ACTION_COMMAND,        /**< command: a named command ("view.reset") from a binding */
    VV_ACTION_POSE,           /**< position / orientation changed (pointer, pose) */
    VV_ACTION_SNAP_DRAG,      /**< position: the snapped position; snap says to what */
    VV_ACTION_TWO_HAND,       /**< translation, rotation, scale of the pair since the last */
    VV_ACTION_DEVICE_ADDED,
    VV_ACTION_DEVICE_REMOVED,
    VV_ACTION_KIND_COUNT
} vv_input_action_kind;

/** What a snap-drag snapped to (bit set). */
enum { VV_SNAP_AXIS = 1, VV_SNAP_GRID = 2, VV_SNAP_FEATURE = 4 };

#define VV_INPUT_COMMAND_MAX 48

/** One abstract action. Fields not used by the kind are zero (rotation identity). */
typedef struct vv_input_action {
    vv_input_action_kind kind;
    int device;                         /**< the device it came from (two-hand: the first) */
    double time;                        /**< time of the raw event that caused it, s */
    double dt;                          /**< MOTION: seconds since the device's last motion */
    double motion[6];                   /**< MOTION: tx ty tz rx ry rz, each in [-1, 1] */
    vv_vec3 position;                   /**< POSE, SNAP_DRAG: position; TWO_HAND: midpoint */
    vv_vec3 translation;                /**< TWO_HAND: midpoint displacement */
    vv_quat rotation;                   /**< MOTION: motion[3..5] * dt as a rotation (rad);
                                             POSE: orientation; TWO_HAND: rotation */
    double scale;                       /**< TWO_HAND: distance ratio (1 otherwise) */
    int button;                         /**< BUTTON_*: button number */
    int snap;                           /**< SNAP_DRAG: VV_SNAP_* bits */
    int feature;                        /**< SNAP_DRAG: index of the feature point, -1 none */
    char command[VV_INPUT_COMMAND_MAX]; /**< COMMAND: the command name */
} vv_input_action;

/** "motion", "press", "release", "click", "command", "pose", "snap-drag", "two-hand",
 * "added", "removed". */
const char *vv_input_action_kind_name(vv_input_action_kind k);

/* ---- simulation methods as pure functions (also used by the manager) ------- */

/**
 * Direct mapping of one normalized value: 0 inside the dead zone, then
 * sign(x) * ((|x| - dz) / (1 - dz))^exponent, clamped to [-1, 1]. NaN gives 0.
 */
double vv_input_response(double x, double dead_zone, double exponent);

/** Dominant-axis filter: zeroes all but the largest |v[i]| of the six (ties: the first). */
void vv_input_dominant_axis(double v[6]);

/** Parameters of snap-dragging. Feature points are borrowed for the call. */
typedef struct vv_input_snap_params {
    int snap_axes;
    double snap_angle;     /**< radians */
    double grid;           /**< 0: none */
    double feature_radius; /**< 0: none */
    const vv_vec3 *features;
    int n_features;
} vv_input_snap_params;

/**
 * Snap-dragging: the drag from @p start to @p p becomes a snapped position.
 * Order: a feature point within feature_radius of p wins (VV_SNAP_FEATURE);
 * otherwise the drag vector is projected on the coordinate axis it is within
 * snap_angle of (VV_SNAP_AXIS), and the result is rounded to the grid
 * (VV_SNAP_GRID, along the free coordinates only when axis-snapped).
 * *snapped and *feature (may be NULL) say what happened.
 * Source: Bier, "Snap-dragging in three dimensions", I3D 1990; VolVis sec. 6.
 */
vv_vec3 vv_input_snap(const vv_input_snap_params *p, vv_vec3 start, vv_vec3 pos, int *snapped,
                      int *feature);

/** The result of a two-hand gesture. */
typedef struct vv_input_two_hand {
    vv_vec3 translation; /**< midpoint after - midpoint before */
    vv_quat rotation;    /**< shortest rotation taking (b0 - a0) to (b1 - a1) */
    double scale;        /**< |b1 - a1| / |b0 - a0| */
    vv_vec3 center;      /**< midpoint after */
} vv_input_two_hand;

/**
 * Two-hand translate / rotate / scale from hand positions a, b before (0) and
 * after (1). A degenerate pair (coincident hands) gives identity rotation and
 * scale 1. Source: VolVis sec. 6 (two-hand gestures).
 */
vv_input_two_hand vv_input_two_hand_solve(vv_vec3 a0, vv_vec3 b0, vv_vec3 a1, vv_vec3 b1);

/* ---- the manager ---------------------------------------------------------------- */

typedef struct vv_input_manager vv_input_manager;

/** Fixed ids of the devices every manager has (the GUI feeds them). */
enum { VV_INPUT_KEYBOARD_ID = 1, VV_INPUT_MOUSE_ID = 2 };

/**
 * Creates a manager with a keyboard (id 1) and a mouse (id 2). @p db is the
 * information base, COPIED (NULL: vv_input_devinfo_db_load's default search,
 * failing quietly back to built-in defaults). Errors: VV_ERR_NOMEM, VV_ERR_IO
 * (epoll). Free with vv_input_manager_free (closes every driver).
 */
vv_status vv_input_manager_new(vv_input_manager **out, const vv_input_devinfo_db *db);
void vv_input_manager_free(vv_input_manager *m);

/**
 * Adds a device fed by the caller (or a driver); the kind picks its
 * information-base entry and default method. *id receives the new id.
 * Errors: VV_ERR_LIMIT (more than 64 devices), VV_ERR_INVALID.
 */
vv_status vv_input_manager_device_add(vv_input_manager *m, vv_input_kind kind, const char *name,
                                      int *id);

/** Public description of a device of the manager. */
typedef struct vv_input_device_desc {
    int id;
    vv_input_kind kind;
    char name[VV_INPUT_NAME_MAX];
    char driver[16];             /**< "gui", "spacenav", "sdl", "replay", "network" */
    char app[VV_INPUT_NAME_MAX]; /**< the application it is assigned to, "" all */
    int present;
    const vv_input_devinfo *info; /**< borrowed from the manager */
} vv_input_device_desc;

/** Number of devices (present or removed) and the i-th one. VV_ERR_INVALID out of range. */
int vv_input_manager_device_count(const vv_input_manager *m);
vv_status vv_input_manager_device_get(const vv_input_manager *m, int index,
                                      vv_input_device_desc *out);

/** Current state of device @p id. VV_ERR_INVALID for an unknown id. */
vv_status vv_input_manager_state(const vv_input_manager *m, int id, vv_input_state *out);

/**
 * Feeds one raw event (GUI key/mouse events; drivers use it too). Non-finite
 * values drop the event (counted as a warning), huge ones are clamped to the
 * device's range. The resulting actions are delivered to the subscribers
 * before the call returns (unless called from inside a subscriber, then at
 * the end of the outer delivery). Recorded when recording is on.
 * Errors: VV_ERR_INVALID for an unknown device or kind (also counted).
 */
vv_status vv_input_manager_feed(vv_input_manager *m, const vv_input_raw_event *ev);

/** Subscriber callback: @p a is borrowed for the call. It may call the manager. */
typedef void (*vv_input_action_fn)(void *user, const vv_input_action *a);

/**
 * Subscribes @p fn for application @p app: it receives the actions of
 * devices assigned to @p app and of unassigned devices (@p app NULL or ""
 * receives every device's actions). *sub_id (may be NULL) is for unsubscribe.
 * Errors: VV_ERR_LIMIT (more than 32 subscribers), VV_ERR_INVALID.
 */
vv_status vv_input_manager_subscribe(vv_input_manager *m, const char *app, vv_input_action_fn fn,
                                     void *user, int *sub_id);
void vv_input_manager_unsubscribe(vv_input_manager *m, int sub_id);

/** Assigns device @p id to application @p app (NULL or "": every application). */
vv_status vv_input_manager_assign(vv_input_manager *m, int id, const char *app);

/**
 * Replaces the simulation method of device @p id (copied). Snap-drag feature
 * points are set with vv_input_manager_set_features. Errors: VV_ERR_INVALID.
 */
vv_status vv_input_manager_set_method(vv_input_manager *m, int id, const vv_input_method *method);
/** The method in use. */
vv_status vv_input_manager_get_method(const vv_input_manager *m, int id, vv_input_method *out);
/** Feature points for snap-dragging device @p id (copied; n may be 0). */
vv_status vv_input_manager_set_features(vv_input_manager *m, int id, const vv_vec3 *points, int n);
/**
 * Pairs devices @p a and @p b for two-hand gestures: both switch to
 * VV_METHOD_TWO_HAND; each pose or pointer change of either then gives a
 * VV_ACTION_TWO_HAND (device = a) computed from both positions.
 */
vv_status vv_input_manager_pair(vv_input_manager *m, int a, int b);

/**
 * Binds key or button @p code of device @p id (kind VV_RAW_KEY or
 * VV_RAW_BUTTON) to a named command: a press then also emits a
 * VV_ACTION_COMMAND. command NULL removes the binding. Bindings from the
 * information base ("bindings") are installed when a device is added.
 * Keys may also drive navigation axes: command "axis:+tx" .. "axis:-rz".
 */
vv_status vv_input_manager_bind(vv_input_manager *m, int id, vv_input_raw_kind kind, int code,
                                const char *command);

/* ---- main-loop integration ------------------------------------------------------ */

/** One descriptor to watch for reading (never changes for the manager's life). */
int vv_input_manager_fd(const vv_input_manager *m);
/**
 * Seconds from @p now until the manager needs vv_input_manager_dispatch even
 * if its descriptor stays quiet (0: now), or -1: only when the fd is ready.
 */
double vv_input_manager_timeout(const vv_input_manager *m, double now);
/**
 * Reads everything ready on every driver without blocking, runs the replay
 * clock up to @p now, delivers the actions. Returns the number of actions
 * delivered (>= 0). Driver failures never stop it: a lost device becomes
 * VV_ACTION_DEVICE_REMOVED and a warning.
 */
int vv_input_manager_dispatch(vv_input_manager *m, double now);

/** Number of dropped or repaired events so far, and the last warning ("" none). */
uint64_t vv_input_manager_warning_count(const vv_input_manager *m);
const char *vv_input_manager_last_warning(const vv_input_manager *m);

/* ---- drivers ---------------------------------------------------------------------- */

/**
 * Connects to spacenavd through libspnav ($SPNAV_SOCKET, else /etc/spnavrc,
 * else /var/run/spnav.sock) and adds a VV_INPUT_SPACEBALL device (*id).
 * Errors: VV_ERR_UNSUPPORTED (built without libspnav, or already open in
 * this process), VV_ERR_IO (no daemon answers). Takes up to 0.3 s: libspnav
 * waits that long for a protocol-v1 answer before falling back to v0.
 */
vv_status vv_input_manager_open_spacenav(vv_input_manager *m, int *id);

/**
 * Starts the SDL2 game-controller driver: every controller attached now or
 * later becomes a VV_INPUT_GAMECONTROLLER device (VV_ACTION_DEVICE_ADDED);
 * a removed one gives VV_ACTION_DEVICE_REMOVED. SDL has no descriptor: the
 * manager's timeout asks for a poll every 1/60 s while a controller is
 * attached and every 0.5 s (hot-plug) otherwise. Left stick x/y -> tx/tz,
 * right stick -> ry/rx, triggers -> ty (+right, -left); buttons are raw
 * buttons numbered as SDL_GameControllerButton. Errors: VV_ERR_UNSUPPORTED
 * (built without SDL2), VV_ERR_IO (SDL_Init failed).
 */
vv_status vv_input_manager_open_controllers(vv_input_manager *m);

/**
 * Opens a recording for replay. The whole file is validated first
 * (VV_ERR_FORMAT "replay: FILE: line N: problem", VV_ERR_IO, VV_ERR_LIMIT);
 * then its devices are added (the recorded kinds and names) and its events
 * are fed on a virtual clock: the first event is due at @p start, and event
 * t at start + (t - t_first) / speed (speed > 0; INFINITY: all at once). A
 * dispatch that comes more than 0.1 s after an event was due (a stalled
 * caller) delays the rest of the replay by that much instead of delivering
 * it all at once, so a recorded motion keeps its duration. Fed events keep
 * the recorded times, so a replay is bit-for-bit repeatable.
 * *n_devices / first_id (may be NULL) receive how many devices it added and
 * the id of the first (the others follow in order).
 */
vv_status vv_input_manager_open_replay(vv_input_manager *m, const char *path, double start,
                                       double speed, int *first_id, int *n_devices);
/** 1 while a replay still has events to feed. */
int vv_input_manager_replay_pending(const vv_input_manager *m);

/**
 * Records every raw event fed from now on (any driver) to @p path, written
 * atomically when recording stops (vv_input_manager_record_stop or free).
 * Errors: VV_ERR_IO, VV_ERR_INVALID (already recording).
 */
vv_status vv_input_manager_record_start(vv_input_manager *m, const char *path);
vv_status vv_input_manager_record_stop(vv_input_manager *m);

/**
 * Listens on a Unix-domain stream socket at @p path (an existing socket
 * file there is replaced) for the line protocol of docs/input.md: each
 * client declares devices ("device LOCAL-ID KIND NAME") and sends events
 * ("KIND LOCAL-ID CODE VALUES..."), stamped with the manager's clock on
 * arrival. A bad line is answered "error ..." and dropped (warning); a
 * closed connection removes its devices. Errors: VV_ERR_IO, VV_ERR_INVALID
 * (path too long, already listening).
 */
vv_status vv_input_manager_listen(vv_input_manager *m, const char *path);

/** The monotonic clock the manager uses for live drivers (seconds). */
double vv_input_now(void);

#ifdef __cplusplus
}
#endif
#endif
