#!/bin/bash
# zfp's fixed-accuracy mode (-a TOL: |error| <= TOL per value, as .vvc's
# --max-error) on a volume converted to float32 with teem-unu, one thread
# (the zfp CLI is serial), beside bench/bench_compress --max-errors:
#   anchor=zfp-VERSION op=zfp_accE_{bits_per_voxel,psnr,maxerr,compress_wall,
#   decompress_wall,compress_mvoxels,decompress_mvoxels} dataset=... value=... unit=...
# PSNR with peak = max - min of the data (as ../shared/anchors/bench_zfp.sh);
# wall times are the median of RUNS after WARMUP and include reading and
# writing the files from the page cache.
# Usage: bench/zfp_accuracy.sh VOLUME          env: TOLS="1 4 10 40" RUNS=5 WARMUP=1
set -euo pipefail
VOL=${1:?usage: zfp_accuracy.sh VOLUME}
TOLS=${TOLS:-"1 4 10 40"}
RUNS=${RUNS:-5}
WARMUP=${WARMUP:-1}
PY=/usr/bin/python3
UNU=/usr/bin/teem-unu
ZFP=/usr/bin/zfp
DS=$(basename "$VOL")
ANCHOR="zfp-$( ($ZFP 2>&1 || true) | sed -n "s/^zfp version \([0-9.]*\).*/\1/p")"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
emit() { echo "anchor=$ANCHOR op=$1 dataset=$DS value=$2 unit=$3"; }
$UNU convert -i "$VOL" -t float | $UNU save -f nrrd -e raw -en little -o "$TMP/f.nrrd"
$UNU data "$TMP/f.nrrd" >"$TMP/raw.f32"
read -r NX NY NZ <<<"$($UNU head "$TMP/f.nrrd" | sed -n 's/^sizes: //p')"
N=$((NX * NY * NZ))
median_wall() {
  local i t0 t1 ts=()
  for ((i = 0; i < WARMUP + RUNS; i++)); do
    t0=$(date +%s.%N); "$@" >/dev/null 2>&1; t1=$(date +%s.%N)
    ((i >= WARMUP)) && ts+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.6f", b-a}')")
  done
  printf '%s\n' "${ts[@]}" | sort -g | awk '{a[NR]=$1} END{print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'
}
for T in $TOLS; do
  $ZFP -h -f -3 "$NX" "$NY" "$NZ" -a "$T" -i "$TMP/raw.f32" -z "$TMP/c.zfp"
  $ZFP -h -z "$TMP/c.zfp" -o "$TMP/d.f32"
  read -r P MAXE <<<"$($PY - "$TMP/raw.f32" "$TMP/d.f32" <<'PYEOF'
import sys, numpy as np
a = np.fromfile(sys.argv[1], dtype="<f4").astype(np.float64)
b = np.fromfile(sys.argv[2], dtype="<f4").astype(np.float64)
r = a.max() - a.min(); m = np.mean((a - b) ** 2)
print("%.4f %.6g" % (99.0 if m == 0 else 10 * np.log10(r * r / m), np.abs(a - b).max()))
PYEOF
)"
  B=$(stat -c %s "$TMP/c.zfp")
  TC=$(median_wall $ZFP -h -f -3 "$NX" "$NY" "$NZ" -a "$T" -i "$TMP/raw.f32" -z "$TMP/c.zfp")
  TD=$(median_wall $ZFP -h -z "$TMP/c.zfp" -o "$TMP/d.f32")
  emit "zfp_acc${T}_bits_per_voxel" "$(awk -v b="$B" -v n="$N" 'BEGIN{printf "%.4f", 8*b/n}')" bits/voxel
  emit "zfp_acc${T}_psnr" "$P" dB
  emit "zfp_acc${T}_maxerr" "$MAXE" value
  emit "zfp_acc${T}_compress_wall" "$TC" s
  emit "zfp_acc${T}_decompress_wall" "$TD" s
  emit "zfp_acc${T}_compress_mvoxels" "$(awk -v n="$N" -v t="$TC" 'BEGIN{printf "%.4g", n/t/1e6}')" Mvoxel/s
  emit "zfp_acc${T}_decompress_mvoxels" "$(awk -v n="$N" -v t="$TD" 'BEGIN{printf "%.4g", n/t/1e6}')" Mvoxel/s
done
