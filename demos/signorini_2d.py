# SPDX-License-Identifier: MIT
"""# 2-D Signorini contact of a viscoplastic square with a rigid obstacle (paper §4.1.1)

## The model
A square Ω = (0, 1)² of Perzyna material, σ̇ = E ε(u̇) - (1/μ*) E(σ - P_K σ), hangs from its top
side Γ1 (clamped) and is pulled down by f_0 = (0, -10t) N/m². Its sides are traction-free; its
bottom Γ3 may touch a rigid obstacle, the ellipse (x1 - 3)²/900 + (x2 + 3)²/9 = 1 whose top is the
point (3, 0), so the initial gap g(x1) grows from 0.0067 m at x1 = 1 to 0.0150 m at x1 = 0.
Plane stress, E = 1e8 N/m², ν = 0.3; the yield set is
K = {τ11² + τ22² - τ11τ22 + 3τ12² ≤ σ_Y²} with σ_Y = √10 N/m², and μ* = 200 N/m²·s.

Elastically the square would move by ~1e-7 m, far from the obstacle. The stresses it needs
(σ22 ≈ 10t at the clamp) pass σ_Y ≈ 3.16 early, and near t ≈ 0.38 s the top section reaches its
plastic limit load: from then on the square flows viscously, at a rate set by the overstress
over μ*. With the data as printed it has come down ~3 mm at T = 1 s, still above the obstacle
(6.7 mm below the corner x1 = 1). Run on with ``--t-final 1.6``: contact starts at that corner
at t ≈ 1.28 s and spreads along Γ3 as the square settles onto the ellipse.

## The scheme (the paper's Problem 2)
P1 displacements, stresses at one quadrature point per cell, backward Euler with G at the new
step: the C++ kernel solves the local Perzyna update exactly and returns its consistent tangent.
The Signorini condition u_ν ≤ g is imposed by PETSc SNES VI (vinewtonrsls) as bounds on the
vertical displacement of the Γ3 nodes. Each Newton iteration starts from the last step's
displacement increment extrapolated in time; at the limit load, where Newton can still diverge,
the step is rejected and retried with half the step size (then grown back). The implicit
scheme is the default because with these data E/μ* = 5e5 s⁻¹: the explicit scheme (Problem 4)
is stable only for k below about 4e-6 s.

## What it writes (into the folder printed at the end)
* ``signorini_2d.xdmf``/``.h5``: u, cell stress, von Mises norm at every step (open in ParaView).
* ``fig1_deformed.png``: deformed configuration at t = T coloured by the von Mises norm (Fig. 1).
* ``fig2_contact_evolution.png``: u2 of the contact nodes along Γ3 at several times, with the
  obstacle, and over time at a few nodes (Fig. 2).
* ``contact_history.csv``: t, x, y, z, u_normal, gap, clearance, pressure for every contact node and step.

With ``CI`` set, the run uses a coarser mesh and larger steps.

## Extending it
Any level set can replace the ellipse (``Signorini(tag, obstacle=phi)``); ``--scheme explicit``
shows why the implicit scheme is needed; ``--degree 2`` uses P2 displacements with quadrature
stresses.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from mpi4py import MPI

from vpcontact.paper import signorini as paper
from vpcontact.output import plots, runner


def run(out: str | Path = "output/signorini_2d", n: int | None = None, dt: float | None = None,
        scheme: str = "implicit", degree: int = 1, xdmf: bool = True, t_final: float = paper.T_FINAL):
    """Solve §4.1.1 on an n×n mesh with steps dt up to t_final, write the outputs; return the record."""
    ci = bool(os.environ.get("CI"))
    n = n or (12 if ci else 32)
    dt = dt or (0.1 if ci else 0.02)
    problem = paper.signorini_2d(n, scheme=scheme, degree=degree)
    record, history, cells = runner.run(problem, t_final, dt, out=Path(out),
                                        options=runner.RunOptions(name="signorini_2d",
                                                                  xdmf=xdmf))
    plots.deformed_configuration(Path(out) / "fig1_deformed.png", problem.u, cells.von_mises,
                                 "2-D Signorini problem: von Mises norm at t = T")
    plots.contact_evolution(Path(out) / "fig2_contact_evolution.png", history, axis=0,
                            title="2-D Signorini problem: vertical displacement of the contact nodes")
    if MPI.COMM_WORLD.rank == 0:
        print(runner.summary_text(record, Path(out), MPI.COMM_WORLD, force_unit="N/m"))
    return record


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="2-D Signorini test of the paper (§4.1.1)")
    parser.add_argument("--out", default="output/signorini_2d", help="output folder")
    parser.add_argument("--n", type=int, help="cells per side (default 32; 12 under CI)")
    parser.add_argument("--dt", type=float, help="time step (default 0.02; 0.1 under CI)")
    parser.add_argument("--scheme", choices=["explicit", "implicit"], default="implicit")
    parser.add_argument("--degree", type=int, choices=[1, 2], default=1)
    parser.add_argument("--no-xdmf", action="store_true", help="skip the XDMF time series")
    parser.add_argument("--t-final", type=float, default=paper.T_FINAL,
                        help="final time (default: the paper's T = 1 s; contact starts near 1.28 s)")
    args = parser.parse_args(argv)
    if args.n is not None and args.n < 1:
        parser.error("--n must be >= 1")
    if not 0 < args.t_final < 1e3:
        parser.error("--t-final must lie in (0, 1000)")
    if args.dt is not None and not 0 < args.dt <= args.t_final:
        parser.error(f"--dt must lie in (0, {args.t_final}]")
    run(args.out, args.n, args.dt, args.scheme, args.degree, xdmf=not args.no_xdmf, t_final=args.t_final)
    return 0


if __name__ == "__main__":
    from vpcontact.cli import run_script
    run_script(main)  # JIT messages off the terminal; an error is one line, exit 1
