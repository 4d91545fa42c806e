/*
 * MetaImage (ITK's .mhd header with detached data, or .mha with the data
 * after the header). See docs/formats.md for the keys understood.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <zlib.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

#define MHD_LINE_MAX 4096
#define MHD_MAX_FILES 65536
#define MHD_MAX_WIDTH 64 /* field width of an ElementDataFile pattern */
/* zlib's deflate cannot compress better than about 1032:1. */
#define MHD_ZLIB_MAX_RATIO 1100

typedef struct mhd_header {
    int ndims;
    long dims[3];
    int have_dims;
    vv_voxel_type type;
    int have_type;
    double spacing[3];
    double origin[3];
    double direction[9]; /* ours: row-major, columns are the axes */
    int msb;
    int compressed;
    long long compressed_size; /* -1: not given */
    long long header_size;     /* 0 default, -1: data at the end of the file */
    int have_spacing;          /* ElementSpacing seen (it overrides ElementSize) */
    char *data_file;           /* value of ElementDataFile */
    char **list;               /* LIST: file names, or generated from a pattern */
    int nlist;
    uint64_t data_start; /* LOCAL: offset just after the header */
} mhd_header;

static void
mhd_header_free(mhd_header *h) {
    free(h->data_file);
    for (int i = 0; i < h->nlist; i++)
        free(h->list[i]);
    free(h->list);
}

static char *
mhd_trim(char *s) {
    while (*s && isspace((unsigned char)*s))
        s++;
    size_t n = strlen(s);
    while (n > 0 && isspace((unsigned char)s[n - 1]))
        s[--n] = '\0';
    return s;
}

/*
 * Reads one header line into @p buf without its end of line. Returns 1 for a
 * line, 0 at end of file, -1 (with the trace set) for a line too long or
 * with control bytes: a binary file is refused before its bytes could reach
 * an error message.
 */
static int
mhd_getline(FILE *fp, char *buf, size_t cap, int lineno) {
    size_t n = 0;
    int c;
    while ((c = getc(fp)) != EOF && c != '\n') {
        if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F)
            return vv_error_set(VV_ERR_FORMAT, "line %d: binary data in the header (byte 0x%02x)",
                                lineno, (unsigned)c),
                   -1;
        if (n + 1 >= cap)
            return vv_error_set(VV_ERR_FORMAT, "line %d: too long", lineno), -1;
        buf[n++] = (char)c;
    }
    buf[n] = '\0';
    return c != EOF || n > 0;
}

/* Parses up to @p max numbers; returns how many were found, -1 on junk. */
static int
mhd_numbers(const char *s, double *out, int max) {
    int n = 0;
    char *end;
    for (;;) {
        while (*s && isspace((unsigned char)*s))
            s++;
        if (!*s)
            return n;
        if (n == max)
            return -1;
        double v = strtod(s, &end);
        if (end == s)
            return -1;
        out[n++] = v;
        s = end;
    }
}

static int
mhd_bool(const char *s, int *out) {
    if (!strcasecmp(s, "True") || !strcmp(s, "1")) {
        *out = 1;
        return 1;
    }
    if (!strcasecmp(s, "False") || !strcmp(s, "0")) {
        *out = 0;
        return 1;
    }
    return 0;
}

static vv_status
mhd_parse_type(const char *s, vv_voxel_type *t) {
    static const struct {
        const char *name;
        vv_voxel_type type;
    } map[] = {{"MET_UCHAR", VV_U8},  {"MET_CHAR", VV_I8},   {"MET_USHORT", VV_U16},
               {"MET_SHORT", VV_I16}, {"MET_UINT", VV_U32},  {"MET_INT", VV_I32},
               {"MET_FLOAT", VV_F32}, {"MET_DOUBLE", VV_F64}};
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (!strcasecmp(s, map[i].name)) {
            *t = map[i].type;
            return VV_OK;
        }
    return vv_error_set(VV_ERR_UNSUPPORTED, "ElementType %s is not supported", s);
}

