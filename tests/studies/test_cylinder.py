# SPDX-License-Identifier: MIT
"""A thick-walled tube under internal pressure (plane strain) against Lamé and Hill
(vpcontact.studies.cylinder): quarter annulus a = 1 ≤ r ≤ b = 2, rollers on x = 0 and y = 0,
traction P(t) x/|x| on r = a.

* Elastic, ν = 0.3, P2 displacements: u_r at r = a and r = b within 1e−6 of Lamé on curved
  (6-node, Gmsh order 2) triangles, and the L2 error converging at rate 3 on them. On straight
  facets (the arcs as polygons) the same P2 field converges at rate 2 only: the domain error of
  the polygon, O(h²), dominates (u_r(a) is 0.1 % low at h = 0.05).
* Elastic, ν = 0.4999, P1 displacements: volumetric locking, u_r(a) 39 % below Lamé at h = 0.1
  (28 % at h = 0.05), where ν = 0.3 is within 0.5 % on the same mesh. Asserted as the known
  failure of P1, as documentation.
* Perzyna (3-D von Mises in plane strain, implicit, μ* small) under pressure raised slowly past
  Hill's P_lim = (2/√3) σ_Y ln(b/a): the computed limit is where the secant compliance du_r(a)/dP
  of a step first exceeds 50 × the elastic one (pressure control, the rate-dependent law carries
  any overload by flowing fast, so nothing fails past the limit; the jump in the slope is
  sharp). Measured brackets (P/P_lim): P1 (1.025, 1.0275] at h = 0.2 and (1.0, 1.0025] at
  h = 0.1; P2 (0.9975, 1.0] at h = 0.2 and (0.995, 0.9975] at h = 0.1. The paper's yield set
  (``"3d"``: 3 s:s ≤ σ_Y², uniaxial radius σ_Y/√2) gives √(2/3) σ_Y ln(b/a) instead.

The same checks run for the mixed (Taylor–Hood u ∈ P2, p ∈ P1) formulation, marked xfail while
:class:`QuasistaticProblem` has no ``formulation`` argument: Lamé at ν = 0.5 and 0.4999 within
1 % at r = a on h = 0.1 with the L2 error at rate 3 on curved cells, no locking at ν = 0.4999, and
Hill's limit within 3 %. Measured: u_r(a) off by 1.1e−6 at h = 0.1 (curved) for both ν, L2 rate
2.95 (curved) and 1.99 (polygons), 0.16 % at ν = 0.4999 on the P1 test's polygonal h = 0.1 mesh;
Hill brackets as P2's, (0.9975, 1.0] at h = 0.2 and (0.995, 0.9975] at h = 0.1.

Rate independence: with E = 1000, σ_Y = 1, μ* = 1e−3 and P = P_lim t the largest overstress
before the limit is 1e−4 σ_Y; μ* = 1e−4 gives the same brackets, μ* = 1e−2 moves P1's at h = 0.1
up by one step (0.25 %).
"""

import math

import numpy as np
import pytest
import ufl
from dolfinx import fem

from vpcontact.model import Elastic, Elasticity, Perzyna, PlaneStrain
from vpcontact.solver import Dirichlet, Loads, QuasistaticProblem, StepControl, advance
from vpcontact.studies import cylinder

A, B = 1.0, 2.0
DISPLACEMENT = pytest.param("displacement", id="displacement")
MIXED = pytest.param("mixed", id="mixed")


def tube_problem(mesh, tags, law, pressure, formulation: str, degree: int):
    """The quarter tube with rollers on its symmetry lines and P(t) x/|x| on r = a; the mixed
    formulation always has u ∈ P2 (``degree`` is passed as 2)."""
    parts = [Dirichlet.symmetry(cylinder.SYMMETRY_X, 2, 0, "x = 0"),
             Dirichlet.symmetry(cylinder.SYMMETRY_Y, 2, 1, "y = 0")]
    loads = Loads(tractions={cylinder.INNER: cylinder.pressure_traction(pressure)})
    # explicit: the default picks "mixed" for Perzyna in plane strain
    problem = QuasistaticProblem(mesh, tags, law, dirichlet=parts, loads=loads,
                                 degree=2 if formulation == "mixed" else degree,
                                 formulation=formulation)
    if formulation == "mixed":
        assert len(problem.fields.functions) == 2, "the mixed problem has no pressure"
    return problem


