/*
 * Grid readers (src/io/grid_*.c): every file of ../shared/data/grids loads
 * with its documented counts; round trips through hand-written files in
 * each variant (ASCII / binary VTK, inline / appended / raw / base64 /
 * zlib .vtu, text DX, PLOT3D with record markers and little-endian); bad
 * input gives one-line errors.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "testutil.h"
#include "volvis/sys/format.h"

#if defined(__has_include)
#if __has_include(<netcdf.h>)
#include <netcdf.h>
#define HAVE_NETCDF_H 1
#endif
#endif

static int
have_data(void) {
    FILE *f = fopen(vt_data("grids/hyper.dx"), "rb");
    if (f)
        fclose(f);
    return f != NULL;
}

static vv_grid *
load(const char *rel) {
    vv_grid *g = NULL;
    vt_ok(vv_grid_load(&g, vt_data(rel)));
    return g;
}

static size_t
count_type(const vv_grid *g, int type) {
    size_t n = 0;
    for (size_t c = 0; c < g->n_cells; c++)
        n += g->cell_types[c] == type;
    return n;
}

static void
test_hyper_dx(void **state) {
    (void)state;
    if (!have_data())
        vt_skip("../shared/data/grids is missing");
    vv_grid *g = load("grids/hyper.dx");
    assert_int_equal(g->kind, VV_GRID_UNSTRUCTURED);
    assert_int_equal(g->n_points, 8000);
    assert_int_equal(g->n_cells, 34295);
    assert_int_equal(count_type(g, VV_CELL_TETRA), 34295);
    assert_int_equal(g->n_fields, 2);
    assert_string_equal(g->fields[0].name, "function");
    assert_int_equal(g->fields[0].n_components, 1);
    assert_string_equal(g->fields[1].name, "vectors");
    assert_int_equal(g->fields[1].n_components, 3);
    assert_true(g->fields[0].range[1] > g->fields[0].range[0]);
    printf("hyper.dx: function in [%g, %g]\n", g->fields[0].range[0], g->fields[0].range[1]);
    vv_grid_free(g);
}

static void
test_fire_vtu(void **state) {
    (void)state;
    if (!have_data())
        vt_skip("../shared/data/grids is missing");
    vv_grid *g = load("grids/fire_ug.vtu");
    assert_int_equal(g->n_points, 12323);
    assert_int_equal(g->n_cells, 10462);
    assert_int_equal(count_type(g, VV_CELL_HEXAHEDRON), 10462);
    const char *names[] = {"t", "uvw", "u", "v", "w", "mfrac"};
    assert_int_equal(g->n_fields, 6);
    for (int i = 0; i < 6; i++)
        assert_string_equal(g->fields[i].name, names[i]);
    assert_int_equal(g->fields[1].n_components, 3);
    printf("fire_ug.vtu: t in [%g, %g]\n", g->fields[0].range[0], g->fields[0].range[1]);
    assert_true(g->fields[0].range[1] > g->fields[0].range[0]);
    vv_grid_free(g);
}

static void
test_blow_vtk(void **state) {
    (void)state;
    if (!have_data())
        vt_skip("../shared/data/grids is missing");
    vv_grid *g = load("grids/blow.vtk");
    assert_int_equal(g->n_points, 687);
    assert_int_equal(g->n_cells, 1057);
    assert_int_equal(count_type(g, VV_CELL_TRIANGLE), 928);
    assert_int_equal(count_type(g, VV_CELL_QUAD), 129);
    size_t n3, ns;
    vv_grid_count_cells(g, &n3, &ns);
    assert_int_equal(n3, 0);
    assert_int_equal(ns, 1057);
    assert_true(vv_grid_find_field(g, "thickness", 9) >= 0);
    assert_true(vv_grid_find_field(g, "displacement", 9) >= 0);
    assert_int_equal(g->fields[vv_grid_find_field(g, "displacement", 0)].n_components, 3);
    vv_grid_free(g);
}

static void
test_plot3d(void **state) {
    (void)state;
    if (!have_data())
        vt_skip("../shared/data/grids is missing");
    vv_grid *g = load("grids/bluntfinxyz.bin");
    assert_int_equal(g->kind, VV_GRID_CURVILINEAR);
    assert_int_equal(g->n_blocks, 1);
    assert_int_equal(g->block_dims[0][0], 40);
    assert_int_equal(g->block_dims[0][1], 32);
    assert_int_equal(g->block_dims[0][2], 32);
    assert_int_equal(g->n_points, 40 * 32 * 32);
    assert_int_equal(g->n_cells, 39 * 31 * 31);
    assert_true(vv_grid_find_field(g, "density", 0) >= 0);
    const vv_grid_field *d = &g->fields[vv_grid_find_field(g, "density", 0)];
    printf("bluntfin: density in [%g, %g]\n", d->range[0], d->range[1]);
    assert_true(d->range[0] > 0 && d->range[1] < 10);
    vv_grid_free(g);
    g = load("grids/combxyz.bin");
    assert_int_equal(g->block_dims[0][0], 57);
    assert_int_equal(g->block_dims[0][1], 33);
    assert_int_equal(g->block_dims[0][2], 25);
    assert_int_equal(g->n_cells, 56 * 32 * 24);
    d = &g->fields[vv_grid_find_field(g, "density", 0)];
    printf("comb: density in [%g, %g]\n", d->range[0], d->range[1]);
    assert_true(d->range[0] > 0 && d->range[1] < 10);
    vv_grid_free(g);
}

static void
test_levitus(void **state) {
    (void)state;
    if (!have_data())
        vt_skip("../shared/data/grids is missing");
    vv_grid *g = NULL;
    vv_status s = vv_grid_load(&g, vt_data("grids/levitus_climatology.cdf"));
    if (s == VV_ERR_UNSUPPORTED)
        vt_skip("the build has no NetCDF (libnetcdf-dev)");
    vt_ok(s);
    assert_int_equal(g->kind, VV_GRID_SPHERICAL);
    assert_int_equal(g->sph_dims[0], 21); /* depth edges */
    assert_int_equal(g->sph_dims[1], 181);
    assert_int_equal(g->sph_dims[2], 360); /* longitudes wrap */
    assert_int_equal(g->n_cells, 360 * 180 * 20);
    int t = vv_grid_find_field(g, "TEMP", 0);
    assert_true(t >= 0);
    assert_true(g->fields[t].cell_data);
    /* uneven depth: the radii step by different amounts */
    const double *r = g->sph_axes[0];
    assert_true(fabs((r[20] - r[19]) - (r[1] - r[0])) > 1);
    size_t missing = 0;
    for (size_t i = 0; i < g->fields[t].n_tuples; i++)
        missing += vv_grid_field_missing(&g->fields[t], i);
    printf("levitus: TEMP in [%g, %g], %zu of %zu cells land\n", g->fields[t].range[0],
           g->fields[t].range[1], missing, g->fields[t].n_tuples);
    assert_true(missing > 100000 && missing < g->fields[t].n_tuples);
    assert_true(g->fields[t].range[0] > -5 && g->fields[t].range[1] < 40);
    vv_grid_free(g);
}

