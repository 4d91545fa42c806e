#!/usr/bin/env bash
# Seeds of fuzz_render (tests/fuzz/corpus/render/: a first line naming the
# format and the options, then the file), more .vvc seeds
# (tests/fuzz/corpus/vvc/: every format version, subcube side, voxel type
# and the corrections of --max-error), written by VolVis itself from small
# volumes made here, and raw files of several bricks and voxel types
# (tests/fuzz/corpus/raw/: a --raw description line, then the file), SLC
# wider and taller than its icon and VTK of two components a point. Every
# seed is a few KB at most. Run from the repository root; needs
# /usr/bin/python3 with NumPy and VolVis's CLI (VOLVIS, default
# build/release/volvis). Never deletes anything.
set -euo pipefail
cd "$(dirname "$0")/../.."
C=tests/fuzz/corpus
V=${VOLVIS:-build/release/volvis}
PY=/usr/bin/python3
mkdir -p $C/render $C/vvc $C/raw
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

# ---- small volumes: a blob in u8, i16, u16 and f32, and a 72x5x4 row and a 66x9x7 block (past one brick of 64: levels) -------
$PY - "$T" <<'PYEOF'
import sys, numpy as np
T = sys.argv[1]
def blob(nx, ny, nz):
    z, y, x = np.mgrid[0:nz, 0:ny, 0:nx].astype(float)
    r = np.sqrt(((x - nx / 2) / nx) ** 2 + ((y - ny / 2) / ny) ** 2 + ((z - nz / 2) / nz) ** 2)
    return np.clip(1.2 - 2 * r, 0, 1)
b = blob(9, 7, 6)
(b * 255).astype('u1').tofile(T + '/u8.raw')
(b * 3000 - 1000).astype('<i2').tofile(T + '/i16.raw')
(b * 60000).astype('<u2').tofile(T + '/u16.raw')
(b * 2.5 - 0.5).astype('<f4').tofile(T + '/f32.raw')
(blob(72, 5, 4) * 200).astype('u1').tofile(T + '/row.raw')
(blob(66, 9, 7) * 1000).astype('<i2').tofile(T + '/cube.raw')
z, y, x = np.mgrid[0:4, 0:5, 0:140]
((np.sin(x / 9.0) + 1) * 100 + y * 5 + z).astype('u1').tofile(T + '/long.raw')
np.ascontiguousarray(((np.sin(x / 9.0) + 1) * 100).astype('u1').transpose(0, 2, 1)).tofile(T + '/tall.raw')
z, y, x = np.mgrid[0:3, 0:4, 0:400]
((np.sin(x / 9.0) + 1) * 100 + y * 5 + z).astype('u1').tofile(T + '/wide.raw')
PYEOF
R_U8=9x7x6:u8
R_I16=9x7x6:i16:le:1x1x2
R_U16=9x7x6:u16
R_F32=9x7x6:f32:le:0.5x0.5x1
R_ROW=72x5x4:u8
R_CUBE=66x9x7:i16
R_LONG=140x5x4:u8

# ---- .vvc: both versions, the subcube sides 8 and 16 (32: tables of 40 KB),
# the voxel types, corrections
"$V" compress -q --raw $R_U8 --quality 60 --block 8 $T/u8.raw $C/vvc/v2_u8_b8.vvc
"$V" compress -q --raw $R_I16 --format 1 --quality 70 --block 8 $T/i16.raw $C/vvc/v1_i16_b8.vvc
"$V" compress -q --raw $R_U16 --quality 100 --block 16 $T/u16.raw $C/vvc/v2_u16_lossless.vvc
"$V" compress -q --raw $R_F32 --max-error 0.01 --block 8 $T/f32.raw $C/vvc/v2_f32_maxerr.vvc
"$V" compress -q --raw $R_CUBE --quality 40 --block 8 --slope 0 $T/cube.raw $C/vvc/v2_cube_flat.vvc
"$V" compress -q --raw $R_CUBE --format 1 --quality 30 --block 8 $T/cube.raw $C/vvc/v1_cube.vvc

# ---- SLC: wider and taller than the writer's icon (64 pixels), run-length and not
mkdir -p $C/slc
"$V" convert -q --raw $R_LONG $T/long.raw $C/slc/icon_wide.slc
"$V" convert -q --no-compress --raw 5x140x4:u8 $T/tall.raw $C/slc/icon_tall.slc

