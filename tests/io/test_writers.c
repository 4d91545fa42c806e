/*
 * The NIfTI, MetaImage and TIFF writers (issue 34): byte-identical voxels
 * for every voxel type through .nii, .nii.gz, NIfTI-2, .mha and .mhd (raw
 * and zlib), .tif and .ome.tif (every codec, BigTIFF), geometry carried (an oblique direction; LPS
 * into NIfTI's RAS and RAS into MetaImage's LPS, x and y negated), and the failures: a full disk
 * (RLIMIT_FSIZE), an unwritable folder, a float label volume, a .hdr name;
 * each a one-line error naming the file, with no file left behind; and
 * nanometres through every writer (kept, or converted to microns). The
 * independent readers (nibabel, VTK) are in tests/writers.
 */
#include "testutil.h"

#include <dirent.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "volvis/io.h"

/* A volume of @p t with values over the type's whole range (seeded), an
 * oblique orthonormal direction, spacing (0.7, 1.1, 2.3), origin (-5, 7, 11). */
static vv_volume *
make_volume(vv_voxel_type t, int nx, int ny, int nz, vv_space space) {
    int dims[3] = {nx, ny, nz};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, t));
    uint64_t seed = 1234 + (uint64_t)t;
    size_t bytes = (size_t)vv_volume_voxel_count(v) * vv_voxel_type_size(t);
    unsigned char *p = v->data;
    for (size_t i = 0; i < bytes; i++)
        p[i] = (unsigned char)(vt_rnd(&seed, 0, 256));
    if (t == VV_F32) /* no NaN bit patterns: values compare */
        for (size_t i = 0; i < bytes / 4; i++)
            ((float *)v->data)[i] = (float)vt_rnd(&seed, -1e6, 1e6);
    if (t == VV_F64)
        for (size_t i = 0; i < bytes / 8; i++)
            ((double *)v->data)[i] = vt_rnd(&seed, -1e12, 1e12);
    double a = 0.3, b = -0.2; /* rotation about z by a, then about x by b */
    double rz[9] = {cos(a), -sin(a), 0, sin(a), cos(a), 0, 0, 0, 1};
    double rx[9] = {1, 0, 0, 0, cos(b), -sin(b), 0, sin(b), cos(b)};
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double s = 0;
            for (int k = 0; k < 3; k++)
                s += rx[r * 3 + k] * rz[k * 3 + c];
            v->direction[r * 3 + c] = s;
        }
    v->spacing[0] = 0.7;
    v->spacing[1] = 1.1;
    v->spacing[2] = 2.3;
    v->origin[0] = -5;
    v->origin[1] = 7;
    v->origin[2] = 11;
    v->unit = VV_UNIT_MM;
    v->space = space;
    vv_volume_update_range(v);
    return v;
}

/* Asserts @p back has @p v's voxels byte for byte and its geometry, x and y
 * negated when @p flip, to @p eps. */
static void
assert_same(const vv_volume *v, const vv_volume *back, int flip, double eps) {
    assert_int_equal(back->type, v->type);
    for (int i = 0; i < 3; i++)
        assert_int_equal(back->dims[i], v->dims[i]);
    size_t bytes = (size_t)vv_volume_voxel_count(v) * vv_voxel_type_size(v->type);
    assert_memory_equal(back->data, v->data, bytes);
    for (int r = 0; r < 3; r++) {
        double s = flip && r < 2 ? -1 : 1;
        assert_near(back->spacing[r], v->spacing[r], eps);
        assert_near(back->origin[r], s * v->origin[r], eps * 10);
        for (int c = 0; c < 3; c++)
            assert_near(back->direction[r * 3 + c], s * v->direction[r * 3 + c], eps);
    }
}

static void
roundtrip(const char *name, const vv_save_options *o, vv_space space, int flip, double eps) {
    const char *dir = vt_outdir("io_writers");
    for (int t = VV_U8; t <= VV_F64; t++) {
        vv_volume *v = make_volume((vv_voxel_type)t, 13, 7, 5, space), *back = NULL;
        const char *path = vt_path(dir, name);
        vt_ok(vv_volume_save_with(v, path, o));
        vt_ok(vv_volume_load(&back, path, NULL));
        assert_same(v, back, flip, eps);
        vv_volume_free(back);
        vv_volume_free(v);
    }
}

