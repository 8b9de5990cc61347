# SPDX-License-Identifier: MIT
"""The command line on bundled and hand-written scenes: outputs, exit codes, located errors, and
"only what the scene calls for" (no viscoplastic kernel, no VI, one factorization when possible).

Scenes run at reduced size (coarser mesh, shorter T) by rewriting their ``cells``/``T``/``k`` lines.
"""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact.paper import bar1d
from vpcontact import cli
from vpcontact import scene as scenes
from vpcontact.scene import build
from vpcontact.model import LinearRate, Perzyna, PlaneStrain

from tests.support.mpi_launch import write_shared


def _small(name: str, folder: Path, cells: str, T: float, k: float, extra: str = "") -> Path:
    """A bundled scene with its mesh (uniform: without the scene's refinement boxes), final time
    and step replaced, written into ``folder``."""
    text = scenes.bundled()[name].read_text()
    text = re.sub(r"(?ms)^refine = \[.*?\}\]\n", "", text)
    text = re.sub(r"(?m)^cells = .*$", f"cells = {cells}", text)
    text = re.sub(r"(?m)^T = .*$", f"T = {T}", text)
    text = re.sub(r"(?m)^k = .*$", f"k = {k}", text)
    return write_shared(folder / f"{name}.toml", text + extra)


def _summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def test_list_shows_every_bundled_scene(capsys):
    assert cli.main(["list"]) == 0
    shown = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        for name in scenes.bundled():
            assert name in shown


@pytest.mark.parametrize("name", sorted(scenes.bundled()))
def test_bundled_scenes_validate(name, capsys):
    assert cli.main(["validate", name]) == 0


def test_show_prints_a_scene_that_loads_again(capsys):
    assert cli.main(["show", "signorini_3d"]) == 0
    text = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert scenes.loads_text(text) == scenes.load(scenes.resolve("signorini_3d"))


def test_bad_scene_exits_2_with_its_place_and_writes_nothing(shared_tmp_path, capsys):
    bad = _small("elastic_2d", shared_tmp_path, "[4, 2]", 1.0, 0.5)
    text = bad.read_text().replace("E = 1e5", "E = -1e5")
    write_shared(bad, text)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        line = 1 + text.splitlines().index("E = -1e5")
        assert f"{bad}:{line}: material.E" in err
    assert not out.exists()


@pytest.mark.parametrize("change, where, message", [
    (("value = 4.0", "value = 5.0"), "boundary.end", "selects no boundary facet"),
    (("[boundary.end]\nkind = \"traction\"\nplane = { axis = \"x\", value = 4.0 }",
      "[boundary.end]\nkind = \"traction\"\nplane = { axis = \"x\", value = 0.0 }"),
     "boundary.end", "overlap"),
])
def test_mesh_level_errors_are_located(shared_tmp_path, capsys, change, where, message):
    path = _small("elastic_2d", shared_tmp_path, "[4, 2]", 1.0, 0.5)
    text = path.read_text()
    assert change[0] in text
    write_shared(path, text.replace(change[0], change[1]))
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(rf"{re.escape(str(path))}:\d+: {where}: .*{message}", err), err
    assert not out.exists()


def test_elastic_scene_uses_one_factorization_and_no_viscoplastic_kernel(shared_tmp_path):
    path = _small("elastic_2d", shared_tmp_path, "[16, 4]", 1.0, 0.1)
    model = build(scenes.load(path))
    law = model.problem.law
    assert isinstance(law, LinearRate) and law.a == 0 and law.b == 0  # σ = E ε: no Perzyna
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    summary = _summary(out)
    assert summary["completed"] and summary["steps"] == 10
    assert summary["jacobian_assemblies"] == 1, "one assembly (and factorization) for all steps"
    assert summary["vi_solves"] == 0
    assert (out / "elastic_2d.xdmf").exists()
    assert not (out / "contact.csv").exists() and not (out / "final_state.png").exists()


