/* VvgSceneView: the scene view and the Navigator (vvg-scene-view.h): the
 * widget, what it asks the render thread for as the World changes, the image
 * and its overlays on screen, picking, and mouse, scroll and flight-key input.
 * The render thread and the frames it hands over are vvg-scene-render.c. */
#include "vvg-scene-overlay.h"
#include "vvg-scene-render.h"
#include "vvg-widgets.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Volumes of at most this many voxels (256^3) are never drawn as boxes. */
#define SURFACES_ABOVE_VOXELS (256.0 * 256.0 * 256.0)

static gint64 start_us;

void
vvg_scene_view_set_start_time(gint64 us) {
    start_us = us;
}

G_DEFINE_TYPE(VvgSceneView, vvg_scene_view, GTK_TYPE_WIDGET)

static gboolean
refine_cb(gpointer data) {
    VvgSceneView *self = data;
    self->refine_source = 0;
    self->moving = FALSE;
    /* 1/2 first when the frame on screen is coarser and the full frame is
     * slow (or not known yet), then the full frame */
    g_mutex_lock(&self->lock);
    double half = self->policy.seconds[VV_PREVIEW_RAYCAST_2];
    g_mutex_unlock(&self->lock);
    /* (the first time, or when the final frame is slow and the 1/2 step
     * quick: it must not delay the final frame by more than a few frames) */
    vv_preview_kind kinds[2];
    int n = 0;
    if ((self->shown_kind < VV_PREVIEW_RAYCAST_2 || self->shown_gen != self->gen) &&
        (self->full_ms <= 0 || (self->full_ms > 300 && half >= 0 && half <= 0.04)))
        kinds[n++] = VV_PREVIEW_RAYCAST_2;
    kinds[n++] = VV_PREVIEW_FULL;
    vvg_scene_render_post(self, TRUE, kinds, n);
    return G_SOURCE_REMOVE;
}

/* The World changed: draw a preview now and refine after the delay. */
static gboolean sync_size(VvgSceneView *self);

static void
state_changed(VvgSceneView *self) {
    sync_size(self);
    self->gen++;
    __atomic_store_n(&self->cancel_below, self->gen, __ATOMIC_RELAXED);
    self->moving = TRUE;
    if (vvg_document_world(self->doc)->n_objects == 0) {
        /* nothing to render: the background alone */
        g_clear_object(&self->texture);
        self->shown_gen = self->gen;
        gtk_widget_queue_draw(GTK_WIDGET(self));
        return;
    }
    /* volumes up to 256^3 are always cast (at 1/8 size at worst): boxes and
     * surfaces only stand in for larger ones whose 1/8 cast misses the budget */
    const vv_world *wd = vvg_document_world(self->doc);
    double voxels = 0;
    for (int i = 0; i < wd->n_objects; i++) {
        const vv_volume *v = wd->objects[i]->volume;
        if (v && wd->objects[i]->visible)
            voxels = fmax(voxels, (double)v->dims[0] * v->dims[1] * v->dims[2]);
    }
    g_mutex_lock(&self->lock);
    for (int k = VV_PREVIEW_BBOX; k <= VV_PREVIEW_COARSE_MC; k++)
        self->policy.allowed[k] = voxels > SURFACES_ABOVE_VOXELS;
    vv_preview_kind k = vv_preview_policy_choose(&self->policy, VVG_PREVIEW_BUDGET);
    g_mutex_unlock(&self->lock);
    vvg_scene_render_post(self, FALSE, &k, 1);
    if (self->refine_source)
        g_source_remove(self->refine_source);
    self->refine_source = g_timeout_add(self->refine_delay_ms, refine_cb, self);
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    state_changed(VVG_SCENE_VIEW(user));
}

void
vvg_scene_view_refresh(VvgSceneView *self) {
    state_changed(self);
}

/* ---- geometry of the view on screen ---------------------------------------- */

