# SPDX-License-Identifier: MIT
"""vpcontact: quasistatic frictionless contact of rate-type elastic-viscoplastic bodies."""
import os

# dolfinx partitions meshes with PT-Scotch, whose threads make the partition (and so the
# round-off and Krylov iteration counts of a parallel run) change from run to run. One Scotch
# thread per rank gives the same partition every time; a value already in the environment is kept.
os.environ.setdefault("SCOTCH_PTHREAD_NUMBER", "1")

__version__ = "0.1.0"
