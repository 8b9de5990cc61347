# SPDX-License-Identifier: MIT
"""The constitutive kernels (C++ behind vpcontact.kernels) against independent formulations."""
