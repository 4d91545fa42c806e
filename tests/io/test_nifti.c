/*
 * NIfTI reading: the MNI template, files whose headers are built here byte by
 * byte (NIfTI-2 with scaling and an sform, a NIfTI-1 .hdr/.img pair with a
 * qform, gzip with pixdim only, 2-D), a 5-D file's time steps and channels
 * (also through vv_time_series), and bad input.
 */
#include "testutil.h"

#include "io/io_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <zlib.h>

/* cmocka 1.1.5 has no assert_double_equal */

static char *
out_path(const char *name) {
    static char buf[4][1024];
    static int slot;
    slot = (slot + 1) % 4;
    snprintf(buf[slot], sizeof buf[slot], "%s/%s", vt_outdir("io_nifti"), name);
    return buf[slot];
}

static void
test_mni_template(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_nifti_read(&v, vt_data("volumes/avg152T1_RL_nifti.nii.gz")));
    assert_int_equal(v->space, VV_SPACE_RAS);
    assert_int_equal(v->dims[0], 91);
    assert_int_equal(v->dims[1], 109);
    assert_int_equal(v->dims[2], 91);
    assert_int_equal(v->type, VV_U8);
    for (int i = 0; i < 3; i++)
        assert_near(v->spacing[i], 2, 1e-12);
    /* sform (code 4, MNI): srow translation -90 -126 -72, axes along +x +y +z */
    assert_near(v->origin[0], -90, 1e-9);
    assert_near(v->origin[1], -126, 1e-9);
    assert_near(v->origin[2], -72, 1e-9);
    for (int i = 0; i < 9; i++)
        assert_near(v->direction[i], (i % 4) == 0, 1e-12);
    assert_int_equal(v->unit, VV_UNIT_MM);
    assert_near(v->range[0], 0, 0);
    assert_near(v->range[1], 255, 0);
    /* values checked against the file itself (gunzipped, offset 352) */
    assert_near(vv_volume_get(v, 0, 0, 0), 7, 0);
    assert_near(vv_volume_get(v, 45, 54, 45), 121, 0);
    vv_volume_free(v);
}

static void
test_ch2_if_installed(void **state) {
    (void)state;
    const char *path = "/usr/share/mricron/templates/ch2.nii.gz";
    if (access(path, R_OK) != 0)
        vt_skip("%s (package mricron-data) is not installed", path);
    vv_volume *v = NULL;
    vt_ok(vv_nifti_read(&v, path));
    assert_int_equal(v->dims[0], 181);
    assert_int_equal(v->dims[1], 217);
    assert_int_equal(v->dims[2], 181);
    assert_int_equal(v->type, VV_U8);
    for (int i = 0; i < 3; i++)
        assert_near(v->spacing[i], 1, 1e-12);
    assert_near(v->origin[0], -90, 1e-9);
    assert_near(v->origin[1], -125, 1e-9);
    assert_near(v->origin[2], -71, 1e-9);
    vv_volume_free(v);
}

/*
 * Headers are built by hand here (not with nifti_clib, so that the reader is
 * checked against the format, not against the library talking to itself).
 */
typedef struct hdr_spec {
    int version; /* 1 or 2 */
    int64_t dim[8];
    int datatype, bitpix;
    double pixdim[8];
    double slope, inter;
    int qform_code, sform_code;
    double quatern[3], qoffset[3];
    double srow[3][4];
    int xyzt_units;
    int pair; /* 1: "ni1"/"ni2" header for a .hdr/.img pair (vox_offset 0) */
} hdr_spec;

static void
put(unsigned char *h, int off, const void *x, size_t n) {
    memcpy(h + off, x, n);
}

static void
put_i16(unsigned char *h, int off, int v) {
    int16_t x = (int16_t)v;
    put(h, off, &x, 2);
}

static void
put_i32(unsigned char *h, int off, int v) {
    int32_t x = v;
    put(h, off, &x, 4);
}

static void
put_f32(unsigned char *h, int off, double v) {
    float x = (float)v;
    put(h, off, &x, 4);
}

