#!/usr/bin/env bash
# Lint: clang-tidy (checks in .clang-tidy) over every source file in src/, with the compile commands
# of a configured build (default build/release). Fails on any warning. Run by scripts/test.sh after
# the release build; alone: bash scripts/clang_tidy.sh [BUILD_DIR].
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=${1:-build/release}
# shellcheck source=scripts/common.sh
source scripts/common.sh
require_tool clang_tidy clang-tidy clang-tidy
require_compile_commands clang_tidy "$build_dir"

jobs=${IMPACTDIC_TIDY_JOBS:-2}
log=$(mktemp)
trap 'rm -f "$log"' EXIT
echo "clang_tidy: $(clang-tidy --version | grep -m1 -o 'version [0-9.]*') over src/ with $jobs jobs"
# --warnings-as-errors='*' makes every finding fail its clang-tidy process (and so xargs).
status=0
find src -name '*.cc' -print0 | sort -z |
  xargs -0 -n 4 -P "$jobs" clang-tidy -p "$build_dir" --quiet --warnings-as-errors='*' \
    > "$log" 2>&1 || status=$?
grep -E '(warning|error):' "$log" | sort -u || true
if [ "$status" -ne 0 ]; then
  echo "clang_tidy: FAILED ($(grep -cE '(warning|error):' "$log" || true) findings; full log above)" >&2
  exit 1
fi
echo "clang_tidy: clean"
