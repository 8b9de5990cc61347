# SPDX-License-Identifier: MIT
"""Stage 5, studies: many runs of one scene, measured against an exact or reference solution.

``vpcontact study convergence SCENE`` (error against h, k or both, against an exact solution
or estimated from successive runs by Richardson; observed orders and error constants) and
``vpcontact study cost SCENE`` (error against wall time and dofs × steps, with the Pareto
front). :mod:`.runs` varies the scene, runs it and measures errors; :mod:`.report`
writes the tables (CSV, Markdown) and log–log figures (PNG).
"""

from vpcontact.studies import report
from vpcontact.studies.runs import (EXACT, REFINEMENTS, Grid, Method, Run, convergence, cost,
                                    default_methods, exact_solution, execute, fitted_order,
                                    make_grid, measure, new_run, pareto_front, reference_samples,
                                    richardson, variant_scene)

__all__ = ["EXACT", "REFINEMENTS", "Grid", "Method", "Run", "convergence", "cost",
           "default_methods", "exact_solution", "execute", "fitted_order", "make_grid", "measure",
           "new_run", "pareto_front", "reference_samples", "report", "richardson", "variant_scene"]