/* Expands "name%03d.raw min max step" into a list of file names. */
static vv_status
mhd_expand_pattern(mhd_header *h, const char *value) {
    char fmt[MHD_LINE_MAX];
    long lo, hi, step = 1;
    int n = sscanf(value, "%4095s %ld %ld %ld", fmt, &lo, &hi, &step);
    if (n < 3)
        return vv_error_set(VV_ERR_FORMAT, "ElementDataFile pattern \"%s\" needs min and max",
                            value);
    /* Only one integer conversion is allowed in the pattern. */
    const char *pc = strchr(fmt, '%');
    if (!pc || strchr(pc + 1, '%'))
        return vv_error_set(VV_ERR_FORMAT, "bad ElementDataFile pattern \"%s\"", fmt);
    /* flags, then a field width of at most MHD_MAX_WIDTH (a width of
     * hundreds of millions made snprintf pad for seconds: found by
     * fuzz_mhd) */
    const char *q = pc + 1;
    while (*q && strchr("-+ 0", *q)) /* not '#': undefined for %d */
        q++;
    long width = 0;
    for (; *q >= '0' && *q <= '9'; q++)
        if ((width = width * 10 + (*q - '0')) > MHD_MAX_WIDTH)
            return vv_error_set(VV_ERR_FORMAT,
                                "ElementDataFile pattern \"%s\": field width over %d", fmt,
                                MHD_MAX_WIDTH);
    if (*q != 'd' && *q != 'i')
        return vv_error_set(VV_ERR_FORMAT, "bad ElementDataFile pattern \"%s\"", fmt);
    /* Bounded first so that the arithmetic below cannot overflow. */
    if (labs(lo) > 1000000000L || labs(hi) > 1000000000L || labs(step) > 1000000000L)
        return vv_error_set(VV_ERR_FORMAT, "bad ElementDataFile range %ld %ld %ld", lo, hi, step);
    if (step == 0 || (hi - lo) / step < 0 || (hi - lo) / step >= MHD_MAX_FILES)
        return vv_error_set(VV_ERR_FORMAT, "bad ElementDataFile range %ld %ld %ld", lo, hi, step);
    long count = (hi - lo) / step + 1;
    h->list = calloc((size_t)count, sizeof *h->list);
    if (!h->list)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (long i = 0; i < count; i++) {
        char name[MHD_LINE_MAX + 32];
        snprintf(name, sizeof name, fmt, (int)(lo + i * step));
        h->list[i] = vv_strdup(name);
        if (!h->list[i])
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        h->nlist++;
    }
    return VV_OK;
}

/* Reads the file names of "ElementDataFile = LIST", one per line. */
static vv_status
mhd_read_list(mhd_header *h, FILE *fp) {
    char line[MHD_LINE_MAX];
    int cap = 0;
    int got, lineno = 0;
    uint64_t held = 0; /* the names' bytes, against the memory budget */
    while ((got = mhd_getline(fp, line, sizeof line, ++lineno)) > 0) {
        char *t = mhd_trim(line);
        if (!*t)
            continue;
        if (h->nlist >= MHD_MAX_FILES)
            return vv_error_set(VV_ERR_LIMIT, "more than %d files in the LIST", MHD_MAX_FILES);
        held += strlen(t) + 1 + sizeof *h->list;
        vv_status sb = vv_memory_budget_check(held, "the LIST's file names");
        if (sb != VV_OK)
            return sb;
        if (h->nlist == cap) {
            int nc = cap ? 2 * cap : 64;
            char **nl = realloc(h->list, (size_t)nc * sizeof *nl);
            if (!nl)
                return vv_error_set(VV_ERR_NOMEM, "out of memory");
            h->list = nl;
            cap = nc;
        }
        if (!(h->list[h->nlist] = vv_strdup(t)))
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        h->nlist++;
    }
    if (got < 0)
        return vv_error_prefix(VV_ERR_FORMAT, "LIST");
    if (h->nlist == 0)
        return vv_error_set(VV_ERR_FORMAT, "ElementDataFile = LIST names no files");
    return VV_OK;
}

