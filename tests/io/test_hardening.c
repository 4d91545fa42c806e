/*
 * Hardening of the readers against hostile files (issue 21): the memory
 * budget, the detached-data policy of NRRD and MetaImage (/etc/passwd, a
 * folder, ../../, links out of the folder, /dev/zero, a list of a million
 * names, printf patterns), sizes whose product overflows or exceeds the
 * budget, gzip and zlib bombs generated here by streaming (never committed),
 * NIfTI-2 headers with absurd dim[0], malformed OFF meshes that made Assimp
 * abort, a scene naming itself as its volume, a .vvc whose index points past
 * its end, Teem's memory on failed loads, and the CLI's --max-memory and
 * header-only `info` of a .vvc.
 */
#include "testutil.h"

#include "io/io_internal.h"

#include <errno.h>
#include <malloc.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include <zlib.h>

/*
 * GDCM leaks what it allocated on some malformed files it refuses (an
 * exception thrown past its own buffers): suppress exactly GDCM's
 * allocations (and the file buffer of its stream) for LeakSanitizer. Full
 * stacks are needed to see the GDCM frames.
 */
const char *__lsan_default_suppressions(void);
const char *__asan_default_options(void);
const char *
__lsan_default_suppressions(void) {
    return "leak:libgdcmDSED.so\nleak:libgdcmMSFF.so\nleak:libgdcmCommon.so\n"
           "leak:_M_allocate_internal_buffer\n";
}
const char *
__asan_default_options(void) {
    return "fast_unwind_on_malloc=0";
}

static char g_dir[256];

static const char *
tpath(const char *name) {
    return vt_path(g_dir, name);
}

static void write_text(const char *path, const char *fmt, ...) VV_PRINTF(2, 3);
static void
write_text(const char *path, const char *fmt, ...) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(f, fmt, ap);
    va_end(ap);
    assert_int_equal(fclose(f), 0);
}

static double
now_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Asserts status @p want and that the message holds @p needle. */
static void
expect_error(vv_status got, vv_status want, const char *needle) {
    const char *msg = vv_error_message();
    if (got != want)
        fail_msg("got %s, expected %s: %s", vv_status_name(got), vv_status_name(want), msg);
    if (needle && !strstr(msg, needle))
        fail_msg("message '%s' does not mention '%s'", msg, needle);
}

/*
 * Appends to @p f a gzip (@p gzip 1) or zlib stream of @p zeros zero bytes,
 * deflated in chunks so that nothing of that size is ever in memory.
 */
static void
append_zero_stream(FILE *f, uint64_t zeros, int gzip) {
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    assert_int_equal(deflateInit2(&zs, 9, Z_DEFLATED, gzip ? 15 + 16 : 15, 9, Z_DEFAULT_STRATEGY),
                     Z_OK);
    static unsigned char in[1 << 20], out[1 << 16];
    memset(in, 0, sizeof in);
    uint64_t left = zeros;
    int flush;
    do {
        size_t n = left < sizeof in ? (size_t)left : sizeof in;
        left -= n;
        flush = left == 0 ? Z_FINISH : Z_NO_FLUSH;
        zs.next_in = in;
        zs.avail_in = (uInt)n;
        do {
            zs.next_out = out;
            zs.avail_out = sizeof out;
            deflate(&zs, flush);
            size_t have = sizeof out - zs.avail_out;
            assert_int_equal(fwrite(out, 1, have, f), have);
        } while (zs.avail_out == 0);
    } while (flush != Z_FINISH);
    deflateEnd(&zs);
}

static int
setup(void **state) {
    (void)state;
    snprintf(g_dir, sizeof g_dir, "%s/hardening", vt_outdir("io_hardening"));
    mkdir(g_dir, 0755);
    return 0;
}

static int
teardown_budget(void **state) {
    (void)state;
    vv_memory_budget_set(0);
    return 0;
}

/* ---- the memory budget ------------------------------------------------- */

