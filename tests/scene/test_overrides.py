# SPDX-License-Identifier: MIT
"""Command-line overrides of scene keys (``--set KEY=VALUE``, :mod:`vpcontact.scene.overrides`):
any key, its value read as TOML (a bare word as a string), checked like the file's own keys and
located at the override.

Pure Python (no dolfinx): passes serially and under ``mpirun -n 2``.
"""

import pytest

from vpcontact.scene import SceneError, loads_text
from vpcontact.scene.overrides import Override, parse

from tests.support.scenes import scene_text

BASE = scene_text("base")            # 2-D, normal compliance, no [law]
HELD = scene_text("held_on_a_compliant_face")   # [[contact]] × 2


def _scene(*overrides, text=BASE):
    return loads_text(text, "scene.toml", overrides=overrides)


def _refused(*overrides, text=BASE) -> SceneError:
    with pytest.raises(SceneError) as info:
        _scene(*overrides, text=text)
    return info.value


@pytest.mark.parametrize("given, path, value", [
    ("time.k=0.01", "time.k", 0.01),
    ("mesh.cells=[32,16]", "mesh.cells", [32, 16]),
    ("material.plane=strain", "material.plane", "strain"),
    ('material.plane="strain"', "material.plane", "strain"),
    ("law.sigma_y=sqrt(10)", "law.sigma_y", "sqrt(10)"),
    ("output.figures=false", "output.figures", False),
    ("contact[1].friction={ type = 'coulomb', coefficient = 0.5 }", "contact[1].friction",
     {"type": "coulomb", "coefficient": 0.5}),
    (' boundary."top".plane.value = 1.0 ', "boundary.top.plane.value", 1.0),
])
def test_values_are_toml_and_bare_words_strings(given, path, value):
    assert parse(given) == Override(path, value)


def test_overrides_set_the_file_s_keys_and_create_tables():
    scene = _scene("time.k=0.01", "mesh.cells=[8, 2]", "material.plane=strain",
                   'law.type="perzyna"', "law.sigma_y=5", "law.mu_star=50")
    assert scene.time.k == 0.01 and scene.mesh.cells == (8, 2)
    assert scene.material.plane == "strain"  # over the file's plane = "stress"
    assert scene.law.type == "perzyna" and scene.law.mu_star.value() == 50.0  # no [law] in file
    assert scene.overrides == {"time.k": 0.01, "mesh.cells": [8, 2], "material.plane": "strain",
                               "law.type": "perzyna", "law.sigma_y": 5, "law.mu_star": 50}
    assert scene == loads_text(BASE.replace("k = 0.1", "k = 0.01")
                               .replace("cells = [4, 4]", "cells = [8, 2]")
                               .replace('plane = "stress"', 'plane = "strain"')
                               + '[law]\ntype = "perzyna"\nsigma_y = 5\nmu_star = 50\n')


def test_array_items_and_the_last_override_of_a_key_wins():
    scene = _scene("contact[1].mu=5e-4", "contact[1].mu=2e-4", "initial.u0=[0.0, 1e-3]",
                   "initial.u0[0]=2e-3", text=HELD)
    assert scene.contacts[1].mu == 2e-4 and scene.overrides["contact[1].mu"] == 2e-4
    assert [e.value() for e in scene.initial.u0] == [2e-3, 1e-3]


def test_an_unknown_key_is_located_at_its_override_with_a_suggestion():
    err = _refused("law.mu_sta=50", 'law.type="perzyna"', "law.sigma_y=1", "law.mu_star=5")
    assert str(err) == "--set law.mu_sta: unknown key 'mu_sta'; did you mean 'mu_star'?"
    (problem,) = err.problems
    assert (problem.path, problem.line, problem.origin) == ("law.mu_sta", None, "law.mu_sta")


@pytest.mark.parametrize("given, expected", [
    ("time.k=-1", "--set time.k: must be > 0, got -1"),
    ("time.k=fast", "--set time.k: expected a number, got a string ('fast')"),
    ("mesh.cells=[4, 0]", "--set mesh.cells: mesh.cells[1]: must be > 0, got 0"),
    ("material.plane=flat", "--set material.plane: must be one of 'stress', 'strain'; got 'flat'"),
    ("tiem.k=1", "--set tiem.k: tiem: unknown key 'tiem'; did you mean 'time'?"),
    ("time.k.x=1", "--set time.k.x: time.k is a number, not a table"),
    ("contact.mu=1", "--set contact.mu: contact is an array, not a table (name an item, e.g. "
                     "contact[0].mu)"),
    ("contact[2].mu=1", "--set contact[2].mu: contact has 2 item(s): no item [2]"),
    ("time.k", "--set time.k: takes KEY=VALUE with KEY a scene key such as time.k"),
    ("time..k=1", "--set time..k=1: 'time..k' is not a key path"),
])
def test_bad_overrides_are_located_at_the_override(given, expected):
    err = _refused(given, text=HELD)
    assert str(err).startswith(expected), str(err)


def test_the_missing_keys_of_a_table_an_override_created_are_located_at_it():
    err = _refused('law.type="perzyna"')  # the file has no [law]
    assert "--set law.type: law.sigma_y: missing required key 'sigma_y'" in str(err), str(err)
    assert "--set law.type: law.mu_star: missing required key 'mu_star'" in str(err), str(err)


def test_a_problem_the_file_causes_stays_at_the_file_s_line():
    """An override that is fine itself, with a key of the file it conflicts with: the file's
    key is located at its line."""
    err = _refused("contact[1].type=signorini", text=HELD)
    lines = HELD.splitlines()
    mu_line = next(i for i, line in enumerate(lines, 1) if line.startswith("mu = 0.001"))
    assert f"scene.toml:{mu_line}: contact[1].mu: not allowed" in str(err), str(err)


def test_errors_found_after_reading_are_located_at_the_override():
    scene = _scene("time.k=0.5")
    assert scene.where("time.k") == "--set time.k"
    assert scene.where("time.T") == f"scene.toml:{BASE.splitlines().index('T = 1.0') + 1}"
    assert str(scene.error("time.k", "too large")) == "--set time.k: too large"


def test_the_hash_covers_the_overrides():
    plain, same, other = _scene(), _scene("time.k=0.1"), _scene("time.k=0.05")
    assert plain == same and plain.hash != same.hash and same.hash != other.hash
    assert same.hash == _scene("time.k=0.1").hash


def test_show_writes_the_overrides_and_reads_back_equal():
    scene = _scene("time.k=0.05", "material.plane=strain")
    shown = scene.to_toml()
    assert "# with --set time.k=0.05 --set material.plane=\"strain\"" in shown.splitlines()
    assert loads_text(shown) == scene
