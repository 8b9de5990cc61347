# SPDX-License-Identifier: MIT
"""Hertz contact: closed forms, Gmsh geometries refined near the contact, and measurements.

Closed forms (E* = E/(1 − ν²) for an elastic body on a rigid flat, the body's own E* for a rigid
indenter on an elastic half-space):

* cylinder of radius R, plane strain, force P per unit length: half-width a = √(4PR/(πE*)),
  peak pressure p0 = 2P/(πa), p(x) = p0 √(1 − x²/a²);
* sphere of radius R, force P: contact radius a = (3PR/(4E*))^(1/3), p0 = 3P/(2πa²),
  p(r) = p0 √(1 − r²/a²), approach δ = a²/R, i.e. P = (4/3) E* √R δ^(3/2).

For the 2-D cylinder the approach δ is not fixed by Hertz alone (it depends logarithmically on the
bodies' far-field size), so 2-D checks use P, a and p0 only.

Geometries (Gmsh's OpenCASCADE kernel, written as .msh on rank 0):

* :func:`cylinder_msh`: the quarter x ≥ 0 of a disc of radius R touching y = 0 at the origin,
  cut at its centre line y = R (loaded there); the arc is split at ``contact_angle`` from the
  bottom into the contact arc and a free arc, so that every ray along a contact normal meets the
  plane. Size h_contact within 0.1 R of the origin, growing to 0.1 R.
* :func:`sphere_msh`: the quarter x, y ≥ 0 of the lower half of a ball (radius R, touching z = 0
  at the origin), cut at z = R; symmetry planes x = 0 and y = 0.
* :func:`block_msh`: the quarter of a block to be indented at the origin of its top face.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from mpi4py import MPI

from vpcontact.scene.gmsh_files import gmsh_session

#: Physical tags of the generated meshes.
BODY, CONTACT, TOP, SYMMETRY_X, SYMMETRY_Y, FREE = 1, 1, 2, 3, 4, 5


def cylinder_2d(P: float, R: float, E_star: float) -> tuple[float, float]:
    """(a, p0) of a cylinder pressed with P per unit length."""
    a = math.sqrt(4.0 * P * R / (math.pi * E_star))
    return a, 2.0 * P / (math.pi * a)


def sphere_3d(P: float, R: float, E_star: float) -> tuple[float, float]:
    """(a, p0) of a sphere pressed with P."""
    a = (3.0 * P * R / (4.0 * E_star)) ** (1.0 / 3.0)
    return a, 3.0 * P / (2.0 * math.pi * a * a)


def sphere_force(delta: float, R: float, E_star: float) -> float:
    """Hertz's force P = (4/3) E* √R δ^(3/2) at approach δ."""
    return 4.0 / 3.0 * E_star * math.sqrt(R) * delta ** 1.5


def _size_field(gmsh, h_contact: float, h_far: float, radius: float) -> None:
    """Element size h_contact within ``radius`` of the origin, growing linearly to h_far."""
    point = gmsh.model.occ.addPoint(0.0, 0.0, 0.0)
    gmsh.model.occ.synchronize()
    gmsh.model.mesh.field.add("Distance", 1)
    gmsh.model.mesh.field.setNumbers(1, "PointsList", [point])
    gmsh.model.mesh.field.add("Threshold", 2)
    gmsh.model.mesh.field.setNumber(2, "InField", 1)
    gmsh.model.mesh.field.setNumber(2, "SizeMin", h_contact)
    gmsh.model.mesh.field.setNumber(2, "SizeMax", h_far)
    gmsh.model.mesh.field.setNumber(2, "DistMin", radius)
    gmsh.model.mesh.field.setNumber(2, "DistMax", radius + 10 * h_far)
    gmsh.model.mesh.field.setAsBackgroundMesh(2)
    for option in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints",
                   "Mesh.MeshSizeFromCurvature"):
        gmsh.option.setNumber(option, 0)


