# SPDX-License-Identifier: MIT
"""Command line: ``python3 -m vpcontact run|validate|list|show`` (also the ``vpcontact`` script).

* ``run [SCENE] [--out DIR] [--petsc-options KEY=VALUE ...]``: simulate a scene (default: the
  paper's 2-D Signorini test) and write into DIR the XDMF series, ``contact.csv``,
  ``summary.json`` and PNG figures the scene asks for.
* ``validate SCENE``: check a scene without running it (the mesh-dependent checks included).
* ``list``: the bundled scenes. ``show SCENE``: the scene with every default filled in.

Exit status: 0 on success, 2 for a bad scene or command line (nothing is written), 1 when the
simulation fails (the completed steps are kept and ``summary.json`` says ``"completed": false``).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Optional

from mpi4py import MPI

from vpcontact.errors import ConvergenceError, InputError, NonFiniteStateError, VpcontactError


def main(argv: Optional[list] = None) -> int:
    logging.getLogger().setLevel(logging.WARNING)  # the form compiler logs at INFO
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    comm = MPI.COMM_WORLD
    try:
        return args.func(args, comm)
    except (ConvergenceError, NonFiniteStateError) as err:
        _error(comm, f"the simulation failed: {err}. Try a smaller time step ([time] k), more "
                     "step halvings ([time] max_cuts) or a finer mesh.")
        return 1
    except VpcontactError as err:  # bad scene or arguments: a clear message, nothing written
        _error(comm, str(err))
        return 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="vpcontact", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command")
    run = sub.add_parser("run", help="simulate a scene (default: the paper's 2-D Signorini test)")
    run.add_argument("scene", nargs="?", default=None, help="bundled scene name or TOML file")
    run.add_argument("--out", help="output folder (default: output/<scene name>)")
    run.add_argument("--petsc-options", nargs="+", default=[], metavar="KEY=VALUE",
                     help="PETSc options for the step solver, e.g. snes_rtol=1e-9")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.set_defaults(func=_run)
    for name, func, text in (("validate", _validate, "check a scene without running it"),
                             ("show", _show, "print the scene with all defaults filled in")):
        p = sub.add_parser(name, help=text)
        p.add_argument("scene", help="bundled scene name or TOML file")
        p.set_defaults(func=func)
    sub.add_parser("list", help="list the bundled scenes").set_defaults(func=_list)
    return parser


def _error(comm, message: str) -> None:
    if comm.rank == 0:
        print(f"error: {message}", file=sys.stderr, flush=True)


def _load(name: Optional[str]):
    from vpcontact import scene as scenes
    return scenes.load(scenes.resolve(name or scenes.DEFAULT_SCENE))


def _list(args, comm) -> int:
    from vpcontact import scene as scenes
    if comm.rank == 0:
        for name, path in scenes.bundled().items():
            description = scenes.load(path).description
            print(f"{name:24s} {description}")
    return 0


def _show(args, comm) -> int:
    text = _load(args.scene).to_toml()
    if comm.rank == 0:
        print(text, end="")
    return 0


def _validate(args, comm) -> int:
    from vpcontact.build import build
    scene = _load(args.scene)
    model = build(scene, comm)  # mesh-level checks: empty or overlapping parts, tags, points
    model.problem.solver.destroy()
    if comm.rank == 0:
        print(f"{scene.path}: valid ({scene.dim}-D, {len(scene.boundaries)} boundary parts, "
              f"law {scene.law.type}, contact {scene.contact.type if scene.contact else 'none'})")
    return 0


def _petsc_options(pairs) -> dict:
    options = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        key = key.lstrip("-")
        if not sep or not key:
            raise InputError(f"--petsc-options takes KEY=VALUE, got {pair!r}")
        options[key] = value
    return options


def _run(args, comm) -> int:
    from vpcontact.build import build
    from vpcontact.session import Session
    scene = _load(args.scene)
    extra = _petsc_options(args.petsc_options)
    if extra:
        import dataclasses
        solver = dataclasses.replace(scene.solver,
                                     petsc_options={**scene.solver.petsc_options, **extra})
        scene = dataclasses.replace(scene, solver=solver)
    model = build(scene, comm)
    out = Path(args.out or Path("output") / scene.name)
    session = Session(model, out, progress=not args.quiet)
    return session.run()


if __name__ == "__main__":
    sys.exit(main())
