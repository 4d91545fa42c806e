/*
 * DICOM series through GDCM. The series are written at test time into a
 * temporary folder by scripts/dicom_testdata.py (python3-pydicom) from the CT
 * head of ../shared/data/volumes/ct_head.nrrd, and compressed by gdcmconv
 * (libgdcm-tools); pydicom's own test files cover the codecs and byte orders.
 * Tests skip, saying why, when pydicom, gdcmconv or the shared data are
 * missing (scripts/install-deps.sh test installs them).
 */
#include "testutil.h"

#include "io/io_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define PYTHON "/usr/bin/python3"
#define PYDICOM_FILES "/usr/lib/python3/dist-packages/pydicom/data/test_files"
#define NIBABEL_FILES "/usr/lib/python3/dist-packages/nibabel/nicom/tests/data"

static char g_dir[256]; /* the temporary folder, "" when the data could not be made */
static int g_have_gdcmconv;
static char g_why[256];

static const char *
tmp(const char *name) {
    static char buf[8][1024];
    static int slot;
    slot = (slot + 1) % 8;
    snprintf(buf[slot], sizeof buf[slot], "%s/%s", g_dir, name);
    return buf[slot];
}

static int run(const char *fmt, ...) VV_PRINTF(1, 2);
static int
run(const char *fmt, ...) {
    char cmd[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    int rc = system(cmd);
    if (rc != 0)
        fprintf(stderr, "test_dicom: '%s' failed (%d)\n", cmd, rc);
    return rc;
}

/* 1 when @p s occurs in the @p n bytes of @p d. */
static int
contains(const unsigned char *d, size_t n, const char *s) {
    size_t k = strlen(s);
    for (size_t i = 0; i + k <= n; i++)
        if (!memcmp(d + i, s, k))
            return 1;
    return 0;
}

static void
copy_file(const char *from, const char *to) {
    size_t n;
    unsigned char *d = vt_read_file(from, &n);
    vt_write_file(to, d, n);
    free(d);
}

static int
setup(void **state) {
    (void)state;
    g_dir[0] = '\0';
    if (access(PYTHON, X_OK) != 0 || system(PYTHON " -c 'import pydicom' 2>/dev/null") != 0) {
        snprintf(g_why, sizeof g_why, "python3-pydicom is not installed");
        return 0;
    }
    if (access(vt_data("volumes/ct_head.nrrd"), R_OK) != 0) {
        snprintf(g_why, sizeof g_why, "../shared/data/volumes/ct_head.nrrd is missing");
        return 0;
    }
    g_have_gdcmconv = system("gdcmconv --version >/dev/null 2>&1") == 0;
    char tmpl[sizeof g_dir];
    if (!vt_mkdtemp(tmpl, sizeof tmpl, "vv_dicom_"))
        return -1;
    snprintf(g_dir, sizeof g_dir, "%s", tmpl);
    const char *script = VV_SOURCE_DIR "/scripts/dicom_testdata.py";
    const char *nrrd = vt_data("volumes/ct_head.nrrd");
    int rc = run("%s %s ct %s %s/ct", PYTHON, script, nrrd, g_dir);
    rc |= run("%s %s ct %s %s/obl --first 30 --count 12 --crop 64 --oblique 30 "
              "--reverse-instances",
              PYTHON, script, nrrd, g_dir);
    rc |= run("%s %s ct %s %s/small --first 50 --count 6 --crop 96", PYTHON, script, nrrd, g_dir);
    rc |= run("%s %s multiframe %s %s/enhanced.dcm --first 40 --count 8 --crop 64", PYTHON, script,
              nrrd, g_dir);
    rc |= run("%s %s oblique %s %s/oblr --angle 30 --size 96 --slices 24", PYTHON, script, nrrd,
              g_dir);
    rc |= run("%s %s ct %s %s/mixed --first 50 --count 6 --crop 96 && %s %s ct %s %s/mixed2 "
              "--first 10 --count 3 --crop 32 --series-number 7 --description Scout",
              PYTHON, script, nrrd, g_dir, PYTHON, script, nrrd, g_dir);
    rc |= run("for f in %s/mixed2/*.dcm; do mv \"$f\" \"%s/mixed/scout_$(basename \"$f\")\"; "
              "done",
              g_dir, g_dir);
    if (g_have_gdcmconv)
        rc |= run("%s %s compress %s/small %s/comp jpeg jpegls j2k rle deflated implicit", PYTHON,
                  script, g_dir, g_dir);
    if (rc != 0) {
        /* pydicom and the data are there: a failure of the writer fails the tests */
        fprintf(stderr, "setup: writing the test series with %s failed\n", script);
        run("rm -rf '%s'", g_dir);
        g_dir[0] = '\0';
        return -1;
    }
    return 0;
}

static int
teardown(void **state) {
    (void)state;
    if (g_dir[0])
        run("rm -rf '%s'", g_dir);
    return 0;
}

#define NEED_DATA()                                                                                \
    do {                                                                                           \
        if (!g_dir[0])                                                                             \
            vt_skip("%s", g_why);                                                                  \
    } while (0)

static void
assert_one_line_naming(const char *name) {
    const char *m = vv_error_message();
    assert_non_null(m);
    if (!strstr(m, name))
        fail_msg("error does not name %s: %s", name, m);
    if (strchr(m, '\n'))
        fail_msg("error is not one line: %s", m);
}

/* The CT head series: dims, spacing, RAS geometry, HU values equal to the NRRD's. */
static void
check_ct(const vv_volume *v) {
    assert_int_equal(v->dims[0], 256);
    assert_int_equal(v->dims[1], 256);
    assert_int_equal(v->dims[2], 108);
    assert_int_equal(v->type, VV_I16);
    assert_near(v->spacing[0], 0.9570312, 1e-6);
    assert_near(v->spacing[1], 0.9570312, 1e-6);
    assert_near(v->spacing[2], 1.5, 1e-6);
    assert_int_equal(v->space, VV_SPACE_RAS);
    assert_int_equal(v->unit, VV_UNIT_MM);
    assert_int_equal(v->data_origin, VV_ORIGIN_CT);
    /* LPS (120, 130, -80), rows along -x, columns along -y: RAS identity */
    assert_near(v->origin[0], -120, 1e-4);
    assert_near(v->origin[1], -130, 1e-4);
    assert_near(v->origin[2], -80, 1e-4);
    for (int i = 0; i < 9; i++)
        assert_near(v->direction[i], (i % 4) == 0, 1e-9);
    /* Hounsfield units: air -1024 outside the head, bone up to ~3000 */
    assert_near(v->range[0], -1024, 0);
    assert_near(v->range[1], 2986, 0);
    assert_true(vv_volume_get(v, 2, 2, 54) < -900); /* air */
    vv_volume *n = NULL;
    vt_ok(vv_volume_load(&n, vt_data("volumes/ct_head.nrrd"), NULL));
    assert_memory_equal(v->data, n->data, (size_t)256 * 256 * 108 * 2);
    vv_volume_free(n);
}

static void
test_ct_series(void **state) {
    (void)state;
    NEED_DATA();
    assert_int_equal(vv_format_detect(tmp("ct")), VV_FORMAT_DICOM);
    assert_int_equal(vv_format_detect(tmp("ct/slice0001.dcm")), VV_FORMAT_DICOM);
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, tmp("ct"), NULL));
    check_ct(v);
    vv_volume_free(v);

    vv_dicom_series *s = NULL;
    int n = 0;
    vt_ok(vv_dicom_list(&s, &n, tmp("ct")));
    assert_int_equal(n, 1);
    assert_string_equal(s[0].modality, "CT");
    assert_string_equal(s[0].description, "Head CT");
    assert_int_equal(s[0].dims[2], 108);
    assert_int_equal(s[0].n_files, 108);
    free(s);
}

