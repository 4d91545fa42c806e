/*
 * NRRD volumes through Teem's nrrd library.
 *
 * Teem keeps its error state (biff) in globals, so every call into Teem is
 * made under one process-wide mutex, and biff's message is copied into our
 * thread-local trace before the mutex is released.
 *
 * Reading is done in two passes: the header alone (nio->skipData) to check
 * the sizes with vv_volume_check_size() before Teem allocates anything, then
 * the whole file. Teem handles attached and detached headers, "data file"
 * lists and patterns, raw/ascii/hex/gzip/bzip2 encodings, byte and line
 * skips and both endians (data arrive in host byte order).
 *
 * Orientation: when the header has a 3-D space ("space:" or "space
 * dimension: 3"), spacing = length of each axis's space direction, the
 * direction matrix columns are the normalised space directions and origin is
 * "space origin", all kept as given in the file's space (an LPS file stays in
 * LPS; nothing is flipped to RAS). Without a space, spacing comes from
 * "spacings" (1 when absent; a negative spacing flips the axis direction)
 * and origin from "axis mins" (0 when absent).
 *
 * Writing always produces a single file with an attached header, encoding
 * gzip or raw, host byte order, "space: right-anterior-superior" or
 * "left-posterior-superior" when the volume's space is known, else "space
 * dimension: 3", with "space directions"
 * (direction column times spacing) and "space origin", kinds "space", node
 * centring, and "space units" when the unit is known.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <teem/nrrd.h>

#include "core/bricks_internal.h"
#include "core/internal.h"
#include "volvis/io.h"

static pthread_mutex_t teem_lock = PTHREAD_MUTEX_INITIALIZER;

/* Copies biff's NRRD message (one line, trimmed) into the trace. Call under teem_lock. */
static vv_status
teem_error(vv_status s, const char *what) {
    char *msg = biffGetDone(NRRD);
    const char *why = "";
    if (msg) {
        /* biff stacks "[nrrd] function: why" lines, outermost first; the
         * last one says what was wrong */
        size_t n = strlen(msg);
        while (n > 0 && (msg[n - 1] == '\n' || msg[n - 1] == ' ' || msg[n - 1] == '\r'))
            msg[--n] = '\0';
        char *line = strrchr(msg, '\n');
        line = line ? line + 1 : msg;
        if (!strncmp(line, "[nrrd] ", 7))
            line += 7;
        char *colon = strstr(line, ": ");
        if (colon && colon[2] && !memchr(line, ' ', (size_t)(colon - line)))
            line = colon + 2;
        why = line;
        /* a detached data file that is missing or unreadable is an I/O error */
        if (s == VV_ERR_FORMAT && strstr(why, "couldn't open"))
            s = VV_ERR_IO;
    }
    s = vv_error_set(s, "%s%s%s", what, why[0] ? ": " : "", why);
    free(msg);
    return s;
}

static int
nrrd_type_map(int ntype, vv_voxel_type *out) {
    switch (ntype) {
    case nrrdTypeChar:
        *out = VV_I8;
        return 1;
    case nrrdTypeUChar:
        *out = VV_U8;
        return 1;
    case nrrdTypeShort:
        *out = VV_I16;
        return 1;
    case nrrdTypeUShort:
        *out = VV_U16;
        return 1;
    case nrrdTypeInt:
        *out = VV_I32;
        return 1;
    case nrrdTypeUInt:
        *out = VV_U32;
        return 1;
    case nrrdTypeFloat:
        *out = VV_F32;
        return 1;
    case nrrdTypeDouble:
        *out = VV_F64;
        return 1;
    case nrrdTypeLLong:
    case nrrdTypeULLong:
        *out = VV_F64; /* converted, if every value is exact in a double */
        return 1;
    default:
        return 0;
    }
}

static int
vv_type_to_nrrd(vv_voxel_type t) {
    switch (t) {
    case VV_U8:
        return nrrdTypeUChar;
    case VV_I8:
        return nrrdTypeChar;
    case VV_U16:
        return nrrdTypeUShort;
    case VV_I16:
        return nrrdTypeShort;
    case VV_U32:
        return nrrdTypeUInt;
    case VV_I32:
        return nrrdTypeInt;
    case VV_F32:
        return nrrdTypeFloat;
    case VV_F64:
        return nrrdTypeDouble;
    }
    return nrrdTypeUnknown;
}

