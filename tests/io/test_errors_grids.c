/*
 * Every refusal of our own grid parsers (issue "Our own parsers under
 * attack"): VTK legacy UNSTRUCTURED_GRID (src/io/grid/grid_vtk.c), OpenDX
 * (src/io/grid/grid_dx.c) and PLOT3D (src/io/grid/grid_plot3d.c). Each case is a
 * hostile file written here, the status expected and a piece of the
 * message that names the keyword or the problem; every message must also
 * name the file and be one printable line, and no grid is returned.
 */
#include "testutil.h"

#include "io/io_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* A byte string and its length (the literals may hold NUL bytes). */
#define B(s) s, sizeof(s) - 1

static const char *
outdir(void) {
    return vt_outdir("errors_grids");
}

typedef enum { RD_VTK, RD_DX } reader;

typedef struct gcase {
    const char *name; /* the file's name, also the case's label */
    reader rd;
    const char *data;
    size_t n;
    vv_status want;
    const char *needle;
} gcase;

#define VTK_HEAD "# vtk DataFile Version 3.0\ntitle\nASCII\nDATASET UNSTRUCTURED_GRID\n"
#define VTK_BIN_HEAD "# vtk DataFile Version 3.0\ntitle\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
#define VTK_PTS "POINTS 4 float\n0 0 0  1 0 0  0 1 0  0 0 1\n"
#define VTK_TET "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n"

/* positions (4), one tetrahedron, with the element type given after */
#define DX_POS                                                                                     \
    "object 1 class array type float rank 1 shape 3 items 4 data follows\n"                        \
    "0 0 0  1 0 0  0 1 0  0 0 1\n"
#define DX_CON(shape, cells)                                                                       \
    "object 2 class array type int rank 1 shape " shape " items 1 data follows\n" cells "\n"
#define DX_TET DX_CON("4", "0 1 2 3") "attribute \"element type\" string \"tetrahedra\"\n"
#define DX_FIELD                                                                                   \
    "object \"f\" class field\ncomponent \"positions\" value 1\n"                                  \
    "component \"connections\" value 2\n"

