# SPDX-License-Identifier: MIT
"""The demos, run shortened."""
