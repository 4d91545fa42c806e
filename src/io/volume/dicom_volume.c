/*
 * One DICOM series into a volume (its files found, read and grouped by
 * dicom.c, dicom_scan.h): the slices ordered along the slice normal, time
 * steps picked, the spacing checked, the voxel type chosen and every
 * frame's pixel values read and converted.
 *
 * Geometry (DICOM PS3.3 C.7.6.2): Image Orientation (Patient) gives the row
 * direction r (along which the column index i grows) and the column
 * direction c (j); the slice normal is n = r x c. Each slice's position d is
 * n . Image Position (Patient); slices are sorted by d. The k axis is n, or
 * the direction from the first to the last slice when the stack is sheared
 * (gantry tilt). The spacing is the median step; a step that is a multiple of
 * it is a missing slice, any other difference over 1 % uneven spacing, and a
 * step of zero two slices at one place: all errors naming both files.
 * Coordinates are DICOM's LPS converted to RAS (x and y negated), as the
 * NIfTI reader's world is RAS.
 *
 * Pixel values: the stored integers (Bits Stored masked, sign-extended when
 * Pixel Representation is 1) times Rescale Slope plus Rescale Intercept.
 *
 * Files are read in parallel (OpenMP, one GDCM reader per file); an
 * uncompressed file's pixel data straight from the file where its layout
 * allows.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "core/internal.h"
#include "io/volume/dicom.h"
#include "io/volume/dicom_scan.h"
#include "volvis/io.h"

#ifdef VV_HAVE_GDCM

/* ---- one series into a volume ---------------------------------------------- */

/* One slice: a frame of a file, at position d along the normal. */
typedef struct slice_ref {
    int file; /* index into sc->f */
    int frame;
    double d;
    double p[3];
    int instance;
    int temporal;   /* Temporal Position Identifier, 0 none */
    double trigger; /* Trigger Time (ms), or the instance number when there is none */
} slice_ref;

/* Along the normal, then, at one position, in time: Temporal Position
 * Identifier, Trigger Time, Instance Number, frame. */
static int
cmp_slice(const void *a, const void *b) {
    const slice_ref *x = a, *y = b;
    if (x->d != y->d)
        return x->d < y->d ? -1 : 1;
    if (x->temporal != y->temporal)
        return x->temporal < y->temporal ? -1 : 1;
    if (x->trigger != y->trigger)
        return x->trigger < y->trigger ? -1 : 1;
    if (x->instance != y->instance)
        return x->instance < y->instance ? -1 : 1;
    return x->frame - y->frame;
}

/* Positions closer than this (mm along the normal) are one place. */
#define DCM_SAME_PLACE 1e-4

/* Of n images at the sorted places d(0) <= d(1) <= ... (d(i) the double at
 * @p base + i * @p stride bytes): the number T of images at every place
 * when each place holds the same T; 1 when one each, 0 when the counts
 * differ. */
static int
images_per_place(const void *base, size_t stride, int n) {
#define DCM_D(i) (*(const double *)(const void *)((const char *)base + (size_t)(i)*stride))
    int run = 1;
    while (run < n && DCM_D(run) - DCM_D(0) < DCM_SAME_PLACE)
        run++;
    if (run < 2)
        return 1;
    if (n % run != 0)
        return 0;
    for (int z = 0; z < n; z += run)
        if (DCM_D(z + run - 1) - DCM_D(z) >= DCM_SAME_PLACE ||
            (z + run < n && DCM_D(z + run) - DCM_D(z + run - 1) < DCM_SAME_PLACE))
            return 0;
    return run;
#undef DCM_D
}

/*
 * A time series (a cardiac cine, a perfusion or 4-D CT series: several
 * images at each position, DICOM PS3.3 C.7.6.2 and C.8.3.1): when the
 * sorted @p refs come in runs of one position and every run has the same
 * length T > 1, the series has T time steps and *@p nz becomes the count of
 * positions, refs[k] the image of step @p time at position k (in run order:
 * Temporal Position Identifier, Trigger Time, Instance Number); *@p nt = T
 * and *@p step_s the time between steps in seconds from the first
 * position's trigger times (0 when unknown). Runs of unequal length are left
 * for order_slices to name (two images at one place). Errors: a step out of
 * range.
 */
