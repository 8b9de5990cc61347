# SPDX-License-Identifier: MIT
"""The sections of a resolved scene, as frozen dataclasses with every default filled in.

They mirror the tables of a scene file (see :mod:`vpcontact.scene`). Expression-valued entries hold
:class:`vpcontact.scene.expressions.Expression` objects; entries that do not apply to a scene (e.g.
``material.nu`` in 1-D or ``mesh.cells`` of a Gmsh mesh) are ``None``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from vpcontact.scene.expressions import Expression

__all__ = ["BoundaryPart", "BoxSelector", "ContactSpec", "InitialSpec", "LawSpec", "LoadSpec",
           "MaterialSpec", "MeshSpec", "ObstacleRotation", "ObstacleShape", "OutputSpec",
           "PlaneSelector", "PointLoad", "SolverSpec", "TimeSpec", "BUILTIN_MESHES", "CELL_TYPES",
           "DIAGONALS", "SHAPES"]

#: Time schemes of the constitutive law (``[time] scheme``).
TIME_SCHEMES = ("euler", "bdf2")
#: Built-in mesh types and their dimension.
BUILTIN_MESHES = {"interval": 1, "rectangle": 2, "box": 3}
#: Cell types and their dimension.
CELL_TYPES = {"interval": 1, "triangle": 2, "quadrilateral": 2, "tetrahedron": 3, "hexahedron": 3}
#: Diagonal patterns of 2-D triangle meshes (dolfinx ``DiagonalType`` names).
DIAGONALS = ("right", "left", "crossed", "left/right", "right/left")
#: Built-in obstacle shapes and their parameters (``[contact] obstacle = { shape = ... }``).
SHAPES = {"plane": ("point", "normal"), "sphere": ("center", "radius"),
          "cylinder": ("center", "radius", "axis"), "ellipsoid": ("center", "semi_axes")}


@dataclass(frozen=True)
class MeshSpec:
    """``[mesh]``: a built-in interval/rectangle/box mesh or a Gmsh file.

    Attributes:
        type: ``"interval"``, ``"rectangle"``, ``"box"`` or ``"gmsh"``.
        dim: spatial dimension (1, 2 or 3).
        lower, upper: opposite corners of a built-in mesh (``None`` for Gmsh).
        cells: cells per direction of a built-in mesh (``None`` for Gmsh).
        cell_type: cell type of a built-in mesh (``None`` for Gmsh).
        diagonal: diagonal pattern of a triangle mesh (``None`` otherwise).
        file: absolute path of the Gmsh file (``None`` for built-in meshes).
        refine: boxes ``(lower, upper)`` in which a built-in simplex mesh is refined, once per
            box, in order (empty: none).
    """

    type: str
    dim: int
    lower: tuple[float, ...] | None = None
    upper: tuple[float, ...] | None = None
    cells: tuple[int, ...] | None = None
    cell_type: str | None = None
    diagonal: str | None = None
    file: Path | None = None
    refine: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] = ()

    @property
    def builtin(self) -> bool:
        """Whether the mesh is generated (not read from a file)."""
        return self.type != "gmsh"

    @property
    def extent(self) -> float | None:
        """The largest side of a built-in mesh's box (``None`` for Gmsh meshes)."""
        if self.lower is None or self.upper is None:
            return None
        return max(b - a for a, b in zip(self.lower, self.upper))


@dataclass(frozen=True)
class PlaneSelector:
    """Facets on the plane x[axis] = value, within ``tol`` (``None``: 1e-8 × the mesh extent)."""

    axis: int
    value: float
    tol: float | None = None


@dataclass(frozen=True)
class BoxSelector:
    """Facets whose vertices all lie in the closed box [lower, upper]."""

    lower: tuple[float, ...]
    upper: tuple[float, ...]


@dataclass(frozen=True)
class BoundaryPart:
    """``[boundary.<name>]``: a named part of ∂Ω, selected by exactly one selector.

    Attributes:
        name: the part's name.
        kind: ``"clamped"`` (u = 0), ``"displacement"`` (u = u_D(x, t), some components),
            ``"symmetry"`` (u·n = 0 on an axis-aligned plane), ``"traction"`` (Γ2) or
            ``"contact"`` (Γ3).
        tag: Gmsh physical facet tag, or ``None``.
        plane: plane selector, or ``None``.
        box: box selector, or ``None``.
        where: boolean expression in x, or ``None``.
        traction: surface traction f_2(x, t) (traction parts only, else ``None``).
        displacement: u_D(x, t) per component, ``None`` for a free one (displacement parts
            only, else ``None``).
    """

    name: str
    kind: str
    tag: int | None = None
    plane: PlaneSelector | None = None
    box: BoxSelector | None = None
    where: Expression | None = None
    traction: tuple[Expression, ...] | None = None
    displacement: tuple[Expression | None, ...] | None = None

    @property
    def selector(self) -> str:
        """Which selector is set: ``"tag"``, ``"plane"``, ``"box"`` or ``"where"``."""
        for name in ("tag", "plane", "box", "where"):
            if getattr(self, name) is not None:
                return name
        return ""


@dataclass(frozen=True)
class PointLoad:
    """``[[loads.point]]``: a force(t) applied at the point ``at``."""

    at: tuple[float, ...]
    force: tuple[Expression, ...]


@dataclass(frozen=True)
class LoadSpec:
    """``[loads]``: body force f_0(x, t) and point loads."""

    body_force: tuple[Expression, ...]
    point: tuple[PointLoad, ...] = ()


@dataclass(frozen=True)
class MaterialSpec:
    """``[material]``: Young's modulus, Poisson's ratio (``None`` in 1-D), 2-D model."""

    E: float
    nu: float | None = None
    plane: str | None = None