static void
test_memory_budget(void **state) {
    (void)state;
    uint64_t b = 0;
    vt_ok(vv_memory_size_parse("512M", &b));
    assert_true(b == (uint64_t)512 << 20);
    vt_ok(vv_memory_size_parse("8G", &b));
    assert_true(b == (uint64_t)8 << 30);
    vt_ok(vv_memory_size_parse("1.5KiB", &b));
    assert_true(b == 1536);
    vt_ok(vv_memory_size_parse("4096", &b));
    assert_true(b == 4096);
    vt_err(vv_memory_size_parse("lots", &b));
    vt_err(vv_memory_size_parse("5Q", &b));
    vt_err(vv_memory_size_parse("-1G", &b));

    vv_memory_budget_set(0);
    assert_true(vv_memory_budget_get() >= (uint64_t)64 << 20);
    vv_memory_budget_set((uint64_t)1 << 20);
    assert_true(vv_memory_budget_get() == (uint64_t)1 << 20);
    vv_volume *v = NULL;
    int dims[3] = {128, 128, 128};
    vv_error_clear();
    expect_error(vv_volume_new(&v, dims, VV_U8), VV_ERR_LIMIT, "memory budget");
    assert_null(v);
    int small[3] = {64, 64, 64};
    vt_ok(vv_volume_new(&v, small, VV_U8));
    vv_volume_free(v);
    vv_memory_budget_set(0);
}

/* ---- NRRD: the detached-data policy ------------------------------------ */

static vv_status
load_nhdr(const char *name, const char *data_file) {
    write_text(tpath(name),
               "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
               "data file: %s\n",
               data_file);
    vv_volume *v = NULL;
    vv_error_clear();
    vv_status s = vv_nrrd_read(&v, tpath(name));
    vv_volume_free(v);
    return s;
}

static void
test_nrrd_detached_policy(void **state) {
    (void)state;
    write_text(tpath("data.raw"), "abcdefgh");
    char sub[512];
    snprintf(sub, sizeof sub, "%s", tpath("sub"));
    mkdir(sub, 0755);
    write_text(tpath("sub/d.raw"), "ABCDEFGH");

    vt_ok(load_nhdr("ok.nhdr", "data.raw"));
    vt_ok(load_nhdr("ok_sub.nhdr", "sub/d.raw"));
    expect_error(load_nhdr("passwd.nhdr", "/etc/passwd"), VV_ERR_FORMAT, "absolute path");
    /* Teem reads field names in any case: so does the policy (found by
     * fuzzing: "Data file: LIST" with a control character in a name) */
    write_text(tpath("case.nhdr"),
               "NRRD0004\nType: uchar\nDimension: 3\nSizes: 2 2 2\n"
               "Encoding: raw\nData File: %s\n",
               "/etc/passwd");
    {
        vv_volume *cv = NULL;
        vv_error_clear();
        expect_error(vv_nrrd_read(&cv, tpath("case.nhdr")), VV_ERR_FORMAT, "absolute path");
        assert_null(cv);
    }
    write_text(tpath("ctl.nhdr"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\n"
                                  "encoding: raw\nDATA FILE: LIST\na.raw\001b.raw\n");
    {
        vv_volume *cv = NULL;
        vv_error_clear();
        expect_error(vv_nrrd_read(&cv, tpath("ctl.nhdr")), VV_ERR_FORMAT, "control character");
        assert_null(cv);
    }
    expect_error(load_nhdr("dir.nhdr", "sub"), VV_ERR_FORMAT, "a folder");
    expect_error(load_nhdr("up.nhdr", "../../../../../../etc/passwd"), VV_ERR_FORMAT, "'..'");
    expect_error(load_nhdr("up2.nhdr", "sub/../data.raw"), VV_ERR_FORMAT, "'..'");

    /* links: out of the folder, and to a device */
    unlink(tpath("link.raw"));
    assert_int_equal(symlink("/etc/passwd", tpath("link.raw")), 0);
    expect_error(load_nhdr("link.nhdr", "link.raw"), VV_ERR_FORMAT, "outside the header's folder");
    unlink(tpath("zero.raw"));
    assert_int_equal(symlink("/dev/zero", tpath("zero.raw")), 0);
    expect_error(load_nhdr("zero.nhdr", "zero.raw"), VV_ERR_FORMAT, "a device");

    /* patterns: printf conversions other than one integer, and huge ranges */
    expect_error(load_nhdr("pat.nhdr", "x%s%n 1 2 1"), VV_ERR_FORMAT, "integer conversion");
    expect_error(load_nhdr("pat2.nhdr", "x%d 1 1000000 1"), VV_ERR_LIMIT, "1000000 files");

    /* a header line longer than Teem's 1 KB message buffer (it aborted) */
    char longline[3001];
    memset(longline, 'x', 3000);
    longline[3000] = '\0';
    write_text(tpath("longline.nrrd"),
               "NRRD0004\nfoo: %s\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n"
               "abcdefgh",
               longline);
    vv_volume *lv = NULL;
    vv_error_clear();
    expect_error(vv_nrrd_read(&lv, tpath("longline.nrrd")), VV_ERR_FORMAT, "header line");

    /* the header itself on a device */
    vv_volume *v = NULL;
    vv_error_clear();
    expect_error(vv_nrrd_read(&v, "/dev/zero"), VV_ERR_IO, "not a regular file");
}

/* A LIST of a million names is refused quickly (Teem takes a minute). */
static void
test_nrrd_million_list(void **state) {
    (void)state;
    const char *path = tpath("million.nhdr");
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1000000\nencoding: raw\n"
               "data file: LIST\n");
    for (int i = 0; i < 1000000; i++)
        fprintf(f, "data.raw\n");
    assert_int_equal(fclose(f), 0);
    write_text(tpath("data.raw"), "abcdefgh");
    double t0 = now_s();
    vv_volume *v = NULL;
    vv_error_clear();
    vv_status s = vv_nrrd_read(&v, path);
    double dt = now_s() - t0;
    assert_int_not_equal(s, VV_OK);
    assert_true(s == VV_ERR_LIMIT);
    if (dt > 5)
        fail_msg("rejecting a million-name list took %.1f s", dt);
}