def mesh(tmp, h: float, order: int = 1):
    """The quarter annulus of size h (order 2: curved 6-node triangles)."""
    path = cylinder.quarter_annulus_msh(tmp / f"annulus_{h}_{order}.msh", A, B, h=h, order=order)
    return cylinder.read_msh(path, 2)


def elastic_solve(tmp, h, order, nu, formulation, degree, P=0.01):
    """The tube loaded by P in one step: (problem, Tube)."""
    tube = cylinder.Tube(A, B, 1.0, nu)
    law = PlaneStrain(Elastic(Elasticity("3d_standard", tube.E, nu)))
    problem = tube_problem(*mesh(tmp, h, order), law, lambda t: P * t, formulation, degree)
    for _ in advance(problem, 1.0, StepControl(1.0)):
        pass
    return problem, tube


def lame_errors(problem, tube, P=0.01):
    """(relative u_r errors at r = a and r = b, relative L2 error of u)."""
    ua = cylinder.mean_radial_displacement(problem.u, A)
    ub = cylinder.mean_radial_displacement(problem.u, B)
    return (ua / tube.radial_displacement(A, P) - 1, ub / tube.radial_displacement(B, P) - 1,
            cylinder.l2_error(problem.u, tube, P))


def rate(h, errors) -> float:
    """Slope of log(error) against log(h)."""
    return float(np.polyfit(np.log(h), np.log(errors), 1)[0])


SIZES = (0.2, 0.1, 0.05, 0.025)


def test_lame_closed_form_at_every_poisson_ratio():
    tube = cylinder.Tube(A, B, 2.0, 0.3)
    sr, st = tube.stresses(np.array([A, B]), 1.0)
    assert np.allclose(sr, [-1.0, 0.0]) and np.allclose(st, [5 / 3, 2 / 3]), (sr, st)
    # u_r = r ε_θθ with the plane-strain ε_θθ = ((1 + ν)/E)((1 − ν)σ_θθ − ν σ_rr), any ν ≤ 0.5
    for nu in (-0.5, 0.0, 0.3, 0.4999, 0.5):
        t = cylinder.Tube(A, B, 2.0, nu)
        r = np.linspace(A, B, 7)
        sr, st = t.stresses(r, 1.0)
        expected = r * (1 + nu) / t.E * ((1 - nu) * st - nu * sr)
        assert np.allclose(t.radial_displacement(r, 1.0), expected, rtol=1e-13), nu
    # ν = 0.5: no volume change, u_r r constant
    u = cylinder.Tube(A, B, 1.0, 0.5).radial_displacement(np.array([A, B]), 1.0)
    assert u[0] * A == pytest.approx(u[1] * B, rel=1e-14)
    with pytest.raises(ValueError):
        cylinder.Tube(A, B, 1.0, 0.51)


def test_yield_radii_of_the_kernels_and_hills_pressure():
    # "3d_standard" (scene yield_set "von_mises", the only set of plane-strain scenes):
    # 3/2 s:s ≤ σ_Y²; "3d" (yield_set "paper", 3-D scenes only): 3 s:s ≤ σ_Y²
    uniaxial, shear = cylinder.yield_radii("3d_standard", 2.0)
    assert (uniaxial, shear) == pytest.approx((2.0, 2.0 / math.sqrt(3))), (uniaxial, shear)
    uniaxial, shear = cylinder.yield_radii("3d", 2.0)
    assert (uniaxial, shear) == pytest.approx((2.0 / math.sqrt(2), 2.0 / math.sqrt(6))), \
        (uniaxial, shear)
    for model in ("3d_standard", "3d"):
        # Hill: σ_θθ − σ_rr = 2k on the whole wall at collapse, k the shear yield stress
        _, k = cylinder.yield_radii(model, 1.0)
        assert cylinder.limit_pressure(A, B, 1.0, model) == pytest.approx(2 * k * math.log(B / A))
    assert cylinder.limit_pressure(1.0, math.e, 1.0) == pytest.approx(2 / math.sqrt(3))


