# SPDX-License-Identifier: MIT
"""Every expression of a scene finite where and when it is used, checked on the mesh before the
first step (a NaN load would otherwise show up as a step that "did not converge"): at the mesh's
vertices (:func:`check_finite`), at the displacement's nodes once the problem is built (P2: the
edges' midpoints too), and the loads where they are integrated, their quadrature points
(:func:`check_assembled_loads`): ``sqrt(abs(x[0] - 0.125) - 0.1)`` is finite at every vertex of
a mesh of step 0.25 and NaN at quadrature points between them."""

from __future__ import annotations

import math

import numpy as np
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from vpcontact.model.extent import node_coordinates
from vpcontact.scene.files import Scene


#: Largest number of times at which time-dependent expressions are checked.
MAX_CHECKED_TIMES = 257


def _checked_times(scene: Scene) -> np.ndarray:
    """t = 0 and the step times (at most MAX_CHECKED_TIMES of them, evenly spread)."""
    steps = max(1, int(math.ceil(scene.time.T / scene.time.k - 1e-9)))
    return np.unique(np.concatenate([[0.0], np.linspace(0.0, scene.time.T,
                                                        min(steps, MAX_CHECKED_TIMES - 1) + 1)]))


def check_finite(scene: Scene, mesh, part_tags, facet_tags, nodes=None) -> None:
    """Every expression of the scene finite where and when it is used: loads, tractions,
    prescribed displacements, gaps and initial values at the vertices they act on (or at the
    nodes of the function space ``nodes``), at t = 0 and at the step times (at most
    MAX_CHECKED_TIMES of them, evenly spread); point forces and an obstacle's motion and
    rotation at those times. The first offender is reported with its place in the scene file,
    a point and a time, before anything is solved (collective)."""
    V = nodes if nodes is not None else fem.FunctionSpace(mesh, ("Lagrange", 1))
    x_all = node_coordinates(V)[:V.dofmap.index_map.size_local].T
    fdim = mesh.topology.dim - 1

    def on_part(name):
        dofs = fem.locate_dofs_topological(V, fdim, facet_tags.find(part_tags[name]))
        return x_all[:, dofs[dofs < x_all.shape[1]]]

    times = _checked_times(scene)
    checks = [("loads.body_force", scene.loads.body_force, x_all),
              ("initial.u0", scene.initial.u0, x_all),
              ("initial.sigma0", scene.initial.sigma0, x_all)]
    for name, part in scene.boundaries.items():
        if part.traction is not None:
            checks.append((f"boundary.{name}.traction", part.traction, on_part(name)))
        if part.displacement is not None:
            checks.append((f"boundary.{name}.displacement", part.displacement, on_part(name)))
    single = []  # keys of single expressions (no component index)
    nonnegative = []  # keys of expressions that must also be >= 0 (a Tresca threshold)
    for i, contact in enumerate(scene.contacts):
        where = scene.contact_key(i)
        if contact.gap is not None:
            checks.append((f"{where}.gap", (contact.gap,), on_part(contact.boundary)))
            single.append(f"{where}.gap")
        if contact.motion is not None:
            checks.append((f"{where}.motion", contact.motion, np.zeros((3, 1))))
        if contact.force is not None:
            checks.append((f"{where}.force", contact.force, np.zeros((3, 1))))
        if contact.friction is not None and contact.friction.threshold is not None:
            checks.append((f"{where}.friction.threshold", (contact.friction.threshold,),
                           on_part(contact.boundary)))
            single.append(f"{where}.friction.threshold")
            nonnegative.append(f"{where}.friction.threshold")
        if contact.rotation is not None:
            checks.append((f"{where}.rotation.angle", (contact.rotation.angle,),
                           np.zeros((3, 1))))
            single.append(f"{where}.rotation.angle")
    for i, point in enumerate(scene.loads.point):
        checks.append((f"loads.point[{i}].force", point.force, np.zeros((3, 1))))
    found = None
    for path, exprs, x in checks:
        for j, e in enumerate(exprs):
            if e is None or (e.is_constant and np.isfinite(e.value())):
                continue
            for t in (times if e.depends_on_time else times[:1]):
                values = e.numpy(x, t) if x.shape[1] else np.zeros(0)
                bad = np.flatnonzero(~np.isfinite(values) |
                                     ((values < 0) if path in nonnegative else False))
                if len(bad):
                    key = (path if len(exprs) == 1 and path in single else f"{path}[{j}]")
                    point = ((x[:scene.dim, bad[0]] + 0.0).round(12).tolist()
                             if "x" in e.names else None)
                    found = (key, e.source, float(values[bad[0]]), point, float(t))
                    break
            if found:
                break
        if found:
            break
    found = next((f for f in mesh.comm.allgather(found) if f is not None), None)
    if found is not None:
        key, source, value, point, t = found
        where = f"at x = {point}, " if point is not None else "at "
        rule = ("must be finite and >= 0 at every node of its part (a friction threshold)"
                if math.isfinite(value) else
                "every expression must be finite wherever and whenever it is used")
        raise scene.error(key, f"{source!r} evaluates to {value:g} {where}t = {t:g}; {rule}")


