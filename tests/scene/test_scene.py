# SPDX-License-Identifier: MIT
"""Scene files: bundled scenes, defaults, round trips, and located errors for invalid input.

Pure Python (no dolfinx): every rank runs the same checks on its own, so the file passes serially
and under ``mpirun -n 2``.
"""

import hashlib
import math
import re

import numpy as np
import pytest

from vpcontact import scene as sc
from vpcontact.scene import DEFAULT_SCENE, SceneError, bundled, load, loads_text, resolve

from tests.support.scenes import scene_text

BASE = scene_text("base")

NO_CONTACT = scene_text("no_contact")

BAR = scene_text("bar")


def edit(text: str, old: str, new: str) -> str:
    """``text`` with ``old`` (which must occur) replaced by ``new``."""
    if old not in text:
        raise KeyError(old)
    return text.replace(old, new, 1)


def line_of(text: str, snippet: str, nth: int = 1) -> int:
    """1-based line of the ``nth`` line containing ``snippet``."""
    hits = [i + 1 for i, line in enumerate(text.splitlines()) if snippet in line]
    return hits[nth - 1]


def problems(text: str, match: str) -> SceneError:
    """Load ``text`` expecting a SceneError whose message matches ``match``."""
    with pytest.raises(SceneError, match=match) as info:
        loads_text(text, "scene.toml")
    return info.value


def problem_at(err: SceneError, needle: str):
    """The (first) problem whose message or path contains ``needle``."""
    for p in err.problems:
        if needle in p.message or needle in p.path:
            return p
    raise AssertionError(f"no problem mentions {needle!r} in:\n{err}")


# -- bundled scenes ---------------------------------------------------------------------------

EXPECTED = {"elastic_2d", "indentation_relaxation", "normal_compliance_1d", "normal_compliance_2d", "normal_compliance_3d",
            "signorini_2d", "signorini_3d"}


def test_bundled_list():
    assert EXPECTED <= set(bundled())
    assert DEFAULT_SCENE in bundled()


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bundled_scene_loads_and_round_trips(name):
    path = bundled()[name]
    scene = load(path)
    assert scene.name == name
    assert scene.hash == hashlib.sha256(path.read_bytes()).hexdigest()
    assert path.read_text().startswith("# SPDX-License-Identifier: MIT")
    again = loads_text(scene.to_toml())
    assert again == scene
    # the same keys and values (the comments mark what the first one took by default)
    assert _values(again.to_toml()) == _values(scene.to_toml())
    assert loads_text(again.to_toml()).to_toml() == again.to_toml()


def _values(shown: str) -> list[str]:
    """The lines of ``show``'s TOML without its comments."""
    return [re.sub(r"  # .*$", "", line) for line in shown.splitlines()
            if not line.startswith("#")]


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_resolve_by_name(name, tmp_path):
    assert resolve(name) == bundled()[name]
    assert resolve(f"{name}.toml") == bundled()[name]
    own = tmp_path / "mine.toml"
    own.write_text(NO_CONTACT)
    assert resolve(own) == own
    assert resolve(str(own)) == own


def test_resolve_unknown_lists_bundled_names():
    with pytest.raises(SceneError, match="no bundled scene named 'signorini2d'.*signorini_2d"):
        resolve("signorini2d")


def test_signorini_2d_data():
    scene = load(resolve("signorini_2d"))
    assert scene.dim == 2 and scene.mesh.cells == (32, 32) and scene.mesh.cell_type == "triangle"
    assert [p.kind for p in scene.boundaries.values()] == ["clamped", "traction", "traction",
                                                           "contact"]
    assert scene.boundaries["top"].plane == sc.PlaneSelector(1, 1.0, None)
    assert scene.material == sc.MaterialSpec(1e8, 0.3, "stress")
    assert scene.law.type == "perzyna" and scene.law.scheme == "implicit"
    assert math.isclose(scene.law.sigma_y.value(), math.sqrt(10.0))
    assert scene.law.mu_star.value() == 200.0 and scene.law.yield_set == "von_mises"
    assert scene.contact.type == "signorini" and scene.contact.gap is None
    phi = scene.contact.obstacle.numpy(np.array([[3.0, 0.0], [0.0, 0.0]]), 0.0)
    assert np.allclose(phi, [0.0, 0.01])  # the ellipse's top (3, 0) is on it; (0, 0) above it
    f = scene.loads.body_force[1].numpy(np.zeros((2, 3)), 0.5)
    assert np.allclose(f, -5.0)
    assert (scene.time.T, scene.time.k) == (1.0, 0.02)
    assert scene.output.contact_csv


