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
# A file whose fingerprint (clang-tidy's version, .clang-tidy, its compile command and preprocessed
# text) was clean before is not linted again (scripts/clang_tidy_files.py); IMPACTDIC_TIDY_CACHE=off
# lints every file.
cache=${IMPACTDIC_TIDY_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/impactdic/clang-tidy}
echo "clang_tidy: $(clang-tidy --version | grep -m1 -o 'version [0-9.]*') over src/ with $jobs jobs (remembered clean results: $cache)"
python3 scripts/clang_tidy_files.py "$build_dir" "$jobs" "$cache"
echo "clang_tidy: clean"
