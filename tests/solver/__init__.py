# SPDX-License-Identifier: MIT
"""The solver: SNES (VI) steps, linear solvers and preconditioners, time stepping, hard cases."""
