#!/usr/bin/env bash
# Installs the optional DEM engine of the validation (docs/validation.md): Debian's LAMMPS
# (package lammps, 20220106, serial binary `lmp`, GRANULAR package included). Not needed by the
# main build or CI. Run as root on Debian 12.
set -euo pipefail
if command -v lmp >/dev/null 2>&1; then
  echo "lmp already installed: $(command -v lmp)"
  exit 0
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends lammps
command -v lmp
