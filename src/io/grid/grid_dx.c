/*
 * OpenDX native files with positions, connections and data, text or
 * binary, either byte order ("IBM Visualization Data Explorer, User's
 * Guide", appendix B, "Data Explorer native file format").
 *
 * The reader holds the whole file in memory (at most VV_GRID_FILE_MAX
 * bytes) and checks every count against the bytes that remain. Its stages:
 * the header (objects: arrays with their type, shape, items, byte order and
 * where their data is; fields with their components; attributes) up to the
 * "end" line that starts the binary section; then the grid from the first
 * field with positions and connections; then the data of every field on
 * those positions or connections.
 */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "io/grid/grid_io_internal.h"
#include "io/io_internal.h"
#include "volvis/grid.h"
#include "volvis/sys/format.h"

typedef struct dx_array {
    int id;        /* object number, or -1 for named objects */
    char name[64]; /* named object */
    vv_gtype type;
    int big_endian;
    int rank, shape;
    size_t items;
    int follows;   /* data follows: inline after the header line */
    size_t offset; /* data offset in the binary section */
    int text;      /* ascii data */
    const unsigned char *inline_data;
    char dep[64];     /* attribute "dep" */
    char element[64]; /* attribute "element type" */
} dx_array;

typedef struct dx_field {
    char name[64];
    int data, positions, connections; /* array ids, -1 none */
} dx_field;

#define DX_MAX_OBJ 256

/* A file's header as read. */
typedef struct dx_doc {
    vv_gcur c;
    const char *path;
    dx_array *arr; /* DX_MAX_OBJ */
    int n_arr;
    dx_field fields[DX_MAX_OBJ];
    int n_fields;
    const unsigned char *binary_start; /* after the "end" line; NULL without one */
    dx_array *cur;                     /* the object whose attributes follow */
    dx_field *curf;
} dx_doc;

/* @p s as an int: 1, or 0 for anything else (junk, a number out of
 * range: atoi's behaviour there is undefined). */
static int
dx_int(const char *s, int *out) {
    char *end;
    errno = 0;
    const long v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < INT_MIN || v > INT_MAX)
        return 0;
    *out = (int)v;
    return 1;
}

static int
dx_quoted_or_number(vv_gcur *c, char *buf, size_t cap, int *id) {
    while (c->p < c->end && isspace(*c->p) && *c->p != '\n')
        c->p++;
    if (c->p < c->end && *c->p == '"') {
        c->p++;
        size_t n = 0;
        while (c->p < c->end && *c->p != '"' && *c->p != '\n') {
            /* binary junk never reaches an error message */
            if (n + 1 < cap)
                buf[n++] = (char)(*c->p >= 0x20 && *c->p <= 0x7e ? *c->p : '?');
            c->p++;
        }
        if (c->p < c->end && *c->p == '"')
            c->p++;
        buf[n] = '\0';
        *id = -1;
        return 1;
    }
    if (!vv_gcur_token(c, buf, cap))
        return 0;
    if (!dx_int(buf, id))
        *id = -1; /* not an object number */
    return 1;
}

static const dx_array *
dx_find(const dx_array *arr, int n, int id) {
    for (int i = 0; id >= 0 && i < n; i++)
        if (arr[i].id == id)
            return &arr[i];
    return NULL;
}

/* Reads an array's values as doubles. */
static vv_status
dx_values(const vv_gcur *c0, const unsigned char *binary_start, const dx_array *a, double *out) {
    const size_t n = a->items * (size_t)(a->shape > 0 ? a->shape : 1);
    vv_gcur c = *c0;
    if (a->follows) {
        c.p = a->inline_data;
        return vv_gcur_values(&c, !a->text, a->big_endian, a->type, n, out, "data follows");
    }
    if (!binary_start)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: array %d refers to data but the file has no "
                            "\"end\" line",
                            c.path, a->id);
    if (a->offset > (size_t)(c.end - binary_start))
        return vv_error_set(VV_ERR_FORMAT, "%s: array %d: data offset %zu is past the end", c.path,
                            a->id, a->offset);
    c.p = binary_start + a->offset;
    return vv_gcur_values(&c, !a->text, a->big_endian, a->type, n, out, "array data");
}