static vv_status
mhd_parse_header(mhd_header *h, FILE *fp) {
    char line[MHD_LINE_MAX];
    int lineno = 0;
    h->ndims = 0;
    h->compressed_size = -1;
    for (int a = 0; a < 3; a++) {
        h->spacing[a] = 1.0;
        h->origin[a] = 0.0;
        h->dims[a] = 1;
    }
    for (int i = 0; i < 9; i++)
        h->direction[i] = (i % 4 == 0) ? 1.0 : 0.0;

    int got;
    while ((got = mhd_getline(fp, line, sizeof line, lineno + 1)) > 0) {
        lineno++;
        char *eq = strchr(line, '=');
        char *t = mhd_trim(line);
        if (!*t)
            continue;
        if (!eq)
            return vv_error_set(VV_ERR_FORMAT, "line %d: expected \"Key = Value\"", lineno);
        *eq = '\0';
        char *key = mhd_trim(t);
        char *val = mhd_trim(eq + 1);
        double num[16];
        int n;
        if (!strcasecmp(key, "ObjectType")) {
            if (strcasecmp(val, "Image"))
                return vv_error_set(VV_ERR_UNSUPPORTED, "ObjectType %s (only Image)", val);
        } else if (!strcasecmp(key, "NDims")) {
            n = mhd_numbers(val, num, 1);
            if (n != 1 || (num[0] != 2 && num[0] != 3))
                return vv_error_set(VV_ERR_UNSUPPORTED, "NDims %s (only 2 or 3)", val);
            h->ndims = (int)num[0];
        } else if (!strcasecmp(key, "DimSize")) {
            n = mhd_numbers(val, num, 3);
            if (n < 2)
                return vv_error_set(VV_ERR_FORMAT, "bad DimSize \"%s\"", val);
            /* a second DimSize replaces the first, axes it leaves out included */
            for (int a = 0; a < 3; a++)
                h->dims[a] = 1;
            for (int a = 0; a < n; a++) {
                if (!(num[a] >= 1) || num[a] != floor(num[a]))
                    return vv_error_set(VV_ERR_FORMAT, "bad DimSize \"%s\"", val);
                if (num[a] > VV_VOLUME_MAX_DIM)
                    return vv_error_set(VV_ERR_LIMIT, "DimSize %s is over the limit of %d per axis",
                                        val, VV_VOLUME_MAX_DIM);
                h->dims[a] = (long)num[a];
            }
            h->have_dims = n;
        } else if (!strcasecmp(key, "ElementType")) {
            vv_status s = mhd_parse_type(val, &h->type);
            if (s != VV_OK)
                return s;
            h->have_type = 1;
        } else if (!strcasecmp(key, "ElementSpacing") || !strcasecmp(key, "ElementSize")) {
            /* ElementSpacing wins over ElementSize whatever the order. */
            int is_spacing = !strcasecmp(key, "ElementSpacing");
            n = mhd_numbers(val, num, 3);
            if (n < 2)
                return vv_error_set(VV_ERR_FORMAT, "bad %s \"%s\"", key, val);
            for (int a = 0; a < n; a++)
                if (!(num[a] > 0) || !isfinite(num[a]))
                    return vv_error_set(VV_ERR_FORMAT, "bad %s \"%s\"", key, val);
            if (is_spacing || !h->have_spacing)
                for (int a = 0; a < n; a++)
                    h->spacing[a] = num[a];
            if (is_spacing)
                h->have_spacing = 1;
        } else if (!strcasecmp(key, "Offset") || !strcasecmp(key, "Position") ||
                   !strcasecmp(key, "Origin")) {
            n = mhd_numbers(val, num, 3);
            if (n < 2)
                return vv_error_set(VV_ERR_FORMAT, "bad %s \"%s\"", key, val);
            for (int a = 0; a < n; a++) {
                if (!isfinite(num[a]))
                    return vv_error_set(VV_ERR_FORMAT, "bad %s \"%s\"", key, val);
                h->origin[a] = num[a];
            }
        } else if (!strcasecmp(key, "TransformMatrix") || !strcasecmp(key, "Orientation") ||
                   !strcasecmp(key, "Rotation")) {
            n = mhd_numbers(val, num, 9);
            if (n != 4 && n != 9)
                return vv_error_set(VV_ERR_FORMAT, "bad %s \"%s\"", key, val);
            int d = n == 4 ? 2 : 3;
            double *m = h->direction;
            for (int i = 0; i < 9; i++)
                m[i] = (i % 4 == 0) ? 1.0 : 0.0;
            /* MetaImage lists the matrix axis by axis: entries [a*d .. a*d+d-1]
               are the world direction of index axis a (ITK's MetaImageIO calls
               SetDirection(a, those entries)). Our direction keeps axes in
               columns, so entry (r, a) = listed[a*d + r]. */
            for (int a = 0; a < d; a++)
                for (int r = 0; r < d; r++) {
                    if (!isfinite(num[a * d + r]))
                        return vv_error_set(VV_ERR_FORMAT, "bad %s \"%s\"", key, val);
                    m[r * 3 + a] = num[a * d + r];
                }
        } else if (!strcasecmp(key, "BinaryDataByteOrderMSB") ||
                   !strcasecmp(key, "ElementByteOrderMSB")) {
            if (!mhd_bool(val, &h->msb))
                return vv_error_set(VV_ERR_FORMAT, "bad %s \"%s\"", key, val);
        } else if (!strcasecmp(key, "CompressedData")) {
            if (!mhd_bool(val, &h->compressed))
                return vv_error_set(VV_ERR_FORMAT, "bad CompressedData \"%s\"", val);
        } else if (!strcasecmp(key, "CompressedDataSize")) {
            n = mhd_numbers(val, num, 1);
            if (n != 1 || !(num[0] >= 0) || num[0] > 9.0e18 || num[0] != floor(num[0]))
                return vv_error_set(VV_ERR_FORMAT, "bad CompressedDataSize \"%s\"", val);
            h->compressed_size = (long long)num[0];
        } else if (!strcasecmp(key, "HeaderSize")) {
            n = mhd_numbers(val, num, 1);
            if (n != 1 || !(num[0] >= -1) || num[0] > 9.0e18 || num[0] != floor(num[0]))
                return vv_error_set(VV_ERR_FORMAT, "bad HeaderSize \"%s\"", val);
            h->header_size = (long long)num[0];
        } else if (!strcasecmp(key, "ElementNumberOfChannels")) {
            n = mhd_numbers(val, num, 1);
            if (n != 1 || num[0] != 1)
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "ElementNumberOfChannels %s (only 1 is supported)", val);
        } else if (!strcasecmp(key, "BinaryData")) {
            int b;
            if (!mhd_bool(val, &b))
                return vv_error_set(VV_ERR_FORMAT, "bad BinaryData \"%s\"", val);
            if (!b)
                return vv_error_set(VV_ERR_UNSUPPORTED, "BinaryData = False (ASCII data)");
        } else if (!strcasecmp(key, "ElementDataFile")) {
            off_t pos = ftello(fp);
            if (pos < 0)
                return vv_error_set(VV_ERR_IO, "cannot tell the header size");
            h->data_start = (uint64_t)pos;
            if (!*val)
                return vv_error_set(VV_ERR_FORMAT, "empty ElementDataFile");
            if (!(h->data_file = vv_strdup(val)))
                return vv_error_set(VV_ERR_NOMEM, "out of memory");
            if (!strncasecmp(val, "LIST", 4) && (val[4] == '\0' || isspace((unsigned char)val[4])))
                return mhd_read_list(h, fp);
            if (strchr(val, '%') && strchr(val, ' '))
                return mhd_expand_pattern(h, val);
            return VV_OK;
        }
        /* Other keys (Comment, AnatomicalOrientation, CenterOfRotation, ...)
           do not change the voxels or the grid. */
    }
    if (got < 0)
        return VV_ERR_FORMAT;
    if (ferror(fp))
        return vv_error_set(VV_ERR_IO, "read error: %s", strerror(errno));
    if (lineno == 0)
        return vv_error_set(VV_ERR_FORMAT, "empty file");
    return vv_error_set(VV_ERR_FORMAT, "no ElementDataFile (truncated header?)");
}

