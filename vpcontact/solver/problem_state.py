# SPDX-License-Identifier: MIT
"""Checkpoints of a :class:`~vpcontact.solver.problem.QuasistaticProblem`: what continues a run
exactly — u and the other fields, the quadrature-point state, the law's internal variables, the
predictor's and the time scheme's history, each contact part's state and arrays, the step
solver's, and for a body held by its contacts the stabilising spring's anchor and force
scale. The arrays keep the names of the files written before (``u``, ``stress``, …,
``_u_prev``, ``bdf2_w_prev``, ``contact<i>_…``, ``solver_…``), so that those still resume."""

from __future__ import annotations

import numpy as np

from vpcontact.errors import InputError
from vpcontact.model.contact import merged_bounds


def checkpoint(problem) -> tuple[dict, dict]:
    """(scalars, arrays): the state of ``problem`` at the last accepted step — u, the
    quadrature-point stress, strain and tangent, the law's own internal variables, the predictor's and BDF2's
    history, the time and step, the contact flag, and the solver's (see
    :meth:`StepSolver.checkpoint`). Arrays are this rank's local values (ghosts included)."""
    st = problem.state
    arrays = {"u": problem.u.x.array, "stress": st.stress.x.array,
              "stress_old": st.stress_old.x.array, "strain_old": st.strain_old.x.array,
              "tangent": st.tangent.x.array}
    arrays.update({f"field_{k}": f.x.array for k, f in problem.fields.saved_functions().items()})
    arrays.update(problem.history.arrays())
    if hasattr(problem.law, "internal_state"):
        arrays.update({f"law_{k}": v for k, v in problem.law.internal_state().items()})
    arrays.update(problem.scheme.arrays())
    for i, part in enumerate(problem.contacts):
        arrays.update({f"contact{i}_{k}": v for k, v in part.arrays().items()})
    solver_flags, solver_arrays = problem.solver.checkpoint()
    arrays.update({f"solver_{k}": v for k, v in solver_arrays.items()})
    if problem.held is not None:  # the stabilising spring's anchor (a body held by contacts)
        arrays["held_position"] = problem.held.held.x.array
    scalars = {"time": float(problem.time.value), "dt": problem.dt,
               "step_index": problem.step_index, **problem.history.scalars(),
               "contact_active": problem._contact_active, "tangent_key": problem._tangent_key,
               **problem.scheme.scalars(),
               "solver": solver_flags, "contacts": [p.state() for p in problem.contacts],
               "held": None if problem.held is None else problem.held.state()}
    return scalars, {k: np.asarray(v) for k, v in arrays.items()}


def restore(problem, scalars: dict, arrays: dict) -> None:
    """Continue ``problem`` from :func:`checkpoint` (same mesh, partition and scene)."""
    st = problem.state
    saved = [(f"field_{k}", f) for k, f in problem.fields.saved_functions().items()]
    for name, function in [("u", problem.u), ("stress", st.stress), ("stress_old", st.stress_old),
                           ("strain_old", st.strain_old), ("tangent", st.tangent)] + saved:
        if name not in arrays:
            raise InputError(f"the checkpoint has no {name}: it was written by another "
                             "formulation")
        if arrays[name].shape != function.x.array.shape:
            raise InputError(f"the checkpoint's {name} has {arrays[name].size} values here, "
                             f"the problem {function.x.array.size}: another mesh or partition")
        function.x.array[:] = arrays[name]
    problem.history.restore(scalars, arrays, len(problem.fields.functions) - 1)
    law_state = {k[4:]: v for k, v in arrays.items() if k.startswith("law_")}
    if law_state:
        problem.law.set_internal_state(law_state)
    problem.scheme.restore(scalars, arrays)
    problem.time.value = scalars["time"]
    problem.dt = scalars["dt"]
    problem.step_index = int(scalars["step_index"])
    problem._contact_active = bool(scalars["contact_active"])
    key = scalars["tangent_key"]
    problem._tangent_key = tuple(key) if key is not None else None
    if problem.dirichlet.moving:
        problem.dirichlet.update(scalars["time"])
    for i, (part, state) in enumerate(zip(problem.contacts, scalars.get(
            "contacts", [{}] * len(problem.contacts)))):
        prefix = f"contact{i}_"
        part.restore(state, scalars["time"], {k[len(prefix):]: v for k, v in arrays.items()
                                              if k.startswith(prefix)})
    if problem.held is not None:  # (a checkpoint written before it kept no anchor: u's)
        problem.held.restore(scalars.get("held") or {},
                             arrays.get("held_position", problem.u.x.array))
    if problem.variables is not None:
        problem.variables.refresh()
    if any(p.moving for p in problem.contacts):
        problem.solver.update_bounds(*merged_bounds(problem.u, problem.contacts))
    problem.solver.restore(scalars["solver"], {k[7:]: v for k, v in arrays.items()
                                            if k.startswith("solver_")})
