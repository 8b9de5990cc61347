# SPDX-License-Identifier: MIT
"""Regression guards: the bundled scenes' summaries against stored values."""