static void
put_f64(unsigned char *h, int off, double v) {
    put(h, off, &v, 8);
}

/* Fills @p h (NIfTI-1: 352 bytes, NIfTI-2: 544, including the 4 extension bytes). */
static size_t
build_header(const hdr_spec *sp, unsigned char *h) {
    memset(h, 0, 544);
    if (sp->version == 1) {
        put_i32(h, 0, 348);
        for (int i = 0; i < 8; i++)
            put_i16(h, 40 + 2 * i, (int)sp->dim[i]);
        put_i16(h, 70, sp->datatype);
        put_i16(h, 72, sp->bitpix);
        for (int i = 0; i < 8; i++)
            put_f32(h, 76 + 4 * i, sp->pixdim[i]);
        put_f32(h, 108, sp->pair ? 0 : 352);
        put_f32(h, 112, sp->slope);
        put_f32(h, 116, sp->inter);
        h[123] = (unsigned char)sp->xyzt_units;
        put_i16(h, 252, sp->qform_code);
        put_i16(h, 254, sp->sform_code);
        for (int i = 0; i < 3; i++) {
            put_f32(h, 256 + 4 * i, sp->quatern[i]);
            put_f32(h, 268 + 4 * i, sp->qoffset[i]);
            for (int c = 0; c < 4; c++)
                put_f32(h, 280 + 16 * i + 4 * c, sp->srow[i][c]);
        }
        memcpy(h + 344, sp->pair ? "ni1" : "n+1", 4);
        return 352;
    }
    put_i32(h, 0, 540);
    memcpy(h + 4, sp->pair ? "ni2\0\r\n\032\n" : "n+2\0\r\n\032\n", 8);
    put_i16(h, 12, sp->datatype);
    put_i16(h, 14, sp->bitpix);
    for (int i = 0; i < 8; i++) {
        put(h, 16 + 8 * i, &sp->dim[i], 8);
        put_f64(h, 104 + 8 * i, sp->pixdim[i]);
    }
    int64_t off = sp->pair ? 0 : 544;
    put(h, 168, &off, 8);
    put_f64(h, 176, sp->slope);
    put_f64(h, 184, sp->inter);
    put_i32(h, 344, sp->qform_code);
    put_i32(h, 348, sp->sform_code);
    for (int i = 0; i < 3; i++) {
        put_f64(h, 352 + 8 * i, sp->quatern[i]);
        put_f64(h, 376 + 8 * i, sp->qoffset[i]);
        for (int c = 0; c < 4; c++)
            put_f64(h, 400 + 32 * i + 8 * c, sp->srow[i][c]);
    }
    put_i32(h, 500, sp->xyzt_units);
    return 544;
}

/* Writes header + data to @p path (gzip-compressed when it ends in .gz). */
static void
write_nifti(const char *path, const hdr_spec *sp, const void *data, size_t nbytes) {
    unsigned char h[544];
    size_t hn = build_header(sp, h);
    unsigned char *buf = malloc(hn + nbytes);
    assert_non_null(buf);
    memcpy(buf, h, hn);
    memcpy(buf + hn, data, nbytes);
    size_t len = strlen(path);
    if (len > 3 && !strcmp(path + len - 3, ".gz")) {
        gzFile g = gzopen(path, "wb");
        assert_non_null(g);
        assert_int_equal(gzwrite(g, buf, (unsigned)(hn + nbytes)), (int)(hn + nbytes));
        gzclose(g);
    } else {
        vt_write_file(path, buf, hn + nbytes);
    }
    free(buf);
}

