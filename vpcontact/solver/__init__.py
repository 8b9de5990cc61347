# SPDX-License-Identifier: MIT
"""Stage 3, the solver: the fully discrete problem and how each time step is solved.

Takes a mesh, a law and contact condition from :mod:`vpcontact.model`, loads and Dirichlet parts;
gives the state (u, σ, ε at quadrature points) step after step:

* :mod:`.problem`: :class:`QuasistaticProblem`, the paper's Problems 2 and 4 (Euler, or BDF2 for
  the constitutive law, :mod:`.bdf2`), with :class:`Loads` and :func:`tag_facets` (:mod:`.loads`);
* :mod:`.dirichlet`: clamped, prescribed-displacement and symmetry parts (:class:`Dirichlet`),
  the rigid-motion check and the support reactions;
* :mod:`.step_solver`: :class:`StepSolver`, one step as a PETSc SNES solve (VI mode for
  Signorini), converged reasons checked after every solve; a thin wrapper of SNES that composes
  what SNES evaluates (:mod:`.assembly`), its own options (:mod:`.step_options`), the
  convergence test (:mod:`.convergence`), the retries of a step built from the nodal terms'
  protocol (:mod:`.retries`), the line-search policy (:mod:`.line_search`), SNES VI's bounds
  (:mod:`.vi_bounds`) and linear solver (:mod:`.vi_solver`);
* :mod:`.vi_linear`: the linear solves inside SNES VI, with factorizations that outlive the
  active set;
* :mod:`.pc`: the iterative solver's preconditioners (p-multigrid, vertex stars, the mixed
  formulation's field split), behind one factory;
* :mod:`.stepping`: step control (halve a failed step, adaptive steps from a local error estimate,
  :mod:`.error_estimate`) and :func:`advance`, the time loop as a generator of accepted steps.
"""

from vpcontact.solver.dirichlet import Dirichlet, DirichletParts
from vpcontact.solver.error_estimate import extrapolation_weights, milne_factor
from vpcontact.solver.loads import Loads, PointLoad, tag_facets
from vpcontact.solver.problem import QuasistaticProblem, StepReport, stress_quadrature_degree
from vpcontact.solver.snes_options import DEFAULT_OPTIONS, reason_name, time_split
from vpcontact.solver.step_solver import StepSolver
from vpcontact.solver.stepping import Cut, StepControl, advance
from vpcontact.solver.near_nullspace import rigid_body_modes
from vpcontact.solver.vi_linear import LaggedDirectSolve, LaggedMultigrid, options_in_database

__all__ = ["advance", "Cut", "DEFAULT_OPTIONS", "Dirichlet", "DirichletParts",
           "extrapolation_weights", "LaggedDirectSolve", "LaggedMultigrid", "Loads",
           "milne_factor", "options_in_database", "PointLoad", "QuasistaticProblem", "reason_name",
           "rigid_body_modes", "StepControl", "StepReport", "StepSolver",
           "stress_quadrature_degree", "tag_facets", "time_split"]