/* The headers of a series are read in parallel (scan_files, an OpenMP loop):
 * with four threads, in this process (VOLVIS_SANDBOX=0) and in the reader,
 * the CT series and the listing of a folder of two series come out as with
 * one thread. scripts/tsan.sh runs this under ThreadSanitizer. */
static void
test_parallel_headers(void **state) {
    (void)state;
    NEED_DATA();
    int threads = vv_threads_get();
    for (int sandbox = 0; sandbox < 2; sandbox++) {
        if (sandbox)
            unsetenv("VOLVIS_SANDBOX");
        else
            setenv("VOLVIS_SANDBOX", "0", 1);
        vv_dicom_series *one = NULL, *four = NULL;
        int n_one = 0, n_four = 0;
        vv_threads_set(1);
        vt_ok(vv_dicom_list(&one, &n_one, tmp("mixed")));
        vv_threads_set(4);
        assert_int_equal(vv_threads_get(), 4);
        vt_ok(vv_dicom_list(&four, &n_four, tmp("mixed")));
        assert_int_equal(n_one, 2);
        assert_int_equal(n_four, n_one);
        assert_memory_equal(four, one, (size_t)n_one * sizeof *one);
        free(one);
        free(four);
        vv_volume *v = NULL;
        vt_ok(vv_volume_load(&v, tmp("ct"), NULL));
        check_ct(v);
        vv_volume_free(v);
    }
    unsetenv("VOLVIS_SANDBOX");
    vv_threads_set(threads);
}