static const gcase grid_cases[] = {
    /* ---- VTK legacy UNSTRUCTURED_GRID ---- */
    {"magic.vtk", RD_VTK, B("# vtk DataFil"), VV_ERR_FORMAT, "not a VTK legacy file"},
    {"fmt.vtk", RD_VTK, B("# vtk DataFile Version 3.0\ntitle\nHEX\n"), VV_ERR_FORMAT,
     "expected ASCII or BINARY, got \"HEX\""},
    {"fmt_missing.vtk", RD_VTK, B("# vtk DataFile Version 3.0\ntitle\n"), VV_ERR_FORMAT,
     "ASCII or BINARY: missing"},
    {"dataset.vtk", RD_VTK, B("# vtk DataFile Version 3.0\ntitle\nASCII\nDATASET POLYDATA\n"),
     VV_ERR_FORMAT, "\"DATASET POLYDATA\" is not DATASET UNSTRUCTURED_GRID"},
    {"keyword.vtk", RD_VTK, B(VTK_HEAD "\x1b[2J 1\n"), VV_ERR_FORMAT,
     "unexpected keyword \"?[2J\""},
    {"nothing.vtk", RD_VTK, B(VTK_HEAD), VV_ERR_FORMAT, "POINTS missing"},
    {"no_cells.vtk", RD_VTK, B(VTK_HEAD VTK_PTS), VV_ERR_FORMAT, "CELLS missing"},
    {"no_types.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 2 3\n"), VV_ERR_FORMAT,
     "CELL_TYPES missing"},
    {"pts_count.vtk", RD_VTK, B(VTK_HEAD "POINTS -4 float\n"), VV_ERR_FORMAT,
     "POINTS count: expected a count, got \"-4\""},
    {"pts_limit.vtk", RD_VTK, B(VTK_HEAD "POINTS 999999999999 float\n"), VV_ERR_LIMIT,
     "POINTS count: 999999999999 is over the limit"},
    {"pts_type.vtk", RD_VTK, B(VTK_HEAD "POINTS 4 quaternion\n"), VV_ERR_FORMAT,
     "POINTS: unknown type \"quaternion\""},
    {"pts_left.vtk", RD_VTK, B(VTK_HEAD "POINTS 100000000 float\n0 0 0\n"), VV_ERR_FORMAT,
     "POINTS 100000000: the file has only"},
    {"pts_short.vtk", RD_VTK, B(VTK_HEAD "POINTS 4 float\n0 0 0  1 0 0  0 1 0  0 0\n"),
     VV_ERR_FORMAT, "POINTS: value 11 of 12 missing"},
    {"pts_word.vtk", RD_VTK, B(VTK_HEAD "POINTS 4 float\n0 0 0  1 0 0  0 one 0  0 0 1\n"),
     VV_ERR_FORMAT, "POINTS: value 7 is \"one\", not a number"},
    {"pts_bin.vtk", RD_VTK, B(VTK_BIN_HEAD "POINTS 4 float\n0123456789abc"), VV_ERR_FORMAT,
     "POINTS: 12 values of 4 bytes but only 13 bytes are left"},
    {"pts_twice.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS "CELLS 2 8\n3 0 1 2\n3 0 1 3\n" VTK_PTS "CELL_TYPES 2\n5\n5\n"),
     VV_ERR_FORMAT, "POINTS given twice"},
    {"cells_first.vtk", RD_VTK, B(VTK_HEAD VTK_TET VTK_PTS), VV_ERR_FORMAT, "CELLS before POINTS"},
    {"cells_twice.vtk", RD_VTK, B(VTK_HEAD VTK_PTS VTK_TET "CELLS 1 5\n4 0 1 2 3\n"), VV_ERR_FORMAT,
     "CELLS given twice"},
    {"cells_size.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 3 2\n4 0 1 2 3\n"), VV_ERR_FORMAT,
     "CELLS 3 2: inconsistent with the"},
    {"cells_left.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 50000\n4 0 1 2 3\n"), VV_ERR_FORMAT,
     "CELLS 1 50000: inconsistent with the"},
    {"cells_limit.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 99999999999\n"), VV_ERR_LIMIT,
     "CELLS size: 99999999999 is over the limit"},
    {"cells_count.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 2 10\n0 0 1 2 3\n4 0 1 2 3\n"),
     VV_ERR_FORMAT, "CELLS: cell 0 has 0 points"},
    {"cells_lie.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 2 10\n9 0 1 2 3\n4 0 1 2 3\n"),
     VV_ERR_FORMAT, "CELLS: cell 0 has 9 points"},
    {"cells_index.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 2 4\n"), VV_ERR_FORMAT,
     "CELLS: cell 0 uses point 4 but there are 4 points"},
    {"cells_negative.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 -2 3\n"), VV_ERR_FORMAT,
     "CELLS: cell 0 uses point -2"},
    {"point_nan.vtk", RD_VTK, B(VTK_HEAD "POINTS 4 float\n0 0 0  1 0 0  0 nan 0  0 0 1\n" VTK_TET),
     VV_ERR_FORMAT, "point 2 has a coordinate that is not finite"},
    {"point_inf.dx", RD_DX,
     B("object 1 class array type float rank 1 shape 3 items 4 data follows\n"
       "0 0 0\n1 0 0\n0 1 0\n0 0 inf\n"
       "object 2 class array type int rank 1 shape 4 items 1 data follows\n0 1 2 3\n"
       "attribute \"element type\" string \"tetrahedra\"\n"
       "object 3 class field\ncomponent \"positions\" value 1\n"
       "component \"connections\" value 2\n"),
     VV_ERR_FORMAT, "point 3 has a coordinate that is not finite"},
    {"cells_nan.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 nan 3\n"), VV_ERR_FORMAT,
     "CELLS: cell 0 uses point nan"},
    {"cells_slack.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 6\n4 0 1 2 3 3\n"), VV_ERR_FORMAT,
     "CELLS: size 6 disagrees with the cells"},
    {"off_none.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 0 0\nOFFSETS vtktypeint64\n"), VV_ERR_FORMAT,
     "CELLS: no offsets"},
    {"off_type.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 2 4\nOFFSETS quad\n"), VV_ERR_FORMAT,
     "OFFSETS: unknown type \"quad\""},
    {"off_left.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 2 40000\nOFFSETS vtktypeint64\n0 4\n"),
     VV_ERR_FORMAT, "CELLS 2 40000: more than the"},
    {"off_order.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS "CELLS 3 4\nOFFSETS vtktypeint64\n0 4 2\n"
                        "CONNECTIVITY vtktypeint64\n0 1 2 3\n"),
     VV_ERR_FORMAT, "OFFSETS[2] = 2 out of order or past 4"},
    {"off_start.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS "CELLS 2 4\nOFFSETS vtktypeint64\n1 4\nCONNECTIVITY vtktypeint64\n"
                        "0 1 2 3\n"),
     VV_ERR_FORMAT, "OFFSETS[0] = 1 out of order"},
    {"off_end.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS "CELLS 2 4\nOFFSETS vtktypeint64\n0 3\nCONNECTIVITY vtktypeint64\n"
                        "0 1 2 3\n"),
     VV_ERR_FORMAT, "OFFSETS end at 3, not 4"},
    {"conn_kw.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS "CELLS 2 4\nOFFSETS vtktypeint64\n0 4\nINDICES vtktypeint64\n"
                        "0 1 2 3\n"),
     VV_ERR_FORMAT, "expected CONNECTIVITY <type>, got \"INDICES vtktypeint64\""},
    {"conn_type.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS "CELLS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY huge\n0 1 2 3\n"),
     VV_ERR_FORMAT, "expected CONNECTIVITY <type>, got \"CONNECTIVITY huge\""},
    {"conn_index.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS "CELLS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n"
                        "0 1 2 7\n"),
     VV_ERR_FORMAT, "CONNECTIVITY[3] uses point 7 but there are 4 points"},
    {"types_first.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELL_TYPES 1\n10\n"), VV_ERR_FORMAT,
     "CELL_TYPES 1 without CELLS of as many"},
    {"types_count.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 2\n10 10\n"),
     VV_ERR_FORMAT, "CELL_TYPES 2 without CELLS of as many"},
    {"types_short.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n"),
     VV_ERR_FORMAT, "CELL_TYPES: value 0 of 1 missing"},
    {"types_unknown.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n99\n"),
     VV_ERR_FORMAT, "cell 0: unsupported cell type 99"},
    {"types_huge.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n1e300\n"),
     VV_ERR_FORMAT, "cell 0: unsupported cell type 255"},
    {"types_mismatch.vtk", RD_VTK, B(VTK_HEAD VTK_PTS "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n12\n"),
     VV_ERR_FORMAT, "cell 0: a hexahedron has 8 points, not 4"},
    {"section_count.vtk", RD_VTK, B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 5\n"), VV_ERR_FORMAT,
     "POINT_DATA 5 but the grid has 4"},
    {"cell_count.vtk", RD_VTK, B(VTK_HEAD VTK_PTS VTK_TET "CELL_DATA 2\n"), VV_ERR_FORMAT,
     "CELL_DATA 2 but the grid has 1"},
    {"scalars_outside.vtk", RD_VTK, B(VTK_HEAD VTK_PTS VTK_TET "SCALARS s float\n1 2 3 4\n"),
     VV_ERR_FORMAT, "SCALARS outside POINT_DATA / CELL_DATA"},
    {"scalars_type.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nSCALARS s complex\n1 2 3 4\n"), VV_ERR_FORMAT,
     "SCALARS s: unknown type \"complex\""},
    {"scalars_ncomp.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nSCALARS s float 7\n1 2 3 4\n"), VV_ERR_FORMAT,
     "SCALARS s: 7 components"},
    {"scalars_ncomp_wrap.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nSCALARS s float 4294967297\n1 2 3 4\n"),
     VV_ERR_FORMAT, "SCALARS s: 4294967297 components"},
    {"scalars_ncomp_junk.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nSCALARS s float 1x\n1 2 3 4\n"), VV_ERR_FORMAT,
     "SCALARS s: 1x components"},
    {"scalars_short.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nSCALARS s float\nLOOKUP_TABLE default\n1 2 3\n"),
     VV_ERR_FORMAT, "s: value 3 of 4 missing"},
    {"scalars_noname.vtk", RD_VTK, B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nSCALARS"),
     VV_ERR_FORMAT, "field name: missing"},
    {"vectors_short.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "CELL_DATA 1\nVECTORS v double\n1 2\n"), VV_ERR_FORMAT,
     "v: value 2 of 3 missing"},
    {"field_array.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nFIELD fd 1\na 1 4 octonion\n1 2 3 4\n"),
     VV_ERR_FORMAT, "FIELD fd: bad array a"},
    {"field_ncomp.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nFIELD fd 1\na 0 4 float\n"), VV_ERR_FORMAT,
     "FIELD fd: bad array a"},
    {"field_comp_limit.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nFIELD fd 1\na 10 4 float\n"), VV_ERR_LIMIT,
     "components: 10 is over the limit of 9"},
    {"field_tuples.vtk", RD_VTK,
     B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nFIELD fd 1\na 1 3 float\n1 2 3\n"), VV_ERR_FORMAT,
     "FIELD array a: 3 tuples"},
    {"field_outside.vtk", RD_VTK, B(VTK_HEAD VTK_PTS VTK_TET "FIELD fd 1\na 1 4 float\n"),
     VV_ERR_FORMAT, "FIELD array a: 4 tuples"},
    {"field_many.vtk", RD_VTK, B(VTK_HEAD VTK_PTS VTK_TET "POINT_DATA 4\nFIELD fd 9999\n"),
     VV_ERR_LIMIT, "FIELD arrays: 9999 is over the limit"},
    {"lut_bin.vtk", RD_VTK, B(VTK_BIN_HEAD "LOOKUP_TABLE t 100\n0123456789"), VV_ERR_FORMAT,
     "LOOKUP_TABLE truncated"},
    {"lut_size.vtk", RD_VTK, B(VTK_HEAD "LOOKUP_TABLE t 99999999999\n"), VV_ERR_LIMIT,
     "table size: 99999999999 is over the limit"},

    /* ---- OpenDX ---- */
    {"noobj.dx", RD_DX, B("# nothing but a comment\n"), VV_ERR_FORMAT, "no field object"},
    {"noname.dx", RD_DX, B("object"), VV_ERR_FORMAT, "object without a name"},
    {"noclass.dx", RD_DX, B("object 1 class"), VV_ERR_FORMAT, "class name: missing"},
    {"type.dx", RD_DX, B("object 1 class array type quaternion items 4\n"), VV_ERR_FORMAT,
     "array 1: type quaternion"},
    {"shape0.dx", RD_DX, B("object 1 class array type float shape 0 items 4\n"), VV_ERR_FORMAT,
     "array 1: shape 0"},
    {"shape10.dx", RD_DX, B("object 1 class array type float shape 10 items 4\n"), VV_ERR_FORMAT,
     "array 1: shape 10"},
    {"shape_wrap.dx", RD_DX, B("object 1 class array type float shape 4294967299 items 4\n"),
     VV_ERR_FORMAT, "array 1: shape 4294967299"},
    {"shape_junk.dx", RD_DX, B("object 1 class array type float shape 3x items 4\n"), VV_ERR_FORMAT,
     "array 1: shape 3x"},
    {"rank.dx", RD_DX, B("object 1 class array type float rank one shape 3 items 4\n"),
     VV_ERR_FORMAT, "array 1: rank one"},
    {"items.dx", RD_DX, B("object 1 class array type float shape 3 items -4\n"), VV_ERR_FORMAT,
     "items: expected a count, got \"-4\""},
    {"items_limit.dx", RD_DX, B("object 1 class array type float shape 3 items 999999999999\n"),
     VV_ERR_LIMIT, "items: 999999999999 is over the limit"},
    {"file.dx", RD_DX, B("object 1 class array type float shape 3 items 4 data file x.bin,0\n"),
     VV_ERR_UNSUPPORTED, "array 1: data in another file"},
    {"offset.dx", RD_DX, B("object 1 class array type float shape 3 items 4 data -8\n"),
     VV_ERR_FORMAT, "array 1: data \"-8\""},
    {"offset_word.dx", RD_DX, B("object 1 class array type float shape 3 items 4 data here\n"),
     VV_ERR_FORMAT, "array 1: data \"here\""},
    {"bin_short.dx", RD_DX,
     B("object 1 class array type float shape 3 items 4 msb ieee data follows\n0123"),
     VV_ERR_FORMAT, "array 1 truncated"},
    {"no_end.dx", RD_DX,
     B("object 1 class array type float shape 3 items 4 msb ieee data 0\n" DX_TET DX_FIELD),
     VV_ERR_FORMAT, "array 1 refers to data but the file has no \"end\" line"},
    {"past_end.dx", RD_DX,
     B("object 1 class array type float shape 3 items 4 msb ieee data 4096\n" DX_TET DX_FIELD
       "end\n0123"),
     VV_ERR_FORMAT, "array 1: data offset 4096 is past the end"},
    {"bin_past.dx", RD_DX,
     B("object 1 class array type float shape 3 items 4 msb ieee data 0\n" DX_TET DX_FIELD
       "end\n0123"),
     VV_ERR_FORMAT, "array 1: 12 values cannot fit in the 4 bytes left"},
    {"by_name.dx", RD_DX,
     B(DX_POS DX_TET "object \"f\" class field\ncomponent \"positions\" value \"pos\"\n"),
     VV_ERR_UNSUPPORTED, "field f: component positions by name is not supported"},
    {"comp_value.dx", RD_DX, B(DX_POS DX_TET "object \"f\" class field\ncomponent \"positions\""),
     VV_ERR_FORMAT, "field f: component positions: no value"},
    {"no_grid.dx", RD_DX, B(DX_POS "object \"f\" class field\ncomponent \"positions\" value 1\n"),
     VV_ERR_FORMAT, "no field has positions and connections"},
    {"missing_array.dx", RD_DX,
     B(DX_POS "object \"f\" class field\ncomponent \"positions\" value 1\n"
              "component \"connections\" value 7\n"),
     VV_ERR_FORMAT, "field f refers to a missing array"},
    {"pos_shape.dx", RD_DX,
     B("object 1 class array type float rank 1 shape 2 items 4 data follows\n"
       "0 0  1 0  0 1  1 1\n" DX_TET DX_FIELD),
     VV_ERR_UNSUPPORTED, "positions of shape 2 (3 supported)"},
    {"element.dx", RD_DX,
     B(DX_POS DX_CON("2", "0 1") "attribute \"element type\" string \"lines\"\n" DX_FIELD),
     VV_ERR_UNSUPPORTED, "connections of element type \"lines\""},
    {"element_shape.dx", RD_DX,
     B(DX_POS DX_CON("3", "0 1 2") "attribute \"element type\" string \"tetrahedra\"\n" DX_FIELD),
     VV_ERR_FORMAT, "tetrahedra connections of shape 3"},
    {"con_index.dx", RD_DX,
     B(DX_POS DX_CON("4", "0 1 2 4") "attribute \"element type\" string \"tetrahedra\"\n" DX_FIELD),
     VV_ERR_FORMAT, "connection 0 uses position 4 but there are 4"},
    {"con_negative.dx", RD_DX,
     B(DX_POS DX_CON("4",
                     "0 -1 2 3") "attribute \"element type\" string \"tetrahedra\"\n" DX_FIELD),
     VV_ERR_FORMAT, "connection 0 uses position -1"},
    {"pos_short.dx", RD_DX,
     B("object 1 class array type float rank 1 shape 3 items 4 data follows\n0 0 0 1 0 0\n" DX_TET
           DX_FIELD),
     VV_ERR_FORMAT, "field f refers to a missing array"},
    {"pos_lie.dx", RD_DX,
     B("object 1 class array type float rank 1 shape 3 items 100000000 ascii data 0\n" DX_TET
           DX_FIELD "end\n0 0 0  1 0 0  0 1 0  0 0 1\n"),
     VV_ERR_FORMAT, "array 1: 300000000 values cannot fit in the 27 bytes left"},
    {"con_lie.dx", RD_DX,
     B(DX_POS "object 2 class array type int rank 1 shape 4 items 50000000 msb ieee data 0\n"
              "attribute \"element type\" string \"tetrahedra\"\n" DX_FIELD
              "end\n0123456789abcdef"),
     VV_ERR_FORMAT, "array 2: 200000000 values cannot fit in the 16 bytes left"},
    {"data_lie.dx", RD_DX,
     B(DX_POS DX_TET "object 3 class array type float rank 0 items 4 msb ieee data 0\n"
                     "attribute \"dep\" string \"positions\"\n" DX_FIELD
                     "component \"data\" value 3\nend\n0123"),
     VV_ERR_FORMAT, "array 3: 4 values cannot fit in the 4 bytes left"},
};