static vv_status
pick_time_step(const dicom_scan *sc, slice_ref *refs, int *nz, int time, int *nt, double *step_s) {
    *nt = 1;
    *step_s = 0;
    const int run = images_per_place(&refs[0].d, sizeof *refs, *nz);
    if (run < 2)
        return time <= 0 ? VV_OK
               : run     ? vv_error_set(VV_ERR_INVALID,
                                        "time step %d asked, the series has one time step", time)
                         : vv_error_set(VV_ERR_INVALID,
                                        "time step %d asked, but the series' positions hold "
                                            "different numbers of images",
                                        time);
    if (time < 0 || time >= run)
        return vv_error_set(VV_ERR_INVALID, "time step %d asked, the series has %d", time, run);
    const vv_dcm_file *f0 = &sc->f[refs[0].file], *f1 = &sc->f[refs[1].file];
    if (f0->has_trigger && f1->has_trigger && refs[1].trigger > refs[0].trigger)
        *step_s = (refs[1].trigger - refs[0].trigger) / 1000.0;
    const int n = *nz / run;
    for (int k = 0; k < n; k++)
        refs[k] = refs[k * run + time];
    *nz = n;
    *nt = run;
    return VV_OK;
}

static void
cross(const double a[3], const double b[3], double out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double
dot(const double a[3], const double b[3]) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static int
cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* "FILE" or "frame N of FILE" for messages. */
static const char *
slice_name(const dicom_scan *sc, const slice_ref *r, char *buf, size_t cap) {
    const vv_dcm_file *f = &sc->f[r->file];
    if (f->frames > 1)
        snprintf(buf, cap, "frame %d of %s", r->frame + 1, f->path);
    else
        snprintf(buf, cap, "%s", f->path);
    return buf;
}

/* Orders @p refs, keeps time step @p time's (pick_time_step: *@p nz, *@p nt,
 * *@p step_s) and sets the volume's geometry, or errors on gaps. */
static vv_status
order_slices(const dicom_scan *sc, slice_ref *refs, int *nz_io, const vv_dcm_file *f0, int time,
             int *nt, double *step_s, vv_volume *v) {
    int nz = *nz_io;
    int geo = f0->has_iop;
    for (int z = 0; z < nz && geo; z++) {
        const vv_dcm_file *f = &sc->f[refs[z].file];
        if (!(f->has_iop && (f->has_ipp || f->frame_ipp)))
            geo = 0;
    }
    double r[3] = {1, 0, 0}, c[3] = {0, 1, 0}, nrm[3] = {0, 0, 1};
    if (geo) {
        memcpy(r, f0->iop, sizeof r);
        memcpy(c, f0->iop + 3, sizeof c);
        double lr = sqrt(dot(r, r)), lc = sqrt(dot(c, c));
        if (!(lr > 0.5 && lc > 0.5 && fabs(dot(r, c)) < 1e-2 * lr * lc))
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: Image Orientation (Patient) is not two orthogonal "
                                "directions",
                                f0->path);
        for (int i = 0; i < 3; i++) {
            r[i] /= lr;
            c[i] /= lc;
        }
        cross(r, c, nrm);
        for (int z = 0; z < nz; z++) {
            const vv_dcm_file *f = &sc->f[refs[z].file];
            for (int i = 0; i < 6; i++)
                if (fabs(f->iop[i] - f0->iop[i]) > 1e-3)
                    return vv_error_set(VV_ERR_FORMAT,
                                        "%s: Image Orientation (Patient) differs from %s's (a "
                                        "series of several orientations)",
                                        f->path, f0->path);
            if (f->frame_ipp) {
                memcpy(refs[z].p, f->frame_ipp + 3 * refs[z].frame, sizeof refs[z].p);
            } else {
                /* frames without positions (RT dose, ultrasound): stacked
                 * along the normal at GDCM's frame spacing */
                double step = f->frame_spacing > 0 ? f->frame_spacing : 1;
                for (int i = 0; i < 3; i++)
                    refs[z].p[i] = f->ipp[i] + refs[z].frame * step * nrm[i];
            }
            refs[z].d = dot(nrm, refs[z].p);
        }
    } else {
        for (int z = 0; z < nz; z++)
            refs[z].d = (double)sc->f[refs[z].file].instance_number * 1e6 + refs[z].frame;
    }
    qsort(refs, (size_t)nz, sizeof *refs, cmp_slice);
    *nt = 1;
    *step_s = 0;
    if (geo) {
        vv_status s = pick_time_step(sc, refs, &nz, time, nt, step_s);
        if (s != VV_OK)
            return s;
        *nz_io = nz;
    } else if (time > 0) {
        return vv_error_set(VV_ERR_INVALID,
                            "time step %d asked, the series has one time step (its images have "
                            "no positions)",
                            time);
    }

    double dz = 1, kaxis[3];
    memcpy(kaxis, nrm, sizeof kaxis);
    if (!geo) {
        if (f0->frames > 1 && f0->frame_spacing > 0)
            dz = f0->frame_spacing;
    } else if (nz > 1) {
        double *steps = malloc((size_t)(nz - 1) * sizeof *steps);
        if (!steps)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        for (int z = 0; z + 1 < nz; z++)
            steps[z] = refs[z + 1].d - refs[z].d;
        qsort(steps, (size_t)(nz - 1), sizeof *steps, cmp_double);
        double med = steps[(nz - 1) / 2];
        free(steps);
        char a[1100], b[1100];
        for (int z = 0; z + 1 < nz; z++) {
            double step = refs[z + 1].d - refs[z].d;
            if (step < DCM_SAME_PLACE)
                return vv_error_set(VV_ERR_FORMAT,
                                    "%s and %s are at the same position (%.4g mm along the "
                                    "normal): several acquisitions in one series? (a time "
                                    "series has as many images at every position)",
                                    slice_name(sc, &refs[z], a, sizeof a),
                                    slice_name(sc, &refs[z + 1], b, sizeof b), refs[z].d);
        }
        for (int z = 0; z + 1 < nz; z++) {
            double step = refs[z + 1].d - refs[z].d;
            if (fabs(step - med) <= fmax(0.01 * med, 1e-3))
                continue;
            double k = round(step / med);
            if (k >= 2 && fabs(step - k * med) <= 0.05 * med)
                return vv_error_set(
                    VV_ERR_FORMAT,
                    "missing slice%s: a gap of %.4g mm between %s (at %.4g mm) and %s (at %.4g "
                    "mm) where slices are %.4g mm apart (%d slice%s missing)",
                    k > 2 ? "s" : "", step, slice_name(sc, &refs[z], a, sizeof a), refs[z].d,
                    slice_name(sc, &refs[z + 1], b, sizeof b), refs[z + 1].d, med, (int)k - 1,
                    k > 2 ? "s" : "");
            return vv_error_set(VV_ERR_FORMAT,
                                "uneven slice spacing: %.4g mm between %s and %s where slices "
                                "are %.4g mm apart",
                                step, slice_name(sc, &refs[z], a, sizeof a),
                                slice_name(sc, &refs[z + 1], b, sizeof b), med);
        }
        dz = med;
        /* a sheared stack (gantry tilt): the k axis goes from slice to slice */
        double span[3];
        for (int i = 0; i < 3; i++)
            span[i] = refs[nz - 1].p[i] - refs[0].p[i];
        double ls = sqrt(dot(span, span));
        if (ls > 0 && dot(span, nrm) / ls < cos(1e-3)) {
            for (int i = 0; i < 3; i++)
                kaxis[i] = span[i] / ls;
            dz = ls / (nz - 1);
        }
    }
    if (geo) {
        /* DICOM's LPS to RAS: x and y change sign */
        static const double flip[3] = {-1, -1, 1};
        for (int i = 0; i < 3; i++) {
            v->direction[i * 3 + 0] = flip[i] * r[i] + 0.0;
            v->direction[i * 3 + 1] = flip[i] * c[i] + 0.0;
            v->direction[i * 3 + 2] = flip[i] * kaxis[i] + 0.0;
            v->origin[i] = flip[i] * refs[0].p[i] + 0.0;
        }
        v->space = VV_SPACE_RAS;
    }
    v->spacing[0] = f0->has_spacing && f0->pixel_spacing[1] > 0 ? f0->pixel_spacing[1] : 1;
    v->spacing[1] = f0->has_spacing && f0->pixel_spacing[0] > 0 ? f0->pixel_spacing[0] : 1;
    v->spacing[2] = dz > 0 ? dz : 1;
    v->unit = VV_UNIT_MM;
    return VV_OK;
}