def test_signorini_3d_data():
    scene = load(resolve("signorini_3d"))
    assert scene.dim == 3 and scene.mesh.upper == (3.0, 1.0, 1.0)
    assert scene.mesh.cells == (12, 4, 4) and scene.mesh.cell_type == "tetrahedron"
    end = scene.boundaries["end"]
    assert end.kind == "traction" and end.plane.axis == 0 and end.plane.value == 3.0
    assert end.traction[2].numpy(np.zeros((3, 1)), 1.0)[0] == -10.0
    assert scene.law.yield_set == "paper"
    assert scene.contact.gap.value() == 0.0 and scene.time.k == 0.02
    assert scene.material.plane is None


def test_normal_compliance_1d_data():
    scene = load(resolve("normal_compliance_1d"))
    assert scene.dim == 1 and scene.mesh.cells == (100,) and scene.material.nu is None
    assert scene.law == sc.LawSpec("linear", "explicit", a=scene.law.a, b=scene.law.b)
    assert (scene.law.a.value(), scene.law.b.value()) == (-1.0, 10.0)
    c = scene.contact
    assert (c.type, c.boundary, c.gap.value(), c.mu, c.alpha) == (
        "normal_compliance", "right", 0.25, 100.0, 1.0)
    x = np.linspace(0.0, 1.0, 5)[None, :]
    assert np.allclose(scene.initial.sigma0[0].numpy(x, 0.0), 10.0 - 10.0 * x[0])
    assert (scene.time.T, scene.time.k) == (10.0, 0.01)


def test_normal_compliance_2d_data():
    scene = load(resolve("normal_compliance_2d"))
    assert scene.mesh.upper == (6.0, 3.0) and scene.mesh.cells == (48, 24)
    assert scene.boundaries["right"].kind == "clamped"
    (point,) = scene.loads.point
    assert point.at == (3.0, 3.0)
    assert point.force[1].numpy(np.zeros((2, 1)), 0.5)[0] == -5.0
    assert scene.contact.mu == 100.0 and scene.contact.gap.value() == 0.0


def test_normal_compliance_3d_data():
    scene = load(resolve("normal_compliance_3d"))
    assert scene.contact.type == "normal_compliance" and scene.contact.mu == 1e-6
    assert scene.mesh.cells == (12, 4, 4) and scene.time.k == 0.05


# -- defaults ---------------------------------------------------------------------------------

def test_defaults_filled_in(tmp_path):
    path = tmp_path / "my scene.toml"
    path.write_text(NO_CONTACT)
    scene = load(path)
    assert scene.name == "my_scene" and scene.description == "" and scene.path == path
    mesh = scene.mesh
    assert (mesh.lower, mesh.upper, mesh.cell_type, mesh.diagonal) == (
        (0.0, 0.0), (1.0, 1.0), "triangle", "right")
    assert mesh.file is None and mesh.extent == 1.0
    assert scene.boundaries["top"].plane.tol is None
    assert scene.boundaries["top"].traction is None
    assert scene.material.plane == "strain"  # 2-D scenes are plane strain unless they say so
    assert (scene.law.type, scene.law.scheme, scene.law.sigma_y) == ("elastic", "explicit", None)
    assert scene.contact == sc.ContactSpec("none")
    assert [e.value() for e in scene.loads.body_force] == [0.0, 0.0]
    assert scene.loads.point == ()
    assert len(scene.initial.u0) == 2 and len(scene.initial.sigma0) == 3
    assert all(e.is_constant and e.value() == 0.0 for e in scene.initial.sigma0)
    assert scene.time.max_cuts == 12 and scene.degree == 1
    assert scene.solver == sc.SolverSpec("linear", {})
    assert scene.output == sc.OutputSpec(xdmf=True, contact_csv=False, figures=True, every=1)