/* ---- hand-written variants ---------------------------------------------- */

static const char *
write_text(const char *name, const char *text) {
    const char *p = vt_path(vt_outdir("grid_readers"), name);
    vt_write_file(p, text, strlen(text));
    return p;
}

static const char *two_tets_vtk = "# vtk DataFile Version 3.0\n"
                                  "two tetrahedra\n"
                                  "ASCII\n"
                                  "DATASET UNSTRUCTURED_GRID\n"
                                  "POINTS 5 float\n"
                                  "0 0 0  1 0 0  0 1 0  0 0 1  1 1 1\n"
                                  "CELLS 2 10\n"
                                  "4 0 1 2 3\n"
                                  "4 1 2 3 4\n"
                                  "CELL_TYPES 2\n"
                                  "10 10\n"
                                  "POINT_DATA 5\n"
                                  "SCALARS s float 1\n"
                                  "LOOKUP_TABLE default\n"
                                  "0 1 2 3 4\n"
                                  "CELL_DATA 2\n"
                                  "SCALARS c double\n"
                                  "LOOKUP_TABLE default\n"
                                  "5 6\n";

static void
check_two_tets(const vv_grid *g) {
    assert_int_equal(g->n_points, 5);
    assert_int_equal(g->n_cells, 2);
    assert_int_equal(g->connectivity[7], 4);
    assert_int_equal(g->n_fields, 2);
    assert_false(g->fields[0].cell_data);
    assert_true(g->fields[1].cell_data);
    assert_near(g->fields[0].values[4], 4, 0);
    assert_near(g->fields[1].values[1], 6, 0);
    assert_near(g->points[3 * 4 + 2], 1, 0);
}