/* Where the image is drawn: its top-left corner and scale (<= 1) in the widget. */
static void
image_rect(VvgSceneView *self, double *x0, double *y0, double *scale) {
    const vv_world *w = vvg_document_world(self->doc);
    int ww = gtk_widget_get_width(GTK_WIDGET(self)), wh = gtk_widget_get_height(GTK_WIDGET(self));
    double vw = w->view.width, vh = w->view.height;
    double s = fmin(1.0, fmin(ww / vw, wh / vh));
    *scale = s > 0 ? s : 1;
    *x0 = floor((ww - vw * s) / 2);
    *y0 = floor((wh - vh * s) / 2);
}

gboolean
vvg_scene_view_pick(VvgSceneView *self, double x, double y, vv_vec3 *world) {
    if (!self->shown_depth || self->shown_gen != self->gen || !self->texture)
        return FALSE;
    double x0, y0, s;
    image_rect(self, &x0, &y0, &s);
    const vv_view *v = &self->shown_view;
    int px = (int)floor((x - x0) / s), py = (int)floor((y - y0) / s);
    if (px < 0 || py < 0 || px >= v->width || py >= v->height)
        return FALSE;
    float d = self->shown_depth[(size_t)py * v->width + px];
    if (!isfinite(d))
        return FALSE;
    vv_ray ray = vv_view_ray(v, px, py);
    *world = vv_ray_at(ray, d);
    return TRUE;
}

void
vvg_scene_view_pick_next(VvgSceneView *self, VvgPickFunc fn, gpointer user) {
    self->pick_fn = fn;
    self->pick_user = user;
    gtk_widget_set_cursor_from_name(GTK_WIDGET(self), fn ? "crosshair" : NULL);
}

/* The cut plane a VVG_NAV_CUT drag moves: the selected object's last local
 * one, else the World's last global one; NULL when there is none. With
 * @p t, also its vv_nav_apply target. */
static vv_cut_plane *
target_plane(VvgSceneView *self, vv_nav_target *t) {
    vv_world *w = vvg_document_world(self->doc);
    vv_object *o = vvg_document_selected_object(self->doc);
    vv_nav_target nt = {VV_NAV_TARGET_CUT, -1, -1};
    vv_cut_plane *pl = NULL;
    int co = self->cut_object, cp = self->cut_plane;
    if (cp >= 0 && co < w->n_objects &&
        cp < (co < 0 ? w->n_cut_planes : w->objects[co]->n_cut_planes)) {
        nt.index = co;
        nt.plane = cp;
        pl = co < 0 ? &w->cut_planes[cp] : &w->objects[co]->cut_planes[cp];
    } else if (o && o->n_cut_planes > 0) {
        nt.index = vvg_document_selected(self->doc);
        pl = &o->cut_planes[o->n_cut_planes - 1];
    } else if (w->n_cut_planes > 0) {
        pl = &w->cut_planes[w->n_cut_planes - 1];
    }
    if (pl && t)
        *t = nt;
    return pl;
}

/* ---- drawing -------------------------------------------------------------- */

static void
log_frame(VvgSceneView *self) {
    if (!self->frame_log || self->texture_logged || !self->texture)
        return;
    self->texture_logged = TRUE;
    gint64 now = g_get_monotonic_time();
    double ms = (now - start_us) * 1e-3;
    /* the GUI's own time a frame: from the renderer's end to this paint */
    fprintf(self->frame_log, "%.3f %s %dx%d %.3f %.3f %lu %.3f\n", ms,
            vv_preview_kind_name((vv_preview_kind)self->shown_kind),
            gdk_texture_get_width(self->texture), gdk_texture_get_height(self->texture),
            self->shown_render_ms, self->shown_latency_us * 1e-3, (unsigned long)self->shown_gen,
            (now - self->shown_rendered_us) * 1e-3);
    fflush(self->frame_log);
}

