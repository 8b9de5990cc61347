# SPDX-License-Identifier: MIT
"""The registry of scene keys: every table of a scene file, the keys it accepts, and for each key
its type, default, unit, allowed values and a one-line description.

It is the one source of the allowed-key lists that the readers (:mod:`vpcontact.scene.read`,
:mod:`vpcontact.scene.physics`) check tables against, of the simple defaults they fall back to,
and of the scene-key reference in the manual (:func:`reference_markdown`, written into the Sphinx
source tree at build time). ``tests/scene/test_scene_key_reference.py`` checks that every key a reader
accepts has its entry here, with the default the reader uses.

Tables are named by their path pattern: ``""`` is the top level, ``boundary.<name>`` any boundary
part, ``loads.point[]`` an element of the array ``[[loads.point]]``; ``contact`` stands for a
single ``[contact]`` table and for each element of an array ``[[contact]]``.

Units: a scene has no unit system of its own; its numbers are in whatever consistent units the
user chose. "length", "time", "force" and "stress" (force per area) name the dimension of a
value in those units; "—" is dimensionless.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from vpcontact.scene.schema import REQUIRED

__all__ = ["Key", "Varies", "TABLES", "TITLES", "keys", "default", "entry", "pattern_of",
           "reference_markdown", "REQUIRED"]


@dataclass(frozen=True)
class Varies:
    """A default that depends on the rest of the scene (the dimension, the law's type …).

    Attributes:
        text: how the default is chosen, as shown in the reference.
        values: every value the readers may fall back to.
    """

    text: str
    values: tuple


#: A key that has no default and is simply left out when absent (e.g. ``[time] tolerance``:
#: adaptive steps off); readers fall back to ``None``.
OFF: Any = None


@dataclass(frozen=True)
class Key:
    """One key of a scene table.

    Attributes:
        name: the key as written in the file.
        type: its TOML type ("number", "string", "array of numbers", "expression of x, t", …).
        default: the value the reader falls back to when the key is absent; :data:`REQUIRED`
            when it must be given; ``None`` when absence means "off" or "not used"; a
            :class:`Varies` when it depends on the rest of the scene.
        unit: the dimension of the value (see the module docstring), or "—".
        description: one line.
        choices: the allowed values, when the key is a choice among them.
        shown: how the default is shown in the reference when ``None`` does not say it.
    """

    name: str
    type: str
    default: Any
    unit: str
    description: str
    choices: tuple = ()
    shown: str = ""


def _k(name: str, type_: str, default: Any, unit: str, description: str,
       choices: tuple = (), shown: str = "") -> Key:
    return Key(name, type_, default, unit, description, choices, shown)


_ZEROS = Varies("zero (one component per dimension)", ((0,), (0, 0), (0, 0, 0)))
_VEC = "array of numbers (one per dimension)"
_EXPRS = "array of expressions (one per dimension)"

#: Every table of a scene and its keys, in the order the readers list them in messages.
TABLES: dict[str, tuple[Key, ...]] = {
    "": (
        _k("name", "string", Varies("the file's name without .toml", ()), "—",
           "the scene's name: the default output folder is `output/<name>/`"),
        _k("description", "string", "", "—", "one line shown by `list` and `show`"),
        _k("mesh", "table", REQUIRED, "—", "the mesh: a built-in interval/rectangle/box or a Gmsh file"),
        _k("boundary", "tables `[boundary.<name>]`", {}, "—",
           "named parts of the boundary and their conditions"),
        _k("loads", "table", Varies("no loads", ()), "—", "body force and point loads"),
        _k("material", "table", REQUIRED, "—", "elastic constants"),
        _k("law", "table", Varies("an elastic law", ()), "—",
           "the constitutive law σ̇ = E ε(u̇) + G(σ, ε(u))"),
        _k("contact", "table or array of tables", None, "—",
           "the contact condition(s), one per boundary part of kind contact", shown="no contact"),
        _k("initial", "table", Varies("zero state", ()), "—", "initial displacement and stress"),
        _k("time", "table", REQUIRED, "—", "final time, step and time scheme"),
        _k("discretization", "table", Varies("all defaults", ()), "—",
           "finite elements: formulation and degree"),
        _k("solver", "table", Varies("all defaults", ()), "—",
           "Newton predictor, linear solver, PETSc options"),
        _k("output", "table", Varies("all defaults", ()), "—", "which files the run writes"),
    ),
    "mesh": (
        _k("type", "string", REQUIRED, "—", "built-in mesh or a Gmsh file",
           ("interval", "rectangle", "box", "gmsh")),
        _k("lower", _VEC, Varies("the origin", ((0.0,), (0.0, 0.0), (0.0, 0.0, 0.0))), "length",
           "lower corner of a built-in mesh"),
        _k("upper", _VEC, Varies("ones", ((1.0,), (1.0, 1.0), (1.0, 1.0, 1.0))), "length",
           "upper corner of a built-in mesh"),
        _k("cells", "array of integers (one per dimension)", REQUIRED, "—",
           "cells (boxes) per direction of a built-in mesh"),
        _k("cell_type", "string", Varies("interval, triangle or tetrahedron by dimension",
                                         ("interval", "triangle", "tetrahedron")), "—",
           "cell type of a built-in mesh",
           ("interval", "triangle", "quadrilateral", "tetrahedron", "hexahedron")),
        _k("diagonal", "string", "right", "—", "diagonal pattern of a triangle mesh",
           ("right", "left", "crossed", "left/right", "right/left")),
        _k("refine", "array of tables {lower, upper}", (), "—",
           "boxes in which a built-in triangle or tetrahedron mesh is refined, once per box, in "
           "order (edges inside the box are split; neighbouring cells are split to conform)"),
        _k("file", "string", REQUIRED, "—", "Gmsh .msh file, relative to the scene (type = \"gmsh\")"),
        _k("dim", "integer", REQUIRED, "—", "the Gmsh mesh's dimension (type = \"gmsh\")", (2, 3)),
    ),
    "boundary.<name>": (
        _k("kind", "string", REQUIRED, "—",
           "the condition on this part: u = 0, some u_i given, u·n = 0, a traction, or contact",
           ("clamped", "displacement", "symmetry", "traction", "contact")),
        _k("tag", "integer", None, "—", "selector: Gmsh physical facet tag (Gmsh meshes only)",
           shown="one selector required"),
        _k("plane", "table", None, "—", "selector: facets on the plane x[axis] = value",
           shown="one selector required"),
        _k("box", "table", None, "—", "selector: facets inside the box [lower, upper]",
           shown="one selector required"),
        _k("where", "condition of x", None, "—", "selector: facets where the condition holds, "
           "e.g. \"x[0] > 1 and x[1] < 0.5\"", shown="one selector required"),
        _k("traction", _EXPRS + " of x, t", _ZEROS, "stress",
           "surface traction f_2(x, t) (kind = \"traction\")"),
        _k("displacement", _EXPRS + " of x, t, or \"free\"", REQUIRED, "length",
           "prescribed u_D(x, t) per component, \"free\" leaves one free (kind = \"displacement\")"),
    ),
    "boundary.<name>.plane": (
        _k("axis", "string or integer", REQUIRED, "—", "the plane's normal axis",
           ("x", "y", "z", 0, 1, 2)),
        _k("value", "number", REQUIRED, "length", "the plane's position along the axis"),
        _k("tol", "number", None, "length", "distance tolerance",
           shown="1e-8 × the mesh extent"),
    ),
    "boundary.<name>.box": (
        _k("lower", _VEC, REQUIRED, "length", "the box's lower corner"),
        _k("upper", _VEC, REQUIRED, "length", "the box's upper corner"),
    ),
    "loads": (
        _k("body_force", _EXPRS + " of x, t", _ZEROS, "force/volume", "body force f_0(x, t)"),
        _k("point", "array of tables `[[loads.point]]`", Varies("no point loads", ()), "—",
           "point loads at mesh vertices"),
    ),
    "loads.point[]": (
        _k("at", _VEC, REQUIRED, "length", "where the load acts: a mesh vertex"),
        _k("force", _EXPRS + " of t", REQUIRED, "force", "the force F(t)"),
    ),
    "mesh.refine[]": (
        _k("lower", _VEC, REQUIRED, "length", "lower corner of the box"),
        _k("upper", _VEC, REQUIRED, "length", "upper corner of the box"),
    ),
    "material": (
        _k("E", "number", REQUIRED, "stress", "Young's modulus, > 0"),
        _k("nu", "number", REQUIRED, "—",
           "Poisson's ratio in (−1, 0.5] (0.5 with the mixed formulation only); not in 1-D"),
        _k("plane", "string", "strain", "—",
           "2-D model: plane strain (the default: a slice of a long body, as contact problems "
           "usually are; Perzyna's law then runs the mixed P2–P1 formulation) or plane stress "
           "(a thin plate)", ("stress", "strain")),
    ),
    "law": (
        _k("type", "string", "elastic", "—", "G = 0, Perzyna's law, or G = aσ + bε",
           ("elastic", "perzyna", "linear")),
        _k("scheme", "string", Varies("implicit for perzyna, else explicit",
                                      ("explicit", "implicit")), "—",
           "G at the previous step, at the new step, or linearised at the previous one",
           ("explicit", "implicit", "linearized")),
        _k("sigma_y", "constant expression", REQUIRED, "stress",
           "Perzyna: the yield stress σ_Y (> 0)"),
        _k("mu_star", "constant expression", REQUIRED, "stress·time",
           "Perzyna: the viscosity μ* (> 0)"),
        _k("yield_set", "string", "von_mises", "—",
           "Perzyna: the yield set K, von Mises (|σ| ≤ σ_Y uniaxially) in every dimension unless "
           "a 3-D scene names the paper's printed set (uniaxial yield stress σ_Y/√2)",
           ("paper", "von_mises")),
        _k("a", "constant expression", REQUIRED, "1/time", "linear law: a in G = aσ + bε"),
        _k("b", "constant expression", REQUIRED, "stress/time", "linear law: b in G = aσ + bε"),
    ),
    "contact": (
        _k("type", "string", REQUIRED, "—", "rigid (u_ν ≤ g) or deformable foundation",
           ("none", "signorini", "normal_compliance")),
        _k("boundary", "string", REQUIRED, "—", "the boundary part (of kind contact) it acts on"),
        _k("gap", "expression of x", Varies("normal compliance: 0; Signorini: required unless "
                                             "an obstacle is given", (0,)), "length",
           "initial gap g(x) along the body's normal, ≥ 0 (or an obstacle)"),
        _k("obstacle", "expression of x (and t) or table", None, "length",
           "the obstacle {φ ≤ 0} (a level set φ, > 0 on the body's side) or a built-in shape",
           shown="none: a gap"),
        _k("motion", _EXPRS + " of t", None, "length",
           "Signorini: rigid translation d(t) of the obstacle", shown="fixed"),
        _k("rotation", "table", None, "—", "Signorini: rigid rotation of the obstacle",
           shown="none"),
        _k("force", _EXPRS + " of t", None, "force",
           "Signorini: a force F(t) pressing the obstacle (instead of a motion)",
           shown="none"),
        _k("max_distance", "number", 1e3, "length",
           "longest ray searched for the obstacle from a contact node"),
        _k("mu", "number", REQUIRED, "length^α/stress",
           "normal compliance: the foundation's compliance μ (1/stiffness, not a friction "
           "coefficient), > 0: a pressure p needs the penetration (μ p)^(1/α)"),
        _k("alpha", "number", 1.0, "—", "normal compliance: exponent α in (0, 1]"),
        _k("friction", "table", None, "—", "Coulomb or Tresca friction", shown="frictionless"),
        _k("normals", "string", "body", "—",
           "Signorini with an obstacle: the force along the body's or the obstacle's normal",
           ("body", "obstacle")),
    ),
    "contact.friction": (
        _k("type", "string", REQUIRED, "—", "Coulomb (|σ_τ| ≤ 𝔣 p) or Tresca (|σ_τ| ≤ g_T)",
           ("coulomb", "tresca")),
        _k("coefficient", "number", REQUIRED, "—", "Coulomb: the friction coefficient 𝔣 ≥ 0"),
        _k("threshold", "expression of x", REQUIRED, "stress", "Tresca: the threshold g_T(x) ≥ 0"),
    ),
    "contact.obstacle": (
        _k("shape", "string", REQUIRED, "—", "the built-in shape",
           ("plane", "sphere", "cylinder", "ellipsoid")),
        _k("axis", _VEC, REQUIRED, "—", "cylinder (3-D only): direction of its axis"),
        _k("center", _VEC, REQUIRED, "length", "sphere, cylinder, ellipsoid: centre"),
        _k("normal", _VEC, REQUIRED, "—", "plane: normal, pointing towards the body"),
        _k("point", _VEC, REQUIRED, "length", "plane: a point on it"),
        _k("radius", "number", REQUIRED, "length", "sphere, cylinder: radius, > 0"),
        _k("semi_axes", _VEC, REQUIRED, "length", "ellipsoid: semi-axes, > 0"),
    ),
    "contact.rotation": (
        _k("center", _VEC, REQUIRED, "length", "the point (2-D) or a point of the axis (3-D)"),
        _k("angle", "expression of t", REQUIRED, "rad", "the angle θ(t), right-handed"),
        _k("axis", "array of 3 numbers", REQUIRED, "—", "3-D only: the axis's direction"),
    ),
    "initial": (
        _k("u0", _EXPRS + " of x", _ZEROS, "length", "initial displacement u_0(x)"),
        _k("sigma0", "array of expressions of x (1, 3 or 6)",
           Varies("zero", ((0,), (0, 0, 0), (0, 0, 0, 0, 0, 0))), "stress",
           "initial stress σ_0(x): s11 (1-D); s11 s22 s12 (2-D); s11 s22 s33 s23 s13 s12 (3-D)"),
    ),
    "time": (
        _k("T", "number", REQUIRED, "time", "final time, > 0"),
        _k("k", "number", REQUIRED, "time", "time step, 0 < k ≤ T (the largest step if adaptive)"),
        _k("max_cuts", "integer", 12, "—", "step halvings allowed in a row when a step fails (0–50)"),
        _k("scheme", "string", "euler", "—", "the paper's Euler or second-order BDF2 (implicit laws)",
           ("euler", "bdf2")),
        _k("tolerance", "number", None, "—",
           "adaptive steps: relative local time-error tolerance in (0, 1)", shown="off (fixed k)"),
    ),
    "discretization": (
        _k("degree", "integer", None, "—", "degree of the displacement",
           (1, 2), shown="1 (2 with the mixed formulation)"),
        _k("formulation", "string", "auto", "—",
           "auto: mixed Taylor–Hood P2–P1 where P1 locks, else displacement",
           ("auto", "mixed", "displacement")),
    ),
    "solver": (
        _k("predictor", "string", "linear", "—",
           "the step's initial guess: last increment extrapolated, or the last state",
           ("linear", "none")),
        _k("linear", "string", "auto", "—", "linear solver: by size and scheme, MUMPS, or Krylov",
           ("auto", "direct", "iterative")),
        _k("petsc_options", "table of options", {}, "—",
           "PETSc options passed to the step's SNES (names without the leading -)"),
    ),
    "output": (
        _k("xdmf", "boolean", True, "—", "write the XDMF series (u, stress, pressure …)"),
        _k("contact_csv", "boolean", Varies("true with contact, else false", (True, False)), "—",
           "write contact.csv (needs contact)"),
        _k("figures", "boolean", True, "—", "write the PNG figures"),
        _k("every", "integer", 1, "—", "XDMF stride in steps (the last step is always written)"),
        _k("checkpoint_every", "integer", 10, "—",
           "steps between checkpoints (0: only when interrupted)"),
        _k("probes", "array of points (one number per dimension each)", (), "length",
           "points whose displacement, stress and viscoplastic strain go to probes.csv",
           shown="no probes"),
    ),
}

#: How each table is written in a scene file.
TITLES = {
    "": "Top level", "mesh": "[mesh]",
    "mesh.refine[]": "[mesh] refine = [{…}, …]", "boundary.<name>": "[boundary.<name>]",
    "boundary.<name>.plane": "[boundary.<name>] plane = {…}",
    "boundary.<name>.box": "[boundary.<name>] box = {…}", "loads": "[loads]",
    "loads.point[]": "[[loads.point]]", "material": "[material]", "law": "[law]",
    "contact": "[contact] or [[contact]]", "contact.friction": "[contact] friction = {…}",
    "contact.obstacle": "[contact] obstacle = {shape = …}",
    "contact.rotation": "[contact] rotation = {…}", "initial": "[initial]", "time": "[time]",
    "discretization": "[discretization]", "solver": "[solver]", "output": "[output]",
}


def keys(table: str) -> tuple[str, ...]:
    """The keys the table ``table`` (a path pattern, e.g. ``"contact.friction"``) accepts."""
    return tuple(key.name for key in TABLES[table])


def entry(table: str, key: str) -> Key:
    """The registry entry of ``key`` in ``table``."""
    for item in TABLES[table]:
        if item.name == key:
            return item
    raise KeyError(f"{table}.{key}")


def default(table: str, key: str) -> Any:
    """The default of a key whose default does not depend on the rest of the scene."""
    value = entry(table, key).default
    if isinstance(value, Varies):
        raise ValueError(f"the default of {table}.{key} depends on the scene: {value.text}")
    return value


def pattern_of(path: str) -> str:
    """The table pattern of a table's key path: ``boundary.top.plane`` -> ``boundary.<name>.plane``,
    ``contact[1].friction`` -> ``contact.friction``, ``loads.point[0]`` -> ``loads.point[]``."""
    if path.startswith("boundary."):
        rest = path[len("boundary."):]
        if rest.startswith('"'):
            end = rest.index('"', 1) + 1
        else:
            end = len(rest.split(".", 1)[0])
        path = "boundary.<name>" + rest[end:]
    path = re.sub(r"^contact\[\d+\]", "contact", path)
    return re.sub(r"\[\d+\]", "[]", path)


# -- the reference page ---------------------------------------------------------------------

def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e3:
        return repr(value)
    if isinstance(value, tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{}"
    return repr(value)


def shown_default(key: Key) -> str:
    """The default as the reference shows it."""
    if key.shown:
        return key.shown
    if key.default is REQUIRED:
        return "required"
    if isinstance(key.default, Varies):
        return key.default.text
    if key.default is None:
        return "—"
    return f"`{_value(key.default)}`"


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def reference_markdown() -> str:
    """The scene-key reference as a MyST Markdown page (one table per scene table)."""
    lines = [
        "# Scene keys",
        "",
        "Generated from the registry `vpcontact/scene/keys.py` when the manual is built: the same",
        "lists the scene reader checks files against, so this page cannot drift from the code.",
        "\"required\" keys must be given where their table (or the `kind`/`type` they belong to)",
        "applies. Units name the dimension of a value in the scene's own consistent units",
        "(\"length\", \"time\", \"force\", \"stress\" = force/area); \"—\" is dimensionless.",
        "Expressions are numbers or strings over `x[0]`, `x[1]`, `x[2]`, `t` and the whitelisted",
        "functions (see {doc}`/guide/scenes`).",
        "",
    ]
    for table, entries in TABLES.items():
        lines += [f"## `{TITLES[table]}`" if table else "## Top level", ""]
        lines += ["| key | type | default | unit | allowed values | description |",
                  "|---|---|---|---|---|---|"]
        for key in entries:
            choices = ", ".join(f"`{_value(c)}`" for c in key.choices) if key.choices else ""
            lines.append("| " + " | ".join(_cell(c) for c in (
                f"`{key.name}`", key.type, shown_default(key), key.unit, choices,
                key.description)) + " |")
        lines.append("")
    return "\n".join(lines)
