# SPDX-License-Identifier: MIT
"""# A scratch test of a viscoplastic block: friction against a moving obstacle (beyond the paper)

## The model
A rigid slider with a cylindrical tip (radius 0.5) is pressed 0.02 into the top of a block
Ω = (-1, 1) × (-0.5, 0) of Perzyna material, σ̇ = E ε(u̇) − (1/μ*) E(σ − P_K σ), over
t ≤ 0.25 s, then dragged 0.8 to the right at that depth. Between tip and block: Signorini's
condition and Coulomb friction, 𝔣 = 0.2; the contact force acts along the tip's normal
(``normals = "obstacle"``). The block is clamped at its bottom; plane strain (a long block
scratched across). E = 1000, ν = 0.3, von Mises set with σ_Y = 8, μ* = 20.
This is the bundled scene ``scratch``.

## The scheme
The paper's Problem 2 (stresses at quadrature points, implicit Euler for G) in the mixed
formulation — Taylor–Hood displacement and pressure, vpcontact's default where Perzyna's
volume-keeping flow would lock P1 displacements in plane strain — with the Signorini condition
as a bound of SNES VI on the displacement's normal unknowns and friction nodal, in the contact frames
(``vpcontact/model/nodal_friction.py``): the VI's multiplier λ_i at each contact node sets its
Coulomb threshold 𝔣 λ_i, a return mapping the tangential force; the slip is relative to the
moving tip. The bound is along the block's normal (the paper's u_ν ≤ g, the gap measured along
it), but its force λ_i acts along the tip's normal where the node's ray meets the tip
(``vpcontact/model/obstacle_normals.py``): on the tip's flank it has a tangential part λ_i s_i,
s_i the flank's slope. Each step is one SNES VI solve with the exact generalised Jacobian.

## What it shows
* ``scratch.png``: (a) the tip's forces on the block against time, and their ratio: while the
  tip slides the tangential force is 𝔣 times the normal one plus the ploughing of the groove's
  front: the block flowed away under the tip and does not spring back behind it, so the tip
  bears on its leading flank, whose normal leans against the motion. The ratio rises from 0.275
  to about 0.29 while the front builds up (𝔣 = 0.2; with ``normals = "body"``, the paper's
  condition, it is 𝔣 to 1e−8: the force on a flat face is normal to it). (b) The groove: u_2 along the top at the end of the
  indentation and at t = T — the block flowed under the tip and keeps a groove behind it.
  (c) Where the block slips under the tip (contact nodes slipping, against x1 and t).
* What ``vpcontact run`` writes besides (XDMF series, contact.csv with the friction columns,
  reactions.csv, summary.json).

With ``CI`` set, the run uses a coarser mesh and larger steps.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from mpi4py import MPI

from vpcontact import scene as scenes
from vpcontact.cli import scene_demo_main
from vpcontact.output import Session
from vpcontact.scene import build

PRESS = 0.25  # end of the indentation
COEFFICIENT = 0.2


def run(out: str | Path = "output/scratch", cells: tuple[int, int] | None = None,
        k: float | None = None):
    """Run the scene (``cells`` and step ``k`` overridden if given); return the session."""
    ci = bool(os.environ.get("CI"))
    cells = cells or ((40, 10) if ci else (80, 20))
    k = k or (0.05 if ci else 0.025)
    session = Session(build(scenes.load_bundled("scratch", cells, k)), Path(out))
    session.run()
    _figure(Path(out), session)
    return session


def _figure(out: Path, session) -> None:
    if MPI.COMM_WORLD.rank != 0:
        return
    from vpcontact.output.plots import _pyplot
    plt = _pyplot()
    t = np.array(session.forces.times)
    force = np.array(session.forces.contact)
    rows = np.genfromtxt(out / "contact.csv", delimiter=",", names=True)
    fig, (ax_a, ax_b, ax_c) = plt.subplots(1, 3, figsize=(15, 4.2))
    ax_a.plot(t, -force[:, 1], label="normal (−F_2)")
    ax_a.plot(t, force[:, 0], label="tangential (F_1)")
    loaded = -force[:, 1] > 0
    ratio = np.where(loaded, force[:, 0] / np.where(loaded, -force[:, 1], 1.0), np.nan)
    ax_r = ax_a.twinx()
    ax_r.plot(t, ratio, "k:", label="F_1 / (−F_2)")
    ax_r.axhline(COEFFICIENT, color="gray", lw=0.8)
    ax_r.set_ylabel("ratio")
    ax_a.axvline(PRESS, color="k", ls="--", lw=1)
    ax_a.set(xlabel="t [s]", ylabel="force on the block", title="(a) forces of the tip")
    ax_a.legend(loc="center right", fontsize=8)
    times = np.unique(rows["t"])
    for when in (times[np.argmin(np.abs(times - PRESS))], times[-1]):
        at = np.isclose(rows["t"], when)
        order = np.argsort(rows["x"][at])
        ax_b.plot(rows["x"][at][order], rows["u_normal"][at][order], label=f"t = {when:.3g}")
    ax_b.set(xlabel="x1", ylabel="u_2 on the top", title="(b) the groove")
    ax_b.legend(fontsize=8)
    slipping = rows["slipping"] > 0
    # in contact: on the tip (no clearance) and pressed. (The nodal pressure alone would also
    # mark a P2 midpoint just off the tip's edge: it is the lumped pressure of its facets.)
    pressed = (rows["pressure"] > 1e-6 * np.abs(rows["pressure"]).max()) & (rows["clearance"] <= 0)
    sticking = pressed & ~slipping
    ax_c.plot(rows["x"][slipping], rows["t"][slipping], "r.", ms=2, label="slipping")
    ax_c.plot(rows["x"][sticking], rows["t"][sticking], "b.", ms=2, label="sticking")
    ax_c.set(xlabel="x1", ylabel="t [s]", title="(c) contact nodes: stick and slip")
    ax_c.legend(fontsize=8)
    for ax in (ax_a, ax_b, ax_c):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "scratch.png", dpi=140)
    plt.close(fig)
    sliding = t >= PRESS + 0.1
    print(f"while sliding F_1/(−F_2) = {np.nanmean(ratio[sliding]):.6f} (𝔣 = {COEFFICIENT}); "
          f"groove depth at the end {-rows['u_normal'][np.isclose(rows['t'], times[-1])].min():.4g};"
          f" figures in {out.resolve()}")


def main(argv=None) -> int:
    return scene_demo_main(run, "A scratch test of a Perzyna block", "output/scratch", "80 20", argv)


if __name__ == "__main__":
    from vpcontact.cli import run_script
    run_script(main)  # JIT messages off the terminal; an error is one line, exit 1
