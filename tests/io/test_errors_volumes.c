/*
 * Every refusal of our own volume parsers (issue "Our own parsers under
 * attack"): SLC (src/io/volume/slc.c), MetaImage (src/io/volume/mhd.c), VTK legacy
 * STRUCTURED_POINTS (src/io/volume/vtk_legacy.c), raw (src/io/volume/raw.c) and the
 * CLI's --raw description (cli_parse_raw, apps/volvis/options.c). Each
 * case is a hostile file written here, the status expected and a piece of
 * the message that names the field or the problem; every message must
 * also name the file and be one printable line, and nothing is returned.
 */
#include "testutil.h"

#include "io/io_internal.h"

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "volvis/sys/format.h"

/* A byte string and its length (the literals may hold NUL bytes). */
#define B(s) s, sizeof(s) - 1

static const char *
outdir(void) {
    return vt_outdir("errors_volumes");
}

typedef enum { RD_SLC, RD_MHD, RD_VTK } reader;

typedef struct vcase {
    const char *name; /* the file's name, also the case's label */
    reader rd;
    const char *data;
    size_t n;
    const char *aux_name; /* a second file beside it (MetaImage's data), or NULL */
    const char *aux;
    size_t aux_n;
    vv_status want;
    const char *needle;
} vcase;

#define SLC_HEAD(dims, sp, comp) "11111\n" dims " 8\n" sp "\n0 0 0 " comp "\n0 0 X"