static vv_status
read_case(const gcase *c, const char *path, vv_grid **g) {
    switch (c->rd) {
    case RD_VTK:
        return vv_grid_read_vtk(g, path);
    case RD_DX:
        return vv_grid_read_dx(g, path);
    }
    return VV_ERR_INVALID;
}

static void
test_grid_table(void **state) {
    (void)state;
    const char *dir = outdir();
    for (size_t i = 0; i < sizeof grid_cases / sizeof grid_cases[0]; i++) {
        const gcase *c = &grid_cases[i];
        const char *path = vt_path(dir, c->name);
        vt_write_file(path, c->data, c->n);
        vv_grid *g = (vv_grid *)1;
        vv_status s = read_case(c, path, &g);
        vt_expect_refusal(c->name, s, c->want, c->needle, c->name);
        assert_null(g);
    }
}

/* The table's VTK and DX files, made valid, are read: the cases fail for
 * the reason they name. */
static void
test_grid_table_base(void **state) {
    (void)state;
    const char *dir = outdir();
    const char vtk[] = VTK_HEAD VTK_PTS VTK_TET
        "POINT_DATA 4\nSCALARS s float 1\nLOOKUP_TABLE default\n1 2 3 4\n"
        "FIELD fd 1\na 2 4 float\n1 2 3 4 5 6 7 8\nCELL_DATA 1\nVECTORS v double\n1 2 3\n"
        "LOOKUP_TABLE t 1\n0 0 0 1\n";
    const char dx[] = DX_POS DX_TET DX_FIELD "end\n";
    const char vtk51[] = VTK_HEAD VTK_PTS "CELLS 2 4\nOFFSETS vtktypeint64\n0 4\n"
                                          "CONNECTIVITY vtktypeint64\n0 1 2 3\nCELL_TYPES 1\n10\n";
    vv_grid *g = NULL;
    vt_write_file(vt_path(dir, "base.vtk"), vtk, sizeof vtk - 1);
    vt_ok(vv_grid_read_vtk(&g, vt_path(dir, "base.vtk")));
    assert_int_equal(g->n_points, 4);
    assert_int_equal(g->n_cells, 1);
    assert_int_equal(g->n_fields, 3);
    vv_grid_free(g);
    vt_write_file(vt_path(dir, "base51.vtk"), vtk51, sizeof vtk51 - 1);
    vt_ok(vv_grid_read_vtk(&g, vt_path(dir, "base51.vtk")));
    assert_int_equal(g->n_cells, 1);
    vv_grid_free(g);
    vt_write_file(vt_path(dir, "base.dx"), dx, sizeof dx - 1);
    vt_ok(vv_grid_read_dx(&g, vt_path(dir, "base.dx")));
    assert_int_equal(g->n_points, 4);
    assert_int_equal(g->n_cells, 1);
    vv_grid_free(g);
}