/* Finishes the header checks once all keys are known. */
static vv_status
mhd_validate(mhd_header *h, int dims[3], uint64_t *bytes) {
    if (!h->have_dims)
        return vv_error_set(VV_ERR_FORMAT, "no DimSize");
    if (!h->have_type)
        return vv_error_set(VV_ERR_FORMAT, "no ElementType");
    int nd = h->ndims ? h->ndims : h->have_dims;
    if (h->have_dims != nd)
        return vv_error_set(VV_ERR_FORMAT, "DimSize has %d values for NDims %d", h->have_dims, nd);
    for (int a = 0; a < 3; a++)
        dims[a] = (int)h->dims[a];
    return vv_volume_check_size(dims, h->type, bytes);
}

/* Size of a file, or an error naming it. */
static vv_status
mhd_file_size(const char *path, uint64_t *size) {
    struct stat st;
    if (stat(path, &st) != 0)
        return vv_error_set(VV_ERR_IO, "data file %s: %s", vv_path_basename(path), strerror(errno));
    if (!S_ISREG(st.st_mode))
        return vv_error_set(VV_ERR_IO, "data file %s: not a regular file", vv_path_basename(path));
    *size = (uint64_t)st.st_size;
    return VV_OK;
}

/* Where @p want bytes of raw data start in a file of @p size bytes whose
   own header (LOCAL: the MetaImage header) ends at @p base. */
