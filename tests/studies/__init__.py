# SPDX-License-Identifier: MIT
"""Studies (convergence, cost) and the validation studies against closed forms (Hertz, Lamé)."""