def test_defaults_3d_perzyna_and_contact():
    text = edit(BASE, 'type = "rectangle"\ncells = [4, 4]', 'type = "box"\ncells = [2, 2, 2]')
    text = edit(text, 'axis = "y", value = 1.0', 'axis = "z", value = 1.0')
    text = edit(text, 'axis = "y", value = 0.0', 'axis = 2, value = 0.0')
    text = edit(text, 'plane = "stress"\n', "")
    text += '\n[law]\ntype = "perzyna"\nsigma_y = 1.0\nmu_star = "2*100"\n'
    scene = loads_text(text)
    assert scene.mesh.cell_type == "tetrahedron" and scene.mesh.diagonal is None
    assert scene.law.scheme == "implicit" and scene.law.yield_set == "von_mises"  # as in 2-D
    assert scene.law.mu_star.value() == 200.0
    assert scene.contact.alpha == 1.0 and scene.contact.gap.value() == 0.0
    assert scene.output.contact_csv is True
    assert len(scene.initial.sigma0) == 6 and scene.material.plane is None


def test_defaults_linear_law_and_obstacle():
    text = edit(BASE, 'type = "normal_compliance"\nboundary = "bottom"\nmu = 100.0',
                'type = "signorini"\nboundary = "bottom"\nobstacle = "x[1] + 1"')
    text += '\n[law]\ntype = "linear"\na = -1\nb = 10\n'
    scene = loads_text(text)
    assert scene.law.scheme == "explicit" and scene.law.yield_set is None
    assert scene.contact.max_distance == 1e3 and scene.contact.gap is None


def test_text_scene_name_and_round_trip_of_special_values(tmp_path):
    text = edit(BASE, 'name = "base"', 'description = "quote \\" backslash \\\\ tab\\t é"')
    text += ('\n[solver]\nlinear = "iterative"\npetsc_options = { snes_rtol = 1e-10, ksp_type = "preonly", '
             'snes_monitor = "", snes_max_it = 50, snes_converged_reason = true }\n'
             '[boundary.edge]\nkind = "traction"\nbox = { lower = [0, 0], upper = [1e-9, 1] }\n'
             'traction = ["x[1]*t", -1.5e-3]\n'
             '[[loads.point]]\nat = [0.5, 1]\nforce = ["sin(t)", 0]\n')
    scene = loads_text(text)
    assert scene.name == "scene"
    assert scene.description == 'quote " backslash \\ tab\t é'
    assert scene.solver.petsc_options["snes_max_it"] == 50
    assert scene.solver.linear == "iterative"
    assert loads_text(scene.to_toml()) == scene


def test_gmsh_mesh_found_relative_to_the_scene(tmp_path):
    (tmp_path / "beam.msh").write_text("$MeshFormat\n")
    text = edit(BASE, 'type = "rectangle"\ncells = [4, 4]', 'type = "gmsh"\nfile = "beam.msh"\ndim = 2')
    text = edit(text, 'plane = { axis = "y", value = 1.0 }', "tag = 1")
    path = tmp_path / "scene.toml"
    path.write_text(text)
    scene = load(path)
    assert scene.mesh.file == (tmp_path / "beam.msh").resolve() and scene.dim == 2
    assert scene.boundaries["top"].tag == 1 and scene.boundaries["top"].selector == "tag"
    assert loads_text(scene.to_toml()) == scene


def test_scene_error_and_where_locate_keys():
    scene = loads_text(BASE, "base.toml")
    line = line_of(BASE, "[boundary.bottom]")
    assert scene.where("boundary.bottom") == f"base.toml:{line}"
    assert scene.where("contact.mu") == f"base.toml:{line_of(BASE, 'mu = 100.0')}"
    assert scene.where("nowhere") == "base.toml"
    err = scene.error("boundary.bottom", "selects no facets")
    assert isinstance(err, SceneError)
    assert str(err) == f"base.toml:{line}: boundary.bottom: selects no facets"


# -- invalid scenes ---------------------------------------------------------------------------

def test_unknown_key_suggests_a_close_match():
    text = edit(BASE, "nu = 0.3", "nuu = 0.3")
    err = problems(text, r"material\.nuu: unknown key 'nuu'; did you mean 'nu'\?")
    assert problem_at(err, "nuu").line == line_of(text, "nuu")
    text = edit(BASE, "[material]", "[materail]")
    err = problems(text, r"did you mean 'material'\?")
    assert problem_at(err, "materail").line == line_of(text, "[materail]")
    text = edit(BASE, "plane = { axis = \"y\", value = 0.0 }",
                "plane = { axis = \"y\", valeu = 0.0 }")
    err = problems(text, r"boundary\.bottom\.plane\.valeu: unknown key 'valeu'; did you mean 'value'")
    assert problem_at(err, "valeu").line == line_of(text, "valeu")


