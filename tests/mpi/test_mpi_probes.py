# SPDX-License-Identifier: MIT
"""`mpirun -n 2` writes the serial probes.csv: each probe is evaluated by one rank (the one
owning the colliding cell that every partition picks alike) and gathered on rank 0, launched
from the tests."""

import json

import numpy as np
import pytest

from vpcontact import cli

from tests.mpi.test_mpi_history import _CLI, _two_rank_run
from tests.output.test_probes import PROBES, exact
from tests.support.mpi_launch import clean_environment
from tests.support.scenes import scene_text

pytestmark = [pytest.mark.serial, pytest.mark.mpi]

#: the probes of tests/output/test_probes.py and points on the faces, edges and vertices
#: shared by cells (that several cells, on several ranks, collide with)
POINTS = PROBES + [(1.0, 0.5, 1.0), (0.5, 0.0, 0.5), (1.5, 1.0, 0.0), (0.0, 0.0, 0.0)]


@pytest.mark.parametrize("formulation", ["degree = 1", 'formulation = "mixed"'])
def test_two_ranks_write_the_serial_probes(tmp_path, formulation):
    text = scene_text("creeping_bar", discretization=formulation, xdmf="false",
                      probes=json.dumps([list(p) for p in POINTS]))
    scene = tmp_path / "bar.toml"
    scene.write_text(text)
    rows = {}
    for ranks in (1, 2):
        out = tmp_path / f"out{ranks}"
        arguments = ["run", str(scene), "--out", str(out), "--quiet"]
        if ranks == 1:
            assert cli.main(arguments) == 0
        else:
            _two_rank_run(tmp_path, _CLI, arguments, clean_environment())
        rows[ranks] = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    serial, parallel = rows[1], rows[2]
    assert serial.dtype.names == parallel.dtype.names and serial.shape == parallel.shape
    assert not any(np.isnan(parallel[name]).any() for name in parallel.dtype.names)
    for name in serial.dtype.names:  # (to the size of the quantity: shears are round-off)
        group = [n for n in serial.dtype.names if n.split("_")[0] == name.split("_")[0]]
        scale = max(np.abs(serial[n]).max() for n in group)
        np.testing.assert_allclose(parallel[name], serial[name], rtol=0, atol=1e-10 * scale,
                                   err_msg=name)
    last = parallel[np.isclose(parallel["t"], 1.0)]
    x = np.stack([last["x"], last["y"], last["z"]], axis=1)
    for name, want in exact(x, 1.0).items():
        np.testing.assert_allclose(last[name], want, rtol=0, atol=1e-9 * 3.0, err_msg=name)