def test_unreached_obstacle_costs_no_vi_and_changes_nothing(shared_tmp_path):
    free = _small("elastic_2d", shared_tmp_path, "[16, 4]", 1.0, 0.25)
    text = free.read_text()
    contact = text.replace('[boundary.end]', '[boundary.floor]\nkind = "contact"\n'
                           'plane = { axis = "y", value = 0.0 }\n\n[boundary.end]')
    contact += '\n[contact]\ntype = "signorini"\nboundary = "floor"\ngap = 10.0\n'
    path = shared_tmp_path / "far_obstacle.toml"
    write_shared(path, contact)
    results = []
    for scene_path in (free, path):
        model = build(scenes.load(scene_path))
        for _ in range(4):
            model.problem.step(0.25)
        u = model.problem.u  # global measures: the two meshes may be partitioned differently
        low = MPI.COMM_WORLD.allreduce(float(u.x.array.min()), op=MPI.MIN)
        results.append(np.array([u.vector.norm(), low]))
        solver = model.problem.solver
        assert solver.vi_solves == 0 and solver.jacobian_assemblies == 1
    diff = np.abs(results[0] - results[1]).max() / np.abs(results[0]).max()
    assert diff <= 1e-12, f"relative difference {diff:.2e}"


def test_reached_obstacle_switches_to_the_vi(shared_tmp_path):
    free = _small("elastic_2d", shared_tmp_path, "[16, 4]", 1.0, 0.25)
    text = free.read_text().replace('[boundary.end]', '[boundary.floor]\nkind = "contact"\n'
                                    'plane = { axis = "y", value = 0.0 }\n\n[boundary.end]')
    text += '\n[contact]\ntype = "signorini"\nboundary = "floor"\ngap = 1e-5\n'
    path = shared_tmp_path / "near_obstacle.toml"
    write_shared(path, text)
    model = build(scenes.load(path))
    for _ in range(4):
        model.problem.step(0.25)
    report = model.problem.contact_monitor.report()
    assert model.problem.solver.vi_solves > 0 and report.active > 0
    assert report.max_penetration <= 1e-10


def test_1d_scene_reproduces_the_exact_solution(shared_tmp_path):
    # §4.2.1 with h = k = 0.05 up to t = 2 (contact from t = ln 2): nodal error O(h + k).
    path = _small("normal_compliance_1d", shared_tmp_path, "[20]", 2.0, 0.05)
    out = shared_tmp_path / "out1d"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    model = build(scenes.load(path))
    for _ in range(40):
        model.problem.step(0.05)
    V = model.problem.V
    x = V.sub(0).collapse()[0].tabulate_dof_coordinates()[:, 0]  # bs = 1: the same dof order
    owned = V.dofmap.index_map.size_local
    err = np.abs(model.problem.u.x.array[:owned] - bar1d.exact_displacement(x[:owned], 2.0)).max()
    err = MPI.COMM_WORLD.allreduce(err, op=MPI.MAX)
    assert err < 0.1 * 0.05, f"max nodal error {err:.3e} at r = 0.05 (paper: C r, C = 0.0956)"
    rows = (out / "contact.csv").read_text().splitlines()
    assert rows[0] == "t,x,y,z,u_normal,gap,clearance,pressure" and len(rows) == 1 + 41  # t = 0 and 40 steps
    last = [float(v) for v in rows[-1].split(",")]
    # normal compliance: the node is past the foundation's surface (negative clearance)
    assert last[4] > last[5] and last[7] == pytest.approx((last[4] - last[5]) / 100.0)
    assert last[6] == pytest.approx(last[5] - last[4]) and last[6] < 0


