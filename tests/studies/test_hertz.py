# SPDX-License-Identifier: MIT
"""Signorini on curved contact faces against Hertz's closed forms (vpcontact.studies.hertz).

* 2-D, plane strain: the quarter of an elastic cylinder (R = 1, E = 1, ν = 0.3; Gmsh mesh refined
  near the contact) pressed onto a rigid plane by a prescribed displacement of its centre line,
  symmetry line x = 0. With P the measured force per unit length: peak nodal pressure within 3 %
  of p0 = 2P/(πa), contact half-width within one contact-facet length of a = √(4PR/(πE*)), the
  pressure profile's relative L2 error over |x| < a below 5 % and falling under refinement.
* 3-D: the quarter of an elastic sphere on a rigid plane (symmetry planes as rollers): contact
  radius and the fitted peak of the pressure profile within 5 % of Hertz's a and p0 for the
  measured force.
* An indenter driven by displacement: a rigid sphere moved into a quarter block by δ(t); at every
  step the contact radius follows Hertz for the measured force within 5 %.
"""

import numpy as np
import pytest

from vpcontact.model import Elastic, Elasticity, PlaneStrain, Signorini
from vpcontact.solver import Dirichlet, QuasistaticProblem, StepControl, advance, tag_facets
from vpcontact.studies import hertz

E, NU = 1.0, 0.3
E_STAR = E / (1 - NU ** 2)


def pushed(value, axis: int, dim: int):
    """Components of a prescribed displacement: ``value`` · t on ``axis``, the others free."""
    return tuple((lambda x, t: value * t * np.ones(x.shape[1])) if i == axis else None
                 for i in range(dim))


@pytest.mark.slow
def test_cylinder_on_a_plane_follows_hertz(shared_tmp_path):
    results = []
    for h in (0.01, 0.005, 0.0025):
        path = hertz.cylinder_msh(shared_tmp_path / f"cylinder_{h}.msh", h_contact=h)
        mesh, tags = hertz.read_msh(path, 2)
        parts = [Dirichlet.symmetry(hertz.SYMMETRY_X, 2, 0, "axis"),
                 Dirichlet(hertz.TOP, pushed(-0.005, 1, 2), "top")]
        problem = QuasistaticProblem(
            mesh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", E, NU))),
            dirichlet=parts,
            contact=Signorini(hertz.CONTACT, obstacle=lambda x: x[1], max_distance=10.0))
        for _ in advance(problem, 1.0, StepControl(1.0)):
            pass
        p = hertz.profile(problem, np.zeros(3))
        a, p0 = hertz.cylinder_2d(2 * p.force, 1.0, E_STAR)  # both halves carry P
        results.append((h, a, p0, p, hertz.l2_error(p, a, p0)))
    h, a, p0, p, _ = results[-1]
    assert 0.02 < a < 0.08, f"a/R = {a:.3g}: the contact must be small but resolved"
    assert abs(p.pressure.max() / p0 - 1) < 0.03, (p.pressure.max(), p0)
    assert abs(p.half_width - a) <= p.facet, (p.half_width, a, p.facet)
    errors = [r[-1] for r in results]
    assert max(errors) < 0.05, errors
    assert errors[-1] < errors[0], f"the L2 error must fall under refinement: {errors}"


@pytest.mark.slow
def test_sphere_on_a_plane_follows_hertz(shared_tmp_path):
    path = hertz.sphere_msh(shared_tmp_path / "sphere.msh", h_contact=0.02)
    mesh, tags = hertz.read_msh(path, 3)
    parts = [Dirichlet.symmetry(hertz.SYMMETRY_X, 3, 0, "x = 0"),
             Dirichlet.symmetry(hertz.SYMMETRY_Y, 3, 1, "y = 0"),
             Dirichlet(hertz.TOP, pushed(-0.01, 2, 3), "top")]
    problem = QuasistaticProblem(
        mesh, tags, Elastic(Elasticity("3d_standard", E, NU)), dirichlet=parts,
        contact=Signorini(hertz.CONTACT, obstacle=lambda x: x[2], max_distance=10.0))
    assert problem.contact_dofs.rotated
    for _ in advance(problem, 1.0, StepControl(1.0)):
        pass
    p = hertz.profile(problem, np.zeros(3))
    a, p0 = hertz.sphere_3d(4 * p.force, 1.0, E_STAR)  # the quarter carries P/4
    p0_fit, _ = hertz.fit_profile(p, a)
    assert 0.05 < a < 0.2
    assert abs(p.half_width / a - 1) < 0.05, (p.half_width, a)
    assert abs(p0_fit / p0 - 1) < 0.05, (p0_fit, p0)


@pytest.mark.slow
def test_sphere_indenter_driven_by_displacement_follows_hertz(shared_tmp_path):
    R, depth = 0.5, 0.01
    mesh, _ = hertz.read_msh(hertz.block_msh(shared_tmp_path / "block.msh", h_contact=0.01), 3)
    tags = tag_facets(mesh, {
        1: lambda x: np.isclose(x[2], -1.0), 2: lambda x: np.isclose(x[0], 0.0),
        3: lambda x: np.isclose(x[1], 0.0),
        4: lambda x: np.isclose(x[2], 0.0) & (x[0] ** 2 + x[1] ** 2 <= 0.3 ** 2 + 1e-12)})
    parts = [Dirichlet.clamped(1, 3, "bottom"), Dirichlet.symmetry(2, 3, 0, "x = 0"),
             Dirichlet.symmetry(3, 3, 1, "y = 0")]
    sphere = Signorini(4, obstacle=lambda x: np.linalg.norm(x - np.array([[0.0], [0.0], [R]]),
                                                            axis=0) - R,
                       max_distance=10.0, translation=lambda t: np.array([0.0, 0.0, -depth * t]))
    problem = QuasistaticProblem(mesh, tags, Elastic(Elasticity("3d_standard", E, NU)),
                                 dirichlet=parts, contact=sphere)
    forces = []
    for step in advance(problem, 1.0, StepControl(0.25)):
        p = hertz.profile(problem, np.zeros(3))
        a, _ = hertz.sphere_3d(4 * p.force, R, E_STAR)
        assert abs(p.half_width / a - 1) < 0.05, (step.time, p.half_width, a)
        forces.append(4 * p.force)
        assert problem.driving_displacement() == pytest.approx(-depth * step.time)  # signed
    assert np.all(np.diff(forces) > 0)
    # The clamped block of depth 2R is stiffer than Hertz's half-space: more force, same depth.
    assert 1.0 < forces[-1] / hertz.sphere_force(depth, R, E_STAR) < 1.15
