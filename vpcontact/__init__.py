# SPDX-License-Identifier: MIT
"""vpcontact: quasistatic frictionless contact of rate-type elastic-viscoplastic bodies.

The subpackages follow a run's data flow:

* :mod:`vpcontact.scene`: a TOML scene file, read, validated and built into a model;
* :mod:`vpcontact.model`: laws σ̇ = E ε(u̇) + G(σ, ε(u)), quadrature state, contact conditions
  and obstacles (UFL terms, with :mod:`vpcontact.kernels` doing the constitutive work in C++);
* :mod:`vpcontact.solver`: the discrete problem, one SNES solve per step (VI mode for Signorini),
  step control;
* :mod:`vpcontact.output`: the time loop with its XDMF, CSV and PNG outputs and ``summary.json``;
* :mod:`vpcontact.studies`: convergence and cost studies; :mod:`vpcontact.paper`: the paper's
  examples with their exact solutions; :mod:`vpcontact.cli`: the command line.
"""
import os

# dolfinx partitions meshes with PT-Scotch, whose threads make the partition (and so the
# round-off and Krylov iteration counts of a parallel run) change from run to run. One Scotch
# thread per rank gives the same partition every time; a value already in the environment is kept.
os.environ.setdefault("SCOTCH_PTHREAD_NUMBER", "1")

__version__ = "0.1.0"