static void
test_nifti_types(void **state) {
    (void)state;
    vv_save_options o;
    vv_save_options_init(&o);
    /* NIfTI-1 keeps the geometry as 32-bit floats */
    roundtrip("types.nii", &o, VV_SPACE_RAS, 0, 1e-6);
    roundtrip("types.nii.gz", &o, VV_SPACE_UNKNOWN, 0, 1e-6);
    roundtrip("types_lps.nii.gz", &o, VV_SPACE_LPS, 1, 1e-6);
    o.nifti_version = 2; /* doubles */
    roundtrip("types2.nii", &o, VV_SPACE_RAS, 0, 1e-12);
}

static void
test_mhd_types(void **state) {
    (void)state;
    vv_save_options o;
    vv_save_options_init(&o);
    roundtrip("types.mha", &o, VV_SPACE_LPS, 0, 1e-14);
    roundtrip("types_ras.mha", &o, VV_SPACE_RAS, 1, 1e-14);
    roundtrip("types.mhd", &o, VV_SPACE_UNKNOWN, 0, 1e-14);
    o.compress = 0;
    roundtrip("types_raw.mha", &o, VV_SPACE_UNKNOWN, 0, 1e-14);
    roundtrip("types_raw.mhd", &o, VV_SPACE_UNKNOWN, 0, 1e-14);
}

/* TIFF holds no direction: the volumes are axis-aligned. Plain .tif keeps
 * the in-plane spacing as a 32-bit rational (1 / XResolution), OME-TIFF
 * every figure as written (%.17g). */
static void
tiff_roundtrip(const char *name, const vv_save_options *o, double eps) {
    const char *dir = vt_outdir("io_writers");
    for (int t = VV_U8; t <= VV_F64; t++) {
        vv_volume *v = make_volume((vv_voxel_type)t, 13, 7, 5, VV_SPACE_UNKNOWN), *back = NULL;
        for (int i = 0; i < 9; i++)
            v->direction[i] = i % 4 == 0;
        const char *path = vt_path(dir, name);
        vt_ok(vv_volume_save_with(v, path, o));
        vt_ok(vv_volume_load(&back, path, NULL));
        assert_same(v, back, 0, eps);
        assert_int_equal(back->unit, VV_UNIT_MM);
        vv_volume_free(back);
        vv_volume_free(v);
    }
}

static void
test_tiff_types(void **state) {
    (void)state;
    vv_save_options o;
    vv_save_options_init(&o);
    tiff_roundtrip("types.ome.tif", &o, 1e-12);
    tiff_roundtrip("types.tif", &o, 1e-6);
    static const char *const codecs[] = {"lzw", "zstd", "packbits", "none"};
    for (size_t i = 0; i < sizeof codecs / sizeof codecs[0]; i++) {
        o.codec = codecs[i];
        tiff_roundtrip("codec.ome.tiff", &o, 1e-12);
    }
    o.codec = NULL;
    o.compress = 0;
    tiff_roundtrip("plain.tiff", &o, 1e-6);
    /* BigTIFF on request: the header's version 43 */
    o.compress = -1;
    o.bigtiff = 1;
    tiff_roundtrip("big.ome.tif", &o, 1e-12);
    size_t n = 0;
    unsigned char *b = vt_read_file(vt_path(vt_outdir("io_writers"), "big.ome.tif"), &n);
    assert_true(n > 8 && b[0] == 'I' && b[1] == 'I' && b[2] == 43 && b[3] == 0);
    free(b);
}

/* The compressed streams (zout: 1 MiB blocks deflated on every core) of a
 * volume of 24 MiB, past several batches: the voxels come back, and the
 * files are byte-identical for 1, 2 and 5 threads. */
static void
test_parallel_deflate(void **state) {
    (void)state;
    vv_volume *v = make_volume(VV_I32, 256, 256, 96, VV_SPACE_RAS);
    int32_t *d = v->data;
    for (size_t i = 0; i < (size_t)256 * 256 * 96; i++) /* compressible, not trivially */
        d[i] = (int32_t)((i / 7) % 1000) + (int32_t)(i % 13 == 0) * (int32_t)i;
    vv_volume_update_range(v);
    const char *dir = vt_outdir("io_writers");
    static const char *const names[] = {"par.nii.gz", "par.mha"};
    int keep = vv_threads_get();
    for (size_t f = 0; f < 2; f++) {
        unsigned char *first = NULL;
        size_t first_n = 0;
        for (int t = 1; t <= 5; t += t == 1 ? 1 : 3) {
            vv_threads_set(t);
            char name[64];
            snprintf(name, sizeof name, "t%d_%s", t, names[f]);
            const char *path = vt_path(dir, name);
            vt_ok(vv_volume_save_with(v, path, NULL));
            vv_volume *back = NULL;
            vt_ok(vv_volume_load(&back, path, NULL));
            assert_memory_equal(back->data, v->data, (size_t)256 * 256 * 96 * 4);
            vv_volume_free(back);
            size_t n = 0;
            unsigned char *b = vt_read_file(path, &n);
            if (!first) {
                first = b;
                first_n = n;
            } else {
                assert_int_equal(n, first_n);
                assert_memory_equal(b, first, n);
                free(b);
            }
        }
        free(first);
    }
    vv_threads_set(keep);
    vv_volume_free(v);
}

