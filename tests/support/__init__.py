# SPDX-License-Identifier: MIT
"""Helpers shared by the tests (not tests): MPI launching, the flowing beam."""