static const vcase volume_cases[] = {
    /* ---- SLC ---- */
    {"long.slc", RD_SLC,
     B("11111 1111111111111111111111111111111111111111111111111111111111111111111"), NULL, NULL, 0,
     VV_ERR_FORMAT, "x size: token too long"},
    {"ctl.slc", RD_SLC, B("11111\n\x01 2 2 8"), NULL, NULL, 0, VV_ERR_FORMAT,
     "x size: unexpected byte 0x01"},
    {"hdr_short.slc", RD_SLC, B("11111\n2 2"), NULL, NULL, 0, VV_ERR_FORMAT,
     "z size: missing (truncated header)"},
    {"not_int.slc", RD_SLC, B("11111 2 2 abc 8"), NULL, NULL, 0, VV_ERR_FORMAT,
     "z size: expected an integer, got \"abc\""},
    {"magic.slc", RD_SLC, B("12345 2 2 2 8"), NULL, NULL, 0, VV_ERR_FORMAT, "not an SLC file"},
    {"zero.slc", RD_SLC, B("11111 0 2 2 8"), NULL, NULL, 0, VV_ERR_FORMAT, "bad size 0 x 2 x 2"},
    {"axis.slc", RD_SLC, B("11111 70000 2 2 8"), NULL, NULL, 0, VV_ERR_LIMIT,
     "over the limit of 65536 per axis"},
    {"voxels.slc", RD_SLC, B("11111 65536 65536 65536 8"), NULL, NULL, 0, VV_ERR_LIMIT,
     "over the limit"},
    {"bits.slc", RD_SLC, B("11111 2 2 2 16"), NULL, NULL, 0, VV_ERR_UNSUPPORTED,
     "16 bits per voxel"},
    {"sp_text.slc", RD_SLC, B("11111 2 2 2 8 1 x 1"), NULL, NULL, 0, VV_ERR_FORMAT,
     "y spacing: expected a number, got \"x\""},
    {"sp_zero.slc", RD_SLC, B("11111 2 2 2 8 1 0 1"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad voxel spacing"},
    {"sp_neg.slc", RD_SLC, B("11111 2 2 2 8 -1 1 1"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad voxel spacing"},
    {"sp_nan.slc", RD_SLC, B("11111 2 2 2 8 1 1 nan"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad voxel spacing"},
    {"sp_inf.slc", RD_SLC, B("11111 2 2 2 8 inf 1 1"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad voxel spacing"},
    {"comp.slc", RD_SLC, B("11111 2 2 2 8 1 1 1 0 0 0 2"), NULL, NULL, 0, VV_ERR_FORMAT,
     "unknown compression 2"},
    {"icon_neg.slc", RD_SLC, B("11111 2 2 2 8 1 1 1 0 0 0 0 -1 0 X"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad icon size -1 x 0"},
    {"icon_x.slc", RD_SLC, B("11111 2 2 2 8 1 1 1 0 0 0 0 0 0"), NULL, NULL, 0, VV_ERR_FORMAT,
     "icon: expected 'X'"},
    {"icon_short.slc", RD_SLC, B("11111 2 2 2 8 1 1 1 0 0 0 0 2 2 Xabc"), NULL, NULL, 0,
     VV_ERR_FORMAT, "icon of 2 x 2 is truncated"},
    {"data_short.slc", RD_SLC, B(SLC_HEAD("2 2 2", "1 1 1", "0") "abc"), NULL, NULL, 0,
     VV_ERR_FORMAT, "truncated data: 2 x 2 x 2 needs 8 bytes, the file has 3"},
    {"rle_short.slc", RD_SLC, B(SLC_HEAD("100 100 100", "1 1 1", "1") "4 X\x02\x01\x00\x00"), NULL,
     NULL, 0, VV_ERR_FORMAT, "cannot be run-length coded"},
    {"rle_neg.slc", RD_SLC, B(SLC_HEAD("2 2 1", "1 1 1", "1") "-1 X\x00"), NULL, NULL, 0,
     VV_ERR_FORMAT, "slice 0: compressed size -1 is negative or past the end"},
    {"rle_past.slc", RD_SLC, B(SLC_HEAD("2 2 1", "1 1 1", "1") "9 X\x00"), NULL, NULL, 0,
     VV_ERR_FORMAT, "slice 0: compressed size 9 is negative or past the end"},
    {"rle_x.slc", RD_SLC, B(SLC_HEAD("2 2 1", "1 1 1", "1") "3 Y\x00"), NULL, NULL, 0,
     VV_ERR_FORMAT, "slice 0: size: expected 'X'"},
    {"rle_size.slc", RD_SLC, B(SLC_HEAD("2 2 1", "1 1 1", "1") "\x7f\x00"), NULL, NULL, 0,
     VV_ERR_FORMAT, "slice 0: size: unexpected byte 0x7f"},
    {"rle_run.slc", RD_SLC, B(SLC_HEAD("2 2 1", "1 1 1", "1") "3 X\x05\x07\x00"), NULL, NULL, 0,
     VV_ERR_FORMAT, "slice 0: run of 5 bytes overflows the slice (5 > 4)"},
    {"rle_literal.slc", RD_SLC, B(SLC_HEAD("2 2 1", "1 1 1", "1") "2 X\x83\x01"), NULL, NULL, 0,
     VV_ERR_FORMAT, "slice 0: literal run of 3 bytes at offset 0 passes the end"},
    {"rle_repeat.slc", RD_SLC, B(SLC_HEAD("2 2 1", "1 1 1", "1") "1 X\x02"), NULL, NULL, 0,
     VV_ERR_FORMAT, "slice 0: repeat run at offset 0 has no value byte"},

    /* ---- MetaImage ---- */
    {"binary.mha", RD_MHD, B("NDims = 3\n\x1b[31m = 1\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "line 2: binary data in the header (byte 0x1b)"},
    {"nokey.mha", RD_MHD, B("NDims = 3\njust words\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "line 2: expected \"Key = Value\""},
    {"empty.mha", RD_MHD, B(""), NULL, NULL, 0, VV_ERR_FORMAT, "empty file"},
    {"nodata.mha", RD_MHD, B("NDims = 3\nDimSize = 2 2 2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "no ElementDataFile"},
    {"object.mha", RD_MHD, B("ObjectType = Mesh\n"), NULL, NULL, 0, VV_ERR_UNSUPPORTED,
     "ObjectType Mesh"},
    {"ndims.mha", RD_MHD, B("NDims = 4\n"), NULL, NULL, 0, VV_ERR_UNSUPPORTED, "NDims 4"},
    {"ndims_nan.mha", RD_MHD, B("NDims = nan\n"), NULL, NULL, 0, VV_ERR_UNSUPPORTED, "NDims nan"},
    {"dims_one.mha", RD_MHD, B("DimSize = 2\n"), NULL, NULL, 0, VV_ERR_FORMAT, "bad DimSize \"2\""},
    {"dims_zero.mha", RD_MHD, B("DimSize = 2 0 2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad DimSize \"2 0 2\""},
    {"dims_frac.mha", RD_MHD, B("DimSize = 2 1.5 2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad DimSize"},
    {"dims_nan.mha", RD_MHD, B("DimSize = 2 nan 2\n"), NULL, NULL, 0, VV_ERR_FORMAT, "bad DimSize"},
    {"dims_four.mha", RD_MHD, B("DimSize = 2 2 2 2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad DimSize"},
    {"dims_axis.mha", RD_MHD, B("DimSize = 2 70000 2\n"), NULL, NULL, 0, VV_ERR_LIMIT,
     "DimSize 2 70000 2 is over the limit"},
    {"type.mha", RD_MHD, B("ElementType = MET_LONG\n"), NULL, NULL, 0, VV_ERR_UNSUPPORTED,
     "ElementType MET_LONG"},
    {"sp_one.mha", RD_MHD, B("ElementSpacing = 1\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementSpacing \"1\""},
    {"sp_zero.mha", RD_MHD, B("ElementSpacing = 1 0 1\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementSpacing \"1 0 1\""},
    {"sp_neg.mha", RD_MHD, B("ElementSpacing = 1 1 -2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementSpacing"},
    {"sp_nan.mha", RD_MHD, B("ElementSpacing = 1 nan 1\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementSpacing"},
    {"sp_inf.mha", RD_MHD, B("ElementSize = inf 1 1\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementSize"},
    {"sp_text.mha", RD_MHD, B("ElementSpacing = 1 one 1\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementSpacing"},
    {"offset_one.mha", RD_MHD, B("Offset = 1\n"), NULL, NULL, 0, VV_ERR_FORMAT, "bad Offset \"1\""},
    {"offset_inf.mha", RD_MHD, B("Origin = 0 inf 0\n"), NULL, NULL, 0, VV_ERR_FORMAT, "bad Origin"},
    {"matrix_five.mha", RD_MHD, B("TransformMatrix = 1 0 0 0 1\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad TransformMatrix"},
    {"matrix_nan.mha", RD_MHD, B("Rotation = 1 0 0 nan\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad Rotation"},
    {"msb.mha", RD_MHD, B("BinaryDataByteOrderMSB = maybe\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad BinaryDataByteOrderMSB \"maybe\""},
    {"compressed.mha", RD_MHD, B("CompressedData = yes\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad CompressedData \"yes\""},
    {"csize.mha", RD_MHD, B("CompressedDataSize = -5\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad CompressedDataSize \"-5\""},
    {"hsize.mha", RD_MHD, B("HeaderSize = -2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad HeaderSize \"-2\""},
    {"hsize_frac.mha", RD_MHD, B("HeaderSize = 2.5\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad HeaderSize"},
    {"channels.mha", RD_MHD, B("ElementNumberOfChannels = 3\n"), NULL, NULL, 0, VV_ERR_UNSUPPORTED,
     "ElementNumberOfChannels 3"},
    {"bindata.mha", RD_MHD, B("BinaryData = perhaps\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad BinaryData \"perhaps\""},
    {"ascii.mha", RD_MHD, B("BinaryData = False\n"), NULL, NULL, 0, VV_ERR_UNSUPPORTED,
     "BinaryData = False"},
    {"edf_empty.mha", RD_MHD, B("ElementDataFile =\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "empty ElementDataFile"},
    {"no_dims.mha", RD_MHD, B("ElementType = MET_UCHAR\nElementDataFile = LOCAL\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "no DimSize"},
    {"no_type.mha", RD_MHD, B("DimSize = 2 2 2\nElementDataFile = LOCAL\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "no ElementType"},
    {"nd_mismatch.mha", RD_MHD,
     B("NDims = 3\nDimSize = 2 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n"), NULL, NULL,
     0, VV_ERR_FORMAT, "DimSize has 2 values for NDims 3"},
    {"budget.mha", RD_MHD,
     B("DimSize = 65536 65536 65536\nElementType = MET_DOUBLE\nElementDataFile = LOCAL\n"), NULL,
     NULL, 0, VV_ERR_LIMIT, "over the limit"},
    {"local_short.mha", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\nabc"), NULL, NULL, 0,
     VV_ERR_FORMAT, "truncated: expected 8 bytes"},
    {"tail_short.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_USHORT\nHeaderSize = -1\nElementDataFile = t.raw\n"),
     "t.raw", B("0123456789"), VV_ERR_FORMAT, "t.raw: 10 bytes, too small for 16 bytes"},
    {"abs.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = /etc/passwd\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "an absolute path"},
    {"dotdot.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = ../x.raw\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "'..' leaves the header's folder"},
    {"missing.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = nowhere.raw\n"), NULL, NULL, 0,
     VV_ERR_IO, "nowhere.raw"},
    {"pat_minmax.mhd", RD_MHD, B("ElementDataFile = s%d.raw 1\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "pattern \"s%d.raw 1\" needs min and max"},
    {"pat_two.mhd", RD_MHD, B("ElementDataFile = s%d%d.raw 1 2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementDataFile pattern \"s%d%d.raw\""},
    {"pat_s.mhd", RD_MHD, B("ElementDataFile = s%s.raw 1 2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementDataFile pattern \"s%s.raw\""},
    {"pat_hash.mhd", RD_MHD, B("ElementDataFile = s%#d.raw 1 2\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementDataFile pattern \"s%#d.raw\""},
    {"pat_width.mhd", RD_MHD, B("ElementDataFile = s%0999999999d.raw 1 2\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "field width over 64"},
    {"pat_big.mhd", RD_MHD, B("ElementDataFile = s%d.raw 1 2000000000\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "bad ElementDataFile range 1 2000000000 1"},
    {"pat_step.mhd", RD_MHD, B("ElementDataFile = s%d.raw 1 2 0\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "bad ElementDataFile range 1 2 0"},
    {"pat_many.mhd", RD_MHD, B("ElementDataFile = s%d.raw 0 100000\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "bad ElementDataFile range 0 100000 1"},
    {"pat_dotdot.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = ../s%d.raw 0 1\n"), NULL, NULL,
     0, VV_ERR_FORMAT, "'..' leaves the header's folder"},
    {"list_empty.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = "
       "LIST\n\n  \n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "ElementDataFile = LIST names no files"},
    {"list_binary.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LIST\na.raw\n\x7f\n"), NULL,
     NULL, 0, VV_ERR_FORMAT, "LIST: line 2: binary data in the header (byte 0x7f)"},
    {"list_abs.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LIST\n/dev/zero\n"), NULL, NULL,
     0, VV_ERR_FORMAT, "an absolute path"},
    {"list_split.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LIST\nl.raw\nl.raw\nl.raw\n"),
     "l.raw", B("0123456789"), VV_ERR_FORMAT, "8 bytes of data cannot be split over 3 files"},
    {"list_zlib.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nCompressedData = True\n"
       "ElementDataFile = LIST\nz.raw\nz.raw\n"),
     "z.raw", B("0123456789"), VV_ERR_UNSUPPORTED, "compressed data in a file list"},
    {"zlib_past.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nCompressedData = True\nHeaderSize = 100\n"
       "ElementDataFile = zp.raw\n"),
     "zp.raw", B("0123456789"), VV_ERR_FORMAT, "zp.raw: no compressed data"},
    {"zlib_csize.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nCompressedData = True\n"
       "CompressedDataSize = 11\nElementDataFile = zc.raw\n"),
     "zc.raw", B("0123456789"), VV_ERR_FORMAT, "CompressedDataSize 11 is past the end"},
    {"zlib_bomb.mhd", RD_MHD,
     B("DimSize = 1000 1000 100\nElementType = MET_UCHAR\nCompressedData = True\n"
       "ElementDataFile = zb.raw\n"),
     "zb.raw", B("0123456789"), VV_ERR_FORMAT,
     "10 bytes of compressed data cannot hold 100000000 bytes"},
    {"zlib_junk.mhd", RD_MHD,
     B("DimSize = 2 2 2\nElementType = MET_UCHAR\nCompressedData = True\n"
       "ElementDataFile = zj.raw\n"),
     "zj.raw", B("0123456789"), VV_ERR_FORMAT, "compressed data: "},

    /* ---- VTK legacy STRUCTURED_POINTS ---- */
    {"empty.vtk", RD_VTK, B(""), NULL, NULL, 0, VV_ERR_FORMAT, "empty file"},
    {"magic.vtk", RD_VTK, B("# vtk DataFil\n"), NULL, NULL, 0, VV_ERR_FORMAT,
     "not a VTK legacy file"},
    {"title.vtk", RD_VTK, B("# vtk DataFile Version 3.0"), NULL, NULL, 0, VV_ERR_FORMAT,
     "no title line"},
    {"fmt_missing.vtk", RD_VTK, B("# vtk DataFile Version 3.0\ntitle\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "no ASCII/BINARY line"},
    {"fmt_ctl.vtk", RD_VTK, B("# vtk DataFile Version 3.0\ntitle\nAS\x01II\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "ASCII/BINARY line: unexpected byte 0x01"},
    {"fmt_word.vtk", RD_VTK, B("# vtk DataFile Version 3.0\ntitle\nHEX\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "third line is \"HEX\""},
    {"token.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET "
       "AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"
       "AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"
       "AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"
       "\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "token too long"},
    {"truncated.vtk", RD_VTK, B("# vtk DataFile Version 3.0\nt\nASCII\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "POINT_DATA: missing (truncated header)"},
    {"dataset.vtk", RD_VTK, B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n"), NULL,
     NULL, 0, VV_ERR_UNSUPPORTED, "DATASET POLYDATA is not supported"},
    {"dims_text.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 x 2\n"), NULL,
     NULL, 0, VV_ERR_FORMAT, "DIMENSIONS: expected an integer, got \"x\""},
    {"sp_text.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nSPACING 1 one 1\n"), NULL,
     NULL, 0, VV_ERR_FORMAT, "SPACING: expected a number, got \"one\""},
    {"sp_inf.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nSPACING 1 inf 1\n"), NULL,
     NULL, 0, VV_ERR_FORMAT, "SPACING: expected a number, got \"inf\""},
    {"sp_nan.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nSPACING nan 1 1\n"), NULL,
     NULL, 0, VV_ERR_FORMAT, "SPACING: expected a number, got \"nan\""},
    {"sp_zero.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nSPACING 1 0 1\n"), NULL,
     NULL, 0, VV_ERR_FORMAT, "bad SPACING 1 0 1"},
    {"sp_neg.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nASPECT_RATIO 1 1 -1\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "bad SPACING 1 1 -1"},
    {"origin.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nORIGIN 0 0 1e999\n"), NULL,
     NULL, 0, VV_ERR_FORMAT, "ORIGIN: expected a number"},
    {"cell_data.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nCELL_DATA 1\n"), NULL,
     NULL, 0, VV_ERR_UNSUPPORTED, "CELL_DATA before POINT_DATA is not supported"},
    {"keyword.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nCOLOR 1\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "unexpected keyword \"COLOR\""},
    {"no_dataset.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDIMENSIONS 2 2 2\nPOINT_DATA 8\n"), NULL, NULL, 0,
     VV_ERR_FORMAT, "no DATASET line"},
    {"no_dims.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nPOINT_DATA 8\n"), NULL,
     NULL, 0, VV_ERR_FORMAT, "no DIMENSIONS"},
    {"dims_zero.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 0 2\n"
       "POINT_DATA 0\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "bad DIMENSIONS 2 0 2"},
    {"dims_axis.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 70000 2\n"
       "POINT_DATA 280000\n"),
     NULL, NULL, 0, VV_ERR_LIMIT, "over the limit of 65536 per axis"},
    {"npoints.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 9\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "POINT_DATA 9 does not match DIMENSIONS (8)"},
    {"vectors.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nVECTORS v float\n"),
     NULL, NULL, 0, VV_ERR_UNSUPPORTED, "point data \"VECTORS\" is not supported"},
    {"scalars_short.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS"),
     NULL, NULL, 0, VV_ERR_FORMAT, "SCALARS: truncated"},
    {"scalars_type.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "SCALARS: expected a name and a type"},
    {"scalars_long.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s long\n"),
     NULL, NULL, 0, VV_ERR_UNSUPPORTED, "scalar type long is not supported"},
    {"ncomp.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s float 5\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "SCALARS with 5 components"},
    {"budget.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nBINARY\nDATASET STRUCTURED_POINTS\n"
       "DIMENSIONS 65536 65536 65536\nPOINT_DATA 281474976710656\nSCALARS s double\n"),
     NULL, NULL, 0, VV_ERR_LIMIT, "over the limit"},
    {"lut_short.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s float\nLOOKUP_TABLE"),
     NULL, NULL, 0, VV_ERR_FORMAT, "LOOKUP_TABLE: truncated"},
    {"lut_ctl.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s float\n\x02"),
     NULL, NULL, 0, VV_ERR_FORMAT, "unexpected byte 0x02"},
    {"bin_short.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s short\nLOOKUP_TABLE default\n0123456789"),
     NULL, NULL, 0, VV_ERR_FORMAT, "truncated data: 8 i16 values need 16 bytes"},
    {"ascii_short.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s float\n1 2 3"),
     NULL, NULL, 0, VV_ERR_FORMAT, "truncated data: 8 f32 values need at least 15 bytes"},
    {"ascii_spaces.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s float\n1 2 3                        \n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "truncated data: 3 of 8 values"},
    {"ascii_ctl.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s float\n1 2 3 \x1b[2J 5 6 7 8\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "value 3: unexpected byte 0x1b"},
    {"ascii_word.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s float\n1 2 3 four 5 6 7 8\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "value 3: expected a number, got \"four\""},
    {"ascii_range.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s unsigned_char\n1 2 3 256 5 6 7 8\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "value 3: \"256\" is not a valid u8"},
    {"ascii_frac.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s short\n1 2 3 4.5 5 6 7 8\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "value 3: \"4.5\" is not a valid i16"},
    {"ascii_float.vtk", RD_VTK,
     B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
       "POINT_DATA 8\nSCALARS s float\n1 2 3 1e39 5 6 7 8\n"),
     NULL, NULL, 0, VV_ERR_FORMAT, "value 3: \"1e39\" is out of float range"},
};

static vv_status
read_case(const vcase *c, const char *path, vv_volume **v) {
    switch (c->rd) {
    case RD_SLC:
        return vv_slc_read(v, path);
    case RD_MHD:
        return vv_mhd_read(v, path);
    case RD_VTK:
        return vv_vtk_read(v, path);
    }
    return VV_ERR_INVALID;
}

static void
test_volume_table(void **state) {
    (void)state;
    const char *dir = outdir();
    for (size_t i = 0; i < sizeof volume_cases / sizeof volume_cases[0]; i++) {
        const vcase *c = &volume_cases[i];
        const char *path = vt_path(dir, c->name);
        vt_write_file(path, c->data, c->n);
        if (c->aux_name)
            vt_write_file(vt_path(dir, c->aux_name), c->aux, c->aux_n);
        vv_volume *v = (vv_volume *)1;
        vv_status s = read_case(c, path, &v);
        vt_expect_refusal(c->name, s, c->want, c->needle, c->name);
        assert_null(v);
        /* and through the loader, which detects the format itself */
        vv_volume *w = NULL;
        vv_status s2 = vv_volume_load(&w, path, NULL);
        if (s2 == VV_OK)
            fail_msg("%s: vv_volume_load read it", c->name);
        assert_null(w);
    }
}

/* Paths that are not a file: missing, a folder, NULL arguments. */
static void
test_not_files(void **state) {
    (void)state;
    const char *dir = outdir();
    char sub[512];
    snprintf(sub, sizeof sub, "%s/folder.mha", dir);
    mkdir(sub, 0755);
    vv_volume *v = NULL;
    vt_expect_refusal("slc missing", vv_slc_read(&v, vt_path(dir, "nothing.slc")), VV_ERR_IO,
                      "cannot open", "nothing.slc");
    vt_expect_refusal("slc folder", vv_slc_read(&v, sub), VV_ERR_IO, "not a regular file",
                      "folder.mha");
    vt_expect_refusal("mhd missing", vv_mhd_read(&v, vt_path(dir, "nothing.mha")), VV_ERR_IO,
                      "cannot open", "nothing.mha");
    vt_expect_refusal("mhd folder", vv_mhd_read(&v, sub), VV_ERR_IO, "read error", "folder.mha");
    vt_expect_refusal("vtk folder", vv_vtk_read(&v, sub), VV_ERR_IO, "not a regular file",
                      "folder.mha");
    vv_raw_params p;
    vv_raw_params_init(&p);
    p.dims[0] = p.dims[1] = p.dims[2] = 2;
    vt_expect_refusal("raw missing", vv_raw_read(&v, vt_path(dir, "nothing.raw"), &p), VV_ERR_IO,
                      "cannot open", "nothing.raw");
    vt_expect_refusal("raw folder", vv_raw_read(&v, sub, &p), VV_ERR_IO, "not a regular file",
                      "folder.mha");
    assert_null(v);
    vt_expect_refusal("slc NULL", vv_slc_read(NULL, "x.slc"), VV_ERR_INVALID, "slc: NULL", NULL);
    vt_expect_refusal("mhd NULL", vv_mhd_read(&v, NULL), VV_ERR_INVALID, "mhd: NULL", NULL);
    vt_expect_refusal("vtk NULL", vv_vtk_read(NULL, "x.vtk"), VV_ERR_INVALID, "vtk: NULL", NULL);
    vt_expect_refusal("raw NULL", vv_raw_read(&v, "x.raw", NULL), VV_ERR_INVALID, "raw: NULL",
                      NULL);
}

/* A MetaImage LIST of more files than the reader takes. */
static void
test_mhd_long_list(void **state) {
    (void)state;
    const char *path = vt_path(outdir(), "long_list.mhd");
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LIST\n", f);
    for (int i = 0; i <= 65536; i++)
        fputs("a.raw\n", f);
    assert_int_equal(fclose(f), 0);
    vv_volume *v = NULL;
    vt_expect_refusal("long list", vv_mhd_read(&v, path), VV_ERR_LIMIT,
                      "more than 65536 files in the LIST", "long_list.mhd");
    assert_null(v);
    /* the names count against the memory budget: 1000 names of 2000
       characters under a 1 MiB budget */
    f = fopen(path, "wb");
    assert_non_null(f);
    fputs("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LIST\n", f);
    char name[2001];
    memset(name, 'n', 2000);
    name[2000] = '\0';
    for (int i = 0; i < 1000; i++)
        fprintf(f, "%s\n", name);
    assert_int_equal(fclose(f), 0);
    const uint64_t budget = vv_memory_budget_get();
    vv_memory_budget_set((uint64_t)1 << 20);
    vv_status s = vv_mhd_read(&v, path);
    vv_memory_budget_set(budget);
    vt_expect_refusal("list over the budget", s, VV_ERR_LIMIT, "the LIST's file names",
                      "long_list.mhd");
    assert_null(v);
}

/* A header line longer than the reader's line buffer. */
static void
test_mhd_long_line(void **state) {
    (void)state;
    char text[6000];
    memset(text, 'a', sizeof text);
    memcpy(text, "Comment = ", 10);
    text[sizeof text - 1] = '\n';
    const char *path = vt_path(outdir(), "long_line.mha");
    vt_write_file(path, text, sizeof text);
    vv_volume *v = NULL;
    vt_expect_refusal("long line", vv_mhd_read(&v, path), VV_ERR_FORMAT, "line 1: too long",
                      "long_line.mha");
    assert_null(v);
}

/* A zlib stream that ends before the voxels do. */
static void
test_mhd_zlib_short(void **state) {
    (void)state;
    const char *dir = outdir();
    unsigned char raw[4] = {1, 2, 3, 4}, z[64];
    uLongf zn = sizeof z;
    assert_int_equal(compress2(z, &zn, raw, sizeof raw, 9), Z_OK);
    vt_write_file(vt_path(dir, "zs.raw"), z, zn);
    const char *path = vt_path(dir, "zlib_short.mhd");
    const char hdr[] = "DimSize = 2 2 2\nElementType = MET_UCHAR\nCompressedData = True\n"
                       "ElementDataFile = zs.raw\n";
    vt_write_file(path, hdr, sizeof hdr - 1);
    vv_volume *v = NULL;
    vt_expect_refusal("zlib short", vv_mhd_read(&v, path), VV_ERR_FORMAT,
                      "compressed data gives 4 bytes, expected 8", "zlib_short.mhd");
    assert_null(v);
}

/*
 * A second DimSize with fewer values kept the third size of the first: a
 * 2-D image became 2 x 2 x 3 and read three times its data.
 */
static void
test_mhd_dimsize_twice(void **state) {
    (void)state;
    const char *dir = outdir();
    const char hdr[] = "DimSize = 2 2 3\nDimSize = 2 2\nNDims = 2\nElementType = MET_UCHAR\n"
                       "ElementDataFile = d2.raw\n";
    const char *path = vt_path(dir, "dims_twice.mhd");
    vt_write_file(path, hdr, sizeof hdr - 1);
    vt_write_file(vt_path(dir, "d2.raw"), "abcdefghijkl", 12);
    vv_volume *v = NULL;
    vt_ok(vv_mhd_read(&v, path));
    assert_int_equal(v->dims[0], 2);
    assert_int_equal(v->dims[1], 2);
    assert_int_equal(v->dims[2], 1);
    vv_volume_free(v);
}

/* A channel past the SCALARS' components. */
static void
test_vtk_channel(void **state) {
    (void)state;
    const char text[] = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\n"
                        "DIMENSIONS 2 1 1\nPOINT_DATA 2\nSCALARS s float 2\n1 2 3 4\n";
    const char *path = vt_path(outdir(), "channel.vtk");
    vt_write_file(path, text, sizeof text - 1);
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = VV_FORMAT_VTK;
    o.channel = 2;
    vv_volume *v = NULL;
    vt_expect_refusal("channel", vv_volume_load(&v, path, &o), VV_ERR_INVALID,
                      "channel 2 asked, the file has 2", "channel.vtk");
    assert_null(v);
    o.channel = 1;
    vt_ok(vv_volume_load(&v, path, &o));
    assert_near(vv_volume_get(v, 1, 0, 0), 4.0, 0);
    vv_volume_free(v);
}

/* Raw descriptions the library refuses (the CLI's parser refuses most
 * before, see test_cli_raw). */
static void
test_raw_params(void **state) {
    (void)state;
    const char *path = vt_path(outdir(), "r.raw");
    vt_write_file(path, "0123456789abcdef", 16);
    static const struct {
        const char *label;
        int dims[3];
        int type;
        double sp[3], org[3];
        uint64_t skip;
        vv_status want;
        const char *needle;
    } cases[] = {
        {"type", {2, 2, 2}, 99, {1, 1, 1}, {0, 0, 0}, 0, VV_ERR_INVALID, "bad voxel type 99"},
        {"dims", {2, 0, 2}, VV_U8, {1, 1, 1}, {0, 0, 0}, 0, VV_ERR_INVALID, "bad size 2 x 0 x 2"},
        {"spacing 0",
         {2, 2, 2},
         VV_U8,
         {1, 0, 1},
         {0, 0, 0},
         0,
         VV_ERR_INVALID,
         "bad voxel spacing"},
        {"spacing nan",
         {2, 2, 2},
         VV_U8,
         {1, 1, NAN},
         {0, 0, 0},
         0,
         VV_ERR_INVALID,
         "bad voxel spacing"},
        {"spacing inf",
         {2, 2, 2},
         VV_U8,
         {INFINITY, 1, 1},
         {0, 0, 0},
         0,
         VV_ERR_INVALID,
         "bad voxel spacing"},
        {"spacing neg",
         {2, 2, 2},
         VV_U8,
         {1, -1, 1},
         {0, 0, 0},
         0,
         VV_ERR_INVALID,
         "bad voxel spacing"},
        {"origin", {2, 2, 2}, VV_U8, {1, 1, 1}, {0, NAN, 0}, 0, VV_ERR_INVALID, "bad origin"},
        {"axis", {70000, 1, 1}, VV_U8, {1, 1, 1}, {0, 0, 0}, 0, VV_ERR_LIMIT, "outside 1..65536"},
        {"budget",
         {65536, 65536, 65536},
         VV_F64,
         {1, 1, 1},
         {0, 0, 0},
         0,
         VV_ERR_LIMIT,
         "over the limit"},
        {"small",
         {2, 2, 4},
         VV_U16,
         {1, 1, 1},
         {0, 0, 0},
         0,
         VV_ERR_FORMAT,
         "file too small: 2 x 2 x 4 u16"},
        {"skip",
         {2, 2, 2},
         VV_U8,
         {1, 1, 1},
         {0, 0, 0},
         12,
         VV_ERR_FORMAT,
         "after a 12-byte header needs 20 bytes, the file has 16"},
        {"skip past",
         {1, 1, 1},
         VV_U8,
         {1, 1, 1},
         {0, 0, 0},
         UINT64_MAX,
         VV_ERR_FORMAT,
         "file too small"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        vv_raw_params p;
        vv_raw_params_init(&p);
        memcpy(p.dims, cases[i].dims, sizeof p.dims);
        p.type = (vv_voxel_type)cases[i].type;
        memcpy(p.spacing, cases[i].sp, sizeof p.spacing);
        memcpy(p.origin, cases[i].org, sizeof p.origin);
        p.header_skip = cases[i].skip;
        vv_volume *v = NULL;
        vt_expect_refusal(cases[i].label, vv_raw_read(&v, path, &p), cases[i].want, cases[i].needle,
                          "r.raw");
        assert_null(v);
    }
    /* the raw row's layout without a description */
    const vv_format_record *r = vv_format_record_of(VV_FORMAT_RAW);
    assert_non_null(r);
    assert_non_null(r->raw_layout);
    vv_load_options o;
    vv_load_options_init(&o);
    vv_volume *h = NULL;
    char *data = NULL;
    uint64_t off = 0;
    int big = 0;
    vt_expect_refusal("layout", r->raw_layout(path, &o, &h, &data, &off, &big), VV_ERR_INVALID,
                      "the dimensions and voxel type are needed", "r.raw");
    assert_null(h);
    assert_null(data);
}

/* The CLI's --raw description: each refusal is one usage line naming the
 * field. */
static void
test_cli_raw(void **state) {
    (void)state;
    const char *dir = outdir();
    const char *file = vt_path(dir, "cli.raw");
    vt_write_file(file, "01234567", 8);
    static const struct {
        const char *spec, *needle;
    } cases[] = {
        {"2x2", "expected dimensions WxHxD first, got '2x2'"},
        {"2x2x2x2:u8", "expected dimensions WxHxD first"},
        {"-2x2x2:u8", "expected dimensions WxHxD first"},
        {"0x2x2:u8", "each dimension must be 1..65536, got '0x2x2'"},
        {"2x70000x2:u8", "each dimension must be 1..65536"},
        {"2x2x99999999999999999999:u8", "expected dimensions WxHxD first"},
        {"2x2x2", "expected WxHxD:TYPE"},
        {"2x2x2:u7", "unknown voxel type in '2x2x2:u7'"},
        {"2x2x2:", "unknown voxel type"},
        {"2x2x2:aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa", "unknown voxel type"},
        {"2x2x2:u8:le:be", "byte order given twice"},
        {"2x2x2:u8:xyz", "cannot understand 'xyz' in '2x2x2:u8:xyz'"},
        {"2x2x2:u8:1x1x1:1x1x1", "cannot understand '1x1x1'"},
        {"2x2x2:u8:1x0x1", "voxel spacing must be > 0, got '1x0x1'"},
        {"2x2x2:u8:1x-1x1", "voxel spacing must be > 0"},
        {"2x2x2:u8:1x1x0x10", "cannot understand '1x1x0x10'"},
        {"2x2x2:u8:0x1p3x1x1", "cannot understand '0x1p3x1x1'"},
        {"2x2x2:u8:1xnanx1", "cannot understand '1xnanx1'"},
        {"2x2x2:u8:1xinfx1", "cannot understand '1xinfx1'"},
        {"2x2x2:u8:1x1e999x1", "cannot understand '1x1e999x1'"},
        {"2x2x2:u8:skip=abc", "cannot understand 'skip=abc'"},
        {"2x2x2:u8:skip=-1", "cannot understand 'skip=-1'"},
        {"2x2x2:u8:skip=99999999999999999999999", "cannot understand"},
        {"2x2x2:u8:skip=1:skip=2", "cannot understand 'skip=2'"},
        {"2x2x2:u8:skip=1111111111111111111111111111111111111", "cannot understand"},
        {"2x2x2:u8:skip=4", "file too small"},
        {"2x2x2:u16", "file too small: 2 x 2 x 2 u16"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *args[] = {"info", "--raw", cases[i].spec, file, NULL};
        vt_run_result r = vt_run_cli_v(dir, args);
        if (r.status == 0 || r.status >= 128)
            fail_msg("--raw %s: exit %d: %s", cases[i].spec, r.status, r.err);
        if (!strstr(r.err, cases[i].needle))
            fail_msg("--raw %s: '%s' lacks '%s'", cases[i].spec, r.err, cases[i].needle);
        /* one line on stderr, nothing on stdout */
        const char *nl = strchr(r.err, '\n');
        if (!nl || nl[1] != '\0')
            fail_msg("--raw %s: not one line: '%s'", cases[i].spec, r.err);
        assert_string_equal(r.out, "");
        vt_run_result_free(&r);
    }
}

/* Bytes the CLI prints: none of them control bytes or invalid UTF-8. */
static void
expect_clean(const char *label, const char *what, const char *text) {
    for (const unsigned char *p = (const unsigned char *)text; *p; p++)
        if ((*p < 0x20 && *p != '\n') || *p >= 0x7f)
            fail_msg("%s: %s has byte 0x%02x: '%s'", label, what, *p, text);
}

/* `volvis info` of hostile files: one clean line on stderr. */
static void
test_cli_hostile(void **state) {
    (void)state;
    const char *dir = outdir();
    static const struct {
        const char *name;
        const char *data;
        size_t n;
        const char *needle;
    } cases[] = {
        {"utf8.mha", B("ElementType = MET_\xff\xfe\xc3(\n"), "ElementType MET_\\xff\\xfe\\xc3("},
        {"esc.mha", B("ElementType = MET_UCHAR\x1b[2J\n"), "byte 0x1b"},
        {"utf8.vtk",
         B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\n"
           "DIMENSIONS 1 1 1\nPOINT_DATA 1\nSCALARS s \xe2\x28\xa1\n0\n"),
         "scalar type \\xe2(\\xa1 is not supported"},
        {"ctl.slc", B("11111 2 2 2 8 1 1 1 0 0 0 0 0 0 X\x1b[2J\x07"), "truncated data"},
        {"ctl_grid.vtk",
         B("# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n"
           "\x1b]0;title\x07 4\n"),
         "unexpected keyword"},
        {"ctl.dx", B("object 1 class array type \x1b[2J items 1\n"), "array 1: type ?[2J"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *path = vt_path(dir, cases[i].name);
        vt_write_file(path, cases[i].data, cases[i].n);
        const char *args[] = {"info", path, NULL};
        vt_run_result r = vt_run_cli_v(dir, args);
        if (r.status == 0 || r.status >= 128)
            fail_msg("%s: exit %d: %s", cases[i].name, r.status, r.err);
        if (!strstr(r.err, cases[i].needle) || !strstr(r.err, cases[i].name))
            fail_msg("%s: '%s' lacks '%s' or the file's name", cases[i].name, r.err,
                     cases[i].needle);
        const char *nl = strchr(r.err, '\n');
        if (!nl || nl[1] != '\0')
            fail_msg("%s: not one line: '%s'", cases[i].name, r.err);
        expect_clean(cases[i].name, "stderr", r.err);
        expect_clean(cases[i].name, "stdout", r.out);
        vt_run_result_free(&r);
    }
    /* the CLI's own usage errors quote the command line: an argument's
       escape sequence is printed as \xNN, not sent to the terminal */
    const char *args[] = {"info", "--raw", "\x1b[2Jx", vt_path(dir, "utf8.mha"), NULL};
    vt_run_result r = vt_run_cli_v(dir, args);
    assert_int_equal(r.status, 2);
    if (!strstr(r.err, "'\\x1b[2Jx'"))
        fail_msg("usage error: '%s'", r.err);
    expect_clean("--raw", "stderr", r.err);
    vt_run_result_free(&r);
}

/* The SLC writer's refusals. */
static void
test_slc_write(void **state) {
    (void)state;
    const char *dir = outdir();
    vt_expect_refusal("write NULL", vv_slc_write(NULL, vt_path(dir, "w.slc"), 1), VV_ERR_INVALID,
                      "slc: NULL", NULL);
    const int dims[3] = {8, 8, 8};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    vt_expect_refusal("write folder", vv_slc_write(v, vt_path(dir, "no/such/folder/w.slc"), 1),
                      VV_ERR_IO, NULL, "w.slc");
    /* the name taken by a folder: the file is written, then cannot be named */
    char taken[512];
    snprintf(taken, sizeof taken, "%s/taken.slc", dir);
    mkdir(taken, 0755);
    vt_write_file(vt_path(taken, "keep"), "x", 1);
    vt_expect_refusal("write over a folder", vv_slc_write(v, taken, 1), VV_ERR_IO, NULL,
                      "taken.slc");
    struct stat st;
    assert_int_equal(stat(taken, &st), 0);
    assert_true(S_ISDIR(st.st_mode));
    /* a write that fails (a file size limit, as a full disk would):
       refused, and no file left behind */
    const int big[3] = {64, 64, 64};
    vv_volume *b = NULL;
    vt_ok(vv_volume_new(&b, big, VV_U8));
    struct rlimit old_limit, limit;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
    limit = old_limit;
    limit.rlim_cur = 4096;
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &limit), 0);
    const char *full = vt_path(dir, "full.slc");
    unlink(full);
    vv_status sf = vv_slc_write(b, full, 0);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old_limit), 0);
    signal(SIGXFSZ, old_handler);
    vt_expect_refusal("write error", sf, VV_ERR_IO, "write error", "full.slc");
    assert_int_not_equal(access(full, F_OK), 0);
    vv_volume_free(b);
    vv_volume *u = NULL;
    vt_ok(vv_volume_new(&u, dims, VV_U16));
    vt_expect_refusal("write u16", vv_slc_write(u, vt_path(dir, "w16.slc"), 1), VV_ERR_UNSUPPORTED,
                      "SLC holds 8-bit voxels only", "w16.slc");
    /* under a budget smaller than the volume: refused before writing */
    const uint64_t budget = vv_memory_budget_get();
    vv_memory_budget_set(100);
    vv_status s = vv_slc_write(v, vt_path(dir, "wb.slc"), 1);
    vv_memory_budget_set(budget);
    vt_expect_refusal("write budget", s, VV_ERR_LIMIT, "over the memory budget", "wb.slc");
    /* a u16 volume is rescaled to 8 bits first: that copy is refused */
    vv_memory_budget_set(100);
    s = vv_volume_save(u, vt_path(dir, "wb16.slc"), VV_FORMAT_SLC, 0);
    vv_memory_budget_set(budget);
    vt_expect_refusal("write budget u16", s, VV_ERR_LIMIT, "over the memory budget", "wb16.slc");
    vv_volume_free(u);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_volume_table),   cmocka_unit_test(test_not_files),
        cmocka_unit_test(test_mhd_long_list),  cmocka_unit_test(test_mhd_long_line),
        cmocka_unit_test(test_mhd_zlib_short), cmocka_unit_test(test_mhd_dimsize_twice),
        cmocka_unit_test(test_vtk_channel),    cmocka_unit_test(test_raw_params),
        cmocka_unit_test(test_cli_raw),        cmocka_unit_test(test_cli_hostile),
        cmocka_unit_test(test_slc_write),
    };
    return vt_run_tests(tests, NULL, NULL);
}
