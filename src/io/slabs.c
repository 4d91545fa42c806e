/*
 * A volume read slab by slab (vv_slabs, volvis/io.h): boxes of a volume
 * larger than memory from a format whose reader decodes a range of slices
 * (VV_FORMAT_FLAG_SLICES: TIFF stacks), through vv_volume_load and so
 * through the reader sandbox; or from a gzip- or bzip2-encoded NRRD, whose
 * header Teem reads here as for the bricked reader and whose data zlib or
 * libbz2 decodes here as one stream, forward from slab to slab (back to its
 * start only when a box goes back). The slices of the last box are kept, so the boxes
 * of one slab that a writer asks for in turn (vv_ome_zarr_write_boxes: a
 * row of chunks at a time, every row of a slab before the next slab)
 * decode each slice once.
 */
#include <bzlib.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "core/internal.h"
#include "io/store/bricked_internal.h"
#include "volvis/io.h"

struct vv_slabs {
    char *path;
    vv_load_options opt; /* info NULL */
    vv_volume *header;   /* 1 x 1 x 1 voxels, dims set to the volume's */
    vv_volume *slab;     /* the slices z0 .. z0 + slab->dims[2] - 1, or NULL */
    int z0;
    uint64_t loads; /* slabs read */
    /* a compressed NRRD: its data stream (kind 1: gzip through gz; 2: bzip2
     * through bz over bzf, from data_off), the bytes decoded so far, the byte
     * order */
    int kind;
    gzFile gz;
    FILE *bzf;
    BZFILE *bz;
    int bz_error; /* libbz2's last error (BZ_OK: none) */
    int bz_end;   /* 1: the last stream ended and no other follows */
    uint64_t data_off;
    uint64_t at;
    int swap;
};

/* ---- the compressed data stream ---------------------------------------------- */

/* Opens the bzip2 reader at data_off (again). 0 or -1. */
static int
bz_open(vv_slabs *s) {
    int e = BZ_OK;
    if (fseeko(s->bzf, (off_t)s->data_off, SEEK_SET) != 0)
        return -1;
    s->bz = BZ2_bzReadOpen(&e, s->bzf, 0, 0, NULL, 0);
    s->bz_error = e;
    s->bz_end = 0;
    if (e != BZ_OK) {
        BZ2_bzReadClose(&e, s->bz);
        s->bz = NULL;
        return -1;
    }
    return 0;
}

/* Up to @p n decoded bytes into @p buf: the count (0 at the end) or -1. A
 * bzip2 stream followed by another (pbzip2 writes several) goes on into it. */
static int
stream_read(vv_slabs *s, void *buf, unsigned n) {
    if (s->kind == 1)
        return gzread(s->gz, buf, n);
    if (!s->bz)
        return s->bz_end ? 0 : -1;
    int e = BZ_OK;
    const int r = BZ2_bzRead(&e, s->bz, buf, (int)n);
    if (e == BZ_OK)
        return r;
    if (e != BZ_STREAM_END) {
        s->bz_error = e;
        return -1;
    }
    /* the end of a stream: another may follow in the bytes read ahead */
    void *unused = NULL;
    int nu = 0, e2 = BZ_OK;
    BZ2_bzReadGetUnused(&e2, s->bz, &unused, &nu);
    char rest[BZ_MAX_UNUSED];
    if (e2 == BZ_OK && nu > 0)
        memcpy(rest, unused, (size_t)nu);
    BZ2_bzReadClose(&e2, s->bz);
    s->bz = NULL;
    s->bz_end = 1;
    if (nu > 0 || !feof(s->bzf)) {
        int c = nu > 0 ? 1 : fgetc(s->bzf);
        if (nu == 0 && c != EOF)
            ungetc(c, s->bzf);
        if (c != EOF) {
            s->bz = BZ2_bzReadOpen(&e2, s->bzf, 0, 0, nu > 0 ? rest : NULL, nu);
            s->bz_error = e2;
            s->bz_end = 0;
            if (e2 != BZ_OK) {
                BZ2_bzReadClose(&e2, s->bz);
                s->bz = NULL;
                return r > 0 ? r : -1;
            }
            if (r == 0) /* nothing left of the last stream: read the next */
                return stream_read(s, buf, n);
        }
    }
    return r;
}

/* Back to the data's first byte. 0 or -1. */
static int
stream_rewind(vv_slabs *s) {
    if (s->kind == 1)
        return gzrewind(s->gz);
    int e = BZ_OK;
    if (s->bz)
        BZ2_bzReadClose(&e, s->bz);
    s->bz = NULL;
    return bz_open(s);
}