/* Asserts the message names @p path once: "p: p: No such file" said it twice. */
static void
expect_once(const char *path) {
    const char *msg = vv_error_message(), *first = strstr(msg, path);
    if (!first || strstr(first + 1, path))
        fail_msg("'%s' does not name '%s' once", msg, path);
}

/* Missing files: the readers name them, once. */
static void
test_grid_missing(void **state) {
    (void)state;
    const char *dir = outdir();
    vv_grid *g = NULL;
    vt_expect_refusal("vtk", vv_grid_read_vtk(&g, vt_path(dir, "none.vtk")), VV_ERR_IO, NULL,
                      "none.vtk");
    expect_once(vt_path(dir, "none.vtk"));
    vt_expect_refusal("dx", vv_grid_read_dx(&g, vt_path(dir, "none.dx")), VV_ERR_IO, NULL,
                      "none.dx");
    expect_once(vt_path(dir, "none.dx"));
    vt_expect_refusal("plot3d", vv_grid_read_plot3d(&g, vt_path(dir, "none.xyz"), NULL), VV_ERR_IO,
                      NULL, "none.xyz");
    expect_once(vt_path(dir, "none.xyz"));
    assert_null(g);
}

/* A grid file larger than the memory budget is refused before it is read
 * into memory (the readers hold the whole file). */
