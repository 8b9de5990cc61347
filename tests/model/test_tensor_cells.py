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


def test_point_load_on_hexahedra_is_carried(scene_text, shared_tmp_path):
    """Under one point load, one-point integration left hourglass modes that Newton could not
    resolve (50 iterations, no convergence); an elastic step is one Newton iteration."""
    scene = write_shared(shared_tmp_path / "point_load.toml", scene_text("point_load"))
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["newton_iterations"] == [1]
    assert summary["reactions"]["final"]["bottom"][2] == pytest.approx(1.0, rel=1e-9)


def test_indenter_on_hexahedra_is_felt(scene_text, shared_tmp_path):
    """An ellipsoid pushed 0.01 into a hexahedral block: contact forms, u_ν = g wherever the
    pressure is compressive, and the contact force is balanced by the support. (With one point
    per cell the face's nodes went up and down in a checkerboard and the force stayed zero.)"""
    scene = write_shared(shared_tmp_path / "punch.toml", scene_text("punch"))
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    force = summary["reactions"]["contact_force_final"][2]
    assert force < -0.1
    assert summary["reactions"]["final"]["bottom"][2] == pytest.approx(-force, rel=1e-8)
    rows = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
    last = rows[rows[:, 0] == rows[:, 0].max()]  # t, x, y, z, u_normal, gap, clearance, pressure
    active = last[:, 7] > 1e-8 * np.abs(last[:, 7]).max()
    assert active.sum() >= 1
    np.testing.assert_allclose(last[active, 4], last[active, 5], atol=1e-9)
    assert np.all(last[:, 4] <= last[:, 5] + 1e-9)