/* The anatomical frame and unit of the selected volume (else the first). */
static void
volume_frame(VvgSceneView *self, vv_space *space, const char **units) {
    const vv_world *w = vvg_document_world(self->doc);
    const vv_object *o = vvg_document_selected_object(self->doc);
    for (int i = 0; (!o || !o->volume) && i < w->n_objects; i++)
        o = w->objects[i];
    *space = o && o->volume ? o->volume->space : VV_SPACE_UNKNOWN;
    *units = vvg_unit_label(o ? o->volume : NULL);
}

static void
draw_overlays(VvgSceneView *self, GtkSnapshot *snapshot, int ww, int wh) {
    VvgSceneOverlay ov;
    memset(&ov, 0, sizeof ov);
    ov.world = vvg_document_world(self->doc);
    ov.view = &ov.world->view;
    image_rect(self, &ov.x0, &ov.y0, &ov.scale);
    ov.width = ww;
    ov.height = wh;
    ov.target = self->target;
    ov.moving_plane = self->target == VVG_NAV_CUT ? target_plane(self, NULL) : NULL;
    ov.light = self->light;
    ov.marks = self->marks;
    volume_frame(self, &ov.space, &ov.units);
    cairo_t *cr = gtk_snapshot_append_cairo(snapshot, &GRAPHENE_RECT_INIT(0, 0, ww, wh));
    vvg_scene_overlay_draw(cr, &ov);
    cairo_destroy(cr);
}

static void
vvg_scene_view_snapshot(GtkWidget *widget, GtkSnapshot *snapshot) {
    VvgSceneView *self = VVG_SCENE_VIEW(widget);
    int ww = gtk_widget_get_width(widget), wh = gtk_widget_get_height(widget);
    const vv_world *w = vvg_document_world(self->doc);
    vv_vec3 bg = w->background;
    GdkRGBA bgc = {(float)bg.x, (float)bg.y, (float)bg.z, 1};
    gtk_snapshot_append_color(snapshot, &bgc, &GRAPHENE_RECT_INIT(0, 0, ww, wh));
    if (!self->texture || w->n_objects == 0)
        return;
    /* the view's image: the widget's size (times its scale), centred */
    double x0, y0, sc;
    image_rect(self, &x0, &y0, &sc);
    graphene_rect_t r = GRAPHENE_RECT_INIT((float)x0, (float)y0, (float)(w->view.width * sc),
                                           (float)(w->view.height * sc));
    gtk_snapshot_append_texture(snapshot, self->texture, &r);
    draw_overlays(self, snapshot, ww, wh);
    log_frame(self);
}

/* The view renders at the widget's size in device pixels: the World's view
 * follows it (no undo step, the session stays saved; a saved session
 * renders through the CLI at this size). TRUE when it changed. */
static gboolean
sync_size(VvgSceneView *self) {
    int scale = gtk_widget_get_scale_factor(GTK_WIDGET(self));
    int w = gtk_widget_get_width(GTK_WIDGET(self)) * scale;
    int h = gtk_widget_get_height(GTK_WIDGET(self)) * scale;
    if (w < 16 || h < 16)
        return FALSE;
    const vv_view *v = &vvg_document_world(self->doc)->view;
    if (v->width == w && v->height == h)
        return FALSE;
    vvg_document_set_view_size(self->doc, w, h);
    return TRUE;
}

static void
vvg_scene_view_size_allocate(GtkWidget *widget, int width, int height, int baseline) {
    GTK_WIDGET_CLASS(vvg_scene_view_parent_class)->size_allocate(widget, width, height, baseline);
    VvgSceneView *self = VVG_SCENE_VIEW(widget);
    if (self->doc && sync_size(self))
        state_changed(self);
}

static void
vvg_scene_view_measure(GtkWidget *widget, GtkOrientation o, int for_size, int *min, int *nat,
                       int *min_base, int *nat_base) {
    (void)widget;
    (void)for_size;
    /* small: the view takes what the window gives it */
    *min = 96;
    *nat = o == GTK_ORIENTATION_HORIZONTAL ? 320 : 240;
    *min_base = *nat_base = -1;
}