static void
test_nifti2_scaled_sform(void **state) {
    (void)state;
    hdr_spec sp = {.version = 2,
                   .dim = {3, 4, 3, 2, 1, 1, 1, 1},
                   .datatype = 4, /* DT_INT16 */
                   .bitpix = 16,
                   .pixdim = {1, 0.7, 0.7, 0.7, 1, 1, 1, 1}, /* ignored: the sform wins */
                   .slope = 0.5,
                   .inter = -3,
                   .qform_code = 0,
                   .sform_code = 1,
                   .srow = {{0, -1.5, 0, 12}, {2.5, 0, 0, -4}, {0, 0, 3, 7.25}},
                   .xyzt_units = 3}; /* micron */
    int16_t data[24];
    for (int i = 0; i < 24; i++)
        data[i] = (int16_t)(i * 3 - 7);
    write_nifti(out_path("n2.nii"), &sp, data, sizeof data);

    vv_volume *v = NULL;
    vt_ok(vv_nifti_read(&v, out_path("n2.nii")));
    assert_int_equal(v->type, VV_F32);
    assert_int_equal(v->dims[0], 4);
    assert_int_equal(v->dims[1], 3);
    assert_int_equal(v->dims[2], 2);
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 3; j++)
            for (int i = 0; i < 4; i++) {
                int idx = (k * 3 + j) * 4 + i;
                assert_near(vv_volume_get(v, i, j, k), (idx * 3 - 7) * 0.5 - 3, 1e-6);
            }
    assert_near(v->spacing[0], 2.5, 1e-12);
    assert_near(v->spacing[1], 1.5, 1e-12);
    assert_near(v->spacing[2], 3, 1e-12);
    /* columns: i -> +y, j -> -x, k -> +z */
    const double dir[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    for (int i = 0; i < 9; i++)
        assert_near(v->direction[i], dir[i], 1e-12);
    assert_near(v->origin[0], 12, 1e-12);
    assert_near(v->origin[1], -4, 1e-12);
    assert_near(v->origin[2], 7.25, 1e-12);
    assert_int_equal(v->unit, VV_UNIT_MICRON);
    assert_near(v->range[0], -7 * 0.5 - 3, 1e-6);
    assert_near(v->range[1], (23 * 3 - 7) * 0.5 - 3, 1e-6);
    vv_volume_free(v);
}

