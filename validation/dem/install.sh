#!/usr/bin/env bash
# Installs the DEM engine of the validation (docs/validation.md): Debian's LAMMPS (package
# lammps, 20220106, serial binary `lmp`, GRANULAR package included). It is one of the project's
# dependencies (the reduced DEM case runs in CI), so this is scripts/install_deps.sh, which
# installs whatever of them is missing. Run as root (or with sudo) on Debian 12.
set -euo pipefail
bash "$(dirname "$0")/../../scripts/install_deps.sh"
command -v lmp