/* ---- input ------------------------------------------------------------------ */

static gboolean tick_cb(GtkWidget *widget, GdkFrameClock *clock, gpointer user);

static void
begin_interaction(VvgSceneView *self, const char *label) {
    vvg_document_begin_edit(self->doc, label);
}

/* A drag of (dx, dy) widget pixels, through the Navigator (vv_nav_apply):
 * left drag rotates, Shift or the middle or right button pans, Ctrl zooms
 * (an object scales); Alt moves the selected object. A cut plane slides
 * along its normal, Shift turns it. */
static void
apply_motion(VvgSceneView *self, double dx, double dy) {
    vv_world *w = vvg_document_world(self->doc);
    /* widget pixels to view pixels (the image may be shown scaled down) */
    double x0, y0, s;
    image_rect(self, &x0, &y0, &s);
    dx /= s;
    dy /= s;
    gboolean shift = (self->drag_mods & GDK_SHIFT_MASK) != 0;
    gboolean pan = self->drag_button == 3 || self->drag_button == 2 || shift;
    gboolean zoom = (self->drag_mods & GDK_CONTROL_MASK) != 0;
    VvgNavTarget target = self->target;
    if (self->drag_mods & GDK_ALT_MASK)
        target = VVG_NAV_OBJECT;
    vv_nav_target t = {VV_NAV_TARGET_VIEW, 0, -1};
    vv_nav_motion m = {.kind = zoom  ? VV_NAV_ZOOM
                               : pan ? VV_NAV_PAN
                                     : VV_NAV_ROTATE,
                       .dx = dx,
                       .dy = dy,
                       .factor = exp(-dy / 200.0)};
    if (target == VVG_NAV_OBJECT && vvg_document_selected(self->doc) >= 0) {
        t.kind = VV_NAV_TARGET_OBJECT;
        t.index = vvg_document_selected(self->doc);
    } else if (target == VVG_NAV_CUT) {
        if (!target_plane(self, &t))
            return;
        m.kind = shift ? VV_NAV_ROTATE : VV_NAV_PAN;
    } else if (target == VVG_NAV_LIGHT) {
        if (self->light < 0 || self->light >= w->n_lights)
            return;
        t.kind = VV_NAV_TARGET_LIGHT;
        t.index = self->light;
        m.kind = VV_NAV_ROTATE; /* a light follows any drag */
    }
    if (vv_nav_apply(w, &t, &m) != VV_OK)
        return;
    vvg_document_changed(self->doc);
}

static void
drag_begin(GtkGestureDrag *g, double x, double y, gpointer user) {
    VvgSceneView *self = user;
    self->drag_last_x = 0;
    self->drag_last_y = 0;
    self->drag_button = (int)gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(g));
    self->drag_mods = gtk_event_controller_get_current_event_state(GTK_EVENT_CONTROLLER(g));
    (void)x;
    (void)y;
    self->dragged = FALSE;
    gtk_widget_grab_focus(GTK_WIDGET(self));
}

static void
drag_end(GtkGestureDrag *g, double ox, double oy, gpointer user) {
    VvgSceneView *self = user;
    if (self->flight && self->drag_button == 1) /* the mouse stick is let go */
        self->yaw_rate = self->pitch_rate = 0;
    if (self->dragged || !self->pick_fn || fabs(ox) > 3 || fabs(oy) > 3)
        return;
    double sx, sy;
    gtk_gesture_drag_get_start_point(g, &sx, &sy);
    vv_vec3 p;
    if (!vvg_scene_view_pick(self, sx, sy, &p))
        return; /* stays armed: nothing under the pointer yet */
    VvgPickFunc fn = self->pick_fn;
    gpointer u = self->pick_user;
    vvg_scene_view_pick_next(self, NULL, NULL);
    fn(u, p);
}

