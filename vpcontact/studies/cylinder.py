# SPDX-License-Identifier: MIT
"""Thick-walled cylinder under internal pressure (plane strain): closed forms, meshes, measurements.

A tube a ≤ r ≤ b, pressure P on r = a, free on r = b, ε_zz = 0.

* Lamé's elastic solution (any ν in (−1, 0.5], including the incompressible ν = 0.5):

      σ_rr = A − B/r²,   σ_θθ = A + B/r²,   σ_zz = ν(σ_rr + σ_θθ) = 2νA,
      A = P a²/(b² − a²),   B = P a² b²/(b² − a²),
      u_r = ((1 + ν)/E) ((1 − 2ν) A r + B/r),

  i.e. u = (C₁ + C₂/r²) x with C₁ = (1 + ν)(1 − 2ν)A/E and C₂ = (1 + ν)B/E.
* Hill's limit pressure of a perfectly plastic von Mises tube: at collapse the whole wall flows
  with ε̇_zz = 0, so s_zz = 0 and the von Mises condition √(3/2 s:s) = σ_Y becomes
  σ_θθ − σ_rr = 2σ_Y/√3; with ∂σ_rr/∂r = (σ_θθ − σ_rr)/r this integrates to

      P_lim = (2/√3) σ_Y ln(b/a).

  Yield radius: vpcontact's kernels compare τ·Yτ with σ_Y², where Y gives
  ``"3d_standard"`` (the scene's ``yield_set = "von_mises"``, the only set of 2-D plane-strain
  scenes): 3/2 s:s, uniaxial yield σ_Y, shear yield σ_Y/√3, so P_lim = (2/√3) σ_Y ln(b/a);
  ``"3d"`` (the scene's ``yield_set = "paper"``, a 3-D scene option only; reachable in plane
  strain from the Python API as ``PlaneStrain(Perzyna(Elasticity("3d", ...)))``): 3 s:s, twice
  the standard form, uniaxial yield σ_Y/√2, shear yield σ_Y/√6, so P_lim = √(2/3) σ_Y ln(b/a).
  :func:`yield_radii` measures both on the kernels.

Meshes (Gmsh, OpenCASCADE kernel, written as .msh on rank 0): :func:`quarter_annulus_msh`, the
quarter x, y ≥ 0 of the annulus with the facet groups INNER (r = a), OUTER (r = b), SYMMETRY_X
(x = 0) and SYMMETRY_Y (y = 0); read with :func:`read_msh` (that of
:mod:`vpcontact.studies.hertz`).

Measurements (collective: every rank gets the same value): :func:`radial_displacements` gathers
u_r = u·x/|x| at the nodes on a circle r = R, :func:`mean_radial_displacement` averages it, and
:func:`l2_error` is ‖u_h − u_Lamé‖_L2 over the meshed domain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from vpcontact import kernels
from vpcontact.scene.gmsh_files import gmsh_session
from vpcontact.studies.hertz import read_msh  # reads these meshes too

__all__ = ["BODY", "INNER", "LIMIT_FACTORS", "OUTER", "SYMMETRY_X", "SYMMETRY_Y", "Tube",
           "YIELD_MODELS", "l2_error", "limit_bracket", "limit_pressure", "max_yield_ratio",
           "mean_radial_displacement", "pressure_traction", "quarter_annulus_msh",
           "radial_displacements", "read_msh", "yield_radii"]

#: Physical tags of the generated meshes (BODY is the surface's own group).
BODY, INNER, OUTER, SYMMETRY_X, SYMMETRY_Y = 1, 1, 2, 3, 4

#: Kernel model of each scene yield set, and the factor f in P_lim = f · σ_Y · ln(b/a).
YIELD_MODELS = {"von_mises": "3d_standard", "paper": "3d"}
LIMIT_FACTORS = {"3d_standard": 2.0 / math.sqrt(3.0), "3d": math.sqrt(2.0 / 3.0)}


@dataclass(frozen=True)
class Tube:
    """A thick-walled tube a ≤ r ≤ b of an isotropic material (E, ν) under internal pressure."""

    a: float
    b: float
    E: float
    nu: float

    def __post_init__(self):
        if not 0.0 < self.a < self.b:
            raise ValueError(f"radii must satisfy 0 < a < b, got a = {self.a}, b = {self.b}")
        if not -1.0 < self.nu <= 0.5:
            raise ValueError(f"Poisson's ratio must lie in (-1, 0.5], got {self.nu}")

    def lame_constants(self, P: float) -> tuple[float, float]:
        """(A, B) of σ_rr = A − B/r², σ_θθ = A + B/r²."""
        d = self.b ** 2 - self.a ** 2
        return P * self.a ** 2 / d, P * self.a ** 2 * self.b ** 2 / d

    def displacement_constants(self, P: float) -> tuple[float, float]:
        """(C₁, C₂) of u_r = C₁ r + C₂/r (u = (C₁ + C₂/r²) x)."""
        A, B = self.lame_constants(P)
        return (1 + self.nu) * (1 - 2 * self.nu) * A / self.E, (1 + self.nu) * B / self.E

    def radial_displacement(self, r, P: float):
        """Lamé's u_r(r) (plane strain)."""
        c1, c2 = self.displacement_constants(P)
        return c1 * np.asarray(r) + c2 / np.asarray(r)

    def stresses(self, r, P: float) -> tuple[np.ndarray, np.ndarray]:
        """Lamé's (σ_rr, σ_θθ) at r."""
        A, B = self.lame_constants(P)
        r2 = np.asarray(r, dtype=np.float64) ** 2
        return A - B / r2, A + B / r2

    def compliance(self) -> float:
        """du_r(a)/dP of the elastic tube."""
        return float(self.radial_displacement(self.a, 1.0))

    def limit_pressure(self, sigma_y: float, model: str = "3d_standard") -> float:
        """Hill's P_lim for the kernel model's von Mises set (see :data:`LIMIT_FACTORS`)."""
        return limit_pressure(self.a, self.b, sigma_y, model)