@pytest.mark.parametrize("old, new, match", [
    ("E = 1e8", 'E = "big"', r"material\.E: expected a number, got a string \('big'\)"),
    ("E = 1e8", "E = true", r"material\.E: expected a number, got a boolean \(true\)"),
    ("cells = [4, 4]", 'cells = [4, "4"]', r"mesh\.cells\[1\]: expected an integer, got a string"),
    ("cells = [4, 4]", "cells = [4, 4.0]", r"mesh\.cells\[1\]: expected an integer, got a number"),
    ("cells = [4, 4]", "cells = 4", r"mesh\.cells: expected an array of 2 integers, got an integer"),
    ("k = 0.1", "k = [0.1]", r"time\.k: expected a number, got an array"),
    ('boundary = "bottom"', "boundary = 1", r"contact\.boundary: expected a string, got an integer"),
    ('kind = "clamped"', "kind = 1", r"boundary\.top\.kind: must be one of 'clamped', 'displacement', "
                                     r"'symmetry', 'traction', 'contact'; got 1"),
    ("mu = 100.0", "mu = inf", r"contact\.mu: must be finite, got inf"),
    ("nu = 0.3", "nu = { value = 0.3 }", r"material\.nu: expected a number, got a table"),
    ('name = "base"', 'loads = 3\nname = "base"', r"loads: expected a table, got an integer"),
])
def test_wrong_types(old, new, match):
    text = edit(BASE, old, new)
    err = problems(text, match)
    path = match.split(":")[0].replace("\\", "")
    assert problem_at(err, path).line == line_of(text, new.split("\n")[0])


@pytest.mark.parametrize("old, new, path, match", [
    ("E = 1e8", "E = -1", "material.E", "must be > 0, got -1"),
    ("E = 1e8", "E = 0", "material.E", "must be > 0, got 0"),
    ("E = 1e8", "E = 1e308", "material.E", r"must lie in \[1e-100, 1e\+100\], got 1e\+308"),
    ("nu = 0.3", "nu = 0.5", "material.nu", r"nu = 0.5 \(incompressible\) needs \[discretization\] formulation = \"mixed\""),
    ("nu = 0.3", "nu = 0.51", "material.nu", r"must lie in \(-1, 0.5\], got 0.51"),
    ("nu = 0.3", "nu = -1.0", "material.nu", r"must lie in \(-1, 0.5\], got -1"),
    ("mu = 100.0", "mu = 100.0\nalpha = 0", "contact.alpha", r"must lie in \(0, 1\], got 0"),
    ("mu = 100.0", "mu = 100.0\nalpha = 1.5", "contact.alpha", r"must lie in \(0, 1\], got 1.5"),
    ("mu = 100.0", "mu = 0.0", "contact.mu", "must be > 0, got 0"),
    ("mu = 100.0", "mu = -3", "contact.mu", "must be > 0, got -3"),
    ("k = 0.1", "k = 0", "time.k", "must be > 0, got 0"),
    ("k = 0.1", "k = -0.1", "time.k", r"must be > 0, got -0.1"),
    ("k = 0.1", "k = 2.0", "time.k", "must be <= T = 1, got 2"),
    ("T = 1.0", "T = -1.0", "time.T", "must be > 0, got -1"),
    ("mu = 100.0", "mu = 1.0\ngap = -0.5", "contact.gap", "must be >= 0, got -0.5"),
    ("[time]", "[output]\nevery = 0\n[time]", "output.every", "must be >= 1, got 0"),
])
def test_out_of_range_values_are_located(old, new, path, match):
    text = edit(BASE, old, new)
    err = problems(text, re.escape(path) + ": " + match)
    key = path.split(".")[-1]
    assert problem_at(err, path).line == line_of(text, f"{key} = ")
    assert str(err).startswith(f"scene.toml:{line_of(text, f'{key} = ')}: {path}: ")