static void
drag_update(GtkGestureDrag *g, double ox, double oy, gpointer user) {
    (void)g;
    VvgSceneView *self = user;
    double dx = ox - self->drag_last_x, dy = oy - self->drag_last_y;
    self->drag_last_x = ox;
    self->drag_last_y = oy;
    if (dx == 0 && dy == 0)
        return;
    if (self->flight && self->drag_button == 1 &&
        !(self->drag_mods & (GDK_SHIFT_MASK | GDK_CONTROL_MASK | GDK_ALT_MASK))) {
        /* flight with the mouse: the drag is a stick, its offset from the
         * press sets the yaw and pitch rates (a quarter turn a second at
         * 200 pixels) until the button is released */
        double k = (VV_PI / 2) / 200.0;
        self->yaw_rate = CLAMP(-ox * k, -VV_PI, VV_PI);
        self->pitch_rate = CLAMP(-oy * k, -VV_PI, VV_PI);
        if (!self->dragged) {
            self->dragged = TRUE;
            begin_interaction(self, "fly");
        }
        if (!self->tick_id) {
            self->last_tick_us = 0;
            self->tick_id = gtk_widget_add_tick_callback(GTK_WIDGET(self), tick_cb, self, NULL);
        }
        return;
    }
    if (!self->dragged) {
        self->dragged = TRUE;
        begin_interaction(self, self->target == VVG_NAV_OBJECT  ? "move object"
                                : self->target == VVG_NAV_LIGHT ? "move light"
                                : self->target == VVG_NAV_CUT   ? "move cut plane"
                                                                : "move view");
    }
    apply_motion(self, dx, dy);
}

static gboolean
scroll_cb(GtkEventControllerScroll *c, double dx, double dy, gpointer user) {
    (void)c;
    (void)dx;
    VvgSceneView *self = user;
    if (!isfinite(dy) || dy == 0)
        return FALSE;
    begin_interaction(self, "zoom");
    vv_nav_motion m = {.kind = VV_NAV_ZOOM, .factor = pow(1.1, -dy)};
    vv_nav_target t = {VV_NAV_TARGET_VIEW, 0, -1};
    if (vv_nav_apply(vvg_document_world(self->doc), &t, &m) == VV_OK)
        vvg_document_changed(self->doc);
    return TRUE;
}

static gboolean
tick_cb(GtkWidget *widget, GdkFrameClock *clock, gpointer user) {
    (void)widget;
    VvgSceneView *self = user;
    gint64 now = gdk_frame_clock_get_frame_time(clock);
    double dt = self->last_tick_us ? (now - self->last_tick_us) * 1e-6 : 0.0;
    self->last_tick_us = now;
    if (self->yaw_rate == 0 && self->pitch_rate == 0 && self->roll_rate == 0 &&
        self->throttle == 0) {
        self->tick_id = 0;
        self->last_tick_us = 0;
        return G_SOURCE_REMOVE;
    }
    vv_world *w = vvg_document_world(self->doc);
    /* throttle in scene sizes a second */
    vv_box b = vv_world_bounds(w);
    double size = vv_vec3_length(vv_vec3_sub(b.max, b.min));
    if (!(size > 0))
        size = 1;
    vv_nav_motion m = {.kind = VV_NAV_FLY,
                       .yaw = self->yaw_rate,
                       .pitch = self->pitch_rate,
                       .roll = self->roll_rate,
                       .speed = self->throttle * 0.25 * size,
                       .dt = dt};
    vv_nav_target t = {VV_NAV_TARGET_VIEW, 0, -1};
    if (vv_nav_apply(w, &t, &m) == VV_OK)
        vvg_document_changed(self->doc);
    return G_SOURCE_CONTINUE;
}