/*
 * The three spatial axes of the nrrd: dimension 1..3 (missing axes have size
 * 1), or 4 when the first (or last) axis has size 1, as in a one-component
 * vector volume.
 */
static vv_status
pick_axes(const Nrrd *n, unsigned int ax[3], int *nax) {
    unsigned int first = 0;
    if (n->dim < 1)
        return vv_error_set(VV_ERR_FORMAT, "dimension %u", n->dim);
    if (n->dim == 4) {
        if (n->axis[0].size == 1)
            first = 1;
        else if (n->axis[3].size != 1)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "4-D data with sizes %zu %zu %zu %zu (only a first or last axis "
                                "of size 1 is accepted)",
                                n->axis[0].size, n->axis[1].size, n->axis[2].size, n->axis[3].size);
    } else if (n->dim > 4) {
        return vv_error_set(VV_ERR_UNSUPPORTED, "%u-D data (3-D volumes only)", n->dim);
    }
    *nax = 0;
    for (unsigned int a = first; a < n->dim && *nax < 3; a++)
        ax[(*nax)++] = a;
    return VV_OK;
}

static vv_status
header_dims(const Nrrd *n, int dims[3], vv_voxel_type *type) {
    unsigned int ax[3];
    int nax = 0;
    vv_status s = pick_axes(n, ax, &nax);
    if (s != VV_OK)
        return s;
    if (!nrrd_type_map(n->type, type))
        return vv_error_set(VV_ERR_UNSUPPORTED, "voxel type \"%s\" is not supported",
                            airEnumStr(nrrdType, n->type));
    for (int i = 0; i < 3; i++) {
        size_t sz = i < nax ? n->axis[ax[i]].size : 1;
        if (sz > (size_t)INT_MAX)
            return vv_error_set(VV_ERR_LIMIT, "axis %d has %zu samples (limit %d)", i, sz,
                                VV_VOLUME_MAX_DIM);
        dims[i] = (int)sz;
    }
    return vv_volume_check_size(dims, *type, NULL);
}