@pytest.mark.parametrize("name, cells, T, k", [
    ("signorini_2d", "[6, 6]", 0.2, 0.1),
    ("signorini_3d", "[6, 2, 2]", 0.2, 0.1),
    ("normal_compliance_2d", "[12, 6]", 0.2, 0.1),
    ("normal_compliance_3d", "[6, 2, 2]", 0.2, 0.1),
])
def test_bundled_scene_runs_and_writes_its_outputs(shared_tmp_path, name, cells, T, k):
    path = _small(name, shared_tmp_path, cells, T, k)
    out = shared_tmp_path / name
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    summary = _summary(out)
    assert summary["completed"] and math.isclose(summary["final_time"], T)
    assert summary["scene"]["sha256"] == scenes.load(path).hash
    for f in (f"{name}.xdmf", "contact.csv", "final_state.png", "contact_history.png"):
        assert (out / f).exists(), f
    assert len(summary["converged_reasons"]) == summary["steps"]
    assert all(r.startswith("CONVERGED") for r in summary["converged_reasons"])
    assert "contact_pressure" in (out / f"{name}.xdmf").read_text()
    # The wall-time split: every part measured, none negative, together within the wall time.
    split = summary["wall_time_split_s"]
    assert set(split) == {"kernel", "residual_assembly", "jacobian_assembly", "linear_solve",
                          "vi_and_other_snes", "output"}
    assert all(v > 0 for k, v in split.items() if k != "vi_and_other_snes"), split
    assert split["vi_and_other_snes"] > -1e-3, split  # a difference of two clocks
    assert sum(split.values()) <= summary["wall_time_s"] * 1.01 + 1e-3, split
    values = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
    assert np.isfinite(values).all() and (values[:, 7] >= -1e-8).all()  # compressive only
    # the clearance is the gap less u_ν; a rigid obstacle is never penetrated (to round-off)
    np.testing.assert_allclose(values[:, 6], values[:, 5] - values[:, 4], rtol=0,
                               atol=1e-9 * np.abs(values[:, 4:6]).max())  # 11 digits written
    if scenes.load(path).contact.type == "signorini":
        assert (values[:, 6] >= -1e-9 * np.abs(values[:, 4:6]).max()).all()


def test_failed_run_exits_1_and_keeps_an_incomplete_summary(shared_tmp_path, capsys):
    # One Newton iteration allowed and no step halving: the first step cannot converge.
    path = _small("signorini_2d", shared_tmp_path, "[4, 4]", 1.0, 0.5,
                  extra="\n[solver]\npetsc_options = { snes_max_it = 1 }\n")
    text = re.sub(r"(?m)^k = .*$", "k = 0.5\nmax_cuts = 0", path.read_text())
    write_shared(path, text)
    out = shared_tmp_path / "failed"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 1
    summary = _summary(out)
    assert summary["completed"] is False and "DIVERGED_MAX_IT" in summary["error"]
    assert summary["steps"] == 0
    if MPI.COMM_WORLD.rank == 0:
        assert "the simulation failed" in capsys.readouterr().err


def test_a_negative_compliant_gap_at_one_node_is_a_located_error_on_every_rank(
        shared_tmp_path, capsys):
    """A normal-compliance gap below 0 at one node (here at the part's end, held by one process
    on 2 ranks): ``validate`` and ``run`` refuse it at its line, exit 2, nothing written. The
    part made its gaps on first use, during the run: ``validate`` passed it, ``run`` raised
    after the output folder was made, and on 2 ranks only the owning process raised — the
    other waited in a collective call and the run hung."""
    text = _small("normal_compliance_2d", shared_tmp_path, "[8, 2]", 0.2, 0.05).read_text()
    text = re.sub(r"(?m)^gap = .*$", 'gap = "-0.01 if x[0] < 0.1 else 0.0"', text)
    path = write_shared(shared_tmp_path / "negative_gap.toml", text)
    line = text.splitlines().index('gap = "-0.01 if x[0] < 0.1 else 0.0"') + 1
    out = shared_tmp_path / "negative_gap"
    for command in (["validate", str(path)], ["run", str(path), "--out", str(out), "--quiet"]):
        assert cli.main(command) == 2
        if MPI.COMM_WORLD.rank == 0:
            err = capsys.readouterr().err
            assert f"{path}:{line}: contact.gap:" in err and "-0.01" in err, err
    assert not out.exists()


