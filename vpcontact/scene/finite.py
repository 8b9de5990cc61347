# SPDX-License-Identifier: MIT
"""Every expression of a scene finite where and when it is used, checked on the mesh before the
first step (a NaN load would otherwise show up as a step that "did not converge")."""

from __future__ import annotations

import math

import numpy as np
from dolfinx import fem

from vpcontact.scene.files import Scene


#: Largest number of times at which time-dependent expressions are checked.
MAX_CHECKED_TIMES = 257


def check_finite(scene: Scene, mesh, part_tags, facet_tags) -> None:
    """Every expression of the scene finite where and when it is used: loads, tractions,
    prescribed displacements, gaps and initial values at the vertices they act on, at t = 0 and
    at the step times (at most MAX_CHECKED_TIMES of them, evenly spread); point forces and an
    obstacle's motion and rotation at those times. The first offender is reported with its place in the
    scene file, a point and a time, before anything is solved (collective)."""
    V = fem.FunctionSpace(mesh, ("Lagrange", 1))
    x_all = V.tabulate_dof_coordinates()[:V.dofmap.index_map.size_local].T
    fdim = mesh.topology.dim - 1

    def on_part(name):
        dofs = fem.locate_dofs_topological(V, fdim, facet_tags.find(part_tags[name]))
        return x_all[:, dofs[dofs < x_all.shape[1]]]

    steps = max(1, int(math.ceil(scene.time.T / scene.time.k - 1e-9)))
    times = np.unique(np.concatenate([[0.0], np.linspace(0.0, scene.time.T,
                                                         min(steps, MAX_CHECKED_TIMES - 1) + 1)]))
    checks = [("loads.body_force", scene.loads.body_force, x_all),
              ("initial.u0", scene.initial.u0, x_all),
              ("initial.sigma0", scene.initial.sigma0, x_all)]
    for name, part in scene.boundaries.items():
        if part.traction is not None:
            checks.append((f"boundary.{name}.traction", part.traction, on_part(name)))
        if part.displacement is not None:
            checks.append((f"boundary.{name}.displacement", part.displacement, on_part(name)))
    single = []  # keys of single expressions (no component index)
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
                bad = np.flatnonzero(~np.isfinite(values))
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
        raise scene.error(key, f"{source!r} evaluates to {value} {where}t = {t:g}; every "
                               "expression must be finite wherever and whenever it is used")