/* ---- sizes: overflow, over the budget, more than the file holds ---------- */

static void
test_nrrd_sizes(void **state) {
    (void)state;
    vv_volume *v = NULL;
    /* a product that overflows 64 bits */
    write_text(tpath("overflow.nrrd"), "NRRD0004\ntype: double\ndimension: 3\n"
                                       "sizes: 4294967296 4294967296 4294967296\n"
                                       "encoding: raw\n\nxxxx");
    vv_error_clear();
    vv_status s = vv_nrrd_read(&v, tpath("overflow.nrrd"));
    assert_int_not_equal(s, VV_OK);
    assert_true(s == VV_ERR_LIMIT || s == VV_ERR_FORMAT);
    /* the 86-byte file claiming 2^32 voxels: refused before allocating */
    write_text(tpath("claim.nrrd"),
               "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 65536 65536 1\nencoding: raw\n\nxxxx");
    vv_error_clear();
    expect_error(vv_nrrd_read(&v, tpath("claim.nrrd")), VV_ERR_FORMAT, "header promises");
    /* over the memory budget (with the data there): VV_ERR_LIMIT */
    vv_memory_budget_set((uint64_t)1 << 20);
    FILE *f = fopen(tpath("budget.nrrd"), "wb");
    assert_non_null(f);
    fprintf(f, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1024 1024 2\nencoding: raw\n\n");
    static unsigned char zeros[1 << 16];
    for (int i = 0; i < 32; i++)
        assert_int_equal(fwrite(zeros, 1, sizeof zeros, f), sizeof zeros);
    assert_int_equal(fclose(f), 0);
    vv_error_clear();
    expect_error(vv_nrrd_read(&v, tpath("budget.nrrd")), VV_ERR_LIMIT, "memory budget");
    vv_memory_budget_set(0);
    vt_ok(vv_nrrd_read(&v, tpath("budget.nrrd")));
    vv_volume_free(v);
}

/* ---- gzip and zlib bombs ----------------------------------------------- */

static void
test_bombs(void **state) {
    (void)state;
    vv_volume *v = NULL;
    const uint64_t big = (uint64_t)128 << 20; /* inflates to 128 MiB */

    /* NRRD: a header promising 64^3 followed by a stream of 256 MiB: only
     * the promised 256 KiB are inflated */
    FILE *f = fopen(tpath("bomb.nrrd"), "wb");
    assert_non_null(f);
    fprintf(f, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 64 64 64\nencoding: gzip\n\n");
    append_zero_stream(f, big, 1);
    assert_int_equal(fclose(f), 0);
    double t0 = now_s();
    vt_ok(vv_nrrd_read(&v, tpath("bomb.nrrd")));
    assert_int_equal(v->dims[2], 64);
    vv_volume_free(v);
    if (now_s() - t0 > 5)
        fail_msg("the NRRD bomb took %.1f s: inflated past the promised size", now_s() - t0);

    /* NRRD: promising 8 GiB with a 256 KiB stream: refused before allocating */
    f = fopen(tpath("claim_gz.nrrd"), "wb");
    assert_non_null(f);
    fprintf(f, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2048 2048 2048\nencoding: gzip\n\n");
    append_zero_stream(f, big, 1);
    assert_int_equal(fclose(f), 0);
    vv_error_clear();
    vv_status s = vv_nrrd_read(&v, tpath("claim_gz.nrrd"));
    assert_true(s == VV_ERR_FORMAT || s == VV_ERR_LIMIT);
    assert_null(v);

    /* NRRD: a truncated stream is refused before Teem reads it */
    f = fopen(tpath("short_gz.nrrd"), "wb");
    assert_non_null(f);
    fprintf(f, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 64 64 64\nencoding: gzip\n\n");
    append_zero_stream(f, 1000, 1);
    assert_int_equal(fclose(f), 0);
    vv_error_clear();
    expect_error(vv_nrrd_read(&v, tpath("short_gz.nrrd")), VV_ERR_FORMAT, "header promises");

    /* NIfTI-1 .nii.gz: header promising 64^3 u8, the stream 256 MiB */
    unsigned char h[352];
    memset(h, 0, sizeof h);
    int32_t hs = 348;
    memcpy(h, &hs, 4);
    int16_t dim[8] = {3, 64, 64, 64, 1, 1, 1, 1};
    memcpy(h + 40, dim, sizeof dim);
    int16_t dt[2] = {2, 8}; /* DT_UINT8, bitpix */
    memcpy(h + 70, dt, 4);
    float pix[8] = {1, 1, 1, 1, 1, 1, 1, 1};
    memcpy(h + 76, pix, sizeof pix);
    float off = 352;
    memcpy(h + 108, &off, 4);
    memcpy(h + 344, "n+1", 4);
    gzFile gz = gzopen(tpath("bomb.nii.gz"), "wb1");
    assert_non_null(gz);
    assert_int_equal(gzwrite(gz, h, sizeof h), (int)sizeof h);
    static unsigned char zeros[1 << 20];
    for (int i = 0; i < 128; i++) /* 128 MiB of zeros: about 125 KiB */
        assert_int_equal(gzwrite(gz, zeros, sizeof zeros), (int)sizeof zeros);
    gzclose(gz);
    t0 = now_s();
    vt_ok(vv_nifti_read(&v, tpath("bomb.nii.gz")));
    assert_int_equal(v->dims[0], 64);
    vv_volume_free(v);
    if (now_s() - t0 > 5)
        fail_msg("the NIfTI bomb took %.1f s", now_s() - t0);
    /* the same stream under a header promising 2048^3 (8 GiB): refused */
    int16_t dim2[8] = {3, 2048, 2048, 2048, 1, 1, 1, 1};
    memcpy(h + 40, dim2, sizeof dim2);
    gz = gzopen(tpath("claim.nii.gz"), "wb1");
    assert_non_null(gz);
    assert_int_equal(gzwrite(gz, h, sizeof h), (int)sizeof h);
    for (int i = 0; i < 16; i++)
        assert_int_equal(gzwrite(gz, zeros, sizeof zeros), (int)sizeof zeros);
    gzclose(gz);
    vv_error_clear();
    s = vv_nifti_read(&v, tpath("claim.nii.gz"));
    assert_true(s == VV_ERR_FORMAT || s == VV_ERR_LIMIT);
    assert_null(v);

    /* MetaImage: zlib stream of 256 MiB under a 64^3 header */
    f = fopen(tpath("data_z.raw"), "wb");
    assert_non_null(f);
    append_zero_stream(f, big, 0);
    long clen = ftell(f);
    assert_int_equal(fclose(f), 0);
    write_text(tpath("bomb.mhd"),
               "ObjectType = Image\nNDims = 3\nDimSize = 64 64 64\nElementType = MET_UCHAR\n"
               "CompressedData = True\nCompressedDataSize = %ld\nElementDataFile = data_z.raw\n",
               clen);
    t0 = now_s();
    vt_ok(vv_mhd_read(&v, tpath("bomb.mhd")));
    vv_volume_free(v);
    if (now_s() - t0 > 5)
        fail_msg("the MetaImage bomb took %.1f s", now_s() - t0);
    write_text(tpath("claim.mhd"),
               "ObjectType = Image\nNDims = 3\nDimSize = 2048 2048 2048\nElementType = MET_UCHAR\n"
               "CompressedData = True\nCompressedDataSize = %ld\nElementDataFile = data_z.raw\n",
               clen);
    vv_error_clear();
    s = vv_mhd_read(&v, tpath("claim.mhd"));
    assert_true(s == VV_ERR_FORMAT || s == VV_ERR_LIMIT);
    /* MetaImage: the detached-data policy */
    write_text(tpath("passwd.mhd"), "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\n"
                                    "ElementType = MET_UCHAR\nElementDataFile = /etc/passwd\n");
    vv_error_clear();
    expect_error(vv_mhd_read(&v, tpath("passwd.mhd")), VV_ERR_FORMAT, "absolute path");
    write_text(tpath("up.mhd"), "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\n"
                                "ElementType = MET_UCHAR\nElementDataFile = ../../x.raw\n");
    vv_error_clear();
    expect_error(vv_mhd_read(&v, tpath("up.mhd")), VV_ERR_FORMAT, "'..'");
}

/* ---- NIfTI headers with absurd fields ---------------------------------- */

static vv_status
load_nifti2(int64_t dim0, int64_t d1, int swap) {
    unsigned char h[544 + 8];
    memset(h, 0, sizeof h);
    int32_t hs = 540;
    int16_t dt[2] = {2, 8};
    int64_t dim[8] = {dim0, d1, 2, 2, 1, 1, 1, 1};
    double pix[8] = {1, 1, 1, 1, 1, 1, 1, 1};
    int64_t off = 544;
    memcpy(h, &hs, 4);
    memcpy(h + 4, "n+2\0\r\n\032\n", 8);
    memcpy(h + 12, dt, 4);
    memcpy(h + 16, dim, sizeof dim);
    memcpy(h + 104, pix, sizeof pix);
    memcpy(h + 168, &off, 8);
    if (swap) {
        /* big-endian file: swap the fields written above */
        for (int i = 0; i < 4 / 2; i++) {
            unsigned char t = h[i];
            h[i] = h[3 - i];
            h[3 - i] = t;
        }
        for (int k = 0; k < 8; k++)
            for (int i = 0; i < 4; i++) {
                unsigned char t = h[16 + 8 * k + i];
                h[16 + 8 * k + i] = h[16 + 8 * k + 7 - i];
                h[16 + 8 * k + 7 - i] = t;
            }
    }
    vt_write_file(tpath("abs.nii"), h, sizeof h);
    vv_volume *v = NULL;
    vv_error_clear();
    vv_status s = vv_nifti_read(&v, tpath("abs.nii"));
    vv_volume_free(v);
    return s;
}

static void
test_nifti_absurd_header(void **state) {
    (void)state;
    assert_int_equal(load_nifti2(3, 2, 0), VV_OK);
    const int64_t bad[] = {0, -1, 8, 1000, 32767, INT64_C(1) << 40, INT64_MIN};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        expect_error(load_nifti2(bad[i], 2, 0), VV_ERR_FORMAT, "dim[0]");
        expect_error(load_nifti2(bad[i], 2, 1), VV_ERR_FORMAT, "dim[0]");
    }
    /* a dimension past the limits (the product would overflow inside nifti_clib) */
    expect_error(load_nifti2(3, INT64_C(1) << 40, 0), VV_ERR_LIMIT, "dim[1]");
    expect_error(load_nifti2(3, -7, 0), VV_ERR_FORMAT, "dim[1]");
    /* a bad sizeof_hdr and a truncated header */
    unsigned char h[100] = {0};
    vt_write_file(tpath("short.nii"), h, sizeof h);
    vv_volume *v = NULL;
    vv_error_clear();
    expect_error(vv_nifti_read(&v, tpath("short.nii")), VV_ERR_FORMAT, "sizeof_hdr");
    int32_t hs = 348;
    memcpy(h, &hs, 4);
    vt_write_file(tpath("short.nii"), h, sizeof h);
    vv_error_clear();
    expect_error(vv_nifti_read(&v, tpath("short.nii")), VV_ERR_FORMAT, "truncated");
}

/* ---- OFF meshes that made Assimp abort ---------------------------------- */

static void
test_off_malformed(void **state) {
    (void)state;
    const struct {
        const char *text, *mention;
    } cases[] = {
        {"OFF\n4 0 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n", "faces"},
        {"OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0\n", "face 0"},
        {"OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0\n", "face 0"},
        {"OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 9\n", "out of range"},
        {"OFF\n3 1 0\n0 0 0\n1 0 0\n\n\n\n\n\n\n\n\n\n\n\n", "vertex 2"},
        {"OFF\n", "counts"},
        {"OFF BINARY\n", "binary"},
        {"OFF\n1000000000 1000000000 0\n", "faces"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        write_text(tpath("bad.off"), "%s", cases[i].text);
        vv_mesh *m = NULL;
        vv_error_clear();
        vv_status s = vv_mesh_load(&m, tpath("bad.off"));
        if (s == VV_OK)
            fail_msg("case %zu loaded", i);
        assert_null(m);
        if (!strstr(vv_error_message(), cases[i].mention))
            fail_msg("case %zu: '%s' does not mention '%s'", i, vv_error_message(),
                     cases[i].mention);
    }
    /* a good one still loads */
    write_text(tpath("tet.off"),
               "OFF\n# a tetrahedron\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n"
               "3 0 3 2\n3 1 2 3\n");
    vv_mesh *m = NULL;
    vt_ok(vv_mesh_load(&m, tpath("tet.off")));
    assert_int_equal(m->n_triangles, 4);
    vv_mesh_free(m);
}

/* ---- a scene naming itself, a .vvc index past its end ------------------- */

static void
test_scene_self(void **state) {
    (void)state;
    write_text(tpath("self.json"), "{\"objects\": [{\"name\": \"me\", \"type\": \"volume\", "
                                   "\"file\": \"self.json\"}]}\n");
    vv_world *w = NULL;
    vv_error_clear();
    vv_status s = vv_scene_load(&w, tpath("self.json"));
    assert_int_not_equal(s, VV_OK);
    assert_null(w);
    assert_non_null(strstr(vv_error_message(), "self.json"));
}

static uint64_t
rd64(const unsigned char *p) {
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--)
        v = (v << 8) | p[i];
    return v;
}

static void
test_vvc_index_past_end(void **state) {
    (void)state;
    int dims[3] = {20, 20, 20};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int i = 0; i < 8000; i++)
        ((unsigned char *)v->data)[i] = (unsigned char)(i * 7);
    vv_volume_update_range(v);
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.version = 1; /* the index at the format-1 offsets patched below (format 2 is
                    * covered by test_compress_vvc's corruption tests) */
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, v, &p));
    vv_volume_free(v);
    size_t n = 0;
    const unsigned char *b = vv_vvc_bytes(c, &n);
    unsigned char *d = malloc(n);
    assert_non_null(d);
    memcpy(d, b, n);
    vv_vvc_free(c);
    uint64_t T = rd64(d + 216), I = rd64(d + 224);
    size_t idx = 244 + (size_t)T;
    assert_true(idx + I <= n && I >= 8);
    /* the last offset (u32) points far past the data; the CRC is made right */
    size_t last = idx + (size_t)I - 8;
    d[last] = 0x00;
    d[last + 1] = 0xff;
    d[last + 2] = 0xff;
    d[last + 3] = 0x7f;
    uint32_t crc = (uint32_t)crc32(0L, d + idx, (uInt)(I - 4));
    for (int i = 0; i < 4; i++)
        d[idx + I - 4 + (size_t)i] = (unsigned char)(crc >> (8 * i));
    vv_error_clear();
    vv_status s = vv_vvc_from_memory(&c, d, n, "past.vvc");
    expect_error(s, VV_ERR_FORMAT, "offset");
    assert_null(c);
    /* and a truncated file */
    vv_error_clear();
    assert_int_not_equal(vv_vvc_from_memory(&c, d, n / 2, "half.vvc"), VV_OK);
    free(d);
}

