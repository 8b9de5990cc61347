# SPDX-License-Identifier: MIT
"""# Indentation creep of a viscoplastic block: an indenter driven by a force (beyond the paper)

## The model
A rigid cylinder of radius R = 0.5 (a long punch, plane strain) is pressed into the top of a
block Ω = (-1, 1) × (-1, 0) of Perzyna material, σ̇ = E ε(u̇) − (1/μ*) E(σ − P_K σ), by a force
per unit length F(t) = 6 min(t/0.25, 1): a ramp over 0.25 s, then held. The block is clamped at
its bottom; its top is frictionless Signorini contact with the cylinder where it can reach
(|x1| ≤ 0.4) and traction-free elsewhere. E = 1000, ν = 0.3, von Mises yield set with σ_Y = 8,
μ* = 20 (relaxation time μ*/E = 0.02 s). This is the bundled scene ``indentation_creep``: the
force-controlled twin of ``indentation_relaxation``, whose depth is prescribed.

## The scheme
The depth is not given: the cylinder's displacement d along the force is an unknown of every
step, solved with u in the same SNES VI solve (``vpcontact/solver/variables.py``): the gaps of
the contact nodes are linear in d over the step, u_ν,i ≤ g_i(d_p) + (e·ν_i)(d − d_p), which is a
bound on w_i = u_ν,i − (e·ν_i)(d − d_p); the extra equation is the cylinder's equilibrium,
Σ_i σ_ν,i ν_i·e = F(t). So the contact force equals F(t) to solver tolerance at every step. The
body is the mixed (Taylor–Hood) formulation, the default for plane-strain Perzyna (isochoric
flow locks P1 displacements).

## What it shows
While the force is held the block keeps flowing under the punch, so the depth keeps growing —
creep — ever more slowly as the contact widens and the stress below it relaxes towards the yield
set. Written into the output folder:

* what ``vpcontact run`` writes (XDMF series, ``contact.csv``, ``reactions.csv`` with the depth in
  its ``displacement`` column, ``summary.json``, figures);
* ``creep.png``: (a) the depth against time, with the end of the ramp; (b) the force against the
  depth (the loading branch, then the creep branch at constant force).

With ``CI`` set, the run uses a coarser mesh and larger steps.

## Extending it
A sphere on a 3-D block is the same scene with ``type = "box"`` and a ``sphere`` obstacle; two
indenters are two ``[[contact]]`` tables; a block resting on a foundation needs no Dirichlet part
(its contacts hold it).
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

RAMP = 0.25  # end of the force's ramp in the scene


def run(out: str | Path = "output/indentation_creep", cells: tuple[int, int] | None = None,
        k: float | None = None):
    """Run the scene (``cells`` and step ``k`` overridden if given); return the session."""
    ci = bool(os.environ.get("CI"))
    cells = cells or ((32, 16) if ci else (64, 32))
    k = k or (0.05 if ci else 0.025)
    session = Session(build(scenes.load_bundled("indentation_creep", cells, k)), Path(out))
    session.run()
    _creep_figure(Path(out), session)
    return session


def _creep_figure(out: Path, session) -> None:
    if MPI.COMM_WORLD.rank != 0:
        return
    from vpcontact.output.plots import _pyplot
    plt = _pyplot()
    forces = session.forces
    t = np.array(forces.times)
    depth = -np.array(forces.driver, dtype=float)  # the cylinder's way down
    force = -np.array(forces.contact)[:, 1]
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax_a.plot(t, depth, "o-", ms=3)
    ax_a.axvline(RAMP, color="k", ls="--", lw=1, label="end of the ramp: F held")
    ax_a.set(xlabel="t [s]", ylabel="depth of the cylinder",
             title="(a) the depth grows while the force is held")
    ax_a.legend()
    ax_b.plot(depth, force, "o-", ms=3)
    ax_b.set(xlabel="depth of the cylinder", ylabel="contact force per unit length",
             title="(b) force against depth: loading, then creep")
    for ax in (ax_a, ax_b):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "creep.png", dpi=140)
    plt.close(fig)
    held = t >= RAMP - 1e-12
    print(f"depth {depth[held][0]:.4g} at the end of the ramp, {depth[-1]:.4g} at t = {t[-1]:.3g} "
          f"under the same force {force[-1]:.4g}; figures in {out.resolve()}")


def main(argv=None) -> int:
    return scene_demo_main(run, "Indentation creep of a Perzyna block", "output/indentation_creep", "64 32", argv)


if __name__ == "__main__":
    from vpcontact.cli import run_script
    run_script(main)  # JIT messages off the terminal; an error is one line, exit 1