/* Whether the bytes where @p a's values are said to be can hold them: a
 * binary value takes its size, a text one at least a byte. Checked before
 * anything is allocated for them; where the data is missing altogether
 * dx_values says why. */
static vv_status
dx_check_fits(const dx_doc *d, const dx_array *a) {
    size_t left;
    if (a->follows)
        left = (size_t)(d->c.end - a->inline_data);
    else if (d->binary_start && a->offset <= (size_t)(d->c.end - d->binary_start))
        left = (size_t)(d->c.end - d->binary_start) - a->offset;
    else
        return VV_OK;
    const size_t n = a->items * (size_t)(a->shape > 0 ? a->shape : 1);
    const size_t each = a->text ? 1 : vv_gtype_size(a->type);
    if (n > left / each)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: array %d: %zu values cannot fit in the %zu bytes left of the file",
                            d->path, a->id, n, left);
    return VV_OK;
}

/* "data follows": the values start on the next line; skipped here. */
static vv_status
dx_data_follows(dx_doc *d, dx_array *a) {
    vv_gcur *c = &d->c;
    char tok[128];
    a->follows = 1;
    vv_gcur_skip_line(c);
    a->inline_data = c->p;
    const size_t n = a->items * (size_t)a->shape;
    if (a->text) {
        /* a count past the values ends at the end of the file (dx_values
           says how many are missing): skipping 1.8 billion absent tokens
           took seconds */
        for (size_t i = 0; i < n; i++)
            if (!vv_gcur_token(c, tok, sizeof tok))
                break;
        return VV_OK;
    }
    const size_t nb = n * vv_gtype_size(a->type);
    if (nb > vv_gcur_left(c))
        return vv_error_set(VV_ERR_FORMAT, "%s: array %d truncated", d->path, a->id);
    c->p += nb;
    return VV_OK;
}

/* The rest of an array's line: type, rank, shape, items, byte order,
 * encoding and where the data is. */
static vv_status
dx_array_line(dx_doc *d, dx_array *a) {
    vv_gcur *c = &d->c;
    char tok[128];
    vv_status s;
    const int id = a->id;
    while (c->p < c->end && *c->p != '\n') {
        if (!vv_gcur_token(c, tok, sizeof tok))
            break;
        if (!strcmp(tok, "type")) {
            vv_gcur_token(c, tok, sizeof tok);
            if (!vv_gtype_parse(tok, &a->type))
                return vv_error_set(VV_ERR_FORMAT, "%s: array %d: type %s", d->path, id, tok);
        } else if (!strcmp(tok, "rank")) {
            vv_gcur_token(c, tok, sizeof tok);
            if (!dx_int(tok, &a->rank))
                return vv_error_set(VV_ERR_FORMAT, "%s: array %d: rank %s", d->path, id, tok);
        } else if (!strcmp(tok, "shape")) {
            vv_gcur_token(c, tok, sizeof tok);
            if (!dx_int(tok, &a->shape) || a->shape < 1 || a->shape > 9)
                return vv_error_set(VV_ERR_FORMAT, "%s: array %d: shape %s", d->path, id, tok);
        } else if (!strcmp(tok, "items")) {
            if ((s = vv_gcur_need_size(c, "items", VV_GRID_MAX_POINTS, &a->items)) != VV_OK)
                return s;
        } else if (!strcmp(tok, "msb") || !strcmp(tok, "lsb")) {
            a->big_endian = !strcmp(tok, "msb");
        } else if (!strcmp(tok, "ieee") || !strcmp(tok, "binary")) {
            a->text = 0;
        } else if (!strcmp(tok, "ascii") || !strcmp(tok, "text")) {
            a->text = 1;
        } else if (!strcmp(tok, "data")) {
            vv_gcur_token(c, tok, sizeof tok);
            if (!strcmp(tok, "follows"))
                return dx_data_follows(d, a);
            if (!strcmp(tok, "file"))
                return vv_error_set(VV_ERR_UNSUPPORTED, "%s: array %d: data in another file",
                                    d->path, id);
            char *end;
            const long long off = strtoll(tok, &end, 10);
            if (*end || off < 0)
                return vv_error_set(VV_ERR_FORMAT, "%s: array %d: data \"%s\"", d->path, id, tok);
            a->offset = (size_t)off;
        }
    }
    return VV_OK;
}

