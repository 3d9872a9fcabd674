#!/usr/bin/env bash
# The test command of README.md (and of .ci/run): installs what is missing, builds with warnings as
# errors and runs the whole test suite, lints src/ with clang-tidy, then builds and runs it again under AddressSanitizer+UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install_deps.sh

jobs=$(nproc)
echo "== Release build (warnings are errors) =="
cmake --preset release -DIMPACTDIC_WERROR=ON -DIMPACTDIC_BUILD_TESTS=ON
cmake --build --preset release -j "$jobs"
ctest --preset release -j "$jobs"

echo "== clang-tidy (.clang-tidy) over src/ =="
bash scripts/clang_tidy.sh build/release

echo "== AddressSanitizer + UBSan build =="
cmake --preset asan -DIMPACTDIC_WERROR=ON -DIMPACTDIC_BUILD_TESTS=ON
cmake --build --preset asan -j "$jobs"
ctest --preset asan -j "$jobs"