static gboolean
flight_key(VvgSceneView *self, guint key, gboolean down) {
    double rate = down ? 0.6 : 0.0; /* radians a second */
    switch (key) {
    case GDK_KEY_Left:
        self->yaw_rate = rate;
        break;
    case GDK_KEY_Right:
        self->yaw_rate = -rate;
        break;
    case GDK_KEY_Up:
        self->pitch_rate = rate;
        break;
    case GDK_KEY_Down:
        self->pitch_rate = -rate;
        break;
    case GDK_KEY_q:
        self->roll_rate = -rate;
        break;
    case GDK_KEY_e:
        self->roll_rate = rate;
        break;
    case GDK_KEY_w:
        self->throttle = down ? 1.0 : 0.0;
        break;
    case GDK_KEY_s:
        self->throttle = down ? -1.0 : 0.0;
        break;
    default:
        return FALSE;
    }
    if (down && !self->tick_id) {
        begin_interaction(self, "fly");
        self->last_tick_us = 0;
        self->tick_id = gtk_widget_add_tick_callback(GTK_WIDGET(self), tick_cb, self, NULL);
    }
    return TRUE;
}

static gboolean
key_pressed(GtkEventControllerKey *c, guint key, guint code, GdkModifierType mods, gpointer user) {
    (void)c;
    (void)code;
    VvgSceneView *self = user;
    if (!self->flight || (mods & (GDK_CONTROL_MASK | GDK_ALT_MASK)))
        return FALSE;
    return flight_key(self, key, TRUE);
}

static void
key_released(GtkEventControllerKey *c, guint key, guint code, GdkModifierType mods, gpointer user) {
    (void)c;
    (void)code;
    (void)mods;
    VvgSceneView *self = user;
    if (self->flight)
        flight_key(self, key, FALSE);
}

static void
vvg_scene_view_dispose(GObject *o) {
    VvgSceneView *self = VVG_SCENE_VIEW(o);
    vvg_scene_view_stop(self);
    if (self->refine_source) {
        g_source_remove(self->refine_source);
        self->refine_source = 0;
    }
    if (self->doc) {
        g_signal_handler_disconnect(self->doc, self->changed_id);
        g_clear_object(&self->doc);
    }
    if (self->marks) {
        g_signal_handlers_disconnect_by_data(self->marks, self);
        g_clear_object(&self->marks);
    }
    g_clear_object(&self->texture);
    g_free(self->shown_depth);
    self->shown_depth = NULL;
    vvg_source_set_clear(&self->shown_src);
    if (self->frame_log) {
        fclose(self->frame_log);
        self->frame_log = NULL;
    }
    G_OBJECT_CLASS(vvg_scene_view_parent_class)->dispose(o);
}

static void
vvg_scene_view_finalize(GObject *o) {
    VvgSceneView *self = VVG_SCENE_VIEW(o);
    g_mutex_clear(&self->lock);
    g_cond_clear(&self->cond);
    G_OBJECT_CLASS(vvg_scene_view_parent_class)->finalize(o);
}

static void
vvg_scene_view_class_init(VvgSceneViewClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_scene_view_dispose;
    G_OBJECT_CLASS(klass)->finalize = vvg_scene_view_finalize;
    GTK_WIDGET_CLASS(klass)->snapshot = vvg_scene_view_snapshot;
    GTK_WIDGET_CLASS(klass)->measure = vvg_scene_view_measure;
    GTK_WIDGET_CLASS(klass)->size_allocate = vvg_scene_view_size_allocate;
}

