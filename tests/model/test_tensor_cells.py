# SPDX-License-Identifier: MIT
"""Quadrilateral and hexahedral cells: the stress rule integrates ε(u):ε(v) exactly, so a Q1
cell's stiffness has no zero-energy (hourglass) modes beyond the rigid motions, and runs on these
cells give the answers their physics says (a point load is carried, an obstacle is felt)."""

import json

import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh as dmesh
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI

from vpcontact import cli
from vpcontact.model.tensors import strain
from vpcontact.solver import stress_quadrature_degree

from tests.support.mpi_launch import write_shared


def _one_cell(cell: str):
    if cell == "quadrilateral":
        return dmesh.create_unit_square(MPI.COMM_SELF, 1, 1, dmesh.CellType.quadrilateral)
    return dmesh.create_unit_cube(MPI.COMM_SELF, 1, 1, 1, dmesh.CellType.hexahedron)


def _zero_modes(msh, quadrature_degree: int) -> int:
    """Number of zero eigenvalues of the elastic stiffness of the mesh's one cell."""
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    lam, mu = 0.6, 0.4
    dx = ufl.dx(metadata={"quadrature_degree": quadrature_degree})
    a = (lam * ufl.div(u) * ufl.div(v) + 2 * mu * ufl.inner(strain(u), strain(v))) * dx
    A = fem.petsc.assemble_matrix(fem.form(a))
    A.assemble()
    eigenvalues = np.linalg.eigvalsh(A.convert("dense").getDenseArray())
    return int(np.sum(np.abs(eigenvalues) < 1e-10 * np.abs(eigenvalues).max()))


@pytest.mark.parametrize("cell, rigid", [("quadrilateral", 3), ("hexahedron", 6)])
def test_q1_stiffness_has_only_the_rigid_modes(cell, rigid):
    msh = _one_cell(cell)
    assert _zero_modes(msh, stress_quadrature_degree(msh, 1)) == rigid
    assert _zero_modes(msh, 1) > rigid  # one point per cell: hourglass modes (the test bites)


POINT_LOAD = """\
name = "point_load"

[mesh]
type = "box"
lower = [0.0, 0.0, 0.0]
upper = [1.0, 1.0, 1.0]
cells = [4, 4, 4]
cell_type = "hexahedron"

[boundary.bottom]
kind = "clamped"
plane = { axis = "z", value = 0.0 }

[[loads.point]]
at = [0.5, 0.5, 1.0]
force = [0.0, 0.0, "-1.0*t"]

[material]
E = 1000.0
nu = 0.3

[time]
T = 1.0
k = 1.0

[output]
figures = false
"""

PUNCH = """\
name = "punch"

[mesh]
type = "box"
lower = [-0.5, -0.5, -1.0]
upper = [0.5, 0.5, 0.0]
cells = [8, 8, 4]
cell_type = "hexahedron"

[boundary.bottom]
kind = "clamped"
plane = { axis = "z", value = -1.0 }

[boundary.top]
kind = "contact"
where = "x[2] > -1e-9 and abs(x[0]) < 0.2 and abs(x[1]) < 0.13"

[material]
E = 1000.0
nu = 0.3

[contact]
type = "signorini"
boundary = "top"
obstacle = { shape = "ellipsoid", center = [0.0, 0.0, 0.25], semi_axes = [0.3, 0.2, 0.22] }
motion = [0, 0, "-0.04*min(t/0.5, 1)"]

[time]
T = 1.0
k = 0.25

[output]
figures = false
"""


def test_point_load_on_hexahedra_is_carried(shared_tmp_path):
    """Under one point load, one-point integration left hourglass modes that Newton could not
    resolve (50 iterations, no convergence); an elastic step is one Newton iteration."""
    scene = write_shared(shared_tmp_path / "point_load.toml", POINT_LOAD)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["newton_iterations"] == [1]
    assert summary["reactions"]["final"]["bottom"][2] == pytest.approx(1.0, rel=1e-9)


def test_indenter_on_hexahedra_is_felt(shared_tmp_path):
    """An ellipsoid pushed 0.01 into a hexahedral block: contact forms, u_ν = g wherever the
    pressure is compressive, and the contact force is balanced by the support. (With one point
    per cell the face's nodes went up and down in a checkerboard and the force stayed zero.)"""
    scene = write_shared(shared_tmp_path / "punch.toml", PUNCH)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    force = summary["reactions"]["contact_force_final"][2]
    assert force < -0.1
    assert summary["reactions"]["final"]["bottom"][2] == pytest.approx(-force, rel=1e-8)
    rows = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
    last = rows[rows[:, 0] == rows[:, 0].max()]  # t, x, y, z, u_normal, gap, clearance, pressure
    active = last[:, 7] < -1e-8 * np.abs(last[:, 7]).max()
    assert active.sum() >= 1
    np.testing.assert_allclose(last[active, 4], last[active, 5], atol=1e-9)
    assert np.all(last[:, 4] <= last[:, 5] + 1e-9)
