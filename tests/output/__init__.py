# SPDX-License-Identifier: MIT
"""The command line and its outputs: files, exit codes, checkpoints and resumed runs."""