static void
put_be32(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

static void
put_bef(unsigned char *p, float f) {
    uint32_t u;
    memcpy(&u, &f, 4);
    put_be32(p, u);
}

static void
test_vtk_ascii_binary(void **state) {
    (void)state;
    vv_grid *g = NULL;
    vt_ok(vv_grid_load(&g, write_text("two.vtk", two_tets_vtk)));
    check_two_tets(g);
    vv_grid_free(g);
    /* the same in binary (big-endian) */
    unsigned char buf[2048];
    size_t n = 0;
    n += (size_t)sprintf((char *)buf + n, "# vtk DataFile Version 3.0\nbin\nBINARY\nDATASET "
                                          "UNSTRUCTURED_GRID\nPOINTS 5 float\n");
    const float pts[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    for (int i = 0; i < 15; i++, n += 4)
        put_bef(buf + n, pts[i]);
    n += (size_t)sprintf((char *)buf + n, "\nCELLS 2 10\n");
    const int cells[10] = {4, 0, 1, 2, 3, 4, 1, 2, 3, 4};
    for (int i = 0; i < 10; i++, n += 4)
        put_be32(buf + n, (uint32_t)cells[i]);
    n += (size_t)sprintf((char *)buf + n, "\nCELL_TYPES 2\n");
    put_be32(buf + n, 10);
    put_be32(buf + n + 4, 10);
    n += 8;
    n += (size_t)sprintf((char *)buf + n, "\nPOINT_DATA 5\nSCALARS s float 1\nLOOKUP_TABLE "
                                          "default\n");
    for (int i = 0; i < 5; i++, n += 4)
        put_bef(buf + n, (float)i);
    n += (size_t)sprintf((char *)buf + n, "\nCELL_DATA 2\nSCALARS c float\nLOOKUP_TABLE "
                                          "default\n");
    put_bef(buf + n, 5);
    put_bef(buf + n + 4, 6);
    n += 8;
    const char *p = vt_path(vt_outdir("grid_readers"), "two_bin.vtk");
    vt_write_file(p, buf, n);
    vt_ok(vv_grid_load(&g, p));
    check_two_tets(g);
    vv_grid_free(g);
    /* VTK 5.1: OFFSETS and CONNECTIVITY */
    const char *v51 = "# vtk DataFile Version 5.1\n"
                      "two tetrahedra\n"
                      "ASCII\n"
                      "DATASET UNSTRUCTURED_GRID\n"
                      "POINTS 5 float\n"
                      "0 0 0  1 0 0  0 1 0  0 0 1  1 1 1\n"
                      "CELLS 3 8\n"
                      "OFFSETS vtktypeint64\n"
                      "0 4 8\n"
                      "CONNECTIVITY vtktypeint64\n"
                      "0 1 2 3 1 2 3 4\n"
                      "CELL_TYPES 2\n"
                      "10 10\n"
                      "POINT_DATA 5\n"
                      "SCALARS s float 1\n"
                      "LOOKUP_TABLE default\n"
                      "0 1 2 3 4\n"
                      "CELL_DATA 2\n"
                      "SCALARS c double\n"
                      "LOOKUP_TABLE default\n"
                      "5 6\n";
    vt_ok(vv_grid_load(&g, write_text("two51.vtk", v51)));
    check_two_tets(g);
    vv_grid_free(g);
    /* truncated binary */
    vt_write_file(p, buf, n - 30);
    vt_err(vv_grid_load(&g, p));
    assert_null(g);
}

static const char *
b64(const unsigned char *in, size_t n, char *out) {
    static const char *t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t k = 0;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t w = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0) |
                     (i + 2 < n ? in[i + 2] : 0);
        out[k++] = t[w >> 18 & 63];
        out[k++] = t[w >> 12 & 63];
        out[k++] = i + 1 < n ? t[w >> 6 & 63] : '=';
        out[k++] = i + 2 < n ? t[w & 63] : '=';
    }
    out[k] = '\0';
    return out;
}