static void
vvg_scene_view_init(VvgSceneView *self) {
    g_mutex_init(&self->lock);
    g_cond_init(&self->cond);
    vv_preview_policy_init(&self->policy);
    self->refine_delay_ms = 100;
    self->shown_kind = -1;
    self->cut_plane = -1;
#ifdef VVG_TSAN
    self->tsan_inject_race = g_strcmp0(g_getenv("VOLVIS_TSAN_INJECT_RACE"), "1") == 0;
    if (self->tsan_inject_race)
        g_printerr("volvis-gui: VOLVIS_TSAN_INJECT_RACE=1: the render thread writes the preview "
                   "policy without its lock\n");
#endif
    gtk_widget_set_focusable(GTK_WIDGET(self), TRUE);
    vvg_name(GTK_WIDGET(self), "3-D view");
    gtk_widget_set_hexpand(GTK_WIDGET(self), TRUE);
    gtk_widget_set_vexpand(GTK_WIDGET(self), TRUE);
    const char *log = g_getenv("VOLVIS_FRAME_LOG");
    if (log && *log) {
        self->frame_log = fopen(log, "a");
        if (!self->frame_log)
            g_warning("volvis-gui: VOLVIS_FRAME_LOG: cannot open %s", log);
    }
    /* left drag: rotate (Shift: pan, Ctrl: zoom); middle or right drag: pan */
    for (int button = 1; button <= 3; button++) {
        GtkGesture *drag = gtk_gesture_drag_new();
        gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(drag), (guint)button);
        g_signal_connect(drag, "drag-begin", G_CALLBACK(drag_begin), self);
        g_signal_connect(drag, "drag-update", G_CALLBACK(drag_update), self);
        g_signal_connect(drag, "drag-end", G_CALLBACK(drag_end), self);
        gtk_widget_add_controller(GTK_WIDGET(self), GTK_EVENT_CONTROLLER(drag));
    }
    GtkEventController *scroll = gtk_event_controller_scroll_new(
        GTK_EVENT_CONTROLLER_SCROLL_VERTICAL | GTK_EVENT_CONTROLLER_SCROLL_DISCRETE);
    g_signal_connect(scroll, "scroll", G_CALLBACK(scroll_cb), self);
    gtk_widget_add_controller(GTK_WIDGET(self), scroll);
    GtkEventController *keys = gtk_event_controller_key_new();
    g_signal_connect(keys, "key-pressed", G_CALLBACK(key_pressed), self);
    g_signal_connect(keys, "key-released", G_CALLBACK(key_released), self);
    gtk_widget_add_controller(GTK_WIDGET(self), keys);
}

static void
marks_changed(VvgMarks *m, gpointer user) {
    (void)m;
    gtk_widget_queue_draw(GTK_WIDGET(user));
}

VvgSceneView *
vvg_scene_view_new(VvgDocument *doc, VvgMarks *marks) {
    VvgSceneView *self = g_object_new(VVG_TYPE_SCENE_VIEW, NULL);
    self->doc = g_object_ref(doc);
    self->marks = g_object_ref(marks);
    g_signal_connect(marks, "changed", G_CALLBACK(marks_changed), self);
    self->changed_id = g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    vvg_scene_render_start(self);
    state_changed(self);
    return self;
}

void
vvg_scene_view_set_target(VvgSceneView *self, VvgNavTarget target) {
    self->target = target;
    gtk_widget_queue_draw(GTK_WIDGET(self));
}

void
vvg_scene_view_set_cut_plane(VvgSceneView *self, int object, int plane) {
    self->cut_object = object;
    self->cut_plane = plane;
    if (self->marks)
        vvg_marks_set_cut_plane(self->marks, object, plane);
    gtk_widget_queue_draw(GTK_WIDGET(self));
}

void
vvg_scene_view_set_light(VvgSceneView *self, int index) {
    self->light = index;
    gtk_widget_queue_draw(GTK_WIDGET(self));
}

void
vvg_scene_view_set_preview(VvgSceneView *self, int kind) {
    g_mutex_lock(&self->lock);
    self->policy.forced = kind >= 0 && kind < VV_PREVIEW_COUNT ? kind : -1;
    g_mutex_unlock(&self->lock);
}

void
vvg_scene_view_set_refine_delay(VvgSceneView *self, int ms) {
    self->refine_delay_ms = ms < 0 ? 0 : ms > 2000 ? 2000 : ms;
}

