# SPDX-License-Identifier: MIT
"""Point histories (``[output] probes`` -> ``probes.csv``) and the viscoplastic strain of the
XDMF series, against the closed form of a creeping bar (tests/scenes/creeping_bar.toml).

Under the constant end traction S the stress is σ = S e1⊗e1 everywhere, and the implicit
Perzyna step integrates ε̇_vp = (S − σ_Y)/μ* diag(2/3, −1/3, −1/3) exactly:
ε_vp(t) = (S − σ_Y) t/μ* diag(2/3, −1/3, −1/3), ε = E⁻¹σ + ε_vp, u = ε x, and the von Mises
equivalent of ε_vp is its axial component. The suite runs these tests serially and on 2 ranks
(scripts/test.sh); tests/mpi/test_mpi_probes.py compares the two runs' files.
"""

import json
import re

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli
from vpcontact import scene as scenes
from vpcontact.output.fields import CellStress
from vpcontact.output.strains import ViscoplasticStrain, equivalent_strain
from vpcontact.scene import build

from tests.support.mpi_launch import write_shared

S, E, NU, SIGMA_Y, MU_STAR = 3.0, 1000.0, 0.3, 1.0, 100.0
PROBES = [(2.0, 1.0, 1.0), (1.0, 0.5, 0.5), (0.3, 0.2, 0.7)]
FORMULATIONS = {"P1": "degree = 1", "mixed": 'formulation = "mixed"'}


def exact(x: np.ndarray, t: float) -> dict:
    """The bar's closed form at points ``x`` (n, 3) and time t (the initial state at t = 0 is
    unloaded: the traction acts from the first step on)."""
    load = S if t > 0 else 0.0
    flow = (S - SIGMA_Y) * t / MU_STAR
    axial, lateral = load / E + 2 / 3 * flow, -NU * load / E - flow / 3
    zeros = np.zeros(len(x))
    return {"u_x": axial * x[:, 0], "u_y": lateral * x[:, 1], "u_z": lateral * x[:, 2],
            "sigma_xx": zeros + load, "sigma_yy": zeros, "sigma_zz": zeros, "sigma_xy": zeros,
            "sigma_xz": zeros, "sigma_yz": zeros, "von_mises": zeros + load,
            "eps_vp_xx": zeros + 2 / 3 * flow, "eps_vp_yy": zeros - flow / 3,
            "eps_vp_zz": zeros - flow / 3, "eps_vp_xy": zeros, "eps_vp_xz": zeros,
            "eps_vp_yz": zeros, "eps_vp_eq": zeros + 2 / 3 * flow}


def _scene(folder, scene_text, formulation="P1", xdmf="false", probes=PROBES):
    text = scene_text("creeping_bar", discretization=FORMULATIONS[formulation], xdmf=xdmf,
                      probes=json.dumps([list(p) for p in probes]))
    return write_shared(folder / f"bar_{formulation}.toml", text)


@pytest.mark.parametrize("formulation", sorted(FORMULATIONS))
def test_probes_csv_holds_the_closed_form_of_a_creeping_bar(shared_tmp_path, scene_text,
                                                             formulation):
    path = _scene(shared_tmp_path, scene_text, formulation)
    out = shared_tmp_path / f"out_{formulation}"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    rows = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    times = np.unique(rows["t"])
    np.testing.assert_allclose(times, [0.0, 0.25, 0.5, 0.75, 1.0], atol=1e-12)
    assert len(rows) == len(times) * len(PROBES)
    for t in times:
        now = rows[np.isclose(rows["t"], t)]
        assert list(now["probe"]) == list(range(len(PROBES)))
        x = np.stack([now["x"], now["y"], now["z"]], axis=1)
        np.testing.assert_array_equal(x, np.array(PROBES))
        for name, want in exact(x, t).items():
            scale = max(S / E, S) if not name.startswith("sigma") and name != "von_mises" else S
            np.testing.assert_allclose(now[name], want, rtol=0, atol=1e-9 * scale,
                                       err_msg=f"{name} at t = {t}")
    assert rows["eps_vp_eq"].max() == pytest.approx(2 / 3 * (S - SIGMA_Y) / MU_STAR, rel=1e-9)


