# SPDX-License-Identifier: MIT
"""vpcontact: quasistatic frictionless contact of rate-type elastic-viscoplastic bodies."""
__version__ = "0.1.0"
