# SPDX-License-Identifier: MIT
"""From a scene (:mod:`vpcontact.scene`) to a :class:`~vpcontact.solver.problem.QuasistaticProblem`.

Only what the scene calls for is built: an elastic law runs the linear stress update (never the
viscoplastic kernel), a scene without ``[contact]`` gets neither a compliance term nor a
variational inequality, and a law linear in ε is factorized once per step size
(see :class:`~vpcontact.solver.step_solver.StepSolver`). Problems found on the mesh (a boundary part
that selects no facets, parts that overlap, a Gmsh tag that does not exist, a point load off
the vertices) are reported with their place in the scene file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Dict, Optional

import numpy as np
import ufl
from dolfinx import fem, mesh as dmesh
from mpi4py import MPI

from vpcontact.model.extent import mesh_extent
from vpcontact.model.constitutive import Elastic, Elasticity, LinearRate, Perzyna, PlaneStrain
from vpcontact.model.friction import Friction, FrictionLaw
from vpcontact.model.normal_compliance import NormalCompliance
from vpcontact.errors import InputError, SolverOptionError
from vpcontact.solver.loads import Loads, PointLoad
from vpcontact.solver.problem import QuasistaticProblem
from vpcontact.kernels.mandel import voigt_to_mandel_factors
from vpcontact.scene.files import Scene
from vpcontact.scene.finite import check_assembled_loads, check_finite
from vpcontact.scene.gmsh_files import gmsh_session
from vpcontact.scene.specs import ObstacleShape
from vpcontact.model.obstacle import rotation_matrix, shape_level_set
from vpcontact.model.contact_nodes import Surface, axis_aligned_normal, contact_dofs
from vpcontact.model.signorini import Signorini
from vpcontact.solver.dirichlet import Dirichlet

_CELL_TYPES = {"interval": dmesh.CellType.interval, "triangle": dmesh.CellType.triangle,
               "quadrilateral": dmesh.CellType.quadrilateral,
               "tetrahedron": dmesh.CellType.tetrahedron, "hexahedron": dmesh.CellType.hexahedron}
_DIAGONALS = {"right": dmesh.DiagonalType.right, "left": dmesh.DiagonalType.left,
              "crossed": dmesh.DiagonalType.crossed, "left/right": dmesh.DiagonalType.left_right,
              "right/left": dmesh.DiagonalType.right_left}


@dataclass
class Model:
    """A built scene: the problem and what the outputs need to know about it."""

    scene: Scene
    problem: QuasistaticProblem
    facet_tags: dmesh.MeshTagsMetaClass
    part_tags: Dict[str, int]           # boundary part name -> facet tag


def build(scene: Scene, comm=MPI.COMM_WORLD) -> Model:
    """Build the mesh, boundary parts, law, loads, contact and initial state of ``scene``.

    Raises:
        SceneError: a problem only visible on the mesh, located in the scene file.
    """
    mesh, gmsh_tags = _mesh(scene, comm)
    _check_partition(scene, mesh)
    part_tags, facet_tags = _boundary_parts(scene, mesh, gmsh_tags)
    law = _law(scene)
    limit = law.explicit_step_limit()
    if scene.time.k > limit:
        raise scene.error("time.k", f"k = {scene.time.k:g} exceeds the stability limit "
                          f"{limit:.4g} of the explicit scheme (2/L from the law's data); use "
                          "scheme = \"implicit\" or a smaller k")
    check_finite(scene, mesh, part_tags, facet_tags)
    loads = _loads(scene, part_tags)
    dirichlet = _dirichlet(scene, part_tags, mesh, facet_tags)
    try:
        contacts = _contacts(scene, part_tags, mesh, facet_tags)
        problem = QuasistaticProblem(mesh, facet_tags, law, loads=loads, dirichlet=dirichlet,
                                     contact=contacts, degree=scene.degree,
                                     formulation=scene.formulation,
                                     petsc_options=dict(scene.solver.petsc_options),
                                     predictor=scene.solver.predictor,
                                     linear=scene.solver.linear,
                                     time_scheme=scene.time.scheme)
        problem.check_held(_check_times(scene))
    except SolverOptionError as err:
        if err.problems:  # several options, each at its line
            raise scene.errors({f"solver.petsc_options.{option}": message
                                for option, message in err.problems.items()}) from None
        known = err.option is not None and err.option in scene.solver.petsc_options
        raise scene.error("solver.petsc_options" + (f".{err.option}" if known else ""),
                          str(err)) from None
    except InputError as err:  # located at the key its raiser named (the mesh if none)
        raise scene.error(_scene_key(scene, err), str(err)) from None
    if problem.V.ufl_element().degree() > 1:  # the nodes where values are interpolated
        check_finite(scene, mesh, part_tags, facet_tags, nodes=problem.V)
    check_assembled_loads(scene, problem, part_tags, facet_tags)
    _check_contact_output(scene, mesh, facet_tags, part_tags)
    _initial_state(scene, problem)
    return Model(scene, problem, facet_tags, part_tags)


def _check_partition(scene: Scene, mesh) -> None:
    """Every process needs cells (collective): one without any raised in the set-up while the
    others waited for it in a collective call (a 1-cell bar on 2 ranks hung)."""
    comm, tdim = mesh.comm, mesh.topology.dim
    cells = mesh.topology.index_map(tdim).size_local
    if comm.allreduce(int(cells == 0), op=MPI.SUM):
        total = comm.allreduce(cells, op=MPI.SUM)
        raise scene.error("mesh" if scene.mesh.type == "gmsh" else "mesh.cells",
                          f"the mesh has {total} cell(s), too few for {comm.size} processes "
                          "(each needs some): refine it or run on fewer processes")


def _scene_key(scene: Scene, err: InputError) -> str:
    """The scene key of an error: its own, with ``contact`` made the key of the contact table
    of the part it names (``contact[1].obstacle``); the mesh if it has none."""
    key = err.key or "mesh"
    if err.part is not None and (key == "contact" or key.startswith("contact.")):
        index, _ = scene.contact_part(err.part)
        key = scene.contact_key(index) + key[len("contact"):]
    return key


def _check_contact_output(scene: Scene, mesh, facet_tags, part_tags) -> None:
    """Normal compliance's contact output (contact.csv, figures) is recorded at the nodes of Γ3
    in their vertex normals, which a face that is not an axis-aligned plane has for P1 only."""
    output = scene.output
    if scene.degree == 1 or not (output.contact_csv or output.figures):
        return
    for spec in scene.contacts:
        if spec.type != "normal_compliance":
            continue
        if axis_aligned_normal(mesh, facet_tags, part_tags[spec.boundary]) is None:
            raise scene.error("discretization.degree", (
                f"normal compliance with degree = {scene.degree} on a contact face "
                f"({spec.boundary!r}) that is not an axis-aligned plane: its contact output "
                "(contact.csv, figures) is recorded in vertex normals, for P1 displacements only; "
                "use degree = 1, or set [output] contact_csv = false and figures = false to run "
                "it without that output"))


def _mesh(scene: Scene, comm):
    spec = scene.mesh
    if spec.type == "gmsh":
        mesh, facet_tags = _read_gmsh(scene, comm)
        return mesh, facet_tags
    cell = _CELL_TYPES[spec.cell_type]
    lower, upper = np.array(spec.lower, dtype=float), np.array(spec.upper, dtype=float)
    if spec.dim == 1:
        return dmesh.create_interval(comm, spec.cells[0], [lower[0], upper[0]]), None
    if spec.dim == 2:
        diagonal = _DIAGONALS[spec.diagonal or "right"]
        mesh = dmesh.create_rectangle(comm, [lower, upper], list(spec.cells), cell,
                                      diagonal=diagonal)
    else:
        mesh = dmesh.create_box(comm, [lower, upper], list(spec.cells), cell)
    for box_lower, box_upper in spec.refine:
        mesh = refined_in_box(mesh, np.array(box_lower), np.array(box_upper))
    return mesh, None


def refined_in_box(mesh, lower: np.ndarray, upper: np.ndarray):
    """``mesh`` with every edge that lies in the box [lower, upper] split (Plaza's refinement,
    which splits neighbouring cells as needed to keep the mesh conforming)."""
    dim = mesh.topology.dim
    tol = 1e-12 * float(np.max(upper - lower))

    def inside(x):
        return np.all((x[:dim] >= lower[:, None] - tol) & (x[:dim] <= upper[:, None] + tol), axis=0)

    mesh.topology.create_entities(1)
    edges = dmesh.locate_entities(mesh, 1, inside)
    return dmesh.refine(mesh, edges, redistribute=True)


def _read_gmsh(scene: Scene, comm):
    """Mesh and facet tags of a .msh file, read on rank 0 and distributed.

    (dolfinx 0.5's ``gmshio.read_from_msh`` is broken; ``model_to_mesh`` is used directly.) Rank 0
    checks the file first and shares the verdict, so a bad file fails on every rank together.
    """
    from dolfinx.io import gmshio
    with gmsh_session(comm) as gmsh:
        problem, key = None, "mesh.file"
        if gmsh is not None:
            try:
                gmsh.model.add("scene")
                gmsh.merge(str(scene.mesh.file))
                dims = sorted({d for d, _ in gmsh.model.getPhysicalGroups()})
                model_dim = gmsh.model.getDimension()
                if model_dim in (1, 2, 3) and model_dim != scene.mesh.dim:
                    key = "mesh.dim"
                    problem = (f"the Gmsh file holds a {model_dim}-D mesh but dim = "
                               f"{scene.mesh.dim}: set dim = {model_dim}")
                elif not gmsh.model.getPhysicalGroups(scene.mesh.dim):
                    problem = (f"the Gmsh file has no physical group of dimension "
                               f"{scene.mesh.dim} (the cells to use)"
                               + (f"; its groups have dimension {', '.join(map(str, dims))}"
                                  if dims else ""))
                elif len(kinds := gmsh.model.mesh.getElementTypes(scene.mesh.dim)) > 1:
                    names = [gmsh.model.mesh.getElementProperties(k)[0] for k in kinds]
                    problem = (f"the Gmsh mesh mixes cell types ({', '.join(names)}): dolfinx "
                               "takes one kind per mesh; mesh it with one (e.g. all triangles, "
                               "or Mesh.RecombineAll = 1 for all quadrilaterals)")
            except Exception as err:  # gmsh raises plain Exceptions for unreadable files
                problem = f"cannot read the Gmsh file: {err}"
        problem, key = comm.bcast((problem, key), root=0)
        if problem is not None:
            raise scene.error(key, problem)
        mesh, _, facet_tags = gmshio.model_to_mesh(gmsh.model if gmsh is not None else None,
                                                   comm, 0, gdim=scene.mesh.dim)
    return mesh, facet_tags


def _boundary_parts(scene: Scene, mesh, gmsh_tags):
    """One facet tag per part (1, 2, ... in scene order); every part non-empty, none overlapping."""
    fdim = mesh.topology.dim - 1
    mesh.topology.create_connectivity(fdim, mesh.topology.dim)
    extent = mesh_extent(mesh)
    indices, values, part_tags = [], [], {}
    for i, (name, part) in enumerate(scene.boundaries.items(), start=1):
        if part.tag is not None:
            found = gmsh_tags.find(part.tag) if gmsh_tags is not None else np.zeros(0, np.int32)
            boundary = dmesh.exterior_facet_indices(mesh.topology)
            facets = np.intersect1d(found, boundary).astype(np.int32)
            what = f"Gmsh physical tag {part.tag} marks no boundary facet"
        else:
            facets = dmesh.locate_entities_boundary(mesh, fdim, _selector(part, extent))
            what = "selects no boundary facet"
        if mesh.comm.allreduce(len(facets), op=MPI.SUM) == 0:
            raise scene.error(f"boundary.{name}", f"boundary part '{name}' {what}")
        part_tags[name] = i
        indices.append(facets)
        values.append(np.full(len(facets), i, dtype=np.int32))
    indices, values = np.concatenate(indices), np.concatenate(values)
    unique, counts = np.unique(indices, return_counts=True)
    shared = np.isin(indices, unique[counts > 1])
    clash = sorted(set().union(*mesh.comm.allgather(set(values[shared].tolist()))))
    if clash:
        names = [n for n, t in part_tags.items() if t in clash]
        raise scene.error(f"boundary.{names[-1]}", "boundary parts " + ", ".join(
            f"'{n}'" for n in names) + " overlap: a facet may belong to one part only")
    order = np.argsort(indices)
    tags = dmesh.meshtags(mesh, fdim, indices[order].astype(np.int32), values[order])
    return part_tags, tags


def _selector(part, extent: float):
    if part.plane is not None:
        axis, value = part.plane.axis, part.plane.value
        tol = part.plane.tol if part.plane.tol is not None else 1e-8 * extent
        return lambda x: np.abs(x[axis] - value) <= tol
    if part.box is not None:
        tol = 1e-10 * extent
        lo, hi = np.array(part.box.lower), np.array(part.box.upper)
        d = len(lo)
        return lambda x: np.all((x[:d] >= lo[:, None] - tol) & (x[:d] <= hi[:, None] + tol), axis=0)
    expr = part.where
    return lambda x: np.asarray(expr.numpy(x), dtype=bool) & np.ones(x.shape[1], dtype=bool)


def _dirichlet(scene: Scene, part_tags, mesh, facet_tags) -> list:
    """The clamped, prescribed-displacement and symmetry parts, in scene order."""
    dim = scene.dim
    parts = []
    for name, part in scene.boundaries.items():
        tag = part_tags[name]
        if part.kind == "clamped":
            parts.append(Dirichlet.clamped(tag, dim, name))
        elif part.kind == "displacement":
            parts.append(Dirichlet(tag, tuple(_component(e) for e in part.displacement), name))
        elif part.kind == "symmetry":
            aligned = axis_aligned_normal(mesh, facet_tags, tag) if dim > 1 else (0, 1.0)
            if aligned is None:
                raise scene.error(f"boundary.{name}", f"symmetry part '{name}' must be a plane "
                                  "with an axis-aligned normal (u·n = 0 is imposed on the normal "
                                  "component); for other planes prescribe components instead")
            parts.append(Dirichlet.symmetry(tag, dim, aligned[0], name))
    return parts


def _component(expression):
    """A prescribed component: None (free), a number, or a function (x, t) -> values."""
    if expression is None:
        return None
    if expression.is_constant:
        return expression.value()
    return lambda x, t, e=expression: e.numpy(x, t)


def _law(scene: Scene):
    spec, mat, dim = scene.law, scene.material, scene.dim
    strain = dim == 2 and mat.plane == "strain"
    if dim == 3:  # "paper": the set printed in §4.1.2; "von_mises": the standard one
        model = "3d_standard" if spec.yield_set == "von_mises" else "3d"
    elif strain:  # a 3-D law with ε33 = 0, with the standard von Mises set
        model = "3d_standard"
    else:
        model = {1: "1d", 2: "plane_stress"}[dim]
    law = _law3(spec, Elasticity(model, mat.E, mat.nu if mat.nu is not None else 0.0))
    return PlaneStrain(law) if strain else law


def _law3(spec, elasticity):
    if spec.type == "elastic":
        return Elastic(elasticity)
    if spec.type == "linear":
        return LinearRate(elasticity, spec.a.value(), spec.b.value(), scheme=spec.scheme)
    return Perzyna(elasticity, sigma_y=spec.sigma_y.value(), mu_star=spec.mu_star.value(),
                   scheme=spec.scheme)


def _vector(exprs, dim):
    """(x, t) -> UFL vector (scalar in 1-D) of expressions."""
    def load(x, t):
        parts = [e.ufl(x, t) for e in exprs]
        return parts[0] if dim == 1 else ufl.as_vector(parts)
    return load


def _is_zero(exprs) -> bool:
    return all(e.is_constant and e.value() == 0.0 for e in exprs)


def _loads(scene: Scene, part_tags) -> Loads:
    dim = scene.dim
    loads = Loads()
    if not _is_zero(scene.loads.body_force):
        loads.body_force = _vector(scene.loads.body_force, dim)
    for name, part in scene.boundaries.items():
        if part.kind == "traction" and part.traction is not None and not _is_zero(part.traction):
            loads.tractions[part_tags[name]] = _vector(part.traction, dim)
    for p in scene.loads.point:
        force = p.force
        loads.points.append(PointLoad(tuple(p.at), lambda t, f=force: [e.value(t) for e in f]))
    return loads


def obstacle_level_set(spec, dim: int):
    """The obstacle of a contact table as a function φ(x) or φ(x, t), and whether it takes t."""
    obstacle = spec.obstacle
    if isinstance(obstacle, ObstacleShape):
        return shape_level_set(obstacle.shape, dict(obstacle.params), dim), False
    if obstacle.depends_on_time:
        return (lambda x, t: obstacle.numpy(x, t)), True
    return (lambda x: obstacle.numpy(x)), False


def _contacts(scene: Scene, part_tags, mesh, facet_tags) -> dict:
    """The contact parts' conditions, by boundary part name, in file order."""
    contacts = {}
    for spec in scene.contacts:
        try:
            contacts[spec.boundary] = _condition(scene, spec, part_tags[spec.boundary], mesh,
                                                 facet_tags)
        except InputError as err:
            err.part = spec.boundary
            raise
    return contacts


def _condition(scene: Scene, spec, tag: int, mesh, facet_tags):
    """The law of one contact table on the facets ``tag``."""
    gap = spec.gap
    if spec.type == "normal_compliance":
        if spec.obstacle is not None:
            phi, _ = obstacle_level_set(spec, scene.dim)
            surface = Surface(tag, obstacle=phi, max_distance=spec.max_distance or 1e3)
            g = _foundation_gap(mesh, facet_tags, surface)
        elif gap is None or gap.is_constant:
            g = 0.0 if gap is None else gap.value()
            surface = None
        else:
            g = gap.ufl(ufl.SpatialCoordinate(mesh), 0.0)
            surface = Surface(tag, gap=lambda x: gap.numpy(x))
        return NormalCompliance(tag, mu=spec.mu, alpha=spec.alpha, gap=g, surface=surface,
                                friction=_friction(spec.friction))
    if spec.obstacle is not None and spec.force is not None:
        phi, _ = obstacle_level_set(spec, scene.dim)
        force = spec.force
        return Signorini(tag, obstacle=phi, max_distance=spec.max_distance or 1e3,
                         force=lambda t: np.array([e.value(t) for e in force]),
                         force_direction=_force_direction(scene, force),
                         friction=_friction(spec.friction))
    if spec.obstacle is not None:
        phi, moves = obstacle_level_set(spec, scene.dim)
        motion = spec.motion
        translation = (None if motion is None or all(e.is_constant and e.value() == 0.0
                                                       for e in motion)
                       else (lambda t: np.array([e.value(t) for e in motion])))
        turn = spec.rotation
        rotation = (None if turn is None else
                    (lambda t: rotation_matrix(turn.axis or (0.0, 0.0, 1.0), turn.angle.value(t))))
        center = (0.0,) * 3 if turn is None else turn.center + (0.0,) * (3 - len(turn.center))
        return Signorini(tag, obstacle=phi, max_distance=spec.max_distance or 1e3,
                         obstacle_moves=moves, translation=translation, rotation=rotation,
                         rotation_center=center, friction=_friction(spec.friction),
                         normals=spec.normals)
    if gap is None or gap.is_constant:
        return Signorini(tag, gap=0.0 if gap is None else gap.value(),
                         friction=_friction(spec.friction))
    return Signorini(tag, gap=lambda x: gap.numpy(x), friction=_friction(spec.friction))


def _friction(spec) -> Optional[FrictionLaw]:
    """The friction law of a contact table (None: frictionless), from the friction module's
    factory."""
    if spec is None:
        return None
    threshold = spec.threshold
    if threshold is None or threshold.is_constant:
        return Friction(spec.type, coefficient=spec.coefficient,
                        threshold=None if threshold is None else threshold.value())
    return Friction(spec.type, coefficient=spec.coefficient,
                    threshold=lambda x: threshold.ufl(x, 0.0),
                    threshold_at=lambda x: threshold.numpy(x))


def _check_times(scene: Scene, count: int = 16) -> np.ndarray:
    """t = 0 and up to ``count`` step times, evenly spread, for checks over the run."""
    steps = max(1, int(math.ceil(scene.time.T / scene.time.k - 1e-9)))
    return np.linspace(0.0, scene.time.T, min(steps, count) + 1)


def _force_direction(scene: Scene, force) -> tuple:
    """The fixed direction e of a force F(t) = |F(t)| e that presses an obstacle: F is checked
    at t = 0 and at the step times (at most 256 of them, evenly spread): parallel to one e, in
    its sense, and nonzero for t > 0 (with no force the obstacle has no equilibrium)."""
    steps = max(1, int(math.ceil(scene.time.T / scene.time.k - 1e-9)))
    times = np.linspace(0.0, scene.time.T, min(steps, 256) + 1)
    values = np.array([[e.value(t) for e in force] for t in times])
    sizes = np.linalg.norm(values, axis=1)
    largest = int(np.argmax(sizes))
    if sizes[largest] == 0:
        raise InputError("the force is zero at every step: an obstacle driven by a force needs "
                         "one (use a motion to hold it)", key="contact.force")
    direction = values[largest] / sizes[largest]
    for t, value, size in zip(times, values, sizes):
        if t > 0 and size == 0:
            raise InputError(f"the force is zero at t = {t:g}: an obstacle driven by a force "
                             "must be pressed at every t > 0 (it has no equilibrium otherwise)",
                             key="contact.force")
        if np.linalg.norm(value - (value @ direction) * direction) > 1e-9 * size or (
                value @ direction < 0):
            raise InputError(f"the force turns: at t = {t:g} it is {value.tolist()}, not along "
                             f"{direction.round(12).tolist()} (an obstacle driven by a force "
                             "translates along one fixed direction)", key="contact.force")
    return tuple(direction) + (0.0,) * (3 - len(direction))


def _foundation_gap(mesh, facet_tags, surface: Surface):
    """Normal compliance against a foundation surface: g at each node of Γ3 is the distance to
    it along the node's normal (as for a Signorini obstacle), interpolated by P1 functions."""
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", 1))
    cd = contact_dofs(V, facet_tags, surface, rotate=True)
    g = fem.Function(fem.FunctionSpace(mesh, ("Lagrange", 1)), name="gap")
    g.x.array[cd.nodes] = cd.gap
    g.x.scatter_forward()
    return g


def _initial_state(scene: Scene, problem: QuasistaticProblem) -> None:
    init, dim = scene.initial, scene.dim
    if not _is_zero(init.u0):
        exprs = init.u0
        problem.u.interpolate(lambda x: np.vstack([np.broadcast_to(e.numpy(x), x.shape[1:])
                                                   for e in exprs]))
        comm = problem.mesh.comm  # (collective: the bad node may lie on one process only)
        if comm.allreduce(not np.isfinite(problem.u.x.array).all(), op=MPI.LOR):
            raise scene.error("initial.u0", "u0 is not finite at some mesh node")
        st = problem.state
        st.view(st.strain_old)[:] = st.strain_at_points()
    if not _is_zero(init.sigma0):
        exprs = init.sigma0
        factors = voigt_to_mandel_factors(dim)  # s11 | s11 s22 s12 | s11 s22 s33 s23 s13 s12

        def sigma0(points):
            n = points.shape[1]
            cols = [np.broadcast_to(e.numpy(points[:dim]), (n,)) for e in exprs]
            return np.stack(cols, axis=1) * factors

        problem.set_initial_stress(sigma0)
        if problem.mesh.comm.allreduce(not np.isfinite(problem.state.stress.x.array).all(),
                                       op=MPI.LOR):
            raise scene.error("initial.sigma0", "sigma0 is not finite at some quadrature point")