def test_resuming_a_run_checkpointed_at_its_end_changes_nothing(shared_tmp_path, capsys):
    """A run whose last checkpoint is its last step has nothing to resume: exit 2 with that
    said, and its summary (completed) untouched. It was overwritten with "completed": false
    and an unlocated message about the final time."""
    path = _small("signorini_2d", shared_tmp_path, "[4, 4]", 0.5, 0.25,
                  extra="\n[output]\nxdmf = false\nfigures = false\ncheckpoint_every = 1\n")
    out = shared_tmp_path / "finished"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    summary = (out / "summary.json").read_bytes()
    assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 2
    if MPI.COMM_WORLD.rank == 0:
        assert "already reached T = 0.5" in capsys.readouterr().err
    assert (out / "summary.json").read_bytes() == summary


def test_output_folders_that_cannot_be_are_refused_by_every_command(shared_tmp_path, capsys):
    """``--out`` naming a file is refused by ``study`` as by ``run`` (exit 2; it ended in an
    internal error), an empty ``--out`` too (it wrote into output/<scene>), and the time
    loop that the demos call refuses it with a located error (a traceback before)."""
    from vpcontact.errors import InputError
    from vpcontact.output import runner
    from vpcontact.paper import bar1d

    a_file = write_shared(shared_tmp_path / "a_file", "")
    study = ["study", "convergence", "normal_compliance_1d", "--cells", "10", "--k", "0.1",
             "--T", "1", "--levels", "2", "--quiet"]
    assert cli.main(study + ["--out", str(a_file)]) == 2
    assert cli.main(["run", "signorini_2d", "--out", "", "--quiet"]) == 2
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        assert "an existing file, not a folder" in err and "--out is empty" in err, err
    with pytest.raises(InputError, match="an existing file, not a folder"):
        runner.run(bar1d.build_problem(4), 0.1, 0.05, out=a_file)


@pytest.mark.parametrize("option", ["snes_type=newtonls", "snes_max_it=-5", "snes_rtol=nan",
                                    "ksp_atol=-1", "snes_mf=1"])
def test_solver_options_vpcontact_cannot_run_with_are_refused_up_front(shared_tmp_path, capsys,
                                                                       option):
    """Options PETSc takes but the step solver cannot use (a SNES without bounds for rigid
    contact, a matrix-free SNES) or that PETSc refuses only in the middle of a solve, or never
    (a negative iteration count, a NaN or negative tolerance): exit 2 naming the option,
    nothing written. They ended in internal errors, or ran with the nonsense value."""
    path = _small("signorini_2d", shared_tmp_path, "[4, 4]", 0.5, 0.25)
    out = shared_tmp_path / "bad_option"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet",
                     "--petsc-options", option]) == 2
    if MPI.COMM_WORLD.rank == 0:
        assert f"solver.petsc_options.{option.split('=')[0]}:" in capsys.readouterr().err
    assert not out.exists()


def test_a_mesh_with_fewer_cells_than_processes_is_refused_at_its_line(shared_tmp_path,
                                                                        capsys):
    """A 1-cell bar is a valid scene serially; on 2 ranks one process holds no cell, raised in
    the set-up and left the other waiting in a collective call (validate, run and study hung).
    Now: a located error on every process, exit 2."""
    path = _small("normal_compliance_1d", shared_tmp_path, "[1]", 0.1, 0.05)
    expected = 0 if MPI.COMM_WORLD.size == 1 else 2
    assert cli.main(["validate", str(path)]) == expected
    if expected and MPI.COMM_WORLD.rank == 0:
        line = path.read_text().splitlines().index("cells = [1]") + 1
        assert f"{path}:{line}: mesh.cells: the mesh has 1 cell(s), too few for 2" in \
            capsys.readouterr().err


def test_a_viewer_option_given_true_switches_it_on(shared_tmp_path, capfd):
    """``snes_converged_reason = true`` (natural in TOML and on the command line) is PETSc's
    bare flag: the reason is printed and the run completes. PETSc took "true" for a viewer's
    name and the run stopped with an internal error; ``false`` leaves the option off."""
    path = _small("elastic_2d", shared_tmp_path, "[4, 2]", 1.0, 0.5)
    for value, shown in (("true", True), ("false", False)):
        out = shared_tmp_path / f"reason_{value}"
        assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--petsc-options",
                         f"snes_converged_reason={value}"]) == 0
        printed = capfd.readouterr().out
        if MPI.COMM_WORLD.rank == 0:
            assert ("solve converged due to" in printed) == shown, printed


