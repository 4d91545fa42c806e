/*
 * Format names, detection, and vv_volume_load / vv_volume_save on every
 * shared volume (dimensions from ../shared/data/README.md).
 */
#include "testutil.h"
#include "volvis/sys/format.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

static char *
out_path(const char *name) {
    static char buf[4][1024];
    static int slot;
    slot = (slot + 1) % 4;
    snprintf(buf[slot], sizeof buf[slot], "%s/%s", vt_outdir("io_volume_io"), name);
    return buf[slot];
}

static const struct {
    const char *file;
    vv_format format;
    int dims[3];
    int type; /* -1: not documented */
} shared[] = {
    {"volumes/nut.slc", VV_FORMAT_SLC, {68, 41, 59}, VV_U8},
    {"volumes/bolt.slc", VV_FORMAT_SLC, {70, 123, 66}, VV_U8},
    {"volumes/neghip.slc", VV_FORMAT_SLC, {66, 66, 66}, VV_U8},
    {"volumes/sphere.slc", VV_FORMAT_SLC, {50, 50, 50}, VV_U8},
    {"volumes/ct_head.nrrd", VV_FORMAT_NRRD, {256, 256, 108}, VV_I16},
    {"volumes/headsq/quarter.nhdr", VV_FORMAT_NRRD, {64, 64, 93}, VV_I16},
    {"volumes/ironProt.vtk", VV_FORMAT_VTK, {68, 68, 68}, VV_U8},
    {"volumes/HeadMRVolume.mhd", VV_FORMAT_MHD, {48, 62, 42}, VV_U8},
    {"volumes/avg152T1_RL_nifti.nii.gz", VV_FORMAT_NIFTI, {91, 109, 91}, VV_U8},
    {"volumes/heart.vtk", VV_FORMAT_VTK, {32, 32, 12}, -1},
};
#define N_SHARED (sizeof shared / sizeof shared[0])

static void
test_format_names(void **state) {
    (void)state;
    /* every row of the table: its name and aliases parse to its id */
    const int n = vv_format_count();
    assert_true(n >= 8);
    for (int f = VV_FORMAT_AUTO; f <= n; f++) {
        vv_format g = VV_FORMAT_UNKNOWN;
        vt_ok(vv_format_parse(vv_format_name((vv_format)f), &g));
        assert_int_equal(g, f);
    }
    assert_string_equal(vv_format_name(VV_FORMAT_NIFTI), "nifti");
    assert_string_equal(vv_format_name((vv_format)(n + 1)), "unknown");
    assert_string_equal(vv_format_name(VV_FORMAT_UNKNOWN), "unknown");
    vv_format g;
    vt_ok(vv_format_parse("NRRD", &g));
    assert_int_equal(g, VV_FORMAT_NRRD);
    vt_ok(vv_format_parse("tif", &g));
    assert_int_equal(g, VV_FORMAT_TIFF);
    vt_ok(vv_format_parse("DICOM", &g));
    assert_int_equal(g, VV_FORMAT_DICOM);
    vt_ok(vv_format_parse("metaimage", &g));
    assert_int_equal(g, VV_FORMAT_MHD);
    vv_error_clear();
    assert_int_equal(vv_format_parse("gif", &g), VV_ERR_INVALID);
    /* the message lists the table's names */
    assert_non_null(
        strstr(vv_error_message(),
               "auto, slc, nrrd, nifti, mhd, vtk, raw, tiff, dicom, vti, zarr, hdf5, vvb, bdv, n5, "
               "precomputed, "
               "vtk_grid, vtu, dx, plot3d, netcdf or mesh"));
}

/* The records (include/volvis/sys/format.h): one table for everything that
 * opens -- complete, the version of the header, the named ids in their
 * rows, unique names, a way in for what each holds, writers with
 * extensions -- and each extension of a writer chosen by vv_volume_save. */
