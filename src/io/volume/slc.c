/*
 * SLC: VolVis's own slice format (8-bit voxels, optionally run-length
 * compressed). See docs/formats.md for the layout.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

#define SLC_MAGIC 11111
#define SLC_ICON_MAX 64
/* A repeat run of 127 voxels costs 2 bytes, so RLE cannot expand the data
   more than 63.5 times; a file that claims more is rejected before the
   volume is allocated. */
#define SLC_RLE_MAX_RATIO 64

/* Reader state: the stream and its size, so that every length taken from
   the file can be checked against the bytes that are really there. */
typedef struct slc_in {
    FILE *fp;
    uint64_t size;
} slc_in;

static uint64_t
slc_remaining(const slc_in *in) {
    off_t pos = ftello(in->fp);
    if (pos < 0 || (uint64_t)pos > in->size)
        return 0;
    return in->size - (uint64_t)pos;
}

/* Reads one header token: skips whitespace, then takes characters up to the
   next whitespace or 'X' (the icon and slice sizes are followed by "X" with
   or without a space). */
static vv_status
slc_token(slc_in *in, char *buf, size_t cap, const char *what) {
    int c;
    size_t n = 0;
    do {
        c = getc(in->fp);
    } while (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f');
    while (c != EOF && c != ' ' && c != '\t' && c != '\n' && c != '\r' && c != '\v' && c != '\f' &&
           c != 'X') {
        if (n + 1 >= cap)
            return vv_error_set(VV_ERR_FORMAT, "%s: token too long", what);
        /* Binary junk never ends up in an error message. */
        if (c < 0x21 || c > 0x7E)
            return vv_error_set(VV_ERR_FORMAT, "%s: unexpected byte 0x%02x in the header", what,
                                (unsigned)c);
        buf[n++] = (char)c;
        c = getc(in->fp);
    }
    if (c == 'X')
        ungetc(c, in->fp);
    buf[n] = '\0';
    if (n == 0)
        return vv_error_set(VV_ERR_FORMAT, "%s: missing (truncated header)", what);
    return VV_OK;
}

static vv_status
slc_read_long(slc_in *in, const char *what, long *out) {
    char buf[64];
    vv_status s = slc_token(in, buf, sizeof buf, what);
    if (s != VV_OK)
        return s;
    char *end;
    errno = 0;
    long v = strtol(buf, &end, 10);
    if (*end != '\0' || errno == ERANGE)
        return vv_error_set(VV_ERR_FORMAT, "%s: expected an integer, got \"%s\"", what, buf);
    *out = v;
    return VV_OK;
}

static vv_status
slc_read_double(slc_in *in, const char *what, double *out) {
    char buf[64];
    vv_status s = slc_token(in, buf, sizeof buf, what);
    if (s != VV_OK)
        return s;
    char *end;
    double v = strtod(buf, &end);
    if (*end != '\0')
        return vv_error_set(VV_ERR_FORMAT, "%s: expected a number, got \"%s\"", what, buf);
    *out = v;
    return VV_OK;
}

/* Consumes optional whitespace and the 'X' that ends the icon and slice
   size fields. */
static vv_status
slc_expect_x(slc_in *in, const char *what) {
    int c;
    do {
        c = getc(in->fp);
    } while (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f');
    if (c != 'X')
        return vv_error_set(VV_ERR_FORMAT, "%s: expected 'X'", what);
    return VV_OK;
}

/*
 * Decodes one RLE slice of @p n bytes into @p out (@p len voxels). Never
 * reads past n and never writes past len; a slice that ends early (no
 * terminator, or a terminator before the slice is full) is zero-filled.
 */
static vv_status
slc_rle_decode(const unsigned char *in, uint64_t n, unsigned char *out, uint64_t len) {
    uint64_t ip = 0, op = 0;
    while (ip < n) {
        unsigned c = in[ip++];
        unsigned k = c & 0x7Fu;
        if (k == 0)
            break;
        if (op + k > len)
            return vv_error_set(VV_ERR_FORMAT, "run of %u bytes overflows the slice (%llu > %llu)",
                                k, (unsigned long long)(op + k), (unsigned long long)len);
        if (c & 0x80u) {
            if (ip + k > n)
                return vv_error_set(VV_ERR_FORMAT,
                                    "literal run of %u bytes at offset %llu passes the end of "
                                    "the slice data (%llu bytes)",
                                    k, (unsigned long long)(ip - 1), (unsigned long long)n);
            memcpy(out + op, in + ip, k);
            ip += k;
        } else {
            if (ip >= n)
                return vv_error_set(VV_ERR_FORMAT,
                                    "repeat run at offset %llu has no value byte (slice data "
                                    "is %llu bytes)",
                                    (unsigned long long)(ip - 1), (unsigned long long)n);
            memset(out + op, in[ip++], k);
        }
        op += k;
    }
    if (op < len)
        memset(out + op, 0, len - op);
    return VV_OK;
}

static vv_status
slc_read_stream(vv_volume **out, slc_in *in) {
    long magic = 0, nx = 0, ny = 0, nz = 0, bits = 0, unit = 0, origin = 0, mod = 0, comp = 0;
    long iw = 0, ih = 0;
    double sp[3] = {0, 0, 0};
    vv_status s;
    if ((s = slc_read_long(in, "magic", &magic)) != VV_OK)
        return s;
    if (magic != SLC_MAGIC)
        return vv_error_set(VV_ERR_FORMAT, "not an SLC file (magic %ld, expected 11111)", magic);
    if ((s = slc_read_long(in, "x size", &nx)) != VV_OK ||
        (s = slc_read_long(in, "y size", &ny)) != VV_OK ||
        (s = slc_read_long(in, "z size", &nz)) != VV_OK ||
        (s = slc_read_long(in, "bits per voxel", &bits)) != VV_OK)
        return s;
    if (nx < 1 || ny < 1 || nz < 1)
        return vv_error_set(VV_ERR_FORMAT, "bad size %ld x %ld x %ld", nx, ny, nz);
    if (nx > VV_VOLUME_MAX_DIM || ny > VV_VOLUME_MAX_DIM || nz > VV_VOLUME_MAX_DIM)
        return vv_error_set(VV_ERR_LIMIT, "size %ld x %ld x %ld is over the limit of %d per axis",
                            nx, ny, nz, VV_VOLUME_MAX_DIM);
    int dims[3] = {(int)nx, (int)ny, (int)nz};
    uint64_t bytes;
    if ((s = vv_volume_check_size(dims, VV_U8, &bytes)) != VV_OK)
        return s;
    if (bits != 8)
        return vv_error_set(VV_ERR_UNSUPPORTED, "%ld bits per voxel (only 8 is supported)", bits);
    if ((s = slc_read_double(in, "x spacing", &sp[0])) != VV_OK ||
        (s = slc_read_double(in, "y spacing", &sp[1])) != VV_OK ||
        (s = slc_read_double(in, "z spacing", &sp[2])) != VV_OK)
        return s;
    for (int a = 0; a < 3; a++)
        if (!(sp[a] > 0) || !isfinite(sp[a]))
            return vv_error_set(VV_ERR_FORMAT, "bad voxel spacing %g %g %g", sp[0], sp[1], sp[2]);
    if ((s = slc_read_long(in, "unit", &unit)) != VV_OK ||
        (s = slc_read_long(in, "data origin", &origin)) != VV_OK ||
        (s = slc_read_long(in, "modification", &mod)) != VV_OK ||
        (s = slc_read_long(in, "compression", &comp)) != VV_OK)
        return s;
    if (comp != 0 && comp != 1)
        return vv_error_set(VV_ERR_FORMAT, "unknown compression %ld (0 none, 1 RLE)", comp);
    if ((s = slc_read_long(in, "icon width", &iw)) != VV_OK ||
        (s = slc_read_long(in, "icon height", &ih)) != VV_OK ||
        (s = slc_expect_x(in, "icon")) != VV_OK)
        return s;
    if (iw < 0 || ih < 0 || iw > VV_VOLUME_MAX_DIM || ih > VV_VOLUME_MAX_DIM)
        return vv_error_set(VV_ERR_FORMAT, "bad icon size %ld x %ld", iw, ih);
    uint64_t icon_bytes = 3u * (uint64_t)iw * (uint64_t)ih;
    if (icon_bytes > slc_remaining(in))
        return vv_error_set(VV_ERR_FORMAT, "icon of %ld x %ld is truncated", iw, ih);
    if (fseeko(in->fp, (off_t)icon_bytes, SEEK_CUR) != 0)
        return vv_error_set(VV_ERR_IO, "cannot skip the icon: %s", strerror(errno));

    uint64_t rest = slc_remaining(in);
    if (comp == 0 && rest < bytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "truncated data: %ld x %ld x %ld needs %llu bytes, the file has %llu",
                            nx, ny, nz, (unsigned long long)bytes, (unsigned long long)rest);
    if (comp == 1 && bytes / SLC_RLE_MAX_RATIO > rest)
        return vv_error_set(VV_ERR_FORMAT,
                            "truncated data: %ld x %ld x %ld cannot be run-length coded in the "
                            "%llu bytes left in the file",
                            nx, ny, nz, (unsigned long long)rest);

    vv_volume *v = NULL;
    if ((s = vv_volume_new(&v, dims, VV_U8)) != VV_OK)
        return s;
    v->spacing[0] = sp[0];
    v->spacing[1] = sp[1];
    v->spacing[2] = sp[2];
    v->unit = (unit >= 0 && unit <= 4) ? (vv_unit)unit : VV_UNIT_UNKNOWN;
    v->data_origin = (origin >= 0 && origin <= 7) ? (vv_data_origin)origin : VV_ORIGIN_OTHER;
    v->modification = (mod >= 0 && mod <= 4) ? (vv_modification)mod : VV_MOD_OTHER;

    uint64_t slice = (uint64_t)nx * (uint64_t)ny;
    unsigned char *data = v->data;
    unsigned char *buf = NULL;
    uint64_t cap = 0;
    for (long z = 0; z < nz; z++) {
        unsigned char *dst = data + (uint64_t)z * slice;
        if (comp == 0) {
            size_t got = fread(dst, 1, slice, in->fp);
            if (got != slice) {
                s = vv_error_set(VV_ERR_FORMAT, "slice %ld: truncated (%zu of %llu bytes)", z, got,
                                 (unsigned long long)slice);
                goto fail;
            }
            continue;
        }
        long n = 0;
        char what[48];
        snprintf(what, sizeof what, "slice %ld: size", z);
        if ((s = slc_read_long(in, what, &n)) != VV_OK || (s = slc_expect_x(in, what)) != VV_OK)
            goto fail;
        uint64_t left = slc_remaining(in);
        if (n < 0 || (uint64_t)n > left) {
            s = vv_error_set(VV_ERR_FORMAT,
                             "slice %ld: compressed size %ld is negative or past the end of the "
                             "file (%llu bytes left)",
                             z, n, (unsigned long long)left);
            goto fail;
        }
        if ((uint64_t)n > cap) {
            unsigned char *nb = realloc(buf, (size_t)n);
            if (!nb) {
                s = vv_error_set(VV_ERR_NOMEM, "slice %ld: cannot allocate %ld bytes", z, n);
                goto fail;
            }
            buf = nb;
            cap = (uint64_t)n;
        }
        if (n > 0 && fread(buf, 1, (size_t)n, in->fp) != (size_t)n) {
            s = vv_error_set(VV_ERR_FORMAT, "slice %ld: truncated compressed data", z);
            goto fail;
        }
        if ((s = slc_rle_decode(buf, (uint64_t)n, dst, slice)) != VV_OK) {
            vv_error_prefix(s, "slice %ld", z);
            goto fail;
        }
    }
    free(buf);
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
fail:
    free(buf);
    vv_volume_free(v);
    return s;
}

vv_status
vv_slc_read(vv_volume **out, const char *path) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "slc: NULL argument");
    *out = NULL;
    const char *name = vv_path_basename(path);
    slc_in in = {NULL, 0};
    vv_status s = vv_open_regular(path, &in.fp, &in.size);
    if (s != VV_OK)
        return vv_error_prefix(s, "slc: %s", name);
    s = slc_read_stream(out, &in);
    fclose(in.fp);
    if (s != VV_OK)
        return vv_error_prefix(s, "slc: %s", name);
    return VV_OK;
}