static void
test_grid_file_budget(void **state) {
    (void)state;
    const char *dir = outdir();
    static unsigned char big[8192];
    memset(big, ' ', sizeof big);
    const char *names[] = {"budget.vtk", "budget.dx", "budget.xyz"};
    for (int i = 0; i < 3; i++)
        vt_write_file(vt_path(dir, names[i]), big, sizeof big);
    const uint64_t budget = vv_memory_budget_get();
    vv_memory_budget_set(4096);
    vv_grid *g = NULL;
    vv_status s[3];
    char msg[3][512];
    s[0] = vv_grid_read_vtk(&g, vt_path(dir, names[0]));
    snprintf(msg[0], sizeof msg[0], "%s", vv_error_message());
    s[1] = vv_grid_read_dx(&g, vt_path(dir, names[1]));
    snprintf(msg[1], sizeof msg[1], "%s", vv_error_message());
    s[2] = vv_grid_read_plot3d(&g, vt_path(dir, names[2]), NULL);
    snprintf(msg[2], sizeof msg[2], "%s", vv_error_message());
    vv_memory_budget_set(budget);
    for (int i = 0; i < 3; i++) {
        if (s[i] != VV_ERR_LIMIT || !strstr(msg[i], "8193 bytes is over the memory budget") ||
            !strstr(msg[i], names[i]))
            fail_msg("%s: %s: %s", names[i], vv_status_name(s[i]), msg[i]);
    }
    assert_null(g);
}