/* Why the stream stopped short: its library's words, or "truncated". */
static const char *
stream_why(vv_slabs *s) {
    if (s->kind == 1) {
        int zerr = Z_OK;
        const char *msg = gzerror(s->gz, &zerr);
        return zerr != Z_OK && msg && msg[0] ? msg : "truncated";
    }
    switch (s->bz_error) {
    case BZ_DATA_ERROR:
        return "bzip2 data integrity error";
    case BZ_DATA_ERROR_MAGIC:
        return "not bzip2 data";
    case BZ_MEM_ERROR:
        return "out of memory";
    case BZ_IO_ERROR:
        return "read error";
    default:
        return "truncated";
    }
}

static void
stream_close(vv_slabs *s) {
    if (s->gz)
        gzclose(s->gz);
    int e = BZ_OK;
    if (s->bz)
        BZ2_bzReadClose(&e, s->bz);
    if (s->bzf)
        fclose(s->bzf);
    s->gz = NULL;
    s->bz = NULL;
    s->bzf = NULL;
    s->kind = 0;
}

/* A gzip or bzip2 NRRD's header and data stream, or 0 when @p path is no
 * such NRRD (vv_volume_load then reads its slabs). -1: an error. */
static int
open_stream_nrrd(vv_slabs *s) {
    /* one 3-D volume: a channel or step of a compressed NRRD is read whole */
    if (s->opt.has_raw || s->opt.channel > 0 || s->opt.time > 0 ||
        vv_format_detect(s->path) != VV_FORMAT_NRRD)
        return 0;
    vv_volume *h = NULL;
    char *data = NULL;
    uint64_t off = 0;
    int big = 0, gzip = 1;
    vv_error_clear();
    if (vv_nrrd_data_layout(s->path, &h, &data, &off, &big, &gzip) != VV_OK || !gzip) {
        vv_volume_free(h);
        free(data);
        vv_error_clear(); /* raw NRRD and the rest: vv_volume_load's errors */
        return 0;
    }
    const int fd = open(data, O_RDONLY | O_CLOEXEC);
    int ok = fd >= 0 && lseek(fd, (off_t)off, SEEK_SET) == (off_t)off;
    if (ok && gzip == 1) {
        ok = (s->gz = gzdopen(fd, "rb")) != NULL;
        if (ok)
            gzbuffer(s->gz, 1 << 20);
    } else if (ok) {
        s->data_off = off;
        ok = (s->bzf = fdopen(fd, "rb")) != NULL && bz_open(s) == 0;
    }
    if (!ok) {
        const int e = errno;
        if (fd >= 0 && !s->gz && !s->bzf)
            close(fd);
        stream_close(s);
        vv_error_set(VV_ERR_IO, "slabs: %s: cannot open its data %s: %s", vv_path_basename(s->path),
                     vv_path_basename(data), e ? strerror(e) : "not a bzip2 stream");
        vv_volume_free(h);
        free(data);
        return -1;
    }
    free(data);
    s->kind = gzip;
    s->header = h;
    s->swap = big == vv_host_is_little_endian();
    return 1;
}

/* A compressed NRRD's data stream ended (or broke) inside slice @p z. */
static vv_status
stream_short(vv_slabs *s, int z) {
    return vv_error_set(VV_ERR_FORMAT, "the %s data ends before slice %d of %d (%s)",
                        s->kind == 1 ? "gzip" : "bzip2", z, s->header->dims[2], stream_why(s));
}

/* Slices z0 .. z0 + n - 1 of a compressed NRRD decoded into @p dst. */
static vv_status
read_stream_slices(vv_slabs *s, int z0, int n, unsigned char *dst) {
    const int *D = s->header->dims;
    const size_t es = vv_voxel_type_size(s->header->type);
    const uint64_t slice = (uint64_t)D[0] * (uint64_t)D[1] * es, from = (uint64_t)z0 * slice;
    if (from < s->at) { /* back: from the stream's start again */
        if (stream_rewind(s) != 0)
            return vv_error_set(VV_ERR_IO, "cannot rewind the %s data",
                                s->kind == 1 ? "gzip" : "bzip2");
        s->at = 0;
    }
    /* forward, inflating what lies between */
    unsigned char *skip = NULL;
    while (s->at < from) {
        if (!skip && !(skip = malloc(1 << 20)))
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        const uint64_t want = from - s->at < (1u << 20) ? from - s->at : (1u << 20);
        const int got = stream_read(s, skip, (unsigned)want);
        if (got <= 0)
            break;
        s->at += (uint64_t)got;
    }
    free(skip);
    if (s->at < from)
        return stream_short(s, (int)(s->at / slice));
    const uint64_t bytes = slice * (uint64_t)n;
    uint64_t done = 0;
    while (done < bytes) {
        const uint64_t want = bytes - done < (1u << 30) ? bytes - done : (1u << 30);
        const int got = stream_read(s, dst + done, (unsigned)want);
        if (got <= 0)
            break;
        done += (uint64_t)got;
        s->at += (uint64_t)got;
    }
    if (done != bytes)
        return stream_short(s, z0 + (int)(done / slice));
    if (s->swap && es > 1)
        vv_byteswap(dst, (uint64_t)D[0] * D[1] * (uint64_t)n, es);
    return VV_OK;
}