/* ---- writer ------------------------------------------------------------ */

/*
 * Run-length codes one slice into @p out (capacity at least len + len / 127
 * + 2). Repeat runs for three or more equal bytes, literal runs otherwise,
 * at most 127 per run, and a 0 byte at the end. Returns the byte count.
 */
static size_t
slc_rle_encode(const unsigned char *in, size_t len, unsigned char *out) {
    size_t ip = 0, op = 0;
    while (ip < len) {
        size_t r = 1;
        while (ip + r < len && r < 127 && in[ip + r] == in[ip])
            r++;
        if (r >= 3) {
            out[op++] = (unsigned char)r;
            out[op++] = in[ip];
            ip += r;
            continue;
        }
        /* Literal: extend until a run of three equal bytes starts. */
        size_t start = ip, k = 0;
        while (ip < len && k < 127) {
            if (ip + 2 < len && in[ip] == in[ip + 1] && in[ip] == in[ip + 2])
                break;
            ip++;
            k++;
        }
        out[op++] = (unsigned char)(0x80u | k);
        memcpy(out + op, in + start, k);
        op += k;
    }
    out[op++] = 0;
    return op;
}

/*
 * Icon: maximum intensity projection along z, reduced to at most
 * SLC_ICON_MAX pixels on its longer side (each icon pixel is the maximum
 * over the block of voxels it covers), stored grey as R, G and B planes.
 */
