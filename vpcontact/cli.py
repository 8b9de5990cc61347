# SPDX-License-Identifier: MIT
"""Command line: ``python3 -m vpcontact run|validate|list|show`` (also the ``vpcontact`` script).

* ``run [SCENE] [--out DIR] [--set KEY=VALUE ...] [--petsc-options KEY=VALUE ...] [-v]``:
  simulate a scene (default: ``indentation_relaxation``, a cylinder pushed into a viscoplastic
  block) and write into DIR the XDMF series, ``contact.csv``, ``reactions.csv``,
  ``summary.json`` and PNG figures the scene asks for. Its first line names the law, yield set,
  plane and formulation taken (:func:`vpcontact.scene.describe.choices`). ``-v`` also shows the
  form compiler's messages.
* ``validate SCENE``: check a scene without running it (the mesh-dependent checks included).
* ``list``: the bundled scenes. ``show SCENE``: the scene with every default filled in.
* ``--set KEY=VALUE`` (``run``, ``validate``, ``show``; repeatable): set a scene key over the
  file's, e.g. ``--set time.k=0.01 --set 'mesh.cells=[32, 16]'`` (:mod:`vpcontact.scene.overrides`);
  checked like the file's keys, and recorded in ``summary.json``.
* ``validate`` and ``run`` print warnings for data a small-strain model cannot mean (mixed
  units, an unreachable compliance, a huge step count: :mod:`vpcontact.scene.plausibility`).
* ``study convergence SCENE``: error against h, k or both, observed orders and error constants;
  ``study cost SCENE``: error against wall time and dofs × steps for every combination of mesh,
  step, degree and scheme, with the Pareto front (:mod:`vpcontact.studies`). Both write CSV,
  Markdown and PNG into ``--out`` (default ``output/<scene name>/study``).

Exit status: 0 on success, 2 for a bad scene or command line (nothing is written), 1 when the
simulation fails (the completed steps are kept and ``summary.json`` says ``"completed": false``),
3 for an internal error (a bug; one line, or the traceback with ``--traceback``).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Optional

from mpi4py import MPI

from vpcontact.errors import (INTERNAL_ERROR, ConvergenceError, InputError, Interrupted,
                              NonFiniteStateError, OutputError, StepRejected, StepTooSmall,
                              VpcontactError)


def main(argv: Optional[list] = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    configure_logging(getattr(args, "verbose", False))
    if args.command is None:
        parser.print_help()
        return 2
    comm = MPI.COMM_WORLD
    try:
        return args.func(args, comm)
    except Interrupted as err:  # outputs, checkpoint and summary are on disk: one line, no trace
        if comm.rank == 0:
            out = getattr(args, "out_folder", None)
            print(f"vpcontact: {err}; outputs and a checkpoint are in {out} (continue with "
                  f"--resume)", file=sys.stderr, flush=True)
        return exit_status(err.signal)
    except OutputError as err:
        _error(comm, f"{err}. The completed steps and the record were kept as far as they "
                     "could be written.")
        return 1
    except StepTooSmall as err:
        _error(comm, f"the simulation failed: {err}. Smaller steps do not help there: look at "
                     "the model's data (e.g. a nearly rate-independent law, a contact law "
                     "without a derivative at touch-down) or the solver's tolerances.")
        return 1
    except (ConvergenceError, NonFiniteStateError, StepRejected) as err:
        _error(comm, f"the simulation failed: {err}. Try a smaller time step ([time] k), more "
                     "step halvings ([time] max_cuts) or a finer mesh.")
        return 1
    except VpcontactError as err:  # bad scene or arguments: a clear message, nothing written
        _error(comm, str(err))
        return 2
    except Exception as err:  # a bug in vpcontact, not in the scene: one line, unless asked
        if args.traceback:
            raise
        _error(comm, f"internal error, a bug in vpcontact rather than in the scene: "
                     f"{type(err).__name__}: {err}. A run keeps the steps it completed "
                     "(summary.json says \"completed\": false). Please report it with the "
                     "scene file; `vpcontact --traceback ...` shows where it happened.")
        return INTERNAL_ERROR


def configure_logging(verbose: bool = False) -> None:
    """Keep the form compiler's JIT messages (logged at INFO on a fresh machine) off the terminal
    unless ``verbose`` (``-v``); demos and benchmarks call it too. distutils resets the root
    logger's level to INFO at every JIT build, so the level is set on the root handler, which
    nothing else touches."""
    logging.basicConfig()  # the root handler (FFCx's own basicConfig() is then a no-op)
    level = logging.INFO if verbose else logging.WARNING
    for handler in logging.getLogger().handlers:
        handler.setLevel(level)
    logging.getLogger().setLevel(level)
    # vpcontact's own messages (e.g. the step lines of a demo's run) as plain lines on stdout
    ours = logging.getLogger("vpcontact")
    if not any(getattr(h, "_vpcontact", False) for h in ours.handlers):
        handler = logging.StreamHandler(sys.stdout)
        handler.setFormatter(logging.Formatter("%(message)s"))
        handler._vpcontact = True
        ours.addHandler(handler)
    ours.setLevel(logging.INFO)
    ours.propagate = False


def run_script(main) -> None:
    """Run a demo's or benchmark's ``main()`` the way the command line runs: JIT messages off
    the terminal, a :class:`VpcontactError` ends in one line on stderr and exit status 1
    (nothing written as a result), any other status from ``main()`` is the exit status."""
    from vpcontact.errors import VpcontactError
    configure_logging()
    try:
        sys.exit(main())
    except VpcontactError as err:
        print(f"error: {err}", file=sys.stderr)
        sys.exit(1)


def scene_demo_main(run, description: str, out: str, cells: str, argv=None) -> int:
    """The command line of a demo on a bundled 2-D scene: ``--out``, ``--cells N1 N2`` (default
    ``cells``, the scene's) and ``--k``, validated, then ``run(out, cells or None, k or None)``."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--out", default=out, help="output folder")
    parser.add_argument("--cells", type=int, nargs=2, help=f"cells along x1 and x2 (default {cells})")
    parser.add_argument("--k", type=float, help="time step (default 0.025)")
    args = parser.parse_args(argv)
    if args.cells is not None and min(args.cells) < 1:
        parser.error("--cells must be >= 1")
    if args.k is not None and not 0 < args.k <= 1:
        parser.error("--k must lie in (0, 1]")
    run(args.out, tuple(args.cells) if args.cells else None, args.k)
    return 0


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="vpcontact", description=__doc__.splitlines()[0])
    parser.add_argument("--traceback", action="store_true",
                        help="on an internal error (a bug), show Python's traceback")
    verbose = argparse.ArgumentParser(add_help=False)
    verbose.add_argument("-v", "--verbose", action="store_true",
                         help="also show the form compiler's messages (JIT builds)")
    sub = parser.add_subparsers(dest="command")
    run = sub.add_parser("run", parents=[verbose],
                         help="simulate a scene (default: indentation_relaxation)")
    run.add_argument("scene", nargs="?", default=None, help="bundled scene name or TOML file")
    run.add_argument("--out", help="output folder (default: output/<scene name>)")
    _add_set(run)
    run.add_argument("--petsc-options", nargs="+", default=[], metavar="KEY=VALUE",
                     help="PETSc options for the step solver, e.g. snes_rtol=1e-9")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--resume", action="store_true",
                     help="continue the run in --out from its last checkpoint")
    run.set_defaults(func=_run)
    for name, func, text in (("validate", _validate, "check a scene without running it"),
                             ("show", _show, "print the scene with all defaults filled in")):
        p = sub.add_parser(name, help=text, parents=[verbose])
        p.add_argument("scene", help="bundled scene name or TOML file")
        _add_set(p)
        p.set_defaults(func=func)
    sub.add_parser("list", help="list the bundled scenes").set_defaults(func=_list)
    study = sub.add_parser("study", help="convergence and work-precision studies of a scene")
    kinds = study.add_subparsers(dest="study")
    conv = kinds.add_parser("convergence", parents=[verbose],
                            help="error against h, k or both; observed orders")
    conv.add_argument("--refine", choices=("both", "h", "k"), default="both",
                      help="what to halve at each level (default: both, the paper's h = k path)")
    conv.add_argument("--levels", type=int, default=4, help="number of refinements (default 4)")
    conv.add_argument("--degree", type=int, choices=(1, 2), default=None,
                      help="displacement degree: 1 is the displacement formulation (the paper's "
                           "P1), 2 the scene's formulation with P2 (default: the scene's own, "
                           "Taylor-Hood where the scene would lock)")
    conv.add_argument("--law-scheme", choices=("explicit", "implicit", "linearized"),
                      help="Euler scheme of the law (default: the scene's)")
    conv.add_argument("--time-scheme", choices=("euler", "bdf2"), default="euler")
    conv.set_defaults(func=_study_convergence)
    cost = kinds.add_parser("cost", parents=[verbose],
                            help="work-precision: error against wall time, Pareto front")
    cost.add_argument("--levels", type=int, default=3,
                      help="h and k levels each (levels² runs per method; default 3)")
    cost.add_argument("--degrees", type=int, nargs="+", choices=(1, 2), default=None)
    cost.add_argument("--schemes", nargs="+",
                      choices=("explicit", "implicit", "linearized", "bdf2"),
                      help="explicit/implicit/linearized Euler, or BDF2 (default: the scene's, "
                           "implicit, bdf2)")
    cost.set_defaults(func=_study_cost)
    for p in (conv, cost):
        p.add_argument("scene", help="bundled scene name or TOML file (built-in mesh)")
        p.add_argument("--cells", type=int, nargs="+", help="coarsest mesh (default: the scene's)")
        p.add_argument("--k", type=float, help="coarsest step (default: the scene's)")
        p.add_argument("--T", type=float, help="final time (default: the scene's)")
        p.add_argument("--exact", help="compare with an exact solution: paper_1d, or u(x, t) as "
                                       "expressions of x[i] and t, one per component separated "
                                       "by ';' (default: convergence estimates the order from "
                                       "successive runs, Richardson; cost compares with a finer "
                                       "run)")
        p.add_argument("--out", help="output folder (default: output/<scene name>/study)")
        p.add_argument("--quiet", action="store_true", help="no line per run")
    study.set_defaults(func=lambda args, comm: (study.print_help(), 2)[1])
    return parser