static void
cross(const double a[3], const double b[3], double c[3]) {
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Fills spacing, origin, direction and unit of @p v from the nrrd's axes. */
static vv_status
set_geometry(vv_volume *v, const Nrrd *n) {
    unsigned int ax[3];
    int nax = 0;
    vv_status s = pick_axes(n, ax, &nax);
    if (s != VV_OK)
        return s;
    double col[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    int have[3] = {0, 0, 0};
    double spacing[3] = {1, 1, 1};
    double origin[3] = {0, 0, 0};

    if (n->space == nrrdSpaceRightAnteriorSuperior || n->space == nrrdSpace3DRightHanded)
        v->space = n->space == nrrdSpaceRightAnteriorSuperior ? VV_SPACE_RAS : VV_SPACE_UNKNOWN;
    else if (n->space == nrrdSpaceLeftPosteriorSuperior)
        v->space = VV_SPACE_LPS;
    if (n->spaceDim == 3) {
        for (int i = 0; i < nax; i++) {
            const double *d = n->axis[ax[i]].spaceDirection;
            if (!isfinite(d[0]) || !isfinite(d[1]) || !isfinite(d[2]))
                continue; /* a "none" axis: filled in below */
            double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(len > 0) || !isfinite(len))
                return vv_error_set(VV_ERR_FORMAT, "axis %u: space direction has zero length",
                                    ax[i]);
            spacing[i] = len;
            for (int r = 0; r < 3; r++)
                col[i][r] = d[r] / len;
            have[i] = 1;
        }
        /* an axis without a direction (e.g. a missing third axis of a 2-D
         * image): perpendicular to the other two when they exist */
        for (int i = 0; i < 3; i++) {
            if (have[i])
                continue;
            int a = (i + 1) % 3, b = (i + 2) % 3;
            if (have[a] && have[b]) {
                double c[3];
                cross(col[a], col[b], c);
                double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                if (len > 0)
                    for (int r = 0; r < 3; r++)
                        col[i][r] = c[r] / len;
            }
            if (i < nax && isfinite(n->axis[ax[i]].spacing) && n->axis[ax[i]].spacing != 0)
                spacing[i] = fabs(n->axis[ax[i]].spacing);
        }
        for (int r = 0; r < 3; r++)
            if (isfinite(n->spaceOrigin[r]))
                origin[r] = n->spaceOrigin[r];
        vv_unit u = vv_unit_parse(n->spaceUnits[0]);
        if (u != VV_UNIT_UNKNOWN)
            v->unit = u;
    } else {
        /* no 3-D space (none, or a 2-D/4-D one): per-axis spacings and mins */
        for (int i = 0; i < nax; i++) {
            const NrrdAxisInfo *a = &n->axis[ax[i]];
            if (isfinite(a->spacing) && a->spacing != 0) {
                spacing[i] = fabs(a->spacing);
                if (a->spacing < 0)
                    col[i][i] = -1;
            }
            if (isfinite(a->min))
                origin[i] = a->min;
            else if (isfinite(a->max) && a->size > 1 && isfinite(a->spacing) && a->spacing != 0)
                origin[i] = a->max - a->spacing * (double)(a->size - 1);
        }
    }
    for (int i = 0; i < 3; i++) {
        v->spacing[i] = spacing[i];
        v->origin[i] = origin[i];
        for (int r = 0; r < 3; r++)
            v->direction[r * 3 + i] = col[i][r];
    }
    return VV_OK;
}

/* Copies (and for 64-bit integers converts) the nrrd's data into @p v. */
static vv_status
copy_data(vv_volume *v, const Nrrd *n) {
    uint64_t count = vv_volume_voxel_count(v);
    if (nrrdElementNumber(n) != count)
        return vv_error_set(VV_ERR_FORMAT, "data holds %zu samples, expected %llu",
                            nrrdElementNumber(n), (unsigned long long)count);
    if (n->type == nrrdTypeLLong || n->type == nrrdTypeULLong) {
        const long long lim = 9007199254740992LL; /* 2^53: every integer up to it is exact */
        double *dst = v->data;
        for (uint64_t i = 0; i < count; i++) {
            double d;
            int exact;
            if (n->type == nrrdTypeLLong) {
                long long x = ((const long long *)n->data)[i];
                exact = x >= -lim && x <= lim;
                d = (double)x;
            } else {
                unsigned long long x = ((const unsigned long long *)n->data)[i];
                exact = x <= (unsigned long long)lim;
                d = (double)x;
            }
            if (!exact)
                return vv_error_set(
                    VV_ERR_UNSUPPORTED,
                    "64-bit integer sample %llu (%.17g) cannot be held exactly in a "
                    "double",
                    (unsigned long long)i, d);
            dst[i] = d;
        }
        return VV_OK;
    }
    memcpy(v->data, n->data, (size_t)(count * vv_voxel_type_size(v->type)));
    return VV_OK;
}

static vv_status
check_magic(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f)
        return vv_error_set(VV_ERR_IO, "cannot open: %s", strerror(errno));
    char buf[8] = {0};
    size_t got = fread(buf, 1, 7, f);
    fclose(f);
    if (got == 0)
        return vv_error_set(VV_ERR_FORMAT, "empty file");
    if (got < 7 || memcmp(buf, "NRRD000", 7) != 0)
        return vv_error_set(VV_ERR_FORMAT, "not a NRRD file (no \"NRRD000x\" magic)");
    return VV_OK;
}

