/* VvgModelingPage: voxelized primitives, meshes and CSG (vvg-modeling-page.h). */
#include "vvg-modeling-page.h"
#include "vvg-widgets.h"

#include <string.h>

struct _VvgModelingPage {
    GtkBox parent;
    VvgDocument *doc;
    GtkWidget *prim_kind, *prim_size, *prim_res, *model_progress, *prim_mesh, *prim_pos[3];
    GtkWidget *prim_axis, *prim_angle, *csg_a, *csg_b, *csg_op;
    GHashTable *recipes;      /* vv_volume * -> model_recipe * of the objects made here */
    GPtrArray *model_volumes; /* the volumes listed in csg_a and csg_b, in order */
};

G_DEFINE_TYPE(VvgModelingPage, vvg_modeling_page, GTK_TYPE_BOX)

/* ---- Modeling page ------------------------------------------------------------ */

/*
 * How an object of the Modeling page was made, so that CSG can rebuild both
 * operands as shapes (vv_shape_csg takes its children): a primitive or a mesh
 * file with its placement, or a CSG of two recipes. Kept per volume made
 * (the volume's address; the object may be renamed, moved in the list or
 * copied by undo, and keeps its volume).
 */
typedef struct model_recipe {
    int kind; /* index of prim_names; PRIM_MESH: a mesh file; PRIM_CSG: op of a and b */
    double size;
    char *mesh;
    vv_vec3 position;
    int axis;     /* 0 x, 1 y, 2 z */
    double angle; /* degrees */
    vv_csg_op op;
    struct model_recipe *a, *b;
} model_recipe;

static const char *const prim_names[] = {"sphere", "box",       "torus", "cylinder",
                                         "cone",   "mesh file", NULL};
#define PRIM_MESH 5
#define PRIM_CSG 6

static void
recipe_free(gpointer p) {
    model_recipe *r = p;
    if (!r)
        return;
    g_free(r->mesh);
    recipe_free(r->a);
    recipe_free(r->b);
    g_free(r);
}

static model_recipe *
recipe_copy(const model_recipe *r) {
    if (!r)
        return NULL;
    model_recipe *c = g_new(model_recipe, 1);
    *c = *r;
    c->mesh = g_strdup(r->mesh);
    c->a = recipe_copy(r->a);
    c->b = recipe_copy(r->b);
    return c;
}

/* A fresh shape tree for @p r (caller frees). */
static vv_status
recipe_shape(const model_recipe *r, vv_shape **out) {
    *out = NULL;
    vv_status st;
    double h = r->size / 2;
    switch (r->kind) {
    case 0:
        st = vv_shape_sphere(out, h);
        break;
    case 1:
        st = vv_shape_box(out, vv_vec3_make(r->size, r->size, r->size), 0.1 * h);
        break;
    case 2:
        st = vv_shape_torus(out, 0.7 * h, 0.25 * h);
        break;
    case 3:
        st = vv_shape_cylinder(out, 0.5 * h, r->size);
        break;
    case 4:
        st = vv_shape_cone(out, 0.6 * h, 0, r->size);
        break;
    case PRIM_MESH:
        st = vv_shape_mesh_load(out, r->mesh, VV_MESH_AUTO, 0);
        break;
    default: {
        vv_shape *kids[2] = {NULL, NULL};
        st = recipe_shape(r->a, &kids[0]);
        if (st == VV_OK)
            st = recipe_shape(r->b, &kids[1]);
        if (st != VV_OK) {
            vv_shape_free(kids[0]);
            vv_shape_free(kids[1]);
            return st;
        }
        return vv_shape_csg(out, r->op, 2, kids);
    }
    }
    if (st != VV_OK)
        return st;
    vv_vec3 ax = vv_vec3_make(r->axis == 0, r->axis == 1, r->axis == 2);
    vv_shape_transform(*out, vv_mat4_mul(vv_mat4_translate(r->position),
                                         vv_mat4_rotate(ax, vv_deg_to_rad(r->angle))));
    return VV_OK;
}