def limit_pressure(a: float, b: float, sigma_y: float, model: str = "3d_standard") -> float:
    """Hill's limit pressure f σ_Y ln(b/a) of a perfectly plastic tube in plane strain, f = 2/√3
    for ``"3d_standard"`` (scene yield_set ``"von_mises"``), √(2/3) for ``"3d"`` (``"paper"``)."""
    return LIMIT_FACTORS[model] * sigma_y * math.log(b / a)


def yield_radii(model: str, sigma_y: float = 1.0) -> tuple[float, float]:
    """(uniaxial, shear) yield stresses of a kernel model, measured with
    :func:`vpcontact.kernels.yield_function`: the yield function is a quadratic form, so the
    stress t·τ₀ on the surface τ·Yτ = σ_Y² has t = σ_Y/√(τ₀·Yτ₀)."""
    uniaxial = np.zeros((1, 3, 3))
    uniaxial[0, 0, 0] = 1.0
    shear = np.zeros((1, 3, 3))
    shear[0, 0, 1] = shear[0, 1, 0] = 1.0
    return tuple(float(sigma_y / math.sqrt(kernels.yield_function(s, model=model)[0]))
                 for s in (uniaxial, shear))


def quarter_annulus_msh(path: Path, a: float = 1.0, b: float = 2.0, h: float = 0.1,
                        h_inner: float | None = None, order: int = 1,
                        comm=MPI.COMM_WORLD) -> Path:
    """Write the quarter annulus a ≤ r ≤ b, x, y ≥ 0 (tags INNER, OUTER, SYMMETRY_X, SYMMETRY_Y).

    Args:
        path: the .msh file to write (by rank 0; every rank returns once it exists).
        a, b: inner and outer radii.
        h: element size.
        h_inner: element size at r = a, growing linearly to h at r = b (None: h everywhere).
        order: geometry order, 1 (straight facets: the arcs become polygons, whose O(h²)
            domain error caps the L2 error of P2 displacements at O(h²)) or 2 (curved 6-node
            triangles, on which P2 converges at O(h³)).
        comm: the communicator.
    """
    try:
        with gmsh_session(comm) as gmsh:
            if gmsh is not None:
                _annulus(gmsh, a, b, h, h_inner, order)
                gmsh.model.mesh.generate(2)
                gmsh.write(str(path))
    finally:
        comm.barrier()
    return path


def _annulus(gmsh, a, b, h, h_inner, order) -> None:
    """The geometry, physical groups and size options of :func:`quarter_annulus_msh`."""
    gmsh.model.add("quarter_annulus")
    occ = gmsh.model.occ
    centre = occ.addPoint(0.0, 0.0, 0.0)
    corners = [occ.addPoint(a, 0.0, 0.0), occ.addPoint(b, 0.0, 0.0),
               occ.addPoint(0.0, b, 0.0), occ.addPoint(0.0, a, 0.0)]
    bottom = occ.addLine(corners[0], corners[1])
    outer = occ.addCircleArc(corners[1], centre, corners[2])
    side = occ.addLine(corners[2], corners[3])
    inner = occ.addCircleArc(corners[3], centre, corners[0])
    surface = occ.addPlaneSurface([occ.addCurveLoop([bottom, outer, side, inner])])
    occ.remove([(0, centre)])
    occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [surface], BODY)
    for tag, curve in ((INNER, inner), (OUTER, outer), (SYMMETRY_X, side),
                       (SYMMETRY_Y, bottom)):
        gmsh.model.addPhysicalGroup(1, [curve], tag)
    if h_inner is None:
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    else:
        gmsh.model.mesh.setSizeCallback(
            lambda dim, tag, x, y, z, lc: h_inner + (h - h_inner) * min(
                max((math.hypot(x, y) - a) / (b - a), 0.0), 1.0))
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0 if h_inner else 1)
    gmsh.option.setNumber("Mesh.ElementOrder", order)