static vv_status
slc_make_icon(const vv_volume *v, int *w_out, int *h_out, unsigned char **icon_out) {
    int nx = v->dims[0], ny = v->dims[1], nz = v->dims[2];
    size_t slice = (size_t)nx * (size_t)ny;
    unsigned char *mip = calloc(slice, 1);
    if (!mip)
        return vv_error_set(VV_ERR_NOMEM, "cannot allocate the icon");
    const unsigned char *d = v->data;
    for (int z = 0; z < nz; z++) {
        const unsigned char *s = d + (size_t)z * slice;
        for (size_t i = 0; i < slice; i++)
            if (s[i] > mip[i])
                mip[i] = s[i];
    }
    int w = nx, h = ny;
    if (w > SLC_ICON_MAX || h > SLC_ICON_MAX) {
        if (nx >= ny) {
            w = SLC_ICON_MAX;
            h = (int)((double)ny * SLC_ICON_MAX / nx + 0.5);
        } else {
            h = SLC_ICON_MAX;
            w = (int)((double)nx * SLC_ICON_MAX / ny + 0.5);
        }
        if (w < 1)
            w = 1;
        if (h < 1)
            h = 1;
    }
    size_t plane = (size_t)w * (size_t)h;
    unsigned char *icon = malloc(3 * plane);
    if (!icon) {
        free(mip);
        return vv_error_set(VV_ERR_NOMEM, "cannot allocate the icon");
    }
    for (int y = 0; y < h; y++) {
        int y0 = (int)((int64_t)y * ny / h), y1 = (int)((int64_t)(y + 1) * ny / h);
        if (y1 <= y0)
            y1 = y0 + 1;
        for (int x = 0; x < w; x++) {
            int x0 = (int)((int64_t)x * nx / w), x1 = (int)((int64_t)(x + 1) * nx / w);
            if (x1 <= x0)
                x1 = x0 + 1;
            unsigned char m = 0;
            for (int yy = y0; yy < y1; yy++)
                for (int xx = x0; xx < x1; xx++)
                    if (mip[(size_t)yy * nx + xx] > m)
                        m = mip[(size_t)yy * nx + xx];
            icon[(size_t)y * w + x] = m;
        }
    }
    memcpy(icon + plane, icon, plane);
    memcpy(icon + 2 * plane, icon, plane);
    free(mip);
    *w_out = w;
    *h_out = h;
    *icon_out = icon;
    return VV_OK;
}

