# SPDX-License-Identifier: MIT
"""``[mesh] refine``: boxes of local refinement of a built-in simplex mesh."""

from __future__ import annotations

import numpy as np
import pytest

from vpcontact import scene as scenes
from vpcontact.scene import SceneError, build
from vpcontact.scene.write import dump

BASE = """
name = "graded"
[mesh]
type = "rectangle"
lower = [-1.0, -1.0]
upper = [1.0, 0.0]
cells = [8, 4]
{mesh}
[boundary.bottom]
kind = "clamped"
plane = {{ axis = "y", value = -1.0 }}
[boundary.top]
kind = "traction"
plane = {{ axis = "y", value = 0.0 }}
traction = [0.0, "-t"]
[material]
E = 1000.0
nu = 0.3
plane = "stress"
[law]
type = "elastic"
[time]
T = 1.0
k = 1.0
"""
BOXES = 'refine = [{ lower = [-0.5, -0.5], upper = [0.5, 0.0] }, { lower = [-0.25, -0.25], upper = [0.25, 0.0] }]'


def _vertices(mesh) -> int:
    return mesh.topology.index_map(0).size_global


def _top_facets(built) -> int:
    """The number of facets of the part ``top`` over all ranks."""
    tags = built.facet_tags
    part = built.part_tags["top"]
    owned = built.problem.mesh.topology.index_map(1).size_local
    return built.problem.mesh.comm.allreduce(int(np.sum(tags.indices[tags.values == part] < owned)))


def test_each_box_refines_the_mesh_once_where_it_lies(tmp_path):
    plain = build(scenes.loads_text(BASE.format(mesh=""), tmp_path / "a.toml"))
    graded = build(scenes.loads_text(BASE.format(mesh=BOXES), tmp_path / "b.toml"))
    assert _vertices(graded.problem.mesh) > _vertices(plain.problem.mesh)
    # the top edge inside the inner box (|x| <= 0.25) is split twice, within the outer box once
    assert _top_facets(plain) == 8
    assert _top_facets(graded) == 8 + 4 + 4


def test_refine_round_trips_through_the_resolved_scene(tmp_path):
    scene = scenes.loads_text(BASE.format(mesh=BOXES), tmp_path / "b.toml")
    again = scenes.loads_text(dump(scene), tmp_path / "c.toml")
    assert again.mesh.refine == scene.mesh.refine == (((-0.5, -0.5), (0.5, 0.0)),
                                                      ((-0.25, -0.25), (0.25, 0.0)))


@pytest.mark.parametrize("mesh, where, message", [
    ('cell_type = "quadrilateral"\n' + BOXES, "mesh.refine", "triangle or tetrahedron"),
    ('refine = [{ lower = [0.5, -0.5], upper = [0.0, 0.0] }]', "mesh.refine[0].upper",
     "must exceed lower"),
    ('refine = [{ lower = [0.0, -0.5] }]', "mesh.refine[0].upper", ""),
    ('refine = [{ lower = [0.0, -0.5], upper = [1.0, 0.0], size = 2 }]', "mesh.refine[0].size", ""),
    ('refine = { lower = [0.0, -0.5], upper = [1.0, 0.0] }', "mesh.refine", "array of tables"),
    ('refine = [' + ", ".join(['{ lower = [-1.0, -1.0], upper = [1.0, 0.0] }'] * 8) + ']',
     "mesh.refine", "too many cells"),
])
def test_bad_refinement_boxes_are_located(tmp_path, mesh, where, message):
    text = BASE.format(mesh=mesh).replace("cells = [8, 4]", "cells = [400, 200]")
    with pytest.raises(SceneError) as err:
        scenes.loads_text(text, tmp_path / "bad.toml")
    assert where in str(err.value) and message in str(err.value)
