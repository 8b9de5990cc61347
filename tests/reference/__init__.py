# SPDX-License-Identifier: MIT
"""Test oracles: independent implementations and stored values the tests compare against."""
