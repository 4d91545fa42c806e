#!/usr/bin/env bash
# Regenerates the seed corpus of the fuzz harnesses (tests/fuzz/corpus/<format>/)
# from ../shared/data (cropped to a few voxels with Teem's unu), the repository's
# examples and test-data script, and hand-written minimal files. Every seed is a
# few KB at most. Run from the repository root; needs teem-unu, /usr/bin/python3
# (NumPy, pydicom, vtk9; zarr, numcodecs and h5py for make_corpus_structured.py),
# gdcmimg and ImageMagick's convert. The committed corpus also holds the crash
# inputs the fuzzers found (crash-*, regression inputs): this script never
# deletes anything.
set -euo pipefail
cd "$(dirname "$0")/../.."
D=../shared/data
C=tests/fuzz/corpus
PY=/usr/bin/python3
mkdir -p $C/{slc,nrrd,nifti,mhd,vtk,raw,scene,vvc,vvb,mesh,grid,dicom,tiff,animation,replay}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

# ---- NRRD: a 6x5x4 crop of the CT head, raw, gzip, ascii, detached --------
teem-unu crop -i $D/volumes/ct_head.nrrd -min 120 110 50 -max 125 114 53 -o $T/crop.nrrd
teem-unu save -f nrrd -i $T/crop.nrrd -e raw -o $C/nrrd/crop_raw.nrrd
teem-unu save -f nrrd -i $T/crop.nrrd -e gzip -o $C/nrrd/crop_gzip.nrrd
teem-unu save -f nrrd -i $T/crop.nrrd -e ascii -o $C/nrrd/crop_ascii.nrrd
teem-unu save -f nrrd -i $T/crop.nrrd -e raw -o $T/det.nhdr
sed 's/^data file: .*/data file: data.raw/' $T/det.nhdr > $C/nrrd/detached.txt
printf -- '--DATA--\n' >> $C/nrrd/detached.txt
cat $T/det.raw >> $C/nrrd/detached.txt
printf 'NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nspace: left-posterior-superior\nspace directions: (1,0,0) (0,2,0) (0,0,3)\nspace origin: (1,2,3)\nencoding: ascii\n\n1 2 3 4 5 6 7 8\n' > $C/nrrd/space_lps.nrrd
printf 'NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: LIST\ndata.raw\ndata.raw\n' > $C/nrrd/list.nhdr
printf -- '--DATA--\nabcd' >> $C/nrrd/list.nhdr

# ---- SLC, VTK, MetaImage, NIfTI, raw, .vvc: written by VolVis from the crop --
V=${VOLVIS:-build/release/apps/volvis/volvis}
"$V" convert $T/crop.nrrd $C/slc/crop.slc
"$V" convert --rle $T/crop.nrrd $C/slc/crop_rle.slc 2>/dev/null || true
"$V" compress --quality 50 --block 8 $T/crop.nrrd $C/vvc/crop.vvc
# .vvb: one brick raw and zstd; two bricks (70 voxels along x) zstd
"$V" convert -q --no-compress $T/crop.nrrd $C/vvb/crop_raw.vvb
"$V" convert -q $T/crop.nrrd $C/vvb/crop_zstd.vvb
teem-unu crop -i $D/volumes/ct_head.nrrd -min 90 120 50 -max 159 121 51 -o $T/row.nrrd
"$V" convert -q --no-levels $T/row.nrrd $C/vvb/two_bricks_zstd.vvb
# ... and with pyramid levels (70 x 2 x 2: a level of 35 x 1 x 1), zstd and raw
"$V" convert -q $T/row.nrrd $C/vvb/levels_zstd.vvb
"$V" convert -q --no-compress $T/row.nrrd $C/vvb/levels_raw.vvb
$PY - "$T/crop.nrrd" "$C" <<'PYEOF'
import sys, struct, gzip, zlib, numpy as np
src, C = sys.argv[1], sys.argv[2]
# the crop's data (raw little-endian short after the blank line)
raw = open(src, 'rb').read()
hdr, data = raw.split(b'\n\n', 1)
sizes = [int(x) for x in [l for l in hdr.split(b'\n') if l.startswith(b'sizes:')][0].split()[1:]]
a = np.frombuffer(data, dtype='<i2')[:np.prod(sizes)].reshape(sizes[::-1])
# VTK legacy, binary and ASCII
def vtk(binary):
    h = ('# vtk DataFile Version 3.0\ncrop\n%s\nDATASET STRUCTURED_POINTS\nDIMENSIONS %d %d %d\n'
         'SPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA %d\nSCALARS v short 1\nLOOKUP_TABLE default\n'
         % ('BINARY' if binary else 'ASCII', sizes[0], sizes[1], sizes[2], a.size)).encode()
    return h + (a.astype('>i2').tobytes() if binary else ' '.join(map(str, a.ravel())).encode() + b'\n')