/* object NAME class KIND ...: an array (with its line) or a field. */
static vv_status
dx_object(dx_doc *d) {
    char name[64], cl[32], kind[32];
    int id;
    vv_status s;
    if (!dx_quoted_or_number(&d->c, name, sizeof name, &id))
        return vv_error_set(VV_ERR_FORMAT, "%s: object without a name", d->path);
    if ((s = vv_gcur_need(&d->c, cl, sizeof cl, "class")) != VV_OK ||
        (s = vv_gcur_need(&d->c, kind, sizeof kind, "class name")) != VV_OK)
        return s;
    d->cur = NULL;
    d->curf = NULL;
    if (!strcmp(kind, "array")) {
        if (d->n_arr >= DX_MAX_OBJ)
            return vv_error_set(VV_ERR_LIMIT, "%s: more than %d arrays", d->path, DX_MAX_OBJ);
        dx_array *a = d->cur = &d->arr[d->n_arr++];
        a->id = id;
        snprintf(a->name, sizeof a->name, "%s", name);
        a->type = VV_GT_F32;
        a->big_endian = 1;
        a->text = 1;
        a->shape = 1;
        return dx_array_line(d, a);
    }
    if (!strcmp(kind, "field")) {
        if (d->n_fields >= DX_MAX_OBJ)
            return vv_error_set(VV_ERR_LIMIT, "%s: more than %d fields", d->path, DX_MAX_OBJ);
        dx_field *f = d->curf = &d->fields[d->n_fields++];
        snprintf(f->name, sizeof f->name, "%s", id < 0 ? name : "field");
        f->data = f->positions = f->connections = -1;
    }
    return VV_OK;
}

/* component NAME value ID of the current field. */
static vv_status
dx_component(dx_doc *d) {
    char cn[64], val[64], tok[128];
    int id, dummy;
    dx_field *f = d->curf;
    dx_quoted_or_number(&d->c, cn, sizeof cn, &dummy);
    vv_gcur_token(&d->c, tok, sizeof tok); /* "value" */
    /* at the end of the file no value is read and id was left unset */
    if (!dx_quoted_or_number(&d->c, val, sizeof val, &id))
        return vv_error_set(VV_ERR_FORMAT, "%s: field %s: component %s: no value", d->path, f->name,
                            cn);
    if (id < 0)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "%s: field %s: component %s by name is not supported", d->path, f->name,
                            cn);
    if (!strcmp(cn, "data"))
        f->data = id;
    else if (!strcmp(cn, "positions"))
        f->positions = id;
    else if (!strcmp(cn, "connections"))
        f->connections = id;
    return VV_OK;
}

/* The header, up to the "end" line (or the end of the file). */
static vv_status
dx_header(dx_doc *d) {
    char tok[128];
    vv_status s = VV_OK;
    while (s == VV_OK && vv_gcur_token(&d->c, tok, sizeof tok)) {
        if (tok[0] == '#') {
            vv_gcur_skip_line(&d->c);
        } else if (!strcmp(tok, "end")) {
            vv_gcur_skip_line(&d->c);
            d->binary_start = d->c.p;
            break;
        } else if (!strcmp(tok, "object")) {
            s = dx_object(d);
        } else if (!strcmp(tok, "attribute")) {
            char an[64], av[64];
            int dummy;
            dx_quoted_or_number(&d->c, an, sizeof an, &dummy);
            vv_gcur_token(&d->c, tok, sizeof tok); /* "string" */
            dx_quoted_or_number(&d->c, av, sizeof av, &dummy);
            if (d->cur && !strcmp(an, "dep"))
                snprintf(d->cur->dep, sizeof d->cur->dep, "%s", av);
            else if (d->cur && !strcmp(an, "element type"))
                snprintf(d->cur->element, sizeof d->cur->element, "%s", av);
            else if (d->curf && !strcmp(an, "name"))
                snprintf(d->curf->name, sizeof d->curf->name, "%s", av);
        } else if (!strcmp(tok, "component") && d->curf) {
            s = dx_component(d);
        } else {
            vv_gcur_skip_line(&d->c); /* member, other keywords */
        }
    }
    return s;
}

