#!/usr/bin/env bash
# One validation case of docs/validation.md: DEM impact (LAMMPS, one core), filmed by
# `impactdic synth --dem`, processed by `impactdic run`, compared by `impactdic validate-dem`.
#
#   validation/dem/run_case.sh MASS_KG DROP_HEIGHT_M WIDTH_M WORK_DIR
#   e.g. validation/dem/run_case.sh 10 0.7 0.15 /tmp/dem
#
# The settled bed (bed.in then bed_relax.in, 29,432 grains) is made once into WORK_DIR/bed/bed.data and reused by
# every case. Large DEM output stays in WORK_DIR (not committed). Environment: IMPACTDIC (the
# binary, default build/release/src/cli/impactdic), LMP (default lmp; install with
# validation/dem/install.sh), TAFTER (simulated time after contact, default 0.04 s), MUROLL
# (rolling friction, default 0.1; a bed made with another value needs its own WORK_DIR).
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
command -v "$lmp" >/dev/null || { echo "$lmp not found: run validation/dem/install.sh" >&2; exit 1; }
[ -x "$impactdic" ] || { echo "$impactdic not found: build the release preset first" >&2; exit 1; }
mkdir -p "$work/bed"
work=$(cd "$work" && pwd)

if [ ! -s "$work/bed/bed.data" ]; then
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
(cd "$dem" && "$lmp" -in "$here/impact.in" -var bed "$work/bed/bed.data" -var dir "$dem" \
  -var mp "$mass" -var D "$width" -var v0 "$v0" -var tafter "$tafter" -var muroll "$muroll" -log log.lammps > out.txt)
echo "DEM impact $case_name: $((SECONDS - start)) s wall"

"$impactdic" synth "$here/camera_spec.yaml" --dem "$dem" -o "$scene"
"$impactdic" run "$scene/scene.yaml" -o "$run" > "$run.log" 2>&1 || {
  cat "$run.log" >&2
  exit 1
}
mkdir -p "$run/compare"
"$impactdic" validate-dem "$scene/truth.h5" "$run/results.h5" --figures "$run/compare" \
  --csv "$run/compare/series.csv" | tee "$run/compare/table.md"
