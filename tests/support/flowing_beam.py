# SPDX-License-Identifier: MIT
"""The solver tests' flowing beam: the paper's 3-D test at its data (mixed P2–P1, linearized
scheme, 6×2×2 cells), pressed into contact and flowing from t = 0 to 0.08 in steps of 0.02."""

from typing import Optional

from vpcontact.paper import signorini as paper
from vpcontact.solver import StepControl, advance


def run(linear: str = "iterative", options: Optional[dict] = None,
        krylov_iterations: Optional[int] = None):
    """Run the beam with the linear solver ``linear`` and the step's PETSc ``options``, at most
    ``krylov_iterations`` per solve of the iterative solver inside SNES VI (None: its default).

    Returns:
        (problem, step reports)
    """
    problem = paper.signorini_3d(6, 2, 2, petsc_options=options, sigma_y=paper.SIGMA_Y,
                                 mu_star=paper.MU_STAR, formulation="mixed", degree=2,
                                 linear=linear, scheme="linearized")
    if krylov_iterations is not None:
        problem.solver.lagged_lu.max_iterations = krylov_iterations
    return problem, list(advance(problem, 0.08, StepControl(0.02)))