/* An axis of 40000 voxels is NIfTI-2 (NIfTI-1 holds 32767); asking for
 * NIfTI-1 is an error. */
static void
test_nifti2_long_axis(void **state) {
    (void)state;
    const char *dir = vt_outdir("io_writers");
    vv_volume *v = make_volume(VV_U8, 40000, 2, 1, VV_SPACE_RAS), *back = NULL;
    const char *path = vt_path(dir, "long.nii");
    vt_ok(vv_volume_save_with(v, path, NULL));
    size_t n = 0;
    unsigned char *bytes = vt_read_file(path, &n);
    assert_int_equal(n, 544 + 80000);
    int32_t hs;
    memcpy(&hs, bytes, 4);
    assert_int_equal(hs, 540);
    free(bytes);
    vt_ok(vv_volume_load(&back, path, NULL));
    assert_same(v, back, 0, 1e-12);
    vv_volume_free(back);
    vv_save_options o;
    vv_save_options_init(&o);
    o.nifti_version = 1;
    unlink(path);
    assert_int_equal(vv_volume_save_with(v, path, &o), VV_ERR_UNSUPPORTED);
    assert_non_null(strstr(vv_error_message(), "32767"));
    assert_int_not_equal(access(path, F_OK), 0);
    vv_volume_free(v);
}

/* Number of entries of @p dir other than . and .. */
static int
entries(const char *dir) {
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return n;
}

/* Asserts the last error is one line naming @p name. */
static void
assert_one_line(const char *name) {
    const char *m = vv_error_message();
    if (!strstr(m, name) || strchr(m, '\n'))
        fail_msg("not a one-line error naming %s: \"%s\"", name, m);
}

/* A file-size limit of 64 KiB (a full disk) under a 1 MiB volume: each
 * writer fails with one line naming the file and leaves no file. The limit
 * is this process's soft limit, lowered for the write and raised back (no
 * fork: a child of a process with OpenMP threads can deadlock in them). */
static void
test_full_disk(void **state) {
    (void)state;
    char dir[512];
    snprintf(dir, sizeof dir, "%s/fsize", vt_outdir("io_writers"));
    mkdir(dir, 0755);
    static const char *const names[] = {"full.nii", "full.nii.gz",  "full.mha",    "full_raw.mha",
                                        "full.mhd", "full_raw.tif", "full.ome.tif"};
    vv_volume *v = make_volume(VV_U8, 128, 128, 64, VV_SPACE_RAS);
    void (*was)(int) = signal(SIGXFSZ, SIG_IGN);
    struct rlimit keep;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &keep), 0);
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        unlink(vt_path(dir, names[i]));
        vv_save_options o;
        vv_save_options_init(&o);
        o.compress = strstr(names[i], "raw") ? 0 : 1;
        struct rlimit rl = {64 * 1024, keep.rlim_max};
        assert_int_equal(setrlimit(RLIMIT_FSIZE, &rl), 0);
        vv_status s = vv_volume_save_with(v, vt_path(dir, names[i]), &o);
        assert_int_equal(setrlimit(RLIMIT_FSIZE, &keep), 0);
        const char *m = vv_error_message();
        if (!(s == VV_ERR_IO && strstr(m, names[i]) && !strchr(m, '\n')))
            fail_msg("%s: status %d, \"%s\"", names[i], (int)s, m);
        assert_int_equal(entries(dir), 0);
    }
    signal(SIGXFSZ, was);
    vv_volume_free(v);
}

