/*
 * Every refusal of the BigDataViewer dataset XML (src/io/store/bdv_xml.c) and of
 * the HDF5 pyramid reader (src/io/store/hdf5_pyramid.c) on hostile files written
 * here (the HDF5 ones with the HDF5 C API): each row a file, the status and
 * a piece of the message naming the field; every message one line naming
 * the file, no volume or store left behind, nothing for the sanitizers.
 *
 * - XML: a <!DOCTYPE> is refused before anything it declares is read (an
 *   entity bomb, an external entity naming /etc/passwd), a Timepoints
 *   pattern that repeats a long range is read in time, hdf5 paths leaving
 *   the folder (by name or by a link), affines that are not 12 finite
 *   numbers, singular, or that put the origin at infinity.
 * - HDF5: negative, zero, NaN, decreasing and string resolutions,
 *   subdivisions, wrong ranks, huge dims, missing datasets, unsupported and
 *   differing voxel types, a companion XML with a bad voxelSize or a
 *   <!DOCTYPE>; Imaris extents whose spacing overflows, image sizes past the
 *   data, a corrupt chunk; voxels in other files (external links, external
 *   raw storage, virtual datasets) never read; FIFOs for the XML, the
 *   companion and the HDF5 file (an open would block) refused.
 * Everything runs in this process (VOLVIS_SANDBOX=0).
 */
#include "testutil.h"

#define expect(got, want, needle, file) vt_expect_refusal(NULL, got, want, needle, file)

#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <hdf5.h>

#include "io/store/pyramid.h"
#include "volvis/sys/format.h"
#include "volvis/volvis.h"

static char g_dir[4096];

static const char *
tpath(const char *name) {
    return vt_path(g_dir, name);
}