/* Renamed files in a shuffled order, and an explicit list of files. */
static void
test_shuffled_renamed(void **state) {
    (void)state;
    NEED_DATA();
    char dir[512];
    snprintf(dir, sizeof dir, "%s", tmp("shuffled"));
    mkdir(dir, 0755);
    char **list = calloc(108, sizeof *list);
    for (int k = 0; k < 108; k++) {
        int to = (k * 37 + 11) % 108; /* a permutation (37 is prime to 108) */
        char from[64], name[64];
        snprintf(from, sizeof from, "ct/slice%04d.dcm", k + 1);
        snprintf(name, sizeof name, "IM%03d", to);
        copy_file(tmp(from), vt_path(dir, name));
        list[to] = strdup(vt_path(dir, name));
    }
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, dir, NULL));
    check_ct(v);
    vv_volume_free(v);
    vt_ok(vv_dicom_read_files(&v, (const char *const *)list, 108, 0, -1));
    check_ct(v);
    vv_volume_free(v);
    for (int k = 0; k < 108; k++)
        free(list[k]);
    free(list);
}

static void
test_missing_slice(void **state) {
    (void)state;
    NEED_DATA();
    char dir[512];
    snprintf(dir, sizeof dir, "%s", tmp("gap"));
    mkdir(dir, 0755);
    for (int k = 1; k <= 20; k++) {
        if (k == 12)
            continue;
        char from[64], name[64];
        snprintf(from, sizeof from, "ct/slice%04d.dcm", k);
        snprintf(name, sizeof name, "slice%04d.dcm", k);
        copy_file(tmp(from), vt_path(dir, name));
    }
    vv_volume *v = NULL;
    vt_err(vv_volume_load(&v, dir, NULL));
    assert_null(v);
    assert_one_line_naming("slice0011.dcm");
    assert_one_line_naming("slice0013.dcm");
    assert_non_null(strstr(vv_error_message(), "missing slice"));
    assert_non_null(strstr(vv_error_message(), "gap of 3 mm"));

    /* two slices at one position */
    copy_file(tmp("ct/slice0005.dcm"), vt_path(dir, "slice0012.dcm"));
    unlink(vt_path(dir, "slice0013.dcm"));
    vt_err(vv_volume_load(&v, dir, NULL));
    assert_non_null(strstr(vv_error_message(), "same position"));
}

