#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Idempotent set-up on Debian 12: installs the FEniCSx stack from Debian (and scikit-build-core from
# bookworm-backports), creates .venv (system site packages) and builds vpcontact's C++ module when it
# is missing or older than its sources. Sourced by scripts/run.sh and scripts/test.sh.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
PY=/usr/bin/python3
PACKAGES=(python3-dolfinx-real python3-basix python3-ffcx python3-ufl python3-petsc4py-real
          python3-mpi4py libdolfinx-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest
          python3-matplotlib python3-meshio python3-venv python3-pip openmpi-bin cmake g++ make
          libopenblas0-pthread python3-gmsh python3-hypothesis
          python3-sphinx python3-myst-parser furo)
# Sphinx, MyST and furo build the manual (scripts/docs.sh).
# OpenBLAS replaces Debian's reference BLAS (alternatives): MUMPS factorizations run about 2x faster.
# One BLAS thread per process: the tests and demos run one MPI rank per core.
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"

log() { printf '[setup] %s\n' "$*" >&2; }
as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else
  log "need root or sudo to install Debian packages: $*"; exit 1; fi; }

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
need_skbuild=0
dpkg-query -W -f='${Status}' python3-scikit-build-core 2>/dev/null | grep -q "install ok installed" || need_skbuild=1
if [ ${#missing[@]} -gt 0 ] || [ $need_skbuild -eq 1 ]; then
  log "installing Debian packages: ${missing[*]:-} (scikit-build-core from backports: $need_skbuild)"
  if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
    echo "deb http://deb.debian.org/debian bookworm-backports main" |
      as_root tee /etc/apt/sources.list.d/vpcontact-backports.list >/dev/null
  fi
  as_root apt-get update -qq
  export DEBIAN_FRONTEND=noninteractive
  if [ ${#missing[@]} -gt 0 ]; then
    as_root apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
  if [ $need_skbuild -eq 1 ]; then
    as_root apt-get install -y -qq --no-install-recommends -t bookworm-backports \
      python3-scikit-build-core >/dev/null
  fi
fi

if [ ! -x "$VENV/bin/python" ]; then
  log "creating $VENV (with Debian's site packages)"
  "$PY" -m venv --system-site-packages "$VENV"
fi

# (Re)build the extension module when it is missing or any C++/build file is newer than the stamp.
# The editable install maps each Python module to its file when it is installed, so it is also
# redone when the package's set of modules changes (the stamp holds a hash of their paths).
STAMP="$VENV/.vpcontact-build-stamp"
modules="$(cd "$ROOT" && find vpcontact -name '*.py' | LC_ALL=C sort | sha256sum | cut -d' ' -f1)"
rebuild=0
[ -f "$STAMP" ] || rebuild=1
[ $rebuild -eq 1 ] || [ "$(cat "$STAMP")" = "$modules" ] || rebuild=1
if [ $rebuild -eq 0 ] && [ -n "$(find "$ROOT/cpp_kernels" "$ROOT/CMakeLists.txt" "$ROOT/pyproject.toml" -newer "$STAMP" -print -quit)" ]; then
  rebuild=1
fi
if [ $rebuild -eq 0 ] && ! "$VENV/bin/python" -c "import vpcontact._cpp" 2>/dev/null; then rebuild=1; fi
if [ $rebuild -eq 1 ]; then
  log "building vpcontact (C++ kernels, Release)"
  (cd "$ROOT" && "$VENV/bin/pip" install -q --no-build-isolation --no-deps --no-index -e .)
  echo "$modules" > "$STAMP"
fi

# Open MPI refuses to run as root unless told otherwise (CI machines run as root).
if [ "$(id -u)" -eq 0 ]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
export OMPI_MCA_rmaps_base_oversubscribe=1
export VPCONTACT_PYTHON="$VENV/bin/python"