/* The cell type and points per cell of a connections array's element type. */
static vv_status
dx_element(const dx_doc *d, const dx_array *con, int *ctype, int *per) {
    static const struct {
        const char *name;
        int type, per;
    } elements[] = {{"tetrahedra", VV_CELL_TETRA, 4},
                    {"cubes", VV_CELL_HEXAHEDRON, 8},
                    {"triangles", VV_CELL_TRIANGLE, 3},
                    {"quads", VV_CELL_QUAD, 4}};
    for (size_t i = 0; i < sizeof elements / sizeof elements[0]; i++) {
        if (strcmp(con->element, elements[i].name))
            continue;
        *ctype = elements[i].type;
        *per = elements[i].per;
        if (con->shape != *per)
            return vv_error_set(VV_ERR_FORMAT, "%s: %s connections of shape %d", d->path,
                                con->element, con->shape);
        return VV_OK;
    }
    return vv_error_set(VV_ERR_UNSUPPORTED, "%s: connections of element type \"%s\"", d->path,
                        con->element);
}

/* The connections of @p con (@p per points each, DX order) as the grid's cells. */
static vv_status
dx_cells(const dx_doc *d, const dx_array *con, int ctype, int per, vv_grid *g) {
    const size_t nc = con->items, np = g->n_points, nconn = nc * (size_t)per;
    double *tmp = malloc((nconn ? nconn : 1) * sizeof *tmp);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", d->path);
    vv_status s = dx_values(&d->c, d->binary_start, con, tmp);
    /* DX cubes order their corners as bits (z fastest); VTK's hexahedron differs */
    static const int cube_to_vtk[8] = {0, 4, 6, 2, 1, 5, 7, 3};
    for (size_t i = 0; s == VV_OK && i < nc; i++) {
        for (int k = 0; k < per; k++) {
            const double v =
                tmp[i * (size_t)per + (size_t)(ctype == VV_CELL_HEXAHEDRON ? cube_to_vtk[k] : k)];
            if (!(v >= 0) || v >= (double)np) {
                s = vv_error_set(VV_ERR_FORMAT,
                                 "%s: connection %zu uses position %g but there are %zu", d->path,
                                 i, v, np);
                break;
            }
            g->connectivity[i * (size_t)per + (size_t)k] = (uint32_t)v;
        }
        g->cell_types[i] = (uint8_t)ctype;
        g->cell_offsets[i + 1] = (i + 1) * (size_t)per;
    }
    free(tmp);
    return s;
}

