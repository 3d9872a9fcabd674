#!/usr/bin/env bash
# The main-job command of README.md: installs what is missing, builds the release binary and the
# Python module (build/release/python) and runs the whole pipeline on sample_frames/ (outputs in
# results/sample/).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install_deps.sh
cmake --preset release
cmake --build --preset release -j "$(nproc)" --target impactdic impactdic_python
./build/release/src/cli/impactdic run sample_frames/scene.yaml -o results/sample
echo "Outputs are in $(pwd)/results/sample"
