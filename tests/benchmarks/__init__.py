# SPDX-License-Identifier: MIT
"""The benchmark scripts under bench/: their command lines and fits."""