/* Rotated orientation, instance numbers counting down: the frame follows IOP/IPP. */
static void
test_oblique(void **state) {
    (void)state;
    NEED_DATA();
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, tmp("obl"), NULL));
    assert_int_equal(v->dims[0], 64);
    assert_int_equal(v->dims[1], 64);
    assert_int_equal(v->dims[2], 12);
    const double pi = 3.14159265358979323846;
    double c = cos(30 * pi / 180), s = sin(30 * pi / 180);
    /* LPS row (-c, 0, s), column (0, -1, 0), normal (s, 0, c); RAS: x, y negated */
    const double want[9] = {c, 0, -s, 0, 1, 0, s, 0, c};
    for (int i = 0; i < 9; i++)
        assert_near(v->direction[i], want[i], 1e-6);
    assert_near(v->spacing[2], 1.5, 1e-5);
    /* the first slice is the lowest position, whatever the instance numbers */
    vv_volume *ct = NULL;
    vt_ok(vv_volume_load(&ct, tmp("ct"), NULL));
    for (int k = 0; k < 12; k++)
        for (int j = 0; j < 64; j += 7)
            for (int i = 0; i < 64; i += 5)
                assert_near(vv_volume_get(v, i, j, k), vv_volume_get(ct, i, j, 30 + k), 0);
    double origin_lps[3] = {120 + 30 * 1.5 * s, 130, -80 + 30 * 1.5 * c};
    assert_near(v->origin[0], -origin_lps[0], 1e-3);
    assert_near(v->origin[1], -origin_lps[1], 1e-3);
    assert_near(v->origin[2], origin_lps[2], 1e-3);
    vv_volume_free(ct);
    vv_volume_free(v);
}

/* An oblique slab resampled from the upright head: read with its rotated
 * orientation, every voxel lands where the same anatomy is in the upright
 * series, i.e. it renders upright (a tilted box around an upright head). */
static void
test_oblique_upright(void **state) {
    (void)state;
    NEED_DATA();
    vv_volume *obl = NULL, *ct = NULL;
    vt_ok(vv_volume_load(&obl, tmp("oblr"), NULL));
    vt_ok(vv_volume_load(&ct, tmp("ct"), NULL));
    assert_int_equal(obl->dims[0], 96);
    assert_int_equal(obl->dims[2], 24);
    assert_true(fabs(obl->direction[2]) > 0.4); /* really oblique */
    vv_mat4 to_world = vv_volume_index_to_world(obl);
    vv_mat4 to_index = vv_volume_world_to_index(ct);
    long n = 0, same = 0, tissue = 0;
    for (int k = 0; k < obl->dims[2]; k++)
        for (int j = 0; j < obl->dims[1]; j += 3)
            for (int i = 0; i < obl->dims[0]; i += 3) {
                vv_vec3 w = vv_mat4_mul_point(to_world, vv_vec3_make(i, j, k));
                vv_vec3 x = vv_mat4_mul_point(to_index, w);
                int ii = (int)floor(x.x + 0.5), jj = (int)floor(x.y + 0.5),
                    kk = (int)floor(x.z + 0.5);
                if (ii < 0 || jj < 0 || kk < 0 || ii >= 256 || jj >= 256 || kk >= 108)
                    continue;
                double a = vv_volume_get(obl, i, j, k), b = vv_volume_get(ct, ii, jj, kk);
                n++;
                same += a == b;
                tissue += b > -500;
            }
    assert_true(n > 5000);
    assert_true(tissue > n / 4); /* the slab goes through the head */
    if ((double)same < 0.99 * (double)n)
        fail_msg("only %ld of %ld oblique voxels match the upright head there", same, n);
    vv_volume_free(ct);
    vv_volume_free(obl);
}

/* One Enhanced CT file: geometry and rescale from the functional groups,
 * frames stored scrambled and sorted by their Plane Position. */
