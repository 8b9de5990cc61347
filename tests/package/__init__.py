# SPDX-License-Identifier: MIT
"""The package as a whole: references in docstrings, process-wide settings."""
