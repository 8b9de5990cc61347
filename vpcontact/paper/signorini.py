# SPDX-License-Identifier: MIT
"""The paper's Signorini tests (§4.1.1 in 2-D, §4.1.2 in 3-D): data and problem builders.

Both use E = 1e8 N/m², ν = 0.3, Perzyna's law with σ_Y = √10 N/m² and μ* = 200 N/m²·s, and start
from u_0 = 0, σ_0 = 0 over T = 1 s.

Misprints in the paper, corrected here:

* 3-D traction: the paper prints f_2 = (0, 0, -10t) "if x1 = 0", but x1 = 0 is the clamped face
  Γ1, where a traction does nothing. It acts on the free end face x1 = 3.
* 3-D yield set: the printed K = {(τ11-τ22)² + (τ22-τ33)² + (τ33-τ11)² + 6(τ12²+τ13²+τ23²) ≤ σ_Y²}
  has twice the left side of the standard von Mises set {½(…) + 3(…) ≤ σ_Y²}. ``model="3d"`` uses
  the printed set (default, to reproduce the paper); ``model="3d_standard"`` the standard one.
* 3-D figure: Fig. 4's caption speaks of "the second component ... on the surface x1 = 0"; the
  contact surface is x3 = 0 and the displacement component normal to it is u3, which is plotted.
"""

from __future__ import annotations

import math

import numpy as np
import ufl
from dolfinx import mesh as dmesh
from mpi4py import MPI

from vpcontact.model.constitutive import Elasticity, Perzyna
from vpcontact.solver.loads import Loads, tag_facets
from vpcontact.solver.problem import QuasistaticProblem
from vpcontact.model.signorini import Signorini

YOUNG = 1e8
POISSON = 0.3
SIGMA_Y = math.sqrt(10.0)
MU_STAR = 200.0
T_FINAL = 1.0
CLAMP, TRACTION, CONTACT = 1, 2, 3


def obstacle_2d(x: np.ndarray) -> np.ndarray:
    """Level set of the paper's 2-D obstacle: (x1 - 3)²/900 + (x2 + 3)²/9 - 1 (≤ 0 inside)."""
    return (x[0] - 3.0) ** 2 / 900.0 + (x[1] + 3.0) ** 2 / 9.0 - 1.0


def signorini_2d(n: int = 32, scheme: str = "implicit", degree: int = 1, comm=MPI.COMM_WORLD,
                 petsc_options=None, sigma_y: float = SIGMA_Y,
                 time_scheme: str = "euler", mu_star: float = MU_STAR) -> QuasistaticProblem:
    """§4.1.1: Ω = (0,1)², clamped on top, f_0 = (0, -10t), plane stress, obstacle below.

    ``sigma_y`` and ``mu_star`` default to the paper's (see :func:`signorini_3d`)."""
    mesh = dmesh.create_unit_square(comm, n, n)
    tags = tag_facets(mesh, {
        CLAMP: lambda x: np.isclose(x[1], 1.0),
        TRACTION: lambda x: np.isclose(x[0], 0.0) | np.isclose(x[0], 1.0),
        CONTACT: lambda x: np.isclose(x[1], 0.0)})
    law = Perzyna(Elasticity("plane_stress", YOUNG, POISSON), sigma_y=sigma_y, mu_star=mu_star,
                  scheme=scheme)
    loads = Loads(body_force=lambda x, t: ufl.as_vector([0.0, -10.0 * t]))  # f_2 = 0 on Γ2
    return QuasistaticProblem(mesh, tags, law, clamped_tag=CLAMP, loads=loads,
                              contact=Signorini(CONTACT, obstacle=obstacle_2d), degree=degree,
                              petsc_options=petsc_options, time_scheme=time_scheme)


def signorini_3d(nx: int = 24, ny: int = 8, nz: int = 8, scheme: str = "implicit",
                 model: str = "3d", degree: int = 1, comm=MPI.COMM_WORLD, petsc_options=None,
                 sigma_y: float = SIGMA_Y, mu_star: float = MU_STAR,
                 formulation: str = "displacement", linear: str = "auto") -> QuasistaticProblem:
    """§4.1.2: Ω = (0,3)×(0,1)², clamped at x1 = 0, f_2 = (0,0,-10t) on x1 = 3, g = 0 on x3 = 0.

    ``sigma_y`` and ``mu_star`` default to the paper's; the benchmarks vary them (a larger μ*
    lowers the stiffness contrast k E/μ* of the plastic tangent). The default discretization is
    the paper's (P1 displacements), which locks once the beam flows; ``formulation="mixed"``
    (with ``degree=2``) is the locking-free Taylor–Hood one; ``linear`` picks the linear solver
    (:mod:`vpcontact.linear_solvers`)."""
    mesh = dmesh.create_box(comm, [np.zeros(3), np.array([3.0, 1.0, 1.0])], [nx, ny, nz],
                            dmesh.CellType.tetrahedron)
    tags = tag_facets(mesh, {
        CLAMP: lambda x: np.isclose(x[0], 0.0),
        TRACTION: lambda x: np.isclose(x[0], 3.0),
        CONTACT: lambda x: np.isclose(x[2], 0.0)})
    law = Perzyna(Elasticity(model, YOUNG, POISSON), sigma_y=sigma_y, mu_star=mu_star,
                  scheme=scheme)
    loads = Loads(tractions={TRACTION: lambda x, t: ufl.as_vector([0.0, 0.0, -10.0 * t])})
    return QuasistaticProblem(mesh, tags, law, clamped_tag=CLAMP, loads=loads,
                              contact=Signorini(CONTACT, gap=0.0), degree=degree,
                              petsc_options=petsc_options, formulation=formulation,
                              linear=linear)
