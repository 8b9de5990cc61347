# SPDX-License-Identifier: MIT
"""Tables (CSV, Markdown) and log–log figures (PNG) of the studies in :mod:`vpcontact.studies`."""

from __future__ import annotations

import csv
import math
from collections import defaultdict
from pathlib import Path
from typing import Sequence

import numpy as np

from vpcontact.studies.runs import Run, fitted_order, pareto_front

_FIELDS = ("method", "level_h", "level_k", "h", "k", "dofs", "steps", "newton_iterations",
           "wall_time_s", "error", "difference", "skipped")


def _row(run: Run) -> dict:
    return {"method": run.method.label, "level_h": run.level_h, "level_k": run.level_k,
            "h": f"{run.h:.6g}", "k": f"{run.k:.6g}", "dofs": run.dofs, "steps": run.steps,
            "newton_iterations": run.newton_iterations, "wall_time_s": f"{run.wall_time:.6g}",
            "error": "" if run.error is None else f"{run.error:.6e}",
            "difference": "" if run.difference is None else f"{run.difference:.6e}",
            "skipped": run.skipped}


def write_csv(path: Path, runs: Sequence[Run], extra: dict | None = None) -> None:
    extra = extra or {}
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=_FIELDS + tuple(extra))
        writer.writeheader()
        for i, run in enumerate(runs):
            writer.writerow({**_row(run), **{key: values[i] for key, values in extra.items()}})


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


# -- convergence ------------------------------------------------------------------------------

def convergence_parameter(runs: Sequence[Run], refine: str) -> np.ndarray:
    return np.array([r.k if refine == "k" else r.h for r in runs])


def convergence_summary(runs: Sequence[Run], refine: str) -> dict:
    """Fitted order and constant, successive orders, and max err / max(h, k) (the paper's error
    constant C on its h = k path); ``estimated``: the errors are Richardson estimates
    (:func:`~vpcontact.studies.runs.richardson`), the orders those of the differences."""
    param = convergence_parameter(runs, refine)
    errors = np.array([r.error for r in runs])
    order, constant = fitted_order(param, errors)
    successive = [math.nan] + [float(np.log(errors[i - 1] / errors[i])
                                     / np.log(param[i - 1] / param[i])) for i in range(1, len(runs))]
    return {"order": order, "constant": constant, "successive": successive,
            "hk_constant": float(max(r.error / max(r.h, r.k) for r in runs)),
            "estimated": runs[0].difference is not None}


def _error_definition(reference: str, estimated: bool) -> list[str]:
    """The sentences that say what the error column is."""
    measured = ("max over the sampled times and the coarsest mesh's vertices of "
                "|u_i - u_{i+1}|, the difference of run i to the next finer run i+1")
    if not estimated:
        return [f"Error: max over the sampled times and the coarsest mesh's vertices of "
                f"|u - u_ref|, against the {reference}."]
    return [f"Errors: {reference}.", "",
            f"No exact solution was given (`--exact`), so the order is not fitted to errors "
            f"against a finer run (whose own error would steepen the fit) but to the "
            f"differences d_i = {measured}: for an error C r^p they are C r_i^p (1 - 2^-p), so "
            "p = log(d_(i-1)/d_i)/log 2 from any three runs (Richardson), fitted by least "
            "squares over all of them; the estimated error of run i is d_i/(1 - 2^-p)."]


def write_convergence(out: Path, scene_name: str, runs: Sequence[Run], refine: str,
                      reference: str) -> dict:
    """convergence.csv, convergence.md, convergence.png in ``out``; returns the summary."""
    summary = convergence_summary(runs, refine)
    write_csv(out / "convergence.csv", runs,
              {"observed_order": [f"{p:.4f}" for p in summary["successive"]]})
    name = {"both": "h and k together", "h": "h (k fixed)", "k": "k (h fixed)"}[refine]
    estimated = runs[0].difference is not None
    lines = [f"# Convergence of `{scene_name}`: {runs[0].method.label}, refining {name}", "",
             *_error_definition(reference, estimated), "",
             "| h | k | dofs | steps | Newton its | wall time [s] | "
             + ("difference to the next run | estimated error" if estimated else "error")
             + " | observed order |", "|---|---|---|---|---|---|---|---|" + "---|" * estimated]
    for run, p in zip(runs, summary["successive"]):
        order = "" if math.isnan(p) else f"{p:.2f}"
        error = (f"{run.difference:.3e} | " if estimated else "") + f"{run.error:.3e}"
        lines.append(f"| {run.h:.4g} | {run.k:.4g} | {run.dofs} | {run.steps} | "
                     f"{run.newton_iterations} | {run.wall_time:.3g} | {error} | {order} |")
    variable = "k" if refine == "k" else "h"
    lines += ["", ("Fitted (Richardson, to the differences): " if estimated else "Fitted: ")
              + f"error ≈ {summary['constant']:.3g} · {variable}^{summary['order']:.2f}; "
                  f"error constant max error / max(h, k) = {summary['hk_constant']:.3g} "
                  "(the paper's C when h = k).", ""]
    (out / "convergence.md").write_text("\n".join(lines))
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    param = convergence_parameter(runs, refine)
    errors = [r.error for r in runs]
    ax.loglog(param, errors, "o-", label=runs[0].method.label)
    ax.loglog(param, summary["constant"] * param ** summary["order"], "k--", lw=0.8,
              label=f"fit: order {summary['order']:.2f}")
    ax.set(xlabel=variable, ylabel=("estimated " if estimated else "")
           + "max nodal displacement error", title=f"{scene_name}: refining {name}")
    ax.grid(True, which="both", lw=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "convergence.png", dpi=120)
    plt.close(fig)
    return summary


