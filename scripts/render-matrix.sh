#!/usr/bin/env bash
# Renders every example scene (examples/*.json) and a few plain volumes with
# every renderer at quality 2, and the CT head out of core (by bricks, by
# levels, by level of detail, a scene of two files in one cache) with the
# region renderers, into OUTDIR, one PNG each, so two builds can be
# compared image by image (refactoring must not change a pixel).
#
#   scripts/render-matrix.sh VOLVIS OUTDIR            render
#   scripts/render-matrix.sh --compare DIR_A DIR_B    ImageMagick AE per image
#
# A renderer that refuses a scene (e.g. irregular on a scene without grids)
# leaves OUTDIR/NAME.err with its one-line error instead of a PNG; the
# comparison reports a change of outcome as a difference.
set -uo pipefail
cd "$(dirname "$0")/.."

if [ "${1:-}" = "--compare" ]; then
  a="$2"
  b="$3"
  diffs=0
  for f in "$a"/*.png "$a"/*.err; do
    [ -e "$f" ] || continue
    n="$(basename "$f")"
    stem="${n%.*}"
    if [ "${n##*.}" = err ]; then
      if [ -e "$b/$stem.png" ]; then
        echo "CHANGED $stem: error before, image now"
        diffs=$((diffs + 1))
      fi
      continue
    fi
    if [ ! -e "$b/$n" ]; then
      echo "CHANGED $stem: image before, $(cat "$b/$stem.err" 2>/dev/null || echo missing) now"
      diffs=$((diffs + 1))
      continue
    fi
    ae="$(compare -metric AE "$f" "$b/$n" null: 2>&1 || true)"
    if [ "$ae" != "0" ]; then
      psnr="$(compare -metric PSNR "$f" "$b/$n" null: 2>&1 || true)"
      echo "DIFF $stem: AE $ae PSNR $psnr"
      diffs=$((diffs + 1))
    fi
  done
  for f in "$b"/*.png; do
    [ -e "$f" ] || continue
    n="$(basename "$f")"
    stem="${n%.*}"
    if [ ! -e "$a/$n" ] && [ ! -e "$a/$stem.err" ]; then
      echo "NEW $stem"
    fi
  done
  echo "compare: $diffs difference(s)"
  [ "$diffs" -eq 0 ]
  exit $?
fi

volvis="$(realpath "$1")"
out="$2"
mkdir -p "$out"
data=../shared/data
renderers=(raycast raytrace radiosity splat raster fourier irregular)
inputs=()
for s in examples/*.json; do inputs+=("$s"); done
inputs+=("$data/volumes/ct_head.nrrd" "$data/volumes/neghip.slc" "$data/grids/fire_ug.vtu")
for in in "${inputs[@]}"; do
  base="$(basename "$in")"
  base="${base//./_}" # ct_head.json and ct_head.nrrd apart
  for r in "${renderers[@]}"; do
    extra=()
    if [ "$r" = fourier ]; then extra=(--ortho); fi
    for mode in default mip; do
      m=()
      if [ "$mode" = mip ]; then
        case "$in" in *.json) continue ;; esac
        m=(--mode mip)
      fi
      name="${base}_${r}_${mode}"
      rm -f "$out/$name.png" "$out/$name.err"
      if ! "$volvis" render "$in" --renderer "$r" --quality 2 --size 256x192 "${m[@]}" \
          "${extra[@]}" -q -o "$out/$name.png" 2>"$out/$name.err"; then
        rm -f "$out/$name.png"
      else
        rm -f "$out/$name.err"
      fi
    done
  done
done
# Out of core: the CT head read by bricks (.vvb without levels), by levels
# (.vvb and OME-Zarr pyramids) at level 0, level 1 and by level of detail,
# and a scene of two of them in one cache, with the region renderers.
ooc="$out/ooc-files"
mkdir -p "$ooc"
head="$data/volumes/ct_head.nrrd"
"$volvis" convert -q --no-levels "$head" "$ooc/flat.vvb"
"$volvis" convert -q "$head" "$ooc/levels.vvb"
"$volvis" convert -q "$head" "$ooc/levels.ome.zarr"
cat >"$ooc/two.json" <<EOF
{"view": {"width": 256, "height": 192, "eye": [250, -1100, 300], "at": [250, 122, 54],
  "up": [0, 0, 1], "fov": 30},
 "lights": [{"type": "directional", "color": [1, 1, 1], "intensity": 1.0}],
 "objects": [
  {"name": "bricks", "file": "flat.vvb", "transfer_function": {"opacity": [[100, 0], [1500, 0.8]]}},
  {"name": "levels", "file": "levels.ome.zarr", "mode": "mip", "position": [270, 0, 0]}]}
EOF
ooc_render() { # NAME INPUT ARGS...
  local name="$1" in="$2"
  shift 2
  rm -f "$out/$name.png" "$out/$name.err"
  if ! "$volvis" render "$in" --quality 2 --size 256x192 -q -o "$out/$name.png" "$@" \
      2>"$out/$name.err"; then
    rm -f "$out/$name.png"
  else
    rm -f "$out/$name.err"
  fi
}
for r in raycast raytrace; do
  for mode in default mip; do
    m=()
    if [ "$mode" = mip ]; then m=(--mode mip); fi
    ooc_render "ooc_bricks_${r}_${mode}" "$ooc/flat.vvb" --renderer "$r" "${m[@]}" \
      --memory-limit 16M
    for f in levels.vvb levels.ome.zarr; do
      stem="ooc_${f//./_}_${r}_${mode}"
      ooc_render "${stem}_level0" "$ooc/$f" --renderer "$r" "${m[@]}" --memory-limit 16M \
        --level 0
      ooc_render "${stem}_level1" "$ooc/$f" --renderer "$r" "${m[@]}" --level 1
      ooc_render "${stem}_lod" "$ooc/$f" --renderer "$r" "${m[@]}" --lod 1
    done
  done
  ooc_render "ooc_scene_${r}" "$ooc/two.json" --renderer "$r" --memory-limit 16M
done
# The door (vv_world_open): every kind of input a user names, with the
# command line's overrides, read in memory, out of core and by channels.
vol="$data/volumes"
mri=/usr/share/mricron/templates/ch2better.nii.gz
/usr/bin/python3 - "$ooc/channels.tif" <<'EOF'
import sys
import numpy as np
import tifffile
z, y, x = np.mgrid[0:24, 0:40, 0:48].astype(np.float32)
a = 1000 * np.exp(-((x - 16) ** 2 + (y - 20) ** 2 + (z - 12) ** 2) / 60)
b = 800 * np.exp(-((x - 32) ** 2 + (y - 20) ** 2 + (z - 12) ** 2) / 90)
tifffile.imwrite(sys.argv[1], np.stack([a, b], 1).astype(np.uint16), imagej=True,
                 metadata={"axes": "ZCYX"})
EOF
for mode in composite mip minip xray; do
  ooc_render "door_ct_$mode" "$head" --mode "$mode"
done
ooc_render door_ct_iso "$head" --iso 600
ooc_render door_ct_tf_turn "$head" --tf 100:1500 --azimuth 30 --elevation 10 --zoom 1.3
ooc_render door_ct_step_ortho "$head" --step 1 --ortho
ooc_render door_nut_labels "$vol/nut.slc" --labels
ooc_render door_mhd "$vol/HeadMRVolume.mhd"
ooc_render door_vtk "$vol/ironProt.vtk"
ooc_render door_nifti "$vol/avg152T1_RL_nifti.nii.gz"
ooc_render door_ch2better "$mri"
ooc_render door_raw "$vol/headsq/quarter.1" --raw 256x256x1:u16:be
ooc_render door_store "$ooc/levels.ome.zarr"
ooc_render door_store_level1_mip "$ooc/levels.ome.zarr" --level 1 --mode mip
ooc_render door_grid_blow "$data/grids/blow.vtk"
ooc_render door_grid_fire_iso "$data/grids/fire_ug.vtu" --mode iso
ooc_render door_channels "$ooc/channels.tif" --channels 0,1
ooc_render door_channels_colors "$ooc/channels.tif" --colors red,cyan --blend maximum
ooc_render door_channel1 "$ooc/channels.tif" --channel 1 --mode mip
ooc_render door_scene_overrides examples/ct_head.json --tf 200:1200 --mode composite --step 1
ls "$out" | wc -l
