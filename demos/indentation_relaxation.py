# SPDX-License-Identifier: MIT
"""# Indentation and stress relaxation of a viscoplastic block (beyond the paper)

## The model
A rigid cylinder of radius R = 0.5 (a long punch, plane strain) is pushed into the top of a block
Ω = (-1, 1) × (-1, 0) of Perzyna material, σ̇ = E ε(u̇) − (1/μ*) E(σ − P_K σ), by a prescribed
depth d(t) = 0.02 min(t/0.25, 1): a ramp over 0.25 s, then held. The block is clamped at its
bottom; its top is frictionless Signorini contact with the moving cylinder where the cylinder can
reach it (|x1| ≤ 0.4) and traction-free elsewhere. E = 1000, ν = 0.3, von Mises yield set with
σ_Y = 8, μ* = 20 (relaxation time μ*/E = 0.02 s). This is the bundled scene
``indentation_relaxation`` (``vpcontact run`` with no scene runs it).

## The scheme
The paper's Problem 2 (P1 displacements, stresses at quadrature points, implicit Euler for G)
with the Signorini condition u_ν ≤ g imposed by SNES VI. The cylinder is a built-in obstacle
shape; its translation d(t) moves it, and the gap of each contact node, measured along the node's
normal to the cylinder, is recomputed at every step (negative once the cylinder has passed the
node's reference position).

## What it shows
While the punch goes down, the material below it is driven beyond the yield set and the contact
force rises; once the depth is held, the stress relaxes towards K at the rate (1/μ*) E(σ − P_K σ),
so the force falls from its peak and settles at the force of the relaxed, yield-limited state,
with a flatter pressure profile. Written into the output folder:

* what ``vpcontact run`` writes (XDMF series, ``contact.csv``, ``reactions.csv``,
  ``summary.json``, ``final_state.png``, ``contact_history.png``, ``reactions.png``);
* ``relaxation.png``: (a) the contact force against time, with the end of the ramp; (b) the
  contact pressure along the top at the end of the ramp and at t = T.

With ``CI`` set, the run uses a coarser mesh and larger steps.

## Extending it
Any obstacle shape or level set φ(x, t) can push (``[contact] obstacle``, ``motion``); a sphere
on a 3-D block is the same scene with ``type = "box"``; a load-controlled creep test needs the
indenter's force as the unknown, which this displacement-driven setting leaves for later.
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

RAMP = 0.25  # end of the ramp in the scene's motion


def run(out: str | Path = "output/indentation_relaxation", cells: tuple[int, int] | None = None,
        k: float | None = None):
    """Run the scene (``cells`` and step ``k`` overridden if given); return the session."""
    ci = bool(os.environ.get("CI"))
    cells = cells or ((8, 4) if ci else None)  # the scene's own: 16×8, graded by refinement
    k = k or (0.05 if ci else 0.025)
    scene = scenes.load_bundled("indentation_relaxation", cells, k)
    session = Session(build(scene), Path(out))
    session.run()
    _relaxation_figure(Path(out), session)
    return session


def _relaxation_figure(out: Path, session) -> None:
    if MPI.COMM_WORLD.rank != 0:
        return
    from vpcontact.output.plots import _pyplot
    plt = _pyplot()
    forces = session.forces
    t = np.array(forces.times)
    force = -np.array(forces.contact)[:, 1]
    rows = np.genfromtxt(out / "contact.csv", delimiter=",", names=True)  # columns by name
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax_a.plot(t, force, "o-", ms=3)
    ax_a.axvline(RAMP, color="k", ls="--", lw=1, label="end of the ramp")
    ax_a.set(xlabel="t [s]", ylabel="contact force per unit length",
             title="(a) the force relaxes while the depth is held")
    ax_a.legend()
    for when in (t[np.argmin(np.abs(t - RAMP))], t[-1]):
        at = np.isclose(rows["t"], when)
        order = np.argsort(rows["x"][at])
        ax_b.plot(rows["x"][at][order], rows["pressure"][at][order], "o-", ms=3,
                  label=f"t = {when:.3g}")
    ax_b.set(xlabel="x1", ylabel="contact pressure −σ_ν", title="(b) pressure along the top")
    ax_b.legend()
    for ax in (ax_a, ax_b):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "relaxation.png", dpi=140)
    plt.close(fig)
    peak, final = force.max(), force[-1]
    print(f"contact force: peak {peak:.4g} at t = {t[np.argmax(force)]:.3g}, {final:.4g} at "
          f"t = {t[-1]:.3g} ({100 * (1 - final / peak):.0f} % relaxed); figures in {out.resolve()}")


def main(argv=None) -> int:
    return scene_demo_main(run, "Indentation and relaxation of a Perzyna block", "output/indentation_relaxation",
                           "16 8, refined towards the contact", argv)


if __name__ == "__main__":
    from vpcontact.cli import run_script
    run_script(main)  # JIT messages off the terminal; an error is one line, exit 1
