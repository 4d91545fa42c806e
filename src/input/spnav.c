/*
 * The 3-D mouse driver: spacenavd through libspnav (Debian's libspnav 1.0
 * honours $SPNAV_SOCKET, then /etc/spnavrc's "socket =", then
 * /var/run/spnav.sock). Motion events become VV_RAW_MOTION6, buttons
 * VV_RAW_BUTTON; a closed socket removes the device. libspnav keeps one
 * global connection, so one manager per process may have it open.
 */
#include "input_internal.h"

#ifdef VV_HAVE_SPNAV
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>

#include <spnav.h>

static int spnav_owner; /* 1 while some manager holds libspnav's connection */

typedef struct spnav_drv {
    int fd;
    int id;
} spnav_drv;

static void
spnav_gone(vv_input_manager *m, spnav_drv *s, double now) {
    vv_input_raw_event ev;
    memset(&ev, 0, sizeof ev);
    ev.device = s->id;
    ev.time = now;
    ev.kind = VV_RAW_REMOVED;
    vv_input_manager_feed(m, &ev);
    vv_input_unwatch(m, s->fd);
    spnav_close();
    spnav_owner = 0;
    s->fd = -1;
}

static void
spnav_ready(vv_input_manager *m, vv_input_driver *drv, int fd, double now) {
    spnav_drv *s = drv->self;
    (void)fd;
    /* bounded: a daemon flooding us cannot hold the UI thread */
    for (int i = 0; i < 256 && s->fd >= 0; i++) {
        char probe;
        ssize_t n = recv(s->fd, &probe, 1, MSG_PEEK | MSG_DONTWAIT);
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
            spnav_gone(m, s, now);
            return;
        }
        if (n < 0)
            return;
        spnav_event e;
        memset(&e, 0, sizeof e);
        int type = spnav_poll_event(&e);
        vv_input_raw_event ev;
        memset(&ev, 0, sizeof ev);
        ev.device = s->id;
        ev.time = now;
        if (type == SPNAV_EVENT_MOTION) {
            ev.kind = VV_RAW_MOTION6;
            ev.v[0] = e.motion.x;
            ev.v[1] = e.motion.y;
            ev.v[2] = e.motion.z;
            ev.v[3] = e.motion.rx;
            ev.v[4] = e.motion.ry;
            ev.v[5] = e.motion.rz;
            ev.v[6] = e.motion.period;
        } else if (type == SPNAV_EVENT_BUTTON) {
            if (e.button.bnum < 0 || e.button.bnum > 63) {
                vv_input_warn(m, "spacenav: button %d out of range 0..63, dropped", e.button.bnum);
                continue;
            }
            ev.kind = VV_RAW_BUTTON;
            ev.code = e.button.bnum;
            ev.v[0] = e.button.press ? 1 : 0;
        } else {
            if (type == 0)
                vv_input_warn(m, "spacenav: malformed event from the daemon dropped");
            continue; /* device and configuration events carry nothing for us */
        }
        if (vv_input_manager_feed(m, &ev) != VV_OK)
            vv_error_clear();
    }
}

static void
spnav_drv_close(vv_input_manager *m, vv_input_driver *drv) {
    spnav_drv *s = drv->self;
    if (!s)
        return;
    if (s->fd >= 0) {
        vv_input_unwatch(m, s->fd);
        spnav_close();
        spnav_owner = 0;
    }
    free(s);
    drv->self = NULL;
}

vv_status
vv_input_manager_open_spacenav(vv_input_manager *m, int *id) {
    if (!m)
        return vv_error_set(VV_ERR_INVALID, "spacenav: no manager");
    if (spnav_owner)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "spacenav: already open in this process (libspnav has one connection)");
    if (spnav_open() == -1)
        return vv_error_set(VV_ERR_IO, "spacenav: no spacenavd answers at %s",
                            getenv("SPNAV_SOCKET") ? getenv("SPNAV_SOCKET")
                                                   : "/var/run/spnav.sock");
    spnav_drv *s = calloc(1, sizeof *s);
    if (!s) {
        spnav_close();
        return vv_error_set(VV_ERR_NOMEM, "spacenav: out of memory");
    }
    s->fd = spnav_fd();
    vv_status st = vv_input_device_add_driver(m, VV_INPUT_SPACEBALL, "spacenavd 3-D mouse",
                                              "spacenav", &s->id);
    vv_input_driver drv = {"spacenav", s, spnav_ready, NULL, NULL, spnav_drv_close};
    int idx = st == VV_OK ? vv_input_driver_add(m, &drv) : -1;
    if (idx < 0 || vv_input_watch(m, idx, s->fd) != VV_OK) {
        if (idx >= 0)
            m->n_drivers--;
        spnav_close();
        free(s);
        return VV_ERR_LIMIT;
    }
    spnav_owner = 1;
    if (id)
        *id = s->id;
    return VV_OK;
}
#else
vv_status
vv_input_manager_open_spacenav(vv_input_manager *m, int *id) {
    (void)m;
    (void)id;
    return vv_error_set(VV_ERR_UNSUPPORTED, "spacenav: this build has no libspnav");
}
#endif