def test_obstacle_normals_on_a_bar_are_located():
    """normals = "obstacle" on a 1-D bar stopped with an internal error (dolfinx will not
    tabulate the bar's one-component space); its contact point's normal is the bar's axis
    anyway, so the key is refused at its line."""
    text = """name = "bar"
[mesh]
type = "interval"
lower = [0.0]
upper = [1.0]
cells = [10]
[boundary.left]
kind = "clamped"
plane = { axis = "x", value = 0.0 }
[boundary.right]
kind = "contact"
plane = { axis = "x", value = 1.0 }
[material]
E = 1000.0
[law]
type = "elastic"
[contact]
type = "signorini"
boundary = "right"
obstacle = { shape = "plane", point = [1.01], normal = [-1.0] }
motion = ["-0.03*t"]
normals = "obstacle"
[time]
T = 1.0
k = 0.25
"""
    err = problems(text, r"contact\.normals: a 1-D body touches at its end point")
    assert problem_at(err, "contact.normals").line == line_of(text, "normals = ")
    loads_text(text.replace('normals = "obstacle"\n', ""))  # the default, along the bar


def test_no_clamped_part():
    """Without a Dirichlet part a scene needs a contact part to hold the body (whether it does is
    checked on the mesh, tests/solver/test_held_bodies.py)."""
    text = edit(NO_CONTACT, 'kind = "clamped"', 'kind = "traction"')
    err = problems(text, r"boundary: no boundary part has kind = 'clamped', 'displacement' or "
                         r"'symmetry', and no contact part")
    assert problem_at(err, "clamped").line == line_of(text, "[boundary.top]")
    loads_text(edit(BASE, "kind = \"clamped\"", "kind = \"traction\""))  # held by its contact


def test_contact_part_without_contact_section():
    text = NO_CONTACT + '\n[boundary.bottom]\nkind = "contact"\nwhere = "x[1] < 1e-9"\n'
    err = problems(text, r"boundary\.bottom\.kind: boundary part 'bottom' has kind 'contact' "
                         r"but the scene has no \[contact\] section")
    assert problem_at(err, "bottom").line == line_of(text, 'kind = "contact"')
    text = edit(BASE, 'type = "normal_compliance"\nboundary = "bottom"\nmu = 100.0', 'type = "none"')
    problems(text, "but contact.type is 'none'")


def test_contact_naming_a_missing_or_wrong_part():
    text = edit(BASE, 'boundary = "bottom"', 'boundary = "botom"')
    err = problems(text, r"contact\.boundary: no boundary part named 'botom'; did you mean 'bottom'")
    assert problem_at(err, "botom").line == line_of(text, 'boundary = "botom"')
    text = edit(BASE, 'boundary = "bottom"', 'boundary = "top"')
    problems(text, r"contact\.boundary: boundary part 'top' has kind 'clamped', not 'contact'")
    text = BASE + '\n[boundary.other]\nkind = "contact"\nwhere = "x[0] < 0"\n'
    problems(text, r"boundary\.other\.kind: boundary part 'other' has kind 'contact' but no "
                   r"contact table names it")


def test_gmsh_problems(tmp_path):
    text = edit(BASE, 'type = "rectangle"\ncells = [4, 4]', 'type = "gmsh"\nfile = "none.msh"\ndim = 2')
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match=r"mesh\.file: Gmsh file not found: .*none\.msh") as info:
        load(path)
    assert problem_at(info.value, "mesh.file").line == line_of(text, "file =")
    text = edit(BASE, 'cells = [4, 4]', 'cells = [4, 4]\ndim = 2')
    problems(text, r"mesh\.dim: not allowed: only for type = 'gmsh'")


def test_tag_on_a_builtin_mesh():
    text = edit(BASE, 'plane = { axis = "y", value = 1.0 }', "tag = 3")
    err = problems(text, r"boundary\.top\.tag: tags need mesh\.type = 'gmsh'")
    assert problem_at(err, "tags need").line == line_of(text, "tag = 3")


def test_expression_with_unknown_name_reports_the_column():
    text = BASE + '\n[loads]\nbody_force = [0, "-10*tt"]\n'
    err = problems(text, r"loads\.body_force\[1\]: invalid expression '-10\*tt' at column 5")
    assert problem_at(err, "body_force").line == line_of(text, "body_force")
    assert "tt" in problem_at(err, "body_force").message


def test_time_not_allowed_in_initial_displacement():
    text = BASE + '\n[initial]\nu0 = ["0.1*t", 0]\n'
    err = problems(text, r"initial\.u0\[0\]: invalid expression '0\.1\*t' at column 5: .*t")
    assert problem_at(err, "u0").line == line_of(text, "u0 =")
    problems(BASE + '\n[[loads.point]]\nat = [0, 1]\nforce = ["x[0]", 0]\n',
             r"loads\.point\[0\]\.force\[0\]: invalid expression 'x\[0\]'")
    problems(BASE.replace('mu = 100.0', 'mu = 1.0\ngap = "t"'), r"contact\.gap: invalid expression")


