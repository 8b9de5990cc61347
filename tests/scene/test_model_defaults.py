# SPDX-License-Identifier: MIT
"""Defaults that decide the model do not change meaning with the dimension, and are never taken
silently (issue 45).

* The yield set is von Mises by default in every dimension: a 3-D Perzyna scene that does not
  name it got the paper's printed set (uniaxial yield stress σ_Y/√2), where 2-D got von Mises.
* 2-D scenes are plane strain unless they say ``plane = "stress"`` (the mixed P2–P1 formulation
  with Perzyna's law).
* A Signorini part with neither a gap nor an obstacle is refused at its table.
* ``show`` writes the model taken (law, yield set, plane, formulation), marking defaults, and
  says what ``mu`` is: the foundation's compliance, not a friction coefficient.

Pure Python (no dolfinx): passes serially and under ``mpirun -n 2``.
"""

import re
import tomllib

import pytest

from vpcontact.scene import SceneError, bundled, keys, load, loads_text
from vpcontact.scene.describe import choices

from tests.support.scenes import scene_text

BAR_3D = scene_text("relaxing_bar_3d", yield_set="")
BASE = scene_text("base")  # 2-D, plane = "stress", normal compliance


def _without_plane(text: str) -> str:
    assert 'plane = "stress"\n' in text
    return text.replace('plane = "stress"\n', "")


PERZYNA = '[law]\ntype = "perzyna"\nsigma_y = 1.0\nmu_star = 1.0\n'


def test_a_3d_perzyna_scene_without_yield_set_is_von_mises():
    """The same scene as with yield_set = "von_mises" written out (Scene equality compares the
    whole resolved problem), not the paper's set."""
    implicit = loads_text(BAR_3D)
    explicit = loads_text(scene_text("relaxing_bar_3d", yield_set='yield_set = "von_mises"'))
    paper = loads_text(scene_text("relaxing_bar_3d", yield_set='yield_set = "paper"'))
    assert implicit.law.yield_set == "von_mises"
    assert implicit == explicit and implicit != paper


def test_a_2d_scene_without_plane_is_plane_strain_and_perzyna_runs_mixed():
    elastic = loads_text(_without_plane(BASE))
    assert elastic.material.plane == "strain"
    assert elastic == loads_text(BASE.replace('plane = "stress"', 'plane = "strain"'))
    perzyna = loads_text(_without_plane(BASE) + PERZYNA)
    assert (perzyna.material.plane, perzyna.formulation, perzyna.degree) == ("strain", "mixed", 2)
    stress = loads_text(BASE + PERZYNA)
    assert (stress.formulation, stress.degree) == ("displacement", 1)


def test_the_registry_states_the_rules():
    """The key reference (generated from the registry) gives the defaults the reader uses."""
    assert keys.default("material", "plane") == "strain"
    assert keys.default("law", "yield_set") == "von_mises"
    assert "plane strain (the default" in keys.entry("material", "plane").description
    assert "in every dimension" in keys.entry("law", "yield_set").description
    mu = keys.entry("contact", "mu").description
    assert "compliance" in mu and "not a friction coefficient" in mu
    page = keys.reference_markdown()
    assert "not a friction coefficient" in page and "in every dimension" in page


@pytest.mark.parametrize("name", sorted(bundled()))
def test_bundled_scenes_name_the_choices_their_answers_depend_on(name):
    """Every bundled 3-D Perzyna scene names its yield set and every 2-D scene its plane, so
    that no bundled answer depends on those defaults."""
    scene = load(bundled()[name])
    assert "law.yield_set" not in scene.defaulted
    assert "material.plane" not in scene.defaulted


def test_a_signorini_part_with_neither_gap_nor_obstacle_is_refused_at_its_table():
    text = BASE.replace('type = "normal_compliance"\nboundary = "bottom"\nmu = 100.0',
                        'type = "signorini"\nboundary = "bottom"')
    with pytest.raises(SceneError, match=r"contact: a Signorini part needs a gap or an "
                                         r"obstacle") as info:
        loads_text(text, "scene.toml")
    (problem,) = info.value.problems
    assert problem.path == "contact"
    assert problem.line == text.splitlines().index("[contact]") + 1
    assert str(info.value).startswith(f"scene.toml:{problem.line}: contact: ")
    # gap = 0 written out is the rigid foundation touching the face at the start
    assert loads_text(text.replace('boundary = "bottom"\n', 'boundary = "bottom"\ngap = 0\n',
                                   1)).contact.gap.value() == 0.0


def test_a_signorini_part_of_an_array_is_refused_at_its_own_table():
    text = scene_text("held_on_a_compliant_face").replace(
        'obstacle = { shape = "plane", point = [0.0, 1.01], normal = [0.0, -1.0] }\n'
        'motion = [0.0, "-0.03*t"]\n', "")
    with pytest.raises(SceneError, match=r"contact\[0\]: a Signorini part needs") as info:
        loads_text(text, "scene.toml")
    assert info.value.problems[0].line == text.splitlines().index("[[contact]]") + 1


def test_choices_mark_what_came_from_defaults():
    text = _without_plane(BASE) + PERZYNA
    assert choices(loads_text(text)) == ("law perzyna (yield set von_mises, default), "
                                         "plane strain (default), mixed P2–P1 (default)")
    given = (BASE + PERZYNA + 'yield_set = "von_mises"\n[discretization]\n'
             'formulation = "displacement"\n')
    assert choices(loads_text(given)) == ("law perzyna (yield set von_mises), plane stress, "
                                          "displacement P1")
    assert choices(loads_text(scene_text("bar"))) == "law elastic (default), displacement P1 (default)"
    assert choices(loads_text(BAR_3D)) == (  # degree = 1: "auto" chose P1 displacements
        "law perzyna (yield set von_mises, default), displacement P1 (default)")


def test_show_writes_the_model_taken_and_what_mu_is():
    text = _without_plane(BASE) + PERZYNA
    shown = loads_text(text).to_toml()
    lines = shown.splitlines()
    assert lines[1] == ("# law perzyna (yield set von_mises, default), plane strain (default), "
                        "mixed P2–P1 (default)")
    assert 'plane = "strain"  # default' in lines
    assert 'yield_set = "von_mises"  # default' in lines
    assert any(re.fullmatch(r'formulation = "mixed"  # default: "auto" chose it', line)
               for line in lines)
    assert "mu = 100.0  # the foundation's compliance (1/stiffness), not a friction coefficient" \
        in lines
    # the comments do not change what it reads back as
    again = loads_text(shown)
    assert again == loads_text(text) and tomllib.loads(shown)["contact"]["mu"] == 100.0
    assert again.defaulted == frozenset()  # everything is written out now
