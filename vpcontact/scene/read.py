# SPDX-License-Identifier: MIT
"""Reading the tables of a parsed scene file into the section dataclasses of
:mod:`vpcontact.scene.specs`.

Every reader reports what is wrong to a :class:`~vpcontact.scene.schema.Report` and goes on, so
one pass finds all problems; the values it returns are only used when no problem was found.
The physics sections (law, contact) are in :mod:`vpcontact.scene.physics`.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

from vpcontact.scene.keys import default, keys
from vpcontact.scene.locate import join
from vpcontact.scene.physics import read_contacts, read_law
from vpcontact.scene.schema import (REQUIRED, Report, Table, at_least, between, fmt, greater, type_name,
                                    unknown_key)
from vpcontact.linear_solvers import LINEAR_SOLVERS
from vpcontact.model.constitutive import MAX_MODULUS, MIN_MODULUS
from vpcontact.model.locking import FORMULATIONS, locking_expected
from vpcontact.scene.specs import (BUILTIN_MESHES, CELL_TYPES, DIAGONALS, BoundaryPart,
                                   BoxSelector, ContactSpec, InitialSpec, LawSpec, LoadSpec,
                                   MaterialSpec, MeshSpec, OutputSpec, PlaneSelector, PointLoad,
                                   SolverSpec, TIME_SCHEMES, TimeSpec)

__all__ = ["TOP_KEYS", "read_scene"]

# The keys each table accepts come from the registry (vpcontact/scene/keys.py), which the
# manual's scene-key reference is generated from.
TOP_KEYS = keys("")
MESH_KEYS = keys("mesh")
PART_KEYS = keys("boundary.<name>")
SELECTORS = ("tag", "plane", "box", "where")
KINDS = ("clamped", "displacement", "symmetry", "traction", "contact")
#: Kinds that prescribe displacement components (Dirichlet parts).
DIRICHLET_KINDS = ("clamped", "displacement", "symmetry")
PART_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
SCENE_NAME = r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}"
PETSC_KEY = r"[A-Za-z0-9_]+"
AXES = {"x": 0, "y": 1, "z": 2}
MAX_CELLS = 5_000_000
#: Each refinement box at most quadruples (2-D) or octuples (3-D) the cells it covers.
MAX_REFINE_BOXES = 8
MAX_STEPS = 10_000_000
MAX_CUTS = 50
#: Cells per box of the structured grid, by cell type (crossed triangles: 4).
CELLS_PER_BOX = {"interval": 1, "triangle": 2, "quadrilateral": 1, "tetrahedron": 6,
                 "hexahedron": 1}


def zeros(n: int | None) -> tuple[int, ...] | None:
    """The default of a vector of n expressions (``None`` if n is unknown)."""
    return None if n is None else (0,) * n


def read_scene(data: dict, report: Report, base_dir: Path, default_name: str) -> dict[str, Any]:
    """All fields of a :class:`~vpcontact.scene.Scene` but its path, hash and locator."""
    top = Table(report, "", data, TOP_KEYS)
    mesh = read_mesh(top, base_dir)
    dim = mesh.dim if mesh is not None else None
    boundaries = read_boundaries(top, mesh)
    contacts, array = read_contacts(top, dim)
    check_parts(report, boundaries, contacts, array, data.get("contact"))
    material, law = read_material(top, dim), read_law(top, dim)
    return {
        "name": top.string("name", default_name, pattern=SCENE_NAME),
        "description": top.string("description", default("", "description")),
        "dim": dim,
        "mesh": mesh,
        "boundaries": boundaries,
        "loads": read_loads(top, dim),
        "material": material,
        "law": law,
        "contacts": tuple(c for c in contacts if c is not None),
        "contact_array": array,
        "initial": read_initial(top, dim),
        "time": read_time(top),
        **read_discretization(top, dim, material, law),
        "solver": read_solver(top),
        "output": read_output(top, contacts, dim),
        "defaulted": defaulted(data, dim, law),
    }


#: The model choices whose defaults ``show`` and the run's first line mark, by key path.
CHOICES = ("law.type", "law.yield_set", "material.plane", "discretization.formulation")


def defaulted(data: dict, dim: int | None, law: LawSpec) -> frozenset[str]:
    """The key paths of :data:`CHOICES` that the scene leaves to their defaults (of those that
    apply to it: the yield set to Perzyna's law, the plane to 2-D scenes);
    ``formulation = "auto"`` counts as left to the default."""
    def given(table: str, key: str) -> Any:
        section = data.get(table)
        return section.get(key) if isinstance(section, dict) else None

    applies = {"law.type": True, "law.yield_set": law.type == "perzyna",
               "material.plane": dim == 2, "discretization.formulation": True}
    return frozenset(path for path in CHOICES if applies[path]
                     and given(*path.split(".")) in (None, "auto"))


# -- mesh -----------------------------------------------------------------------------------

def read_mesh(top: Table, base_dir: Path) -> MeshSpec | None:
    """``[mesh]``: a built-in mesh or a Gmsh file."""
    t = top.table("mesh", MESH_KEYS, required=True)
    if t is None:
        return None
    mesh_type = t.choice("type", tuple(BUILTIN_MESHES) + ("gmsh",))
    if mesh_type is None:
        return None
    if mesh_type == "gmsh":
        return _gmsh_mesh(t, base_dir)
    return _builtin_mesh(t, mesh_type)


def _builtin_mesh(t: Table, mesh_type: str) -> MeshSpec:
    dim = BUILTIN_MESHES[mesh_type]
    for key in ("file", "dim"):
        t.forbid(key, "only for type = 'gmsh'")
    lower = t.numbers("lower", dim, (0.0,) * dim)
    upper = t.numbers("upper", dim, (1.0,) * dim)
    if lower is not None and upper is not None:
        for i, (a, b) in enumerate(zip(lower, upper)):
            if not b > a:
                t.report.add(join(t.at("upper"), i),
                             f"must exceed lower[{i}] = {fmt(a)}, got {fmt(b)}")
    cells = t.numbers("cells", dim, integer=True, check=greater(0))
    cell_type = t.choice("cell_type", tuple(CELL_TYPES), ("interval", "triangle", "tetrahedron")[dim - 1])
    if cell_type is not None and CELL_TYPES[cell_type] != dim:
        t.add("cell_type", f"{cell_type!r} cells are {CELL_TYPES[cell_type]}-D, but a "
                           f"{mesh_type!r} mesh is {dim}-D")
        cell_type = None
    diagonal = None
    if cell_type == "triangle":
        diagonal = t.choice("diagonal", DIAGONALS, default("mesh", "diagonal"))
    elif cell_type is not None:
        t.forbid("diagonal", "only for triangle meshes")
    refine = _refine_boxes(t, dim, cell_type)
    if cells is not None and cell_type is not None:
        count = math.prod(cells) * CELLS_PER_BOX[cell_type] * (2 if diagonal == "crossed" else 1)
        if count > MAX_CELLS:
            t.add("cells", f"too many cells ({count}, at most {MAX_CELLS})")
        elif refine and lower is not None and upper is not None:
            estimate = _refined_count(count, lower, upper, refine)
            if estimate > MAX_CELLS:
                t.add("refine", f"too many cells after refinement (about {estimate:.3g}, at most "
                                f"{MAX_CELLS})")
    return MeshSpec(mesh_type, dim, lower=lower, upper=upper, cells=cells, cell_type=cell_type,
                    diagonal=diagonal, refine=refine)


def _refined_count(count: int, lower, upper, boxes) -> float:
    """An estimate of the cell count after refinement: each box splits the cells it covers (by
    its share of the domain's volume) into 2^dim, and as many again around it to conform."""
    dim, volume = len(lower), math.prod(b - a for a, b in zip(lower, upper))
    for box_lower, box_upper in boxes:
        share = math.prod(max(0.0, min(b, bu) - max(a, bl))
                          for a, b, bl, bu in zip(lower, upper, box_lower, box_upper)) / volume
        count += 2 * share * count * (2 ** dim - 1)
    return count


def _refine_boxes(t: Table, dim: int, cell_type: str | None) -> tuple:
    """``refine = [{lower, upper}, …]``: boxes of local refinement (triangles, tetrahedra)."""
    raw = t.data.get("refine", [])
    if not isinstance(raw, list):
        t.add("refine", f"expected an array of tables {{lower, upper}}, got {type_name(raw)}")
        return ()
    if raw and cell_type not in ("triangle", "tetrahedron"):
        t.add("refine", f"local refinement needs triangle or tetrahedron cells, got {cell_type!r}")
        return ()
    if len(raw) > MAX_REFINE_BOXES:
        t.add("refine", f"at most {MAX_REFINE_BOXES} boxes (each refines once), got {len(raw)}")
        return ()
    boxes = []
    for i, item in enumerate(raw):
        if not isinstance(item, dict):
            t.report.add(join(t.at("refine"), i), f"expected a table, got {type_name(item)}")
            continue
        box = Table(t.report, join(t.at("refine"), i), item, keys("mesh.refine[]"))
        lower, upper = box.numbers("lower", dim), box.numbers("upper", dim)
        if lower is None or upper is None:
            continue
        if any(not b > a for a, b in zip(lower, upper)):
            box.add("upper", f"must exceed lower in every direction, got lower = {list(lower)}, "
                             f"upper = {list(upper)}")
            continue
        boxes.append((tuple(lower), tuple(upper)))
    return tuple(boxes)


def _gmsh_mesh(t: Table, base_dir: Path) -> MeshSpec:
    for key in ("lower", "upper", "cells", "cell_type", "diagonal", "refine"):
        t.forbid(key, "only for built-in meshes (interval, rectangle, box)")
    dim = t.choice("dim", (2, 3))
    name = t.string("file", max_length=4096)
    file = None
    if name is not None:
        candidate = base_dir / name
        try:
            exists = "\x00" not in name and candidate.is_file()
        except OSError:
            exists = False
        if exists:
            file = candidate.resolve()
        else:
            t.add("file", f"Gmsh file not found: {candidate}")
    return MeshSpec("gmsh", dim, file=file)


# -- boundary -------------------------------------------------------------------------------

def read_boundaries(top: Table, mesh: MeshSpec | None) -> dict[str, BoundaryPart]:
    """``[boundary.<name>]`` tables, in file order."""
    raw = top.data.get("boundary", {})
    if not isinstance(raw, dict):
        top.add("boundary", f"expected tables [boundary.<name>], got {type_name(raw)}")
        return {}
    parts = {}
    for name, value in raw.items():
        path = join("boundary", name)
        if not re.fullmatch(PART_NAME, name):
            top.report.add(path, f"part name {name!r} must match {PART_NAME}")
        if not isinstance(value, dict):
            top.report.add(path, f"expected a table [boundary.{name}], got {type_name(value)}")
            continue
        parts[name] = _read_part(Table(top.report, path, value, PART_KEYS), name, mesh)
    return parts


def _read_part(t: Table, name: str, mesh: MeshSpec | None) -> BoundaryPart:
    dim = mesh.dim if mesh is not None else None
    kind = t.choice("kind", KINDS)
    given = [key for key in SELECTORS if t.has(key)]
    if not given:
        t.report.add(t.path, "needs exactly one selector: tag, plane, box or where")
    for key in given[1:]:
        t.add(key, f"only one selector per part; {given[0]!r} is already given")
    tag = plane = box = where = None
    if t.has("tag"):
        if mesh is not None and mesh.builtin:
            t.add("tag", "tags need mesh.type = 'gmsh'; select parts of built-in meshes with "
                         "plane, box or where")
        else:
            tag = t.integer("tag", check=greater(0))
    if t.has("plane"):
        plane = _read_plane(t, dim)
    if t.has("box"):
        box = _read_box(t, dim)
    if t.has("where"):
        where = t.expr("where", ("x",), dim, condition=True)
    traction = displacement = None
    if kind == "traction":
        traction = t.exprs("traction", ("x", "t"), dim, dim, zeros(dim))
    elif kind is not None:
        t.forbid("traction", "only for kind = 'traction'")
    if kind == "displacement":
        displacement = t.exprs("displacement", ("x", "t"), dim, dim, free=True)
    elif kind is not None:
        t.forbid("displacement", "only for kind = 'displacement'")
    return BoundaryPart(name, kind, tag=tag, plane=plane, box=box, where=where, traction=traction,
                        displacement=displacement)


def _read_plane(t: Table, dim: int | None) -> PlaneSelector | None:
    p = t.table("plane", keys("boundary.<name>.plane"))
    if p is None:
        return None
    raw_axis = p.choice("axis", ("x", "y", "z", 0, 1, 2))
    axis = AXES.get(raw_axis, raw_axis)
    if axis is not None and dim is not None and axis >= dim:
        p.add("axis", f"axis {fmt(raw_axis)} does not exist in {dim}-D"
                      + (" (use 'x')" if dim == 1 else ""))
        axis = None
    value = p.number("value")
    tol = p.number("tol", default("boundary.<name>.plane", "tol"), check=greater(0))
    if axis is None or value is None or (p.has("tol") and tol is None):
        return None
    return PlaneSelector(axis, value, tol)


def _read_box(t: Table, dim: int | None) -> BoxSelector | None:
    b = t.table("box", keys("boundary.<name>.box"))
    if b is None:
        return None
    lower, upper = b.numbers("lower", dim), b.numbers("upper", dim)
    if lower is None or upper is None:
        return None
    bad = [i for i, (lo, hi) in enumerate(zip(lower, upper)) if hi < lo]
    for i in bad:
        b.report.add(join(b.at("upper"), i), f"must be >= lower[{i}] = {fmt(lower[i])}, "
                                              f"got {fmt(upper[i])}")
    return None if bad else BoxSelector(lower, upper)


def check_parts(report: Report, parts: dict[str, BoundaryPart],
                contacts: tuple[ContactSpec | None, ...], array: bool, raw_contact) -> None:
    """Cross checks: a Dirichlet or contact part exists; every boundary part of kind contact has a contact
    table and every contact table names its own boundary part of kind contact. (Whether the
    Dirichlet parts hold the body is checked on the mesh, by the builder.)"""
    if not contacts and not any(part.kind in DIRICHLET_KINDS for part in parts.values()):
        report.add("boundary", "no boundary part has kind = 'clamped', 'displacement' or "
                               "'symmetry', and no contact part; one is needed to hold the body")
    if any(c is None for c in contacts):
        return  # an invalid contact table: reported where it is
    named = {}
    for i, contact in enumerate(contacts):
        where = join(contact_key(i, array), "boundary")
        if contact.boundary is None:
            continue
        target = parts.get(contact.boundary)
        if target is None:
            report.add(where, f"no boundary part named {contact.boundary!r}"
                              + _suggest(contact.boundary, list(parts)))
        elif target.kind is not None and target.kind != "contact":
            report.add(where, f"boundary part {contact.boundary!r} has kind {target.kind!r}, "
                              "not 'contact'")
        elif contact.boundary in named:
            report.add(where, f"boundary part {contact.boundary!r} has a contact table already "
                              f"({contact_key(named[contact.boundary], array)}); one contact "
                              "condition per part")
        else:
            named[contact.boundary] = i
    for name, part in parts.items():
        if part.kind != "contact" or name in named:
            continue
        where = join(join("boundary", name), "kind")
        if raw_contact is None:
            why = "the scene has no [contact] section"
        elif not contacts:
            why = "contact.type is 'none'"
        else:
            why = "no contact table names it as its boundary"
        if contacts and any(c.boundary not in parts for c in contacts):
            continue  # the misspelt name is reported at the contact table
        report.add(where, f"boundary part {name!r} has kind 'contact' but {why}")


def contact_key(index: int, array: bool) -> str:
    """The scene key of the ``index``-th contact table: ``contact`` or ``contact[index]``."""
    return f"contact[{index}]" if array else "contact"


def _suggest(name: str, names: list[str]) -> str:
    hint = unknown_key(name, names)
    return hint[hint.index(";"):] if names else " (the scene has no boundary parts)"


# -- loads, material, initial state ---------------------------------------------------------

def read_loads(top: Table, dim: int | None) -> LoadSpec:
    """``[loads]``: body force and ``[[loads.point]]`` point loads."""
    t = top.section("loads", keys("loads"))
    body_force = t.exprs("body_force", ("x", "t"), dim, dim, zeros(dim))
    raw = t.data.get("point", [])
    points = []
    if not isinstance(raw, list):
        t.add("point", f"expected an array of tables [[loads.point]], got {type_name(raw)}")
        raw = []
    for i, item in enumerate(raw):
        if not isinstance(item, dict):
            t.report.add(join(t.at("point"), i), f"expected a table, got {type_name(item)}")
            continue
        p = Table(t.report, join(t.at("point"), i), item, keys("loads.point[]"))
        points.append(PointLoad(p.numbers("at", dim), p.exprs("force", ("t",), dim, dim)))
    return LoadSpec(body_force, tuple(points))


def read_material(top: Table, dim: int | None) -> MaterialSpec:
    """``[material]``: E, ν (not in 1-D) and the 2-D model."""
    t = top.section("material", keys("material"), required=True)
    # (E ≤ 0 is not a material; outside [1e-100, 1e100] the stresses leave double precision)
    young = t.number("E", check=lambda v: (greater(0)(v)
                                           or between(MIN_MODULUS, MAX_MODULUS, "[]")(v)))
    nu = plane = None
    if dim == 1:
        t.forbid("nu", "Poisson's ratio is not used in 1-D")
    else:  # required in 2-D and 3-D (optional while the dimension is unknown)
        # ν = 0.5 only with the mixed formulation (checked with [discretization])
        nu = t.number("nu", None if dim is None else REQUIRED, check=between(-1.0, 0.5, "(]"))
    if dim == 2:
        plane = t.choice("plane", ("stress", "strain"), default("material", "plane"))
    elif dim is not None:
        t.forbid("plane", "only for 2-D scenes (plane stress or plane strain)")
    return MaterialSpec(young, nu, plane)


def read_initial(top: Table, dim: int | None) -> InitialSpec:
    """``[initial]``: u_0(x) and σ_0(x) (Voigt order s11 s22 s33 s23 s13 s12, by dimension)."""
    t = top.section("initial", keys("initial"))
    n_stress = {1: 1, 2: 3, 3: 6}.get(dim)
    return InitialSpec(t.exprs("u0", ("x",), dim, dim, zeros(dim)),
                       t.exprs("sigma0", ("x",), dim, n_stress, zeros(n_stress)))


# -- time, solver, output -------------------------------------------------------------------

def read_discretization(top: Table, dim: int | None, material: MaterialSpec,
                        law: LawSpec) -> dict[str, Any]:
    """``[discretization]``: the formulation and the displacement degree, resolved.

    ``formulation = "auto"`` (the default) is ``"mixed"`` (Taylor–Hood P2–P1, free of
    volumetric locking) where P_k displacements lock — 3-D or plane strain with Perzyna's
    isochoric flow, or elasticity with ν ≥ 0.45 (:func:`vpcontact.model.locking.locking_expected`)
    — unless ``degree = 1`` is asked for (the paper's P1/P0 scheme), else ``"displacement"``.
    """
    t = top.section("discretization", keys("discretization"))
    formulation = t.choice("formulation", ("auto",) + FORMULATIONS,
                           default("discretization", "formulation"))
    degree = t.choice("degree", (1, 2), default("discretization", "degree"))
    three_d = dim == 3 or (dim == 2 and material.plane == "strain")
    constants = [law.a, law.b]
    isochoric = law.type in ("elastic", "perzyna") or (
        law.type == "linear" and all(c is not None and c.value() == 0.0 for c in constants))
    nu = material.nu if material.nu is not None else 0.0
    if formulation == "auto":
        locking = locking_expected(three_d, isochoric, law.type == "perzyna", nu)
        formulation = "mixed" if locking and degree != 1 else "displacement"
    if formulation == "mixed":
        if dim is not None and not three_d:
            t.add("formulation", "the mixed formulation is for 3-D and plane-strain bodies "
                                 "(in plane stress and 1-D nothing locks)")
        elif law.type is not None and not isochoric:
            t.add("formulation", "the mixed formulation needs a law whose flow keeps the volume "
                                 "(elastic or perzyna); use formulation = \"displacement\"")
        if degree == 1:
            t.add("degree", "the mixed formulation is Taylor–Hood (P2 displacements, P1 "
                            "pressure): use degree = 2, or leave degree out")
        degree = 2
    elif nu == 0.5:
        t.report.add("material.nu", "nu = 0.5 (incompressible) needs [discretization] "
                                    "formulation = \"mixed\" (3-D or plane strain)")
    return {"formulation": formulation, "degree": degree if degree is not None else 1}


def read_time(top: Table) -> TimeSpec:
    """``[time]``: T > 0, 0 < k ≤ T, max_cuts, scheme, tolerance."""
    t = top.section("time", keys("time"), required=True)
    final, step = t.number("T", check=greater(0)), t.number("k", check=greater(0))
    if final is not None and step is not None:
        if step > final:
            t.add("k", f"must be <= T = {fmt(final)}, got {fmt(step)}")
        elif final / step > MAX_STEPS:
            t.add("k", f"too many time steps (T/k = {final / step:.3g}, at most {MAX_STEPS})")
    max_cuts = t.integer("max_cuts", default("time", "max_cuts"),
                         check=between(0, MAX_CUTS, "[]"))
    scheme = t.choice("scheme", TIME_SCHEMES, default("time", "scheme"))
    tolerance = t.number("tolerance", default("time", "tolerance"), check=between(0.0, 1.0))
    return TimeSpec(final, step, max_cuts, scheme, tolerance)


def read_solver(top: Table) -> SolverSpec:
    """``[solver]``: predictor, linear solver and PETSc options (keys without the leading "-")."""
    t = top.section("solver", keys("solver"))
    predictor = t.choice("predictor", ("linear", "none"), default("solver", "predictor"))
    linear = t.choice("linear", LINEAR_SOLVERS, default("solver", "linear"))
    raw = t.data.get("petsc_options", {})
    if not isinstance(raw, dict):
        t.add("petsc_options", f"expected a table, got {type_name(raw)}")
        raw = {}
    options = {}
    for key, value in raw.items():
        path = join(t.at("petsc_options"), key)
        message = _petsc_option_problem(key, value)
        if message is not None:
            t.report.add(path, message)
        else:
            options[key] = value
    return SolverSpec(predictor, options, linear)


def _petsc_option_problem(key: str, value: Any) -> str | None:
    if key.startswith("-"):
        return "write PETSc option names without the leading '-'"
    if not re.fullmatch(PETSC_KEY, key):
        return f"PETSc option name {key!r} must match {PETSC_KEY}"
    if isinstance(value, float) and not math.isfinite(value):
        return f"must be finite, got {fmt(value)}"
    if isinstance(value, str) and (len(value) > 1000 or not value.isprintable()):
        return "must be a printable string of at most 1000 characters"
    if not isinstance(value, (str, int, float, bool)):
        return f"expected a string, number or boolean, got {type_name(value)}"
    return None


def read_output(top: Table, contacts: tuple, dim: int | None = None) -> OutputSpec:
    """``[output]``: XDMF, contact CSV (only with contact), figures, XDMF stride, checkpoints,
    probes."""
    t = top.section("output", keys("output"))
    contact_csv = t.boolean("contact_csv", bool(contacts))
    if contact_csv and not contacts:
        t.add("contact_csv", "needs a [contact] section with type other than 'none'")
    return OutputSpec(xdmf=t.boolean("xdmf", default("output", "xdmf")), contact_csv=contact_csv,
                      figures=t.boolean("figures", default("output", "figures")),
                      every=t.integer("every", default("output", "every"), check=at_least(1)),
                      checkpoint_every=t.integer("checkpoint_every",
                                                 default("output", "checkpoint_every"),
                                                 check=at_least(0)),
                      probes=_read_probes(t, dim))


def _read_probes(t: Table, dim: int | None) -> tuple:
    """``[output] probes``: points ``[[x, y(, z)], …]`` of ``dim`` finite numbers each (whether
    they lie in the mesh is checked once it is built: :mod:`vpcontact.output.probes`)."""
    raw = t.data.get("probes", default("output", "probes"))
    if not isinstance(raw, (list, tuple)):
        t.add("probes", f"expected an array of points [[x, y(, z)], …], got {type_name(raw)}")
        return ()
    points = []
    for i, item in enumerate(raw):
        numbers = isinstance(item, list) and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in item)
        if not numbers or (dim is not None and len(item) != dim):
            t.report.add(join(t.at("probes"), i),
                         f"expected a point of {dim or 'one per dimension'} finite numbers, "
                         f"got {fmt(item)}")
        else:
            points.append(tuple(float(v) for v in item))
    return tuple(points)
