# SPDX-License-Identifier: MIT
"""# A rigid sphere indenting an elastic block, driven by displacement, against Hertz

## The model
A rigid sphere of radius R = 0.5 is moved into the top face of an elastic block
[0, 1]² × [−1, 0] (the quarter x, y ≥ 0 of a block 2 × 2 × 1, with rollers on the symmetry planes
x = 0 and y = 0) by a prescribed depth δ(t) = δ_max t; the block is clamped at its bottom. E = 1,
ν = 0.3. The sphere is a built-in obstacle shape moved by a translation; the block's top face
within r ≤ 0.3 of the axis is the Signorini contact part (every ray along its normal meets the
sphere there). The Gmsh mesh is refined within 0.15 of the contact point
(:mod:`vpcontact.studies.hertz`).

## What it shows
Hertz's theory for a rigid sphere on an elastic half-space gives, for the force P,

    a = (3PR/(4E*))^(1/3),   δ_Hertz = a²/R,   i.e. P = (4/3) E* √R δ^(3/2),   E* = E/(1 − ν²).

At every step the contact radius measured on the mesh (midway between the last node in contact
and the first one free) is compared with Hertz's a for the measured force, and the force–depth
curve with Hertz's. The block is not a half-space: clamped at depth 2R it is stiffer, so the
measured force lies above Hertz's for the same depth (5–7 % here); equivalently, for the measured
force Hertz's half-space would need a few per cent more depth than was applied — none of δ goes
into extra compliance of the block. Written into the output folder:

* ``force_depth.png``: (a) P against δ, measured and Hertz's; (b) the contact radius against
  δ, measured and Hertz's for the measured force;
* ``indentation.csv``: δ, P, Hertz's P(δ), a measured, Hertz's a(P), Hertz's δ(P).

With ``CI`` set, the mesh is coarser and the steps fewer.

## Extending it
A Perzyna block (``Perzyna(...)`` instead of ``Elastic``) shows how plastic flow below the
indenter bends the curve away from Hertz's; a cylinder (``hertz.cylinder_2d``) gives the plane
strain version, for which Hertz fixes a(P) and p0(P) but not δ.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
from mpi4py import MPI

from vpcontact.model import Elastic, Elasticity, Signorini
from vpcontact.solver import Dirichlet, QuasistaticProblem, StepControl, advance, tag_facets
from vpcontact.studies import hertz

E, NU, R = 1.0, 0.3, 0.5
E_STAR = E / (1 - NU ** 2)


def run(out: str | Path = "output/hertz_indentation", depth: float = 0.01,
        h_contact: float | None = None, steps: int | None = None) -> np.ndarray:
    """Indent to ``depth`` in ``steps`` steps; write the outputs; return the table's rows."""
    ci = bool(os.environ.get("CI"))
    h_contact = h_contact or (0.02 if ci else 0.01)
    steps = steps or (3 if ci else 4)
    out = Path(out)
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    mesh, _ = hertz.read_msh(hertz.block_msh(out / "block.msh", h_contact=h_contact), 3)
    tags = tag_facets(mesh, {
        1: lambda x: np.isclose(x[2], -1.0), 2: lambda x: np.isclose(x[0], 0.0),
        3: lambda x: np.isclose(x[1], 0.0),
        4: lambda x: np.isclose(x[2], 0.0) & (x[0] ** 2 + x[1] ** 2 <= 0.3 ** 2 + 1e-12)})
    sphere = Signorini(4, obstacle=lambda x: np.linalg.norm(x - np.array([[0.0], [0.0], [R]]),
                                                            axis=0) - R,
                       max_distance=10.0, translation=lambda t: np.array([0.0, 0.0, -depth * t]))
    problem = QuasistaticProblem(
        mesh, tags, Elastic(Elasticity("3d_standard", E, NU)), contact=sphere,
        dirichlet=[Dirichlet.clamped(1, 3, "bottom"), Dirichlet.symmetry(2, 3, 0, "x = 0"),
                   Dirichlet.symmetry(3, 3, 1, "y = 0")])
    rows = []
    for step in advance(problem, 1.0, StepControl(1.0 / steps)):
        p = hertz.profile(problem, np.zeros(3))
        force = 4 * p.force  # the quarter carries P/4
        a_hertz, _ = hertz.sphere_3d(force, R, E_STAR)
        d = depth * step.time
        rows.append((d, force, hertz.sphere_force(d, R, E_STAR), p.half_width, a_hertz,
                     a_hertz ** 2 / R))
    rows = np.array(rows)
    if comm.rank == 0:
        np.savetxt(out / "indentation.csv", rows, delimiter=",", comments="",
                   header="depth,force,force_hertz,radius,radius_hertz,depth_hertz")
        _figure(out / "force_depth.png", rows)
        worst = np.abs(rows[:, 3] / rows[:, 4] - 1).max()
        share = 1 - rows[:, 5] / rows[:, 0]
        print(f"contact radius within {100 * worst:.1f} % of Hertz's at every step; force "
              f"{100 * (rows[-1, 1] / rows[-1, 2] - 1):+.1f} % against Hertz's at δ = {depth:g}; "
              f"Hertz's half-space would need {100 * -share.max():.1f}–{100 * -share.min():.1f} % "
              f"more depth for the measured force; outputs in {out.resolve()}")
    return rows


def _figure(path: Path, rows: np.ndarray) -> None:
    from vpcontact.output.plots import _pyplot
    plt = _pyplot()
    d = np.linspace(0.0, rows[-1, 0], 100)
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax_a.plot(rows[:, 0], rows[:, 1], "o", label="measured (4 × the quarter model)")
    ax_a.plot(d, [hertz.sphere_force(x, R, E_STAR) for x in d], "-",
              label="Hertz: P = (4/3) E* √R δ^(3/2)")
    ax_a.set(xlabel="depth δ", ylabel="force P", title="(a) force against depth")
    ax_b.plot(rows[:, 0], rows[:, 3], "o", label="measured")
    ax_b.plot(rows[:, 0], rows[:, 4], "x-", label="Hertz's a for the measured P")
    ax_b.set(xlabel="depth δ", ylabel="contact radius a", title="(b) contact radius")
    for ax in (ax_a, ax_b):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=140)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="A sphere indenting an elastic block vs Hertz")
    parser.add_argument("--out", default="output/hertz_indentation", help="output folder")
    parser.add_argument("--depth", type=float, default=0.01, help="final depth (default 0.01)")
    parser.add_argument("--h", type=float, help="element size at the contact (default 0.01)")
    parser.add_argument("--steps", type=int, help="steps (default 4)")
    args = parser.parse_args(argv)
    if not 0 < args.depth <= 0.05:
        parser.error("--depth must lie in (0, 0.05] (a small contact against the block)")
    if args.h is not None and not 0 < args.h <= 0.1:
        parser.error("--h must lie in (0, 0.1]")
    if args.steps is not None and args.steps < 1:
        parser.error("--steps must be >= 1")
    run(args.out, args.depth, args.h, args.steps)
    return 0


if __name__ == "__main__":
    from vpcontact.cli import run_script
    run_script(main)  # JIT messages off the terminal; an error is one line, exit 1
