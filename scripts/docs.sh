#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the manual (docs/, Sphinx + MyST Markdown + furo) into docs/_build/html, with warnings as
# errors. Sets up first if needed (scripts/setup.sh). Extra arguments go to sphinx-build.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$ROOT"
"$VPCONTACT_PYTHON" -m sphinx -W --keep-going -b html "$@" docs docs/_build/html
echo "[docs] built: docs/_build/html/index.html"