static const char *
base(const char *path) {
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

static void
put_text(const char *path, const char *text) {
    vt_write_file(path, text, strlen(text));
}

/* Loads @p path as @p format (level, channel, time as given): refused as
 * expected, no volume; then opened as a pyramid: refused alike, no pyramid
 * (@p pyr 0: the pyramid does not read that level or step). */
static void
load_expect(const char *path, vv_format format, int level, int channel, int time, vv_status want,
            const char *needle, int pyr) {
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = format;
    o.level = level;
    o.channel = channel;
    o.time = time;
    vv_volume *v = (vv_volume *)(uintptr_t)1;
    vv_status s = vv_volume_load(&v, path, &o);
    assert_null(v);
    expect(s, want, needle, base(path));
    if (!pyr)
        return;
    vv_pyramid *p = (vv_pyramid *)(uintptr_t)1;
    s = vv_pyramid_open(&p, path, channel, time, vt_cache(64u << 20), NULL);
    assert_null(p);
    expect(s, want, needle, base(path));
}

/* ---- HDF5 files ------------------------------------------------------------------------ */

static hid_t
h5_new(const char *path) {
    hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(f >= 0);
    return f;
}

/* Dataset @p path (intermediate groups created) of @p rank dims (C order)
 * and file type @p type; @p data (may be NULL: never written) in memory
 * type @p mtype; chunked by @p chunk when not NULL. */
static void
h5_dset(hid_t f, const char *path, int rank, const hsize_t *dims, hid_t type, hid_t mtype,
        const void *data, const hsize_t *chunk) {
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (chunk)
        H5Pset_chunk(dcpl, rank, chunk);
    hid_t sp = H5Screate_simple(rank, dims, NULL);
    hid_t d = H5Dcreate2(f, path, type, sp, lcpl, dcpl, H5P_DEFAULT);
    assert_true(d >= 0);
    if (data)
        assert_true(H5Dwrite(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0);
    H5Dclose(d);
    H5Sclose(sp);
    H5Pclose(dcpl);
    H5Pclose(lcpl);
}

static void
h5_group(hid_t f, const char *path) {
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    hid_t g = H5Gcreate2(f, path, lcpl, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(g >= 0);
    H5Gclose(g);
    H5Pclose(lcpl);
}

static void
h5_table(hid_t f, const char *path, int rows, int cols, const double *v) {
    const hsize_t dims[2] = {(hsize_t)rows, (hsize_t)cols};
    h5_dset(f, path, 2, dims, H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE, v, NULL);
}

static void
h5_cells(hid_t f, const char *path, int n, hid_t type) {
    const hsize_t dims[3] = {(hsize_t)n, (hsize_t)n, (hsize_t)n};
    double *buf = calloc((size_t)n * (size_t)n * (size_t)n, sizeof(double));
    /* zeros (a bit field's own type: no conversion from numbers) */
    const int bits = H5Tget_class(type) == H5T_BITFIELD;
    h5_dset(f, path, 3, dims, type, bits ? type : H5T_NATIVE_DOUBLE, buf, NULL);
    free(buf);
}

/* Imaris writes numbers as an array of one-character strings. */
static void
h5_attr(hid_t obj, const char *name, const char *text) {
    const hsize_t n = strlen(text);
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, 1);
    hid_t sp = H5Screate_simple(1, &n, NULL);
    hid_t a = H5Acreate2(obj, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(a >= 0 && H5Awrite(a, t, text) >= 0);
    H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(t);
}

/* How a BigDataViewer file is spoiled. */
typedef struct bdv_spec {
    int levels;          /* levels written (cells and resolutions rows) */
    double res[2][3];    /* the factors */
    int res_cols;        /* 3, or another count */
    int res_string;      /* resolutions as a string dataset */
    int no_res;          /* no resolutions */
    int cells_rank;      /* 3, or another rank */
    hsize_t big;         /* > 0: level 0's x size (chunked, never written) */
    hid_t type0, type1;  /* the cells' types (0: int16) */
    int level1_bigger;   /* level 1 larger than level 0 */
    int no_level1_cells; /* level 1's cells missing */
    int cells_group;     /* level 0's cells a group */
} bdv_spec;

enum { T_I16, T_I64, T_BITS, T_F32 };

static hid_t
file_type(int t) {
    return t == T_I64    ? H5T_STD_I64LE
           : t == T_BITS ? H5T_STD_B8LE
           : t == T_F32  ? H5T_IEEE_F32LE
                         : H5T_STD_I16LE;
}

static void
write_bdv(const char *path, const bdv_spec *b) {
    hid_t f = h5_new(path);
    double res[6];
    for (int l = 0; l < b->levels; l++)
        for (int k = 0; k < 3; k++)
            res[3 * l + k] = b->res[l][k];
    if (b->res_string) {
        const hsize_t one = 1;
        hid_t t = H5Tcopy(H5T_C_S1);
        H5Tset_size(t, 8);
        h5_dset(f, "s00/resolutions", 1, &one, t, t, "1, 1, 1", NULL);
        H5Tclose(t);
    } else if (!b->no_res) {
        h5_table(f, "s00/resolutions", b->levels, b->res_cols ? b->res_cols : 3, res);
    }
    const int sub[6] = {4, 4, 4, 4, 4, 4};
    const hsize_t sd[2] = {(hsize_t)b->levels, 3};
    h5_dset(f, "s00/subdivisions", 2, sd, H5T_NATIVE_INT, H5T_NATIVE_INT, sub, NULL);
    if (b->cells_group)
        h5_group(f, "t00000/s00/0/cells");
    else if (b->big) {
        const hsize_t dims[3] = {4, 4, b->big}, ch[3] = {4, 4, 4};
        h5_dset(f, "t00000/s00/0/cells", 3, dims, H5T_STD_I16LE, H5T_NATIVE_INT16, NULL, ch);
    } else if (b->cells_rank && b->cells_rank != 3) {
        const hsize_t dims[4] = {4, 4, 4, 4};
        h5_dset(f, "t00000/s00/0/cells", b->cells_rank, dims, H5T_STD_I16LE, H5T_NATIVE_INT16, NULL,
                NULL);
    } else {
        h5_cells(f, "t00000/s00/0/cells", 4, file_type(b->type0));
    }
    if (b->levels > 1 && !b->no_level1_cells)
        h5_cells(f, "t00000/s00/1/cells", b->level1_bigger ? 8 : 2, file_type(b->type1));
    H5Fclose(f);
}

typedef struct hcase {
    const char *name;
    bdv_spec spec;
    int level, channel, time;
    vv_status want;
    const char *needle;
    int pyr;
} hcase;

#define OK1 .levels = 1, .res = {{1, 1, 1}}
#define OK2 .levels = 2, .res = {{1, 1, 1}, {2, 2, 2}}

static const hcase g_h5[] = {
    {"res_missing", {OK1, .no_res = 1}, 0, -1, -1, VV_ERR_FORMAT, "s00/resolutions: missing", 1},
    {"res_string",
     {OK1, .res_string = 1},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "s00/resolutions: missing, or not a table",
     1},
    {"res_cols", {OK1, .res_cols = 2}, 0, -1, -1, VV_ERR_FORMAT, "s00/resolutions", 1},
    {"res_zero",
     {.levels = 1, .res = {{1, 0, 1}}},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "level 0's factor 0 along axis 1",
     1},
    {"res_negative",
     {.levels = 1, .res = {{-2, 1, 1}}},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "level 0's factor -2 along axis 0",
     1},
    {"res_nan",
     {.levels = 1, .res = {{1, 1, NAN}}},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "level 0's factor nan along axis 2",
     1},
    {"res_huge",
     {.levels = 1, .res = {{1, 1e9, 1}}},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "factor 1e+09 along axis 1",
     1},
    {"res_decreasing",
     {.levels = 2, .res = {{2, 2, 2}, {1, 1, 1}}},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "level 1's factor 1 along axis 0 (inconsistent multiscales)",
     1},
    {"cells_2d",
     {OK1, .cells_rank = 2},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "t00000/s00/0/cells: 2 dimensions, not 3",
     1},
    {"cells_4d", {OK1, .cells_rank = 4}, 0, -1, -1, VV_ERR_FORMAT, "4 dimensions, not 3", 1},
    {"cells_group",
     {OK1, .cells_group = 1},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "no dataset t00000/s00/0/cells",
     1},
    {"cells_missing",
     {OK2, .no_level1_cells = 1},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "no dataset t00000/s00/1/cells",
     1},
    {"cells_huge",
     {OK1, .big = 100000},
     0,
     -1,
     -1,
     VV_ERR_LIMIT,
     "100000 voxels along axis 0 (1 .. 65536 allowed)",
     1},
    {"type_i64",
     {OK1, .type0 = T_I64},
     0,
     -1,
     -1,
     VV_ERR_UNSUPPORTED,
     "level 0: a voxel type other than",
     1},
    {"type_f16ish",
     {OK1, .type0 = T_BITS},
     0,
     -1,
     -1,
     VV_ERR_UNSUPPORTED,
     "a voxel type other than",
     1},
    {"type_differs",
     {OK2, .type1 = T_F32},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "level 1: its type differs from level 0's",
     1},
    {"level1_bigger",
     {OK2, .level1_bigger = 1},
     0,
     -1,
     -1,
     VV_ERR_FORMAT,
     "level 1: 8 voxels along axis 0, more than level 0's 4",
     1},
    {"channel_past", {OK1}, 0, 1, -1, VV_ERR_INVALID, "channel 1 asked, the file has 1 setups", 1},
    {"time_past", {OK1}, 0, -1, 2, VV_ERR_INVALID, "time step 2 asked, the file has 1", 1},
    {"level_past", {OK2}, 2, -1, -1, VV_ERR_INVALID, "level 2 asked, the file has 2", 0},
};

static void
test_hdf5_bdv(void **state) {
    (void)state;
    for (size_t i = 0; i < sizeof g_h5 / sizeof g_h5[0]; i++) {
        const hcase *c = &g_h5[i];
        char name[128];
        snprintf(name, sizeof name, "%s.h5", c->name);
        print_message("%s\n", c->name);
        write_bdv(tpath(name), &c->spec);
        load_expect(tpath(name), VV_FORMAT_HDF5, c->level, c->channel, c->time, c->want, c->needle,
                    c->pyr);
    }
}

/* A BigDataViewer file whose level-0 cells are not its own: an external
 * link to another file's dataset (@p how 0), a link of the level's group
 * (1), raw data in an external file (2), a virtual dataset (3). */
static void
write_elsewhere(const char *path, const char *other, const char *raw, int how) {
    hid_t f = h5_new(path);
    const double res[3] = {1, 1, 1};
    h5_table(f, "s00/resolutions", 1, 3, res);
    h5_group(f, "t00000/s00");
    const hsize_t dims[3] = {4, 4, 4};
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    hid_t sp = H5Screate_simple(3, dims, NULL);
    if (how == 0) {
        h5_group(f, "t00000/s00/0");
        assert_true(H5Lcreate_external(other, "/t00000/s00/0/cells", f, "t00000/s00/0/cells",
                                       H5P_DEFAULT, H5P_DEFAULT) >= 0);
    } else if (how == 1) {
        assert_true(H5Lcreate_external(other, "/t00000/s00/0", f, "t00000/s00/0", H5P_DEFAULT,
                                       H5P_DEFAULT) >= 0);
    } else {
        if (how == 2)
            assert_true(H5Pset_external(dcpl, raw, 0, 4 * 4 * 4 * 2) >= 0);
        else
            assert_true(H5Pset_virtual(dcpl, sp, other, "/t00000/s00/0/cells", sp) >= 0);
        h5_group(f, "t00000/s00/0");
        hid_t d =
            H5Dcreate2(f, "t00000/s00/0/cells", H5T_STD_I16LE, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
        assert_true(d >= 0);
        H5Dclose(d);
    }
    H5Sclose(sp);
    H5Pclose(dcpl);
    H5Fclose(f);
}

/* Voxels in other files (anywhere the file names) are never read. */
static void
test_hdf5_elsewhere(void **state) {
    (void)state;
    char dir[4200], other[4400], raw[4400];
    snprintf(dir, sizeof dir, "%s", vt_outdir("errors_bdv_hdf5_outside"));
    snprintf(other, sizeof other, "%s/other.h5", dir);
    snprintf(raw, sizeof raw, "%s/secret.raw", dir);
    const bdv_spec ok = {OK1};
    write_bdv(other, &ok);
    unsigned char secret[128];
    memset(secret, 's', sizeof secret);
    vt_write_file(raw, secret, sizeof secret);
    static const struct {
        const char *name, *needle;
    } rows[] = {
        {"elink.h5", "t00000/s00/0/cells: an external link to \""},
        {"elink_group.h5", "an external link to \""},
        {"external.h5", "t00000/s00/0/cells: a virtual dataset or external storage"},
        {"virtual.h5", "a virtual dataset or external storage"},
    };
    for (int i = 0; i < 4; i++) {
        print_message("%s\n", rows[i].name);
        write_elsewhere(tpath(rows[i].name), other, raw, i);
        load_expect(tpath(rows[i].name), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT, rows[i].needle,
                    1);
    }
    /* the resolutions table stored outside: not read either */
    hid_t f = h5_new(tpath("external_table.h5"));
    const hsize_t td[2] = {1, 3};
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE), lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    assert_true(H5Pset_external(dcpl, raw, 0, 3 * 8) >= 0);
    hid_t sp = H5Screate_simple(2, td, NULL);
    hid_t d = H5Dcreate2(f, "s00/resolutions", H5T_IEEE_F64LE, sp, lcpl, dcpl, H5P_DEFAULT);
    assert_true(d >= 0);
    H5Dclose(d);
    H5Sclose(sp);
    H5Pclose(dcpl);
    H5Pclose(lcpl);
    h5_cells(f, "t00000/s00/0/cells", 4, H5T_STD_I16LE);
    H5Fclose(f);
    load_expect(tpath("external_table.h5"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "s00/resolutions: missing, or not a table", 1);
}

/* Not HDF5; HDF5 of neither layout; 17 Imaris levels. */
static void
test_hdf5_files(void **state) {
    (void)state;
    put_text(tpath("junk.h5"), "\x89HDF\r\n\x1a\n but nothing after the signature");
    load_expect(tpath("junk.h5"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_IO,
                "cannot open it as an HDF5 file", 1);
    hid_t f = h5_new(tpath("plain.h5"));
    h5_cells(f, "volume", 4, H5T_STD_U8LE);
    H5Fclose(f);
    load_expect(tpath("plain.h5"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_UNSUPPORTED,
                "neither a BigDataViewer file", 0);
}

/* A companion XML (NAME.xml beside NAME.h5) that is spoiled. */
static void
test_hdf5_companion(void **state) {
    (void)state;
    static const struct {
        const char *name, *xml;
        const char *needle;
    } rows[] = {
        {"comp_broken", "<SpimData><SequenceDescription>", "the companion XML cannot be parsed"},
        {"comp_doctype",
         "<?xml version=\"1.0\"?>\n<!DOCTYPE SpimData [<!ENTITY xxe SYSTEM "
         "\"file:///etc/passwd\">]>\n<SpimData><SequenceDescription><ViewSetups><ViewSetup>"
         "<id>0</id><voxelSize><size>&xxe;</size></voxelSize></ViewSetup></ViewSetups>"
         "</SequenceDescription></SpimData>",
         "has a <!DOCTYPE>"},
        {"comp_nan",
         "<SpimData><SequenceDescription><ViewSetups><ViewSetup><id>0</id><voxelSize>"
         "<unit>um</unit><size>1 nan 1</size></voxelSize></ViewSetup></ViewSetups>"
         "</SequenceDescription></SpimData>",
         "ViewSetup 0's voxelSize \"1 nan 1\" is not three positive numbers"},
        {"comp_zero",
         "<SpimData><SequenceDescription><ViewSetups><ViewSetup><id>0</id><voxelSize>"
         "<size>0 1 1</size></voxelSize></ViewSetup></ViewSetups></SequenceDescription>"
         "</SpimData>",
         "voxelSize \"0 1 1\""},
        {"comp_two",
         "<SpimData><SequenceDescription><ViewSetups><ViewSetup><id>0</id><voxelSize>"
         "<size>1 1</size></voxelSize></ViewSetup></ViewSetups></SequenceDescription>"
         "</SpimData>",
         "voxelSize \"1 1\""},
        {"comp_none",
         "<SpimData><SequenceDescription><ViewSetups><ViewSetup><id>0</id><voxelSize>"
         "</voxelSize></ViewSetup></ViewSetups></SequenceDescription></SpimData>",
         "voxelSize \"\""},
    };
    const bdv_spec ok = {OK1};
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        char h5[128], xml[128];
        snprintf(h5, sizeof h5, "%s.h5", rows[i].name);
        snprintf(xml, sizeof xml, "%s.xml", rows[i].name);
        print_message("%s\n", rows[i].name);
        write_bdv(tpath(h5), &ok);
        put_text(tpath(xml), rows[i].xml);
        load_expect(tpath(h5), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT, rows[i].needle, 1);
        assert_non_null(strstr(vv_error_message(), xml));
    }
    /* over 64 MiB (sparse) */
    write_bdv(tpath("comp_big.h5"), &ok);
    int fd = open(tpath("comp_big.xml"), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, (64 << 20) + 1), 0);
    close(fd);
    load_expect(tpath("comp_big.h5"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "comp_big.xml: 67108865 bytes, over the 64 MiB", 1);
}

/* An Imaris file: @p levels levels of 4^3 (level 1 @p l1 a side), extents
 * @p lo .. @p hi along x, ImageSizeX @p isx (NULL: none); @p channels
 * channels. */
static void
write_ims(const char *path, int levels, int l1, const char *lo, const char *hi, const char *isx,
          int channels) {
    hid_t f = h5_new(path);
    char p[256];
    for (int l = 0; l < levels; l++)
        for (int c = 0; c < channels; c++) {
            snprintf(p, sizeof p, "DataSet/ResolutionLevel %d/TimePoint 0/Channel %d/Data", l, c);
            h5_cells(f, p, l == 1 ? l1 : 4, H5T_STD_U8LE);
            if (isx && l == 0) {
                snprintf(p, sizeof p, "DataSet/ResolutionLevel %d/TimePoint 0/Channel %d", l, c);
                hid_t g = H5Gopen2(f, p, H5P_DEFAULT);
                h5_attr(g, "ImageSizeX", isx);
                H5Gclose(g);
            }
        }
    h5_group(f, "DataSetInfo/Image");
    hid_t g = H5Gopen2(f, "DataSetInfo/Image", H5P_DEFAULT);
    for (int k = 0; k < 3; k++) {
        char a[16];
        snprintf(a, sizeof a, "ExtMin%d", k);
        h5_attr(g, a, k == 0 ? lo : "0");
        snprintf(a, sizeof a, "ExtMax%d", k);
        h5_attr(g, a, k == 0 ? hi : "4");
    }
    h5_attr(g, "Unit", "um");
    H5Gclose(g);
    H5Fclose(f);
}

static void
test_imaris(void **state) {
    (void)state;
    write_ims(tpath("ims_levels.ims"), VV_PYRAMID_MAX_LEVELS + 1, 4, "0", "4", NULL, 1);
    load_expect(tpath("ims_levels.ims"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_LIMIT,
                "more than 16 resolution levels", 1);
    write_ims(tpath("ims_chan.ims"), 1, 4, "0", "4", NULL, 2);
    load_expect(tpath("ims_chan.ims"), VV_FORMAT_HDF5, 0, 2, -1, VV_ERR_INVALID,
                "channel 2 asked, the file has 2", 1);
    load_expect(tpath("ims_chan.ims"), VV_FORMAT_HDF5, 0, -1, 1, VV_ERR_INVALID,
                "time step 1 asked, the file has 1", 1);
    write_ims(tpath("ims_size.ims"), 1, 4, "0", "4", "9", 1);
    load_expect(tpath("ims_size.ims"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "ImageSizeX 9 outside the Data dataset's 4 voxels", 1);
    write_ims(tpath("ims_size0.ims"), 1, 4, "0", "4", "0", 1);
    load_expect(tpath("ims_size0.ims"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "ImageSizeX 0 outside", 1);
    write_ims(tpath("ims_bigger.ims"), 2, 8, "0", "4", NULL, 1);
    load_expect(tpath("ims_bigger.ims"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "level 1: 8 voxels along axis 0, more than level 0's 4", 1);
    /* extents whose difference overflows: an infinite spacing */
    write_ims(tpath("ims_inf.ims"), 1, 4, "-1e308", "1e308", NULL, 1);
    load_expect(tpath("ims_inf.ims"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "is a spacing of inf", 1);
    /* an extent of one unit in the last place at the smallest normal
     * double, over 4 voxels: a spacing that rounds to 0 */
    write_ims(tpath("ims_zero.ims"), 1, 4, "2.2250738585072014e-308", "2.2250738585072019e-308",
              NULL, 1);
    load_expect(tpath("ims_zero.ims"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "is a spacing of 0", 1);
}

/* ---- the dataset XML ------------------------------------------------------------------- */

#define SEQ_(loader, setups, tp)                                                                   \
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<SpimData version=\"0.2\">"                       \
    "<SequenceDescription>" loader "<ViewSetups>" setups "</ViewSetups>" tp                        \
    "</SequenceDescription>"
#define LOADER "<ImageLoader format=\"bdv.hdf5\"><hdf5 type=\"relative\">ok.h5</hdf5></ImageLoader>"
#define SETUP0                                                                                     \
    "<ViewSetup><id>0</id><name>one</name><voxelSize><unit>um</unit></voxelSize></ViewSetup>"
#define TP1 "<Timepoints type=\"range\"><first>0</first><last>0</last></Timepoints>"
#define XML_(loader, setups, tp, regs) SEQ_(loader, setups, tp) regs "</SpimData>"
#define XMLR(regs) XML_(LOADER, SETUP0, TP1, "<ViewRegistrations>" regs "</ViewRegistrations>")
#define AFFINE(a)                                                                                  \
    "<ViewRegistration timepoint=\"0\" setup=\"0\"><ViewTransform type=\"affine\"><affine>" a      \
    "</affine></ViewTransform></ViewRegistration>"

typedef struct xcase {
    const char *name, *xml;
    int level, channel, time;
    vv_status want;
    const char *needle;
} xcase;

static const xcase g_xml[] = {
    {"not_xml", "<SpimData><SequenceDescription>", 0, -1, -1, VV_ERR_FORMAT, "not well-formed XML"},
    {"root", "<?xml version=\"1.0\"?><SpimDatum/>", 0, -1, -1, VV_ERR_FORMAT,
     "the root element is <SpimDatum>, not <SpimData>"},
    {"no_seq", "<SpimData><Nothing/></SpimData>", 0, -1, -1, VV_ERR_FORMAT,
     "no SequenceDescription"},
    {"bomb",
     "<?xml version=\"1.0\"?>\n<!DOCTYPE SpimData [\n<!ENTITY a \"aaaaaaaaaa\">\n"
     "<!ENTITY b \"&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;\">\n<!ENTITY c "
     "\"&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;\">"
     "\n<!ENTITY d \"&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;\">\n<!ENTITY e \"&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;"
     "\">\n<!ENTITY f \"&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;\">\n<!ENTITY g \"&f;&f;&f;&f;&f;&f;&f;&f;&f;"
     "&f;\">\n<!ENTITY h \"&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;\">\n]>\n<SpimData><SequenceDescription>"
     "<ViewSetups><ViewSetup><id>0</id><name>&h;</name></ViewSetup></ViewSetups>"
     "</SequenceDescription></SpimData>",
     0, -1, -1, VV_ERR_FORMAT, "a <!DOCTYPE>"},
    {"xxe",
     "<?xml version=\"1.0\"?>\n<!DOCTYPE SpimData [<!ENTITY xxe SYSTEM \"file:///etc/passwd\">]>"
     "\n" SEQ_(LOADER, "<ViewSetup><id>0</id><name>&xxe;</name></ViewSetup>", TP1) "</SpimData>",
     0, -1, -1, VV_ERR_FORMAT, "a <!DOCTYPE>"},
    {"external_dtd",
     "<?xml version=\"1.0\"?>\n<!DOCTYPE SpimData SYSTEM \"/etc/passwd\">\n" SEQ_(
         LOADER, SETUP0, TP1) "</SpimData>",
     0, -1, -1, VV_ERR_FORMAT, "a <!DOCTYPE>"},
    {"undeclared_entity",
     XML_(LOADER, "<ViewSetup><id>0</id><name>&xxe;</name></ViewSetup>", TP1, ""), 0, -1, -1,
     VV_ERR_FORMAT, "not well-formed XML"},
    {"loader_format",
     XML_("<ImageLoader format=\"spimreconstruction.filelist\"></ImageLoader>", SETUP0, TP1, ""), 0,
     -1, -1, VV_ERR_UNSUPPORTED, "ImageLoader format \"spimreconstruction.filelist\""},
    {"n5_missing",
     XML_("<ImageLoader format=\"bdv.n5\"><n5>x.n5</n5></ImageLoader>", SETUP0, TP1, ""), 0, -1, -1,
     VV_ERR_FORMAT, "x.n5: no group setup0/timepoint0"},
    {"n5_none", XML_("<ImageLoader format=\"bdv.n5\"></ImageLoader>", SETUP0, TP1, ""), 0, -1, -1,
     VV_ERR_FORMAT, "the ImageLoader names no n5 container"},
    {"loader_none", XML_("", SETUP0, TP1, ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "ImageLoader format \"\""},
    {"hdf5_none", XML_("<ImageLoader format=\"bdv.hdf5\"></ImageLoader>", SETUP0, TP1, ""), 0, -1,
     -1, VV_ERR_FORMAT, "the ImageLoader names no hdf5 file"},
    {"hdf5_empty",
     XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5 type=\"relative\"> </hdf5></ImageLoader>", SETUP0,
          TP1, ""),
     0, -1, -1, VV_ERR_FORMAT, "names no hdf5 file"},
    {"hdf5_absolute",
     XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5 type=\"absolute\">ok.h5</hdf5></ImageLoader>",
          SETUP0, TP1, ""),
     0, -1, -1, VV_ERR_FORMAT, "the hdf5 file \"ok.h5\" is not a relative path"},
    {"hdf5_root",
     XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>/etc/passwd</hdf5></ImageLoader>", SETUP0, TP1,
          ""),
     0, -1, -1, VV_ERR_FORMAT, "\"/etc/passwd\" is not a relative path"},
    {"hdf5_up",
     XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>../x.h5</hdf5></ImageLoader>", SETUP0, TP1, ""),
     0, -1, -1, VV_ERR_FORMAT, "\"../x.h5\" is not a relative path"},
    {"hdf5_mid",
     XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>a/../../x.h5</hdf5></ImageLoader>", SETUP0, TP1,
          ""),
     0, -1, -1, VV_ERR_FORMAT, "is not a relative path"},
    {"hdf5_end",
     XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>a/..</hdf5></ImageLoader>", SETUP0, TP1, ""), 0,
     -1, -1, VV_ERR_FORMAT, "is not a relative path"},
    {"hdf5_dotdot",
     XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>..</hdf5></ImageLoader>", SETUP0, TP1, ""), 0, -1,
     -1, VV_ERR_FORMAT, "is not a relative path"},
    {"hdf5_absent",
     XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>absent.h5</hdf5></ImageLoader>", SETUP0, TP1, ""),
     0, -1, -1, VV_ERR_IO, "x_hdf5_absent.xml: absent.h5: cannot open it as an HDF5 file"},
    {"setup_no_id", XML_(LOADER, "<ViewSetup><name>x</name></ViewSetup>", TP1, ""), 0, -1, -1,
     VV_ERR_FORMAT, "a ViewSetup without an id"},
    {"setup_bad_id", XML_(LOADER, "<ViewSetup><id>-3</id></ViewSetup>", TP1, ""), 0, -1, -1,
     VV_ERR_FORMAT, "a ViewSetup without an id"},
    {"setup_big_id", XML_(LOADER, "<ViewSetup><id>100000</id></ViewSetup>", TP1, ""), 0, -1, -1,
     VV_ERR_FORMAT, "a ViewSetup without an id"},
    {"setup_twice", XML_(LOADER, SETUP0 "<ViewSetup><id>1</id></ViewSetup>" SETUP0, TP1, ""), 0, -1,
     -1, VV_ERR_FORMAT, "two ViewSetups of id 0"},
    {"setup_none", XML_(LOADER, "", TP1, ""), 0, -1, -1, VV_ERR_FORMAT, "no ViewSetup"},
    {"tp_none", XML_(LOADER, SETUP0, "", ""), 0, -1, -1, VV_ERR_FORMAT, "no Timepoints"},
    {"tp_range",
     XML_(LOADER, SETUP0, "<Timepoints type=\"range\"><first>3</first></Timepoints>", ""), 0, -1,
     -1, VV_ERR_FORMAT, "Timepoints range without a first and last"},
    {"tp_range_back",
     XML_(LOADER, SETUP0, "<Timepoints type=\"range\"><first>3</first><last>1</last></Timepoints>",
          ""),
     0, -1, -1, VV_ERR_FORMAT, "Timepoints range"},
    {"tp_range_huge",
     XML_(LOADER, SETUP0,
          "<Timepoints type=\"range\"><first>0</first><last>999999</last></Timepoints>", ""),
     0, -1, -1, VV_ERR_FORMAT, "Timepoints range"},
    {"tp_pattern_none", XML_(LOADER, SETUP0, "<Timepoints type=\"pattern\"></Timepoints>", ""), 0,
     -1, -1, VV_ERR_FORMAT, "Timepoints pattern without integerpattern"},
    {"tp_pattern_text",
     XML_(LOADER, SETUP0,
          "<Timepoints type=\"pattern\"><integerpattern>0-3, x</integerpattern></Timepoints>", ""),
     0, -1, -1, VV_ERR_FORMAT, "Timepoints pattern \"0-3, x\" is not integers"},
    {"tp_pattern_range",
     XML_(LOADER, SETUP0,
          "<Timepoints type=\"pattern\"><integerpattern>5-2</integerpattern></Timepoints>", ""),
     0, -1, -1, VV_ERR_FORMAT, "Timepoints pattern \"5-2\" out of range"},
    {"tp_pattern_step",
     XML_(LOADER, SETUP0,
          "<Timepoints type=\"pattern\"><integerpattern>0-9:0</integerpattern></Timepoints>", ""),
     0, -1, -1, VV_ERR_FORMAT, "out of range"},
    {"tp_pattern_int_max",
     XML_(LOADER, SETUP0,
          "<Timepoints type=\"pattern\"><integerpattern>2147483600-2147483647:100"
          "</integerpattern></Timepoints>",
          ""),
     0, -1, -1, VV_ERR_FORMAT, "out of range"},
    {"tp_pattern_many",
     XML_(LOADER, SETUP0,
          "<Timepoints type=\"pattern\"><integerpattern>0-99999, 100000</integerpattern>"
          "</Timepoints>",
          ""),
     0, -1, -1, VV_ERR_LIMIT, "over 100000 time points"},
    {"tp_list_no_id",
     XML_(LOADER, SETUP0, "<Timepoints type=\"list\"><Timepoint><x/></Timepoint></Timepoints>", ""),
     0, -1, -1, VV_ERR_FORMAT, "a Timepoint without an id"},
    {"tp_list_empty", XML_(LOADER, SETUP0, "<Timepoints type=\"list\"></Timepoints>", ""), 0, -1,
     -1, VV_ERR_FORMAT, "no time point"},
    {"tp_type", XML_(LOADER, SETUP0, "<Timepoints type=\"steps\"></Timepoints>", ""), 0, -1, -1,
     VV_ERR_FORMAT, "Timepoints of type \"steps\" (range, pattern, list)"},
    {"channel_past", XMLR(""), 0, 1, -1, VV_ERR_INVALID, "channel 1 asked, the dataset has 1"},
    {"time_past", XMLR(""), 0, -1, 1, VV_ERR_INVALID, "time step 1 asked, the dataset has 1"},
    {"level_past", XMLR(""), 1, -1, -1, VV_ERR_INVALID, "level 1 asked, the dataset has 1"},
    {"affine_short", XMLR(AFFINE("1 0 0 0 0 1 0 0 0 0 1")), 0, -1, -1, VV_ERR_FORMAT,
     "a ViewTransform of view (0, 0) is not an affine of 12 numbers"},
    {"affine_long", XMLR(AFFINE("1 0 0 0 0 1 0 0 0 0 1 0 7")), 0, -1, -1, VV_ERR_FORMAT,
     "not an affine of 12 numbers"},
    {"affine_missing",
     XMLR("<ViewRegistration timepoint=\"0\" setup=\"0\"><ViewTransform/></ViewRegistration>"), 0,
     -1, -1, VV_ERR_FORMAT, "not an affine of 12 numbers"},
    {"affine_nan", XMLR(AFFINE("1 0 0 0 0 nan 0 0 0 0 1 0")), 0, -1, -1, VV_ERR_FORMAT,
     "a ViewTransform of view (0, 0) is not finite"},
    {"affine_huge", XMLR(AFFINE("1 0 0 1e31 0 1 0 0 0 0 1 0")), 0, -1, -1, VV_ERR_FORMAT,
     "is not finite"},
    {"affine_singular", XMLR(AFFINE("1 0 0 0 0 0 0 0 0 0 1 0")), 0, -1, -1, VV_ERR_FORMAT,
     "the view's affine is singular (axis 1 has no length)"},
    /* ten scalings by 1e30 (1e300), a shift by 1e30 there (infinite), ten
     * scalings back: finite axes, the origin at infinity */
    {"affine_origin_inf",
     XMLR("<ViewRegistration timepoint=\"0\" setup=\"0\">"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e30 0 0 0 0 1e30 0 0 0 0 1e30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1 0 0 1e30 0 1 0 0 0 0 1 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "<ViewTransform><affine>1e-30 0 0 0 0 1e-30 0 0 0 0 1e-30 0</affine></ViewTransform>"
          "</ViewRegistration>"),
     0, -1, -1, VV_ERR_FORMAT, "the view's affine puts level 0's origin at infinity (axis 0)"},
    {"setup_not_in_h5", XML_(LOADER, "<ViewSetup><id>7</id></ViewSetup>", TP1, ""), 0, -1, -1,
     VV_ERR_FORMAT, "ok.h5: no setup 7 at time point 0 (t00000/s07)"},
};

static void
test_xml(void **state) {
    (void)state;
    const bdv_spec ok = {OK1};
    write_bdv(tpath("ok.h5"), &ok);
    for (size_t i = 0; i < sizeof g_xml / sizeof g_xml[0]; i++) {
        const xcase *c = &g_xml[i];
        char name[128];
        snprintf(name, sizeof name, "x_%s.xml", c->name); /* no HDF5 file's companion */
        print_message("%s\n", c->name);
        put_text(tpath(name), c->xml);
        load_expect(tpath(name), VV_FORMAT_BDV_XML, c->level, c->channel, c->time, c->want,
                    c->needle, c->level == 0 && i >= 3); /* the first 3 are not detected */
        assert_null(strstr(vv_error_message(), "root:"));
    }
}

/* Limits: 1025 ViewSetups; an hdf5 name too long for a path; a pattern
 * that repeats a range of 100000 ids 400 times (its square was a hang);
 * an XML over 64 MiB; one that cannot be opened. */
static void
test_xml_limits(void **state) {
    (void)state;
    const bdv_spec ok = {OK1};
    write_bdv(tpath("ok.h5"), &ok);
    size_t cap = 1 << 20, n = 0;
    char *x = malloc(cap);
    n += (size_t)snprintf(x + n, cap - n, "%s", SEQ_(LOADER, "", ""));
    n -= strlen("</ViewSetups></SequenceDescription>");
    for (int i = 0; i <= 1024; i++)
        n += (size_t)snprintf(x + n, cap - n, "<ViewSetup><id>%d</id></ViewSetup>", i);
    n += (size_t)snprintf(x + n, cap - n, "</ViewSetups>" TP1 "</SequenceDescription></SpimData>");
    put_text(tpath("setups.xml"), x);
    load_expect(tpath("setups.xml"), VV_FORMAT_BDV_XML, 0, -1, -1, VV_ERR_LIMIT,
                "over 1024 ViewSetups", 1);

    char name[4200];
    memset(name, 'a', 4050); /* fits the text, not the path beside the XML */
    name[4050] = '\0';
    snprintf(x, cap,
             SEQ_("<ImageLoader format=\"bdv.hdf5\"><hdf5>%s</hdf5></ImageLoader>", SETUP0,
                  TP1) "</SpimData>",
             name);
    put_text(tpath("long.xml"), x);
    load_expect(tpath("long.xml"), VV_FORMAT_BDV_XML, 0, -1, -1, VV_ERR_LIMIT,
                "the hdf5 file's path is too long", 1);

    n = (size_t)snprintf(x, cap, "%s", SEQ_(LOADER, SETUP0, ""));
    n -= strlen("</SequenceDescription>");
    n += (size_t)snprintf(x + n, cap - n, "<Timepoints type=\"pattern\"><integerpattern>");
    for (int i = 0; i < 400; i++)
        n += (size_t)snprintf(x + n, cap - n, "%s0-99999", i ? "," : "");
    snprintf(x + n, cap - n, "</integerpattern></Timepoints></SequenceDescription></SpimData>");
    put_text(tpath("repeat.xml"), x);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    load_expect(tpath("repeat.xml"), VV_FORMAT_BDV_XML, 0, -1, 100000, VV_ERR_INVALID,
                "time step 100000 asked, the dataset has 100000", 0);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    const double s = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    if (s > 20)
        fail_msg("a repeated pattern took %.1f s", s);
    free(x);

    /* straight through the row (detection would not call a sparse file XML) */
    const vv_format_record *r = vv_format_record_of(VV_FORMAT_BDV_XML);
    assert_non_null(r);
    vv_load_options o;
    vv_load_options_init(&o);
    int fd = open(tpath("huge.xml"), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, (64 << 20) + 1), 0);
    close(fd);
    vv_volume *v = NULL;
    expect(r->read(&v, tpath("huge.xml"), &o), VV_ERR_LIMIT,
           "huge.xml: 67108865 bytes, over the 64 MiB", NULL);
    assert_null(v);
    expect(r->read(&v, tpath("absent.xml"), &o), VV_ERR_IO, "bdv: absent.xml: No such file", NULL);
    assert_null(v);
}

/* A deflated chunk overwritten with junk: the read fails, one line. */
static void
test_corrupt_chunk(void **state) {
    (void)state;
    const char *path = tpath("corrupt.h5");
    hid_t f = h5_new(path);
    const double res[3] = {1, 1, 1};
    h5_table(f, "s00/resolutions", 1, 3, res);
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE), dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    const hsize_t dims[3] = {8, 8, 8};
    H5Pset_chunk(dcpl, 3, dims);
    H5Pset_deflate(dcpl, 6);
    hid_t sp = H5Screate_simple(3, dims, NULL);
    hid_t d = H5Dcreate2(f, "t00000/s00/0/cells", H5T_STD_I16LE, sp, lcpl, dcpl, H5P_DEFAULT);
    short buf[512];
    for (int i = 0; i < 512; i++)
        buf[i] = (short)(i * 7);
    assert_true(H5Dwrite(d, H5T_NATIVE_SHORT, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
    H5Fflush(f, H5F_SCOPE_GLOBAL);
    haddr_t addr = 0;
    hsize_t size = 0, off[3];
    unsigned mask = 0;
    assert_true(H5Dget_chunk_info(d, sp, 0, off, &mask, &addr, &size) >= 0);
    H5Dclose(d);
    H5Sclose(sp);
    H5Pclose(dcpl);
    H5Pclose(lcpl);
    H5Fclose(f);
    FILE *fp = fopen(path, "r+b");
    assert_non_null(fp);
    assert_int_equal(fseek(fp, (long)addr, SEEK_SET), 0);
    for (hsize_t i = 0; i < size; i++)
        fputc(0xa5, fp);
    fclose(fp);
    load_expect(path, VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "level 0: the chunk at voxel (0, 0, 0) does not read", 1);
    /* the same file through a dataset XML naming it */
    put_text(tpath("x_corrupt.xml"),
             XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>corrupt.h5</hdf5></ImageLoader>", SETUP0,
                  TP1, ""));
    load_expect(tpath("x_corrupt.xml"), VV_FORMAT_BDV_XML, 0, -1, -1, VV_ERR_FORMAT,
                "bdv: x_corrupt.xml: level 0: the chunk at voxel (0, 0, 0) does not read", 1);
}

/* The HDF5 file an XML names is a link out of the XML's folder (itself, or
 * a folder on its way): refused; a link inside the folder is read. */
static void
test_xml_links(void **state) {
    (void)state;
    char out[4200], target[4400];
    snprintf(out, sizeof out, "%s", vt_outdir("errors_bdv_hdf5_outside"));
    snprintf(target, sizeof target, "%s/other.h5", out);
    const bdv_spec ok = {OK1};
    write_bdv(target, &ok);
    write_bdv(tpath("ok.h5"), &ok);
    unlink(tpath("link_out.h5"));
    assert_int_equal(symlink(target, tpath("link_out.h5")), 0);
    unlink(tpath("sub_out"));
    assert_int_equal(symlink(out, tpath("sub_out")), 0);
    unlink(tpath("link_in.h5"));
    assert_int_equal(symlink("ok.h5", tpath("link_in.h5")), 0);
    put_text(tpath("x_link_out.xml"),
             XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>link_out.h5</hdf5></ImageLoader>", SETUP0,
                  TP1, ""));
    load_expect(tpath("x_link_out.xml"), VV_FORMAT_BDV_XML, 0, -1, -1, VV_ERR_FORMAT,
                "x_link_out.xml: the hdf5 file \"link_out.h5\" resolves outside the XML's folder",
                1);
    put_text(tpath("x_sub_out.xml"),
             XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>sub_out/other.h5</hdf5></ImageLoader>",
                  SETUP0, TP1, ""));
    load_expect(tpath("x_sub_out.xml"), VV_FORMAT_BDV_XML, 0, -1, -1, VV_ERR_FORMAT,
                "resolves outside the XML's folder", 1);
    put_text(tpath("x_link_in.xml"),
             XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>link_in.h5</hdf5></ImageLoader>", SETUP0,
                  TP1, ""));
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = VV_FORMAT_BDV_XML;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, tpath("x_link_in.xml"), &o));
    assert_int_equal(v->dims[0], 4);
    vv_volume_free(v);
}

/* FIFOs where files belong (an open would block until a writer came): a
 * dataset XML, a companion XML, the HDF5 file an XML names. */
static void
test_fifos(void **state) {
    (void)state;
    const vv_format_record *r = vv_format_record_of(VV_FORMAT_BDV_XML);
    vv_load_options o;
    vv_load_options_init(&o);
    vv_volume *v = NULL;
    unlink(tpath("fifo.xml"));
    assert_int_equal(mkfifo(tpath("fifo.xml"), 0644), 0);
    expect(r->read(&v, tpath("fifo.xml"), &o), VV_ERR_FORMAT, "bdv: fifo.xml: not a regular file",
           NULL);
    assert_null(v);

    const bdv_spec ok = {OK1};
    write_bdv(tpath("fifo_comp.h5"), &ok);
    unlink(tpath("fifo_comp.xml"));
    assert_int_equal(mkfifo(tpath("fifo_comp.xml"), 0644), 0);
    load_expect(tpath("fifo_comp.h5"), VV_FORMAT_HDF5, 0, -1, -1, VV_ERR_FORMAT,
                "fifo_comp.xml: the companion XML is not a regular file", 1);

    unlink(tpath("fifo_data.h5"));
    assert_int_equal(mkfifo(tpath("fifo_data.h5"), 0644), 0);
    put_text(tpath("x_fifo_data.xml"),
             XML_("<ImageLoader format=\"bdv.hdf5\"><hdf5>fifo_data.h5</hdf5></ImageLoader>",
                  SETUP0, TP1, ""));
    load_expect(tpath("x_fifo_data.xml"), VV_FORMAT_BDV_XML, 0, -1, -1, VV_ERR_FORMAT,
                "bdv: x_fifo_data.xml: fifo_data.h5: not a regular file", 1);
}

int
main(void) {
    setenv("VOLVIS_SANDBOX", "0", 1);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    snprintf(g_dir, sizeof g_dir, "%s", vt_outdir("errors_bdv_hdf5"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hdf5_bdv),   cmocka_unit_test(test_hdf5_elsewhere),
        cmocka_unit_test(test_hdf5_files), cmocka_unit_test(test_hdf5_companion),
        cmocka_unit_test(test_imaris),     cmocka_unit_test(test_corrupt_chunk),
        cmocka_unit_test(test_xml),        cmocka_unit_test(test_xml_limits),
        cmocka_unit_test(test_xml_links),  cmocka_unit_test(test_fifos),
    };
    return vt_run_tests(tests, NULL, NULL);
}