@contextmanager
def _gmsh_model(name: str, path: Path, dim: int, comm):
    """A Gmsh model on rank 0 (None elsewhere), meshed in ``dim`` and written to ``path`` when
    the block ends; every rank returns once the file is there."""
    try:
        with gmsh_session(comm) as gmsh:
            if gmsh is not None:
                gmsh.model.add(name)
            yield gmsh
            if gmsh is not None:
                gmsh.model.mesh.generate(dim)
                gmsh.write(str(path))
    finally:
        comm.barrier()


def cylinder_msh(path: Path, R: float = 1.0, h_contact: float = 0.01,
                 contact_angle: float = math.radians(30.0), refine: float = 0.25,
                 comm=MPI.COMM_WORLD) -> Path:
    """Write the 2-D quarter cylinder (tags: CONTACT arc, FREE arc, TOP, SYMMETRY_X)."""
    with _gmsh_model("cylinder", path, 2, comm) as gmsh:
        if gmsh is not None:
            occ = gmsh.model.occ
            centre = occ.addPoint(0.0, R, 0.0)
            bottom = occ.addPoint(0.0, 0.0, 0.0)
            split = occ.addPoint(R * math.sin(contact_angle), R * (1 - math.cos(contact_angle)), 0)
            side = occ.addPoint(R, R, 0.0)
            arc_contact = occ.addCircleArc(bottom, centre, split)
            arc_free = occ.addCircleArc(split, centre, side)
            top = occ.addLine(side, centre)
            axis = occ.addLine(centre, bottom)
            loop = occ.addCurveLoop([arc_contact, arc_free, top, axis])
            surface = occ.addPlaneSurface([loop])
            occ.synchronize()
            gmsh.model.addPhysicalGroup(2, [surface], BODY)
            gmsh.model.addPhysicalGroup(1, [arc_contact], CONTACT)
            gmsh.model.addPhysicalGroup(1, [arc_free], FREE)
            gmsh.model.addPhysicalGroup(1, [top], TOP)
            gmsh.model.addPhysicalGroup(1, [axis], SYMMETRY_X)
            _size_field(gmsh, h_contact, 0.1 * R, refine * R)
    return path


def sphere_msh(path: Path, R: float = 1.0, h_contact: float = 0.02,
               contact_angle: float = math.radians(30.0), refine: float = 0.25,
               comm=MPI.COMM_WORLD) -> Path:
    """Write the 3-D quarter half-ball (tags: CONTACT cap, FREE, TOP, SYMMETRY_X, SYMMETRY_Y)."""
    with _gmsh_model("sphere", path, 3, comm) as gmsh:
        if gmsh is not None:
            occ = gmsh.model.occ
            ball = occ.addSphere(0.0, 0.0, R, R)
            box = occ.addBox(0.0, 0.0, 0.0, R, R, R)
            body, _ = occ.intersect([(3, ball)], [(3, box)])
            z_cut = R * (1.0 - math.cos(contact_angle))
            cutter = occ.addRectangle(0.0, 0.0, z_cut, R, R)  # splits the cap off the body
            occ.fragment(body, [(2, cutter)])
            occ.synchronize()
            volumes = [tag for d, tag in gmsh.model.getEntities(3)]
            gmsh.model.addPhysicalGroup(3, volumes, BODY)
            groups = {CONTACT: [], FREE: [], TOP: [], SYMMETRY_X: [], SYMMETRY_Y: []}
            for _, tag in gmsh.model.getEntities(2):
                x, y, z = occ.getCenterOfMass(2, tag)
                if abs(x) < 1e-9:
                    groups[SYMMETRY_X].append(tag)
                elif abs(y) < 1e-9:
                    groups[SYMMETRY_Y].append(tag)
                elif abs(z - R) < 1e-9:
                    groups[TOP].append(tag)
                elif abs(z - z_cut) < 1e-9 and gmsh.model.getType(2, tag) == "Plane":
                    continue  # the cut between the two volumes, and the cutter's rest
                elif z < z_cut:
                    groups[CONTACT].append(tag)
                else:
                    groups[FREE].append(tag)
            for group, tags in groups.items():
                gmsh.model.addPhysicalGroup(2, tags, group)
            _size_field(gmsh, h_contact, 0.15 * R, refine * R)
    return path