/* More objects than the DX reader keeps. */
static void
test_dx_many_objects(void **state) {
    (void)state;
    const char *dir = outdir();
    static char text[64 * 300];
    size_t n = 0;
    for (int i = 0; i < 257; i++)
        n += (size_t)snprintf(text + n, sizeof text - n, "object %d class array items 0\n", i + 1);
    vt_write_file(vt_path(dir, "arrays.dx"), text, n);
    vv_grid *g = NULL;
    vt_expect_refusal("arrays", vv_grid_read_dx(&g, vt_path(dir, "arrays.dx")), VV_ERR_LIMIT,
                      "more than 256 arrays", "arrays.dx");
    n = 0;
    for (int i = 0; i < 257; i++)
        n += (size_t)snprintf(text + n, sizeof text - n, "object \"f%d\" class field\n", i);
    vt_write_file(vt_path(dir, "fields.dx"), text, n);
    vt_expect_refusal("fields", vv_grid_read_dx(&g, vt_path(dir, "fields.dx")), VV_ERR_LIMIT,
                      "more than 256 fields", "fields.dx");
    assert_null(g);
}

static double
now_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/*
 * "data follows" of 1.8 billion text values in a file of a few bytes: the
 * reader skipped them one token at a time past the end of the file, for
 * seconds, before the count was found to lie.
 */
