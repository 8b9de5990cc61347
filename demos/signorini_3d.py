# SPDX-License-Identifier: MIT
"""# 3-D Signorini contact of a viscoplastic beam on a rigid foundation (paper §4.1.2)

Run it in parallel: ``mpirun -n 2 .venv/bin/python demos/signorini_3d.py``.

## The model
A beam Ω = (0, 3) × (0, 1) × (0, 1) of Perzyna material is clamped at x1 = 0 (Γ1), rests on a
rigid foundation at x3 = 0 (Γ3, zero gap) and is pressed down by the traction f_2 = (0, 0, -10t)
N/m² on its free end x1 = 3 (the paper prints "x1 = 0", the clamped face: a misprint). The other
faces are traction-free. E = 1e8 N/m², ν = 0.3, σ_Y = √10 N/m², μ* = 200 N/m²·s, and the yield set
as printed in the paper, (τ11-τ22)² + (τ22-τ33)² + (τ33-τ11)² + 6(τ12²+τ13²+τ23²) ≤ σ_Y², which
is the standard von Mises set with twice its left side (``--yield standard`` selects the standard
one).

The foundation stops the end from moving down, so the load is carried by contact near x1 = 3 and
the beam lifts off where bending makes it rotate: the contact zone is part of the solution.

## The scheme
Backward-Euler Perzyna update in C++, SNES VI for u3 ≥ 0 on Γ3. In space, by default, the
locking-free mixed formulation (Taylor–Hood: P2 displacements, P1 pressure): the beam flows
almost everywhere from t ≈ 0.01 s, its flow keeps the volume, and the paper's P1/P0 scheme
(``--formulation displacement``) is then several times too stiff (see the README's "Volumetric
locking").

## What it writes (into the folder printed at the end)
* ``signorini_3d.xdmf``/``.h5``: u, cell stress, von Mises norm at every step.
* ``fig3_deformed.png``: deformed beam at t = T coloured by the von Mises norm (Fig. 3).
* ``fig4_contact_evolution.png``: u3 (the component normal to Γ3) of the contact nodes on the
  line x2 = 0.5, along x1 at several times and over time (Fig. 4).
* ``contact_history.csv``: t, x, y, z, u_normal, gap, clearance, pressure of every contact node and step.

With ``CI`` set, the run uses a coarser mesh and larger steps.

## Extending it
Swap the yield set, refine (``--n``), or replace the flat foundation by a curved obstacle.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from mpi4py import MPI

from vpcontact.paper import signorini as paper
from vpcontact.output import plots, runner


def run(out: str | Path = "output/signorini_3d", n: int | None = None, dt: float | None = None,
        scheme: str = "implicit", yield_set: str = "printed", xdmf: bool = True,
        formulation: str = "mixed"):
    """Solve §4.1.2 on a (3n)×n×n mesh with steps dt and write the outputs; return the run record."""
    ci = bool(os.environ.get("CI"))
    n = n or (3 if ci else (4 if formulation == "mixed" else 8))
    dt = dt or (0.25 if ci else 0.02)
    model = "3d" if yield_set == "printed" else "3d_standard"
    degree = 2 if formulation == "mixed" else 1
    problem = paper.signorini_3d(3 * n, n, n, scheme=scheme, model=model, degree=degree,
                                 formulation=formulation)
    record, history, cells = runner.run(problem, paper.T_FINAL, dt, out=Path(out),
                                        options=runner.RunOptions(name="signorini_3d",
                                                                  xdmf=xdmf))
    plots.deformed_configuration(Path(out) / "fig3_deformed.png", problem.u, cells.von_mises,
                                 "3-D Signorini problem: von Mises norm at t = T")
    plots.contact_evolution(Path(out) / "fig4_contact_evolution.png", history, axis=0, line=(1, 0.5),
                            obstacle=False,
                            title="3-D Signorini problem: u3 of the contact nodes on x2 = 0.5")
    if MPI.COMM_WORLD.rank == 0:
        print(runner.summary_text(record, Path(out), MPI.COMM_WORLD, force_unit="N"))
    return record


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="3-D Signorini test of the paper (§4.1.2)")
    parser.add_argument("--out", default="output/signorini_3d", help="output folder")
    parser.add_argument("--n", type=int, help="cells across the beam (mesh 3n×n×n; default 4 "
                        "mixed / 8 displacement, 3 under CI)")
    parser.add_argument("--dt", type=float, help="time step (default 0.02; 0.25 under CI)")
    parser.add_argument("--scheme", choices=["explicit", "implicit"], default="implicit")
    parser.add_argument("--yield", dest="yield_set", choices=["printed", "standard"], default="printed")
    parser.add_argument("--no-xdmf", action="store_true", help="skip the XDMF time series")
    parser.add_argument("--formulation", choices=["mixed", "displacement"], default="mixed",
                        help="mixed (Taylor–Hood P2–P1, default) or the paper's P1 displacements")
    args = parser.parse_args(argv)
    if args.n is not None and args.n < 1:
        parser.error("--n must be >= 1")
    if args.dt is not None and not 0 < args.dt <= paper.T_FINAL:
        parser.error(f"--dt must lie in (0, {paper.T_FINAL}]")
    run(args.out, args.n, args.dt, args.scheme, args.yield_set, xdmf=not args.no_xdmf,
        formulation=args.formulation)
    return 0


if __name__ == "__main__":
    from vpcontact.cli import run_script
    run_script(main)  # JIT messages off the terminal; an error is one line, exit 1