static vv_status
mhd_data_offset(const mhd_header *h, const char *name, uint64_t size, uint64_t base, uint64_t want,
                uint64_t *offset) {
    uint64_t off;
    if (h->header_size == -1) {
        if (size < base + want)
            return vv_error_set(VV_ERR_FORMAT,
                                "data file %s: %llu bytes, too small for %llu bytes of data", name,
                                (unsigned long long)size, (unsigned long long)want);
        off = size - want;
    } else {
        off = base + (uint64_t)h->header_size;
        if (off > size || size - off < want)
            return vv_error_set(VV_ERR_FORMAT,
                                "data file %s: truncated: expected %llu bytes at offset %llu, "
                                "the file has %llu",
                                name, (unsigned long long)want, (unsigned long long)off,
                                (unsigned long long)size);
    }
    *offset = off;
    return VV_OK;
}

static vv_status
mhd_read_at(const char *path, uint64_t offset, void *dst, uint64_t n) {
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return vv_error_set(VV_ERR_IO, "data file %s: cannot open: %s", vv_path_basename(path),
                            strerror(errno));
    vv_status s = VV_OK;
    if (fseeko(fp, (off_t)offset, SEEK_SET) != 0 || fread(dst, 1, (size_t)n, fp) != (size_t)n)
        s = vv_error_set(VV_ERR_IO, "data file %s: cannot read %llu bytes at offset %llu",
                         vv_path_basename(path), (unsigned long long)n, (unsigned long long)offset);
    fclose(fp);
    return s;
}

/* Inflates a zlib (or gzip) stream of @p clen bytes into exactly @p n bytes. */
static vv_status
mhd_inflate(const unsigned char *src, uint64_t clen, unsigned char *dst, uint64_t n) {
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    if (inflateInit2(&zs, 15 + 32) != Z_OK)
        return vv_error_set(VV_ERR_NOMEM, "zlib: cannot initialise");
    uint64_t in_done = 0, out_done = 0;
    int rc = Z_OK;
    const uInt chunk = 1u << 30;
    while (rc == Z_OK && out_done < n) {
        if (zs.avail_in == 0 && in_done < clen) {
            uint64_t k = clen - in_done < chunk ? clen - in_done : chunk;
            zs.next_in = (Bytef *)(src + in_done);
            zs.avail_in = (uInt)k;
            in_done += k;
        }
        uint64_t k = n - out_done < chunk ? n - out_done : chunk;
        zs.next_out = dst + out_done;
        zs.avail_out = (uInt)k;
        rc = inflate(&zs, Z_NO_FLUSH);
        out_done += k - zs.avail_out;
        if (rc == Z_BUF_ERROR && zs.avail_in == 0 && in_done >= clen)
            break;
        if (rc == Z_BUF_ERROR && zs.avail_out > 0)
            break;
        if (rc == Z_BUF_ERROR)
            rc = Z_OK;
    }
    const char *msg = zs.msg;
    inflateEnd(&zs);
    if (rc != Z_OK && rc != Z_STREAM_END && out_done < n)
        return vv_error_set(VV_ERR_FORMAT, "compressed data: %s (after %llu of %llu bytes)",
                            msg ? msg : "truncated", (unsigned long long)out_done,
                            (unsigned long long)n);
    if (out_done < n)
        return vv_error_set(VV_ERR_FORMAT, "compressed data gives %llu bytes, expected %llu",
                            (unsigned long long)out_done, (unsigned long long)n);
    return VV_OK;
}