static void
test_dx_follows_lie(void **state) {
    (void)state;
    const char text[] = "object 1 class array type float rank 1 shape 9 items 200000000 "
                        "data follows\n0 0 0\n";
    const char *path = vt_path(outdir(), "follows.dx");
    vt_write_file(path, text, sizeof text - 1);
    vv_grid *g = NULL;
    const double t0 = now_s();
    vt_expect_refusal("follows", vv_grid_read_dx(&g, path), VV_ERR_FORMAT, "no field object",
                      "follows.dx");
    const double dt = now_s() - t0;
    if (dt > 2.0)
        fail_msg("a lying count took %.1f s", dt);
}

static void
put32(unsigned char *p, uint32_t v) {
    memcpy(p, &v, 4); /* the host's order: the reader tries both */
}

/* A single-block PLOT3D grid (no record markers, floats): dims then x, y, z. */
static size_t
plot3d_grid(unsigned char *buf, const int dims[3]) {
    size_t o = 0;
    for (int a = 0; a < 3; a++, o += 4)
        put32(buf + o, (uint32_t)dims[a]);
    const size_t n = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
    for (size_t i = 0; i < 3 * n; i++, o += 4) {
        const float v = (float)(i % 7);
        memcpy(buf + o, &v, 4);
    }
    return o;
}