/* Slices lo .. hi as a new volume through vv_volume_load. */
static vv_status
load_slices(vv_slabs *s, int lo, int hi, vv_volume **out) {
    const int *D = s->header->dims;
    vv_load_options o = s->opt;
    o.z_first = lo;
    o.z_count = hi - lo + 1;
    vv_volume *v = NULL;
    vv_status st = vv_volume_load(&v, s->path, &o);
    if (st == VV_OK && (v->type != s->header->type || v->dims[0] != D[0] || v->dims[1] != D[1] ||
                        v->dims[2] != o.z_count))
        st = vv_error_set(VV_ERR_FORMAT, "slabs: %s: slices %d..%d read as %d x %d x %d %s",
                          vv_path_basename(s->path), lo, hi, v->dims[0], v->dims[1], v->dims[2],
                          vv_voxel_type_name(v->type));
    if (st != VV_OK) {
        vv_volume_free(v);
        return st;
    }
    *out = v;
    return VV_OK;
}

/* Slices lo .. hi read into @p dst: decoded here (a gzip or bzip2 NRRD) or
 * through vv_volume_load. */
static vv_status
read_slices(vv_slabs *s, int lo, int hi, unsigned char *dst) {
    if (s->kind) {
        vv_status st = read_stream_slices(s, lo, hi - lo + 1, dst);
        return st == VV_OK ? VV_OK : vv_error_prefix(st, "nrrd: %s", vv_path_basename(s->path));
    }
    vv_volume *v = NULL;
    vv_status st = load_slices(s, lo, hi, &v);
    if (st == VV_OK)
        memcpy(dst, v->data,
               (size_t)v->dims[0] * v->dims[1] * v->dims[2] * vv_voxel_type_size(v->type));
    vv_volume_free(v);
    return st;
}

/* Makes the slab held cover slices lo .. hi: the slices of the slab held
 * from lo on are kept when the box starts within it (the ghost slices the
 * next layer of .vvb bricks shares with the one before: a stream never
 * goes back for them), and the rest read; the buffer of a slab of as many
 * slices is reused. One slab at a time besides the one being filled. */
static vv_status
ensure_slab(vv_slabs *s, int lo, int hi) {
    vv_volume *old = s->slab;
    const int n = hi - lo + 1;
    if (old && lo >= s->z0 && hi < s->z0 + old->dims[2])
        return VV_OK;
    const int *D = s->header->dims;
    const size_t slice = (size_t)D[0] * (size_t)D[1] * vv_voxel_type_size(s->header->type);
    const int keep =
        old && lo >= s->z0 && lo < s->z0 + old->dims[2] ? s->z0 + old->dims[2] - lo : 0;
    vv_volume *v = NULL;
    vv_status st = VV_OK;
    s->slab = NULL;
    if (!s->kind && !keep) { /* the reader's volume is the slab (one at a time) */
        vv_volume_free(old);
        if ((st = load_slices(s, lo, hi, &v)) != VV_OK)
            return st;
    } else if (old && old->dims[2] == n && old->refcount == 1) {
        v = old; /* the same buffer: the kept slices moved to its start */
        if (keep)
            memmove(v->data, (unsigned char *)v->data + (size_t)(lo - s->z0) * slice,
                    (size_t)keep * slice);
        old = NULL;
    } else {
        if (!keep) { /* freed first: one slab at a time */
            vv_volume_free(old);
            old = NULL;
        }
        const int dims[3] = {D[0], D[1], n};
        st = vv_volume_new(&v, dims, s->header->type);
        if (st == VV_OK && keep)
            memcpy(v->data, (unsigned char *)old->data + (size_t)(lo - s->z0) * slice,
                   (size_t)keep * slice);
        vv_volume_free(old);
    }
    if (st == VV_OK && (s->kind || keep))
        st = read_slices(s, lo + keep, hi, (unsigned char *)v->data + (size_t)keep * slice);
    if (st != VV_OK) {
        vv_volume_free(v);
        return st;
    }
    s->slab = v;
    s->z0 = lo;
    s->loads++;
    return VV_OK;
}

