/*
 * What the grid readers of src/io share (not installed; grid_text.c): a
 * cursor over a file held in memory, the value types of the VTK, VTK XML and
 * OpenDX formats, and the common end of a reader.
 */
#ifndef VOLVIS_GRID_IO_INTERNAL_H
#define VOLVIS_GRID_IO_INTERNAL_H

#include <stddef.h>

#include "volvis/grid.h"

/** Largest grid file read into memory (bytes). */
#define VV_GRID_FILE_MAX (4ull << 30)

/** A cursor over a file held in memory. */
typedef struct vv_gcur {
    const unsigned char *p, *end, *begin;
    const char *path; /**< for messages */
} vv_gcur;

void vv_gcur_init(vv_gcur *c, const unsigned char *data, size_t size, const char *path);
/** Bytes left after the cursor. */
size_t vv_gcur_left(const vv_gcur *c);
/** Next whitespace-separated token (non-printable bytes shown as '?'); 0 at the end. */
int vv_gcur_token(vv_gcur *c, char *buf, size_t cap);
/** Moves past the next newline. */
void vv_gcur_skip_line(vv_gcur *c);
/** A token that must be there. Errors: VV_ERR_FORMAT naming @p what. */
vv_status vv_gcur_need(vv_gcur *c, char *buf, size_t cap, const char *what);
/** A count in [0, max]. Errors: VV_ERR_FORMAT, VV_ERR_LIMIT. */
vv_status vv_gcur_need_size(vv_gcur *c, const char *what, size_t max, size_t *out);

/** Value types of the grid formats. */
typedef enum vv_gtype {
    VV_GT_I8,
    VV_GT_U8,
    VV_GT_I16,
    VV_GT_U16,
    VV_GT_I32,
    VV_GT_U32,
    VV_GT_I64,
    VV_GT_U64,
    VV_GT_F32,
    VV_GT_F64
} vv_gtype;

/** Parses VTK, VTK XML and OpenDX type names; 0 for an unknown name. */
int vv_gtype_parse(const char *s, vv_gtype *t);
size_t vv_gtype_size(vv_gtype t);
/** One value at @p p. */
double vv_gtype_get(const unsigned char *p, vv_gtype t, int big_endian);
/**
 * @p n values as text tokens or binary of type @p t (checked against the
 * bytes left first). Errors: VV_ERR_FORMAT naming @p what.
 */
vv_status vv_gcur_values(vv_gcur *c, int binary, int big_endian, vv_gtype t, size_t n, double *out,
                         const char *what);

/** Validates @p g and sets its field ranges; on failure frees it. */
vv_status vv_grid_finish(vv_grid *g, const char *path, vv_grid **out);

#endif
