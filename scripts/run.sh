#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Quick start, command 1: set up if needed, then run the main job on the bundled default case.
# Extra arguments are passed to the demo (e.g. --out DIR).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$ROOT"
exec "$VPCONTACT_PYTHON" demos/normal_compliance_1d.py "$@"