/* Stored integer range of @p f (Bits Stored, Pixel Representation). */
static void
stored_range(const vv_dcm_file *f, double *lo, double *hi) {
    int bs = f->bits_stored > 0 && f->bits_stored <= f->bits_allocated ? f->bits_stored
                                                                       : f->bits_allocated;
    if (f->pixel_rep) {
        *lo = -ldexp(1, bs - 1);
        *hi = ldexp(1, bs - 1) - 1;
    } else {
        *lo = 0;
        *hi = ldexp(1, bs) - 1;
    }
}

static vv_voxel_type
output_type(const dicom_scan *sc, const slice_ref *refs, int nz) {
    const vv_dcm_file *f0 = &sc->f[refs[0].file];
    int integral = 1, identity = 1;
    double lo = INFINITY, hi = -INFINITY;
    for (int z = 0; z < nz; z++) {
        const vv_dcm_file *f = &sc->f[refs[z].file];
        if (f->slope != 1 || f->intercept != round(f->intercept))
            integral = 0;
        if (f->slope != 1 || f->intercept != 0)
            identity = 0;
        double a, b;
        stored_range(f, &a, &b);
        a = a * f->slope + f->intercept;
        b = b * f->slope + f->intercept;
        lo = fmin(lo, fmin(a, b));
        hi = fmax(hi, fmax(a, b));
    }
    int ba = f0->bits_allocated;
    if (identity)
        return ba == 8    ? (f0->pixel_rep ? VV_I8 : VV_U8)
               : ba == 16 ? (f0->pixel_rep ? VV_I16 : VV_U16)
                          : (f0->pixel_rep ? VV_I32 : VV_U32);
    if (integral) {
        if (lo >= 0 && hi <= 255 && ba == 8)
            return VV_U8;
        if (lo >= 0 && hi <= 65535)
            return VV_U16;
        if (lo >= -32768 && hi <= 32767)
            return VV_I16;
        if (lo >= -2147483648.0 && hi <= 2147483647.0)
            return VV_I32;
    }
    return ba == 32 ? VV_F64 : VV_F32;
}