open(C + '/vtk/crop_binary.vtk', 'wb').write(vtk(True))
open(C + '/vtk/crop_ascii.vtk', 'wb').write(vtk(False))
# MetaImage: LOCAL, compressed LOCAL, detached
mh = ('ObjectType = Image\nNDims = 3\nDimSize = %d %d %d\nElementSpacing = 1 1 2\n'
      'ElementType = MET_SHORT\nBinaryData = True\nBinaryDataByteOrderMSB = False\n'
      % tuple(sizes))
open(C + '/mhd/crop.mha', 'wb').write((mh + 'ElementDataFile = LOCAL\n').encode() + a.tobytes())
z = zlib.compress(a.tobytes())
open(C + '/mhd/crop_zlib.mha', 'wb').write(
    (mh + 'CompressedData = True\nCompressedDataSize = %d\nElementDataFile = LOCAL\n' % len(z)).encode() + z)
open(C + '/mhd/detached.txt', 'wb').write((mh + 'ElementDataFile = data.raw\n').encode()
                                           + b'\n--DATA--\n' + a.tobytes())
# NIfTI-1 and NIfTI-2 single files, NIfTI-1 gzip, an Analyze-style pair
def nifti1(magic=b'n+1\0'):
    h = bytearray(348)
    struct.pack_into('<i', h, 0, 348)
    struct.pack_into('<8h', h, 40, 3, sizes[0], sizes[1], sizes[2], 1, 1, 1, 1)
    struct.pack_into('<hh', h, 70, 4, 16)  # datatype int16, bitpix
    struct.pack_into('<8f', h, 76, 1, 1, 1, 2, 1, 1, 1, 1)
    struct.pack_into('<f', h, 108, 352.0)
    struct.pack_into('<ff', h, 112, 1.0, 0.0)
    h[123] = 2  # xyzt_units mm
    struct.pack_into('<hh', h, 252, 1, 0)  # qform, sform
    h[344:348] = magic
    return bytes(h)
def nifti2():
    h = bytearray(540)
    struct.pack_into('<i', h, 0, 540)
    h[4:12] = b'n+2\0\r\n\x1a\n'
    struct.pack_into('<hh', h, 12, 4, 16)
    struct.pack_into('<8q', h, 16, 3, sizes[0], sizes[1], sizes[2], 1, 1, 1, 1)
    struct.pack_into('<8d', h, 104, 1, 1, 1, 2, 1, 1, 1, 1)
    struct.pack_into('<q', h, 168, 544)
    struct.pack_into('<dd', h, 176, 1.0, 0.0)
    return bytes(h)
body = a.tobytes()
open(C + '/nifti/crop.nii', 'wb').write(nifti1() + b'\0' * 4 + body)
open(C + '/nifti/crop2.nii', 'wb').write(nifti2() + b'\0' * 4 + body)
open(C + '/nifti/crop.nii.gz', 'wb').write(gzip.compress(nifti1() + b'\0' * 4 + body, mtime=0))
open(C + '/nifti/pair.txt', 'wb').write(nifti1(b'ni1\0') + b'\n--DATA--\n' + body)
# raw: a --raw description line, then the data
open(C + '/raw/crop.txt', 'wb').write(('%dx%dx%d:i16:le:1x1x2\n' % tuple(sizes)).encode() + body)
open(C + '/raw/be_skip.txt', 'wb').write(b'2x2x2:u16:be:skip=4\n' + b'HEAD' + bytes(range(16)))
PYEOF

# ---- TIFF: a 3-page 8x6 stack (ImageMagick), DICOM: a 2-slice 8x8 series --
convert -size 8x6 gradient: gradient: xc:gray50 -depth 8 $C/tiff/stack.tif
convert -size 8x6 gradient: -depth 16 -compress lzw $C/tiff/lzw16.tif
$PY scripts/dicom_testdata.py ct $D/volumes/ct_head.nrrd $T/dcm --first 60 --count 1 --crop 8 >/dev/null
cp "$(ls $T/dcm/*.dcm | head -1)" $C/dicom/ct_slice.dcm