static void
test_errors(void **state) {
    (void)state;
    vv_volume *v = make_volume(VV_F32, 4, 4, 4, VV_SPACE_RAS);
    const char *dir = vt_outdir("io_writers");
    /* an unwritable folder: one line, nothing there */
    char ro[512];
    snprintf(ro, sizeof ro, "%s/missing-folder", dir);
    static const char *const names[] = {"a.nii", "a.nii.gz", "a.mha", "a.mhd", "a.tif"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        vv_error_clear();
        assert_int_equal(vv_volume_save_with(v, vt_path(ro, names[i]), NULL), VV_ERR_IO);
        assert_one_line(names[i]);
    }
    /* a codec TIFF does not know */
    vv_save_options o;
    vv_save_options_init(&o);
    o.codec = "jpeg2000";
    const char *p = vt_path(dir, "codec.tif");
    unlink(p);
    vv_error_clear();
    assert_int_equal(vv_volume_save_with(v, p, &o), VV_ERR_INVALID);
    assert_one_line("codec.tif");
    assert_non_null(strstr(vv_error_message(), "jpeg2000"));
    assert_int_not_equal(access(p, F_OK), 0);
    o.codec = NULL;
    /* a float label volume cannot be NIfTI's LABEL intent */
    o.label = 1;
    p = vt_path(dir, "label_f32.nii");
    unlink(p);
    vv_error_clear();
    assert_int_equal(vv_volume_save_with(v, p, &o), VV_ERR_UNSUPPORTED);
    assert_one_line("label_f32.nii");
    assert_non_null(strstr(vv_error_message(), "integers"));
    assert_int_not_equal(access(p, F_OK), 0);
    /* NIfTI is written as one file only */
    o.label = 0;
    o.format = VV_FORMAT_NIFTI;
    p = vt_path(dir, "pair.hdr");
    vv_error_clear();
    assert_int_equal(vv_volume_save_with(v, p, &o), VV_ERR_UNSUPPORTED);
    assert_one_line("pair.hdr");
    assert_int_not_equal(access(p, F_OK), 0);
    vv_volume_free(v);
}

/* The label intent is written: NIfTI-1 intent_code (offset 68) 1002. */
static void
test_label_intent(void **state) {
    (void)state;
    vv_volume *v = make_volume(VV_U16, 4, 4, 4, VV_SPACE_RAS);
    vv_save_options o;
    vv_save_options_init(&o);
    o.label = 1;
    const char *p = vt_path(vt_outdir("io_writers"), "label.nii");
    vt_ok(vv_volume_save_with(v, p, &o));
    size_t n = 0;
    unsigned char *b = vt_read_file(p, &n);
    int16_t code;
    memcpy(&code, b + 68, 2);
    assert_int_equal(code, 1002);
    free(b);
    vv_volume_free(v);
}

/* OME-Zarr's folder is written as a whole or not at all: a path that is
 * not a Zarr store is refused and left as it was, an old store is replaced
 * (no file of it left), and a full disk leaves nothing (no temporary). The
 * voxels are read back by zarr-python in writers_independent.py. */
/* Nanometres (electron microscopy: Neuroglancer precomputed, OME-Zarr's
 * "nanometer"): the unit's names, and every writer's file read back. NRRD,
 * TIFF (ImageJ and OME), OME-Zarr and .vvb keep nm; SLC and NIfTI, which
 * name no nanometres, hold microns, the spacing and origin divided by 1000. */
static void
test_nanometres(void **state) {
    (void)state;
    assert_int_equal(vv_unit_parse("nm"), VV_UNIT_NM);
    assert_int_equal(vv_unit_parse("nanometer"), VV_UNIT_NM);
    assert_int_equal(vv_unit_parse("nanometres"), VV_UNIT_NM);
    assert_int_equal(vv_unit_parse("micrometre"), VV_UNIT_MICRON);
    assert_int_equal(vv_unit_parse("nanoseconds"), VV_UNIT_UNKNOWN);
    assert_string_equal(vv_unit_name(VV_UNIT_NM), "nm");
    assert_string_equal(vv_unit_name((vv_unit)(VV_UNIT_LAST + 1)), "unknown");
    static const struct {
        const char *name;
        vv_unit unit;
        double scale; /* the file's spacing over the volume's */
    } cases[] = {{"nm.nrrd", VV_UNIT_NM, 1},         {"nm.tif", VV_UNIT_NM, 1},
                 {"nm.ome.tif", VV_UNIT_NM, 1},      {"nm.ome.zarr", VV_UNIT_NM, 1},
                 {"nm.vvb", VV_UNIT_NM, 1},          {"nm.slc", VV_UNIT_MICRON, 1e-3},
                 {"nm.nii.gz", VV_UNIT_MICRON, 1e-3}};
    const char *dir = vt_outdir("io_writers");
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        vv_volume *v = make_volume(VV_U8, 12, 10, 6, VV_SPACE_UNKNOWN), *back = NULL;
        for (int i = 0; i < 9; i++)
            v->direction[i] = i % 4 == 0;
        const double sp[3] = {4, 4, 40}, org[3] = {800, 1200, 4000};
        for (int a = 0; a < 3; a++) {
            v->spacing[a] = sp[a];
            v->origin[a] = org[a];
        }
        v->unit = VV_UNIT_NM;
        const char *path = vt_path(dir, cases[c].name);
        vt_ok(vv_volume_save(v, path, VV_FORMAT_AUTO, 0));
        vt_ok(vv_volume_load(&back, path, NULL));
        print_message("# %s: unit %s, spacing %g %g %g\n", cases[c].name, vv_unit_name(back->unit),
                      back->spacing[0], back->spacing[1], back->spacing[2]);
        assert_int_equal(back->unit, cases[c].unit);
        for (int a = 0; a < 3; a++)
            assert_near(back->spacing[a], sp[a] * cases[c].scale, 1e-6 * sp[a] * cases[c].scale);
        assert_memory_equal(back->data, v->data, (size_t)vv_volume_voxel_count(v));
        vv_volume_free(back);
        vv_volume_free(v);
    }
}