static char *
recipe_name(const model_recipe *r) {
    if (r->kind == PRIM_CSG)
        return g_strdup_printf("%s", vv_csg_op_name(r->op));
    if (r->kind == PRIM_MESH) {
        char *b = g_path_get_basename(r->mesh);
        char *dot = strrchr(b, '.');
        if (dot && dot != b)
            *dot = '\0';
        return b;
    }
    return g_strdup(prim_names[r->kind]);
}

typedef struct model_job {
    model_recipe *recipe;
    int res;
    vv_volume *result;
    vv_status status;
    char error[512];
    double fraction;              /* atomic */
    VvgModelingPage *page;        /* the page the progress bar is on */
    const vv_volume *operands[2]; /* CSG: the volumes of A and B (compared only) */
} model_job;

static int
model_progress(void *user, double f) {
    model_job *j = user;
    __atomic_store(&j->fraction, &f, __ATOMIC_RELAXED);
    return 0;
}

static void
model_thread(GTask *task, gpointer src, gpointer data, GCancellable *c) {
    (void)task;
    (void)src;
    (void)c;
    model_job *j = data;
    vv_shape *sh = NULL;
    vv_error_clear();
    j->status = recipe_shape(j->recipe, &sh);
    if (j->status == VV_OK) {
        vv_voxelize_options o;
        vv_voxelize_options_init(&o);
        o.size = j->res;
        o.progress.fn = model_progress;
        o.progress.user = j;
        j->status = vv_voxelize(&j->result, sh, &o);
    }
    if (j->status != VV_OK)
        g_strlcpy(j->error, vv_error_message(), sizeof j->error);
    vv_shape_free(sh);
}

static void
model_job_free(gpointer p) {
    model_job *j = p;
    vv_volume_free(j->result);
    recipe_free(j->recipe);
    g_free(j);
}

static gboolean
model_tick(gpointer user) {
    model_job *j = user;
    double f;
    __atomic_load(&j->fraction, &f, __ATOMIC_RELAXED);
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(j->page->model_progress), f);
    return G_SOURCE_CONTINUE;
}

static void rebuild_model_lists(VvgModelingPage *self);

static void
model_done(GObject *src, GAsyncResult *res, gpointer user) {
    VvgModelingPage *self = VVG_MODELING_PAGE(src);
    g_source_remove(GPOINTER_TO_UINT(user));
    model_job *j = g_task_get_task_data(G_TASK(res));
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(self->model_progress), 1);
    if (j->status != VV_OK) {
        vvg_show_error(GTK_WIDGET(self), "Voxelization failed", j->error);
        return;
    }
    vv_object *o = NULL;
    char *name = recipe_name(j->recipe);
    vv_status st = vv_object_new_volume(&o, j->result, name);
    g_free(name);
    if (st != VV_OK) {
        vvg_show_error(GTK_WIDGET(self), "Voxelization failed", vv_error_message());
        return;
    }
    /* the density surface (127.5 of 255) as an opaque isosurface */
    o->mode = VV_MODE_ISO;
    o->isovalue = 127.5;
    if (!g_hash_table_contains(self->recipes, j->result))
        g_hash_table_insert(self->recipes, vv_volume_ref(j->result), recipe_copy(j->recipe));
    vv_world *w = vvg_document_world(self->doc);
    gboolean first = w->n_objects == 0;
    vvg_document_add_object(self->doc, o, NULL);
    /* a CSG result stands in for its operands: they are hidden (same undo step) */
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->volume &&
            (w->objects[i]->volume == j->operands[0] || w->objects[i]->volume == j->operands[1]))
            w->objects[i]->visible = 0;
    if (j->operands[0])
        vvg_document_changed(self->doc);
    if (first) {
        if (w->n_lights == 0) {
            vv_light l = {VV_LIGHT_DIRECTIONAL, 1, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1.0};
            vv_world_add_light(w, &l);
        }
        vv_view_frame_box(&w->view, vv_world_bounds(w));
        vvg_document_changed(self->doc);
    }
    rebuild_model_lists(self);
}

