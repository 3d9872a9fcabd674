#!/usr/bin/env bash
# Installs the Debian 12 packages impactdic needs, and nothing when all are present (idempotent).
# Run as root (or with sudo available). Used by both README commands.
set -euo pipefail

PACKAGES=(
  cmake ninja-build g++ pkg-config git          # toolchain
  libopencv-dev                                 # OpenCV 4.6: core imgproc imgcodecs videoio calib3d
  libopencv-contrib-dev                         # OpenCV 4.6 contrib: aruco (ChArUco calibration boards)
  libeigen3-dev                                 # Eigen 3.4
  libhdf5-dev                                   # HDF5 1.10 with the C++ API
  zlib1g-dev                                    # zlib (greyscale PNG frames; HDF5 uses it too)
  libtbb-dev                                    # oneTBB 2021
  libgtest-dev libgmock-dev                     # GoogleTest 1.12
  libbenchmark-dev                              # Google Benchmark 1.7 (bench/, built on request)
  libcli11-dev libyaml-cpp-dev libspdlog-dev libfmt-dev
  gnuplot-nox                                   # figures (PNG through gnuplot's cairo/png terminal)
  python3-h5py                                  # tests check that h5py opens our files
  clang-tidy                                    # lint (.clang-tidy), run by scripts/test.sh
  ccache                                        # compiler cache: a fresh clone reuses earlier objects (scripts/test.sh)
  python3-numpy                                 # bench/dic_challenge.py (and its tests)
  python3-meshio                                # tests: a real XDMF reader opens results.xdmf
  python3-matplotlib                            # tests: the h5py example of docs/python.md
  python3-dev pybind11-dev                      # the Python module (src/python; docs/python.md)
  python3-pytest python3-xarray                 # its tests (tests/python) and to_xarray()
  python3-nbconvert python3-ipykernel           # CI executes docs/python_sample14.ipynb
  python3-pil                                   # bench/python_overhead.py reads the pair
  lammps                                        # DEM validation (`lmp`; tests/validation, docs/validation.md)
  slurm-wlm munge                               # a one-node Slurm for the job-array test (label slurm; docs/campaign.md)
)

# shellcheck source=scripts/common.sh
source "$(dirname "$0")/common.sh"
install_missing_packages install_deps "${PACKAGES[@]}"