static void
test_enhanced_multiframe(void **state) {
    (void)state;
    NEED_DATA();
    vv_volume *v = NULL, *ct = NULL;
    vt_ok(vv_volume_load(&v, tmp("enhanced.dcm"), NULL));
    vt_ok(vv_volume_load(&ct, tmp("ct"), NULL));
    assert_int_equal(v->dims[0], 64);
    assert_int_equal(v->dims[1], 64);
    assert_int_equal(v->dims[2], 8);
    assert_int_equal(v->type, VV_I16);
    assert_near(v->spacing[0], 0.9570312, 1e-6);
    assert_near(v->spacing[2], 1.5, 1e-6);
    assert_near(v->origin[2], -80 + 40 * 1.5, 1e-4);
    for (int i = 0; i < 9; i++)
        assert_near(v->direction[i], (i % 4) == 0, 1e-9);
    for (int k = 0; k < 8; k++)
        for (int j = 0; j < 64; j++)
            for (int i = 0; i < 64; i++)
                if (vv_volume_get(v, i, j, k) != vv_volume_get(ct, i, j, 40 + k))
                    fail_msg("voxel (%d, %d, %d) differs from the series", i, j, k);
    vv_volume_free(ct);
    vv_volume_free(v);
}

static void
test_compressions(void **state) {
    (void)state;
    NEED_DATA();
    if (!g_have_gdcmconv)
        vt_skip("gdcmconv (libgdcm-tools) is not installed");
    vv_volume *ref = NULL;
    vt_ok(vv_volume_load(&ref, tmp("small"), NULL));
    assert_int_equal(ref->dims[2], 6);
    static const char *const syntaxes[] = {"jpeg", "jpegls", "j2k", "rle", "deflated", "implicit"};
    for (size_t i = 0; i < sizeof syntaxes / sizeof syntaxes[0]; i++) {
        char sub[64];
        snprintf(sub, sizeof sub, "comp/%s", syntaxes[i]);
        vv_volume *v = NULL;
        vv_status st = vv_volume_load(&v, tmp(sub), NULL);
        if (st != VV_OK)
            fail_msg("%s: %s", syntaxes[i], vv_error_message());
        assert_int_equal(v->type, ref->type);
        for (int d = 0; d < 3; d++)
            assert_int_equal(v->dims[d], ref->dims[d]);
        if (memcmp(v->data, ref->data, vv_volume_voxel_count(v) * 2) != 0)
            fail_msg("%s: voxels differ from the uncompressed series", syntaxes[i]);
        for (int d = 0; d < 9; d++)
            assert_near(v->direction[d], ref->direction[d], 1e-12);
        vv_volume_free(v);
    }
    vv_volume_free(ref);
}

static vv_volume *
load_file(const char *name) {
    char p[512];
    snprintf(p, sizeof p, "%s/%s", PYDICOM_FILES, name);
    vv_volume *v = NULL;
    vv_error_clear();
    if (vv_dicom_read(&v, p, 0, -1) != VV_OK)
        fail_msg("%s: %s", name, vv_error_message());
    return v;
}

/* nibabel's real Siemens MR slices (python3-nibabel): sizes and values as
 * pydicom reads them, and its pixel-less file is a one-line error naming
 * the file. */
static void
test_nibabel_files(void **state) {
    (void)state;
    if (access(NIBABEL_FILES "/0.dcm", R_OK) != 0)
        vt_skip("python3-nibabel's DICOM test files are not installed");
    static const struct {
        const char *name;
        int nx, ny;
        double lo, hi;
    } files[] = {{"0.dcm", 256, 256, 0, 4095},
                 {"1.dcm", 256, 256, 0, 4095},
                 {"slicethickness_empty_string.dcm", 384, 384, 0, 594},
                 /* slope 2, intercept -4096 over zero pixels */
                 {"decimal_rescale.dcm", 128, 96, -4096, -4096}};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char p[512];
        snprintf(p, sizeof p, "%s/%s", NIBABEL_FILES, files[i].name);
        vv_volume *v = NULL;
        vv_error_clear();
        if (vv_dicom_read(&v, p, 0, -1) != VV_OK)
            fail_msg("%s: %s", files[i].name, vv_error_message());
        assert_int_equal(v->dims[0], files[i].nx);
        assert_int_equal(v->dims[1], files[i].ny);
        assert_int_equal(v->dims[2], 1);
        assert_float_equal(v->range[0], files[i].lo, 1e-9);
        assert_float_equal(v->range[1], files[i].hi, 1e-9);
        vv_volume_free(v);
    }
    vv_volume *v = NULL;
    vv_error_clear();
    assert_int_not_equal(vv_dicom_read(&v, NIBABEL_FILES "/csa_slice_norm.dcm", 0, -1), VV_OK);
    assert_null(v);
    const char *msg = vv_error_message();
    assert_non_null(strstr(msg, "csa_slice_norm.dcm: truncated pixel data"));
    /* the file is named once, not twice */
    assert_null(strstr(strstr(msg, "csa_slice_norm.dcm") + 1, "csa_slice_norm.dcm"));
}

