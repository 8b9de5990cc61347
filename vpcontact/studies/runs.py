# SPDX-License-Identifier: MIT
"""Convergence and work–precision studies of a scene (``vpcontact study convergence|cost``).

A study runs one scene many times, each time with a *variant* of its discretisation: the mesh
refined ``2^i`` times per direction, the step divided by ``2^j``, the displacement degree, the
law's scheme (explicit/implicit Euler) and the time scheme (Euler/BDF2). Every run is sampled on
the same grid: the vertices of the coarsest mesh (a vertex of every refinement, so P1 and P2
runs are compared at their own nodal values, without interpolation) at the multiples of the
coarsest step (every run lands on them: :func:`vpcontact.solver.stepping.advance` ends exactly at its
final time). The error of a run is

    max over sampled times t and vertices x of |u_run(x, t) - u_ref(x, t)|   (all components),

the paper's "max nodal displacement error", against an exact solution where one is given
(``--exact paper_1d``: eqs. (21)-(22) for the §4.2.1 bar; or ``--exact "EXPR; ..."``, u(x, t) as
one expression of x and t per component, read by the scenes' safe evaluator). Without one, the
convergence study does not measure its runs against a finer run and fit that (the finer run's
own error biases the fit upwards: a first-order ramped Perzyna bar came out at order 1.47); it
estimates the order from the differences of successive runs (Richardson,
:func:`richardson`). The work–precision study compares with a finer run of the most accurate
variant. Wall time is that of the time loop on the slowest rank (mesh, forms and
sampling excluded; each method's coarsest run is done once untimed first, since a process's first
run of a method pays one-off costs); work is also counted as dofs × steps.
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from dataclasses import dataclass
from typing import Callable, Optional, Sequence

import numpy as np
from mpi4py import MPI

from vpcontact.errors import InputError, VpcontactError
from vpcontact.paper import bar1d
from vpcontact.scene import builder, expressions
from vpcontact.solver.stepping import StepControl, advance


@dataclass(frozen=True)
class Method:
    """How a run discretises the scene, apart from h and k."""

    degree: int = 1
    law_scheme: str = "implicit"   # "explicit" | "implicit" | "linearized" (the law's Euler)
    time_scheme: str = "euler"     # "euler" | "bdf2"
    tolerance: Optional[float] = None  # adaptive steps (k then the largest step), or uniform

    @property
    def label(self) -> str:
        scheme = "BDF2" if self.time_scheme == "bdf2" else f"{self.law_scheme} Euler"
        adaptive = "" if self.tolerance is None else f", adaptive {self.tolerance:g}"
        return f"P{self.degree}, {scheme}{adaptive}"


@dataclass
class Run:
    """One run of a study: its variant, cost and error (None until compared)."""

    method: Method
    level_h: int
    level_k: int
    h: float                       # mesh size: the largest cell edge of the box grid
    k: float
    dofs: int = 0
    steps: int = 0
    newton_iterations: int = 0
    wall_time: float = 0.0
    error: Optional[float] = None
    difference: Optional[float] = None  # max |u - u_finer| to the next finer run (Richardson)
    skipped: str = ""              # why the variant could not run ("" if it ran)
    samples: Optional[np.ndarray] = dataclasses.field(default=None, repr=False)

    @property
    def work(self) -> int:
        return self.dofs * self.steps


# -- exact solutions --------------------------------------------------------------------------

def _paper_1d(scene) -> Callable[[np.ndarray, float], np.ndarray]:
    c = scene.contact  # the first (the bar has one)
    same = (scene.dim == 1 and scene.law.type == "linear" and scene.material.E == bar1d.YOUNG
            and scene.law.a.value() == bar1d.G_A and scene.law.b.value() == bar1d.G_B
            and c.type == "normal_compliance" and c.mu == bar1d.MU and c.alpha == 1.0
            and c.gap is not None and c.gap.is_constant and c.gap.value() == bar1d.GAP
            and tuple(scene.mesh.lower) == (0.0,) and tuple(scene.mesh.upper) == (1.0,))
    if not same:
        raise InputError("--exact paper_1d: the scene is not the paper's §4.2.1 bar (E = 10, "
                         "G = -σ + 10ε, μ = 100, α = 1, g = 0.25 on (0, 1))")
    return lambda x, t: bar1d.exact_displacement(x[:, 0], t)[:, None]


#: Exact solutions a study can compare against, by name.
EXACT = {"paper_1d": _paper_1d}

#: Separates the components of an exact solution given as expressions.
COMPONENT_SEPARATOR = ";"


def _expression(scene, text: str) -> Callable[[np.ndarray, float], np.ndarray]:
    """u(x, t) given as expressions of ``x[i]`` and ``t``, one per displacement component,
    separated by :data:`COMPONENT_SEPARATOR` (e.g. ``"x[0]*(0.02*t + max(t - 0.5, 0)**2)"`` for
    a 1-D bar). They are checked by :func:`vpcontact.scene.expressions.parse` (a whitelist walked
    on the syntax tree, never Python's eval)."""
    texts = [part.strip() for part in text.split(COMPONENT_SEPARATOR)]
    if len(texts) != scene.dim:
        raise InputError(f"--exact: {len(texts)} expression(s) for the {scene.dim} displacement "
                         f"component(s) of this {scene.dim}-D scene (separate them by "
                         f"{COMPONENT_SEPARATOR!r})")
    parsed = [expressions.parse(part, names=("x", "t"), dim=scene.dim) for part in texts]

    def exact(x: np.ndarray, t: float) -> np.ndarray:
        return np.stack([e.numpy(np.asarray(x, float).T, t) for e in parsed], axis=1)
    return exact


# -- one run ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Grid:
    """The sampling grid: the coarsest mesh's vertices and the coarsest step's multiples."""

    lower: np.ndarray
    upper: np.ndarray
    cells: tuple
    times: np.ndarray

    @property
    def points(self) -> np.ndarray:
        axes = [np.linspace(lo, hi, n + 1) for lo, hi, n in zip(self.lower, self.upper, self.cells)]
        mesh = np.meshgrid(*axes, indexing="ij")
        return np.stack([m.ravel() for m in mesh], axis=1)


def make_grid(scene, cells: Optional[Sequence[int]], k: Optional[float],
              t_final: Optional[float]) -> Grid:
    """The coarsest level: the scene's mesh and step unless ``cells``/``k``/``t_final`` given."""
    if scene.mesh.type == "gmsh":
        raise InputError("studies refine built-in meshes only (the scene reads a Gmsh file)")
    base = tuple(int(c) for c in (cells or scene.mesh.cells))
    if len(base) != len(scene.mesh.cells) or min(base) < 1:
        raise InputError(f"--cells needs {len(scene.mesh.cells)} positive integer(s), "
                         f"got {list(base)}")
    T = float(t_final if t_final is not None else scene.time.T)
    step = float(k if k is not None else scene.time.k)
    if not (T > 0 and step > 0 and math.isfinite(T) and math.isfinite(step)):
        raise InputError(f"--T and --k must be positive, got T = {T}, k = {step}")
    n = round(T / step)
    if n < 1 or not math.isclose(n * step, T, rel_tol=1e-9):
        raise InputError(f"k = {step:g} must divide T = {T:g}")
    if n > 100_000:
        raise InputError(f"too many steps at the coarsest level (T/k = {n})")
    return Grid(np.array(scene.mesh.lower, float), np.array(scene.mesh.upper, float), base,
                step * np.arange(1, n + 1))


def variant_scene(scene, grid: Grid, run: Run):
    """The scene with the run's mesh, step, degree and schemes."""
    cells = tuple(c * 2 ** run.level_h for c in grid.cells)
    mesh = dataclasses.replace(scene.mesh, cells=cells)
    time = dataclasses.replace(scene.time, T=float(grid.times[-1]), k=run.k,
                               scheme=run.method.time_scheme)
    law = dataclasses.replace(scene.law, scheme=run.method.law_scheme)
    # P1 is the displacement formulation (the mixed one is Taylor–Hood, P2)
    formulation = "displacement" if run.method.degree == 1 else scene.formulation
    return dataclasses.replace(scene, mesh=mesh, time=time, law=law, degree=run.method.degree,
                               formulation=formulation)


def new_run(grid: Grid, method: Method, level_h: int, level_k: int) -> Run:
    spacing = (grid.upper - grid.lower) / np.array(grid.cells)
    h = float(np.linalg.norm(spacing)) / 2 ** level_h
    k = float(grid.times[0]) / 2 ** level_k
    return Run(method, level_h, level_k, h, k)


class _Sampler:
    """Nodal displacements at the grid's points (every grid point is a node of every level)."""

    def __init__(self, V, grid: Grid):
        self.comm = V.mesh.comm
        bs = V.dofmap.index_map_bs
        dim = len(grid.cells)
        # node coordinates through the first component (dolfinx cannot tabulate them for a
        # vector space of dimension 1); its parent dofs are bs * node in the blocked layout
        V0, parent = V.sub(0).collapse()
        n_owned = V0.dofmap.index_map.size_local
        x = V0.tabulate_dof_coordinates()[:n_owned, :dim]
        node = np.asarray(parent[:n_owned]) // bs
        spacing = (grid.upper - grid.lower) / np.array(grid.cells)
        idx = (x - grid.lower) / spacing
        nearest = np.rint(idx)
        on = (np.all(np.abs(idx - nearest) < 1e-8, axis=1)
              & np.all((nearest >= 0) & (nearest <= np.array(grid.cells)), axis=1))
        self.nodes = node[on]
        self.flat = np.ravel_multi_index(nearest[on].astype(np.int64).T,
                                         tuple(c + 1 for c in grid.cells))
        self.bs, self.n_points = bs, int(np.prod([c + 1 for c in grid.cells]))
        found = self.comm.allreduce(len(self.flat), op=MPI.SUM)
        if found != self.n_points:  # shared nodes are owned once, so this is exact
            raise InputError(f"{found} of the {self.n_points} grid vertices are nodes of the mesh")

    def __call__(self, u) -> np.ndarray:
        values = u.x.array.reshape(-1, self.bs)[self.nodes]
        out = np.zeros((self.n_points, self.bs))
        out[self.flat] = values
        return self.comm.allreduce(out, op=MPI.SUM)


def execute(scene, grid: Grid, run: Run, comm=MPI.COMM_WORLD) -> Run:
    """Build and run one variant; fills the run's cost and samples, or ``skipped``."""
    try:
        model = builder.build(variant_scene(scene, grid, run), comm)
    except VpcontactError as err:  # e.g. an explicit law beyond its stability limit
        run.skipped = str(err).split(": ")[-1]
        return run
    problem = model.problem
    sample = _Sampler(problem.V, grid)
    control = StepControl(run.k, max_cuts=scene.time.max_cuts, tolerance=run.method.tolerance)
    samples, wall = [], 0.0
    try:
        for t in grid.times:
            comm.barrier()
            start = _time.perf_counter()
            for _ in advance(problem, float(t), control):
                pass
            wall += _time.perf_counter() - start
            samples.append(sample(problem.u))
    finally:
        problem.solver.destroy()
    run.samples = np.array(samples)
    run.dofs = problem.V.dofmap.index_map.size_global * problem.V.dofmap.index_map_bs
    run.steps = len(problem.reports)
    run.newton_iterations = sum(r.newton_iterations for r in problem.reports)
    run.wall_time = comm.allreduce(wall, op=MPI.MAX)
    return run


def reference_samples(grid: Grid, exact) -> np.ndarray:
    points = grid.points
    return np.array([exact(points, float(t)) for t in grid.times])


def measure(runs: Sequence[Run], reference: np.ndarray) -> None:
    for run in runs:
        if run.samples is not None:
            run.error = float(np.max(np.abs(run.samples - reference)))


# -- analysis ---------------------------------------------------------------------------------

def fitted_order(params: Sequence[float], errors: Sequence[float]) -> tuple[float, float]:
    """(p, C) of the least-squares fit error ≈ C param^p in log–log scale."""
    p, log_c = np.polyfit(np.log(params), np.log(errors), 1)
    return float(p), float(math.exp(log_c))


def pareto_front(runs: Sequence[Run], rtol: float = 1e-6) -> list[Run]:
    """Runs that no other run beats in both wall time and error, cheapest first; errors equal to
    ``rtol`` (round-off apart: e.g. P1 and P2 with the same nodal values) do not count as better."""
    done = sorted((r for r in runs if r.error is not None), key=lambda r: (r.wall_time, r.error))
    front, best = [], math.inf
    for run in done:
        if run.error < best * (1 - rtol):
            front.append(run)
            best = run.error
    return front


# -- the two studies --------------------------------------------------------------------------

REFINEMENTS = ("both", "h", "k")

#: How the convergence study's reference reads when no exact solution is given.
RICHARDSON = "Richardson estimate"


def exact_solution(scene, name: Optional[str]):
    """u(x, t) of the exact solution ``name`` for ``scene`` (None for None): one of
    :data:`EXACT`, or expressions of x and t (:func:`_expression`); checked up front."""
    if name is None:
        return None
    if name in EXACT:
        return EXACT[name](scene)
    try:
        return _expression(scene, name)
    except expressions.ExpressionError as err:
        raise InputError(f"unknown exact solution {name!r}: neither one of {', '.join(EXACT)} "
                         f"nor u(x, t) as expressions of x[i] and t ({err})") from None


def _execute_reference(scene, grid: Grid, finer: Run, comm) -> str:
    """Run ``finer`` (the reference run); its description."""
    execute(scene, grid, finer, comm)
    if finer.skipped:
        raise InputError(f"the reference run ({finer.method.label}) cannot run: {finer.skipped}")
    return (f"{finer.method.label} with h = {finer.h:.4g}, k = {finer.k:.4g} "
            f"({finer.dofs} dofs, {finer.steps} steps)")


def _reference(scene, grid: Grid, exact: Optional[str], finer: Run, comm):
    """Samples of the exact solution, or of the run ``finer`` (executed here)."""
    if exact is not None:
        return reference_samples(grid, exact_solution(scene, exact)), f"exact solution {exact!r}"
    label = _execute_reference(scene, grid, finer, comm)
    return finer.samples, label


def richardson(runs: Sequence[Run], finest: Run) -> float:
    """The observed order p from the differences of successive runs, without an exact solution.

    Each level halves the refined parameter r (h, k or both), so for an error e_i ≈ C r_i^p
    the differences d_i = max |u_i − u_{i+1}| (``finest`` follows the last of ``runs``) are
    C r_i^p (1 − 2^−p): they fall like the errors themselves, and from three runs
    p = log(d_{i−1}/d_i)/log 2 (Richardson). Over more runs p is the least-squares slope of
    log₂ d_i against the level. Each run's ``difference`` is set, and its ``error`` to the
    estimate e_i = d_i/(1 − 2^−p) (exact for an exact power law; d_i/(2^p − 1) is the finer
    run's).

    Measuring each run against the finest run instead, e_i − e_L = C r_i^p (1 − 2^{(i−L)p})
    falls faster than e_i near the reference and the fitted order comes out too high.

    Raises:
        InputError: two successive runs agree to round-off (no order to estimate), or the
            differences do not fall (p ≤ 0: no convergence is observed).
    """
    chain = list(runs) + [finest]
    diffs = np.array([float(np.max(np.abs(a.samples - b.samples)))
                      for a, b in zip(chain, chain[1:])])
    scale = max(float(np.max(np.abs(finest.samples))), np.finfo(float).tiny)
    if np.any(diffs <= 1e-13 * scale):
        raise InputError(f"successive runs agree to round-off (differences "
                         f"{', '.join(f'{d:.2e}' for d in diffs)}): this discretization is exact "
                         "for the scene along this refinement, there is no order to estimate")
    p = -float(np.polyfit(np.arange(len(diffs)), np.log2(diffs), 1)[0])
    if not p > 0:
        raise InputError(f"the differences between successive runs do not fall "
                         f"({', '.join(f'{d:.3e}' for d in diffs)}; order {p:.2f}): refine from "
                         "a finer coarsest level (--cells, --k) or give an exact solution")
    for run, d in zip(runs, diffs):
        run.difference = float(d)
        run.error = float(d) / (1.0 - 2.0 ** -p)
    return p


def convergence(scene, grid: Grid, method: Method, refine: str = "both", levels: int = 4,
                exact: Optional[str] = None, comm=MPI.COMM_WORLD,
                progress: Optional[Callable[[Run], None]] = None) -> tuple[list[Run], str]:
    """Refine h, k or both by halving ``levels`` times; errors against ``exact``, or else
    estimated from the differences of successive runs with one more level (Richardson,
    :func:`richardson`). Returns the runs and a description of what the errors are measured
    against ("exact solution …" or "Richardson …")."""
    if refine not in REFINEMENTS:
        raise InputError(f"refine must be one of {', '.join(REFINEMENTS)}, got {refine!r}")
    if not 2 <= levels <= 8:
        raise InputError(f"levels must be in [2, 8], got {levels}")
    exact_solution(scene, exact)

    def path(level):
        return {"both": (level, level), "h": (level, 0), "k": (0, level)}[refine]

    execute(scene, grid, new_run(grid, method, 0, 0), comm)  # warm-up: the first run is slower
    runs = []
    for level in range(levels):
        run = execute(scene, grid, new_run(grid, method, *path(level)), comm)
        if run.skipped:
            raise InputError(f"{method.label} with k = {run.k:g}: {run.skipped}")
        if progress is not None:
            progress(run)
        runs.append(run)
    finer = new_run(grid, method, *path(levels))
    if exact is None:
        label = _execute_reference(scene, grid, finer, comm)
        order = richardson(runs, finer)
        return runs, (f"{RICHARDSON} (no exact solution given): each run against the next finer "
                      f"one, the finest being {label}; order {order:.2f} fitted to those "
                      "differences, errors estimated from them")
    reference, label = _reference(scene, grid, exact, finer, comm)
    measure(runs, reference)
    return runs, label


def default_methods(scene) -> list[Method]:
    """P1 and P2 with the scene's Euler scheme, implicit Euler and BDF2 (for rate-type laws)."""
    own = scene.law.scheme
    schemes = [(own, "euler")]
    if scene.law.type != "elastic":
        if own != "implicit":
            schemes.append(("implicit", "euler"))
        schemes.append(("implicit", "bdf2"))
    return [Method(d, law, ts) for d in (1, 2) for law, ts in schemes]


def cost(scene, grid: Grid, methods: Sequence[Method], levels: int = 3,
         exact: Optional[str] = None, comm=MPI.COMM_WORLD,
         progress: Optional[Callable[[Run], None]] = None) -> tuple[list[Run], str]:
    """Every method on every (h, k) level pair in [0, levels)²; errors against ``exact`` or the
    most accurate method one level finer in both h and k."""
    if not 1 <= levels <= 6:
        raise InputError(f"levels must be in [1, 6], got {levels}")
    if not methods:
        raise InputError("no method to study")
    exact_solution(scene, exact)
    runs = []
    for method in methods:
        execute(scene, grid, new_run(grid, method, 0, 0), comm)  # warm-up, not timed
        for i in range(levels):
            for j in range(levels):
                run = execute(scene, grid, new_run(grid, method, i, j), comm)
                if progress is not None:
                    progress(run)
                runs.append(run)
    best = max(methods, key=lambda m: (m.degree, m.time_scheme == "bdf2",
                                       m.law_scheme == "implicit"))
    reference, label = _reference(scene, grid, exact, new_run(grid, best, levels, levels), comm)
    measure(runs, reference)
    return runs, label
