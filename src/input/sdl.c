/*
 * The game-controller driver: SDL2's game-controller API, headless (no
 * window, no video). SDL has no descriptor to watch, so the manager's
 * timeout asks for a poll at 60 Hz while a controller is attached and at
 * 2 Hz (hot-plug) otherwise. Sticks and triggers become navigation axes,
 * buttons raw buttons (SDL_GameControllerButton numbers).
 */
#include "input_internal.h"

#ifdef VV_HAVE_SDL2
#include <SDL2/SDL.h>
#include <stdlib.h>
#include <string.h>

#define SDL_MAX_PADS 8

typedef struct sdl_pad {
    SDL_GameController *gc; /* NULL: free */
    SDL_JoystickID instance;
    int id;
    double trig[2]; /* left, right in [0, 1] */
} sdl_pad;

typedef struct sdl_drv {
    sdl_pad pad[SDL_MAX_PADS];
    int n_open;
} sdl_drv;

static int sdl_owner;

static void
feed(vv_input_manager *m, int id, double now, vv_input_raw_kind kind, int code, double v) {
    vv_input_raw_event ev;
    memset(&ev, 0, sizeof ev);
    ev.device = id;
    ev.time = now;
    ev.kind = kind;
    ev.code = code;
    ev.v[0] = v;
    if (vv_input_manager_feed(m, &ev) != VV_OK)
        vv_error_clear();
}

static sdl_pad *
pad_of(sdl_drv *s, SDL_JoystickID inst) {
    for (int i = 0; i < SDL_MAX_PADS; i++)
        if (s->pad[i].gc && s->pad[i].instance == inst)
            return &s->pad[i];
    return NULL;
}

static void
pad_added(vv_input_manager *m, sdl_drv *s, int index, double now) {
    SDL_JoystickID inst = SDL_JoystickGetDeviceInstanceID(index);
    if (pad_of(s, inst))
        return;
    for (int i = 0; i < SDL_MAX_PADS; i++) {
        sdl_pad *p = &s->pad[i];
        if (p->gc)
            continue;
        p->gc = SDL_GameControllerOpen(index);
        if (!p->gc) {
            vv_input_warn(m, "controllers: cannot open controller %d: %s", index, SDL_GetError());
            return;
        }
        p->instance = inst;
        p->trig[0] = p->trig[1] = 0;
        const char *name = SDL_GameControllerName(p->gc);
        if (vv_input_device_add_driver(m, VV_INPUT_GAMECONTROLLER, name, "sdl", &p->id) != VV_OK) {
            vv_input_warn(m, "controllers: %s", vv_error_message());
            vv_error_clear();
            SDL_GameControllerClose(p->gc);
            p->gc = NULL;
            return;
        }
        s->n_open++;
        feed(m, p->id, now, VV_RAW_ADDED, 0, 0);
        return;
    }
    vv_input_warn(m, "controllers: more than %d controllers", SDL_MAX_PADS);
}