# -- work–precision ---------------------------------------------------------------------------

def method_advice(runs: Sequence[Run]) -> dict[str, str]:
    """One sentence per method: where it is on the Pareto front (error against wall time)."""
    front = pareto_front(runs)
    on_front = defaultdict(list)
    for run in front:
        on_front[run.method.label].append(run)
    by_method = defaultdict(list)
    for run in runs:
        by_method[run.method.label].append(run)
    advice = {}
    for label, mine in by_method.items():
        done = [r for r in mine if r.error is not None]
        if not done:
            advice[label] = f"{label}: no run completed ({mine[0].skipped or 'skipped'})."
            continue
        best = on_front.get(label, [])
        if best:
            lo, hi = min(r.error for r in best), max(r.error for r in best)
            span = f"{hi:.1e}" if lo == hi else f"{hi:.1e} down to {lo:.1e}"
            advice[label] = (f"{label}: on the Pareto front for errors {span} ({len(best)} of its "
                             f"{len(done)} runs); pick it there.")
        else:
            beaters = defaultdict(int)
            for run in done:
                for other in front:
                    if other.wall_time <= run.wall_time and other.error <= run.error:
                        beaters[other.method.label] += 1
                        break
            winner = max(beaters, key=beaters.get) if beaters else "another method"
            advice[label] = (f"{label}: never on the front; a run of {winner} is both faster and "
                             f"more accurate than most of its runs.")
    return advice


def write_cost(out: Path, scene_name: str, runs: Sequence[Run], reference: str) -> dict:
    """cost.csv, cost.md, cost.png in ``out``; returns the Pareto front and the advice."""
    front = pareto_front(runs)
    on_front = {id(r) for r in front}
    write_csv(out / "cost.csv", runs, {"pareto": [int(id(r) in on_front) for r in runs]})
    advice = method_advice(runs)
    lines = [f"# Work–precision of `{scene_name}`", "",
             f"Error: max over the sampled times and the coarsest mesh's vertices of "
             f"|u - u_ref|, against the {reference}. Wall time: the time loop alone.", "",
             "| method | h | k | dofs × steps | wall time [s] | error | Pareto |",
             "|---|---|---|---|---|---|---|"]
    done = sorted((r for r in runs if r.error is not None), key=lambda r: r.wall_time)
    for run in done:
        mark = "**yes**" if id(run) in on_front else ""
        lines.append(f"| {run.method.label} | {run.h:.4g} | {run.k:.4g} | {run.work} | "
                     f"{run.wall_time:.3g} | {run.error:.3e} | {mark} |")
    skipped = [r for r in runs if r.skipped]
    if skipped:
        lines += ["", "Not run: " + "; ".join(f"{r.method.label}, k = {r.k:.4g} ({r.skipped})"
                                              for r in skipped)]
    lines += ["", "When to pick which:", ""] + [f"* {text}" for text in advice.values()] + [""]
    (out / "cost.md").write_text("\n".join(lines))

    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    markers = "osD^v<>p*h"
    for n, label in enumerate(sorted({r.method.label for r in done})):
        mine = [r for r in done if r.method.label == label]
        for ax, cost_of in zip(axes, (lambda r: r.wall_time, lambda r: r.work)):
            ax.loglog([cost_of(r) for r in mine], [r.error for r in mine], markers[n % 10],
                      ls="none", alpha=0.8, label=label)
    axes[0].step([r.wall_time for r in front], [r.error for r in front], "k-", where="post",
                 lw=1.0, label="Pareto front")
    axes[0].set(xlabel="wall time of the time loop [s]", ylabel="max nodal displacement error")
    axes[1].set(xlabel="dofs × steps", ylabel="max nodal displacement error")
    for ax in axes:
        ax.grid(True, which="both", lw=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{scene_name}: work–precision")
    fig.tight_layout()
    fig.savefig(out / "cost.png", dpi=120)
    plt.close(fig)
    return {"front": front, "advice": advice}