/* A .vtu of the two tetrahedra with its arrays encoded as asked. */
static const char *
write_vtu(const char *name, const char *mode) {
    const float pts[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    const int32_t conn[8] = {0, 1, 2, 3, 1, 2, 3, 4}, offs[2] = {4, 8};
    const uint8_t types[2] = {10, 10};
    const float s[5] = {0, 1, 2, 3, 4};
    const double c[2] = {5, 6};
    const void *arr[6] = {pts, conn, offs, types, s, c};
    const size_t len[6] = {sizeof pts, sizeof conn, sizeof offs, sizeof types, sizeof s, sizeof c};
    const char *decl[6] = {"type=\"Float32\" NumberOfComponents=\"3\"",
                           "type=\"Int32\" Name=\"connectivity\"",
                           "type=\"Int32\" Name=\"offsets\"",
                           "type=\"UInt8\" Name=\"types\"",
                           "type=\"Float32\" Name=\"s\"",
                           "type=\"Float64\" Name=\"c\""};
    const int zlib = strstr(mode, "zlib") != NULL;
    const int appended = strstr(mode, "appended") != NULL;
    const int raw = strstr(mode, "raw") != NULL;
    static char xml[16384];
    static unsigned char app[8192];
    size_t an = 0;
    static char body[6][4096];
    for (int i = 0; i < 6; i++) {
        unsigned char blob[1024];
        size_t bn = 0;
        if (zlib) {
            unsigned char z[512];
            uLongf zl = sizeof z;
            compress(z, &zl, arr[i], len[i]);
            const uint32_t h[4] = {1, (uint32_t)len[i], (uint32_t)len[i], (uint32_t)zl};
            memcpy(blob, h, 16);
            bn = 16;
            if (raw || !appended) {
                memcpy(blob + bn, z, zl);
                bn += zl;
            } else {
                /* base64: header and data encoded separately, as VTK does */
                char e1[256], e2[1024];
                b64(blob, 16, e1);
                b64(z, zl, e2);
                const size_t off = an;
                memcpy(app + an, e1, strlen(e1));
                an += strlen(e1);
                memcpy(app + an, e2, strlen(e2));
                an += strlen(e2);
                snprintf(body[i], sizeof body[i],
                         "<DataArray %s format=\"appended\" offset=\"%zu\"/>", decl[i], off);
                continue;
            }
        } else {
            const uint32_t h = (uint32_t)len[i];
            memcpy(blob, &h, 4);
            memcpy(blob + 4, arr[i], len[i]);
            bn = 4 + len[i];
        }
        if (appended) {
            const size_t off = an;
            if (raw) {
                memcpy(app + an, blob, bn);
                an += bn;
            } else {
                char e[2048];
                b64(blob, bn, e);
                memcpy(app + an, e, strlen(e));
                an += strlen(e);
            }
            snprintf(body[i], sizeof body[i], "<DataArray %s format=\"appended\" offset=\"%zu\"/>",
                     decl[i], off);
        } else {
            char e[2048];
            if (zlib) {
                /* inline compressed: header then data, separately encoded */
                char e1[256];
                b64(blob, 16, e1);
                b64(blob + 16, bn - 16, e);
                snprintf(body[i], sizeof body[i],
                         "<DataArray %s format=\"binary\">%s%s</DataArray>", decl[i], e1, e);
            } else {
                b64(blob, bn, e);
                snprintf(body[i], sizeof body[i],
                         "<DataArray %s format=\"binary\">\n  %s\n</DataArray>", decl[i], e);
            }
        }
    }
    int n = snprintf(xml, sizeof xml,
                     "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" "
                     "byte_order=\"LittleEndian\"%s>\n<UnstructuredGrid>\n<Piece "
                     "NumberOfPoints=\"5\" NumberOfCells=\"2\">\n<PointData>%s</PointData>\n"
                     "<CellData>%s</CellData>\n<Points>%s</Points>\n<Cells>%s%s%s</Cells>\n"
                     "</Piece>\n</UnstructuredGrid>\n",
                     zlib ? " compressor=\"vtkZLibDataCompressor\"" : "", body[4], body[5], body[0],
                     body[1], body[2], body[3]);
    const char *p = vt_path(vt_outdir("grid_readers"), name);
    unsigned char *all = malloc((size_t)n + an + 128);
    size_t k = (size_t)n;
    memcpy(all, xml, k);
    if (appended) {
        k += (size_t)sprintf((char *)all + k, "<AppendedData encoding=\"%s\">\n_",
                             raw ? "raw" : "base64");
        memcpy(all + k, app, an);
        k += an;
        k += (size_t)sprintf((char *)all + k, "\n</AppendedData>\n");
    }
    k += (size_t)sprintf((char *)all + k, "</VTKFile>\n");
    vt_write_file(p, all, k);
    free(all);
    return p;
}

static void
test_vtu_variants(void **state) {
    (void)state;
    const char *modes[] = {"inline",       "inline zlib",          "appended base64",
                           "appended raw", "appended base64 zlib", "appended raw zlib"};
    for (int i = 0; i < 6; i++) {
        char name[64];
        snprintf(name, sizeof name, "two_%d.vtu", i);
        vv_grid *g = NULL;
        vv_status s = vv_grid_load(&g, write_vtu(name, modes[i]));
        if (s != VV_OK)
            fail_msg("%s: %s", modes[i], vv_error_message());
        check_two_tets(g);
        vv_grid_free(g);
    }
}

static void
test_dx_text(void **state) {
    (void)state;
    const char *dx = "object 1 class array type float rank 1 shape 3 items 5 data follows\n"
                     "0 0 0  1 0 0  0 1 0  0 0 1  1 1 1\n"
                     "object 2 class array type int rank 1 shape 4 items 2 data follows\n"
                     "0 1 2 3  1 2 3 4\n"
                     "attribute \"element type\" string \"tetrahedra\"\n"
                     "attribute \"ref\" string \"positions\"\n"
                     "object 3 class array type float rank 0 items 5 data follows\n"
                     "0 1 2 3 4\n"
                     "attribute \"dep\" string \"positions\"\n"
                     "object \"s\" class field\n"
                     "component \"positions\" value 1\n"
                     "component \"connections\" value 2\n"
                     "component \"data\" value 3\n"
                     "end\n";
    vv_grid *g = NULL;
    vt_ok(vv_grid_load(&g, write_text("two.dx", dx)));
    assert_int_equal(g->n_points, 5);
    assert_int_equal(g->n_cells, 2);
    assert_string_equal(g->fields[0].name, "s");
    assert_near(g->fields[0].values[3], 3, 0);
    vv_grid_free(g);
}

static void
put_le32(unsigned char *p, uint32_t v) {
    memcpy(p, &v, 4);
}

/* PLOT3D, little-endian, multi-block with record markers, 2 blocks. */
static void
test_plot3d_variants(void **state) {
    (void)state;
    unsigned char buf[4096];
    size_t n = 0;
    const int dims[2][3] = {{2, 2, 2}, {3, 2, 2}};
    put_le32(buf + n, 4);
    put_le32(buf + n + 4, 2);
    put_le32(buf + n + 8, 4);
    n += 12;
    put_le32(buf + n, 24);
    n += 4;
    for (int b = 0; b < 2; b++)
        for (int a = 0; a < 3; a++, n += 4)
            put_le32(buf + n, (uint32_t)dims[b][a]);
    put_le32(buf + n, 24);
    n += 4;
    for (int b = 0; b < 2; b++) {
        const int np = dims[b][0] * dims[b][1] * dims[b][2];
        put_le32(buf + n, (uint32_t)(12 * np));
        n += 4;
        for (int a = 0; a < 3; a++)
            for (int k = 0; k < dims[b][2]; k++)
                for (int j = 0; j < dims[b][1]; j++)
                    for (int i = 0; i < dims[b][0]; i++, n += 4) {
                        float v = (float)(a == 0 ? i + 10 * b : a == 1 ? j : k);
                        memcpy(buf + n, &v, 4);
                    }
        put_le32(buf + n, (uint32_t)(12 * np));
        n += 4;
    }
    const char *p = vt_path(vt_outdir("grid_readers"), "multi.xyz");
    vt_write_file(p, buf, n);
    vv_grid *g = NULL;
    vt_ok(vv_grid_load(&g, p));
    assert_int_equal(g->kind, VV_GRID_CURVILINEAR);
    assert_int_equal(g->n_blocks, 2);
    assert_int_equal(g->n_points, 8 + 12);
    assert_int_equal(g->n_cells, 1 + 2);
    assert_near(g->points[3 * 8], 10, 0);
    vv_grid_free(g);
    /* single block, big-endian, no markers, IBLANK (point 3 blanked), with a solution */
    {
        unsigned char b2[1024];
        size_t m = 0;
        for (int a = 0; a < 3; a++, m += 4)
            put_be32(b2 + m, 2);
        for (int a = 0; a < 3; a++)
            for (int i = 0; i < 8; i++, m += 4)
                put_bef(b2 + m, (float)((i >> a) & 1));
        for (int i = 0; i < 8; i++, m += 4)
            put_be32(b2 + m, i == 3 ? 0 : 1);
        const char *xp = vt_path(vt_outdir("grid_readers"), "blank.xyz");
        vt_write_file(xp, b2, m);
        m = 0;
        for (int a = 0; a < 3; a++, m += 4)
            put_be32(b2 + m, 2);
        for (int k = 0; k < 4; k++, m += 4)
            put_bef(b2 + m, 0.5f); /* fsmach, alpha, re, time */
        for (int k = 0; k < 5; k++)
            for (int i = 0; i < 8; i++, m += 4)
                put_bef(b2 + m, k == 0 ? 1.0f + (float)i : 0.0f);
        vt_write_file(vt_path(vt_outdir("grid_readers"), "blank.q"), b2, m);
        vt_ok(vv_grid_load(&g, xp));
        assert_int_equal(g->n_points, 8);
        const vv_grid_field *den = &g->fields[vv_grid_find_field(g, "density", 0)];
        assert_true(vv_grid_field_missing(den, 3));
        assert_false(vv_grid_field_missing(den, 2));
        assert_near(den->values[7], 8, 0);
        vv_grid_free(g);
    }
    /* a size that no layout explains */
    vt_write_file(p, buf, n - 6);
    vt_err(vv_grid_load(&g, p));
    assert_non_null(strstr(vv_error_message(), "no PLOT3D layout"));
}

/* ---- bad input ----------------------------------------------------------- */

static void
expect_error(const char *name, const char *text, const char *needle) {
    vv_grid *g = NULL;
    vv_error_clear();
    vv_status s = vv_grid_load(&g, write_text(name, text));
    assert_true(s < 0);
    assert_null(g);
    const char *m = vv_error_message();
    printf("  %s: %s\n", name, m);
    assert_null(strchr(m, '\n'));
    if (needle && !strstr(m, needle))
        fail_msg("%s: '%s' lacks '%s'", name, m, needle);
}

static void
test_bad_input(void **state) {
    (void)state;
    char text[4096];
    /* a cell indexing a missing point */
    snprintf(text, sizeof text, "%s", two_tets_vtk);
    char *c = strstr(text, "4 1 2 3 4\n");
    c[8] = '9';
    expect_error("missing_point.vtk", text, "point 9");
    /* a huge count in a small file */
    expect_error("huge.vtk",
                 "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS "
                 "100000000 float\n0 0 0\n",
                 "POINTS");
    /* a wrong point count for a cell type */
    snprintf(text, sizeof text, "%s", two_tets_vtk);
    c = strstr(text, "CELL_TYPES 2\n10 10");
    c[17] = '2'; /* 10 12: a hexahedron of 4 points */
    expect_error("wrong_type.vtk", text, "hexahedron");
    /* an XML bomb */
    expect_error("bomb.vtu",
                 "<?xml version=\"1.0\"?>\n<!DOCTYPE lolz [<!ENTITY lol \"lol\"><!ENTITY lol2 "
                 "\"&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;\">]>\n<VTKFile "
                 "type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"1\" "
                 "NumberOfCells=\"0\">&lol2;</Piece></UnstructuredGrid></VTKFile>\n",
                 "XML bomb");
    /* truncated base64 */
    {
        const char *p = write_vtu("trunc.vtu", "inline");
        size_t n = 0;
        unsigned char *d = vt_read_file(p, &n);
        /* the last 12 characters of the first array's base64 text removed */
        char *pos = strstr((char *)d, "\n</DataArray>");
        memmove(pos - 12, pos, n - (size_t)(pos - (char *)d));
        n -= 12;
        vt_write_file(p, d, n);
        free(d);
        vv_grid *g = NULL;
        vt_err(vv_grid_load(&g, p));
        printf("  trunc.vtu: %s\n", vv_error_message());
        assert_non_null(strstr(vv_error_message(), "base64"));
    }
    /* not well-formed XML */
    expect_error("broken.vtu", "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece",
                 "XML");
    /* binary junk in a DX attribute stays out of the message */
    expect_error("junk.dx",
                 "object 1 class array type float rank 1 shape 3 items 4 data follows\n"
                 "0 0 0 1 0 0 0 1 0 0 0 1\n"
                 "object 2 class array type int rank 1 shape 4 items 1 data follows\n"
                 "0 1 2 3\n"
                 "attribute \"element type\" string \"tetra\x99\x01hedra\"\n"
                 "object \"s\" class field\n"
                 "component \"positions\" value 1\n"
                 "component \"connections\" value 2\n"
                 "end\n",
                 "tetra??hedra");
    /* DX connections to missing positions */
    expect_error("bad.dx",
                 "object 1 class array type float rank 1 shape 3 items 2 data follows\n"
                 "0 0 0 1 0 0\n"
                 "object 2 class array type int rank 1 shape 4 items 1 data follows\n"
                 "0 1 2 3\n"
                 "attribute \"element type\" string \"tetrahedra\"\n"
                 "object \"s\" class field\n"
                 "component \"positions\" value 1\n"
                 "component \"connections\" value 2\n"
                 "end\n",
                 "position");
}

/* A grid object in a scene file: loaded, saved, loaded back the same;
 * a bad field is an error with the scene position. */
static void
test_scene_grid_object(void **state) {
    (void)state;
    const char *dir = vt_outdir("grid_readers");
    write_text("scene_two.vtk", two_tets_vtk);
    const char *scene = "{\"objects\": [{\"type\": \"grid\", \"file\": \"scene_two.vtk\", "
                        "\"field\": \"c\", \"mode\": \"mip\", \"position\": [1, 2, 3],\n"
                        "\"cut_planes\": [{\"point\": [0, 0, 0.5], \"normal\": [0, 0, 1]}]}],\n"
                        "\"render\": {\"renderer\": \"irregular\"}}\n";
    const char *sp = write_text("grid_scene.json", scene);
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, sp));
    assert_int_equal(w->n_objects, 1);
    vv_object *o = w->objects[0];
    assert_int_equal(o->type, VV_OBJECT_GRID);
    assert_string_equal(o->field, "c");
    assert_int_equal(o->mode, VV_MODE_MIP);
    assert_int_equal(o->n_cut_planes, 1);
    assert_int_equal(vv_object_grid_field(o), 1);
    const char *sp2 = vt_path(dir, "grid_scene_saved.json");
    vt_ok(vv_scene_save(w, sp2, NULL));
    vv_world *w2 = NULL;
    vt_ok(vv_scene_load(&w2, sp2));
    assert_int_equal(w2->objects[0]->type, VV_OBJECT_GRID);
    assert_string_equal(w2->objects[0]->field, "c");
    assert_int_equal(w2->objects[0]->mode, VV_MODE_MIP);
    assert_near(w2->objects[0]->position.z, 3, 1e-12);
    assert_int_equal(w2->objects[0]->tf.n_opacity, o->tf.n_opacity);
    /* the world box of the grid object follows its transform */
    vv_box b = vv_world_bounds(w2);
    assert_near(b.max.x, 2, 1e-12);
    vv_world_free(w2);
    vv_world_free(w);
    /* an unknown field */
    const char *bad =
        write_text("grid_scene_bad.json", "{\"objects\": [{\"type\": \"grid\", \"file\": "
                                          "\"scene_two.vtk\", \"field\": \"nope\"}]}\n");
    vt_err(vv_scene_load(&w, bad));
    printf("  grid_scene_bad.json: %s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "nope"));
}