/* Stored sample @p idx of @p src as an integer (masked, sign-extended). */
static inline int64_t
stored_at(const unsigned char *src, size_t idx, int ba, int bs, int sign) {
    int64_t x;
    if (ba == 8)
        x = src[idx];
    else if (ba == 16) {
        uint16_t u;
        memcpy(&u, src + 2 * idx, 2);
        x = u;
    } else {
        uint32_t u;
        memcpy(&u, src + 4 * idx, 4);
        x = u;
    }
    if (bs < ba) {
        x &= ((int64_t)1 << bs) - 1;
        if (sign && (x >> (bs - 1)) & 1)
            x -= (int64_t)1 << bs;
    } else if (sign) {
        if (ba == 8)
            x = (int8_t)x;
        else if (ba == 16)
            x = (int16_t)x;
        else
            x = (int32_t)x;
    }
    return x;
}

/* Frame @p frame, sample @p ch of the decoded pixels @p src of @p f into slice @p dst. */
static void
convert_frame(const vv_dcm_file *f, const unsigned char *src, int frame, int ch, vv_voxel_type t,
              void *dst) {
    size_t np = (size_t)f->rows * (size_t)f->cols;
    int ba = f->bits_allocated, spp = f->samples;
    int bs = f->bits_stored > 0 && f->bits_stored <= ba ? f->bits_stored : ba;
    size_t base, step;
    if (spp > 1 && f->planar) {
        base = ((size_t)frame * spp + (size_t)ch) * np;
        step = 1;
    } else {
        base = (size_t)frame * np * spp + (size_t)ch;
        step = (size_t)spp;
    }
    double slope = f->slope, inter = f->intercept;
    /* the common case: 16-bit samples, integer output */
    if (ba == 16 && step == 1 && (t == VV_I16 || t == VV_U16) && slope == 1) {
        const unsigned char *s = src + 2 * base;
        int32_t off = (int32_t)inter;
        uint16_t mask = (uint16_t)((1u << bs) - 1);
        int sign = f->pixel_rep;
        uint16_t sbit = (uint16_t)(1u << (bs - 1));
        uint16_t *o = dst;
        for (size_t i = 0; i < np; i++) {
            uint16_t u;
            memcpy(&u, s + 2 * i, 2);
            int32_t x = u & mask;
            if (sign && (x & sbit))
                x -= (int32_t)mask + 1;
            o[i] = (uint16_t)(x + off);
        }
        return;
    }
    for (size_t i = 0; i < np; i++) {
        int64_t x = stored_at(src, base + i * step, ba, bs, f->pixel_rep);
        switch (t) {
        case VV_U8:
            ((uint8_t *)dst)[i] = (uint8_t)(x + (int64_t)inter);
            break;
        case VV_I8:
            ((int8_t *)dst)[i] = (int8_t)(x + (int64_t)inter);
            break;
        case VV_U16:
            ((uint16_t *)dst)[i] = (uint16_t)(x + (int64_t)inter);
            break;
        case VV_I16:
            ((int16_t *)dst)[i] = (int16_t)(x + (int64_t)inter);
            break;
        case VV_U32:
            ((uint32_t *)dst)[i] = (uint32_t)(x + (int64_t)inter);
            break;
        case VV_I32:
            ((int32_t *)dst)[i] = (int32_t)(x + (int64_t)inter);
            break;
        case VV_F32:
            ((float *)dst)[i] = (float)((double)x * slope + inter);
            break;
        case VV_F64:
            ((double *)dst)[i] = (double)x * slope + inter;
            break;
        }
    }
}

