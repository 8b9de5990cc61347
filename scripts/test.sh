#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Quick start, command 2: set up if needed, then run the test suite serially and on 2 MPI ranks.
# Extra arguments go to pytest (e.g. -k kernels, -m "not slow").
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$ROOT"
"$VPCONTACT_PYTHON" -m pytest "$@"
echo "[test] again on 2 MPI ranks (tests not marked serial)"
mpirun -n 2 "$VPCONTACT_PYTHON" -m pytest -q -p no:cacheprovider -m "not serial" "$@"
