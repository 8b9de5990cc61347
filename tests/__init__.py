# SPDX-License-Identifier: MIT
"""vpcontact's test suite: one folder per stage (see tests/README.md)."""