vv_status
vv_slabs_open(vv_slabs **out, const char *path, const vv_load_options *opt) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "slabs: NULL argument");
    *out = NULL;
    vv_slabs *s = calloc(1, sizeof *s);
    if (!s || !(s->path = strdup(path))) {
        free(s);
        return vv_error_set(VV_ERR_NOMEM, "slabs: out of memory");
    }
    if (opt)
        s->opt = *opt;
    else
        vv_load_options_init(&s->opt);
    s->opt.info = NULL;
    const int g = open_stream_nrrd(s);
    if (g != 0) {
        vv_status st =
            g > 0 ? vv_volume_check_limits(s->header->dims, s->header->type, NULL) : VV_ERR_IO;
        if (st != VV_OK) {
            vv_slabs_free(s);
            return st;
        }
        *out = s;
        return VV_OK;
    }
    /* the geometry and the count of slices, from slice 0 */
    vv_load_info info;
    vv_load_options first = s->opt;
    first.z_first = 0;
    first.z_count = 1;
    first.info = &info;
    vv_volume *v = NULL;
    vv_status st = vv_volume_load(&v, path, &first);
    const int one[3] = {1, 1, 1};
    if (st == VV_OK)
        st = vv_volume_new(&s->header, one, v->type);
    if (st == VV_OK) {
        vv_volume *h = s->header;
        h->dims[0] = v->dims[0];
        h->dims[1] = v->dims[1];
        h->dims[2] = info.n_slices;
        memcpy(h->spacing, v->spacing, sizeof h->spacing);
        memcpy(h->origin, v->origin, sizeof h->origin);
        memcpy(h->direction, v->direction, sizeof h->direction);
        h->unit = v->unit;
        h->space = v->space;
        h->data_origin = v->data_origin;
        h->modification = v->modification;
        st = vv_volume_check_limits(h->dims, h->type, NULL);
    }
    vv_volume_free(v);
    if (st != VV_OK) {
        vv_slabs_free(s);
        return st;
    }
    *out = s;
    return VV_OK;
}

const vv_volume *
vv_slabs_header(const vv_slabs *s) {
    return s ? s->header : NULL;
}

uint64_t
vv_slabs_loads(const vv_slabs *s) {
    return s ? s->loads : 0;
}

vv_status
vv_slabs_read_box(void *slabs, const int lo[3], const int hi[3], vv_volume **out) {
    vv_slabs *s = slabs;
    if (!s || !lo || !hi || !out)
        return vv_error_set(VV_ERR_INVALID, "slabs: NULL argument");
    *out = NULL;
    const int *D = s->header->dims;
    for (int a = 0; a < 3; a++)
        if (lo[a] < 0 || hi[a] < lo[a] || hi[a] >= D[a])
            return vv_error_set(VV_ERR_INVALID, "slabs: %s: box %d..%d outside 0..%d on axis %d",
                                vv_path_basename(s->path), lo[a], hi[a], D[a] - 1, a);
    vv_status st = ensure_slab(s, lo[2], hi[2]);
    if (st != VV_OK)
        return st;
    const int dims[3] = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
    vv_volume *b = NULL;
    if ((st = vv_volume_new(&b, dims, s->header->type)) != VV_OK)
        return st;
    const size_t es = vv_voxel_type_size(b->type), row = (size_t)dims[0] * es;
    for (int k = 0; k < dims[2]; k++)
        for (int y = 0; y < dims[1]; y++) {
            const size_t src = (((size_t)(lo[2] + k - s->z0) * D[1] + (size_t)(lo[1] + y)) * D[0] +
                                (size_t)lo[0]) *
                               es;
            memcpy((char *)b->data + ((size_t)k * dims[1] + (size_t)y) * row,
                   (const char *)s->slab->data + src, row);
        }
    for (int a = 0; a < 3; a++) {
        b->spacing[a] = s->header->spacing[a];
        b->origin[a] = s->header->origin[a];
        for (int c = 0; c < 3; c++)
            b->origin[a] += s->header->direction[3 * a + c] * lo[c] * s->header->spacing[c];
    }
    memcpy(b->direction, s->header->direction, sizeof b->direction);
    b->unit = s->header->unit;
    b->space = s->header->space;
    vv_volume_update_range(b);
    *out = b;
    return VV_OK;
}

void
vv_slabs_free(vv_slabs *s) {
    if (!s)
        return;
    vv_volume_free(s->slab);
    vv_volume_free(s->header);
    stream_close(s);
    free(s->path);
    free(s);
}