# ---- meshes: minimal OFF/OBJ/PLY/STL and the first faces of real ones ----
printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' > $C/mesh/tet.off
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n' > $C/mesh/tet.obj
printf 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' > $C/mesh/tet.ply
printf 'solid t\nfacet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid t\n' > $C/mesh/tri.stl
head -c 1500 $D/meshes/cow.obj | head -n -1 > $C/mesh/cow_head.obj

# ---- grids: a 2-tet VTK legacy grid, a .vtu (vtk9), an OpenDX cube, PLOT3D --
printf '# vtk DataFile Version 3.0\ntets\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\nCELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\nCELL_TYPES 2\n10\n10\nPOINT_DATA 5\nSCALARS s float 1\nLOOKUP_TABLE default\n0 1 2 3 4\n' > $C/grid/tets.vtk
$PY - "$C/grid/tets.vtu" <<'PYEOF'
import sys, vtk
pts = vtk.vtkPoints()
for p in [(0,0,0),(1,0,0),(0,1,0),(0,0,1),(1,1,1)]: pts.InsertNextPoint(p)
g = vtk.vtkUnstructuredGrid(); g.SetPoints(pts)
for c in [(0,1,2,3),(1,2,3,4)]:
    ids = vtk.vtkIdList()
    for i in c: ids.InsertNextId(i)
    g.InsertNextCell(vtk.VTK_TETRA, ids)
s = vtk.vtkFloatArray(); s.SetName('s')
for i in range(5): s.InsertNextValue(i)
g.GetPointData().AddArray(s)
w = vtk.vtkXMLUnstructuredGridWriter(); w.SetFileName(sys.argv[1]); w.SetInputData(g)
w.SetCompressorTypeToZLib(); w.Write()
PYEOF
head -c 3000 $D/grids/hyper.dx > /dev/null
printf 'object 1 class array type float rank 1 shape 3 items 4 data follows\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nobject 2 class array type int rank 1 shape 4 items 1 data follows\n0 1 2 3\nattribute "element type" string "tetrahedra"\nattribute "ref" string "positions"\nobject 3 class array type float rank 0 items 4 data follows\n0 1 2 3\nattribute "dep" string "positions"\nobject "f" class field\ncomponent "positions" value 1\ncomponent "connections" value 2\ncomponent "data" value 3\nend\n' > $C/grid/tet.dx
$PY - "$C/grid/plot3d.bin" <<'PYEOF'
import sys, struct
ni, nj, nk = 2, 2, 2
xyz = [float(i & 1) for i in range(8)] + [float((i >> 1) & 1) for i in range(8)] + [float(i >> 2) for i in range(8)]
g = struct.pack('<3i', ni, nj, nk) + struct.pack('<24f', *xyz)
q = struct.pack('<3i', ni, nj, nk) + struct.pack('<4f', 0.5, 0, 1e5, 0) + struct.pack('<40f', *([1.0] * 40))
open(sys.argv[1], 'wb').write(g + b'\n--DATA--\n' + q)
PYEOF

# ---- scenes, animations, recordings ----------------------------------------
for f in examples/*.json; do
  [ "$(stat -c %s "$f")" -le 4096 ] && cp "$f" $C/scene/
done
printf '{"volvis_animation": 1, "fps": 10, "duration": 2, "tracks": [\n {"property": "view.eye", "closed": false, "keys": [\n  {"time": 0, "value": [0, -700, 0]}, {"time": 2, "value": [700, 0, 100], "easing": "ease-in-out"}]},\n {"property": "view.fov", "interpolation": "linear", "keys": [{"time": 0, "value": 30}, {"time": 1, "value": 40}]}]}\n' > $C/animation/orbit.json
printf 'volvis-input 1\ndevice 1 mouse m\ndevice 7 dataglove right hand\n0.0 pointer 1 0 10 20\n0.05 button 1 1 1\n0.1 pose 7 0 23 2 0 1 0 0 0\n0.2 button 7 0 1\n0.3 key 1 65 1\n' > $C/replay/mixed.rec
# ---- OME-Zarr stores and BigDataViewer / Imaris HDF5 (zarr-python, h5py) ----
$PY tests/fuzz/make_corpus_structured.py
# Zarr v3 and OME-Zarr 0.5 (zarr-python 3, in the .venv of install-deps.sh test)
if [ -x .venv/bin/python ]; then .venv/bin/python tests/fuzz/make_corpus_zarr3.py; fi
ls -la $C/*/ | awk '$5 > 8192 {print "big seed:", $0}'