@dataclass(frozen=True)
class LawSpec:
    """``[law]``: σ̇ = E ε̇ + G(σ, ε).

    Attributes:
        type: ``"elastic"`` (G = 0), ``"perzyna"`` (G = -(1/μ*) E(σ - P_K σ)) or ``"linear"``
            (G = aσ + bε).
        scheme: ``"explicit"`` (G at the previous step), ``"implicit"`` (at the new step) or
            ``"linearized"`` (at the new step, linearised at the previous one).
        sigma_y, mu_star: Perzyna's yield stress and viscosity (constants), else ``None``.
        yield_set: Perzyna's yield set, ``"paper"`` or ``"von_mises"``, else ``None``.
        a, b: coefficients of the linear law (constants), else ``None``.
    """

    type: str
    scheme: str
    sigma_y: Expression | None = None
    mu_star: Expression | None = None
    yield_set: str | None = None
    a: Expression | None = None
    b: Expression | None = None


@dataclass(frozen=True)
class ObstacleShape:
    """A built-in obstacle shape (see :data:`SHAPES`): its name and parameters, with the body on
    the side where its level set is positive (outside a sphere, cylinder or ellipsoid; on the
    side a plane's ``normal`` points to)."""

    shape: str
    params: tuple[tuple[str, tuple[float, ...] | float], ...]

    def get(self, name: str):
        return dict(self.params)[name]


@dataclass(frozen=True)
class ObstacleRotation:
    """A rigid rotation of the obstacle by ``angle``(t) (radians, right-handed) about the line
    through ``center`` along ``axis`` (3-D; in 2-D about the point ``center``, counter-clockwise),
    applied before ``motion``'s translation: the obstacle at t is {c + d(t) + Q(t)(y − c)} for
    y in the obstacle at rest."""

    center: tuple[float, ...]
    angle: Expression
    axis: tuple[float, ...] | None = None


@dataclass(frozen=True)
class FrictionSpec:
    """``friction = { type = "coulomb", coefficient = 𝔣 }`` or ``{ type = "tresca",
    threshold = g_T(x) }`` in a contact table (see :mod:`vpcontact.model.friction`)."""

    type: str
    coefficient: float | None = None
    threshold: Expression | None = None


@dataclass(frozen=True)
class ContactSpec:
    """``[contact]``: the contact condition on the part named ``boundary``.

    Attributes:
        type: ``"none"``, ``"signorini"`` or ``"normal_compliance"``.
        boundary: name of the contact part (``None`` for type none).
        gap: initial gap g(x) (``None`` for type none or with an obstacle).
        obstacle: a rigid obstacle (Signorini) or the foundation's surface (normal compliance):
            a level set φ(x) or φ(x, t) of {φ ≤ 0}, a built-in :class:`ObstacleShape`, or
            ``None``.
        motion: rigid translation d(t) of the obstacle (one expression of t per component), or
            ``None``.
        rotation: rigid rotation of the obstacle (:class:`ObstacleRotation`), or ``None``.
        force: the force F(t) pressing a Signorini obstacle on the body (one expression of t per
            component) instead of a motion: it translates along F by an unknown amount that
            balances F; or ``None``.
        max_distance: longest ray searched for the obstacle (with an obstacle only).
        mu: deformability μ of the foundation (normal compliance only).
        alpha: exponent α of normal compliance (normal compliance only).
        friction: Coulomb or Tresca friction, or ``None``.
        normals: the direction of a rigid obstacle's contact force, ``"body"`` (the body's
            normal, the paper's condition) or ``"obstacle"`` (the obstacle's normal: ploughing).
    """

    type: str = "none"
    boundary: str | None = None
    gap: Expression | None = None
    obstacle: Expression | ObstacleShape | None = None
    motion: tuple[Expression, ...] | None = None
    rotation: ObstacleRotation | None = None
    force: tuple[Expression, ...] | None = None
    max_distance: float | None = None
    mu: float | None = None
    alpha: float | None = None
    friction: FrictionSpec | None = None
    normals: str = "body"


@dataclass(frozen=True)
class InitialSpec:
    """``[initial]``: u_0(x) (d components) and σ_0(x) (1, 3 or 6 components).

    σ_0's components are s11 (1-D), s11 s22 s12 (2-D), s11 s22 s33 s23 s13 s12 (3-D).
    """

    u0: tuple[Expression, ...]
    sigma0: tuple[Expression, ...]


@dataclass(frozen=True)
class TimeSpec:
    """``[time]``: final time T, step k, step halvings allowed in a row, and the time scheme of
    the constitutive law: ``"euler"`` (the paper's) or ``"bdf2"`` (second order; implicit laws),
    and the local time-error tolerance of adaptive stepping (k is then the largest step)."""

    T: float
    k: float
    max_cuts: int = 12
    scheme: str = "euler"
    tolerance: float | None = None  # relative local time-error tolerance (adaptive k); None: off


@dataclass(frozen=True)
class SolverSpec:
    """``[solver]``: Newton predictor, extra PETSc options (without the leading "-") and the
    linear solver (``"auto"``, ``"direct"`` or ``"iterative"``, see
    :mod:`vpcontact.solver.linear`)."""

    predictor: str = "linear"
    petsc_options: dict[str, str | int | float | bool] = field(default_factory=dict)
    linear: str = "auto"


@dataclass(frozen=True)
class OutputSpec:
    """``[output]``: what to write, the XDMF stride, and checkpoints every ``checkpoint_every``
    steps (0: only when interrupted)."""

    xdmf: bool = True
    contact_csv: bool = False
    figures: bool = True
    every: int = 1
    checkpoint_every: int = 10
    #: points whose histories go to probes.csv (``[output] probes``)
    probes: tuple[tuple[float, ...], ...] = ()
