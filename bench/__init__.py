# SPDX-License-Identifier: MIT
"""vpcontact's maintained benchmarks (see bench/README.md). Each script runs as a file,
``python bench/NAME.py``, or as a module, ``python -m bench.NAME``; the tests import them as
``bench.NAME``."""