@pytest.mark.parametrize("source", [
    "__import__('os').system('echo pwned')",
    "().__class__.__bases__[0].__subclasses__()",
    "x.__class__",
    "open('/etc/passwd').read()",
    "eval('1')",
    "lambda: 0",
    "[c for c in 'abc']",
    "'a' * 10",
    "x[0] if x[1] else 1",
    "(" * 500 + "1" + ")" * 500,
    "1" + "+1" * 20000,
    "sqrt",
    "x[0]; import os",
], ids=lambda source: source[:24])
def test_hostile_expressions_are_rejected(source):
    text = BASE + '\n[loads]\nbody_force = [0, ' + _toml_string(source) + ']\n'
    err = problems(text, r"loads\.body_force\[1\]")
    assert problem_at(err, "body_force").line == line_of(text, "body_force")


def test_hostile_constant_is_rejected_or_finite():
    text = BASE + '\n[law]\ntype = "perzyna"\nsigma_y = "9**9**9**9"\nmu_star = 1\n'
    problems(text, r"law\.sigma_y")


def _toml_string(source: str) -> str:
    return '"' + source.replace("\\", "\\\\").replace('"', '\\"') + '"'


def test_where_must_be_a_condition():
    text = edit(BASE, 'plane = { axis = "y", value = 0.0 }', 'where = "x[1] + 1"')
    problems(text, r"boundary\.bottom\.where: must be a condition")
    text = edit(BASE, 'plane = { axis = "y", value = 0.0 }', 'where = "x[1] < 1e-9 and t > 0"')
    problems(text, r"boundary\.bottom\.where: invalid expression")


def test_several_errors_are_all_reported_sorted_by_line():
    text = edit(BASE, "E = 1e8", "E = -5")
    text = edit(text, "k = 0.1", "k = 3.0")
    text = edit(text, "cells = [4, 4]", "cells = [4, 0]")
    text = edit(text, "nu = 0.3", "nu = 0.3\nfoo = 1")
    err = problems(text, r"must be > 0, got -5")
    lines = [p.line for p in err.problems]
    assert len(err.problems) == 4, str(err)
    assert lines == sorted(lines)
    assert lines == [line_of(text, "cells"), line_of(text, "E = -5"), line_of(text, "foo"),
                     line_of(text, "k = 3.0")]
    assert len(str(err).splitlines()) == 4


def test_toml_syntax_error_has_its_line():
    text = edit(BASE, "E = 1e8", "E = 1e8 8")
    err = problems(text, r"scene\.toml:\d+: TOML syntax error")
    assert err.problems[0].line == line_of(text, "E = 1e8 8")
    err = problems(BASE + "\nx = [1,\n", "TOML syntax error")
    assert err.problems[0].line is not None
    problems(edit(BASE, "[material]", "[mesh]"), r"TOML syntax error: Cannot declare")


def test_file_read_errors(tmp_path):
    with pytest.raises(SceneError, match="no such scene file"):
        load(tmp_path / "missing.toml")
    bad = tmp_path / "latin1.toml"
    bad.write_bytes(b'name = "x"\ndescription = "caf\xe9"\n')
    with pytest.raises(SceneError, match=r"latin1\.toml:2: not UTF-8"):
        load(bad)
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * 1_100_000 + "\n")
    with pytest.raises(SceneError, match="larger than"):
        load(big)
    with pytest.raises(SceneError, match="larger than"):
        loads_text("# " + "x" * 1_100_000)
    with pytest.raises(SceneError, match="nested too deeply|TOML syntax error"):
        loads_text("x = " + "[" * 5000 + "]" * 5000)