static vv_status
slc_write_stream(const vv_volume *v, FILE *fp, int rle) {
    /* Values outside SLC's enumerations are written as the nearest honest
       value: nanometres in microns (the spacing scaled), an unknown unit as
       millimetres, "other". */
    int unit = (int)v->unit, origin = (int)v->data_origin, mod = (int)v->modification;
    const double sp = unit == VV_UNIT_NM ? 1e-3 : 1;
    if (unit == VV_UNIT_NM)
        unit = VV_UNIT_MICRON;
    else if (unit < 0 || unit > 4)
        unit = VV_UNIT_MM;
    if (origin < 0 || origin > 7)
        origin = VV_ORIGIN_OTHER;
    if (mod < 0 || mod > 4)
        mod = VV_MOD_OTHER;
    int iw = 0, ih = 0;
    unsigned char *icon = NULL;
    vv_status s = slc_make_icon(v, &iw, &ih, &icon);
    if (s != VV_OK)
        return s;
    fprintf(fp, "%d\n%d %d %d 8\n%.17g %.17g %.17g\n%d %d %d %d\n%d %d X", SLC_MAGIC, v->dims[0],
            v->dims[1], v->dims[2], sp * v->spacing[0], sp * v->spacing[1], sp * v->spacing[2],
            unit, origin, mod, rle ? 1 : 0, iw, ih);
    fwrite(icon, 1, 3 * (size_t)iw * (size_t)ih, fp);
    free(icon);

    size_t slice = (size_t)v->dims[0] * (size_t)v->dims[1];
    const unsigned char *d = v->data;
    unsigned char *buf = NULL;
    if (rle) {
        buf = malloc(slice + slice / 127 + 2);
        if (!buf)
            return vv_error_set(VV_ERR_NOMEM, "cannot allocate a slice buffer");
    }
    for (int z = 0; z < v->dims[2]; z++) {
        const unsigned char *src = d + (size_t)z * slice;
        if (rle) {
            size_t n = slc_rle_encode(src, slice, buf);
            fprintf(fp, "%zu X", n);
            fwrite(buf, 1, n, fp);
        } else {
            fwrite(src, 1, slice, fp);
        }
        if (ferror(fp))
            break;
    }
    free(buf);
    if (ferror(fp))
        return vv_error_set(VV_ERR_IO, "write error: %s", strerror(errno));
    return VV_OK;
}

