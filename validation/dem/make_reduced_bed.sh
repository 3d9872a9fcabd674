#!/usr/bin/env bash
# Makes the settled bed of the reduced DEM case that CI runs (docs/validation.md, "The reduced
# case in CI") from the full bed of the three full cases (bed.in then bed_relax.in, 29,432 grains,
# 0.80 m wide, top at 0.59 m): a window of it, the grains lying wholly within 0.25 m of the
# pounder axis and 0.30 m of the bed top, moved into a box 0.50 m wide with its floor at the
# window's bottom, then re-settled by bed_relax.in (the grains close the gaps of at most one grain
# left at the new walls and floor). So the grains under the pounder are the full bed's, in its
# packing. The data file is then made small: positions and diameters rounded to 1 nm (contact
# overlaps at rest are ~1 um), densities to 7 digits, no Velocities section (the settled grains
# move at ~2.5 mm/s rms; the impact at 3.7 m/s), gzipped (LAMMPS reads a .gz data file through
# gzip): 198 KB. Run once (the full bed ~9 min on one core if WORK_DIR has none, the window ~1 min); the result
# is committed as validation/dem/reduced_bed.data.gz.
#
#   validation/dem/make_reduced_bed.sh WORK_DIR
#
# WORK_DIR/bed/bed.data is the full bed (the one run_case.sh makes and reuses; made here if
# missing); the window is made in WORK_DIR/reduced_bed/.
set -euo pipefail
if [ $# -ne 1 ]; then
  echo "usage: $0 WORK_DIR" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
lmp=${LMP:-lmp}
export OMP_NUM_THREADS=1
command -v "$lmp" >/dev/null || { echo "$lmp not found: run scripts/install_deps.sh" >&2; exit 1; }
mkdir -p "$1/bed" "$1/reduced_bed"
work=$(cd "$1" && pwd)
if [ ! -s "$work/bed/bed.data" ]; then
  echo "settling the full bed ..."
  (cd "$work/bed" && "$lmp" -in "$here/bed.in" -var out "$work/bed/poured.data" -log bed.log \
    > bed.out)
  (cd "$work/bed" && "$lmp" -in "$here/bed_relax.in" -var in "$work/bed/poured.data" \
    -var out "$work/bed/bed.data.tmp" -log relax.log > relax.out)
  mv "$work/bed/bed.data.tmp" "$work/bed/bed.data"
fi

# The window (atom_style sphere lines: id type diameter density x y z [image flags]), renumbered.
half_width=0.25 depth=0.30
awk -v hw="$half_width" -v depth="$depth" '
  FNR == 1 { pass++ }
  /^Velocities/ { section = "" ; next }
  /^Atoms/ { section = "atoms"; if (pass == 2) { atoms_line = FNR }; next }
  /^[A-Z]/ { section = "" }
  pass == 1 && section == "atoms" && NF >= 7 {
    if ($6 > ytop || n == 0) ytop = $6
    n++
    next
  }
  pass == 1 && /xlo xhi/ { axis = ($1 + $2) / 2 }
  pass == 2 && section == "atoms" && NF >= 7 {
    r = $3 / 2; x = $5 - (axis - hw); y = $6 - (ytop - depth)
    if (x - r >= 0 && x + r <= 2 * hw && y - r >= 0) {
      kept++
      line[kept] = sprintf("%d %d %.9f %.7g %.9f %.9f 0", kept, $2, $3, $4, x, y)
    }
  }
  END {
    print "LAMMPS data file: a window of the full bed (validation/dem/make_reduced_bed.sh)\n"
    print kept " atoms\n2 atom types\n"
    printf "0 %.6g xlo xhi\n0 1.2 ylo yhi\n-0.005 0.005 zlo zhi\n\nAtoms # sphere\n\n", 2 * hw
    for (i = 1; i <= kept; i++) print line[i]
  }
' "$work/bed/bed.data" "$work/bed/bed.data" > "$work/reduced_bed/window.data"
echo "window: $(sed -n 3p "$work/reduced_bed/window.data")"
start=$SECONDS
(cd "$work/reduced_bed" && "$lmp" -in "$here/bed_relax.in" -var in "$work/reduced_bed/window.data" \
  -var out "$work/reduced_bed/bed.data" -log relax.log > relax.out)
echo "re-settled: $((SECONDS - start)) s wall"
# Compact: everything up to the Atoms section as written, the atoms rounded, no Velocities.
awk '
  /^Velocities/ { exit }
  section == "atoms" && NF >= 7 {
    printf "%d %d %.9f %.7g %.9f %.9f 0\n", $1, $2, $3, $4, $5, $6
    next
  }
  /^Atoms/ { section = "atoms" }
  { print }
' "$work/reduced_bed/bed.data" | gzip -9 -n > "$here/reduced_bed.data.gz"
echo "wrote $here/reduced_bed.data.gz ($(stat -c %s "$here/reduced_bed.data.gz") bytes)"