@pytest.mark.parametrize("text, match", [
    (edit(BAR, "E = 10.0", "E = 10.0\nnu = 0.3"), r"material\.nu: not allowed: Poisson's ratio is not used in 1-D"),
    (edit(BAR, "E = 10.0", "E = 10.0\nplane = \"stress\""), r"material\.plane: not allowed: only for 2-D"),
    (edit(BAR, 'axis = "x"', 'axis = "y"'), r"boundary\.left\.plane\.axis: axis 'y' does not exist in 1-D \(use 'x'\)"),
    (edit(BASE, "nu = 0.3", ""), r"material\.nu: missing required key 'nu'"),
    (edit(BASE, "cells = [4, 4]", "cells = [4, 4]\ncell_type = \"tetrahedron\""), r"mesh\.cell_type: 'tetrahedron' cells are 3-D"),
    (edit(BASE, "cells = [4, 4]", "cells = [4000, 4000]"), r"mesh\.cells: too many cells"),
    (edit(BASE, "cells = [4, 4]", "cells = [4, 4]\ncell_type = \"quadrilateral\"\ndiagonal = \"left\""), r"mesh\.diagonal: not allowed"),
    (edit(BASE, "mu = 100.0", "mu = 1.0\nobstacle = \"x[1] + 1\"\nmotion = [0, \"t\"]"),
     r"contact\.motion: not allowed: a foundation surface stays where it is"),
    (edit(BASE, "mu = 100.0", "mu = 1.0\nobstacle = \"x[1] + t\""),
     r"contact\.obstacle: invalid expression 'x\[1\] \+ t'.*variables allowed here: x\)"),
    (edit(BASE, 'type = "normal_compliance"', 'type = "signorini"'), r"contact\.mu: not allowed"),
    (edit(BASE, "[time]", "[law]\nsigma_y = 1\n[time]"), r"law\.sigma_y: not allowed: only for type = 'perzyna'"),
    (edit(BASE, "[time]", "[law]\ntype = \"perzyna\"\nsigma_y = 1\nmu_star = 1\nyield_set = \"paper\"\n[time]"), r"law\.yield_set: only 'von_mises'"),
    (edit(BASE, "[time]", "[law]\ntype = \"perzyna\"\nmu_star = 1\n[time]"), r"law\.sigma_y: missing required key"),
    (edit(BASE, "[time]", "[law]\ntype = \"linear\"\na = \"x[0]\"\nb = 1\n[time]"), r"law\.a: invalid expression"),
    (edit(BASE, "[time]", "[solver]\npetsc_options = { \"-snes_rtol\" = 1 }\n[time]"), r"without the leading '-'"),
    (edit(BASE, "[time]", "[solver]\npetsc_options = { \"a b\" = 1 }\n[time]"), r"PETSc option name 'a b' must match"),
    (NO_CONTACT + "\n[output]\ncontact_csv = true\n", r"output\.contact_csv: needs a \[contact\] section"),
    (edit(BASE, 'plane = { axis = "y", value = 0.0 }', ""), r"boundary\.bottom: needs exactly one selector"),
    (edit(BASE, 'plane = { axis = "y", value = 0.0 }', 'plane = { axis = "y", value = 0.0 }\nwhere = "x[0] > 0"'), r"boundary\.bottom\.where: only one selector per part"),
    (edit(BASE, "[boundary.bottom]", "[boundary.1bottom]"), r"part name '1bottom' must match"),
    (edit(BASE, 'kind = "contact"', 'kind = "contact"\ntraction = [0, 0]'), r"boundary\.bottom\.traction: not allowed"),
    (edit(BASE, 'plane = { axis = "y", value = 0.0 }', "box = { lower = [0, 0], upper = [1, -1] }"), r"boundary\.bottom\.box\.upper\[1\]: must be >= lower\[1\]"),
    (edit(BASE, 'name = "base"', 'name = "../../etc"'), r"name: '\.\./\.\./etc' must match"),
    (edit(BASE, "mu = 100.0", "mu = 100.0\nobstacle = \"x[0] > 1\""),
     r"contact\.obstacle: must be a value, not a condition"),
    (edit(BASE, "[mesh]", "[discretization]\ndegree = 3\n[mesh]"), r"discretization\.degree: must be one of 1, 2; got 3"),
    (edit(BASE, "[mesh]", "[solver]\npredictor = \"quadratic\"\n[mesh]"), r"solver\.predictor: must be one of"),
    (edit(BASE, "[mesh]", "[solver]\nlinear = \"cg\"\n[mesh]"), r"solver\.linear: must be one of"),
    ("", r"mesh: missing required table \[mesh\]"),
])
def test_other_invalid_scenes(text, match):
    problems(text, match)


def test_missing_required_key_points_at_its_table():
    text = edit(BASE, "E = 1e8\n", "")
    err = problems(text, r"material\.E: missing required key 'E'")
    assert problem_at(err, "material.E").line == line_of(text, "[material]")