static void
test_hdr_img_pair_qform(void **state) {
    (void)state;
    /* 90 degrees about z: quaternion (cos 45, 0, 0, sin 45) */
    hdr_spec sp = {.version = 1,
                   .dim = {3, 3, 2, 2, 1, 1, 1, 1},
                   .datatype = 512, /* DT_UINT16 */
                   .bitpix = 16,
                   .pixdim = {1, 0.5, 0.75, 4, 1, 1, 1, 1},
                   .slope = 1,
                   .inter = 0, /* identity scaling: the type is kept */
                   .qform_code = 1,
                   .quatern = {0, 0, sqrt(0.5)},
                   .qoffset = {1, 2, 3},
                   .xyzt_units = 2,
                   .pair = 1};
    unsigned char h[544];
    size_t hn = build_header(&sp, h);
    vt_write_file(out_path("pair.hdr"), h, hn - 4);
    uint16_t data[12];
    for (int i = 0; i < 12; i++)
        data[i] = (uint16_t)(i * 3 + 1000);
    vt_write_file(out_path("pair.img"), data, sizeof data);

    vv_volume *v = NULL;
    vt_ok(vv_nifti_read(&v, out_path("pair.hdr")));
    assert_int_equal(v->type, VV_U16);
    assert_near(vv_volume_get(v, 2, 1, 1), (double)(11 * 3 + 1000), 0);
    assert_near(v->spacing[0], 0.5, 1e-6);
    assert_near(v->spacing[1], 0.75, 1e-6);
    assert_near(v->spacing[2], 4, 1e-6);
    const double dir[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    for (int i = 0; i < 9; i++)
        assert_near(v->direction[i], dir[i], 1e-6);
    assert_near(v->origin[0], 1, 1e-6);
    assert_near(v->origin[1], 2, 1e-6);
    assert_near(v->origin[2], 3, 1e-6);
    assert_int_equal(v->unit, VV_UNIT_MM);
    vv_volume_free(v);
    /* naming the image half works too */
    vt_ok(vv_nifti_read(&v, out_path("pair.img")));
    assert_int_equal(v->dims[0], 3);
    vv_volume_free(v);
    /* the image half missing */
    assert_int_equal(unlink(out_path("pair.img")), 0);
    vt_err(vv_nifti_read(&v, out_path("pair.hdr")));
    assert_null(v);
}

static void
test_pixdim_only_f64_scaled_gz(void **state) {
    (void)state;
    hdr_spec sp = {.version = 1,
                   .dim = {3, 2, 2, 3, 1, 1, 1, 1},
                   .datatype = 64, /* DT_FLOAT64 */
                   .bitpix = 64,
                   .pixdim = {1, 1.5, -2, 2.5, 1, 1, 1, 1},
                   .slope = 2,
                   .inter = 1};
    double data[12];
    for (int i = 0; i < 12; i++)
        data[i] = i * 0.125 - 1;
    write_nifti(out_path("pix.nii.gz"), &sp, data, sizeof data);
    vv_volume *v = NULL;
    vt_ok(vv_nifti_read(&v, out_path("pix.nii.gz")));
    assert_int_equal(v->type, VV_F64);
    assert_near(vv_volume_get(v, 1, 1, 2), (11 * 0.125 - 1) * 2 + 1, 0);
    assert_near(v->spacing[0], 1.5, 1e-12);
    assert_near(v->spacing[1], 2, 1e-12);
    assert_near(v->spacing[2], 2.5, 1e-12);
    for (int i = 0; i < 9; i++)
        assert_near(v->direction[i], (i % 4) == 0, 0);
    for (int i = 0; i < 3; i++)
        assert_near(v->origin[i], 0, 0);
    vv_volume_free(v);

    /* a 2-D image is one slice */
    hdr_spec s2 = {.version = 2,
                   .dim = {2, 3, 2, 1, 1, 1, 1, 1},
                   .datatype = 2,
                   .bitpix = 8,
                   .pixdim = {1, 1, 1, 1, 1, 1, 1, 1}};
    unsigned char px[6] = {1, 2, 3, 4, 5, 6};
    write_nifti(out_path("flat.nii"), &s2, px, sizeof px);
    vt_ok(vv_nifti_read(&v, out_path("flat.nii")));
    assert_int_equal(v->type, VV_U8);
    assert_int_equal(v->dims[2], 1);
    assert_near(vv_volume_get(v, 2, 1, 0), 6, 0);
    vv_volume_free(v);
}

static void
expect_error(const char *path, vv_status want) {
    vv_volume *v = (vv_volume *)1;
    vv_error_clear();
    vv_status s = vv_nifti_read(&v, path);
    if (s != want)
        fail_msg("%s: got %s (%s), want %s", path, vv_status_name(s), vv_error_message(),
                 vv_status_name(want));
    assert_null(v);
    assert_true(strncmp(vv_error_message(), "nifti: ", 7) == 0);
}

static void
set_i16(unsigned char *h, int off, int16_t x) {
    memcpy(h + off, &x, 2);
}

static void
test_bad_input(void **state) {
    (void)state;
    expect_error(out_path("missing.nii"), VV_ERR_IO);
    vt_write_file(out_path("empty.nii"), "", 0);
    expect_error(out_path("empty.nii"), VV_ERR_FORMAT);

    unsigned char junk[1000];
    uint32_t x = 7;
    for (size_t i = 0; i < sizeof junk; i++) {
        x = x * 1103515245u + 12345u;
        junk[i] = (unsigned char)(x >> 16);
    }
    vt_write_file(out_path("junk.nii"), junk, sizeof junk);
    expect_error(out_path("junk.nii"), VV_ERR_FORMAT);

    /* a good little-endian NIfTI-1 file to break in several ways */
    hdr_spec sp = {.version = 1,
                   .dim = {3, 8, 8, 8, 1, 1, 1, 1},
                   .datatype = 4,
                   .bitpix = 16,
                   .pixdim = {1, 1, 1, 1, 1, 1, 1, 1}};
    int16_t vox[512];
    for (int i = 0; i < 512; i++)
        vox[i] = (int16_t)i;
    write_nifti(out_path("good.nii"), &sp, vox, sizeof vox);
    size_t n = 0;
    unsigned char *good = vt_read_file(out_path("good.nii"), &n);
    assert_int_equal(n, 352 + 8 * 8 * 8 * 2);
    vv_volume *v = NULL;
    vt_ok(vv_nifti_read(&v, out_path("good.nii")));
    vv_volume_free(v);

    vt_write_file(out_path("trunc.nii"), good, n - 100);
    expect_error(out_path("trunc.nii"), VV_ERR_FORMAT);
    vt_write_file(out_path("trunc_hdr.nii"), good, 200);
    expect_error(out_path("trunc_hdr.nii"), VV_ERR_FORMAT);

    unsigned char *bad = malloc(n);
    assert_non_null(bad);
    memcpy(bad, good, n);
    set_i16(bad, 42, 30000); /* dim[1..3] = 30000: 2.7e13 voxels */
    set_i16(bad, 44, 30000);
    set_i16(bad, 46, 30000);
    vt_write_file(out_path("huge.nii"), bad, n);
    expect_error(out_path("huge.nii"), VV_ERR_LIMIT);

    memcpy(bad, good, n);
    set_i16(bad, 40, 4); /* a 4-D series of 2 volumes: the first is read */
    set_i16(bad, 48, 2);
    set_i16(bad, 46, 4);
    vt_write_file(out_path("series.nii"), bad, n);
    vv_volume *first = NULL;
    vt_ok(vv_nifti_read(&first, out_path("series.nii")));
    assert_int_equal(first->dims[2], 4);
    vv_volume_free(first);
    set_i16(bad, 40, 6); /* an axis past time and channels: refused */
    set_i16(bad, 48, 1);
    set_i16(bad, 52, 2);
    vt_write_file(out_path("sixd.nii"), bad, n);
    expect_error(out_path("sixd.nii"), VV_ERR_UNSUPPORTED);

    memcpy(bad, good, n);
    set_i16(bad, 40, 4); /* 4-D with dim[4] = 1 is a volume */
    set_i16(bad, 48, 1);
    vt_write_file(out_path("one.nii"), bad, n);
    vt_ok(vv_nifti_read(&v, out_path("one.nii")));
    assert_int_equal(v->dims[2], 8);
    vv_volume_free(v);

    memcpy(bad, good, n);
    set_i16(bad, 70, 32); /* complex64 */
    vt_write_file(out_path("complex.nii"), bad, n);
    vt_err(vv_nifti_read(&v, out_path("complex.nii")));

    free(bad);
    free(good);
}

/* Voxel (i, j, k) of time step t, channel c in test_time_steps. */
static uint16_t
step_value(int i, int j, int k, int t, int c) {
    return (uint16_t)(c * 20000 + t * 1000 + (k * 12 + j) * 16 + i);
}

/*
 * A 5-D NIfTI-2 (16 x 12 x 10 voxels, 6 time steps, 2 channels; u16; time
 * in ms): each (t, c) read through vv_volume_load with the axes reported,
 * and the steps of channel 1 through a time series whose cache holds two:
 * the voxels, the bound on resident steps, a read-ahead that makes the
 * next get read nothing, a step out of range, volumes outliving eviction.
 */
static void
test_time_steps(void **state) {
    (void)state;
    enum { NX = 16, NY = 12, NZ = 10, NT = 6, NC = 2 };
    hdr_spec sp = {.version = 2,
                   .dim = {5, NX, NY, NZ, NT, NC, 1, 1},
                   .datatype = 512, /* DT_UINT16 */
                   .bitpix = 16,
                   .pixdim = {1, 1, 1, 1, 40, 1, 1, 1},
                   .slope = 1,
                   .xyzt_units = 2 | 16}; /* mm, ms */
    size_t n = (size_t)NX * NY * NZ * NT * NC;
    uint16_t *data = malloc(n * sizeof *data);
    assert_non_null(data);
    size_t q = 0;
    for (int c = 0; c < NC; c++)
        for (int t = 0; t < NT; t++)
            for (int k = 0; k < NZ; k++)
                for (int j = 0; j < NY; j++)
                    for (int i = 0; i < NX; i++)
                        data[q++] = step_value(i, j, k, t, c);
    write_nifti(out_path("series5d.nii"), &sp, data, n * sizeof *data);
    free(data);
    const char *path = out_path("series5d.nii");

    for (int c = 0; c < NC; c++)
        for (int t = 0; t < NT; t += 5) {
            vv_load_options o;
            vv_load_options_init(&o);
            vv_load_info info;
            o.channel = c;
            o.time = t;
            o.info = &info;
            vv_volume *v = NULL;
            vt_ok(vv_volume_load(&v, path, &o));
            assert_int_equal(info.n_channels, NC);
            assert_int_equal(info.n_times, NT);
            assert_near(info.time_step, 0.040, 1e-9);
            assert_int_equal(vv_volume_get(v, 3, 5, 7), step_value(3, 5, 7, t, c));
            assert_int_equal(vv_volume_get(v, NX - 1, NY - 1, NZ - 1),
                             step_value(NX - 1, NY - 1, NZ - 1, t, c));
            vv_volume_free(v);
        }
    vv_load_options o;
    vv_load_options_init(&o);
    o.time = NT;
    vv_volume *bad = NULL;
    vt_err(vv_volume_load(&bad, path, &o));
    assert_non_null(strstr(vv_error_message(), "time step 6 asked, the file has 6"));

    o.time = -1;
    o.channel = 1;
    vv_time_series *ts = NULL;
    const uint64_t step_bytes = (uint64_t)NX * NY * NZ * 2;
    vt_ok(vv_time_series_open(&ts, path, &o, 2 * step_bytes));
    assert_int_equal(vv_time_series_count(ts), NT);
    assert_int_equal(vv_time_series_info(ts)->n_channels, NC);
    vv_volume *keep = NULL;
    int reads = 0, resident = 0;
    for (int t = 0; t < NT; t++) {
        vv_volume *v = NULL;
        vt_ok(vv_time_series_get(ts, t, &v));
        assert_int_equal(vv_volume_get(v, 1, 2, 3), step_value(1, 2, 3, t, 1));
        vv_time_series_stats(ts, &reads, &resident, NULL);
        assert_true(resident <= 2);
        if (t == 0)
            keep = v; /* evicted later, still ours */
        else
            vv_volume_free(v);
    }
    assert_int_equal(reads, NT);
    assert_int_equal(vv_volume_get(keep, 1, 2, 3), step_value(1, 2, 3, 0, 1));
    vv_volume_free(keep);
    /* a read-ahead of step 1 (evicted): the get that follows reads nothing */
    vv_time_series_prefetch(ts, 1);
    for (int tries = 0; tries < 5000; tries++) {
        vv_time_series_stats(ts, &reads, NULL, NULL);
        if (reads == NT + 1)
            break;
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
    assert_int_equal(reads, NT + 1);
    vv_volume *v1 = NULL;
    vt_ok(vv_time_series_get(ts, 1, &v1));
    vv_time_series_stats(ts, &reads, &resident, NULL);
    assert_int_equal(reads, NT + 1);
    assert_int_equal(vv_volume_get(v1, 0, 0, 0), step_value(0, 0, 0, 1, 1));
    vv_volume_free(v1);
    vt_err(vv_time_series_get(ts, NT, &v1));
    assert_null(v1);
    /* freed with a read-ahead perhaps in flight */
    vv_time_series_prefetch(ts, 4);
    vv_time_series_free(ts);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mni_template),
        cmocka_unit_test(test_ch2_if_installed),
        cmocka_unit_test(test_nifti2_scaled_sform),
        cmocka_unit_test(test_hdr_img_pair_qform),
        cmocka_unit_test(test_pixdim_only_f64_scaled_gz),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_time_steps),
    };
    return vt_run_tests(tests, NULL, NULL);
}