/* ---- what the fuzzers found: a VTK grid's cell counts, a NRRD line, DICOM lengths */

static void
test_fuzz_findings(void **state) {
    (void)state;
    /* CELLS 2 4: the first cell claims all four ints, leaving none for the
     * second cell's count (wrote past the connectivity array) */
    write_text(tpath("cells.vtk"), "# vtk DataFile Version 3.0\nx\nASCII\n"
                                   "DATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n"
                                   "0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 2 4\n3 0 1 2\n"
                                   "CELL_TYPES 2\n10\n10\n");
    vv_grid *g = NULL;
    vv_error_clear();
    expect_error(vv_grid_load(&g, tpath("cells.vtk")), VV_ERR_FORMAT, "cell 0 has 3 points");
    assert_null(g);
    /* a NRRD header line of 960 bytes that Teem does not recognise: its
     * message about it overflowed a 1 KB buffer (a fortified abort) */
    {
        char line[961];
        memset(line, 'x', 960);
        line[960] = '\0';
        write_text(tpath("long_line.nrrd"),
                   "NRRD0005\n%s\ntype: short\ndimension: 3\nsizes: 1 5 1\n"
                   "encoding: raw\nendian: little\n\n0123456789",
                   line);
        vv_volume *lv = NULL;
        vv_error_clear();
        expect_error(vv_nrrd_read(&lv, tpath("long_line.nrrd")), VV_ERR_FORMAT,
                     "a header line of 960 bytes (at most 768)");
        assert_null(lv);
    }
    /* a 1.2 KB DICOM file one of whose lengths says 775 MB: GDCM allocated
     * it (0.9 GB, 6 s) before noticing the file ends */
    char dcm[1024];
    snprintf(dcm, sizeof dcm, "%s/tests/fuzz/corpus/dicom/timeout-huge-length", VV_SOURCE_DIR);
    vv_volume *v = NULL;
    double t0 = now_s();
    vv_error_clear();
    vv_status s = vv_dicom_read(&v, dcm, 0, -1);
    if (s == VV_ERR_UNSUPPORTED)
        return; /* built without GDCM */
    expect_error(s, VV_ERR_FORMAT, "claims 774909494 bytes");
    if (now_s() - t0 > 3)
        fail_msg("refusing the file took %.1f s", now_s() - t0);
    /* a UN element holding a sequence, whose implicit-VR element inside
     * claims 2 GB: GDCM allocated it (2.1 GB, 24 s for a 300-byte file)
     * before the length walk followed UN sequences; undefined and defined
     * length */
    static const char *const un_files[] = {"timeout-un-sequence", "timeout-un-defined-sequence"};
    for (int k = 0; k < 2; k++) {
        snprintf(dcm, sizeof dcm, "%s/tests/fuzz/corpus/dicom/%s", VV_SOURCE_DIR, un_files[k]);
        t0 = now_s();
        vv_error_clear();
        s = vv_dicom_read(&v, dcm, 0, -1);
        expect_error(s, VV_ERR_FORMAT, "(0029,0010) claims 2147483632 bytes");
        assert_null(v);
        if (now_s() - t0 > 3)
            fail_msg("refusing %s took %.1f s", un_files[k], now_s() - t0);
    }
    /* an unknown VR ("CU", a mutated CS) that GDCM reads as UN first: the
     * 32-bit length after it ("MONO" of MONOCHROME2) made it allocate 1.3 GB */
    snprintf(dcm, sizeof dcm, "%s/tests/fuzz/corpus/dicom/oom-unknown-vr-long-length",
             VV_SOURCE_DIR);
    t0 = now_s();
    vv_error_clear();
    s = vv_dicom_read(&v, dcm, 0, -1);
    expect_error(s, VV_ERR_FORMAT, "(0028,0004) claims 1330532173 bytes");
    assert_null(v);
    if (now_s() - t0 > 3)
        fail_msg("refusing the unknown VR took %.1f s", now_s() - t0);
    /* a malformed explicit-VR element on which GDCM fails an assertion
     * (abort()): read in volvis-reader, that is one line of error, twice,
     * not the end of this process */
    snprintf(dcm, sizeof dcm, "%s/tests/fuzz/corpus/dicom/crash-gdcm-assert-vr16-explicit",
             VV_SOURCE_DIR);
    for (int k = 0; k < 2; k++) {
        vv_load_options o;
        vv_load_options_init(&o);
        o.format = VV_FORMAT_DICOM;
        vv_error_clear();
        s = vv_volume_load(&v, dcm, &o);
        printf("  %s\n", vv_error_message());
        assert_true(s < 0);
        assert_null(v);
        assert_true(vv_error_message()[0] != '\0');
        assert_null(strchr(vv_error_message(), '\n'));
    }
}