@pytest.mark.parametrize("command", ["run", "validate"])
def test_a_probe_outside_the_mesh_is_a_located_error(shared_tmp_path, scene_text, capsys,
                                                     command):
    probes = PROBES[:2] + [(2.5, 0.5, 0.5)]
    path = _scene(shared_tmp_path, scene_text, probes=probes)
    out = shared_tmp_path / "outside"
    extra = ["--out", str(out), "--quiet"] if command == "run" else []
    assert cli.main([command, str(path)] + extra) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        line = 1 + path.read_text().splitlines().index(
            "probes = " + json.dumps([list(p) for p in probes]))
        assert re.search(rf"{re.escape(str(path))}:{line}: output\.probes\[2\]: the point "
                         r"\(2\.5, 0\.5, 0\.5\) is outside the mesh", err), err
        assert "Traceback" not in err
    assert not (out / "probes.csv").exists() and not (out / "summary.json").exists()


@pytest.mark.parametrize("probes, message", [
    ("[[1.0, 0.5]]", r"output\.probes\[0\]: expected a point of 3 finite numbers"),
    ('[[1.0, 0.5, "a"]]', r"output\.probes\[0\]: expected a point of 3 finite numbers"),
    ("[1.0, 0.5, 0.5]", r"output\.probes\[0\]: expected a point"),
    ("1.0", r"output\.probes: expected an array of points"),
])
def test_malformed_probes_are_refused_at_their_line(shared_tmp_path, scene_text, capsys,
                                                    probes, message):
    text = scene_text("creeping_bar", discretization="degree = 1", xdmf="false", probes=probes)
    path = write_shared(shared_tmp_path / "bad.toml", text)
    assert cli.main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        line = 1 + text.splitlines().index(f"probes = {probes}")
        assert re.search(rf"bad\.toml:{line}: {message}", err), err


@pytest.mark.parametrize("formulation", sorted(FORMULATIONS))
def test_the_viscoplastic_strain_fields_hold_the_closed_form(shared_tmp_path, scene_text,
                                                             formulation):
    """The DG0 fields the XDMF series writes, after four steps: ε_vp is the closed form in
    every cell (also in the mixed formulation, whose σ_h differs from the kernels' σ_q by a
    mean stress), and its equivalent is the axial component."""
    path = _scene(shared_tmp_path, scene_text, formulation)
    problem = build(scenes.load(path)).problem
    for _ in range(4):
        problem.step(0.25)
    strain = ViscoplasticStrain(CellStress.of(problem), problem.law)
    strain.update()
    flow = (S - SIGMA_Y) / MU_STAR
    tensors = strain.tensor.x.array.reshape(-1, 3, 3)
    want = np.diag([2 / 3 * flow, -flow / 3, -flow / 3])
    assert np.abs(tensors - want).max() <= 1e-9 * flow, np.abs(tensors - want).max()
    np.testing.assert_allclose(strain.equivalent.x.array, 2 / 3 * flow, rtol=1e-9)


def test_the_xdmf_series_carries_the_viscoplastic_strain(shared_tmp_path, scene_text):
    path = _scene(shared_tmp_path, scene_text, xdmf="true")
    out = shared_tmp_path / "xdmf"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    text = (out / "creeping_bar.xdmf").read_text()
    for name in ("viscoplastic_strain", "equivalent_viscoplastic_strain"):
        assert text.count(f'<Attribute Name="{name}"') == 4, name  # at each of the four steps
    h5py = _h5py()  # (without h5py, test_the_viscoplastic_strain_fields_… checks the values)
    if h5py is None or MPI.COMM_WORLD.rank != 0:
        return
    with h5py.File(out / "creeping_bar.h5", "r") as f:
        group = f["Function/equivalent_viscoplastic_strain"]
        last = max(group, key=lambda key: float(key.replace("_", ".")))
        values = np.asarray(group[last]).ravel()
    np.testing.assert_allclose(values, 2 / 3 * (S - SIGMA_Y) / MU_STAR, rtol=1e-9)


def _h5py():
    try:
        import h5py
    except ImportError:
        return None
    return h5py


def test_the_equivalent_strain_is_von_mises_of_the_deviator():
    """√(2/3 dev e : dev e): the uniaxial isochoric strain diag(1, −1/2, −1/2) gives 1, a
    volumetric strain 0, a plane-stress tensor is taken with e33 = 0, a bar's |e|."""
    uniaxial = np.diag([1.0, -0.5, -0.5])[None]
    assert equivalent_strain(uniaxial) == pytest.approx([1.0])
    assert equivalent_strain(np.eye(3)[None] * 0.3) == pytest.approx([0.0], abs=1e-15)
    shear = np.array([[[0.0, 0.1], [0.1, 0.0]]])
    assert equivalent_strain(shear) == pytest.approx([2 * 0.1 / np.sqrt(3)])
    assert equivalent_strain(np.array([[[-0.2]]])) == pytest.approx([0.2])
