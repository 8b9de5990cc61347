# SPDX-License-Identifier: MIT
"""The linear solver of a step: a direct factorization, or Krylov with a preconditioner that
scales, chosen by the size of the problem.

``direct``: MUMPS (LU, or LDLᵀ inside the VI solver when the matrix is symmetric); robust for
every tangent, but its cost grows like unknowns^1.4–1.5 in 3-D and its memory faster.

``iterative``: for the displacement formulation, GMRES with algebraic multigrid (GAMG, the
rigid-body modes as near null space). For the mixed formulation, FGMRES with a block
preconditioner (PCFIELDSPLIT, Schur complement factorization): one two-level p-multigrid
cycle on the displacement block (Chebyshev–Jacobi or vertex stars on P2, a P1 Galerkin coarse
problem under GAMG: :mod:`vpcontact.solver.pc.p_multigrid`) and, for the Schur complement, the
pressure mass matrix weighted by the current tangent's shear compliance (capped where a thin
zone flows) + 1/K (:meth:`~vpcontact.model.fields.DisplacementPressure.
schur_preconditioner_form`) or, where the vertex stars smooth, their own Schur complement
(:mod:`vpcontact.solver.pc.star_schur`). The displacement block no longer carries the bulk modulus, so
multigrid works on it even where the body flows (where P1 or P2 displacements alone make every
algebraic multigrid fail: the tangent is nearly incompressible). Inside SNES VI the same
preconditioner acts on the full-size matrix M of :class:`~vpcontact.solver.vi_linear.
LaggedMultigrid` (active rows and columns replaced by the identity), rebuilt with every
Jacobian (:data:`REBUILD_WITH_EVERY_JACOBIAN`).

``auto``: iterative from :data:`ITERATIVE_FROM` unknowns on (by formulation), direct below
(see :mod:`vpcontact.linear_solvers` and the README's "Linear solvers").

The preconditioners themselves, their options and their contexts are in
:mod:`vpcontact.solver.pc` (its factory gives the step solver both); this module holds the
Krylov tolerances the step solver aims at and the displacement formulation's options.
"""

from __future__ import annotations

from vpcontact.linear_solvers import ITERATIVE_FROM, LINEAR_SOLVERS, choose  # noqa: F401

#: Relative tolerance of the block-preconditioned Krylov solves of the mixed formulation: an
#: inexact Newton step. Measured on the paper's 3-D test while it flows (t = 0.3–0.4 s, k = 0.01,
#: 1 038 unknowns): 1e-4 takes 49 Newton iterations for 10 steps (MUMPS: 48) with the same
#: contact force to 1e-12, at 56 GMRES iterations per Newton iteration; 1e-9 stalls at about
#: 1e-9 after 300 iterations and the steps are cut 8-fold; 1e-6 needs 115 per Newton iteration.
ITERATIVE_RTOL = 1e-4

#: A step whose Jacobian does not change within it (the linearized scheme, a linear law) is a
#: linear complementarity problem: Newton's only nonlinearity is the contact set. Its Krylov
#: solves inside SNES VI then aim at what the step needs (:func:`step_rtol`): the first loosely
#: (it mainly finds the contact set; the residual after it falls by ~1e-2-1e-3 whatever the
#: tolerance), the next ones to SNES's own target, so the step ends one Newton iteration and
#: one multigrid set-up after the contact set settles. A later solve is probed at
#: STEP_FIRST_RTOL and ends there if its direction crosses a bound, which changes the contact
#: set again (``probe_rtol`` of :class:`~vpcontact.solver.vi_linear.LaggedMultigrid`).
#: Measured on the paper's 3-D test (linearized, t = 0.05-0.08 s, 44 508 unknowns): 3.67 ->
#: 2.67 Newton iterations and 3.87 -> 2.85 s per step (every solve at 1e-10: 2.67 Newton
#: iterations of 42 FGMRES iterations each, slower than at ITERATIVE_RTOL); README, "Aimed
#: Krylov tolerances".
STEP_FIRST_RTOL = 1e-2
#: (the tightest relative tolerance asked of one solve, and the margin below SNES's target)
STEP_RTOL_FLOOR, STEP_RTOL_SAFETY = 1e-8, 0.5


def step_rtol(iteration: int, fnorm: float, target: float) -> float:
    """Relative tolerance of Newton iteration ``iteration``'s Krylov solve in a step with a fixed
    Jacobian, at residual norm ``fnorm``, SNES converging at ``target``: STEP_FIRST_RTOL at the
    first, then ``STEP_RTOL_SAFETY * target / fnorm`` within [STEP_RTOL_FLOOR, ITERATIVE_RTOL]."""
    if iteration == 0:
        return STEP_FIRST_RTOL
    wanted = STEP_RTOL_SAFETY * target / fnorm if fnorm > 0.0 else ITERATIVE_RTOL
    return min(ITERATIVE_RTOL, max(STEP_RTOL_FLOOR, wanted))


#: Inside SNES VI, the lagged solver (:class:`~vpcontact.solver.vi_linear.LaggedMultigrid`)
#: rebuilds the block preconditioner with every Jacobian (every Newton iteration) instead of
#: keeping it while its iterations stay within 1.5× a fresh one's: the plastic tangent moves
#: between Newton iterations and a kept hierarchy does not follow. Measured on the paper's
#: 3-D test (t = 0.3 → 0.4 s, k = 0.01), FGMRES iterations per Newton iteration at 1 038 /
#: 2 953 / 6 400 unknowns: 56 / 71 / 99 kept → 40 / 42 / 50 rebuilt.
REBUILD_WITH_EVERY_JACOBIAN = True

#: The same for the displacement formulation.
DISPLACEMENT_OPTIONS = {
    "ksp_type": "gmres",
    "ksp_rtol": 1e-8,
    "ksp_max_it": 1000,
    "ksp_gmres_restart": 100,
    "pc_type": "gamg",
    "pc_gamg_reuse_interpolation": "false",
}