/*
 * Where the uncompressed Pixel Data value of @p f starts. Returns 1 with
 * *@p start when it was found and agrees with GDCM (the element's end is
 * where GDCM's reading of the file ended), 0 when the file is too short for
 * @p need bytes (*@p have gets the bytes there), 2 when it cannot tell. The
 * element is looked for in the first 64 KiB as its tag (7FE0,0010), either
 * byte order, with an explicit OB/OW or an implicit length of at least
 * @p need: a check of sizes and an offset for reading native voxels
 * straight into the volume; the parsing is GDCM's.
 */
static int
native_pixels(const vv_dcm_file *f, uint64_t need, uint64_t *start_out, uint64_t *have) {
    struct stat st;
    if (stat(f->path, &st) != 0)
        return 2;
    uint64_t size = (uint64_t)st.st_size;
    if (size < need) {
        *have = size;
        return 0;
    }
    FILE *fp = fopen(f->path, "rb");
    if (!fp)
        return 2;
    unsigned char buf[65536];
    size_t n = fread(buf, 1, sizeof buf, fp);
    fclose(fp);
    for (size_t i = 0; i + 12 <= n; i++) {
        int le = buf[i] == 0xe0 && buf[i + 1] == 0x7f && buf[i + 2] == 0x10 && buf[i + 3] == 0;
        int be = buf[i] == 0x7f && buf[i + 1] == 0xe0 && buf[i + 2] == 0 && buf[i + 3] == 0x10;
        if (!le && !be)
            continue;
        const unsigned char *p = buf + i + 4;
        uint64_t len, start;
        if ((p[0] == 'O' && (p[1] == 'W' || p[1] == 'B')) && p[2] == 0 && p[3] == 0) {
            p += 4;
            start = i + 12;
        } else {
            start = i + 8;
        }
        len =
            le ? (uint64_t)p[0] | (uint64_t)p[1] << 8 | (uint64_t)p[2] << 16 | (uint64_t)p[3] << 24
               : (uint64_t)p[3] | (uint64_t)p[2] << 8 | (uint64_t)p[1] << 16 | (uint64_t)p[0] << 24;
        if (len == 0xffffffffu || len < need)
            continue;
        if (size < start + need) {
            *have = size > start ? size - start : 0;
            return 0;
        }
        *start_out = start;
        return f->pixel_end >= 0 && (uint64_t)f->pixel_end == start + len ? 1 : 2;
    }
    return 2;
}

/* Min and max of @p n voxels of type @p t at @p p (NaN skipped), folded into lo/hi. */
static void
slice_range(vv_voxel_type t, const void *p, size_t n, double *lo, double *hi) {
#define VV_DCM_RANGE(T)                                                                            \
    do {                                                                                           \
        const T *q = p;                                                                            \
        T a = q[0], b = q[0];                                                                      \
        for (size_t i = 1; i < n; i++) {                                                           \
            a = q[i] < a ? q[i] : a;                                                               \
            b = q[i] > b ? q[i] : b;                                                               \
        }                                                                                          \
        if ((double)a < *lo)                                                                       \
            *lo = (double)a;                                                                       \
        if ((double)b > *hi)                                                                       \
            *hi = (double)b;                                                                       \
    } while (0)
    switch (t) {
    case VV_U8:
        VV_DCM_RANGE(uint8_t);
        break;
    case VV_I8:
        VV_DCM_RANGE(int8_t);
        break;
    case VV_U16:
        VV_DCM_RANGE(uint16_t);
        break;
    case VV_I16:
        VV_DCM_RANGE(int16_t);
        break;
    case VV_U32:
        VV_DCM_RANGE(uint32_t);
        break;
    case VV_I32:
        VV_DCM_RANGE(int32_t);
        break;
    case VV_F32:
    case VV_F64: {
        for (size_t i = 0; i < n; i++) {
            double x = vv_voxel_value(t, p, i);
            if (x < *lo)
                *lo = x;
            if (x > *hi)
                *hi = x;
        }
        break;
    }
    }
#undef VV_DCM_RANGE
}