vv_status
vv_slc_write(const vv_volume *v, const char *path, int rle) {
    if (!v || !path || !v->data)
        return vv_error_set(VV_ERR_INVALID, "slc: NULL argument");
    const char *name = vv_path_basename(path);
    if (v->type != VV_U8)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "slc: %s: SLC holds 8-bit voxels only, the volume is %s", name,
                            vv_voxel_type_name(v->type));
    vv_status s = vv_volume_check_size(v->dims, v->type, NULL);
    if (s != VV_OK)
        return vv_error_prefix(s, "slc: %s", name);
    vv_atomic_file af;
    memset(&af, 0, sizeof af);
    if ((s = vv_atomic_file_open(&af, path)) != VV_OK)
        return vv_error_prefix(s, "slc: %s", name);
    if ((s = slc_write_stream(v, af.fp, rle)) != VV_OK) {
        vv_atomic_file_abort(&af);
        return vv_error_prefix(s, "slc: %s", name);
    }
    if ((s = vv_atomic_file_commit(&af)) != VV_OK)
        return vv_error_prefix(s, "slc: %s", name);
    return VV_OK;
}

/* ---- the format record ------------------------------------------------------ */

/* "11111" (the magic number) after optional white space. */
static int
slc_looks_like(const vv_format_probe *p, int deep) {
    if (deep || p->is_dir)
        return 0;
    size_t i = 0;
    while (i < p->n && isspace(p->head[i]))
        i++;
    return p->n - i >= 5 && !memcmp(p->head + i, "11111", 5);
}