static void
test_zarr_store(void **state) {
    (void)state;
    char dir[512];
    snprintf(dir, sizeof dir, "%s/zarr", vt_outdir("io_writers"));
    mkdir(dir, 0755);
    vv_volume *v = make_volume(VV_U16, 100, 90, 70, VV_SPACE_RAS);
    for (int i = 0; i < 9; i++)
        v->direction[i] = i % 4 == 0;
    /* a plain file by that name: refused, untouched */
    const char *p = vt_path(dir, "notes.zarr");
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    fputs("mine", f);
    fclose(f);
    vv_error_clear();
    assert_int_equal(vv_volume_save_with(v, p, NULL), VV_ERR_IO);
    assert_one_line("notes.zarr");
    size_t n = 0;
    char *back = (char *)vt_read_file(p, &n);
    assert_true(n == 4 && !memcmp(back, "mine", 4));
    free(back);
    unlink(p);
    /* a store (OME-NGFF 0.5 by default: Zarr v3), then a smaller one over
     * it: the old level 1 is gone */
    p = vt_path(dir, "a.ome.zarr");
    vt_ok(vv_volume_save_with(v, p, NULL));
    char lvl[600];
    snprintf(lvl, sizeof lvl, "%s/1/zarr.json", p);
    assert_int_equal(access(lvl, F_OK), 0);
    vv_volume *small = make_volume(VV_U8, 20, 20, 20, VV_SPACE_RAS);
    for (int i = 0; i < 9; i++)
        small->direction[i] = i % 4 == 0;
    vt_ok(vv_volume_save_with(small, p, NULL));
    assert_int_not_equal(access(lvl, F_OK), 0);
    snprintf(lvl, sizeof lvl, "%s/0/zarr.json", p);
    back = (char *)vt_read_file(lvl, &n);
    assert_non_null(strstr(back, "\"uint8\""));
    free(back);
    assert_int_equal(entries(dir), 1);
    /* and a Zarr v2 store (0.4) over the v3 one: no zarr.json left */
    vv_save_options o4;
    vv_save_options_init(&o4);
    o4.ngff_version = 4;
    vt_ok(vv_volume_save_with(small, p, &o4));
    assert_int_not_equal(access(lvl, F_OK), 0);
    snprintf(lvl, sizeof lvl, "%s/0/.zarray", p);
    back = (char *)vt_read_file(lvl, &n);
    assert_non_null(strstr(back, "\"|u1\""));
    free(back);
    assert_int_equal(entries(dir), 1);
    /* a full disk (64 KiB per file, a 1.2 MB level): one line, nothing left
     * but the store written before */
    void (*was)(int) = signal(SIGXFSZ, SIG_IGN);
    struct rlimit keep;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &keep), 0);
    vv_save_options o;
    vv_save_options_init(&o);
    o.compress = 0;
    struct rlimit rl = {64 * 1024, keep.rlim_max};
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &rl), 0);
    vv_error_clear();
    vv_status s = vv_volume_save_with(v, vt_path(dir, "full.zarr"), &o);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &keep), 0);
    signal(SIGXFSZ, was);
    assert_int_equal(s, VV_ERR_IO);
    assert_one_line("full.zarr");
    assert_int_equal(entries(dir), 1);
    vv_volume_free(small);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nifti_types),      cmocka_unit_test(test_mhd_types),
        cmocka_unit_test(test_nifti2_long_axis), cmocka_unit_test(test_full_disk),
        cmocka_unit_test(test_errors),           cmocka_unit_test(test_label_intent),
        cmocka_unit_test(test_tiff_types),       cmocka_unit_test(test_parallel_deflate),
        cmocka_unit_test(test_zarr_store),       cmocka_unit_test(test_nanometres),
    };
    return vt_run_tests(tests, NULL, NULL);
}