/* The body of vv_nrrd_read, under teem_lock. */
static vv_status
read_locked(vv_volume **out, const char *path) {
    vv_status s = VV_OK;
    vv_volume *v = NULL;
    int dims[3];
    vv_voxel_type type;

    /* pass 1: header only; detached data files are checked for existence */
    Nrrd *n = nrrdNew();
    NrrdIoState *nio = nrrdIoStateNew();
    if (!n || !nio) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    nio->skipData = AIR_TRUE;
    if (nrrdLoad(n, path, nio)) {
        s = teem_error(VV_ERR_FORMAT, "cannot read header");
        goto done;
    }
    s = header_dims(n, dims, &type);
    if (s != VV_OK)
        goto done;
    nrrdNuke(n);
    nrrdIoStateNix(nio);

    /* pass 2: the data */
    n = nrrdNew();
    nio = nrrdIoStateNew();
    if (!n || !nio) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (nrrdLoad(n, path, nio)) {
        s = teem_error(VV_ERR_FORMAT, "cannot read data");
        goto done;
    }
    /* the file may have changed between the passes: check again */
    int dims2[3];
    vv_voxel_type type2;
    s = header_dims(n, dims2, &type2);
    if (s != VV_OK)
        goto done;
    if (dims2[0] != dims[0] || dims2[1] != dims[1] || dims2[2] != dims[2] || type2 != type) {
        s = vv_error_set(VV_ERR_FORMAT, "file changed while being read");
        goto done;
    }
    if (!n->data) {
        s = vv_error_set(VV_ERR_FORMAT, "no data");
        goto done;
    }
    s = vv_volume_new(&v, dims, type);
    if (s != VV_OK)
        goto done;
    s = set_geometry(v, n);
    if (s != VV_OK)
        goto done;
    s = copy_data(v, n);
    if (s != VV_OK)
        goto done;
    v->modification = VV_MOD_ORIGINAL;
    vv_volume_update_range(v);
    *out = v;
    v = NULL;
done:
    vv_volume_free(v);
    if (n)
        nrrdNuke(n);
    if (nio)
        nrrdIoStateNix(nio);
    return s;
}

vv_status
vv_nrrd_read(vv_volume **out, const char *path) {
    if (!out || !path) {
        return vv_error_set(VV_ERR_INVALID, "nrrd: NULL argument");
    }
    *out = NULL;
    vv_status s = check_magic(path);
    if (s == VV_OK) {
        pthread_mutex_lock(&teem_lock);
        s = read_locked(out, path);
        pthread_mutex_unlock(&teem_lock);
    }
    if (s != VV_OK)
        return vv_error_prefix(s, "nrrd: %s", vv_path_basename(path));
    return VV_OK;
}

/* The body of vv_nrrd_write, under teem_lock, writing into af->fp. */
static vv_status
write_locked(const vv_volume *v, FILE *fp, int gzip) {
    vv_status s = VV_OK;
    Nrrd *n = nrrdNew();
    NrrdIoState *nio = nrrdIoStateNew();
    if (!n || !nio) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    /* Teem only reads the data while writing; the cast drops const for its API */
    if (nrrdWrap_va(n, v->data, vv_type_to_nrrd(v->type), 3, (size_t)v->dims[0], (size_t)v->dims[1],
                    (size_t)v->dims[2])) {
        s = teem_error(VV_ERR_INVALID, "cannot describe the volume");
        goto done;
    }
    /* the anatomical frame when known (so LPS data stay LPS), else a plain
     * 3-D space */
    if (v->space == VV_SPACE_RAS || v->space == VV_SPACE_LPS
            ? nrrdSpaceSet(n, v->space == VV_SPACE_RAS ? nrrdSpaceRightAnteriorSuperior
                                                       : nrrdSpaceLeftPosteriorSuperior)
            : nrrdSpaceDimensionSet(n, 3)) {
        s = teem_error(VV_ERR_INVALID, "cannot set the space");
        goto done;
    }
    double dir[3][NRRD_SPACE_DIM_MAX];
    for (int i = 0; i < 3; i++) {
        for (int r = 0; r < NRRD_SPACE_DIM_MAX; r++)
            dir[i][r] = r < 3 ? v->direction[r * 3 + i] * v->spacing[i] : AIR_NAN;
    }
    nrrdAxisInfoSet_va(n, nrrdAxisInfoSpaceDirection, dir[0], dir[1], dir[2]);
    nrrdAxisInfoSet_va(n, nrrdAxisInfoKind, nrrdKindSpace, nrrdKindSpace, nrrdKindSpace);
    nrrdAxisInfoSet_va(n, nrrdAxisInfoCenter, nrrdCenterNode, nrrdCenterNode, nrrdCenterNode);
    if (nrrdSpaceOriginSet(n, v->origin)) {
        s = teem_error(VV_ERR_INVALID, "cannot set the space origin");
        goto done;
    }
    const char *un = v->unit == VV_UNIT_UNKNOWN ? NULL : vv_unit_name(v->unit);
    if (un) {
        for (int i = 0; i < 3; i++) {
            n->spaceUnits[i] = airStrdup(un);
            if (!n->spaceUnits[i]) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                goto done;
            }
        }
    }
    nio->encoding = gzip ? nrrdEncodingGzip : nrrdEncodingRaw;
    if (gzip && !nrrdEncodingGzip->available()) {
        s = vv_error_set(VV_ERR_UNSUPPORTED, "this Teem has no gzip encoding");
        goto done;
    }
    nio->endian = airMyEndian();
    nio->zlibLevel = 6;
    if (nrrdWrite(fp, n, nio)) {
        s = teem_error(VV_ERR_IO, "cannot write");
        goto done;
    }