/* The files a..b of a series agree (size, samples, bits; no multi-frame
 * file among others) and make a volume within the limits: its dims and the
 * slice count in *@p nz, the channel in *@p ch. */
static vv_status
check_series(const dicom_scan *sc, int a, int b, int channel, int dims[3], long *nz, int *ch) {
    const int nfiles = b - a;
    const vv_dcm_file *f0 = &sc->f[sc->order[a]];
    *nz = 0;
    for (int i = a; i < b; i++) {
        const vv_dcm_file *f = &sc->f[sc->order[i]];
        if (f->frames > 1 && nfiles > 1)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "%s: a multi-frame file in a series of %d files (read it alone)",
                                f->path, nfiles);
        if (f->rows != f0->rows || f->cols != f0->cols || f->samples != f0->samples ||
            f->bits_allocated != f0->bits_allocated || f->pixel_rep != f0->pixel_rep)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: %d x %d pixels of %d x %d bits, %s has %d x %d of %d x %d "
                                "bits (mixed images in one series)",
                                f->path, f->cols, f->rows, f->samples, f->bits_allocated, f0->path,
                                f0->cols, f0->rows, f0->samples, f0->bits_allocated);
        *nz += f->frames;
    }
    if (f0->bits_allocated != 8 && f0->bits_allocated != 16 && f0->bits_allocated != 32)
        return vv_error_set(VV_ERR_UNSUPPORTED, "%s: %d bits allocated (8, 16 or 32 supported)",
                            f0->path, f0->bits_allocated);
    if (f0->samples < 1 || f0->samples > 4)
        return vv_error_set(VV_ERR_FORMAT, "%s: %d samples per pixel", f0->path, f0->samples);
    *ch = channel < 0 ? 0 : channel;
    if (*ch >= f0->samples)
        return vv_error_set(VV_ERR_INVALID, "%s: channel %d asked, the images have %d", f0->path,
                            *ch, f0->samples);
    if (*nz > VV_VOLUME_MAX_DIM || f0->rows < 1 || f0->cols < 1)
        return vv_error_set(VV_ERR_LIMIT, "%s: %d x %d pixels x %ld slices (limit %d per side)",
                            f0->path, f0->cols, f0->rows, *nz, VV_VOLUME_MAX_DIM);
    dims[0] = f0->cols;
    dims[1] = f0->rows;
    dims[2] = (int)*nz;
    vv_status s = vv_volume_check_size(dims, VV_F64, NULL);
    if (s != VV_OK)
        return vv_error_prefix(s, "%s", f0->path);
    return VV_OK;
}

/* Uncompressed pixel data must fit in the file: a cheap check for
 * truncated files and absurd sizes before anything is allocated (GDCM reads
 * a short Pixel Data element without complaint, zero-filled). Also where
 * the value starts, for reading native voxels straight into the volume:
 * direct[i - a] = start + 1, or 0 to read through GDCM (calloc'ed). */
static vv_status
plan_direct_reads(const dicom_scan *sc, int a, int b, uint64_t frame_bytes, uint64_t **direct_out) {
    uint64_t *direct = calloc((size_t)(b - a), sizeof *direct);
    if (!direct)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = a; i < b; i++) {
        const vv_dcm_file *f = &sc->f[sc->order[i]];
        if (f->encapsulated)
            continue;
        uint64_t need = frame_bytes * (uint64_t)f->frames, have = 0, start = 0;
        int r = native_pixels(f, need, &start, &have);
        if (r == 0) {
            free(direct);
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: truncated pixel data: %d x %d x %d pixels of %d bits need "
                                "%llu bytes, the file holds %llu",
                                f->path, f->cols, f->rows, f->frames, f->bits_allocated,
                                (unsigned long long)need, (unsigned long long)have);
        }
        if (r == 1 && f->native_le && f->frames == 1 && f->samples == 1 &&
            vv_host_is_little_endian())
            direct[i - a] = start + 1;
    }
    *direct_out = direct;
    return VV_OK;
}

/* What the parallel read of a series' pixels shares. */
typedef struct series_read {
    const dicom_scan *sc;
    int a, b, ch;
    long nz;
    const slice_ref *refs;
    const uint64_t *direct; /* plan_direct_reads */
    const long *slot;       /* the slice of each file's first frame, -1 none */
    uint64_t frame_bytes;
    vv_volume *v;
} series_read;

/* Reads every file's pixels into its slices of the volume (in parallel),
 * rescaled; the value range in *lo, *hi. The first file that fails (in
 * series order, whatever the threads did) is named in the error. */