static void
test_format_table(void **state) {
    (void)state;
    int n = 0;
    const vv_format_record *const *t = vv_format_table(&n);
    assert_int_equal(n, vv_format_count());
    int kinds[3] = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        const vv_format_record *r = t[i];
        assert_int_equal(r->version, VV_FORMAT_RECORD_VERSION);
        assert_non_null(r->name);
        assert_non_null(r->title);
        assert_non_null(r->doc);
        assert_true(r->holds >= VV_DATA_VOLUME && r->holds <= VV_DATA_MESH);
        kinds[r->holds]++;
        if (r->holds == VV_DATA_VOLUME)
            assert_true(r->read || r->write); /* a written-only format: .vti */
        else if (r->holds == VV_DATA_GRID)
            assert_non_null(r->read_grid);
        else
            assert_non_null(r->read_mesh);
        assert_true(strlen(r->doc) > 20);
        assert_string_equal(vv_format_name((vv_format)(i + 1)), r->name);
        assert_ptr_equal(vv_format_record_of((vv_format)(i + 1)), r);
        for (int j = 0; j < i; j++)
            assert_string_not_equal(t[j]->name, r->name);
        /* a format with no signature is read only when described */
        if (!r->looks_like && r->read)
            assert_true(r->flags & VV_FORMAT_FLAG_DESCRIBED);
        if (r->write)
            assert_non_null(r->extensions);
    }
    assert_true(kinds[VV_DATA_VOLUME] >= 13 && kinds[VV_DATA_GRID] >= 5 &&
                kinds[VV_DATA_MESH] >= 1);
    /* the pyramids open a store, the bricked formats by bricks */
    assert_non_null(t[VV_FORMAT_OME_ZARR - 1]->open_store);
    assert_non_null(t[VV_FORMAT_HDF5 - 1]->open_store);
    assert_non_null(t[VV_FORMAT_BDV_XML - 1]->open_store);
    assert_non_null(t[VV_FORMAT_N5 - 1]->open_store);
    assert_non_null(t[VV_FORMAT_PRECOMPUTED - 1]->open_store);
    assert_non_null(t[VV_FORMAT_VVB - 1]->open_store);
    assert_non_null(t[VV_FORMAT_VVB - 1]->open_bricks);
    assert_non_null(t[VV_FORMAT_NRRD - 1]->raw_layout);
    assert_non_null(t[VV_FORMAT_RAW - 1]->raw_layout);
    assert_true(t[VV_FORMAT_VVB - 1]->flags & VV_FORMAT_FLAG_OUT_OF_CORE);
    static const struct {
        vv_format id;
        const char *name;
    } named[] = {{VV_FORMAT_SLC, "slc"},
                 {VV_FORMAT_NRRD, "nrrd"},
                 {VV_FORMAT_NIFTI, "nifti"},
                 {VV_FORMAT_MHD, "mhd"},
                 {VV_FORMAT_VTK, "vtk"},
                 {VV_FORMAT_RAW, "raw"},
                 {VV_FORMAT_TIFF, "tiff"},
                 {VV_FORMAT_DICOM, "dicom"},
                 {VV_FORMAT_VTI, "vti"},
                 {VV_FORMAT_OME_ZARR, "zarr"},
                 {VV_FORMAT_HDF5, "hdf5"},
                 {VV_FORMAT_VVB, "vvb"},
                 {VV_FORMAT_BDV_XML, "bdv"},
                 {VV_FORMAT_N5, "n5"},
                 {VV_FORMAT_PRECOMPUTED, "precomputed"}};
    for (size_t i = 0; i < sizeof named / sizeof named[0]; i++)
        assert_string_equal(t[named[i].id - 1]->name, named[i].name);
    /* the third-party parsers are marked for the sandbox */
    assert_true(t[VV_FORMAT_NRRD - 1]->flags & VV_FORMAT_FLAG_THIRD_PARTY);
    assert_true(t[VV_FORMAT_DICOM - 1]->flags & VV_FORMAT_FLAG_THIRD_PARTY);
    assert_true(t[VV_FORMAT_BDV_XML - 1]->flags & VV_FORMAT_FLAG_THIRD_PARTY);
    assert_false(t[VV_FORMAT_VVB - 1]->flags & VV_FORMAT_FLAG_THIRD_PARTY);
    assert_false(t[VV_FORMAT_SLC - 1]->flags & VV_FORMAT_FLAG_THIRD_PARTY);
    /* SLC's fits test says what it cannot hold */
    int dims[3] = {2, 2, 2};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_I16));
    char why[256] = "";
    assert_false(t[VV_FORMAT_SLC - 1]->fits(v, why, sizeof why));
    assert_non_null(strstr(why, "8-bit"));
    assert_non_null(strstr(why, "i16"));
    vv_volume_free(v);
}

static void
test_detect_shared(void **state) {
    (void)state;
    for (size_t i = 0; i < N_SHARED; i++) {
        vv_format f = vv_format_detect(vt_data(shared[i].file));
        if (f != shared[i].format)
            fail_msg("%s detected as %s", shared[i].file, vv_format_name(f));
    }
    /* the data half of a MetaImage and a headsq slice are raw: not detected */
    assert_int_equal(vv_format_detect(vt_data("volumes/HeadMRVolume.raw")), VV_FORMAT_UNKNOWN);
    assert_int_equal(vv_format_detect(vt_data("volumes/headsq/quarter.1")), VV_FORMAT_UNKNOWN);
    assert_int_equal(vv_format_detect(out_path("missing.nrrd")), VV_FORMAT_UNKNOWN);
}