static vv_status
mhd_read_data(vv_volume **out, mhd_header *h, const char *hdr_path, const int dims[3],
              uint64_t bytes) {
    vv_status s;
    vv_volume *v = NULL;
    char **paths = NULL;
    int npaths = 0;
    unsigned char *cbuf = NULL;
    uint64_t base = 0;

    int local = !strcasecmp(h->data_file, "LOCAL");
    if (local) {
        npaths = 1;
        base = h->data_start;
    } else {
        npaths = h->nlist ? h->nlist : 1;
    }
    paths = calloc((size_t)npaths, sizeof *paths);
    if (!paths)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < npaths; i++) {
        const char *rel = local ? vv_path_basename(hdr_path) : h->nlist ? h->list[i] : h->data_file;
        if (local) {
            paths[i] = vv_strdup(hdr_path);
            if (!paths[i]) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                goto done;
            }
        } else if ((s = vv_detached_path(hdr_path, rel, &paths[i], NULL)) != VV_OK) {
            /* the detached-data policy: inside the header's folder, regular files */
            goto done;
        }
    }
    if (bytes % (uint64_t)npaths != 0) {
        s = vv_error_set(VV_ERR_FORMAT, "%llu bytes of data cannot be split over %d files",
                         (unsigned long long)bytes, npaths);
        goto done;
    }
    uint64_t part = bytes / (uint64_t)npaths;
    if (h->compressed && npaths > 1) {
        s = vv_error_set(VV_ERR_UNSUPPORTED, "compressed data in a file list");
        goto done;
    }

    if (h->compressed) {
        uint64_t size;
        if ((s = mhd_file_size(paths[0], &size)) != VV_OK)
            goto done;
        uint64_t off = base + (h->header_size > 0 ? (uint64_t)h->header_size : 0);
        if (off > size) {
            s = vv_error_set(VV_ERR_FORMAT, "data file %s: no compressed data",
                             vv_path_basename(paths[0]));
            goto done;
        }
        uint64_t clen = size - off;
        if (h->compressed_size >= 0) {
            if ((uint64_t)h->compressed_size > clen) {
                s = vv_error_set(VV_ERR_FORMAT,
                                 "CompressedDataSize %lld is past the end of the file (%llu "
                                 "bytes of data)",
                                 h->compressed_size, (unsigned long long)clen);
                goto done;
            }
            clen = (uint64_t)h->compressed_size;
            if (h->header_size == -1)
                off = size - clen;
        }
        if (clen == 0 || bytes / MHD_ZLIB_MAX_RATIO > clen) {
            s = vv_error_set(VV_ERR_FORMAT,
                             "%llu bytes of compressed data cannot hold %llu bytes of voxels",
                             (unsigned long long)clen, (unsigned long long)bytes);
            goto done;
        }
        cbuf = malloc((size_t)clen);
        if (!cbuf) {
            s = vv_error_set(VV_ERR_NOMEM, "cannot allocate %llu bytes", (unsigned long long)clen);
            goto done;
        }
        if ((s = mhd_read_at(paths[0], off, cbuf, clen)) != VV_OK)
            goto done;
        if ((s = vv_volume_new(&v, dims, h->type)) != VV_OK)
            goto done;
        if ((s = mhd_inflate(cbuf, clen, v->data, bytes)) != VV_OK)
            goto done;
    } else {
        uint64_t *offs = calloc((size_t)npaths, sizeof *offs);
        if (!offs) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            goto done;
        }
        /* Check every file before allocating the volume. */
        for (int i = 0; i < npaths; i++) {
            uint64_t size;
            if ((s = mhd_file_size(paths[i], &size)) != VV_OK ||
                (s = mhd_data_offset(h, vv_path_basename(paths[i]), size, base, part, &offs[i])) !=
                    VV_OK) {
                free(offs);
                goto done;
            }
        }
        if ((s = vv_volume_new(&v, dims, h->type)) != VV_OK) {
            free(offs);
            goto done;
        }
        for (int i = 0; i < npaths && s == VV_OK; i++)
            s = mhd_read_at(paths[i], offs[i], (unsigned char *)v->data + part * (uint64_t)i, part);
        free(offs);
        if (s != VV_OK)
            goto done;
    }

    size_t vs = vv_voxel_type_size(h->type);
    if (vs > 1 && h->msb == vv_host_is_little_endian())
        vv_byteswap(v->data, bytes / vs, vs);
    for (int a = 0; a < 3; a++) {
        v->spacing[a] = h->spacing[a];
        v->origin[a] = h->origin[a];
    }
    memcpy(v->direction, h->direction, sizeof v->direction);
    v->unit = VV_UNIT_MM; /* ITK's convention for medical images */
    vv_volume_update_range(v);
    *out = v;
    v = NULL;
    s = VV_OK;