void
vvg_scene_view_set_flight(VvgSceneView *self, gboolean on) {
    self->flight = on;
    if (!on)
        self->yaw_rate = self->pitch_rate = self->roll_rate = self->throttle = 0;
}

double
vvg_scene_view_full_ms(VvgSceneView *self) {
    return self->full_ms;
}

/* The cache's status below (out of core), after why the gpu renderer did
 * not draw the frame on screen, when it did not. */
static char *cache_status(VvgSceneView *self);

char *
vvg_scene_view_cache_status(VvgSceneView *self) {
    char *t = cache_status(self);
    if (!self->shown_gpu_note[0])
        return t;
    char *both = g_strdup_printf("the gpu renderer failed (%s): drawn by the CPU ray caster%s%s",
                                 self->shown_gpu_note, t[0] ? "; " : "", t);
    g_free(t);
    return both;
}

static char *
cache_status(VvgSceneView *self) {
    if (self->shown_lod_note[0])
        return g_strdup_printf("the proxies in memory: %s", self->shown_lod_note);
    if (self->shown_src.n == 0)
        return g_strdup("");
    /* the sums over the files drawn (two objects of one file: counted once) */
    guint64 chunks = 0, bricks = 0;
    int loading = 0, pyramids = 0, bricked = 0;
    for (int i = 0; i < self->shown_src.n; i++) {
        int seen = 0;
        for (int k = 0; k < i; k++)
            seen |= self->shown_src.s[k] == self->shown_src.s[i];
        if (seen)
            continue;
        vv_source_stats st;
        vv_source_stats_get(self->shown_src.s[i], &st);
        for (int l = 0; l < VV_SOURCE_MAX_LEVELS; l++)
            chunks += st.chunk_reads[l];
        bricks += st.loads;
        loading += st.loading;
        pyramids += st.kind == VV_SOURCE_PYRAMID;
        bricked += st.kind == VV_SOURCE_BRICKS;
    }
    /* the one cache every file shares, and its one budget */
    const vv_cache *cache = vv_source_cache(self->shown_src.s[0]);
    vv_cache_stats cs;
    vv_cache_stats_get(cache ? cache : vv_cache_process(), &cs);
    GString *s = g_string_new(NULL);
    if (self->shown_src.n > 1)
        g_string_append_printf(s, "%d objects ", self->shown_src.n);
    g_string_append_printf(s, "out of core: %" G_GUINT64_FORMAT " %s held (%.1f of %.0f MiB)",
                           cs.entries,
                           pyramids && bricked ? "chunks and bricks"
                           : pyramids          ? "chunks"
                                               : "bricks",
                           (double)cs.held / 1048576.0, (double)cs.limit / 1048576.0);
    if (pyramids)
        g_string_append_printf(s, ", %d loading, %" G_GUINT64_FORMAT " chunks read", loading,
                               chunks);
    if (bricked)
        g_string_append_printf(s, ", %" G_GUINT64_FORMAT " bricks read", bricks);
    /* what it held at most, with the working sets reserved (never over the limit) */
    g_string_append_printf(s, ", at most %.1f MiB", (double)cs.peak / 1048576.0);
    gboolean levels = FALSE;
    for (int l = 0; l < VV_LOD_MAX_LEVELS; l++)
        if (self->shown_nodes[l] > 0) {
            g_string_append_printf(s, "%s %d (%d nodes)", levels ? "" : "; level in use:", l,
                                   self->shown_nodes[l]);
            levels = TRUE;
        }
    if (self->shown_pending > 0)
        g_string_append_printf(s, "; %d nodes still coarser%s", self->shown_pending,
                               self->shown_stalled ? " (more than the memory limit holds)" : "");
    else
        g_string_append(s, "; converged");
    return g_string_free(s, FALSE);
}

const char *
vvg_scene_view_shown(VvgSceneView *self) {
    return self->shown_kind < 0 ? "" : vv_preview_kind_name((vv_preview_kind)self->shown_kind);
}