def test_a_solver_option_nothing_reads_is_refused_at_its_line(shared_tmp_path, capsys):
    """A misspelt PETSc option (``snes_linesearh_type``) or vpcontact option
    (``vpcontact_stal_rtol``) was silently ignored and the run used the defaults. PETSc's
    options database says which options the step solver's SNES, KSP and PC read when they were
    set up: the others are refused there, each at its line, exit 2, nothing written; the
    options that are read (``snes_rtol``, ``pc_factor_shift_type``) are not."""
    extra = ('\n[solver.petsc_options]\nsnes_rtol = 1e-9\npc_factor_shift_type = "none"\n'
             'snes_linesearh_type = "bt"\nvpcontact_stal_rtol = 1e-6\n')
    path = _small("elastic_2d", shared_tmp_path, "[4, 2]", 1.0, 0.5, extra=extra)
    out = shared_tmp_path / "misspelt_option"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    assert not out.exists()
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        lines = path.read_text().splitlines()
        at = {key: f"{path}:{lines.index(next(s for s in lines if s.startswith(key))) + 1}: "
              f"solver.petsc_options.{key}: " for key in ("snes_linesearh_type",
                                                           "vpcontact_stal_rtol")}
        assert at["snes_linesearh_type"] + "PETSc never read this option" in err, err
        assert at["vpcontact_stal_rtol"] + "not an option of vpcontact (did you mean " \
            '"vpcontact_stall_rtol"?' in err, err
        assert "snes_rtol:" not in err and "pc_factor_shift_type:" not in err, err


def test_an_option_read_only_while_solving_that_nothing_read_is_reported(shared_tmp_path,
                                                                         capsys):
    """Options PETSc reads only while solving (viewers, at the end of a solve) cannot be judged
    at set-up: one that no solve read (``snes_vieww``) ends the run with a warning naming it,
    on stderr and in summary.json. Options of solvers this run never set up (``lagged_*``: the
    VI's linear solver, here without contact; ``fieldsplit_*``: the iterative solver) and the
    viewers that were read are not reported. (The misspelt viewer was silently ignored.)"""
    extra = ('\n[solver.petsc_options]\nsnes_vieww = "ascii:/dev/null"\n'
             'snes_view = "ascii:/dev/null"\nksp_converged_reason = "ascii:/dev/null"\n'
             'lagged_pc_type = "lu"\nfieldsplit_u_ksp_type = "cg"\n')
    path = _small("elastic_2d", shared_tmp_path, "[4, 2]", 1.0, 0.5, extra=extra)
    out = shared_tmp_path / "unread_viewer"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    warnings = [w for w in _summary(out)["warnings"] if "solver option" in w]
    assert len(warnings) == 1 and warnings[0].startswith(
        f"PETSc never read the solver option snes_vieww ({path}:"), warnings
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        assert "warning: PETSc never read the solver option snes_vieww" in err, err


