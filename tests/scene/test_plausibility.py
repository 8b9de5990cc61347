# SPDX-License-Identifier: MIT
"""Warnings for data a small-strain model cannot mean (:mod:`vpcontact.scene.plausibility`):
returned as located problems, not raised; the command line prints them at ``validate`` and
``run`` (``tests/output/test_overrides.py``).

Pure Python (no dolfinx): passes serially and under ``mpirun -n 2``.
"""

import math

import pytest

from vpcontact.scene import bundled, load, loads_text
from vpcontact.scene.plausibility import warnings

from tests.support.scenes import scene_text

BASE = scene_text("base")  # unit square, E = 1e8, elastic, normal compliance mu = 100


def _line(text: str, start: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if line.startswith(start))


def _warned(text: str, **kw):
    return warnings(loads_text(text, "scene.toml"), **kw)


def _perzyna(young: float, sigma_y: float) -> str:
    text = BASE.replace("E = 1e8", f"E = {young!r}").replace("mu = 100.0", "mu = 1e-9")
    return text + f"[law]\ntype = \"perzyna\"\nsigma_y = {sigma_y!r}\nmu_star = 1.0\n"


def test_mixed_units_give_a_yield_strain_of_1190_located_at_sigma_y():
    """Steel with E in MPa and σ_Y in Pa."""
    text = _perzyna(210e3, 250e6)
    (found,) = _warned(text)
    assert (found.path, found.line) == ("law.sigma_y", _line(text, "sigma_y"))
    assert "sigma_y/E = 2.5e+08/210000 = 1.19e+03" in found.message
    assert found.format("scene.toml").startswith(f"scene.toml:{found.line}: law.sigma_y: ")
    assert _warned(_perzyna(210e3, 250.0)) == ()  # both in MPa: 0.12 %
    assert _warned(_perzyna(1000.0, 50.0)) == ()  # 5 %: the limit itself is not warned
    assert _warned(_perzyna(1000.0, 51.0))


def test_a_foundation_too_soft_to_carry_the_working_pressure():
    """Elastic law: working pressure E·1e-3 = 1e5; μ = 100 needs a penetration of 1e7 in a
    unit square (μ read as a friction coefficient, say); μ = 1e-2 needs 1e3, 1e3 times the
    body's size: the limit, not warned."""
    (found,) = _warned(BASE)
    assert (found.path, found.line) == ("contact.mu", _line(BASE, "mu = "))
    assert "the penetration (mu p)^(1/alpha) = 1e+07" in found.message
    assert "not a friction coefficient" in found.message and "1e+07 times the body's size 1" \
        in found.message
    assert _warned(BASE.replace("mu = 100.0", "mu = 1e-2")) == ()
    assert _warned(BASE.replace("mu = 100.0", "mu = 1.01e-2"))
    # α < 1: δ = (μ p)^(1/α) = (1e-3·1e5)^2 = 1e4
    (found,) = _warned(BASE.replace("mu = 100.0", "mu = 1e-3\nalpha = 0.5"))
    assert "= 1e+04" in found.message


def test_a_foundation_stiffer_than_the_coordinates_can_resolve():
    """Perzyna's law: working pressure σ_Y; μ σ_Y below 2.2e-16 × the body's size."""
    text = _perzyna(1e8, math.sqrt(10.0)).replace("mu = 1e-9", "mu = 1e-17")
    (found,) = _warned(text)
    assert found.path == "contact.mu" and "below the round-off of the coordinates" in found.message
    assert _warned(text.replace("mu = 1e-17", "mu = 1e-16")) == ()  # 3.2e-16 > 2.2e-16


def test_the_body_size_of_a_gmsh_mesh_comes_from_the_caller():
    scene = loads_text(BASE, "scene.toml")
    assert len(warnings(scene, extent=1e8)) == 0 and len(warnings(scene, extent=1.0)) == 1


def test_each_part_of_an_array_is_located_at_its_own_table():
    text = scene_text("held_on_a_compliant_face").replace("mu = 0.001", "mu = 1e6")
    (found,) = _warned(text)
    assert (found.path, found.line) == ("contact[1].mu", _line(text, "mu = 1e6"))


def test_more_than_ten_thousand_steps():
    text = BASE.replace("mu = 100.0", "mu = 1e-6").replace("k = 0.1", "k = 1e-4")
    assert _warned(text) == ()  # 10 000 steps
    (found,) = _warned(text.replace("k = 1e-4", "k = 9.9e-5"))
    assert (found.path, found.line) == ("time.k", _line(text, "k = "))
    assert "10102 steps, more than 10000" in found.message


def test_overridden_keys_are_warned_at_their_override():
    scene = loads_text(BASE, "scene.toml", overrides=["contact.mu=1e3"])
    (found,) = warnings(scene)
    assert found.format("scene.toml").startswith("--set contact.mu: mu = 1000 is the "
                                                 "foundation's compliance")


@pytest.mark.parametrize("name", sorted(bundled()))
def test_bundled_scenes(name):
    """No bundled scene is warned. The paper's §4.2.2 foundation (μ = 100 under a block of
    E = 1e8, σ_Y = √10) carries σ_Y only after sinking 316, 53 times the block's size (in the
    paper's test it carries 0.0041 of the load 10 at T): soft on purpose, below SOFT_FACTOR."""
    assert warnings(load(bundled()[name])) == ()