/* A NetCDF variable whose dimensions have no coordinate variables. */
static void
test_netcdf_without_coordinates(void **state) {
    (void)state;
#ifdef HAVE_NETCDF_H
    const char *p = vt_path(vt_outdir("grid_readers"), "nocoords.nc");
    int nc, d[3], v;
    assert_int_equal(nc_create(p, NC_CLOBBER, &nc), NC_NOERR);
    nc_def_dim(nc, "z", 2, &d[0]);
    nc_def_dim(nc, "y", 3, &d[1]);
    nc_def_dim(nc, "x", 4, &d[2]);
    nc_def_var(nc, "T", NC_FLOAT, 3, d, &v);
    nc_enddef(nc);
    float vals[24] = {0};
    nc_put_var_float(nc, v, vals);
    nc_close(nc);
    vv_grid *g = NULL;
    vv_error_clear();
    vv_status s = vv_grid_load(&g, p);
    if (s == VV_ERR_UNSUPPORTED)
        vt_skip("the build has no NetCDF (libnetcdf-dev)");
    assert_true(s < 0);
    assert_null(g);
    printf("  nocoords.nc: %s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "no coordinate variable"));
#else
    vt_skip("the test program was built without NetCDF (libnetcdf-dev)");
#endif
}

/* The grid rows of the format table: complete records in the order of
 * vv_grid_format, and every shared grid file detected as its format
 * (volume files not). */
static void
test_format_table(void **state) {
    (void)state;
    int n = 0, k = 0;
    const vv_format_record *const *t = vv_format_table(&n);
    static const char *const names[] = {"vtk_grid", "vtu", "dx", "plot3d", "netcdf"};
    for (int i = 0; i < n; i++) {
        if (t[i]->holds != VV_DATA_GRID)
            continue;
        assert_true(k < VV_GRID_FORMAT_NETCDF);
        assert_int_equal(t[i]->version, VV_FORMAT_RECORD_VERSION);
        assert_string_equal(t[i]->name, names[k++]);
        assert_non_null(t[i]->title);
        assert_true(strlen(t[i]->doc) > 20);
        assert_non_null(t[i]->looks_like);
        assert_non_null(t[i]->read_grid);
    }
    assert_int_equal(k, VV_GRID_FORMAT_NETCDF);
    if (!have_data())
        vt_skip("../shared/data/grids is missing");
    static const struct {
        const char *file;
        vv_grid_format f;
    } files[] = {{"grids/hyper.dx", VV_GRID_FORMAT_DX},
                 {"grids/fire_ug.vtu", VV_GRID_FORMAT_VTU},
                 {"grids/bluntfinxyz.bin", VV_GRID_FORMAT_PLOT3D},
                 {"grids/combxyz.bin", VV_GRID_FORMAT_PLOT3D},
                 {"grids/blow.vtk", VV_GRID_FORMAT_VTK},
                 {"grids/levitus_climatology.cdf", VV_GRID_FORMAT_NETCDF}};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        vv_grid_format f = VV_GRID_FORMAT_AUTO;
        if (!vv_grid_file_detect(vt_data(files[i].file), &f) || f != files[i].f)
            fail_msg("%s detected as %d, expected %d", files[i].file, (int)f, (int)files[i].f);
    }
    vv_grid_format f = VV_GRID_FORMAT_VTK;
    assert_false(vv_grid_file_detect(vt_data("volumes/ironProt.vtk"), &f)); /* structured points */
    assert_int_equal(f, VV_GRID_FORMAT_AUTO);
    assert_false(vv_grid_file_detect(vt_data("volumes/nut.slc"), NULL));
    assert_false(vv_grid_file_detect(vt_data("grids"), NULL)); /* a folder */
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_format_table),
        cmocka_unit_test(test_hyper_dx),
        cmocka_unit_test(test_fire_vtu),
        cmocka_unit_test(test_blow_vtk),
        cmocka_unit_test(test_plot3d),
        cmocka_unit_test(test_levitus),
        cmocka_unit_test(test_vtk_ascii_binary),
        cmocka_unit_test(test_vtu_variants),
        cmocka_unit_test(test_dx_text),
        cmocka_unit_test(test_plot3d_variants),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_netcdf_without_coordinates),
        cmocka_unit_test(test_scene_grid_object),
    };
    return vt_run_tests(tests, NULL, NULL);
}
