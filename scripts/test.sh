#!/usr/bin/env bash
# The test command of README.md (and of .ci/run): installs what is missing, builds with warnings as
# errors and runs the whole test suite, lints src/ with clang-tidy, then builds and runs it again under AddressSanitizer+UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install_deps.sh

# Tests that read the public benchmark data in ../shared/data fail, instead of skipping, when it is
# absent (tests/core/shared_data.h); IMPACTDIC_REQUIRE_SHARED_DATA=0 bash scripts/test.sh skips them.
export IMPACTDIC_REQUIRE_SHARED_DATA="${IMPACTDIC_REQUIRE_SHARED_DATA:-1}"

# ccache (installed by install_deps.sh, used by CMakeLists.txt's IMPACTDIC_CCACHE): paths under the
# checkout hashed relative to it and the build folder left out, so a fresh clone in another folder
# (as CI's) reuses the objects of an earlier build of the same sources; the tests' precompiled
# header is cached too (no source uses __DATE__ or __TIME__).
export CCACHE_BASEDIR="$PWD"
export CCACHE_NOHASHDIR=1
export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}"
if command -v ccache > /dev/null 2>&1; then ccache --zero-stats > /dev/null; fi

jobs=$(nproc)
echo "== Release build (warnings are errors), $(date -u +%T) UTC =="
cmake --preset release -DIMPACTDIC_WERROR=ON -DIMPACTDIC_BUILD_TESTS=ON
cmake --build --preset release -j "$jobs"
ctest --preset release -j "$jobs"

echo "== clang-tidy (.clang-tidy) over src/, $(date -u +%T) UTC =="
bash scripts/clang_tidy.sh build/release

echo "== AddressSanitizer + UBSan build, $(date -u +%T) UTC =="
cmake --preset asan -DIMPACTDIC_WERROR=ON -DIMPACTDIC_BUILD_TESTS=ON
cmake --build --preset asan -j "$jobs"
if ! ctest --preset asan -j "$jobs"; then
  # LeakSanitizer's own stop-the-world tracer crashes now and then at a process's exit ("Tracer
  # caught signal 11 ... LeakSanitizer has encountered a fatal error"; google/sanitizers#1353):
  # a failure of the sanitizer, not a finding. Those tests, and only when every failure is one,
  # run once more; a leak report, a test failure or a second crash fails CI.
  if bash scripts/lsan_tracer_crashes_only.sh build/asan; then
    echo "== Re-running the tests that failed by LeakSanitizer's tracer crash only =="
    ctest --preset asan --rerun-failed
  else
    exit 1
  fi
fi
if command -v ccache > /dev/null 2>&1; then
  echo "== ccache, this run's compiles =="
  ccache --show-stats
fi
echo "== Done, $(date -u +%T) UTC =="
