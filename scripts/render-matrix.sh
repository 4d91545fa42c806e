#!/usr/bin/env bash
# Renders every example scene (examples/*.json) and a few plain volumes with
# every renderer at quality 2 into OUTDIR, one PNG each, so two builds can be
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
renderers=(raycast raytrace radiosity splat surface fourier irregular)
inputs=()
for s in examples/*.json; do inputs+=("$s"); done
inputs+=("$data/volumes/ct_head.nrrd" "$data/volumes/neghip.slc" "$data/grids/fire_ug.vtu")
for in in "${inputs[@]}"; do
  base="$(basename "$in")"
  base="${base%%.*}"
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
ls "$out" | wc -l