def test_mesh_tags_and_radial_sampling(shared_tmp_path):
    m, tags = mesh(shared_tmp_path, 0.2)
    comm = m.comm
    ds = ufl.Measure("ds", domain=m, subdomain_data=tags)
    one = fem.Constant(m, 1.0)
    lengths = {tag: comm.allreduce(fem.assemble_scalar(fem.form(one * ds(tag))))
               for tag in (cylinder.INNER, cylinder.OUTER, cylinder.SYMMETRY_X,
                           cylinder.SYMMETRY_Y)}
    # polygonal arcs fall short of π/2 r by O(h²)
    assert lengths[cylinder.INNER] == pytest.approx(math.pi / 2 * A, rel=5e-3), lengths
    assert lengths[cylinder.OUTER] == pytest.approx(math.pi / 2 * B, rel=5e-3), lengths
    assert lengths[cylinder.SYMMETRY_X] == pytest.approx(B - A), lengths
    assert lengths[cylinder.SYMMETRY_Y] == pytest.approx(B - A), lengths
    V = fem.VectorFunctionSpace(m, ("Lagrange", 2))
    u = fem.Function(V)
    u.interpolate(lambda x: np.vstack([3 * x[0], 3 * x[1]]))  # u_r = 3r
    theta, ur = cylinder.radial_displacements(u, A)
    assert np.allclose(ur, 3 * A) and theta[0] == pytest.approx(0.0)
    assert theta[-1] == pytest.approx(math.pi / 2) and len(theta) == len(set(theta))
    assert cylinder.mean_radial_displacement(u, B) == pytest.approx(3 * B)


@pytest.mark.parametrize("formulation, nu", [
    pytest.param("displacement", 0.3, id="displacement-nu0.3"),
    pytest.param("mixed", 0.5, id="mixed-nu0.5"),
    pytest.param("mixed", 0.4999, id="mixed-nu0.4999")])
@pytest.mark.slow
def test_elastic_tube_follows_lame_with_p2(shared_tmp_path, formulation, nu):
    curved = [lame_errors(*elastic_solve(shared_tmp_path, h, 2, nu, formulation, 2))
              for h in SIZES]
    straight = [lame_errors(*elastic_solve(shared_tmp_path, h, 1, nu, formulation, 2))
                for h in SIZES]
    ea, eb, _ = curved[-1]
    l2_curved = [abs(e[2]) for e in curved]
    l2_straight = [abs(e[2]) for e in straight]
    report = (f"curved: u_r(a), u_r(b), L2 errors {curved}; straight: {straight}; "
              f"rates curved {rate(SIZES, l2_curved):.3f}, straight {rate(SIZES, l2_straight):.3f}")
    if formulation == "displacement":
        # measured at h = 0.025: 2.0e-7, 7e-10
        assert abs(ea) < 1e-6 and abs(eb) < 1e-6, report
    else:
        assert abs(curved[1][0]) < 0.01, report  # h = 0.1
    # measured (displacement, ν = 0.3): 3.03 on curved cells, 1.99 on polygons
    assert 2.8 < rate(SIZES, l2_curved) < 3.3, report
    assert 1.8 < rate(SIZES, l2_straight) < 2.2, report
    assert l2_curved[-1] < 1e-6 if formulation == "displacement" else l2_curved[-1] < 1e-4, report


@pytest.mark.parametrize("formulation", [DISPLACEMENT, MIXED])
def test_p1_locks_near_incompressibility(shared_tmp_path, formulation):
    """P1 displacements lock at ν = 0.4999 (a known failure, asserted as documentation); the
    mixed formulation does not."""
    problem, tube = elastic_solve(shared_tmp_path, 0.1, 1, 0.4999, formulation, 1)
    ea, eb, l2 = lame_errors(problem, tube)
    if formulation == "displacement":
        compressible = lame_errors(*elastic_solve(shared_tmp_path, 0.1, 1, 0.3, formulation, 1))
        # measured: u_r(a) −38.7 % (ν = 0.4999), −0.46 % (ν = 0.3) at h = 0.1
        assert abs(compressible[0]) < 0.01, compressible
        assert ea < -0.25 and eb < -0.25, f"P1 must lock: u_r(a), u_r(b) off by {ea:.3g}, {eb:.3g}"
    else:
        assert abs(ea) < 0.01 and abs(eb) < 0.01 and l2 < 0.01, (ea, eb, l2)