static vv_status
read_pixels(const series_read *R, double *lo_out, double *hi_out) {
    const dicom_scan *sc = R->sc;
    vv_volume *v = R->v;
    const vv_voxel_type t = v->type;
    const vv_dcm_file *f0 = &sc->f[sc->order[R->a]];
    const size_t slice_bytes = (size_t)f0->rows * f0->cols * vv_voxel_type_size(t);
    const size_t np = (size_t)f0->rows * f0->cols;
    const int same_size = vv_voxel_type_size(t) * 8 == (size_t)f0->bits_allocated;
    int failed = -1;
    char err[256] = "";
    double lo = INFINITY, hi = -INFINITY;
    vv_dcm_init();
#pragma omp parallel
    {
        unsigned char *buf = NULL;
        size_t cap = 0;
        double tlo = INFINITY, thi = -INFINITY;
#pragma omp for schedule(dynamic, 2)
        for (int i = R->a; i < R->b; i++) {
            const vv_dcm_file *f = &sc->f[sc->order[i]];
            if (f->frames == 1 && R->slot[i - R->a] < 0)
                continue; /* an image of another time step */
            size_t need = (size_t)(R->frame_bytes * (uint64_t)f->frames);
            char e[256] = "";
            int bad = 0;
            if (R->direct[i - R->a] && same_size && R->slot[i - R->a] >= 0) {
                /* native little-endian voxels: read in place, rescale in place */
                unsigned char *dst =
                    (unsigned char *)v->data + (size_t)R->slot[i - R->a] * slice_bytes;
                FILE *fp = fopen(f->path, "rb");
                if (!fp || fseeko(fp, (off_t)(R->direct[i - R->a] - 1), SEEK_SET) != 0 ||
                    fread(dst, 1, need, fp) != need) {
                    snprintf(e, sizeof e, "cannot read the pixel data: %s",
                             fp ? "file truncated" : strerror(errno));
                    bad = 1;
                } else {
                    convert_frame(f, dst, 0, 0, t, dst);
                    slice_range(t, dst, np, &tlo, &thi);
                }
                if (fp)
                    fclose(fp);
            } else {
                if (need > cap) {
                    free(buf);
                    buf = malloc(need);
                    cap = buf ? need : 0;
                }
                if (!buf) {
                    snprintf(e, sizeof e, "out of memory for %zu bytes", need);
                    bad = 1;
                } else if (vv_dcm_read_pixels(f->path, buf, need, e, sizeof e) != 0) {
                    bad = 1;
                } else {
                    for (long k = 0; k < R->nz; k++)
                        if (R->refs[k].file == sc->order[i]) {
                            unsigned char *dst = (unsigned char *)v->data + (size_t)k * slice_bytes;
                            convert_frame(f, buf, R->refs[k].frame, R->ch, t, dst);
                            slice_range(t, dst, np, &tlo, &thi);
                        }
                }
            }
            if (bad) {
#pragma omp critical(vv_dicom_err)
                if (failed < 0 || i < failed) {
                    failed = i;
                    snprintf(err, sizeof err, "%s", e);
                }
            }
        }
        free(buf);
#pragma omp critical(vv_dicom_range)
        {
            lo = fmin(lo, tlo);
            hi = fmax(hi, thi);
        }
    }
    *lo_out = lo;
    *hi_out = hi;
    if (failed < 0)
        return VV_OK;
    const char *fp = sc->f[sc->order[failed]].path;
    /* the decoder's message may already begin with the file's name */
    if (strncmp(err, fp, strlen(fp)) == 0)
        return vv_error_set(VV_ERR_FORMAT, "%s", err);
    return vv_error_set(VV_ERR_FORMAT, "%s: %s", fp, err);
}