def _add_set(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE",
                        help="set a scene key over the file's (repeatable), e.g. time.k=0.01, "
                             "law.mu_star=50, 'mesh.cells=[32,16]', material.plane=strain; "
                             "the value is read as TOML (a bare word as a string)")


def exit_status(signal_name: str) -> int:
    """128 + the signal's number: 130 for SIGINT, 143 for SIGTERM."""
    import signal
    return 128 + int(getattr(signal, signal_name))


def _error(comm, message: str) -> None:
    if comm.rank == 0:
        print(f"error: {message}", file=sys.stderr, flush=True)


def _load(name: Optional[str], overrides=()):
    from vpcontact import scene as scenes
    return scenes.load(scenes.resolve(name or scenes.DEFAULT_SCENE), overrides)


def _warn(scene, model, comm) -> None:
    """Print what the scene's data say against a small-strain model (on rank 0; the size of
    the body from the built mesh, Gmsh meshes included; collective)."""
    from vpcontact.model.extent import mesh_extent
    from vpcontact.scene.plausibility import warnings
    found = warnings(scene, mesh_extent(model.problem.mesh))
    if comm.rank == 0:
        for problem in found:
            print(f"warning: {problem.format(str(scene.path))}", file=sys.stderr, flush=True)


def _first_line(scene) -> str:
    """``name: 2-D, law perzyna (yield set von_mises, default), plane strain (default), …``"""
    from vpcontact.scene.describe import choices
    return f"{scene.name}: {scene.dim}-D, {choices(scene)}"