static vv_status
slc_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    (void)opt;
    return vv_slc_read(out, path);
}

static int
slc_fits(const vv_volume *v, char *why, size_t cap) {
    if (v->type != VV_U8) {
        snprintf(why, cap, "SLC holds 8-bit voxels only, the volume is %s",
                 vv_voxel_type_name(v->type));
        return 0;
    }
    if (v->unit == VV_UNIT_NM) {
        snprintf(why, cap, "SLC holds no nanometres (the spacing is written in microns)");
        return 0;
    }
    return 1;
}

/* A u8 copy of @p v rescaled linearly from range[] to 0..255. */
static vv_status
to_u8(const vv_volume *v, vv_volume **out) {
    vv_volume *u = NULL;
    vv_status s = vv_volume_new(&u, v->dims, VV_U8);
    if (s != VV_OK)
        return s;
    memcpy(u->spacing, v->spacing, sizeof u->spacing);
    memcpy(u->origin, v->origin, sizeof u->origin);
    memcpy(u->direction, v->direction, sizeof u->direction);
    u->unit = v->unit;
    u->data_origin = v->data_origin;
    u->modification = VV_MOD_OTHER;
    double lo = v->range[0], hi = v->range[1];
    double scale = (hi > lo && isfinite(hi - lo)) ? 255.0 / (hi - lo) : 0;
    unsigned char *dst = u->data;
    uint64_t i = 0;
    for (int k = 0; k < v->dims[2]; k++)
        for (int j = 0; j < v->dims[1]; j++)
            for (int x = 0; x < v->dims[0]; x++, i++) {
                double val = vv_volume_get(v, x, j, k);
                double y = (val - lo) * scale;
                if (!(y > 0)) /* also NaN */
                    y = 0;
                if (y > 255)
                    y = 255;
                dst[i] = (unsigned char)lround(y);
            }
    vv_volume_update_range(u);
    *out = u;
    return VV_OK;
}

/* Run-length compressed unless asked otherwise; other voxel types rescaled
 * to 8 bits (vv_volume_save_with has refused them when strict). */
static vv_status
slc_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    const int rle = opt->compress != 0;
    if (v->type == VV_U8)
        return vv_slc_write(v, path, rle);
    vv_volume *u = NULL;
    vv_status s = to_u8(v, &u);
    if (s != VV_OK)
        return vv_error_prefix(s, "slc: %s", vv_path_basename(path));
    s = vv_slc_write(u, path, rle);
    vv_volume_free(u);
    return s;
}

static const char *const slc_extensions[] = {"slc", NULL};

const vv_format_record vv_format_slc = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "slc",
    .title = "SLC",
    .extensions = slc_extensions,
    .doc = "VolVis's slice format: 8-bit voxels, run-length compressed, voxel spacing",
    .looks_like = slc_looks_like,
    .fits = slc_fits,
    .read = slc_read_record,
    .write = slc_write_record,
};