vv_status
dicom_read_series(vv_volume **out, const dicom_scan *sc, int si, int channel, int time,
                  vv_load_info *info) {
    int a = sc->start[si], b = sc->start[si + 1];
    const vv_dcm_file *f0 = &sc->f[sc->order[a]];
    int dims[3] = {0, 0, 0}, ch = 0;
    long nz = 0;
    vv_status s = check_series(sc, a, b, channel, dims, &nz, &ch);
    if (s != VV_OK)
        return s;
    /* the decoded size of each file, checked before any allocation */
    uint64_t frame_bytes =
        (uint64_t)f0->rows * (uint64_t)f0->cols * (uint64_t)f0->samples * (f0->bits_allocated / 8);
    uint64_t *direct = NULL;
    if ((s = plan_direct_reads(sc, a, b, frame_bytes, &direct)) != VV_OK)
        return s;
    slice_ref *refs = calloc((size_t)nz, sizeof *refs);
    long *slot = malloc((size_t)(b - a) * sizeof *slot);
    vv_volume *v = NULL, *geo = NULL;
    if (!refs || !slot) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    long z = 0;
    for (int i = a; i < b; i++) {
        const vv_dcm_file *f = &sc->f[sc->order[i]];
        for (int fr = 0; fr < f->frames; fr++, z++) {
            refs[z].file = sc->order[i];
            refs[z].frame = fr;
            refs[z].instance = f->instance_number;
            refs[z].temporal = f->temporal_position;
            refs[z].trigger = f->has_trigger ? f->trigger_time : f->instance_number;
        }
    }
    vv_voxel_type t = output_type(sc, refs, (int)nz);
    /* the geometry, and of a time series the one step's slices, first: the
     * volume has that many */
    int nzi = (int)nz, nt = 1;
    double step_s = 0;
    if ((s = vv_volume_new(&geo, (const int[3]){1, 1, 1}, t)) != VV_OK ||
        (s = order_slices(sc, refs, &nzi, f0, time, &nt, &step_s, geo)) != VV_OK)
        goto done;
    nz = nzi;
    dims[2] = nzi;
    if ((s = vv_volume_new(&v, dims, t)) != VV_OK)
        goto done;
    memcpy(v->spacing, geo->spacing, sizeof v->spacing);
    memcpy(v->origin, geo->origin, sizeof v->origin);
    memcpy(v->direction, geo->direction, sizeof v->direction);
    v->space = geo->space;
    v->unit = geo->unit;
    /* the slot of each file's first frame; -1 for a file of another step */
    for (int i = 0; i < b - a; i++)
        slot[i] = -1;
    for (long k = 0; k < nz; k++)
        for (int i = a; i < b; i++)
            if (sc->order[i] == refs[k].file && refs[k].frame == 0)
                slot[i - a] = k;
    if (info) {
        info->n_times = nt;
        info->time_step = step_s;
    }
    series_read R = {sc, a, b, ch, nz, refs, direct, slot, frame_bytes, v};
    double lo, hi;
    if ((s = read_pixels(&R, &lo, &hi)) != VV_OK)
        goto done;
    if (!strcasecmp(f0->modality, "CT"))
        v->data_origin = VV_ORIGIN_CT;
    else if (!strcasecmp(f0->modality, "MR"))
        v->data_origin = VV_ORIGIN_MRI;
    else
        v->data_origin = VV_ORIGIN_OTHER;
    v->modification = VV_MOD_ORIGINAL;
    /* the range gathered slice by slice (NaN never compares less or more) */
    v->range[0] = lo <= hi ? lo : 0;
    v->range[1] = lo <= hi ? hi : 0;
    v->modified++;
done:
    vv_volume_free(geo);
    free(slot);
    free(refs);
    free(direct);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    *out = v;
    return VV_OK;
}

/* The time steps of series @p si as its reader finds them (pick_time_step):
 * the images' places along the first one's normal, sorted, in runs of T
 * images each; 1 when the images have no positions or one each. */
int
dicom_series_time_steps(const dicom_scan *sc, int si, long frames) {
    const vv_dcm_file *f0 = &sc->f[sc->order[sc->start[si]]];
    if (!f0->has_iop || frames < 2 || frames > (1L << 24))
        return 1;
    double *d = malloc((size_t)frames * sizeof *d);
    if (!d)
        return 1;
    const double *r = f0->iop, *c = f0->iop + 3;
    const double nrm[3] = {r[1] * c[2] - r[2] * c[1], r[2] * c[0] - r[0] * c[2],
                           r[0] * c[1] - r[1] * c[0]};
    long k = 0;
    int ok = 1;
    for (int i = sc->start[si]; ok && i < sc->start[si + 1]; i++) {
        const vv_dcm_file *f = &sc->f[sc->order[i]];
        ok = f->frame_ipp || (f->has_ipp && f->frames == 1);
        for (int fr = 0; ok && fr < f->frames; fr++) {
            const double *p = f->frame_ipp ? f->frame_ipp + 3 * fr : f->ipp;
            d[k++] = nrm[0] * p[0] + nrm[1] * p[1] + nrm[2] * p[2];
        }
    }
    int t = 1;
    if (ok) {
        qsort(d, (size_t)k, sizeof *d, cmp_double);
        t = images_per_place(d, sizeof *d, (int)k);
    }
    free(d);
    return t > 1 ? t : 1;
}

#endif
