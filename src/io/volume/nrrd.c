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
#include <strings.h>

#include <teem/nrrd.h>
#include <zlib.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/prescan.h"
#include "io/store/bricked_internal.h"
#include "io/write_check.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

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

/* 1: an axis of this kind holds the components of a sample (a colour, a
 * vector, a list): the channels of a volume. Time has its own axis; domain,
 * space, stub, scalar and unknown axes are spatial. */
static int
kind_is_channel(int kind) {
    return kind != nrrdKindUnknown && kind != nrrdKindDomain && kind != nrrdKindSpace &&
           kind != nrrdKindTime && kind != nrrdKindStub && kind != nrrdKindScalar &&
           kind > nrrdKindUnknown && kind < nrrdKindLast;
}

/*
 * The axes of the nrrd: the three spatial ones in @p ax (dimension 1..3;
 * missing axes have size 1), and the axis of kind time and the axis of a
 * channel kind (RGB-color, vector, list, ...) in @p t_axis and @p c_axis
 * (-1: none). Of four spatial-looking axes a first (or last) one of size 1
 * is dropped, as in a one-component vector volume.
 */
static vv_status
pick_axes(const Nrrd *n, unsigned int ax[3], int *nax, int *c_axis, int *t_axis) {
    *c_axis = *t_axis = -1;
    if (n->dim < 1 || n->dim > NRRD_DIM_MAX)
        return vv_error_set(VV_ERR_FORMAT, "dimension %u", n->dim);
    unsigned int rest[NRRD_DIM_MAX];
    unsigned int nrest = 0;
    for (unsigned int a = 0; a < n->dim; a++) {
        int k = n->axis[a].kind;
        int *slot = k == nrrdKindTime ? t_axis : kind_is_channel(k) ? c_axis : NULL;
        if (slot && *slot >= 0)
            return vv_error_set(VV_ERR_UNSUPPORTED, "axes %d and %u are both %s axes", *slot, a,
                                slot == t_axis ? "time" : "channel (non-spatial kind)");
        if (slot)
            *slot = (int)a;
        else
            rest[nrest++] = a;
    }
    unsigned int first = 0;
    if (nrest == 4) {
        if (n->axis[rest[0]].size == 1)
            first = 1;
        else if (n->axis[rest[3]].size != 1)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "4-D data with sizes %zu %zu %zu %zu (only a first or last axis "
                                "of size 1, or an axis of kind time or of a channel kind such as "
                                "RGB-color or vector, is accepted)",
                                n->axis[0].size, n->axis[1].size, n->axis[2].size, n->axis[3].size);
    } else if (nrest > 4) {
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "%u-D data with %u spatial axes (3 spatial axes, a time and a "
                            "channel axis at most)",
                            n->dim, nrest);
    }
    *nax = 0;
    for (unsigned int i = first; i < nrest && *nax < 3; i++)
        ax[(*nax)++] = rest[i];
    return VV_OK;
}

/* The spatial dims and voxel type; the channel and time axes' sizes in
 * @p nc and @p nt (1 when absent). @p whole: the volume is to be read
 * whole (the memory budget applies), else by boxes (the limits only). */