/* A single-block solution: dims, fsmach alpha re time, then 5 values a point. */
static size_t
plot3d_q(unsigned char *buf, const int dims[3]) {
    size_t o = 0;
    for (int a = 0; a < 3; a++, o += 4)
        put32(buf + o, (uint32_t)dims[a]);
    const size_t n = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
    for (size_t i = 0; i < 4 + 5 * n; i++, o += 4) {
        const float v = 1.0f;
        memcpy(buf + o, &v, 4);
    }
    return o;
}

static void
test_plot3d_errors(void **state) {
    (void)state;
    const char *dir = outdir();
    static unsigned char buf[1 << 16];
    vv_grid *g = NULL;

    /* a 2-D block */
    const int flat[3] = {3, 3, 1};
    vt_write_file(vt_path(dir, "flat.xyz"), buf, plot3d_grid(buf, flat));
    vt_expect_refusal("flat", vv_grid_read_plot3d(&g, vt_path(dir, "flat.xyz"), NULL),
                      VV_ERR_UNSUPPORTED, "block 0 is 3x3x1 (2-D blocks are not supported)",
                      "flat.xyz");

    /* no layout fits */
    vt_write_file(vt_path(dir, "odd.xyz"), "0123456789abcdefg", 17);
    vt_expect_refusal("odd", vv_grid_read_plot3d(&g, vt_path(dir, "odd.xyz"), NULL), VV_ERR_FORMAT,
                      "no PLOT3D layout", "odd.xyz");

    /* a solution missing, of other blocks, or of no layout */
    const int d2[3] = {2, 2, 2}, d3[3] = {2, 2, 3};
    vt_write_file(vt_path(dir, "g.xyz"), buf, plot3d_grid(buf, d2));
    vt_expect_refusal("q missing",
                      vv_grid_read_plot3d(&g, vt_path(dir, "g.xyz"), vt_path(dir, "none.q")),
                      VV_ERR_IO, NULL, "none.q");
    expect_once(vt_path(dir, "none.q"));
    vt_write_file(vt_path(dir, "other.q"), buf, plot3d_q(buf, d3));
    vt_expect_refusal("q other",
                      vv_grid_read_plot3d(&g, vt_path(dir, "g.xyz"), vt_path(dir, "other.q")),
                      VV_ERR_FORMAT, "the solution's blocks differ from the grid's", "other.q");
    vt_write_file(vt_path(dir, "odd.q"), "0123456789abcdefg", 17);
    vt_expect_refusal("q odd",
                      vv_grid_read_plot3d(&g, vt_path(dir, "g.xyz"), vt_path(dir, "odd.q")),
                      VV_ERR_FORMAT, "no PLOT3D layout", "odd.q");
    /* the same solution, of the grid's blocks, is read */
    vt_write_file(vt_path(dir, "g.q"), buf, plot3d_q(buf, d2));
    vt_ok(vv_grid_read_plot3d(&g, vt_path(dir, "g.xyz"), vt_path(dir, "g.q")));
    assert_int_equal(g->n_points, 8);
    vv_grid_free(g);
    g = NULL;

    /*
     * 2^20 x 2^20 x 2^20 points with IBLANK in single precision need
     * 16 * 2^60 bytes, which is 0 modulo 2^64: a 12-byte file of just the
     * dimensions "fit", and 2^60 bytes were asked for the blanking flags.
     */
    const int huge[3] = {1 << 20, 1 << 20, 1 << 20};
    size_t n = 0;
    for (int a = 0; a < 3; a++, n += 4)
        put32(buf + n, (uint32_t)huge[a]);
    vt_write_file(vt_path(dir, "wrap.xyz"), buf, n);
    vt_expect_refusal("wrap", vv_grid_read_plot3d(&g, vt_path(dir, "wrap.xyz"), NULL),
                      VV_ERR_FORMAT, "no PLOT3D layout", "wrap.xyz");
    assert_null(g);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_table),      cmocka_unit_test(test_grid_table_base),
        cmocka_unit_test(test_grid_missing),    cmocka_unit_test(test_grid_file_budget),
        cmocka_unit_test(test_dx_many_objects), cmocka_unit_test(test_dx_follows_lie),
        cmocka_unit_test(test_plot3d_errors),
    };
    return vt_run_tests(tests, NULL, NULL);
}
