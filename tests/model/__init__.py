# SPDX-License-Identifier: MIT
"""The model: laws, formulations, contact and friction terms, against closed forms."""