static void
sdl_poll(vv_input_manager *m, vv_input_driver *drv, double now) {
    sdl_drv *s = drv->self;
    SDL_Event e;
    SDL_PumpEvents();
    while (SDL_PeepEvents(&e, 1, SDL_GETEVENT, SDL_CONTROLLERAXISMOTION,
                          SDL_CONTROLLERDEVICEREMAPPED) > 0) {
        sdl_pad *p;
        switch (e.type) {
        case SDL_CONTROLLERDEVICEADDED:
            pad_added(m, s, e.cdevice.which, now);
            break;
        case SDL_CONTROLLERDEVICEREMOVED:
            if ((p = pad_of(s, e.cdevice.which))) {
                feed(m, p->id, now, VV_RAW_REMOVED, 0, 0);
                SDL_GameControllerClose(p->gc);
                p->gc = NULL;
                s->n_open--;
            }
            break;
        case SDL_CONTROLLERAXISMOTION: {
            if (!(p = pad_of(s, e.caxis.which)))
                break;
            double v = e.caxis.value / 32767.0;
            v = v < -1 ? -1 : v > 1 ? 1 : v;
            switch (e.caxis.axis) {
            case SDL_CONTROLLER_AXIS_LEFTX:
                feed(m, p->id, now, VV_RAW_AXIS, 0, v);
                break;
            case SDL_CONTROLLER_AXIS_LEFTY: /* stick forward (negative) moves forward (-z) */
                feed(m, p->id, now, VV_RAW_AXIS, 2, v);
                break;
            case SDL_CONTROLLER_AXIS_RIGHTX:
                feed(m, p->id, now, VV_RAW_AXIS, 4, v);
                break;
            case SDL_CONTROLLER_AXIS_RIGHTY:
                feed(m, p->id, now, VV_RAW_AXIS, 3, v);
                break;
            case SDL_CONTROLLER_AXIS_TRIGGERLEFT:
            case SDL_CONTROLLER_AXIS_TRIGGERRIGHT:
                p->trig[e.caxis.axis == SDL_CONTROLLER_AXIS_TRIGGERRIGHT] = v < 0 ? 0 : v;
                feed(m, p->id, now, VV_RAW_AXIS, 1, p->trig[1] - p->trig[0]);
                break;
            default:
                break;
            }
            break;
        }
        case SDL_CONTROLLERBUTTONDOWN:
        case SDL_CONTROLLERBUTTONUP:
            if ((p = pad_of(s, e.cbutton.which)))
                feed(m, p->id, now, VV_RAW_BUTTON, e.cbutton.button,
                     e.type == SDL_CONTROLLERBUTTONDOWN);
            break;
        default:
            break;
        }
    }
    /* joystick-level events are not ours: drop them so the queue stays short */
    SDL_FlushEvents(SDL_JOYAXISMOTION, SDL_JOYBATTERYUPDATED);
}

static double
sdl_timeout(const vv_input_manager *m, const vv_input_driver *drv, double now) {
    (void)m;
    (void)now;
    const sdl_drv *s = drv->self;
    return s->n_open > 0 ? 1.0 / 60 : 0.5;
}

static void
sdl_close(vv_input_manager *m, vv_input_driver *drv) {
    (void)m;
    sdl_drv *s = drv->self;
    if (!s)
        return;
    for (int i = 0; i < SDL_MAX_PADS; i++)
        if (s->pad[i].gc)
            SDL_GameControllerClose(s->pad[i].gc);
    free(s);
    drv->self = NULL;
    SDL_QuitSubSystem(SDL_INIT_GAMECONTROLLER);
    SDL_Quit();
    sdl_owner = 0;
}

vv_status
vv_input_manager_open_controllers(vv_input_manager *m) {
    if (!m)
        return vv_error_set(VV_ERR_INVALID, "controllers: no manager");
    if (sdl_owner)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "controllers: already open in this process (SDL is process-wide)");
    /* headless: no signal handlers of SDL's, no window, events without focus */
    SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "1");
    SDL_SetHint(SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, "1");
    if (SDL_InitSubSystem(SDL_INIT_GAMECONTROLLER) != 0)
        return vv_error_set(VV_ERR_IO, "controllers: SDL_Init: %s", SDL_GetError());
    sdl_drv *s = calloc(1, sizeof *s);
    vv_input_driver drv = {"sdl", s, NULL, sdl_poll, sdl_timeout, sdl_close};
    if (!s || vv_input_driver_add(m, &drv) < 0) {
        free(s);
        SDL_QuitSubSystem(SDL_INIT_GAMECONTROLLER);
        SDL_Quit();
        return s ? VV_ERR_LIMIT : vv_error_set(VV_ERR_NOMEM, "controllers: out of memory");
    }
    sdl_owner = 1;
    m->sdl_open = 1;
    return VV_OK;
}
#else
vv_status
vv_input_manager_open_controllers(vv_input_manager *m) {
    (void)m;
    return vv_error_set(VV_ERR_UNSUPPORTED, "controllers: this build has no SDL2");
}
#endif
