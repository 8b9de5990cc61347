# SPDX-License-Identifier: MIT
"""# 1-D normal compliance: the paper's test with an exact solution (§4.2.1)

## The model
A bar Ω = (0, 1) of a rate-type material

    σ̇ = E ε(u̇) + G(σ, ε(u)),   E = 10,   G(σ, ε) = -σ + 10 ε,

is clamped at x = 0 and pushed by the body force f_0 = 10 towards a deformable foundation at
x = 1, at the initial distance g = 0.25. The foundation reacts by normal compliance,

    σ(1, t) = -(1/μ) (u(1, t) - g)_+,   μ = 100,

starting from u_0 = 0 and σ_0 = 10 - 10x (which is in equilibrium with f_0). The bar creeps
towards the foundation, touches it at t = ln 2, and then settles; (21)-(22) of the paper give the
exact solution for all t ∈ [0, 10].

## The scheme (the paper's Problem 4)
P1 displacements on a uniform mesh of size h, piecewise-constant stresses (one quadrature point per
cell), and a uniform time step k. At each t_n the stress is advanced with G taken at the previous
step,

    σ_n = σ_{n-1} + E (ε(u_n) - ε(u_{n-1})) + k G(σ_{n-1}, ε(u_{n-1})),

by the C++ kernel at the quadrature points, and u_n solves the equilibrium equation with the
compliance term as a UFL boundary integral, (σ_n, ε(v)) + (1/μ)(u_n(1) - g)_+ v(1) = (f_0, v),
by PETSc SNES (Newton; the kernel also returns dσ_n/dε_n = E for the Jacobian).

## What it writes (into the folder printed at the end)
* ``fig5_displacements.png``: u_h at t = 0.5, 1, 2, 4, 8 for h = k = 0.01, and the error ×10³.
* ``fig6_evolution.png``: u_h(x, t) at x = 0.25, 0.5, 1 over time, and the error ×10³.
* ``fig7_error_constant.png``: (max nodal error)/r against r for h = k = r, with the paper's
  constant C = 0.9557e-1.
* ``errors.csv``: ``r,h,k,err_VQ,err_nodal`` where err_VQ = max_n ‖u - u_h‖_V + ‖σ - σ_h‖_Q and
  err_nodal = max_n max_i |u(x_i, t_n) - u_h(x_i, t_n)|.

With the ``CI`` environment variable set, the refinement study stops at r = 0.02 (same outputs).

## Extending it
Change the exponent α of the compliance law (α < 1 needs the regularised Jacobian of a later
release), replace G by a Perzyna law from :mod:`vpcontact.model.constitutive`, or use the implicit scheme
(``--scheme implicit``) and compare the error constants.
"""

from __future__ import annotations

import argparse
import csv
import os
from pathlib import Path

import numpy as np
from mpi4py import MPI

from vpcontact.paper import bar1d

PAPER_CONSTANT = 0.9557e-1
SNAPSHOT_TIMES = (0.5, 1.0, 2.0, 4.0, 8.0)
PROBE_POINTS = (0.25, 0.5, 1.0)


def default_radii() -> list[float]:
    """h = k = r for the refinement study (shorter under CI)."""
    if os.environ.get("CI"):
        return [0.1, 0.05, 0.02]
    return [0.1, 0.05, 0.02, 0.01]


def run(out: str | Path = "output/normal_compliance_1d", radii=None, scheme: str = "explicit",
        plots: bool = True) -> list[bar1d.Bar1DResult]:
    """Run the refinement study, write errors.csv and the figures; return the results."""
    radii = sorted(radii or default_radii(), reverse=True)
    comm = MPI.COMM_WORLD
    out = Path(out)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)

    results = []
    for r in radii:
        result = bar1d.run(r, scheme=scheme)
        results.append(result)
        if comm.rank == 0:
            print(f"r = {r:<6g} err_VQ = {result.err_vq:.4e}  err_nodal = {result.err_nodal:.4e}  "
                  f"err_nodal/r = {result.err_nodal / r:.4e}  "
                  f"(Newton its/step: {np.mean(result.newton_iterations):.2f})", flush=True)

    if comm.rank == 0:
        write_errors(out / "errors.csv", results)
        if plots:
            finest = results[-1]
            plot_snapshots(out / "fig5_displacements.png", finest)
            plot_evolution(out / "fig6_evolution.png", finest)
            plot_error_constant(out / "fig7_error_constant.png", results)
        print(f"outputs written to {out.resolve()}")
    return results


