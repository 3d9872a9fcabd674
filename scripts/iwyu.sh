#!/usr/bin/env bash
# Include what you use: include-what-you-use (mappings in .iwyu.imp) over every source file of src/
# and tests/ and the project headers they include (include/, src/, tests/), with the compile
# commands of a configured build (default build/release). Fails, listing them, if iwyu asks for an
# include to be added to any of our files; what it would remove is printed but does not fail (it
# also proposes dropping the dependencies' umbrella headers, which the code keeps on purpose).
# The benchmarks (bench/*.cc) are checked too, with the compile commands of the bench preset's
# build (default build/bench; IMPACTDIC_IWYU_BENCH_BUILD), when it is configured; otherwise the
# script says they were skipped.
# Alone: bash scripts/iwyu.sh [BUILD_DIR]. Installs the Debian package iwyu when it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=${1:-build/release}
# shellcheck source=scripts/common.sh
source scripts/common.sh
require_tool iwyu include-what-you-use iwyu
require_compile_commands iwyu "$build_dir"

jobs=${IMPACTDIC_IWYU_JOBS:-2}
root=$(pwd)
log=$(mktemp)
trap 'rm -f "$log"' EXIT
mapfile -t sources < <(find src tests -name '*.cc' | sort)
echo "iwyu: $(include-what-you-use --version | head -1) over ${#sources[@]} files with $jobs jobs"
iwyu_tool -p "$build_dir" -j "$jobs" "${sources[@]}" -- \
  -Xiwyu --mapping_file="$root/.iwyu.imp" -Xiwyu --no_fwd_decls \
  -Xiwyu --check_also="$root/include/*" -Xiwyu --check_also="$root/src/*" \
  -Xiwyu --check_also="$root/tests/*" > "$log" 2>&1 || true
bench_build=${IMPACTDIC_IWYU_BENCH_BUILD:-build/bench}
if [ -f "$bench_build/compile_commands.json" ]; then
  mapfile -t bench_sources < <(find bench -name '*.cc' | sort)
  echo "iwyu: and ${#bench_sources[@]} files of bench/ with the compile commands of $bench_build"
  iwyu_tool -p "$bench_build" -j "$jobs" "${bench_sources[@]}" -- \
    -Xiwyu --mapping_file="$root/.iwyu.imp" -Xiwyu --no_fwd_decls \
    -Xiwyu --check_also="$root/include/*" -Xiwyu --check_also="$root/bench/*" >> "$log" 2>&1 || true
else
  echo "iwyu: bench/ skipped: $bench_build is not configured (cmake --preset bench)"
fi
if [ -n "${IMPACTDIC_IWYU_LOG:-}" ]; then cp "$log" "$IMPACTDIC_IWYU_LOG"; fi  # iwyu's full output

# .def files (X-macro lists, expanded by a header) are not checked, nor asked for. A header is
# reported once per file that includes it: keep each (file, line) once.
report() {  # report KIND: "add" or "remove" lines of our files, as "file: line"
  awk -v kind="$1" -v root="$root/" '
    / should (add|remove) these lines:$/ {
      file = $1; sub(root, "", file)
      ours = index($1, root) == 1 && file ~ /^(src|include|tests|bench)\/.*\.(h|cc)$/
      in_section = ours && $3 == kind
      next
    }
    /^$/ || /^The full include-list/ || /^---/ { in_section = 0; next }
    in_section && !/\.def"/ { sub(/ *\/\/.*/, ""); print file ": " $0 }
  ' "$log" | sort -u
}
errors=$(grep -E '^[^ ]+:[0-9]+:[0-9]+: (fatal )?error:' "$log" || true)
adds=$(report add)
removes=$(report remove)
if [ -n "$removes" ]; then
  echo "iwyu: it would also remove (not enforced; $(wc -l <<< "$removes") lines):"
  echo "$removes"
fi
if [ -n "$errors" ]; then
  echo "$errors" >&2
  echo "iwyu: FAILED: iwyu could not parse some files (above)" >&2
  exit 1
fi
if [ -n "$adds" ]; then
  echo "$adds" >&2
  echo "iwyu: FAILED: $(wc -l <<< "$adds") missing includes (above: file: the line to add)" >&2
  exit 1
fi
echo "iwyu: no missing includes"