E_P, SIGMA_Y, MU_STAR = 1000.0, 1.0, 1e-3
#: (end time, step): P(t) = P_lim t, fine steps from 0.97 P_lim on
SEGMENTS = ((0.5, 0.1), (0.9, 0.02), (0.97, 0.01), (1.1, 0.0025))
FACTOR = 50.0  # blow-up: a step's secant compliance above FACTOR × the elastic one


def hill_curve(tmp, h, formulation, degree, model="3d_standard"):
    """Raise P = P_lim t until the curve u_r(a)(P) blows up, then two more steps.

    Returns:
        (P, u_r(a), largest yield ratio √(τ·Yτ)/σ_Y before the blow-up, tube, P_lim).
    """
    tube = cylinder.Tube(A, B, E_P, 0.3)
    p_lim = tube.limit_pressure(SIGMA_Y, model)
    law = PlaneStrain(Perzyna(Elasticity(model, E_P, 0.3), SIGMA_Y, MU_STAR, scheme="implicit"))
    problem = tube_problem(*mesh(tmp, h), law, lambda t: p_lim * t, formulation, degree)
    P, u, ratio, after = [0.0], [0.0], 0.0, None
    for t_end, k in SEGMENTS:
        for step in advance(problem, t_end, StepControl(k)):
            P.append(p_lim * step.time)
            u.append(cylinder.mean_radial_displacement(problem.u, A))
            if after is None and cylinder.limit_bracket(P, u, tube.compliance(), FACTOR):
                after = 0
            if after is None:
                ratio = max(ratio, cylinder.max_yield_ratio(problem))
            elif after == 2:
                return np.array(P), np.array(u), ratio, tube, p_lim
            else:
                after += 1
    return np.array(P), np.array(u), ratio, tube, p_lim


@pytest.mark.parametrize("formulation, degree, model, sizes, band", [
    # measured brackets (P/P_lim): (1.025, 1.0275] at h = 0.2, (1.0, 1.0025] at h = 0.1
    pytest.param("displacement", 1, "3d_standard", (0.2, 0.1), (0.995, 1.04), id="P1"),
    # (0.9975, 1.0] at h = 0.2, (0.995, 0.9975] at h = 0.1
    pytest.param("displacement", 2, "3d_standard", (0.2, 0.1), (0.99, 1.005), id="P2"),
    pytest.param("displacement", 2, "3d", (0.2,), (0.99, 1.005), id="P2-paper-set"),
    pytest.param("mixed", 2, "3d_standard", (0.2, 0.1), (0.97, 1.03), id="mixed",
                 marks=pytest.mark.slow)])
def test_perzyna_tube_reaches_hills_limit(shared_tmp_path, formulation, degree, model, sizes,
                                          band):
    limits = []
    for h in sizes:
        P, u, ratio, tube, p_lim = hill_curve(shared_tmp_path, h, formulation, degree, model)
        bracket = cylinder.limit_bracket(P, u, tube.compliance(), FACTOR)
        curve = (f"h = {h}: P/P_lim {np.round(P[-8:] / p_lim, 4).tolist()}, u_r(a)/(C P_lim) "
                 f"{np.round(u[-8:] / (tube.compliance() * p_lim), 3).tolist()}")
        assert bracket is not None, f"no blow-up up to {P[-1] / p_lim:.3f} P_lim; {curve}"
        low, high = bracket[0] / p_lim, bracket[1] / p_lim
        # the first step (P = 0.1 P_lim) is elastic: Lamé's compliance up to the mesh's error
        assert u[1] / (P[1] * tube.compliance()) == pytest.approx(1.0, abs=0.03), curve
        limits.append(high)
        # rate independence: the viscous overstress stays below 1 % of σ_Y before the limit
        assert ratio < 1.01, f"overstress {ratio - 1:.3g} σ_Y; {curve}"
        assert band[0] <= low and high <= band[1], f"limit in ({low:.4f}, {high:.4f}]; {curve}"
        # beyond it the wall keeps flowing: each further step as compliant
        slopes = np.diff(u[-3:]) / np.diff(P[-3:]) / tube.compliance()
        assert np.all(slopes > FACTOR), f"slopes/C after the limit {slopes}; {curve}"
    if degree == 1:
        assert limits[0] > 1.01 and limits[1] < limits[0], \
            f"P1 overshoots P_lim, less on the finer mesh: {limits}"
