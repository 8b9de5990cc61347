# SPDX-License-Identifier: MIT
"""Benchmark: nanoseconds per quadrature point of the C++ kernels against vectorised numpy.

Targets (issue "[5 of 5]"): the C++ kernels ≥ 20× faster than a numpy implementation of the same
mathematics (tests/reference/numpy_reference.py, the tests' oracle), and ≤ 100 ns per point for
the 3-D implicit update.
For each model (1-D, plane stress, 3-D) and branch (elastic: every point inside K; plastic:
every point outside), times the projection P_K, the explicit update (σ only, as the solver calls
it: its tangent is the constant E, written once per step size) and the implicit update with its
consistent tangent on N points (best of --repeats, C++ and numpy runs alternating), after
checking that C++ and numpy agree.

    .venv/bin/python bench/kernel_throughput.py [--points 100000] [--repeats 20]

writes bench/results/kernel_throughput.json (and prints it).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.reference import numpy_reference as ref
from bench.benchlib import machine, output_file, positive_count, positive_int, save
from vpcontact import kernels

E, NU, SIGMA_Y, MU_STAR, DT = 1e8, 0.3, np.sqrt(10.0), 200.0, 0.01


def _best_pair(cpp, numpy_version, repeats: int) -> tuple:
    """Best times of the C++ and the numpy version, measured in alternation (numpy once every
    four C++ runs) so that both see the same state of the shared machine."""
    best_cpp = best_np = np.inf
    for r in range(repeats):
        start = time.perf_counter()
        cpp()
        best_cpp = min(best_cpp, time.perf_counter() - start)
        if r % 4 == 0:
            start = time.perf_counter()
            numpy_version()
            best_np = min(best_np, time.perf_counter() - start)
    return best_cpp, best_np


def _inputs(model: str, branch: str, points: int, rng):
    """σ_{n−1}, ε_{n−1}, ε_n with every trial stress inside (elastic) or outside (plastic) K."""
    n = kernels.mandel_size(model)
    direction = rng.normal(size=(points, n))
    direction /= np.sqrt(kernels.yield_function(kernels.from_mandel(direction, kernels.dimension(model)),
                                                model=model))[:, None]
    scale = 0.5 if branch == "elastic" else 3.0  # in units of σ_Y along the yield form
    sigma_old = scale * SIGMA_Y * direction
    eps_old = np.zeros((points, n))
    eps_new = np.zeros((points, n))  # the trial stress is σ_{n−1}: the branch is known
    return sigma_old, eps_old, eps_new


def _case(model: str, branch: str, points: int, repeats: int, rng) -> dict:
    Emat = kernels.elasticity_matrix(model, E, NU)
    d, n = kernels.dimension(model), kernels.mandel_size(model)
    Y = ref.yield_matrix(lambda m: kernels.yield_function(kernels.from_mandel(m, d), model=model), n)
    so, eo, en = _inputs(model, branch, points, rng)
    out_s, out_t = np.empty_like(so), np.empty((points, n, n))
    beta = DT / MU_STAR
    ops = {
        "projection": (
            lambda: kernels.project_mandel(so, E=E, nu=NU, sigma_y=SIGMA_Y, model=model, out=out_s),
            lambda: ref.project(so, Emat, Y, SIGMA_Y)),
        "explicit_update": (
            lambda: kernels.stress_update_mandel(so, eo, en, dt=DT, E=E, nu=NU, sigma_y=SIGMA_Y,
                                                 mu_star=MU_STAR, model=model, scheme="explicit",
                                                 out=(out_s, None), tangent=False),
            lambda: ref.explicit_update(so, eo, en, Emat, Y, SIGMA_Y, beta)),
        "implicit_update": (
            lambda: kernels.stress_update_mandel(so, eo, en, dt=DT, E=E, nu=NU, sigma_y=SIGMA_Y,
                                                 mu_star=MU_STAR, model=model, scheme="implicit",
                                                 out=(out_s, out_t)),
            lambda: ref.implicit_update(so, eo, en, Emat, Y, SIGMA_Y, beta)),
    }
    result = {}
    for name, (cpp, numpy_version) in ops.items():
        got, want = cpp(), numpy_version()
        got = tuple(g for g in got if g is not None) if isinstance(got, tuple) else (got,)
        want = want if isinstance(want, tuple) else (want,)
        agreement = max(float(np.abs(g - w).max() / np.abs(w).max())  # σ, and the tangent
                        for g, w in zip(got, want))
        if not agreement <= 1e-10:
            raise SystemExit(f"{model} {branch} {name}: C++ and numpy differ by {agreement:.2e}")
        t_cpp, t_np = _best_pair(cpp, numpy_version, repeats)
        # Bytes the C++ kernel must move per point (inputs read once, outputs written once):
        # the floor set by memory bandwidth, which bounds the elastic branches.
        moved = 8 * {"projection": 2 * n, "explicit_update": 4 * n,
                     "implicit_update": 4 * n + n * n}[name]
        result[name] = {"ns_per_point_cpp": 1e9 * t_cpp / points,
                        "ns_per_point_numpy": 1e9 * t_np / points,
                        "speedup": t_np / t_cpp, "max_relative_difference": agreement,
                        "bytes_per_point": moved, "cpp_gb_per_s": moved * points / t_cpp / 1e9}
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=positive_int, default=100_000)
    parser.add_argument("--repeats", type=positive_count, default=20,
                        help="best of this many C++ runs (of a quarter as many numpy runs): the "
                             "machine is shared, single runs vary by 2x")
    parser.add_argument("--out", type=output_file,
                        default=str(Path(__file__).parent / "results" / "kernel_throughput.json"))
    args = parser.parse_args(argv)
    rng = np.random.default_rng(2026)
    cases = {f"{model}/{branch}": _case(model, branch, args.points, args.repeats, rng)
             for model in ("1d", "plane_stress", "3d") for branch in ("elastic", "plastic")}
    speedups = [op["speedup"] for case in cases.values() for op in case.values()]
    implicit_3d = max(cases[f"3d/{b}"]["implicit_update"]["ns_per_point_cpp"]
                      for b in ("elastic", "plastic"))
    result = {"benchmark": "kernel_throughput", "machine": machine(MPI.COMM_WORLD),
              "points": args.points, "repeats": args.repeats,
              "data": {"E": E, "nu": NU, "sigma_y": SIGMA_Y, "mu_star": MU_STAR, "dt": DT},
              "cases": cases, "min_speedup": min(speedups),
              "ns_per_point_3d_implicit_update": implicit_3d,
              "targets": {"speedup >= 20 (every case)": bool(min(speedups) >= 20),
                          "3-D implicit update <= 100 ns/point": bool(implicit_3d <= 100)}}
    save(result, args.out, MPI.COMM_WORLD)
    return 0


if __name__ == "__main__":
    sys.exit(main())