/* pydicom's files: the MR in every codec and byte order equals the plain one. */
static void
test_pydicom_files(void **state) {
    (void)state;
    if (access(PYDICOM_FILES "/MR_small.dcm", R_OK) != 0)
        vt_skip("python3-pydicom's test files are not installed");
    vv_volume *mr = load_file("MR_small.dcm");
    assert_int_equal(mr->dims[0], 64);
    assert_int_equal(mr->dims[1], 64);
    assert_int_equal(mr->dims[2], 1);
    assert_int_equal(mr->type, VV_I16);
    assert_true(mr->range[1] > mr->range[0]);
    static const char *const same[] = {"MR_small_RLE.dcm",          "MR_small_jpeg_ls_lossless.dcm",
                                       "MR_small_jp2klossless.dcm", "MR_small_bigendian.dcm",
                                       "MR_small_implicit.dcm",     "MR_small_expb.dcm"};
    for (size_t i = 0; i < sizeof same / sizeof same[0]; i++) {
        char p[512];
        snprintf(p, sizeof p, "%s/%s", PYDICOM_FILES, same[i]);
        if (access(p, R_OK) != 0)
            continue;
        vv_volume *v = load_file(same[i]);
        if (memcmp(v->data, mr->data, 64 * 64 * 2) != 0)
            fail_msg("%s decodes to other voxels than MR_small.dcm", same[i]);
        vv_volume_free(v);
    }
    vv_volume_free(mr);

    /* CT with Rescale Intercept -1024: Hounsfield units */
    vv_volume *ct = load_file("CT_small.dcm");
    assert_int_equal(ct->dims[0], 128);
    assert_true(ct->range[0] >= -1024 - 1);
    assert_int_equal(ct->data_origin, VV_ORIGIN_CT);
    vv_volume_free(ct);

    /* JPEG 2000 and JPEG extended (12-bit) */
    vv_volume *j2k = load_file("JPEG2000.dcm");
    assert_int_equal(j2k->dims[0], 256);
    assert_int_equal(j2k->dims[1], 1024);
    assert_true(j2k->range[1] > j2k->range[0]);
    vv_volume_free(j2k);
    vv_volume *jx = load_file("JPGExtended.dcm");
    assert_int_equal(jx->dims[1], 1024);
    assert_true(jx->range[1] > jx->range[0] && jx->range[1] < 4096);
    vv_volume_free(jx);

    /* multi-frame RLE RGB: 2 frames, a channel each */
    vv_volume *rgb[3];
    for (int c = 0; c < 3; c++) {
        char p[512];
        snprintf(p, sizeof p, "%s/SC_rgb_rle_2frame.dcm", PYDICOM_FILES);
        vt_ok(vv_dicom_read(&rgb[c], p, 0, c));
        assert_int_equal(rgb[c]->dims[0], 100);
        assert_int_equal(rgb[c]->dims[2], 2);
    }
    /* the test image is red, green and blue bands: channels differ */
    assert_true(memcmp(rgb[0]->data, rgb[1]->data, 100 * 100) != 0);
    for (int c = 0; c < 3; c++)
        vv_volume_free(rgb[c]);

    /* a multi-frame RT dose grid */
    vv_volume *dose = load_file("rtdose.dcm");
    assert_int_equal(dose->dims[0], 10);
    assert_int_equal(dose->dims[2], 15);
    vv_volume_free(dose);

    /* a DICOMDIR */
    vv_dicom_series *s = NULL;
    int n = 0;
    vt_ok(vv_dicom_list(&s, &n, PYDICOM_FILES "/dicomdirtests/DICOMDIR"));
    assert_true(n >= 1);
    free(s);
}