@pytest.mark.parametrize("linear", ["auto", "direct"])
def test_a_krylov_option_under_auto_is_not_refused_on_a_small_mesh(shared_tmp_path, capsys,
                                                                   linear):
    """``ksp_rtol`` is meant for the iterative solver, which ``linear = "auto"`` picks only on
    large meshes: on a small one (the direct solver) the run goes on and says the option was not
    read; with ``linear = "direct"`` chosen it is refused at its line (it was refused under
    ``auto`` too: a scene that ran on a fine mesh was refused on a coarse one)."""
    extra = f'\n[solver]\nlinear = "{linear}"\n[solver.petsc_options]\nksp_rtol = 1e-8\n'
    path = _small("elastic_2d", shared_tmp_path, "[4, 2]", 1.0, 0.5, extra=extra)
    out = shared_tmp_path / f"krylov_option_{linear}"
    code = cli.main(["run", str(path), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    if linear == "direct":
        assert code == 2 and not out.exists()
        if MPI.COMM_WORLD.rank == 0:
            assert "solver.petsc_options.ksp_rtol: PETSc never read this option" in err, err
    else:
        assert code == 0
        warnings = [w for w in _summary(out)["warnings"] if "solver option" in w]
        assert len(warnings) == 1 and "ksp_rtol" in warnings[0], warnings


def test_an_initial_stress_infinite_at_one_process_s_points_is_refused_on_every_one(
        shared_tmp_path, capsys):
    """sigma0 infinite at the centroids of the first column of cells only (x = h/3, which no
    sampled point of the scene check meets): refused at its line, exit 2, nothing written. On 2
    processes the one without those cells waited for ever (the check was not collective)."""
    path = _small("elastic_2d", shared_tmp_path, "[16, 4]", 1.0, 0.5,
                  extra='\n[initial]\nsigma0 = ["1/(x[0] - 0.25/3)", 0.0, 0.0]\n')
    out = shared_tmp_path / "sigma0_infinite"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    assert not out.exists()
    if MPI.COMM_WORLD.rank == 0:
        assert "initial.sigma0: sigma0 is not finite at some quadrature point" in \
            capsys.readouterr().err


@pytest.mark.parametrize("mu_star, warned", [(1e-6, True), (1e-2, False)])
def test_the_linearized_step_far_into_its_stiff_range_is_warned(shared_tmp_path, scene_text,
                                                                mu_star, warned):
    """k E/μ* = 2.5e8: the linearized step's tangent along the flow is nearly singular, and a
    sweep's plane-strain block came out with displacements 60 times the exact ones, exit 0,
    without a word. The run now says so (2.5e4: no warning)."""
    path = write_shared(shared_tmp_path / f"stiff_{mu_star:g}.toml",
                        scene_text("stiff_linearized", mu_star=repr(mu_star)))
    out = shared_tmp_path / f"stiff_{mu_star:g}"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    found = [w for w in _summary(out)["warnings"] if "linearized step" in w]
    assert bool(found) == warned, _summary(out)["warnings"]
    if warned:
        assert found[0].startswith("k E/mu* = 2.5e+08") and 'scheme = "implicit"' in found[0]


@pytest.mark.parametrize("traction, warned", [("-1", False), ("-1e4", True)])
def test_a_run_beyond_small_strains_is_warned(shared_tmp_path, traction, warned):
    """The elastic cantilever bent by 10⁴ times its own end load: bending strains of about 2
    (200 %) in a small-strain model. A sweep's blocks squeezed to 400 % finished without a word;
    such a run now ends with a warning (its own load: 2e-4, none)."""
    path = _small("elastic_2d", shared_tmp_path, "[16, 4]", 1.0, 0.5)
    text = path.read_text().replace('traction = [0.0, "-t"]',
                                    f'traction = [0.0, "{traction}*t"]')
    assert text != path.read_text()
    path = write_shared(shared_tmp_path / f"strained_{traction}.toml", text)
    out = shared_tmp_path / f"strained_{traction}"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    found = [w for w in _summary(out)["warnings"] if "small-strain" in w]
    assert bool(found) == warned, _summary(out)["warnings"]


_BETWEEN_VERTICES = "sqrt(abs(x[0] - 0.125) - 0.1)"  # finite at x[0] = 0, 0.25, ...; NaN between


@pytest.mark.parametrize("name, extra, key, expected", [
    ("elastic_2d", '\n[boundary.top]\nkind = "traction"\nplane = { axis = "y", value = 1.0 }\n'
     f'traction = [0.0, "{_BETWEEN_VERTICES}"]\n', "boundary.top.traction[1]",
     "is not finite at quadrature points"),
    ("elastic_2d", f'\n[loads]\nbody_force = [0.0, "{_BETWEEN_VERTICES}"]\n',
     "loads.body_force[1]", "is not finite at quadrature points"),
    ("elastic_2d", '\n[discretization]\ndegree = 2\n\n[boundary.top]\nkind = "displacement"\n'
     'plane = { axis = "y", value = 1.0 }\ndisplacement = [0.0, "1e-3/(x[0] - 0.125)"]\n',
     "boundary.top.displacement[1]", "evaluates to inf at x = [0.125, 1.0]"),
    ("scratch", "", "contact.friction.threshold", "must be finite and >= 0 at every node"),
])
def test_an_expression_singular_where_it_is_used_is_refused_at_its_line(
        shared_tmp_path, capsys, name, extra, key, expected):
    """Expressions checked at the mesh's vertices only: NaN at the quadrature points between
    them (a traction, a body force: the first step "did not converge", DIVERGED_FNORM_NAN,
    exit 1, outputs written), infinite at a P2 node (a prescribed displacement: an internal
    error, exit 3), or a Tresca threshold 1/x[0] on a face through x[0] = 0 (±1e16 at the node
    there, negative left of it: the run completed, dividing by zero). Now refused at the key's
    line before anything is solved or written, exit 2."""
    path = _small(name, shared_tmp_path, "[16, 4]", 0.2, 0.1, extra=extra)
    if name == "scratch":
        text = path.read_text().replace('friction = { type = "coulomb", coefficient = 0.2 }',
                                        'friction = { type = "tresca", threshold = "1/x[0]" }')
        assert "1/x[0]" in text
        path = write_shared(path, text)
    out = shared_tmp_path / f"singular_{key}"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    assert not out.exists()
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        lines = path.read_text().splitlines()
        word = key.split(".")[-1].split("[")[0]
        line = max(i for i, s in enumerate(lines) if s.startswith((word, "friction"))) + 1
        assert f"{path}:{line}: {key}: " in err and expected in err, err
        assert "did not converge" not in err and "internal error" not in err, err


def test_a_quadratic_bar_writes_its_contact_history(shared_tmp_path):
    """The paper's 1-D bar with P2 displacements: its contact pressure, written as a P1 field,
    is gathered from the vertices of the one-component vector P2 space (whose coordinates
    dolfinx will not tabulate: the run used to stop with an internal error)."""
    path = _small("normal_compliance_1d", shared_tmp_path, "[20]", 1.0, 0.05,
                  extra="\n[discretization]\ndegree = 2\n")
    out = shared_tmp_path / "bar_p2"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    values = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1, ndmin=2)
    assert np.isfinite(values).all() and len(values) == 21  # t = 0 and every step
    assert values[-1, 7] > 0.0, values[-1]  # in contact at the end (from t = ln 2): pressed


@pytest.mark.serial  # on several ranks the run ends the MPI job instead (test_mpi_abort.py)
def test_an_internal_error_is_one_line_and_exit_3_unless_a_traceback_is_asked(
        shared_tmp_path, capsys, monkeypatch):
    """A bug (here an exception planted in the second step) is not a bad scene nor a failed
    step: one line naming it, exit 3, the completed step kept; ``--traceback`` re-raises it."""
    from vpcontact.solver import QuasistaticProblem

    original = QuasistaticProblem.step

    def step(self, dt, tolerance=None):
        if self.step_index == 1:
            raise ZeroDivisionError("planted")
        return original(self, dt, tolerance)

    monkeypatch.setattr(QuasistaticProblem, "step", step)
    path = _small("signorini_2d", shared_tmp_path, "[4, 4]", 1.0, 0.25)
    out = shared_tmp_path / "bug"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == cli.INTERNAL_ERROR
    summary = _summary(out)
    assert summary["completed"] is False and summary["steps"] == 1
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        assert "internal error" in err and "ZeroDivisionError: planted" in err, err
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    with pytest.raises(ZeroDivisionError, match="planted"):
        cli.main(["--traceback", "run", str(path), "--out", str(out), "--quiet"])


@pytest.mark.slow
def test_newton_that_diverges_to_nan_is_a_failed_step_not_a_traceback(shared_tmp_path, capsys):
    """Stiff units (E = 1e9, σ_Y = 1) with the mixed formulation: the first step's Newton
    iterate becomes non-finite; that is a failed step (rolled back, cut, and finally a clean
    failure with exit 1), not the kernels' refusal of a non-finite strain as a traceback."""
    path = _small("indentation_relaxation", shared_tmp_path, "[32, 16]", 0.05, 0.025)
    text = re.sub(r"(?m)^E = .*$", "E = 1e9", path.read_text())
    text = re.sub(r"(?m)^sigma_y = .*$", "sigma_y = 1.0", text)
    text = re.sub(r"(?m)^k = .*$", "k = 0.025\nmax_cuts = 2", text)
    write_shared(path, text)
    out = shared_tmp_path / "nan"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 1
    summary = _summary(out)
    assert summary["completed"] is False and "did not converge" in summary["error"]
    if MPI.COMM_WORLD.rank == 0:
        assert "the simulation failed" in capsys.readouterr().err


@pytest.mark.slow
def test_round_off_floor_of_a_displacement_driven_run_in_stiff_units(shared_tmp_path):
    """E = 1e9, σ_Y = 1, the paper's P1, driven by the indenter's motion with no load: after
    step cuts a step's initial residual is at the round-off floor of the internal forces (about
    1.5e-9 here), where Newton stalls. The round-off stop now measures the residual against the
    support reactions (it measured it against the applied loads, zero here, and the step failed
    with DIVERGED_MAX_IT until snes_atol was raised by hand)."""
    path = _small("indentation_relaxation", shared_tmp_path, "[32, 16]", 0.05, 0.025,
                  extra="\n[discretization]\nformulation = \"displacement\"\ndegree = 1\n")
    text = re.sub(r"(?m)^E = .*$", "E = 1e9", path.read_text())
    text = re.sub(r"(?m)^sigma_y = .*$", "sigma_y = 1.0", text)
    write_shared(path, text)
    out = shared_tmp_path / "stiff"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    summary = _summary(out)
    assert summary["completed"] and math.isclose(summary["final_time"], 0.05)
    assert all(r.startswith("CONVERGED") for r in summary["converged_reasons"])


def test_explicit_scene_beyond_its_stability_limit_is_refused(shared_tmp_path, capsys):
    path = _small("signorini_2d", shared_tmp_path, "[4, 4]", 1.0, 0.5)
    text = path.read_text().replace('scheme = "implicit"', 'scheme = "explicit"')
    write_shared(path, text)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(r":\d+: time.k: k = 0.5 exceeds the stability limit 2.8e-06", err), err
    assert not out.exists()


def test_plane_strain_scene_runs_the_3d_law_in_the_plane(shared_tmp_path):
    path = _small("elastic_2d", shared_tmp_path, "[8, 2]", 1.0, 0.5)
    text = path.read_text().replace('plane = "stress"', 'plane = "strain"')
    write_shared(path, text)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    assert isinstance(build(scenes.load(path)).problem.law, PlaneStrain)
    assert _summary(out)["completed"]


def test_perzyna_scene_builds_the_viscoplastic_law():
    model = build(scenes.load(scenes.resolve("signorini_2d")))
    assert isinstance(model.problem.law, Perzyna)
    assert model.problem.law.sigma_y == pytest.approx(math.sqrt(10.0))


@pytest.mark.slow
@pytest.mark.serial
@pytest.mark.parametrize("verbose", [False, True])
def test_jit_messages_only_with_verbose(tmp_path, verbose):
    """A first run on a fresh machine (an empty JIT cache) shows the progress summary only; the
    form compiler's build messages appear with -v."""
    import os
    import subprocess
    import sys
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache")}
    command = [sys.executable, "-m", "vpcontact", "run", "elastic_2d", "--out",
               str(tmp_path / "out"), "--quiet"] + (["-v"] if verbose else [])
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    assert any((tmp_path / "cache").rglob("*.so")), "the forms must have been compiled afresh"
    shown = result.stdout + result.stderr
    assert ("INFO" in shown) == verbose, shown[-2000:]
    assert "elastic_2d: t = 1" in result.stdout