done:
    if (n)
        nrrdNix(n); /* the data belongs to v */
    if (nio)
        nrrdIoStateNix(nio);
    return s;
}

static vv_status
check_volume(const vv_volume *v) {
    if (!v->data)
        return vv_error_set(VV_ERR_INVALID, "volume has no data");
    if (vv_type_to_nrrd(v->type) == nrrdTypeUnknown)
        return vv_error_set(VV_ERR_INVALID, "voxel type %d", (int)v->type);
    vv_status s = vv_volume_check_size(v->dims, v->type, NULL);
    if (s != VV_OK)
        return s;
    for (int i = 0; i < 3; i++)
        if (!(v->spacing[i] > 0) || !isfinite(v->spacing[i]) || !isfinite(v->origin[i]))
            return vv_error_set(VV_ERR_INVALID, "axis %d: spacing %g, origin %g", i, v->spacing[i],
                                v->origin[i]);
    for (int i = 0; i < 9; i++)
        if (!isfinite(v->direction[i]))
            return vv_error_set(VV_ERR_INVALID, "direction matrix is not finite");
    return VV_OK;
}

vv_status
vv_nrrd_write(const vv_volume *v, const char *path, int gzip) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "nrrd: NULL argument");
    vv_status s = check_volume(v);
    if (s != VV_OK)
        return vv_error_prefix(s, "nrrd: %s", vv_path_basename(path));
    vv_atomic_file af;
    s = vv_atomic_file_open(&af, path);
    if (s != VV_OK)
        return vv_error_prefix(s, "nrrd: %s", vv_path_basename(path));
    pthread_mutex_lock(&teem_lock);
    s = write_locked(v, af.fp, gzip);
    pthread_mutex_unlock(&teem_lock);
    if (s == VV_OK && ferror(af.fp))
        s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno));
    if (s != VV_OK) {
        vv_atomic_file_abort(&af);
        return vv_error_prefix(s, "nrrd: %s", vv_path_basename(path));
    }
    s = vv_atomic_file_commit(&af);
    if (s != VV_OK)
        return vv_error_prefix(s, "nrrd: %s", vv_path_basename(path));
    return VV_OK;
}

/* ---- raw layout for bricked reading (src/core/bricks.c) --------------- */

/* The byte offset just past the header's blank line ("\n\n" or "\r\n\r\n"). */
static vv_status
attached_offset(const char *path, uint64_t *off) {
    FILE *f = fopen(path, "rb");
    if (!f)
        return vv_error_set(VV_ERR_IO, "cannot open: %s", strerror(errno));
    int prev = 0, c;
    uint64_t pos = 0;
    vv_status s = vv_error_set(VV_ERR_FORMAT, "no blank line after the header");
    while ((c = fgetc(f)) != EOF && pos < ((uint64_t)1 << 24)) {
        pos++;
        if (c == '\r')
            continue;
        if (c == '\n' && prev == '\n') {
            *off = pos;
            s = VV_OK;
            break;
        }
        prev = c;
    }
    fclose(f);
    if (s == VV_OK)
        vv_error_clear();
    return s;
}

