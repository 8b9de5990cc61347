# SPDX-License-Identifier: MIT
"""``python3 -m vpcontact``: the command line (see :mod:`vpcontact.cli`)."""

import sys

from vpcontact.cli import main

if __name__ == "__main__":
    sys.exit(main())
