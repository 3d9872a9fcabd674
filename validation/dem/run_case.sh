#!/usr/bin/env bash
# One validation case of docs/validation.md: DEM impact (LAMMPS, one core) and the bed's own
# P-wave speed (pwave.in, two single-core runs side by side), filmed by
# `impactdic synth --dem`, processed by `impactdic run`, compared by `impactdic validate-dem`.
#
#   validation/dem/run_case.sh MASS_KG DROP_HEIGHT_M WIDTH_M WORK_DIR
#   e.g. validation/dem/run_case.sh 10 0.7 0.15 /tmp/dem
#
# The settled bed (bed.in then bed_relax.in, 29,432 grains) is made once into
# WORK_DIR/bed/bed.data and reused by every case. Large DEM output stays in WORK_DIR (not
# committed). Environment:
#   IMPACTDIC  the binary (default build/release/src/cli/impactdic)
#   LMP        LAMMPS (default lmp; installed by scripts/install_deps.sh)
#   BED        a settled bed to use instead of WORK_DIR/bed/bed.data (e.g. the reduced case's
#              validation/dem/reduced_bed.data.gz, docs/validation.md); no settling then
#   TAFTER     simulated time after contact (default 0.04 s)
#   MUROLL     rolling friction (default 0.1; a bed made with another value needs its own WORK_DIR)
#   SCENE_DIC  extra `key: value` lines (newline-separated) for the `dic:` section of the
#              rendered scene.yaml, e.g. "continuity_check: false" (default: none, the defaults)
set -euo pipefail
if [ $# -ne 4 ]; then
  echo "usage: $0 MASS_KG DROP_HEIGHT_M WIDTH_M WORK_DIR" >&2
  exit 2
fi
mass=$1 height=$2 width=$3 work=$4
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
impactdic=${IMPACTDIC:-$repo/build/release/src/cli/impactdic}
lmp=${LMP:-lmp}
tafter=${TAFTER:-0.04}
muroll=${MUROLL:-0.1}  # rolling friction of the grains (bed and impact)
export OMP_NUM_THREADS=1
command -v "$lmp" >/dev/null || { echo "$lmp not found: run scripts/install_deps.sh" >&2; exit 1; }
[ -x "$impactdic" ] || { echo "$impactdic not found: build the release preset first" >&2; exit 1; }
mkdir -p "$work/bed"
work=$(cd "$work" && pwd)
bed=${BED:-$work/bed/bed.data}
if [ -n "${BED:-}" ]; then
  [ -s "$BED" ] || { echo "BED=$BED: no such bed file" >&2; exit 1; }
  bed=$(cd "$(dirname "$BED")" && pwd)/$(basename "$BED")
fi

if [ -z "${BED:-}" ] && [ ! -s "$work/bed/bed.data" ]; then
  echo "settling the bed (once) ..."
  start=$SECONDS
  (cd "$work/bed" && "$lmp" -in "$here/bed.in" -var out "$work/bed/poured.data" -var muroll "$muroll" -log bed.log \
    > bed.out)
  (cd "$work/bed" && "$lmp" -in "$here/bed_relax.in" -var in "$work/bed/poured.data" \
    -var out "$work/bed/bed.data.tmp" -var muroll "$muroll" -log relax.log > relax.out)
  mv "$work/bed/bed.data.tmp" "$work/bed/bed.data"
  echo "bed: $((SECONDS - start)) s wall"
fi

case_name="m${mass}_h${height}_D${width}"
dem="$work/dem_$case_name" scene="$work/scene_$case_name" run="$work/run_$case_name"
v0=$(awk -v h="$height" 'BEGIN { printf "%.6f", sqrt(2 * 9.81 * h) }')
mkdir -p "$dem"
start=$SECONDS
(cd "$dem" && "$lmp" -in "$here/impact.in" -var bed "$bed" -var dir "$dem" \
  -var mp "$mass" -var D "$width" -var v0 "$v0" -var tafter "$tafter" -var muroll "$muroll" -log log.lammps > out.txt)
echo "DEM impact $case_name: $((SECONDS - start)) s wall"
# The bed's own P-wave speed (pwave.in): the pulse and the same run without it, side by side.
start=$SECONDS
(cd "$dem" && "$lmp" -in "$here/pwave.in" -var bed "$bed" -var dir "$dem" -var muroll "$muroll" \
  -log pwave.log > pwave.out) &
pulse=$!
(cd "$dem" && "$lmp" -in "$here/pwave.in" -var bed "$bed" -var dir "$dem" -var muroll "$muroll" \
  -var sigma 0 -var out pwave_rest.txt -var meta pwave_rest_meta.txt -log pwave_rest.log \
  > pwave_rest.out)
wait "$pulse"
echo "DEM P-wave pulse: $((SECONDS - start)) s wall"

"$impactdic" synth "$here/camera_spec.yaml" --dem "$dem" -o "$scene"
if [ -n "${SCENE_DIC:-}" ]; then
  # Indented under the scene's `dic:` section (written by synth with the grid geometry).
  extra=$(printf '%s\n' "$SCENE_DIC" | sed 's/^/  /')
  awk -v extra="$extra" '{ print } /^dic:/ { print extra }' "$scene/scene.yaml" > "$scene/scene.yaml.tmp"
  mv "$scene/scene.yaml.tmp" "$scene/scene.yaml"
fi
# Every frame stored in results.h5 (66 small frames), so that validate-dem draws the velocity
# field at the grains' t_e, not at the nearest frame of a preview.
"$impactdic" run "$scene/scene.yaml" --outputs.frames all -o "$run" > "$run.log" 2>&1 || {
  cat "$run.log" >&2
  exit 1
}
mkdir -p "$run/compare"
"$impactdic" validate-dem "$scene/truth.h5" "$run/results.h5" --figures "$run/compare" \
  --csv "$run/compare/series.csv" --wave-csv "$run/compare/wave.csv" | tee "$run/compare/table.md"