/* ---- Teem's memory on failed loads --------------------------------------- */

static void
test_teem_failed_loads_free(void **state) {
    (void)state;
    /* a truncated gzip stream (Teem 1.12 leaks its gzip state on it), a bad
     * header, a missing data file */
    FILE *f = fopen(tpath("trunc.nrrd"), "wb");
    assert_non_null(f);
    fprintf(f, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 16 16 16\nencoding: gzip\n\n");
    append_zero_stream(f, 100, 1);
    assert_int_equal(fclose(f), 0);
    write_text(tpath("badhdr.nrrd"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2\n\n");
    write_text(tpath("missing.nhdr"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\n"
                                      "encoding: raw\ndata file: nowhere.raw\n");
    const char *files[] = {tpath("trunc.nrrd"), tpath("badhdr.nrrd"), tpath("missing.nhdr")};
    vv_volume *v = NULL;
    for (int k = 0; k < 20; k++) /* warm up */
        for (int i = 0; i < 3; i++)
            assert_int_not_equal(vv_nrrd_read(&v, files[i]), VV_OK);
    struct mallinfo2 a = mallinfo2();
    for (int k = 0; k < 300; k++)
        for (int i = 0; i < 3; i++)
            assert_int_not_equal(vv_nrrd_read(&v, files[i]), VV_OK);
    struct mallinfo2 b = mallinfo2();
    long grew = (long)b.uordblks - (long)a.uordblks;
    if (grew > 64 * 1024)
        fail_msg("900 failed loads kept %ld bytes", grew);
}

/* ---- the CLI: --max-memory, info of a .vvc reads the header only -------- */

static void
test_cli_budget_and_info(void **state) {
    (void)state;
    int dims[3] = {128, 128, 64};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    vv_volume_update_range(v);
    vt_ok(vv_nrrd_write(v, tpath("one_mib.nrrd"), 1));
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, v, &p));
    vt_ok(vv_vvc_save(c, tpath("one_mib.vvc")));
    vv_vvc_free(c);
    vv_volume_free(v);

    const char *a1[] = {"--max-memory", "512K", "info", tpath("one_mib.nrrd"), NULL};
    vt_run_result r = vt_run_cli_v(g_dir, a1);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "memory budget"));
    vt_run_result_free(&r);
    const char *a2[] = {"info", "--max-memory=2M", tpath("one_mib.nrrd"), NULL};
    r = vt_run_cli_v(g_dir, a2);
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    const char *a3[] = {"--max-memory", "plenty", "info", tpath("one_mib.nrrd"), NULL};
    r = vt_run_cli_v(g_dir, a3);
    assert_int_equal(r.status, 2);
    vt_run_result_free(&r);
    /* a .vvc: the header alone, and with --stats the statistics */
    const char *a4[] = {"info", tpath("one_mib.vvc"), NULL};
    r = vt_run_cli_v(g_dir, a4);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "dimensions:   128 x 128 x 64"));
    assert_non_null(strstr(r.out, "not computed"));
    assert_null(strstr(r.out, "percentiles"));
    vt_run_result_free(&r);
    const char *a5[] = {"info", "--stats", tpath("one_mib.vvc"), NULL};
    r = vt_run_cli_v(g_dir, a5);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "percentiles"));
    vt_run_result_free(&r);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_memory_budget, teardown_budget),
        cmocka_unit_test(test_nrrd_detached_policy),
        cmocka_unit_test(test_nrrd_million_list),
        cmocka_unit_test_teardown(test_nrrd_sizes, teardown_budget),
        cmocka_unit_test(test_bombs),
        cmocka_unit_test(test_nifti_absurd_header),
        cmocka_unit_test(test_off_malformed),
        cmocka_unit_test(test_scene_self),
        cmocka_unit_test(test_vvc_index_past_end),
        cmocka_unit_test(test_fuzz_findings),
        cmocka_unit_test(test_teem_failed_loads_free),
        cmocka_unit_test(test_cli_budget_and_info),
    };
    return vt_run_tests(tests, setup, NULL);
}