done:
    vv_volume_free(v);
    free(cbuf);
    for (int i = 0; i < npaths; i++)
        free(paths[i]);
    free(paths);
    return s;
}

vv_status
vv_mhd_read(vv_volume **out, const char *path) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "mhd: NULL argument");
    *out = NULL;
    const char *name = vv_path_basename(path);
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return vv_error_set(VV_ERR_IO, "mhd: %s: cannot open: %s", name, strerror(errno));
    mhd_header h;
    memset(&h, 0, sizeof h);
    vv_status s = mhd_parse_header(&h, fp);
    fclose(fp);
    int dims[3];
    uint64_t bytes = 0;
    if (s == VV_OK)
        s = mhd_validate(&h, dims, &bytes);
    if (s == VV_OK)
        s = mhd_read_data(out, &h, path, dims, bytes);
    mhd_header_free(&h);
    if (s != VV_OK)
        return vv_error_prefix(s, "mhd: %s", name);
    return VV_OK;
}

/* ---- the format record ------------------------------------------------------ */

/* The first line is "Key = ..." with a MetaImage key. */
static int
mhd_looks_like(const vv_format_probe *p, int deep) {
    static const char *const keys[] = {"ObjectType",
                                       "NDims",
                                       "ObjectSubType",
                                       "DimSize",
                                       "ElementType",
                                       "ElementSpacing",
                                       "Comment",
                                       "TransformType",
                                       "BinaryData",
                                       "BinaryDataByteOrderMSB",
                                       "ElementByteOrderMSB",
                                       "CompressedData",
                                       "Offset",
                                       "Position",
                                       "Origin",
                                       "TransformMatrix",
                                       "Rotation",
                                       "Orientation",
                                       "CenterOfRotation",
                                       "AnatomicalOrientation",
                                       "ElementDataFile",
                                       "HeaderSize",
                                       "ElementNumberOfChannels",
                                       "ElementSize",
                                       "Name",
                                       "ID",
                                       "ParentID",
                                       "Color",
                                       "ElementMin",
                                       "ElementMax"};
    if (deep || p->is_dir)
        return 0;
    const unsigned char *h = p->head;
    const size_t n = p->n;
    size_t i = 0;
    while (i < n && isspace(h[i]))
        i++;
    size_t k0 = i;
    while (i < n && (isalnum(h[i]) || h[i] == '_'))
        i++;
    size_t klen = i - k0;
    if (klen == 0)
        return 0;
    while (i < n && (h[i] == ' ' || h[i] == '\t'))
        i++;
    if (i >= n || h[i] != '=')
        return 0;
    for (size_t j = 0; j < sizeof keys / sizeof keys[0]; j++)
        if (strlen(keys[j]) == klen && !strncasecmp((const char *)h + k0, keys[j], klen))
            return 1;
    return 0;
}

static vv_status
mhd_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    (void)opt;
    return vv_mhd_read(out, path);
}

static vv_status
mhd_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return vv_mhd_write(v, path, opt->compress);
}

static const char *const mhd_extensions[] = {"mhd", "mha", NULL};
static const char *const mhd_aliases[] = {"mha", "metaimage", NULL};

const vv_format_record vv_format_mhd = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "mhd",
    .title = "MetaImage",
    .extensions = mhd_extensions,
    .aliases = mhd_aliases,
    .doc = "MetaImage (ITK): detached data (.mhd) or one file (.mha), raw or zlib; writes "
           "every voxel type, TransformMatrix/Offset/ElementSpacing (RAS turned to ITK's LPS), "
           "zlib-compressed unless --no-compress",
    .looks_like = mhd_looks_like,
    .read = mhd_read_record,
    .write = mhd_write_record,
};