# ---- render: a .vvb with levels or without, raw or zstd, the modes --------
seed() { # NAME LINE FILE [DATA]: the line, the file, and --DATA-- then DATA
  { printf '%s\n' "$2"; cat "$3"
    if [ $# -ge 4 ]; then printf '\n--DATA--\n'; cat "$4"; fi; } > $C/render/$1
}
"$V" convert -q --raw $R_ROW $T/row.raw $T/row_levels.vvb
"$V" convert -q --raw $R_ROW --no-compress $T/row.raw $T/row_levels_raw.vvb
"$V" convert -q --raw $R_ROW --no-levels $T/row.raw $T/row_bricks.vvb
"$V" convert -q --raw $R_CUBE $T/cube.raw $T/cube.vvb
"$V" convert -q --raw $R_F32 --no-levels --no-compress $T/f32.raw $T/f32_raw.vvb
seed vvb_levels.txt "vvb levels" $T/row_levels.vvb
seed vvb_levels_progressive.txt "vvb levels progressive limit=64" $T/row_levels.vvb
seed vvb_levels_raw_mip.txt "vvb levels mip level=1" $T/row_levels_raw.vvb
seed vvb_cube_iso.txt "vvb levels iso lod=4" $T/cube.vvb
seed vvb_cube_progressive.txt "vvb levels progressive xray" $T/cube.vvb
seed vvb_bricks.txt "vvb" $T/row_bricks.vvb
seed vvb_bricks_whole.txt "vvb whole minip" $T/row_bricks.vvb
seed vvb_f32.txt "vvb mip" $T/f32_raw.vvb
# three bricks in a cache of a few KB: chunks evicted by the plan, the loader stopped
"$V" convert -q --raw $R_LONG $T/long.raw $T/long.vvb
seed vvb_long_limit.txt "vvb levels limit=8" $T/long.vvb
seed vvb_long_limit_progressive.txt "vvb levels progressive limit=8 lod=0.5" $T/long.vvb
seed vvb_long_level0_progressive.txt "vvb levels level=0 progressive limit=8" $T/long.vvb
seed vvb_long_level0_progressive_big.txt "vvb levels level=0 progressive iso" $T/long.vvb
seed vvb_cube_fine_progressive.txt "vvb levels progressive lod=0.25 mip" $T/cube.vvb
# five bricks in 6 to 7 KB: the plan's farthest next use evicts, the
# loader stops when the cache is full of wanted chunks; a brick's zstd
# frame corrupt: the loader's read fails, the frame reports it
"$V" convert -q --raw 400x4x3:u8 $T/wide.raw $T/wide.vvb
seed vvb_wide_evict.txt "vvb levels level=0 limit=6" $T/wide.vvb
seed vvb_wide_loader_full.txt "vvb levels level=0 limit=7 progressive" $T/wide.vvb
$PY - $T/wide.vvb $T/wide_bad.vvb <<'PYEOF'
import sys
b = bytearray(open(sys.argv[1], 'rb').read())
frames = [i for i in range(len(b) - 4) if b[i:i + 4] == b'\x28\xb5\x2f\xfd']
for f in frames[1:3]:
    for k in range(8, 14):
        b[f + k] ^= 0x5a
open(sys.argv[2], 'wb').write(bytes(b))
PYEOF
seed vvb_wide_corrupt_progressive.txt "vvb levels level=0 progressive" $T/wide_bad.vvb
seed vvb_long_small.txt "vvb levels limit=4" $T/long.vvb
seed raw_long_limit.txt "raw raw=$R_LONG limit=8" $T/long.raw
# raw out of core (its layout scanned into bricks) and whole
seed raw_u8.txt "raw raw=$R_ROW" $T/row.raw
seed raw_i16_mip.txt "raw raw=$R_CUBE mip limit=128" $T/cube.raw
seed raw_f32_whole.txt "raw raw=$R_F32 whole" $T/f32.raw
seed raw_no_description.txt "raw" $T/u8.raw
seed raw_u16_be.txt "raw raw=4x3x2:u16:be:skip=4" <(printf 'HEAD'; head -c 48 $T/u16.raw)
# our other readers, whole
"$V" convert -q --raw $R_U8 $T/u8.raw $T/u8.slc
"$V" convert -q --raw $R_I16 $T/i16.raw $T/i16.mha
"$V" convert -q --raw $R_F32 $T/f32.raw $T/f32.vtk
seed slc.txt "slc" $T/u8.slc
seed mha.txt "mha iso" $T/i16.mha
seed vtk.txt "vtk mip" $T/f32.vtk
printf 'ObjectType = Image\nNDims = 3\nDimSize = 9 7 6\nElementType = MET_UCHAR\nElementDataFile = data.raw\n' > $T/u8.mhd
seed mhd_detached.txt "mhd" $T/u8.mhd $T/u8.raw

# ---- raw: several bricks along x, every voxel type the scan reads its own way
$PY - "$C/raw" <<'PYEOF'
import sys, numpy as np
C = sys.argv[1]
x = np.arange(140 * 3 * 2)
for name, desc, a in [
        ('bricks_u8.txt', '140x3x2:u8', (x * 7 % 251).astype('u1')),
        ('bricks_f32_be.txt', '140x3x2:f32:be:1x1x2', (x * 0.25 - 9).astype('>f4')),
        ('bricks_i32_skip.txt', '140x3x2:i32:le:skip=3', (x * 1000 - 7).astype('<i4')),
        ('bricks_f64_nan.txt', '70x2x2:f64', np.where(x[:280] % 17 == 0, np.nan, x[:280]).astype('<f8')),
        ('bricks_u16_be.txt', '66x2x2:u16:be', (x[:264] * 211).astype('>u2'))]:
    skip = b'abc' if 'skip' in desc else b''
    open(C + '/' + name, 'wb').write(desc.encode() + b'\n' + skip + a.tobytes())
# '@', a vv_raw_params as in memory (int dims[3], type, big_endian; double
# spacing[3], origin[3]; uint64 skip), then the file: what a library caller passes
import struct
def params(dims, typ, be, sp, org, skip):
    return b'@' + struct.pack('<3iii4x3d3dQ', *dims, typ, be, *sp, *org, skip)
body = bytes(range(48))
for name, p in [
        ('params_ok.bin', params((4, 3, 2), 3, 1, (1, 1, 2), (0, 0, 0), 0)),
        ('params_type.bin', params((4, 3, 2), 99, 0, (1, 1, 1), (0, 0, 0), 0)),
        ('params_dims.bin', params((4, 0, 2), 0, 0, (1, 1, 1), (0, 0, 0), 0)),
        ('params_spacing.bin', params((4, 3, 2), 0, 0, (1, -1, 1), (0, 0, 0), 0)),
        ('params_origin.bin', params((4, 3, 2), 0, 0, (1, 1, 1), (0, float('inf'), 0), 0)),
        ('params_short.bin', params((4, 3, 2), 7, 0, (1, 1, 1), (0, 0, 0), 8))]:
    open(C + '/' + name, 'wb').write(p + body)
# bricks evicted: four bricks along x in a cache of 32 KiB (an odd file)
open(C + '/bricks_evicted.txt', 'wb').write(b'200x20x2:u8:le:skip=1\n' + b'\0' +
                                            (np.arange(8000) * 13 % 256).astype('u1').tobytes())
PYEOF

# ---- VTK legacy: two components a point, binary and ASCII (the component's
# values picked out of the tuples a block at a time)
$PY - "$C/vtk" <<'PYEOF'
import sys, numpy as np
C = sys.argv[1]
a = (np.arange(4 * 3 * 2 * 2) * 37 % 1000).astype('>i2')
for name, binary in [('components_binary.vtk', True), ('components_ascii.vtk', False)]:
    h = ('# vtk DataFile Version 3.0\ntwo components\n%s\nDATASET STRUCTURED_POINTS\n'
         'DIMENSIONS 4 3 2\nSPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA 24\nSCALARS v short 2\n'
         'LOOKUP_TABLE default\n' % ('BINARY' if binary else 'ASCII')).encode()
    open(C + '/' + name, 'wb').write(
        h + (a.tobytes() if binary else ' '.join(map(str, a)).encode() + b'\n'))
PYEOF