static vv_status
raw_layout_locked(const char *path, vv_volume **header, char **data_path, uint64_t *offset,
                  int *big_endian) {
    vv_status s = VV_OK;
    Nrrd *n = nrrdNew();
    NrrdIoState *nio = nrrdIoStateNew();
    vv_volume *v = NULL;
    if (!n || !nio) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    nio->skipData = AIR_TRUE;
    if (nrrdLoad(n, path, nio)) {
        s = teem_error(VV_ERR_FORMAT, "cannot read header");
        goto done;
    }
    int dims[3];
    vv_voxel_type type;
    if ((s = header_dims(n, dims, &type)) != VV_OK)
        goto done;
    if (n->type == nrrdTypeLLong || n->type == nrrdTypeULLong) {
        s = vv_error_set(VV_ERR_FORMAT, "64-bit integers need conversion: convert it to .vvb "
                                        "first (volvis convert IN OUT.vvb)");
        goto done;
    }
    if (nio->encoding != nrrdEncodingRaw) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "encoding %s is not raw: it cannot be read by bricks; convert it "
                         "to .vvb first (volvis convert IN OUT.vvb)",
                         nio->encoding ? nio->encoding->name : "?");
        goto done;
    }
    if (nio->lineSkip != 0 || nio->dataFSkip) {
        s = vv_error_set(VV_ERR_FORMAT, "line skips are not supported for bricked reading");
        goto done;
    }
    const unsigned int nfiles = nio->dataFNArr ? nio->dataFNArr->len : 0;
    if (nfiles > 1 || nio->dataFNFormat) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "%u data files: convert it to .vvb first (volvis convert IN OUT.vvb)",
                         nfiles);
        goto done;
    }
    char *dp = NULL;
    if (nfiles == 1 && strcmp(nio->dataFN[0], "-") != 0) {
        const char *fn = nio->dataFN[0];
        if (fn[0] == '/' || !nio->path || !nio->path[0]) {
            dp = strdup(fn);
        } else {
            dp = malloc(strlen(nio->path) + strlen(fn) + 2);
            if (dp)
                sprintf(dp, "%s/%s", nio->path, fn);
        }
    } else {
        dp = strdup(path);
    }
    if (!dp) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    const uint64_t bytes =
        (uint64_t)dims[0] * (uint64_t)dims[1] * (uint64_t)dims[2] * vv_voxel_type_size(type);
    uint64_t off = 0;
    if (nfiles == 1 && strcmp(nio->dataFN[0], "-") != 0) {
        if (nio->byteSkip >= 0) {
            off = (uint64_t)nio->byteSkip;
        } else {
            FILE *f = fopen(dp, "rb");
            long long size = -1;
            if (f && fseeko(f, 0, SEEK_END) == 0)
                size = (long long)ftello(f);
            if (f)
                fclose(f);
            if (size < 0 || (uint64_t)size < bytes) {
                free(dp);
                s = vv_error_set(VV_ERR_FORMAT, "data file shorter than the data");
                goto done;
            }
            off = (uint64_t)size - bytes;
        }
    } else {
        if ((s = attached_offset(path, &off)) != VV_OK) {
            free(dp);
            goto done;
        }
        off += nio->byteSkip > 0 ? (uint64_t)nio->byteSkip : 0;
    }
    const int one[3] = {1, 1, 1};
    if ((s = vv_volume_new(&v, one, type)) != VV_OK || (s = set_geometry(v, n)) != VV_OK) {
        free(dp);
        goto done;
    }
    memcpy(v->dims, dims, sizeof v->dims);
    *header = v;
    v = NULL;
    *data_path = dp;
    *offset = off;
    *big_endian = nio->endian == airEndianBig;
done:
    vv_volume_free(v);
    if (n)
        nrrdNuke(n);
    if (nio)
        nrrdIoStateNix(nio);
    return s;
}

vv_status
vv_nrrd_raw_layout(const char *path, vv_volume **header, char **data_path, uint64_t *offset,
                   int *big_endian) {
    *header = NULL;
    *data_path = NULL;
    vv_status s = check_magic(path);
    if (s == VV_OK) {
        pthread_mutex_lock(&teem_lock);
        s = raw_layout_locked(path, header, data_path, offset, big_endian);
        pthread_mutex_unlock(&teem_lock);
    }
    if (s != VV_OK)
        return vv_error_prefix(s, "nrrd: %s", vv_path_basename(path));
    return VV_OK;
}