def _list(args, comm) -> int:
    from vpcontact import scene as scenes
    if comm.rank == 0:
        for name, path in scenes.bundled().items():
            description = scenes.load(path).description
            print(f"{name:24s} {description}")
    return 0


def _show(args, comm) -> int:
    text = _load(args.scene, args.overrides).to_toml()
    if comm.rank == 0:
        print(text, end="")
    return 0


def _validate(args, comm) -> int:
    from vpcontact.output.probes import locate
    from vpcontact.scene.builder import build
    from vpcontact.scene.describe import choices
    scene = _load(args.scene, args.overrides)
    model = build(scene, comm)  # mesh-level checks: empty or overlapping parts, tags, points
    if scene.output.probes:  # (as the run does before its first step)
        try:
            locate(model.problem.mesh, scene.output.probes)
        except InputError as err:
            raise scene.error(err.key, str(err)) from None
    _warn(scene, model, comm)
    model.problem.solver.destroy()
    if comm.rank == 0:
        print(f"{scene.path}: valid ({scene.dim}-D, {len(scene.boundaries)} boundary parts, "
              f"{choices(scene)}, contact {_contact_summary(scene)})")
    return 0


def _contact_summary(scene) -> str:
    """``none``, ``signorini`` or, with several parts, ``signorini on 'top', normal_compliance
    on 'bottom'``."""
    if not scene.contacts:
        return "none"
    if len(scene.contacts) == 1:
        return scene.contacts[0].type
    return ", ".join(f"{c.type} on {c.boundary!r}" for c in scene.contacts)