static void
test_detect_handmade(void **state) {
    (void)state;
    const char *p = out_path("slc_ws.dat");
    vt_write_file(p, "  \n11111\n", 9);
    assert_int_equal(vv_format_detect(p), VV_FORMAT_SLC);
    p = out_path("mhd.txt");
    vt_write_file(p, "NDims = 3\nDimSize = 2 2 2\n", 26);
    assert_int_equal(vv_format_detect(p), VV_FORMAT_MHD);
    p = out_path("notmhd.txt");
    vt_write_file(p, "Hello = 3\n", 10);
    assert_int_equal(vv_format_detect(p), VV_FORMAT_UNKNOWN);

    /* NIfTI-1 header in big-endian byte order, and an Analyze .hdr (no magic) */
    unsigned char h[352] = {0};
    h[2] = 0x01;
    h[3] = 0x5c; /* 348 big-endian */
    memcpy(h + 344, "n+1", 4);
    p = out_path("be.nii");
    vt_write_file(p, h, sizeof h);
    assert_int_equal(vv_format_detect(p), VV_FORMAT_NIFTI);
    memset(h + 344, 0, 4);
    p = out_path("analyze.hdr");
    vt_write_file(p, h, 348);
    assert_int_equal(vv_format_detect(p), VV_FORMAT_NIFTI);
    p = out_path("analyze.bin"); /* same bytes, no hint from the name */
    vt_write_file(p, h, 348);
    assert_int_equal(vv_format_detect(p), VV_FORMAT_UNKNOWN);

    /* NIfTI-2 inside gzip */
    unsigned char h2[544] = {0};
    h2[0] = 0x1c;
    h2[1] = 0x02; /* 540 little-endian */
    memcpy(h2 + 4, "n+2\0\r\n\032\n", 8);
    p = out_path("n2.nii.gz");
    gzFile g = gzopen(p, "wb");
    assert_non_null(g);
    assert_int_equal(gzwrite(g, h2, sizeof h2), (int)sizeof h2);
    gzclose(g);
    assert_int_equal(vv_format_detect(p), VV_FORMAT_NIFTI);

    /* gzip of something else */
    p = out_path("text.gz");
    g = gzopen(p, "wb");
    assert_non_null(g);
    gzwrite(g, "NRRD0004\n", 9);
    gzclose(g);
    assert_int_equal(vv_format_detect(p), VV_FORMAT_UNKNOWN);
}

static void
test_load_shared(void **state) {
    (void)state;
    int failures = 0;
    for (size_t i = 0; i < N_SHARED; i++) {
        vv_volume *v = NULL;
        vv_status s = vv_volume_load(&v, vt_data(shared[i].file), NULL);
        if (s != VV_OK) {
            print_error("%s: %s: %s\n", shared[i].file, vv_status_name(s), vv_error_message());
            failures++;
            continue;
        }
        if (v->dims[0] != shared[i].dims[0] || v->dims[1] != shared[i].dims[1] ||
            v->dims[2] != shared[i].dims[2]) {
            print_error("%s: dims %d %d %d\n", shared[i].file, v->dims[0], v->dims[1], v->dims[2]);
            failures++;
        }
        if (shared[i].type >= 0 && (int)v->type != shared[i].type) {
            print_error("%s: type %s\n", shared[i].file, vv_voxel_type_name(v->type));
            failures++;
        }
        /* range[] computed: every file has some contrast */
        if (!(v->range[1] > v->range[0])) {
            print_error("%s: range %g..%g\n", shared[i].file, v->range[0], v->range[1]);
            failures++;
        }
        vv_volume_free(v);
    }
    assert_int_equal(failures, 0);
}

static void
test_load_errors(void **state) {
    (void)state;
    vv_volume *v = NULL;
    const char *missing = out_path("missing.slc");
    vv_error_clear();
    assert_int_equal(vv_volume_load(&v, missing, NULL), VV_ERR_IO);
    assert_null(v);
    assert_non_null(strstr(vv_error_message(), "missing.slc"));
    assert_non_null(strstr(vv_error_message(), "No such file"));

    unsigned char junk[2000];
    uint32_t x = 5;
    for (size_t i = 0; i < sizeof junk; i++) {
        x = x * 1103515245u + 12345u;
        junk[i] = (unsigned char)(x >> 16);
    }
    const char *p = out_path("junk.bin");
    vt_write_file(p, junk, sizeof junk);
    vv_error_clear();
    assert_int_equal(vv_volume_load(&v, p, NULL), VV_ERR_FORMAT);
    assert_null(v);
    assert_non_null(strstr(vv_error_message(), "cannot tell the format"));
    assert_non_null(strstr(vv_error_message(), "--raw"));

    /* empty file */
    p = out_path("empty.vol");
    vt_write_file(p, "", 0);
    assert_int_equal(vv_volume_load(&v, p, NULL), VV_ERR_FORMAT);

    /* a format named explicitly that does not match */
    vv_load_options o;
    vv_load_options_init(&o);
    assert_int_equal(o.format, VV_FORMAT_AUTO);
    assert_int_equal(o.has_raw, 0);
    o.format = VV_FORMAT_NRRD;
    vt_err(vv_volume_load(&v, vt_data("volumes/nut.slc"), &o));
    assert_null(v);
    assert_true(strncmp(vv_error_message(), "nrrd: nut.slc", 13) == 0);

    /* raw needs its parameters */
    o.format = VV_FORMAT_RAW;
    assert_int_equal(vv_volume_load(&v, p, &o), VV_ERR_INVALID);
}