static void
test_mixed_series_and_cli(void **state) {
    (void)state;
    NEED_DATA();
    vv_volume *v = NULL;
    vt_err(vv_volume_load(&v, tmp("mixed"), NULL));
    assert_null(v);
    assert_one_line_naming("mixed");
    assert_non_null(strstr(vv_error_message(), "--series"));
    vv_load_options o;
    vv_load_options_init(&o);
    o.series = 2; /* numbers 1 then 7 */
    vt_ok(vv_volume_load(&v, tmp("mixed"), &o));
    assert_int_equal(v->dims[0], 32);
    assert_int_equal(v->dims[2], 3);
    vv_volume_free(v);
    o.series = 3;
    vt_err(vv_volume_load(&v, tmp("mixed"), &o));

    /* the listing is read by GDCM in volvis-reader (the sandbox): the same
     * series, byte for byte, as read in this process; a reader that
     * aborts while listing is one line */
    vv_dicom_series *sb = NULL, *in = NULL;
    int nsb = 0, nin = 0;
    vt_ok(vv_dicom_list(&sb, &nsb, tmp("mixed")));
    setenv("VOLVIS_SANDBOX", "0", 1);
    vt_ok(vv_dicom_list(&in, &nin, tmp("mixed")));
    unsetenv("VOLVIS_SANDBOX");
    assert_int_equal(nsb, 2);
    assert_int_equal(nsb, nin);
    assert_memory_equal(sb, in, (size_t)nin * sizeof *in);
    free(sb);
    free(in);
    setenv("VOLVIS_SANDBOX_INJECT", "abort", 1);
    vt_err(vv_dicom_list(&sb, &nsb, tmp("mixed")));
    unsetenv("VOLVIS_SANDBOX_INJECT");
    assert_null(sb);
    assert_int_equal(nsb, 0);
    assert_one_line_naming("mixed");
    assert_non_null(strstr(vv_error_message(), "the DICOM reader crashed (SIGABRT)"));

    const char *out = vt_outdir("io_dicom");
    const char *info[] = {"info", tmp("mixed"), NULL};
    vt_run_result r = vt_run_cli_v(out, info);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "2 series"));
    assert_non_null(strstr(r.out, "Scout"));
    assert_null(strstr(r.out, "VOLVIS^TEST"));
    assert_null(strstr(r.out, "VV-PHI-0001"));
    vt_run_result_free(&r);
    const char *phi[] = {"info", "--show-phi", tmp("mixed"), NULL};
    r = vt_run_cli_v(out, phi);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "VOLVIS^TEST"));
    assert_non_null(strstr(r.out, "VV-PHI-0001"));
    vt_run_result_free(&r);

    const char *png = vt_path(out, "scout.png");
    const char *render[] = {"render", tmp("mixed"), "--series", "2", "--size",
                            "64x64",  "-q",         "-o",       png, NULL};
    r = vt_run_cli_v(out, render);
    if (r.status != 0)
        fail_msg("render --series 2: %s", r.err);
    vt_run_result_free(&r);
    const char *render_bad[] = {"render", tmp("mixed"), "--size", "64x64", "-q", "-o", png, NULL};
    r = vt_run_cli_v(out, render_bad);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "--series"));
    vt_run_result_free(&r);

    /* converted files carry no patient identifier */
    const char *nrrd = vt_path(out, "small.nrrd");
    const char *conv[] = {"convert", "-q", tmp("small"), nrrd, NULL};
    r = vt_run_cli_v(out, conv);
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    size_t n;
    unsigned char *d = vt_read_file(nrrd, &n);
    assert_false(contains(d, n, "VOLVIS"));
    assert_false(contains(d, n, "VV-PHI"));
    free(d);
}