def _petsc_options(pairs) -> dict:
    options = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        key = key.lstrip("-")
        if not sep or not key:
            raise InputError(f"--petsc-options takes KEY=VALUE, got {pair!r}")
        options[key] = value
    return options


def _out_folder(given: Optional[str], default: Path) -> Path:
    """``--out`` as given (an empty one refused: it would be the current folder), else the
    default."""
    if given is None:
        return default
    if not given.strip():
        raise InputError("--out is empty: name the output folder (or leave --out out for "
                         f"{default})")
    return Path(given)


def _run(args, comm) -> int:
    from vpcontact.output.interrupt import StopRequest
    from vpcontact.output.lock import OutputLock, check_folder
    from vpcontact.output.session import Session
    from vpcontact.progress import ProgressBar
    from vpcontact.scene.builder import build
    scene = _load(args.scene, args.overrides)
    extra = _petsc_options(args.petsc_options)
    if extra:
        import dataclasses
        solver = dataclasses.replace(scene.solver,
                                     petsc_options={**scene.solver.petsc_options, **extra})
        scene = dataclasses.replace(scene, solver=solver)
    out = _out_folder(args.out, Path("output") / scene.name)
    args.out_folder = out
    check_folder(out)
    if comm.rank == 0:
        print(_first_line(scene), flush=True)
    with StopRequest() as stop:  # SIGINT/SIGTERM: stop after the step in progress
        model = build(scene, comm)
        _warn(scene, model, comm)
        lock = OutputLock(out, comm)
        try:
            bar = ProgressBar(scene.time.T) if not args.quiet and comm.rank == 0 else None
            try:
                result = Session(model, out, progress=bar.update if bar else None, stop=stop,
                                 resume=args.resume).run()
            finally:
                if bar is not None:
                    bar.close()
        finally:
            lock.release()
    if comm.rank == 0:
        for warning in result.warnings:
            print(f"warning: {warning}", file=sys.stderr)
        print(f"{result.name}: t = {result.final_time:.4g} in {result.steps} steps, "
              f"{result.newton_iterations} Newton iterations"
              + (f" ({result.newton_iterations_total} with the rejected steps')"
                 if result.newton_iterations_total != result.newton_iterations else "")
              + f", {result.rejected} rejected, "
              f"{result.wall_time:.1f} s on {result.ranks} rank(s); outputs in {result.out}")
    return 0


def _study_setup(args, comm):
    from vpcontact.studies import runs as study
    scene = _load(args.scene)
    grid = study.make_grid(scene, args.cells, args.k, args.T)
    from vpcontact.output.lock import check_folder
    out = _out_folder(args.out, Path("output") / scene.name / "study")
    check_folder(out)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()

    def progress(run):
        if args.quiet or comm.rank != 0:
            return
        what = (f"skipped: {run.skipped}" if run.skipped else
                f"{run.dofs} dofs, {run.steps} steps, {run.wall_time:.3g} s")
        print(f"{run.method.label:24s} h = {run.h:<10.4g} k = {run.k:<10.4g} {what}", flush=True)
    return scene, grid, out, progress


def _study_convergence(args, comm) -> int:
    from vpcontact.studies import runs as study
    from vpcontact.studies import report as study_report
    scene, grid, out, progress = _study_setup(args, comm)
    method = study.Method(args.degree or scene.degree, args.law_scheme or scene.law.scheme, args.time_scheme)
    runs, reference = study.convergence(scene, grid, method, args.refine, args.levels, args.exact,
                                        comm, progress)
    if comm.rank == 0:
        s = study_report.write_convergence(out, scene.name, runs, args.refine, reference)
        print(f"observed order {s['order']:.2f}, error constant max err/max(h, k) "
              f"{s['hk_constant']:.3g}; tables and figure in {out.resolve()}")
    return 0


def _study_cost(args, comm) -> int:
    from vpcontact.studies import runs as study
    from vpcontact.studies import report as study_report
    scene, grid, out, progress = _study_setup(args, comm)
    methods = study.default_methods(scene)  # P1 and P2
    if args.schemes:
        methods = [study.Method(d, "implicit" if s == "bdf2" else s,
                                "bdf2" if s == "bdf2" else "euler")
                   for d in (1, 2) for s in dict.fromkeys(args.schemes)]
    if args.degrees:
        methods = [m for m in methods if m.degree in args.degrees]
    runs, reference = study.cost(scene, grid, methods, args.levels, args.exact, comm, progress)
    if comm.rank == 0:
        report = study_report.write_cost(out, scene.name, runs, reference)
        print("\n".join(report["advice"].values()))
        print(f"tables and figure in {out.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