static void
test_load_raw(void **state) {
    (void)state;
    /* the MetaImage data file read as raw with the header's numbers */
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = VV_FORMAT_RAW;
    o.has_raw = 1;
    o.raw.dims[0] = 48;
    o.raw.dims[1] = 62;
    o.raw.dims[2] = 42;
    o.raw.type = VV_U8;
    vv_volume *r = NULL, *m = NULL;
    vt_ok(vv_volume_load(&r, vt_data("volumes/HeadMRVolume.raw"), &o));
    vt_ok(vv_volume_load(&m, vt_data("volumes/HeadMRVolume.mhd"), NULL));
    assert_memory_equal(r->data, m->data, 48 * 62 * 42);
    assert_true(r->range[1] > r->range[0]);
    vv_volume_free(r);
    vv_volume_free(m);
}

static void
test_save_reload(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/headsq/quarter.nhdr"), NULL));

    /* NRRD keeps everything */
    const char *p = out_path("headsq.nrrd");
    vt_ok(vv_volume_save(v, p, VV_FORMAT_AUTO, 1));
    assert_int_equal(vv_format_detect(p), VV_FORMAT_NRRD);
    vv_volume *r = NULL;
    vt_ok(vv_volume_load(&r, p, NULL));
    assert_int_equal(r->type, VV_I16);
    assert_memory_equal(r->data, v->data, vv_volume_voxel_count(v) * 2);
    for (int i = 0; i < 3; i++)
        assert_true(fabs(r->spacing[i] - v->spacing[i]) < 1e-12);
    vv_volume_free(r);

    /* SLC: strict refuses 16-bit data, otherwise it is rescaled to 0..255 */
    p = out_path("headsq.slc");
    assert_int_equal(vv_volume_save(v, p, VV_FORMAT_AUTO, 1), VV_ERR_UNSUPPORTED);
    vt_ok(vv_volume_save(v, p, VV_FORMAT_AUTO, 0));
    assert_int_equal(vv_format_detect(p), VV_FORMAT_SLC);
    vt_ok(vv_volume_load(&r, p, NULL));
    assert_int_equal(r->type, VV_U8);
    assert_int_equal(r->dims[2], 93);
    assert_int_equal(r->modification, VV_MOD_OTHER);
    assert_true(r->range[0] == 0 && r->range[1] == 255);
    double lo = v->range[0], hi = v->range[1];
    for (int k = 0; k < 93; k += 11)
        for (int j = 0; j < 64; j += 7)
            for (int i = 0; i < 64; i += 5) {
                double want = round((vv_volume_get(v, i, j, k) - lo) * 255.0 / (hi - lo));
                assert_true(fabs(vv_volume_get(r, i, j, k) - want) <= 0.5);
            }
    vv_volume_free(r);

    /* 8-bit SLC round trip is exact */
    vv_volume *n = NULL;
    vt_ok(vv_volume_load(&n, vt_data("volumes/nut.slc"), NULL));
    p = out_path("nut.slc");
    vt_ok(vv_volume_save(n, p, VV_FORMAT_AUTO, 1));
    vt_ok(vv_volume_load(&r, p, NULL));
    assert_memory_equal(r->data, n->data, vv_volume_voxel_count(n));
    vv_volume_free(r);
    /* .nhdr is NRRD too */
    p = out_path("nut.nhdr");
    vt_ok(vv_volume_save(n, p, VV_FORMAT_AUTO, 1));
    vt_ok(vv_volume_load(&r, p, NULL));
    assert_memory_equal(r->data, n->data, vv_volume_voxel_count(n));
    vv_volume_free(r);
    vv_volume_free(n);

    /* no extension to go by */
    vt_err(vv_volume_save(v, out_path("headsq.dat"), VV_FORMAT_AUTO, 0));
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_format_names),  cmocka_unit_test(test_format_table),
        cmocka_unit_test(test_detect_shared), cmocka_unit_test(test_detect_handmade),
        cmocka_unit_test(test_load_shared),   cmocka_unit_test(test_load_errors),
        cmocka_unit_test(test_load_raw),      cmocka_unit_test(test_save_reload),
    };
    return vt_run_tests(tests, NULL, NULL);
}