static vv_status
header_dims(const Nrrd *n, int dims[3], vv_voxel_type *type, int *nc, int *nt, int whole) {
    unsigned int ax[3];
    int nax = 0, c_axis, t_axis;
    vv_status s = pick_axes(n, ax, &nax, &c_axis, &t_axis);
    if (s != VV_OK)
        return s;
    size_t csz = c_axis >= 0 ? n->axis[c_axis].size : 1,
           tsz = t_axis >= 0 ? n->axis[t_axis].size : 1;
    if (csz > VV_VOLUME_MAX_DIM || tsz > VV_VOLUME_MAX_DIM)
        return vv_error_set(VV_ERR_LIMIT, "%zu %s (limit %d)", csz > VV_VOLUME_MAX_DIM ? csz : tsz,
                            csz > VV_VOLUME_MAX_DIM ? "channels" : "time steps", VV_VOLUME_MAX_DIM);
    *nc = (int)csz;
    *nt = (int)tsz;
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
    return whole ? vv_volume_check_size(dims, *type, NULL)
                 : vv_volume_check_limits(dims, *type, NULL);
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
    int nax = 0, c_axis, t_axis;
    vv_status s = pick_axes(n, ax, &nax, &c_axis, &t_axis);
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

/*
 * What the header text says about where the data are, found by scan_header
 * before Teem reads anything: the bytes available to the data (attached: the
 * file after the header; detached: the data files' sizes) for the check of
 * the promised size.
 */
typedef struct header_scan {
    uint64_t data_bytes; /* bytes available to the data */
    int n_files;         /* detached data files (0: attached) */
    char **files;        /* their paths (n_files, malloc'ed) */
    uint64_t data_start; /* attached: where the data start (after the blank line) */
} header_scan;

static void
header_scan_free(header_scan *hs) {
    for (int i = 0; i < hs->n_files; i++)
        free(hs->files[i]);
    free(hs->files);
    hs->files = NULL;
    hs->n_files = 0;
}

/* The header text is read whole; a longer one (a list of a million data
 * files) is refused before Teem parses it, which takes time quadratic in
 * the number of lines. */
#define NRRD_MAX_HEADER ((size_t)4 << 20)
/* The longest header line (a field) given to Teem: it formats a bad line
 * into a 1 KB message buffer after a prefix of its own, and a line of 960
 * bytes already overflowed it (found by fuzzing); 768 leaves room. */
#define NRRD_MAX_LINE 768
/* At most this many detached data files (one per slice of the largest volume). */
#define NRRD_MAX_FILES VV_VOLUME_MAX_DIM
/* The widest field a "data file" pattern may ask for (%064d). */
#define NRRD_MAX_WIDTH 64

/* Checks one detached data file name against the policy (vv_detached_path). */
static vv_status
scan_data_file(const char *header, const char *name, header_scan *hs) {
    if (hs->n_files >= NRRD_MAX_FILES)
        return vv_error_set(VV_ERR_LIMIT, "more than %d data files", NRRD_MAX_FILES);
    uint64_t size = 0;
    char *resolved = NULL;
    vv_status s = vv_detached_path(header, name, &resolved, &size);
    if (s != VV_OK)
        return s;
    if ((hs->n_files & (hs->n_files - 1)) == 0) { /* grow at powers of two */
        char **nf = realloc(hs->files, sizeof *nf * (size_t)(hs->n_files ? 2 * hs->n_files : 1));
        if (!nf) {
            free(resolved);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        hs->files = nf;
    }
    hs->files[hs->n_files++] = resolved;
    hs->data_bytes += size;
    return VV_OK;
}

/* A "data file" pattern "FORMAT MIN MAX STEP [SUBDIM]": FORMAT must hold one
 * integer conversion (%d, %03d, ...) and nothing else for printf. */
static vv_status
scan_pattern(const char *header, const char *value, header_scan *hs) {
    char fmt[512];
    long long lo, hi, step;
    int used = 0;
    if (sscanf(value, "%511s %lld %lld %lld %n", fmt, &lo, &hi, &step, &used) < 4)
        return vv_error_set(VV_ERR_FORMAT, "data file pattern '%s': expected FORMAT MIN MAX STEP",
                            value);
    int conv = 0;
    for (const char *c = fmt; *c; c++) {
        if (*c != '%')
            continue;
        if (c[1] == '%') {
            c++;
            continue;
        }
        c++;
        /* a field width of at most 64: snprintf padded a width of
           hundreds of millions for seconds (found by fuzz_nrrd) */
        long width = 0;
        while (*c >= '0' && *c <= '9')
            if ((width = width * 10 + (*c++ - '0')) > NRRD_MAX_WIDTH)
                return vv_error_set(VV_ERR_FORMAT, "data file pattern '%s': field width over %d",
                                    fmt, NRRD_MAX_WIDTH);
        if (*c != 'd' && *c != 'u')
            return vv_error_set(VV_ERR_FORMAT,
                                "data file pattern '%s': only integer conversions (%%d, %%03d) are "
                                "allowed",
                                fmt);
        conv++;
    }
    if (conv != 1)
        return vv_error_set(VV_ERR_FORMAT,
                            "data file pattern '%s': needs exactly one integer conversion", fmt);
    if (step == 0 || (step > 0 ? hi < lo : hi > lo) || lo < INT_MIN || lo > INT_MAX ||
        hi < INT_MIN || hi > INT_MAX || step < INT_MIN || step > INT_MAX)
        return vv_error_set(VV_ERR_FORMAT, "data file pattern: bad range %lld %lld %lld", lo, hi,
                            step);
    long long count = (hi - lo) / step + 1;
    if (count > NRRD_MAX_FILES)
        return vv_error_set(VV_ERR_LIMIT, "data file pattern names %lld files (at most %d)", count,
                            NRRD_MAX_FILES);
    for (long long i = 0; i < count; i++) {
        char name[600];
        snprintf(name, sizeof name, fmt, (int)(lo + i * step));
        vv_status s = scan_data_file(header, name, hs);
        if (s != VV_OK)
            return s;
    }
    return VV_OK;
}

/*
 * Reads the header text of @p path (which must be a regular file starting
 * with the NRRD magic) and applies the detached-data policy to every data
 * file it names (a single file, a LIST or a pattern), before Teem opens
 * any: see docs/formats.md, "Detached data files".
 */
static vv_status
scan_header(const char *path, header_scan *hs) {
    memset(hs, 0, sizeof *hs);
    FILE *f = NULL;
    uint64_t fsize = 0;
    vv_status s = vv_open_regular(path, &f, &fsize);
    if (s != VV_OK)
        return s;
    size_t cap = fsize < NRRD_MAX_HEADER ? (size_t)fsize : NRRD_MAX_HEADER;
    char *text = malloc(cap + 1);
    if (!text) {
        fclose(f);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    size_t got = fread(text, 1, cap, f);
    fclose(f);
    text[got] = '\0';
    if (got == 0) {
        free(text);
        return vv_error_set(VV_ERR_FORMAT, "empty file");
    }
    if (got < 7 || memcmp(text, "NRRD000", 7) != 0) {
        free(text);
        return vv_error_set(VV_ERR_FORMAT, "not a NRRD file (no \"NRRD000x\" magic)");
    }
    /* the whole magic line, as Teem accepts it (it leaks a line buffer on
     * any other first line) */
    if (got < 9 || text[7] < '1' || text[7] > '5' ||
        !(text[8] == '\n' || (text[8] == '\r' && got > 9 && text[9] == '\n'))) {
        free(text);
        return vv_error_set(VV_ERR_FORMAT,
                            "the first line is not a NRRD magic (NRRD0001 to NRRD0005)");
    }
    int in_list = 0, ended = 0;
    /* the fields Teem requires; it leaks the data file names it has read
     * when one is missing */
    static const char *const required[4] = {"type:", "dimension:", "sizes:", "encoding:"};
    int seen[4] = {0, 0, 0, 0};
    size_t pos = 0;
    while (s == VV_OK && pos < got) {
        char *line = text + pos;
        char *nl = memchr(line, '\n', got - pos);
        if (!nl && got == cap && fsize > cap) {
            s = vv_error_set(VV_ERR_LIMIT, "header longer than %zu bytes", NRRD_MAX_HEADER);
            break;
        }
        size_t len = nl ? (size_t)(nl - line) : got - pos;
        pos += len + (nl ? 1 : 0);
        if (len > 0 && line[len - 1] == '\r')
            len--;
        if (memchr(line, '\0', len)) {
            if (in_list)
                s = vv_error_set(VV_ERR_FORMAT, "a data file name holds a NUL byte");
            else
                ended = 1; /* binary data right after a header without a blank line */
            break;
        }
        line[len] = '\0';
        if (in_list) {
            /* Teem formats a bad name into its error message past the end
             * of its line buffer when the name holds a control character
             * (found by fuzzing) */
            for (size_t k = 0; k < len && s == VV_OK; k++)
                if ((unsigned char)line[k] < 0x20 && line[k] != '\t')
                    s = vv_error_set(VV_ERR_FORMAT,
                                     "a data file name holds the control character 0x%02x",
                                     (unsigned)(unsigned char)line[k]);
            if (s != VV_OK)
                break;
            if (len > 0)
                s = scan_data_file(path, line, hs);
            continue;
        }
        if (len == 0) {
            ended = 1; /* the blank line: attached data follow */
            break;
        }
        /* Teem formats its message about a bad line into a fixed buffer
         * (1 KB) and aborts on a longer one: refuse long lines first
         * (comments, key/value pairs and "content" are copied safely) */
        if (len > NRRD_MAX_LINE && line[0] != '#' && strncmp(line, "content:", 8) != 0) {
            const char *kv = strstr(line, ":="), *fd = strstr(line, ": ");
            if (!kv || (fd && fd < kv)) {
                s = vv_error_set(VV_ERR_FORMAT, "a header line of %zu bytes (at most %d)", len,
                                 NRRD_MAX_LINE);
                break;
            }
        }
        /* Teem reads field names whatever their case ("Data File:") */
        for (int r = 0; r < 4; r++)
            if (!strncasecmp(line, required[r], strlen(required[r])))
                seen[r] = 1;
        const char *v = NULL;
        if (!strncasecmp(line, "data file:", 10))
            v = line + 10;
        else if (!strncasecmp(line, "datafile:", 9))
            v = line + 9;
        if (!v || *v == '=')
            continue; /* another field, or a "data file:=" key/value pair */
        while (*v == ' ' || *v == '\t')
            v++;
        for (char *e = line + len; e > v && (e[-1] == ' ' || e[-1] == '\t');)
            *--e = '\0';
        if (!strncmp(v, "LIST", 4) && (v[4] == '\0' || v[4] == ' ' || v[4] == '\t')) {
            /* the rest of the file names the data files: count them before
             * checking any (a million names cost a million checks) */
            long names = 0;
            for (size_t i = pos; i < got; i++)
                if (text[i] == '\n' && i > pos && text[i - 1] != '\n')
                    names++;
            if (got > pos && text[got - 1] != '\n')
                names++;
            if (names > NRRD_MAX_FILES || fsize > got) {
                s = vv_error_set(VV_ERR_LIMIT, "the data file LIST names %s%ld files (at most %d)",
                                 fsize > got ? "more than " : "", names, NRRD_MAX_FILES);
                break;
            }
            in_list = 1;
        } else if (strchr(v, '%') && strchr(v, ' '))
            s = scan_pattern(path, v, hs);
        else
            s = scan_data_file(path, v, hs);
    }
    (void)ended;
    for (int r = 0; r < 4 && s == VV_OK; r++)
        if (!seen[r])
            s = vv_error_set(VV_ERR_FORMAT, "the header has no \"%.*s\" field",
                             (int)strlen(required[r]) - 1, required[r]);
    hs->data_start = pos;
    if (s == VV_OK && hs->n_files == 0)
        hs->data_bytes = fsize > pos ? fsize - pos : 0;
    free(text);
    if (s != VV_OK)
        header_scan_free(hs);
    return s;
}

/*
 * Inflates the gzip stream of @p path from @p offset, discarding the output,
 * until @p need bytes came out: VV_OK when they do, else VV_ERR_FORMAT.
 * Teem 1.12 leaks its gzip state (about 56 KB) on a truncated or corrupt
 * stream, so such a stream is refused here before Teem reads it; and
 * nothing inflates past what the header promises.
 */
static vv_status
check_gzip_stream(const char *path, uint64_t offset, uint64_t need) {
    FILE *f = fopen(path, "rb");
    if (!f)
        return vv_error_set(VV_ERR_IO, "cannot open %s: %s", vv_path_basename(path),
                            strerror(errno));
    if (fseeko(f, (off_t)offset, SEEK_SET) != 0) {
        fclose(f);
        return vv_error_set(VV_ERR_IO, "%s: cannot seek", vv_path_basename(path));
    }
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    if (inflateInit2(&zs, 15 + 16) != Z_OK) {
        fclose(f);
        return vv_error_set(VV_ERR_NOMEM, "zlib: cannot initialise");
    }
    unsigned char in[16384], out[65536];
    uint64_t got = 0;
    int rc = Z_OK;
    while (got < need && rc == Z_OK) {
        if (zs.avail_in == 0) {
            size_t n = fread(in, 1, sizeof in, f);
            if (n == 0)
                break;
            zs.next_in = in;
            zs.avail_in = (uInt)n;
        }
        uint64_t want = need - got < sizeof out ? need - got : sizeof out;
        zs.next_out = out;
        zs.avail_out = (uInt)want;
        rc = inflate(&zs, Z_NO_FLUSH);
        got += want - zs.avail_out;
        if (rc == Z_BUF_ERROR)
            rc = Z_OK; /* more input needed */
    }
    /* Teem checks the gzip trailer (CRC-32 and length) when the stream ends
     * right after the promised bytes, and leaks on a mismatch: see whether
     * the stream goes on (then the trailer is never read) or ends well */
    while (got == need && rc == Z_OK) {
        if (zs.avail_in == 0) {
            size_t n = fread(in, 1, sizeof in, f);
            if (n == 0)
                break;
            zs.next_in = in;
            zs.avail_in = (uInt)n;
        }
        zs.next_out = out;
        zs.avail_out = 1;
        rc = inflate(&zs, Z_NO_FLUSH);
        if (zs.avail_out == 0)
            break; /* more data follow: Teem stops before the trailer */
        if (rc == Z_BUF_ERROR)
            rc = Z_OK;
    }
    inflateEnd(&zs);
    fclose(f);
    if (got == need && rc != Z_OK && rc != Z_STREAM_END)
        return vv_error_set(VV_ERR_FORMAT,
                            "gzip data of %s: a corrupt stream or trailer after the promised %llu "
                            "bytes",
                            vv_path_basename(path), (unsigned long long)need);
    if (got < need)
        return vv_error_set(
            VV_ERR_FORMAT, "gzip data of %s end%s after %llu of the %llu bytes the header promises",
            vv_path_basename(path), rc == Z_OK || rc == Z_STREAM_END ? "" : " (corrupt)",
            (unsigned long long)got, (unsigned long long)need);
    return VV_OK;
}

/*
 * Checks that the data available can hold what the header promises before
 * Teem allocates: a raw encoding needs the bytes themselves, gzip at least
 * 1/1032 of them (deflate's largest ratio), hex two characters a byte and
 * ascii two a value. bzip2 has no such bound (the memory budget holds).
 */
static vv_status
check_promise(const char *path, const NrrdIoState *nio, const header_scan *hs, int one_shot,
              uint64_t count, size_t esize) {
    uint64_t need = count * esize, have = hs->data_bytes;
    const char *what = NULL;
    int ok = 1;
    if (nio->encoding == nrrdEncodingRaw) {
        ok = have >= need;
        what = "raw";
    } else if (nio->encoding == nrrdEncodingGzip) {
        ok = have >= need / 1032;
        what = "gzip";
    } else if (nio->encoding == nrrdEncodingHex) {
        ok = have / 2 >= need;
        what = "hex";
    } else if (nio->encoding == nrrdEncodingAscii) {
        ok = have / 2 + 1 >= count;
        what = "ascii";
    }
    if (!ok)
        return vv_error_set(
            VV_ERR_FORMAT,
            "%s data of %llu bytes cannot hold the %llu samples the header promises "
            "(%llu bytes)",
            what, (unsigned long long)have, (unsigned long long)count, (unsigned long long)need);
    /* a gzip stream without skipped lines starts right at the data: it must
     * inflate to the promised size (each file its share). Not in the
     * sandboxed reader (one_shot): the check inflates the whole stream once more only
     * to keep Teem's leak on a broken stream out of a long-lived process,
     * and the reader's leaks end with it (Teem reports the broken stream
     * itself and inflates no more than the header promises) */
    if (nio->encoding == nrrdEncodingGzip && nio->lineSkip == 0 && !one_shot) {
        /* Teem skips byteSkip bytes of the inflated stream of each file */
        uint64_t skip = nio->byteSkip > 0 ? (uint64_t)nio->byteSkip : 0;
        if (hs->n_files == 0)
            return check_gzip_stream(path, hs->data_start, need + skip);
        if (need % (uint64_t)hs->n_files == 0)
            for (int i = 0; i < hs->n_files; i++) {
                vv_status s =
                    check_gzip_stream(hs->files[i], 0, need / (uint64_t)hs->n_files + skip);
                if (s != VV_OK)
                    return s;
            }
    }
    return VV_OK;
}

/* Replaces *@p n by its slice at @p pos along @p axis (Teem's nrrdSlice). */
static vv_status
slice_axis(Nrrd **n, int axis, int pos) {
    Nrrd *out = nrrdNew();
    if (!out)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (nrrdSlice(out, *n, (unsigned int)axis, (size_t)pos)) {
        nrrdNuke(out);
        return teem_error(VV_ERR_FORMAT, "cannot take the slice");
    }
    nrrdNuke(*n);
    *n = out;
    return VV_OK;
}

/* The body of vv_nrrd_read, under teem_lock. */
static vv_status
read_locked(vv_volume **out, const char *path, const header_scan *hs, int channel, int time,
            vv_load_info *info, int one_shot) {
    vv_status s = VV_OK;
    vv_volume *v = NULL;
    int dims[3], nc = 1, nt = 1;
    vv_voxel_type type;
    int ch = channel < 0 ? 0 : channel, tp = time < 0 ? 0 : time;

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
    s = header_dims(n, dims, &type, &nc, &nt, 1);
    if (s != VV_OK)
        goto done;
    if (ch >= nc || tp >= nt) {
        s = ch >= nc
                ? vv_error_set(VV_ERR_INVALID, "channel %d asked, the file has %d channel%s", ch,
                               nc, nc == 1 ? "" : "s")
                : vv_error_set(VV_ERR_INVALID, "time step %d asked, the file has %d time step%s",
                               tp, nt, nt == 1 ? "" : "s");
        goto done;
    }
    /* the whole file is read, then sliced: its size is limited and budgeted
     * (the 3-D count is within the volume limits already; nc, nt <= 2^16) */
    const uint64_t count3 = (uint64_t)dims[0] * (uint64_t)dims[1] * (uint64_t)dims[2];
    const uint64_t steps = (uint64_t)nc * (uint64_t)nt;
    if (steps > VV_VOLUME_MAX_BYTES / (count3 * nrrdTypeSize[n->type])) {
        s = vv_error_set(VV_ERR_LIMIT,
                         "%d channels x %d time steps of %llu voxels (limit %llu bytes)", nc, nt,
                         (unsigned long long)count3, (unsigned long long)VV_VOLUME_MAX_BYTES);
        goto done;
    }
    if (steps > 1 && (s = vv_memory_budget_check(count3 * steps * nrrdTypeSize[n->type],
                                                 "NRRD channels and time steps")) != VV_OK)
        goto done;
    s = check_promise(path, nio, hs, one_shot, count3 * steps, nrrdTypeSize[n->type]);
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
    int dims2[3], nc2, nt2;
    vv_voxel_type type2;
    s = header_dims(n, dims2, &type2, &nc2, &nt2, 1);
    if (s != VV_OK)
        goto done;
    if (dims2[0] != dims[0] || dims2[1] != dims[1] || dims2[2] != dims[2] || type2 != type ||
        nc2 != nc || nt2 != nt) {
        s = vv_error_set(VV_ERR_FORMAT, "file changed while being read");
        goto done;
    }
    if (!n->data) {
        s = vv_error_set(VV_ERR_FORMAT, "no data");
        goto done;
    }
    /* the time step, then the channel (the higher axis first, so the
     * other's index holds) */
    int rgb = 0;
    {
        unsigned int ax[3];
        int nax, c_axis, t_axis;
        if ((s = pick_axes(n, ax, &nax, &c_axis, &t_axis)) != VV_OK)
            goto done;
        rgb = c_axis >= 0 && (n->axis[c_axis].kind == nrrdKindRGBColor ||
                              n->axis[c_axis].kind == nrrdKindRGBAColor);
        int first = c_axis > t_axis ? c_axis : t_axis, second = c_axis > t_axis ? t_axis : c_axis;
        int first_pos = first == c_axis ? ch : tp, second_pos = second == c_axis ? ch : tp;
        if (first >= 0 && (s = slice_axis(&n, first, first_pos)) != VV_OK)
            goto done;
        if (second >= 0 && (s = slice_axis(&n, second, second_pos)) != VV_OK)
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
    if (info) {
        info->n_channels = nc;
        info->n_times = nt;
        if (rgb && ch < 3) { /* an RGB(A)-color axis: red, green, blue (alpha keeps the default) */
            info->color[ch] = 1.0f;
            info->has_color = 1;
        }
    }
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
vv_nrrd_prescan(const char *path) {
    header_scan hs;
    vv_status s = scan_header(path, &hs);
    if (s == VV_OK)
        header_scan_free(&hs);
    return s;
}

static vv_status
nrrd_read_at(vv_volume **out, const char *path, int channel, int time, vv_load_info *info,
             int one_shot) {
    if (!out || !path) {
        return vv_error_set(VV_ERR_INVALID, "nrrd: NULL argument");
    }
    *out = NULL;
    header_scan hs;
    vv_status s = scan_header(path, &hs);
    if (s == VV_OK) {
        pthread_mutex_lock(&teem_lock);
        s = read_locked(out, path, &hs, channel, time, info, one_shot);
        pthread_mutex_unlock(&teem_lock);
        header_scan_free(&hs);
    }
    if (s != VV_OK)
        return vv_error_prefix(s, "nrrd: %s", vv_path_basename(path));
    return VV_OK;
}

vv_status
vv_nrrd_read(vv_volume **out, const char *path) {
    return nrrd_read_at(out, path, -1, -1, NULL, 0);
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
    vv_status s =
        io_write_check_voxels(v, v->data != NULL, vv_type_to_nrrd(v->type) != nrrdTypeUnknown);
    if (s == VV_OK)
        s = vv_volume_check_size(v->dims, v->type, NULL);
    return s != VV_OK ? s : io_write_check_geometry(v, 0);
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

/* ---- raw layout for bricked reading (src/io/store/bricked.c) ----------------- */

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
                  int *big_endian, int *gzip) {
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
    int dims[3], nc, nt;
    vv_voxel_type type;
    if ((s = header_dims(n, dims, &type, &nc, &nt, 0)) != VV_OK)
        goto done;
    if (nc * nt > 1) {
        s = vv_error_set(VV_ERR_UNSUPPORTED,
                         "%d channels and %d time steps: out-of-core reading takes one 3-D "
                         "volume; convert one channel and time step first (volvis convert IN "
                         "OUT.nrrd --channel C --time T)",
                         nc, nt);
        goto done;
    }
    if (n->type == nrrdTypeLLong || n->type == nrrdTypeULLong) {
        s = vv_error_set(VV_ERR_FORMAT, "64-bit integers need conversion: convert it to .vvb "
                                        "first (volvis convert IN OUT.vvb)");
        goto done;
    }
    /* a stream: 1 gzip, 2 bzip2 (when the caller takes one) */
    *gzip = !*gzip                               ? 0
            : nio->encoding == nrrdEncodingGzip  ? 1
            : nio->encoding == nrrdEncodingBzip2 ? 2
                                                 : 0;
    if (nio->encoding != nrrdEncodingRaw && !*gzip) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "encoding %s is not raw: it cannot be read by bricks; convert it "
                         "to .vvb first (volvis convert IN OUT.vvb)",
                         nio->encoding ? nio->encoding->name : "?");
        goto done;
    }
    if (*gzip && nio->byteSkip != 0) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "a byte skip in %s-encoded data is not supported for "
                         "reading slab by slab",
                         *gzip == 2 ? "bzip2" : "gzip");
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
        if (nio->byteSkip >= 0 || *gzip) {
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
vv_nrrd_data_layout(const char *path, vv_volume **header, char **data_path, uint64_t *offset,
                    int *big_endian, int *gzip) {
    *header = NULL;
    *data_path = NULL;
    /* the same header checks and detached-data policy as vv_nrrd_read */
    header_scan hs;
    vv_status s = scan_header(path, &hs);
    if (s == VV_OK) {
        header_scan_free(&hs);
        pthread_mutex_lock(&teem_lock);
        s = raw_layout_locked(path, header, data_path, offset, big_endian, gzip);
        pthread_mutex_unlock(&teem_lock);
    }
    if (s != VV_OK)
        return vv_error_prefix(s, "nrrd: %s", vv_path_basename(path));
    return VV_OK;
}

vv_status
vv_nrrd_raw_layout(const char *path, vv_volume **header, char **data_path, uint64_t *offset,
                   int *big_endian) {
    int gzip = 0;
    return vv_nrrd_data_layout(path, header, data_path, offset, big_endian, &gzip);
}

/* ---- the format record ------------------------------------------------------ */

static int
nrrd_looks_like(const vv_format_probe *p, int deep) {
    return !deep && !p->is_dir && p->n >= 7 && !memcmp(p->head, "NRRD000", 7);
}

static vv_status
nrrd_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    return nrrd_read_at(out, path, opt->channel, opt->time, opt->info, opt->one_shot);
}

/* An uncompressed NRRD's layout, for reading it out of core by bricks; a
 * compressed one is read whole (VV_ERR_UNSUPPORTED). */
static vv_status
nrrd_raw_layout_record(const char *path, const vv_load_options *opt, vv_volume **header,
                       char **data_path, uint64_t *offset, int *big_endian) {
    (void)opt;
    vv_status s = vv_nrrd_raw_layout(path, header, data_path, offset, big_endian);
    return s == VV_ERR_FORMAT ? VV_ERR_UNSUPPORTED : s;
}

/* gzip-compressed unless asked otherwise; NRRD holds every volume. */
static vv_status
nrrd_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return vv_nrrd_write(v, path, opt->compress != 0);
}

static const char *const nrrd_extensions[] = {"nrrd", "nhdr", NULL};
static const char *const nrrd_aliases[] = {"nhdr", NULL};

const vv_format_record vv_format_nrrd = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "nrrd",
    .title = "NRRD",
    .extensions = nrrd_extensions,
    .aliases = nrrd_aliases,
    .doc = "NRRD through Teem: every voxel type, spacing, origin, direction; gzip",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = nrrd_looks_like,
    .read = nrrd_read_record,
    .write = nrrd_write_record,
    .raw_layout = nrrd_raw_layout_record,
};
