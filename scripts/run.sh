#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Quick start, command 1: set up if needed, then run the main job: the bundled default scene (a
# rigid cylinder pushed into a viscoplastic block, then held) through the command line. Extra
# arguments go to `vpcontact run` (e.g. a scene name or file, --out DIR, -v).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$ROOT"
exec "$VPCONTACT_PYTHON" -m vpcontact run "$@"
