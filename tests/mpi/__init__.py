# SPDX-License-Identifier: MIT
"""Tests that launch mpirun or check what several ranks give."""