/* The grid of the first field with positions and connections. */
static vv_status
dx_grid(const dx_doc *d, vv_grid **out) {
    *out = NULL;
    if (d->n_fields == 0)
        return vv_error_set(VV_ERR_FORMAT, "%s: no field object", d->path);
    const dx_field *gf = NULL;
    for (int i = 0; i < d->n_fields && !gf; i++)
        if (d->fields[i].positions >= 0 && d->fields[i].connections >= 0)
            gf = &d->fields[i];
    if (!gf)
        return vv_error_set(VV_ERR_FORMAT, "%s: no field has positions and connections", d->path);
    const dx_array *pos = dx_find(d->arr, d->n_arr, gf->positions);
    const dx_array *con = dx_find(d->arr, d->n_arr, gf->connections);
    if (!pos || !con)
        return vv_error_set(VV_ERR_FORMAT, "%s: field %s refers to a missing array", d->path,
                            gf->name);
    if (pos->shape != 3)
        return vv_error_set(VV_ERR_UNSUPPORTED, "%s: positions of shape %d (3 supported)", d->path,
                            pos->shape);
    int ctype = 0, per = 0;
    vv_status s = dx_element(d, con, &ctype, &per);
    if (s == VV_OK && (s = dx_check_fits(d, pos)) == VV_OK)
        s = dx_check_fits(d, con);
    if (s != VV_OK)
        return s;
    vv_grid *g = NULL;
    if ((s = vv_grid_new(&g, VV_GRID_UNSTRUCTURED)) != VV_OK ||
        (s = vv_grid_alloc(g, pos->items, con->items, con->items * (size_t)per)) != VV_OK ||
        (s = dx_values(&d->c, d->binary_start, pos, g->points)) != VV_OK ||
        (s = dx_cells(d, con, ctype, per, g)) != VV_OK) {
        vv_grid_free(g);
        return s;
    }
    *out = g;
    return VV_OK;
}

/* The data of every field that lies on the grid's positions or connections. */
static vv_status
dx_fields(const dx_doc *d, vv_grid *g) {
    for (int i = 0; i < d->n_fields; i++) {
        const dx_array *a =
            d->fields[i].data >= 0 ? dx_find(d->arr, d->n_arr, d->fields[i].data) : NULL;
        if (!a)
            continue;
        const int cell = !strcmp(a->dep, "connections");
        if (a->items != (cell ? g->n_cells : g->n_points))
            continue; /* a field on other positions */
        vv_status s = dx_check_fits(d, a);
        if (s != VV_OK)
            return s;
        vv_grid_field *f = NULL;
        s = vv_grid_add_field(g, d->fields[i].name, cell, a->shape, &f);
        if (s != VV_OK)
            return s;
        const size_t nv = a->items * (size_t)a->shape;
        double *tmp = malloc((nv ? nv : 1) * sizeof *tmp);
        if (!tmp)
            return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", d->path);
        s = dx_values(&d->c, d->binary_start, a, tmp);
        for (size_t k = 0; s == VV_OK && k < nv; k++)
            f->values[k] = (float)tmp[k];
        free(tmp);
        if (s != VV_OK)
            return s;
    }
    return VV_OK;
}

vv_status
vv_grid_read_dx(vv_grid **out, const char *path) {
    *out = NULL;
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, VV_GRID_FILE_MAX, &data, &size);
    if (s != VV_OK)
        return s; /* the message names the file */
    dx_doc *d = calloc(1, sizeof *d);
    dx_array *arr = calloc(DX_MAX_OBJ, sizeof *arr);
    if (!d || !arr) {
        free(d);
        free(arr);
        free(data);
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
    }
    d->path = path;
    d->arr = arr;
    vv_gcur_init(&d->c, data, (size_t)size, path);
    vv_grid *g = NULL;
    if ((s = dx_header(d)) == VV_OK && (s = dx_grid(d, &g)) == VV_OK)
        s = dx_fields(d, g);
    free(arr);
    free(d);
    free(data);
    if (s != VV_OK) {
        vv_grid_free(g);
        return s;
    }
    return vv_grid_finish(g, path, out);
}

/* ---- the format record ------------------------------------------------------ */

/* An array object in the head of a .dx file, or of a file that starts with
 * an object. */
static int
dx_looks_like(const vv_format_probe *p, int deep) {
    return !deep && (vv_format_path_has_ext(p->path, "dx") || !strncmp(p->text, "object ", 7)) &&
           strstr(p->text, "class array") != NULL;
}

static const char *const dx_extensions[] = {"dx", NULL};

const vv_format_record vv_format_dx = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "dx",
    .title = "OpenDX",
    .extensions = dx_extensions,
    .doc = "OpenDX native: positions, tetrahedra/cubes/triangles/quads, data; text or binary",
    .holds = VV_DATA_GRID,
    .looks_like = dx_looks_like,
    .read_grid = vv_grid_read_dx,
};