static model_job *
start_model(VvgModelingPage *self, model_recipe *r) {
    model_job *j = g_new0(model_job, 1);
    j->recipe = r;
    j->res = (int)vvg_spin_value(self->prim_res);
    j->page = self;
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(self->model_progress), 0);
    guint tick = g_timeout_add(100, model_tick, j);
    GTask *task = g_task_new(self, NULL, model_done, GUINT_TO_POINTER(tick));
    g_task_set_task_data(task, j, model_job_free);
    g_task_run_in_thread(task, model_thread);
    g_object_unref(task);
    return j;
}

static void
act_voxelize(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgModelingPage *self = user;
    model_recipe *r = g_new0(model_recipe, 1);
    r->kind = (int)gtk_drop_down_get_selected(GTK_DROP_DOWN(self->prim_kind));
    r->size = vvg_spin_value(self->prim_size);
    if (r->kind == PRIM_MESH) {
        const char *m = gtk_editable_get_text(GTK_EDITABLE(self->prim_mesh));
        if (!m[0]) {
            g_free(r);
            vvg_show_error(GTK_WIDGET(self), "No mesh file", "enter the mesh file to voxelize");
            return;
        }
        r->mesh = g_strdup(m);
    }
    r->position = vv_vec3_make(vvg_spin_value(self->prim_pos[0]), vvg_spin_value(self->prim_pos[1]),
                               vvg_spin_value(self->prim_pos[2]));
    r->axis = (int)gtk_drop_down_get_selected(GTK_DROP_DOWN(self->prim_axis));
    r->angle = vvg_spin_value(self->prim_angle);
    start_model(self, r);
}

/* The objects made on this page (their recipes), in World order, into the CSG lists. */
static void
rebuild_model_lists(VvgModelingPage *self) {
    GtkStringList *names = gtk_string_list_new(NULL);
    g_ptr_array_set_size(self->model_volumes, 0);
    vv_world *w = vvg_document_world(self->doc);
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->volume && g_hash_table_contains(self->recipes, o->volume)) {
            gtk_string_list_append(names, o->name);
            g_ptr_array_add(self->model_volumes, o->volume);
        }
    }
    gtk_drop_down_set_model(GTK_DROP_DOWN(self->csg_a), G_LIST_MODEL(names));
    gtk_drop_down_set_model(GTK_DROP_DOWN(self->csg_b), G_LIST_MODEL(names));
    if (g_list_model_get_n_items(G_LIST_MODEL(names)) > 1)
        gtk_drop_down_set_selected(GTK_DROP_DOWN(self->csg_b), 1);
    g_object_unref(names);
}

static void
act_csg(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgModelingPage *self = user;
    guint ia = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->csg_a));
    guint ib = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->csg_b));
    if (ia >= self->model_volumes->len || ib >= self->model_volumes->len) {
        vvg_show_error(GTK_WIDGET(self), "No CSG", "make two objects on this page first");
        return;
    }
    const model_recipe *ra = g_hash_table_lookup(self->recipes, self->model_volumes->pdata[ia]);
    const model_recipe *rb = g_hash_table_lookup(self->recipes, self->model_volumes->pdata[ib]);
    if (!ra || !rb)
        return;
    model_recipe *r = g_new0(model_recipe, 1);
    r->kind = PRIM_CSG;
    r->op = (vv_csg_op)gtk_drop_down_get_selected(GTK_DROP_DOWN(self->csg_op));
    r->a = recipe_copy(ra);
    r->b = recipe_copy(rb);
    model_job *j = start_model(self, r);
    j->operands[0] = self->model_volumes->pdata[ia];
    j->operands[1] = self->model_volumes->pdata[ib];
}

static void
model_doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgModelingPage *self = user;
    /* names and objects change with renames, deletes and undo */
    vv_world *w = vvg_document_world(self->doc);
    guint n = 0;
    for (int i = 0; i < w->n_objects; i++)
        n += w->objects[i]->volume && g_hash_table_contains(self->recipes, w->objects[i]->volume);
    if (n != self->model_volumes->len)
        rebuild_model_lists(self);
}