static void
test_bad_input(void **state) {
    (void)state;
    NEED_DATA();
    vv_volume *v = NULL;
    /* a folder with no DICOM */
    const char *none = tmp("nodicom");
    mkdir(none, 0755);
    vt_write_file(vt_path(none, "a.txt"), "hello", 5);
    vt_err(vv_dicom_read(&v, none, 0, -1));
    assert_one_line_naming("nodicom");
    assert_non_null(strstr(vv_error_message(), "no DICOM images"));
    vt_err(vv_volume_load(&v, none, NULL));
    assert_one_line_naming("nodicom");

    /* absurd rows and columns */
    const char *big = tmp("absurd");
    mkdir(big, 0755);
    int rc = run("%s -c \"import pydicom; d = pydicom.dcmread('%s'); d.Rows = 65535; "
                 "d.Columns = 65535; d.save_as('%s/huge.dcm')\"",
                 PYTHON, tmp("small/slice0001.dcm"), big);
    assert_int_equal(rc, 0);
    vt_err(vv_volume_load(&v, big, NULL));
    assert_null(v);
    assert_one_line_naming("huge.dcm");

    /* truncated pixel data */
    const char *tr = tmp("trunc");
    mkdir(tr, 0755);
    size_t n;
    unsigned char *d = vt_read_file(tmp("small/slice0002.dcm"), &n);
    vt_write_file(vt_path(tr, "cut.dcm"), d, n - 3000);
    free(d);
    vt_err(vv_volume_load(&v, tr, NULL));
    assert_null(v);
    assert_one_line_naming("cut.dcm");
    if (access(PYDICOM_FILES "/MR_truncated.dcm", R_OK) == 0) {
        vt_err(vv_dicom_read(&v, PYDICOM_FILES "/MR_truncated.dcm", 0, -1));
        assert_one_line_naming("MR_truncated.dcm");
    }

    /* a corrupt JPEG stream: the middle of the compressed data overwritten */
    if (g_have_gdcmconv) {
        const char *cj = tmp("corrupt_jpeg");
        mkdir(cj, 0755);
        static const char *const codecs[] = {"jpeg", "jpegls", "j2k", "rle"};
        for (size_t i = 0; i < sizeof codecs / sizeof codecs[0]; i++) {
            char from[64];
            snprintf(from, sizeof from, "comp/%s/slice0001.dcm", codecs[i]);
            d = vt_read_file(tmp(from), &n);
            /* the compressed stream is the file's tail: cut most of it away */
            size_t keep = n - (n - 1500) / 2;
            char name[64];
            snprintf(name, sizeof name, "%s_cut.dcm", codecs[i]);
            vt_write_file(vt_path(cj, name), d, keep);
            free(d);
            vt_err(vv_dicom_read_files(&v, (const char *const[]){vt_path(cj, name)}, 1, 0, -1));
            assert_null(v);
            assert_one_line_naming(name);
        }
    }
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ct_series),
        cmocka_unit_test(test_parallel_headers),
        cmocka_unit_test(test_shuffled_renamed),
        cmocka_unit_test(test_missing_slice),
        cmocka_unit_test(test_oblique),
        cmocka_unit_test(test_oblique_upright),
        cmocka_unit_test(test_enhanced_multiframe),
        cmocka_unit_test(test_compressions),
        cmocka_unit_test(test_pydicom_files),
        cmocka_unit_test(test_nibabel_files),
        cmocka_unit_test(test_mixed_series_and_cli),
        cmocka_unit_test(test_bad_input),
    };
    return vt_run_tests(tests, setup, teardown);
}