def check_assembled_loads(scene: Scene, problem, part_tags, facet_tags) -> None:
    """The body force and tractions that depend on x finite where they are integrated: each
    one's load vector (f, v), assembled at the checked times (:func:`check_finite`), is finite.
    The first offender is reported with its place in the scene file, the node next to the
    quadrature point and a time, before anything is solved (collective)."""
    fdim = problem.mesh.topology.dim - 1
    candidates = [("loads.body_force", "body_force", scene.loads.body_force)]
    candidates += [(f"boundary.{name}.traction", part_tags[name], part.traction)
                   for name, part in scene.boundaries.items()
                   if part.kind == "traction" and part.traction is not None]
    times = _checked_times(scene)
    V = problem.V
    nodes = node_coordinates(V)
    bs = V.dofmap.index_map_bs
    found = None
    saved = float(problem.time.value)
    try:
        for path, label, exprs in candidates:
            if label not in problem.load_terms or not any("x" in e.names for e in exprs):
                continue  # (an expression of t alone has its vertices' values everywhere)
            form = fem.form(problem.load_terms[label])
            on = (np.arange(0) if label == "body_force" else  # (collective: on every process)
                  fem.locate_dofs_topological(V, fdim, facet_tags.find(label)))
            vec = fem_petsc.create_vector(form)
            for t in (times if any(e.depends_on_time for e in exprs) else times[:1]):
                problem.time.value = t
                with vec.localForm() as local:
                    local.set(0.0)
                fem_petsc.assemble_vector(vec, form)
                vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
                bad = np.flatnonzero(~np.isfinite(vec.array))
                if found is None and len(bad):  # (every process assembles every time)
                    # (NaN times a test function that is 0 there is NaN: the cells' other
                    # nodes too; show one on the part)
                    bad = np.concatenate([bad[np.isin(bad // bs, on)], bad])
                    node, j = divmod(int(bad[0]), bs)
                    expr = exprs[j] if len(exprs) > 1 else exprs[0]
                    key = f"{path}[{j}]" if len(exprs) > 1 else f"{path}[0]"
                    point = (nodes[node, :scene.dim] + 0.0).round(12).tolist()
                    found = (key, expr.source, point, float(t))
            vec.destroy()
    finally:
        problem.time.value = saved
    found = next((f for f in problem.mesh.comm.allgather(found) if f is not None), None)
    if found is not None:
        key, source, point, t = found
        raise scene.error(key, f"{source!r} is not finite at quadrature points next to x = "
                               f"{point} at t = {t:g}, where the load is integrated (its values "
                               "at the mesh's vertices are finite); every expression must be "
                               "finite wherever and whenever it is used")