static void
build(VvgModelingPage *self) {
    GtkWidget *box = GTK_WIDGET(self);
    GtkWidget *g = vvg_section(box, "Voxelized primitive or mesh (volume sampling)");
    self->prim_kind = vvg_row(g, "model", gtk_drop_down_new_from_strings(prim_names));
    self->prim_size = vvg_row(g, "size (world units)", vvg_spin0(0.1, 1e5, 1, 2));
    vvg_set_spin(self->prim_size, 100);
    self->prim_mesh = vvg_row(g, "mesh file", gtk_entry_new());
    gtk_entry_set_placeholder_text(GTK_ENTRY(self->prim_mesh), "OBJ, PLY, STL, OFF, ...");
    const char *axes[] = {"position x", "position y", "position z"};
    for (int i = 0; i < 3; i++)
        self->prim_pos[i] = vvg_row(g, axes[i], vvg_spin0(-1e5, 1e5, 1, 2));
    static const char *const rot_axes[] = {"x", "y", "z", NULL};
    self->prim_axis = vvg_row(g, "rotation axis", gtk_drop_down_new_from_strings(rot_axes));
    gtk_drop_down_set_selected(GTK_DROP_DOWN(self->prim_axis), 2);
    self->prim_angle = vvg_row(g, "rotation (°)", vvg_spin0(-360, 360, 5, 1));
    self->prim_res = vvg_row(g, "voxels on the longest axis", vvg_spin0(8, 1024, 8, 0));
    vvg_set_spin(self->prim_res, 128);
    gtk_box_append(GTK_BOX(box), vvg_action_button("Add", "win.voxelize"));
    g = vvg_section(box, "CSG of two objects made here");
    self->csg_a = vvg_row(g, "A", gtk_drop_down_new(NULL, NULL));
    static const char *const ops[] = {"union", "intersection", "difference (A - B)", NULL};
    self->csg_op = vvg_row(g, "operation", gtk_drop_down_new_from_strings(ops));
    self->csg_b = vvg_row(g, "B", gtk_drop_down_new(NULL, NULL));
    gtk_box_append(GTK_BOX(box), vvg_action_button("Combine", "win.csg"));
    self->model_progress = gtk_progress_bar_new();
    gtk_box_append(GTK_BOX(box), self->model_progress);
}

static void
vvg_modeling_page_dispose(GObject *o) {
    VvgModelingPage *self = VVG_MODELING_PAGE(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    g_clear_pointer(&self->recipes, g_hash_table_destroy);
    g_clear_pointer(&self->model_volumes, g_ptr_array_unref);
    G_OBJECT_CLASS(vvg_modeling_page_parent_class)->dispose(o);
}

static void
vvg_modeling_page_class_init(VvgModelingPageClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_modeling_page_dispose;
}

static void
vvg_modeling_page_init(VvgModelingPage *self) {
    vvg_vbox_init(GTK_WIDGET(self));
    gtk_widget_set_margin_start(GTK_WIDGET(self), 8);
    gtk_widget_set_margin_end(GTK_WIDGET(self), 8);
    gtk_widget_set_margin_bottom(GTK_WIDGET(self), 8);
    /* a reference is held on each key so that an address is never reused */
    self->recipes = g_hash_table_new_full(g_direct_hash, g_direct_equal,
                                          (GDestroyNotify)vv_volume_free, recipe_free);
    self->model_volumes = g_ptr_array_new();
}

GtkWidget *
vvg_modeling_page_new(VvgDocument *doc, GActionMap *actions) {
    VvgModelingPage *self = g_object_new(VVG_TYPE_MODELING_PAGE, NULL);
    self->doc = g_object_ref(doc);
    const GActionEntry entries[] = {
        {"voxelize", act_voxelize, NULL, NULL, NULL, {0}},
        {"csg", act_csg, NULL, NULL, NULL, {0}},
    };
    g_action_map_add_action_entries(actions, entries, G_N_ELEMENTS(entries), self);
    build(self);
    g_signal_connect(doc, "changed", G_CALLBACK(model_doc_changed), self);
    return GTK_WIDGET(self);
}