def write_errors(path: Path, results) -> None:
    """errors.csv: one row per refinement."""
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["r", "h", "k", "err_VQ", "err_nodal"])
        for res in results:
            writer.writerow([f"{res.k:.6g}", f"{res.h:.6g}", f"{res.k:.6g}",
                             f"{res.err_vq:.10e}", f"{res.err_nodal:.10e}"])


def _time_index(result, t: float) -> int:
    return int(np.argmin(np.abs(result.times - t)))


def plot_snapshots(path: Path, result) -> None:
    """Fig. 5: displacements at several times (a) and the error scaled by 10³ (b)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_u, ax_e) = plt.subplots(1, 2, figsize=(11, 4.2))
    for t in SNAPSHOT_TIMES:
        n = _time_index(result, t)
        u_h = result.displacements[n]
        exact = bar1d.exact_displacement(result.nodes, result.times[n])
        ax_u.plot(result.nodes, u_h, label=f"t = {t:g}")
        ax_e.plot(result.nodes, 1e3 * (exact - u_h), label=f"t = {t:g}")
    ax_u.axhline(bar1d.GAP, color="0.5", ls=":", lw=1, label="gap g")
    ax_u.set(xlabel="x [m]", ylabel="u_h [m]", title=f"(a) displacements, h = k = {result.k:g}")
    ax_e.set(xlabel="x [m]", ylabel="(u - u_h) × 10³", title="(b) error × 10³")
    for ax in (ax_u, ax_e):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def plot_evolution(path: Path, result) -> None:
    """Fig. 6: evolution of u at x = 0.25, 0.5, 1 (a) and the error scaled by 10³ (b)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_u, ax_e) = plt.subplots(1, 2, figsize=(11, 4.2))
    for xp in PROBE_POINTS:
        i = int(np.argmin(np.abs(result.nodes - xp)))
        exact = np.array([bar1d.exact_displacement(result.nodes[i], t) for t in result.times])
        ax_u.plot(result.times, result.displacements[:, i], label=f"x = {xp:g}")
        ax_e.plot(result.times, 1e3 * (exact - result.displacements[:, i]), label=f"x = {xp:g}")
    for ax in (ax_u, ax_e):
        ax.axvline(bar1d.CONTACT_ONSET, color="0.5", ls=":", lw=1)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    ax_u.set(xlabel="t [s]", ylabel="u_h [m]", title="(a) displacement at three points")
    ax_e.set(xlabel="t [s]", ylabel="(u - u_h) × 10³", title="(b) error × 10³")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def plot_error_constant(path: Path, results) -> None:
    """Fig. 7: (max nodal error)/r against r, which the paper finds constant = 0.9557e-1."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = np.array([res.k for res in results])
    c = np.array([res.err_nodal for res in results]) / r
    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.semilogx(r, c, "o-", label="vpcontact: max nodal error / r")
    ax.axhline(PAPER_CONSTANT, color="C3", ls="--", label=f"paper: C = {PAPER_CONSTANT:.4g}")
    ax.set(xlabel="r = h = k", ylabel="error / r", ylim=(0, 1.5 * max(c.max(), PAPER_CONSTANT)),
           title="Asymptotic error constant")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0].lstrip("# "))
    parser.add_argument("--out", default="output/normal_compliance_1d", help="output folder")
    parser.add_argument("--r", type=float, nargs="+", help="values of r = h = k (default: study)")
    parser.add_argument("--scheme", choices=["explicit", "implicit"], default="explicit",
                        help="time discretisation of G (explicit = the paper's Problem 4)")
    parser.add_argument("--no-plots", action="store_true", help="write errors.csv only")
    args = parser.parse_args(argv)
    for r in args.r or []:
        if not (0 < r <= 1 and abs(round(1 / r) * r - 1) < 1e-9):
            parser.error(f"--r {r}: r must be in (0, 1] and divide 1 (e.g. 0.1, 0.05, 0.02, 0.01)")
    run(args.out, radii=args.r, scheme=args.scheme, plots=not args.no_plots)
    return 0


if __name__ == "__main__":
    from vpcontact.cli import run_script
    run_script(main)  # JIT messages off the terminal; an error is one line, exit 1
