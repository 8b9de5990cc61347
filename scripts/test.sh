#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Quick start, command 2: set up if needed, then run the test suite serially and on 2 MPI ranks.
# Extra arguments go to pytest (e.g. -k kernels, -m "not slow").
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$ROOT"
"$VPCONTACT_PYTHON" -m pytest "$@"
echo "[test] again on 2 MPI ranks (tests not marked serial)"
# each rank gets its own pytest base folder (they would race cleaning a shared one). A failure that
# leaves a rank stuck aborts the job (tests/conftest.py); the time limit is the backstop for any
# other hang.
timeout --kill-after=30 "${VPCONTACT_MPI_TEST_TIMEOUT:-2400}" mpirun -n 2 bash -c 'exec "$0" -m pytest -q -p no:cacheprovider --basetemp="/tmp/vpcontact-pytest-$(id -u)-${OMPI_COMM_WORLD_RANK:-0}" -m "not serial" "$@"' \
  "$VPCONTACT_PYTHON" "$@"
