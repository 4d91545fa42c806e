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

/* ---- VTK XML files (grid_vtu.c; the .vti volume reader too) ------------- */

struct _xmlDoc;
struct _xmlNode;

/** A VTK XML file being read: its root's encoding and the appended data. */
typedef struct vv_vtkxml {
    const char *path;              /**< for messages */
    int big_endian;                /**< byte_order="BigEndian" */
    int header64;                  /**< header_type="UInt64" (else UInt32) */
    int zlib;                      /**< compressor="vtkZLibDataCompressor" */
    const unsigned char *appended; /**< the AppendedData bytes after the '_', or NULL */
    size_t appended_len;
    int appended_base64; /**< AppendedData encoding="base64" (else raw) */
} vv_vtkxml;

/**
 * Parses the VTK XML file @p data (@p size bytes, v->path set) whose root
 * VTKFile has type @p type: entity declarations refused before parsing (no
 * XML bomb), the appended data cut out, no network; *@p doc the document
 * (xmlFreeDoc it), *@p xml what was parsed (free() it when it is not
 * @p data), *@p dataset the root's @p type element. Errors: VV_ERR_FORMAT
 * (not well-formed, another type, no such element: one line),
 * VV_ERR_UNSUPPORTED (a compressor other than zlib), VV_ERR_NOMEM.
 */
vv_status vv_vtkxml_open(vv_vtkxml *v, unsigned char *data, uint64_t size, const char *type,
                         struct _xmlDoc **doc, unsigned char **xml, struct _xmlNode **dataset);
/**
 * The bytes of DataArray @p da, "binary" (base64 text) or "appended", zlib
 * compressed or not, checked to be exactly @p nbytes long before anything
 * that size is allocated; *@p out is malloc'ed. @p name names the array in
 * errors. Errors: VV_ERR_FORMAT (another format such as "ascii" included:
 * the caller reads those as text; truncated or inconsistent blocks),
 * VV_ERR_NOMEM.
 */
vv_status vv_vtkxml_array_bytes(const vv_vtkxml *v, struct _xmlNode *da, size_t nbytes,
                                const char *name, unsigned char **out);
/** The first child element of @p n named @p name, or NULL. */
struct _xmlNode *vv_vtkxml_child(struct _xmlNode *n, const char *name);

#endif