def _on_circle(u: fem.Function, radius: float, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """(coordinates, u_r) at this rank's owned dofs of ``u``'s space with |r − radius| ≤ rtol ·
    radius (a subfunction of a mixed space is collapsed first)."""
    if len(u.function_space.component()) > 0:
        u = u.collapse()
    V = u.function_space
    bs = V.dofmap.index_map_bs
    owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:owned, :bs]
    r = np.linalg.norm(x, axis=1)
    on = np.abs(r - radius) <= rtol * radius
    values = u.x.array[:owned * bs].reshape(owned, bs)[on]
    return x[on], np.einsum("ij,ij->i", values, x[on]) / r[on]


def radial_displacements(u: fem.Function, radius: float, rtol: float = 1e-8):
    """(angles, u_r) at the dofs of ``u``'s space on the circle r = ``radius``, gathered on every
    rank and sorted by angle (collective). For P2 on straight facets only the vertices lie on the
    circle; the facet midpoints are inside it and left out.

    Args:
        u: a vector displacement Function (a subfunction of a mixed space is collapsed first).
        radius: the circle.
        rtol: tolerance on |r − radius| relative to ``radius``.
    """
    comm = u.function_space.mesh.comm
    x, ur = _on_circle(u, radius, rtol)
    theta, ur = (np.concatenate(comm.allgather(v)) for v in (np.arctan2(x[:, 1], x[:, 0]), ur))
    order = np.argsort(theta)
    return theta[order], ur[order]


def mean_radial_displacement(u: fem.Function, radius: float, rtol: float = 1e-8) -> float:
    """Mean u_r over the dofs on the circle r = ``radius`` (collective: the sum and the count
    are reduced with allreduce)."""
    comm = u.function_space.mesh.comm
    _, ur = _on_circle(u, radius, rtol)
    total = comm.allreduce(float(ur.sum()), op=MPI.SUM)
    count = comm.allreduce(len(ur), op=MPI.SUM)
    if count == 0:
        raise ValueError(f"no dof lies on the circle r = {radius}")
    return total / count


def l2_error(u: fem.Function, tube: Tube, P: float, relative: bool = True,
             extra_degree: int = 3) -> float:
    """‖u − u_Lamé‖_L2 over the mesh (relative to ‖u_Lamé‖ unless ``relative`` is False),
    u_Lamé = (C₁ + C₂/r²) x evaluated as a UFL expression of x on the meshed (polygonal or
    curved) domain; collective."""
    if len(u.function_space.component()) > 0:
        u = u.collapse()
    mesh = u.function_space.mesh
    x = ufl.SpatialCoordinate(mesh)
    c1, c2 = tube.displacement_constants(P)
    exact = (c1 + c2 / ufl.dot(x, x)) * x
    degree = u.function_space.ufl_element().degree() + extra_degree
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": degree})
    comm = mesh.comm
    error = comm.allreduce(fem.assemble_scalar(fem.form(ufl.inner(u - exact, u - exact) * dx)),
                           op=MPI.SUM)
    norm = comm.allreduce(fem.assemble_scalar(fem.form(ufl.inner(exact, exact) * dx)), op=MPI.SUM)
    return math.sqrt(error / norm) if relative else math.sqrt(error)


def pressure_traction(P):
    """The traction of a pressure P(t) on the inner face, P(t) x/|x| (the face's outward normal
    is −x/|x|), as a load function (x, t) for :class:`vpcontact.solver.Loads`."""
    return lambda x, t: P(t) * x / ufl.sqrt(ufl.dot(x, x))


def max_yield_ratio(problem) -> float:
    """max over the quadrature points of √(τ·Yτ)/σ_Y for a :class:`PlaneStrain` Perzyna problem
    (τ the 3-D stress with the law's σ33; Y the law's own yield form): 1 on the yield surface,
    1 + (viscous overstress)/σ_Y outside it. Collective (max over ranks)."""
    plane = problem.law
    model = plane.elasticity.model
    stress = problem.state.view(problem.state.stress)
    n = stress.shape[0]
    tau = np.zeros((n, 3, 3))
    tau[:, 0, 0], tau[:, 1, 1] = stress[:, 0], stress[:, 1]
    tau[:, 0, 1] = tau[:, 1, 0] = stress[:, 2] / math.sqrt(2.0)
    tau[:, 2, 2] = plane.out_of_plane_stress()
    local = float(np.sqrt(kernels.yield_function(tau, model=model)).max(initial=0.0))
    return problem.mesh.comm.allreduce(local, op=MPI.MAX) / plane.law.sigma_y


def limit_bracket(pressures, displacements, compliance: float, factor: float = 50.0):
    """Where a pressure-controlled curve u(P) blows up: the first step (P_{n−1}, P_n] whose secant
    compliance (u_n − u_{n−1})/(P_n − P_{n−1}) exceeds ``factor`` × the elastic ``compliance``;
    None if none does. The rate-independent curve only approaches P_lim asymptotically
    (du/dP → ∞), so on an exact curve the bracket lies just below P_lim."""
    P, u = np.asarray(pressures, dtype=np.float64), np.asarray(displacements, dtype=np.float64)
    slopes = np.diff(u) / np.diff(P)
    over = np.nonzero(slopes > factor * compliance)[0]
    if over.size == 0:
        return None
    return float(P[over[0]]), float(P[over[0] + 1])