def block_msh(path: Path, L: float = 1.0, H: float = 1.0, h_contact: float = 0.02,
              refine: float = 0.15, comm=MPI.COMM_WORLD) -> Path:
    """Write the quarter block [0, L]² × [−H, 0] to be indented at the origin of its top face
    (size h_contact within ``refine`` of the origin, growing to 0.15 L); facet groups by the
    plane they lie on are not needed (tag its parts with :func:`~vpcontact.solver.tag_facets`)."""
    with _gmsh_model("block", path, 3, comm) as gmsh:
        if gmsh is not None:
            box = gmsh.model.occ.addBox(0.0, 0.0, -H, L, L, H)
            gmsh.model.occ.synchronize()
            gmsh.model.addPhysicalGroup(3, [box], BODY)
            _size_field(gmsh, h_contact, 0.15 * L, refine)
    return path


def read_msh(path: Path, dim: int, comm=MPI.COMM_WORLD):
    """(mesh, facet tags) of a .msh file written by this module."""
    from dolfinx.io import gmshio
    with gmsh_session(comm) as gmsh:
        if gmsh is not None:
            gmsh.merge(str(path))
        mesh, _, facets = gmshio.model_to_mesh(gmsh.model if gmsh is not None else None, comm,
                                               0, gdim=dim)
    return mesh, facets


@dataclass
class ContactProfile:
    """The measured contact state: total force, nodal pressures and where contact is."""

    force: float               # total normal force (of the modelled part of the body)
    radii: np.ndarray          # distance of each contact node from the first contact point
    pressure: np.ndarray       # nodal pressure -σ_ν ≥ 0
    active: np.ndarray         # nodes in contact
    half_width: float          # a: midway between the last active and the first free node
    facet: float               # contact-facet length at the edge of contact


def fit_profile(p: ContactProfile, a: float) -> tuple[float, float]:
    """(p0, a) of the Hertz profile p = p0 √(1 − r²/a²) fitted to the nodal pressures of the
    active nodes within 0.8 a (least squares on p² = p0² − (p0²/a²) r², linear in r²): the peak
    and radius the whole measured profile points to. Single nodal pressures of an unstructured
    3-D mesh scatter by several per cent about the profile (lumped ∫σ_ν φ_i / ∫φ_i)."""
    use = p.active & (p.radii < 0.8 * a)
    A = np.vstack([np.ones(use.sum()), p.radii[use] ** 2]).T
    (c0, c1), *_ = np.linalg.lstsq(A, p.pressure[use] ** 2, rcond=None)
    return math.sqrt(c0), math.sqrt(-c0 / c1)


def l2_error(p: ContactProfile, a: float, p0: float) -> float:
    """Relative L2 error over r < a of the nodal pressures against Hertz's profile (2-D: the
    trapezoidal rule along the contact line)."""
    inside = p.radii < a
    r = p.radii[inside]
    exact = p0 * np.sqrt(np.maximum(1.0 - r ** 2 / a ** 2, 0.0))
    return math.sqrt(np.trapz((p.pressure[inside] - exact) ** 2, r) / np.trapz(exact ** 2, r))


def profile(problem, centre: np.ndarray) -> ContactProfile:
    """Gather the Signorini state of ``problem`` on every rank, as distances from ``centre``."""
    comm = problem.mesh.comm
    cd, monitor = problem.contact_dofs, problem.contact_monitor
    pressure = -monitor.nodal_pressure()
    gap = cd.normal_displacement(problem.u) - cd.gap
    scale = max(comm.allreduce(float(np.max(np.abs(problem.u.x.array), initial=0.0)), op=MPI.MAX),
                1e-300)
    active = gap >= -1e-8 * scale
    radii = np.linalg.norm(cd.points - centre, axis=1)
    radii, pressure, active = (np.concatenate(comm.allgather(a)) for a in (radii, pressure, active))
    order = np.argsort(radii)
    radii, pressure, active = radii[order], pressure[order], active[order]
    inside = radii[active].max()
    outside = radii[~active & (radii > inside)].min()
    force = -comm.allreduce(float(np.sum(monitor.nodal_forces())), op=MPI.SUM)
    return ContactProfile(force, radii, pressure, active, 0.5 * (inside + outside),
                          outside - inside)
