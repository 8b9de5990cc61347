# SPDX-License-Identifier: MIT
"""The pieces :class:`~vpcontact.solver.problem.QuasistaticProblem` is built from that need
nothing of it: the Dirichlet parts, the loads' forms, the contact parts, and the checks and
names of its arguments."""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
import ufl
from mpi4py import MPI

from vpcontact.errors import InputError
from vpcontact.solver.dirichlet import Dirichlet, DirichletParts
from vpcontact.solver.loads import Loads, as_vector


def dirichlet_parts(V, facet_tags, clamped_tag: Optional[int], dirichlet: Sequence[Dirichlet],
                    contacts: bool) -> tuple[DirichletParts, list]:
    """The Dirichlet parts (a clamped one first) and the rigid motions they leave free
    (``contacts``: contact parts may hold the body; without them every rigid motion must be
    held here)."""
    mesh = V.mesh
    dim = mesh.topology.dim
    parts = list(dirichlet)
    if clamped_tag is not None:
        clamped = facet_tags.find(clamped_tag)
        if mesh.comm.allreduce(len(clamped), op=MPI.SUM) == 0:
            raise InputError(f"the clamped boundary (tag {clamped_tag}) has no facets: "
                             "meas(Γ1) > 0 is required", key="boundary")
        parts.insert(0, Dirichlet.clamped(clamped_tag, dim))
    if not parts and not contacts:
        raise InputError("no Dirichlet part: meas(Γ1) > 0 is required (a clamped part, or "
                         "prescribed displacements and symmetry planes that hold the body)",
                         key="boundary")
    held = DirichletParts(V, facet_tags, parts)
    free = [] if any(p.all_zero for p in parts) else held.free_rigid_motions()
    if free and not contacts:
        held.check_rigid_motions()  # (raises: nothing else can hold the body)
    return held, free


def load_terms(mesh, loads: Loads, ds, v, time) -> dict:
    """Each load's (f, v) as a UFL form at the time ``time`` (a constant), by "body_force" or
    traction facet tag."""
    dim = mesh.topology.dim
    x = ufl.SpatialCoordinate(mesh)
    terms: dict = {}
    if loads.body_force is not None:
        terms["body_force"] = ufl.dot(as_vector(loads.body_force(x, time), dim), v) * ufl.dx
    for tag, traction in loads.tractions.items():
        terms[tag] = ufl.dot(as_vector(traction(x, time), dim), v) * ds(tag)
    return terms


def contact_parts(laws: dict, u, facet_tags, equilibrium, prescribed: np.ndarray,
                  rotate: Optional[bool], shear: float) -> list:
    """The contact parts of the ``laws`` (part name -> law), in order: a node belongs to the
    first part that reaches it (``prescribed``: the Dirichlet dofs, which none takes)."""
    V = u.function_space
    parts = []
    taken = prescribed
    for name, condition in laws.items():
        try:
            part = condition.part(u, facet_tags, equilibrium, name=name, exclude=taken,
                                  rotate=rotate, shear_modulus=shear)
            # (a compliant part makes its nodes and gaps on first use: asked for here, a
            # bad gap is refused by every process before anything runs)
            _ = part.nodes
        except InputError as err:
            err.part = name
            raise
        parts.append(part)
        taken = np.union1d(taken, _node_dofs(V, part.node_blocks)).astype(np.int32)
    return parts


def check_choices(predictor: str, unstable_steps: str) -> None:
    """Refuse a predictor or an unstable-step policy that does not exist."""
    if predictor not in ("linear", "none"):
        raise InputError(f"predictor must be 'linear' or 'none', got {predictor!r}",
                         key="solver.predictor")
    if unstable_steps not in ("error", "warn"):
        raise InputError(f"unstable_steps must be 'error' or 'warn', got {unstable_steps!r}")


def shear_modulus(law) -> float:
    """G of the law's elasticity (E in 1-D), the body's stiffness scale."""
    return law.elasticity.shear_modulus


def named_contacts(contact) -> dict:
    """The contact argument of :class:`QuasistaticProblem` as a dict part name -> law."""
    if contact is None:
        return {}
    if isinstance(contact, dict):
        return dict(contact)
    if isinstance(contact, (list, tuple)):
        return {f"contact{i + 1}": c for i, c in enumerate(contact)}
    return {"contact": contact}


def _node_dofs(V, blocks: np.ndarray) -> np.ndarray:
    """Every unrolled dof of the nodes ``blocks``."""
    bs = V.dofmap.index_map_bs
    return (np.asarray(blocks, dtype=np.int64)[:, None] * bs + np.arange(bs)).ravel()


def stress_quadrature_degree(mesh, degree: int) -> int:
    """Quadrature degree of the stress: ε(u):ε(v) integrated exactly. On simplices ε of P_p
    displacements has degree p − 1 (one point per cell for P1); on quadrilaterals and hexahedra
    Q_p's gradient keeps degree p in each coordinate, so the rule needs degree 2p (2×2 or 2×2×2
    Gauss points for Q1: one point would leave the hourglass modes without stiffness)."""
    if mesh.ufl_cell().cellname() in ("quadrilateral", "hexahedron"):
        return 2 * degree
    return max(2 * (degree - 1), 1)
