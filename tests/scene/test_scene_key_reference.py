# SPDX-License-Identifier: MIT
"""The scene-key registry (:mod:`vpcontact.scene.keys`) against the readers and the manual.

While the bundled scenes and a few broad ones are read, every :class:`~vpcontact.scene.schema.Table`
the readers create is recorded with the keys it accepts, and every default a getter falls back to
for an absent key. Each accepted key must have a registry entry with a description, in the
order the reader lists them (the order shows in "expected one of" messages), and the default
the reader used must be the registry's; leaving out each key the scenes give, one at a time,
must make the reader fall back to the registry's default (or report a required key missing).
The reference page, as the manual's extension writes it, must list every key. The key lists
are also pinned as the readers had them before the registry.
"""

import importlib.util
import re
import tomllib
from pathlib import Path
from types import SimpleNamespace

import pytest

from vpcontact.scene import bundled, load, loads_text
from vpcontact.scene import keys as registry
from vpcontact.scene.locate import join
from vpcontact.scene.read import read_scene
from vpcontact.scene.schema import REQUIRED, Report, Table
from vpcontact.scene.specs import SHAPES

BROAD_3D = """\
name = "broad_3d"
description = "many keys at once"

[mesh]
type = "box"
lower = [0.0, 0.0, 0.0]
upper = [2.0, 1.0, 1.0]
cells = [4, 2, 2]
cell_type = "hexahedron"

[boundary.left]
kind = "clamped"
plane = { axis = "x", value = 0.0, tol = 1e-6 }

[boundary.side]
kind = "symmetry"
plane = { axis = 1, value = 0.0 }

[boundary.corner]
kind = "displacement"
box = { lower = [2.0, 0.0, 0.0], upper = [2.0, 0.5, 1.0] }
displacement = ["free", "free", "-0.001*t"]

[boundary.right]
kind = "traction"
where = "x[0] > 1.99 and x[1] > 0.5"
traction = [0.0, 0.0, "-t"]

[boundary.top]
kind = "contact"
plane = { axis = "z", value = 1.0 }

[boundary.bottom]
kind = "contact"
plane = { axis = "z", value = 0.0 }

[loads]
body_force = [0.0, 0.0, "-0.1"]
[[loads.point]]
at = [2.0, 1.0, 1.0]
force = [0.0, 0.0, "-t"]

[material]
E = 1000.0
nu = 0.3

[law]
type = "perzyna"
scheme = "implicit"
sigma_y = "sqrt(10)"
mu_star = 100.0
yield_set = "von_mises"

[[contact]]
type = "signorini"
boundary = "top"
obstacle = { shape = "cylinder", center = [1.0, 0.5, 1.6], radius = 0.5, axis = [0, 1, 0] }
rotation = { center = [1.0, 0.5, 1.6], axis = [0, 1, 0], angle = "0.1*t" }
motion = [0.0, 0.0, "-0.05*t"]
max_distance = 10.0
normals = "obstacle"
friction = { type = "coulomb", coefficient = 0.3 }

[[contact]]
type = "normal_compliance"
boundary = "bottom"
obstacle = { shape = "plane", point = [0.0, 0.0, -0.01], normal = [0, 0, 1] }
mu = 1e-3
alpha = 0.5
friction = { type = "tresca", threshold = "1 + x[0]" }

[initial]
u0 = [0.0, 0.0, 0.0]
sigma0 = [0, 0, 0, 0, 0, 0]

[time]
T = 1.0
k = 0.1
max_cuts = 5
scheme = "bdf2"
tolerance = 1e-4

[discretization]
formulation = "mixed"
degree = 2

[solver]
predictor = "none"
linear = "direct"
petsc_options = { snes_rtol = 1e-9 }

[output]
xdmf = false
contact_csv = true
figures = false
every = 2
checkpoint_every = 0
probes = [[1.0, 0.5, 0.5], [2, 1, 1]]
"""

# Mostly defaults: a 2-D linear law and a signorini gap with a sphere obstacle left out.
SPARSE_2D = """\
[mesh]
type = "rectangle"
cells = [4, 2]

[boundary.bottom]
kind = "clamped"
plane = { axis = "y", value = 0.0 }

[boundary.top]
kind = "contact"
plane = { axis = "y", value = 1.0 }

[material]
E = 10.0
nu = 0.25
plane = "strain"

[law]
type = "linear"
a = -0.1
b = 0.5

[contact]
type = "signorini"
boundary = "top"
gap = "0.1 + 0.01*x[0]"

[time]
T = 1.0
k = 0.5
"""

SHAPES_2D = """\
[mesh]
type = "rectangle"
cells = [4, 2]
diagonal = "crossed"
refine = [{ lower = [0.0, 0.5], upper = [1.0, 1.0] }]

[boundary.bottom]
kind = "clamped"
plane = { axis = "y", value = 0.0 }

[boundary.top]
kind = "contact"
plane = { axis = "y", value = 1.0 }

[boundary.side]
kind = "contact"
plane = { axis = "x", value = 1.0 }

[material]
E = 10.0
nu = 0.25

[[contact]]
type = "signorini"
boundary = "top"
obstacle = { shape = "ellipsoid", center = [0.5, 1.5], semi_axes = [0.2, 0.4] }
force = [0.0, "-t"]

[[contact]]
type = "signorini"
boundary = "side"
obstacle = { shape = "sphere", center = [1.5, 0.5], radius = 0.4 }
rotation = { center = [1.5, 0.0], angle = "0.1*t" }

[time]
T = 1.0
k = 0.5
"""

BAR_1D = """\
[mesh]
type = "interval"
upper = [1.0]
cells = [4]

[boundary.left]
kind = "clamped"
plane = { axis = "x", value = 0.0 }

[boundary.right]
kind = "contact"
plane = { axis = 0, value = 1.0 }

[material]
E = 1.0

[law]
type = "perzyna"
sigma_y = 1.0
mu_star = 1.0

[contact]
type = "normal_compliance"
boundary = "right"
mu = 1.0

[time]
T = 1.0
k = 0.5
"""

TEXTS = {"broad_3d": BROAD_3D, "sparse_2d": SPARSE_2D, "shapes_2d": SHAPES_2D, "bar_1d": BAR_1D}


@pytest.fixture(scope="module")
def recorded():
    """Read every bundled scene and the texts above; return ({pattern: keys}, [(pattern, key,
    default)]) as the readers used them."""
    tables, fallbacks = [], []
    init, get = Table.__init__, Table._get

    def logging_init(self, report, path, data, keys):
        tables.append((path, tuple(keys)))
        init(self, report, path, data, keys)

    def logging_get(self, key, default):
        if key not in self.data:
            fallbacks.append((self.path, key, default))
        return get(self, key, default)

    mp = pytest.MonkeyPatch()
    mp.setattr(Table, "__init__", logging_init)
    mp.setattr(Table, "_get", logging_get)
    try:
        for path in bundled().values():
            load(path)
        for name, text in TEXTS.items():
            loads_text(text, f"{name}.toml")
    finally:
        mp.undo()
    return tables, fallbacks


def test_every_table_the_readers_accept_is_in_the_registry(recorded):
    tables, _ = recorded
    seen = set()
    for path, accepted in tables:
        pattern = registry.pattern_of(path)
        assert pattern in registry.TABLES, f"table {path!r} ({pattern!r}) has no registry entry"
        assert accepted == registry.keys(pattern), (
            f"{path}: the reader accepts {accepted}, the registry lists {registry.keys(pattern)}")
        for key in accepted:
            assert registry.entry(pattern, key).description.strip(), f"{pattern}.{key}"
        seen.add(pattern)
    # every registry table was met while reading (none is dead)
    assert seen == set(registry.TABLES), set(registry.TABLES) ^ seen


def test_defaults_the_readers_use_are_the_registry_s(recorded):
    _, fallbacks = recorded
    assert len(fallbacks) > 50
    for path, key, used in fallbacks:
        pattern = registry.pattern_of(path)
        entry = registry.entry(pattern, key)
        assert _agrees(entry, used), (
            f"{path}.{key} ({pattern}): reader's default {used!r}, registry's {entry.default!r}")


def test_obstacle_keys_are_shape_and_every_shape_parameter():
    union = sorted({k for params in SHAPES.values() for k in params})
    assert registry.keys("contact.obstacle") == ("shape",) + tuple(union)


def _built_reference(tmp_path) -> str:
    """The scene-key page as the manual's extension (docs/_ext/vpdocs.py) writes it."""
    path = Path(__file__).resolve().parents[2] / "docs" / "_ext" / "vpdocs.py"
    spec = importlib.util.spec_from_file_location("vpdocs", path)
    vpdocs = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(vpdocs)
    vpdocs.generate(SimpleNamespace(srcdir=str(tmp_path)))
    return (tmp_path / "_generated" / "scene_keys.md").read_text(encoding="utf-8")


def test_reference_page_lists_every_key(tmp_path):
    page = _built_reference(tmp_path)
    sections = re.split(r"^## ", page, flags=re.M)[1:]
    assert len(sections) == len(registry.TABLES)
    for (table, entries), section in zip(registry.TABLES.items(), sections):
        heading = section.splitlines()[0]
        assert registry.TITLES[table] in heading or table == ""
        rows = [line for line in section.splitlines() if line.startswith("| `")]
        names = [re.match(r"\| `([^`]+)`", line).group(1) for line in rows]
        assert names == [e.name for e in entries], f"{table}: {names}"
        for entry, row in zip(entries, rows):
            assert entry.description.replace("|", "\\|") in row


# The tables' keys as the readers listed them before the registry (1c56bc3): removing an entry
# from the registry would silently shrink what a reader accepts. A new key is added here too.
KEYS_BEFORE_THE_REGISTRY = {
    "": ("name", "description", "mesh", "boundary", "loads", "material", "law", "contact",
         "initial", "time", "discretization", "solver", "output"),
    "mesh": ("type", "lower", "upper", "cells", "cell_type", "diagonal", "refine", "file", "dim"),
    "mesh.refine[]": ("lower", "upper"),  # (added with issue 45)
    "boundary.<name>": ("kind", "tag", "plane", "box", "where", "traction", "displacement"),
    "boundary.<name>.plane": ("axis", "value", "tol"),
    "boundary.<name>.box": ("lower", "upper"),
    "loads": ("body_force", "point"),
    "loads.point[]": ("at", "force"),
    "material": ("E", "nu", "plane"),
    "law": ("type", "scheme", "sigma_y", "mu_star", "yield_set", "a", "b"),
    "contact": ("type", "boundary", "gap", "obstacle", "motion", "rotation", "force",
                "max_distance", "mu", "alpha", "friction", "normals"),
    "contact.friction": ("type", "coefficient", "threshold"),
    "contact.obstacle": ("shape", "axis", "center", "normal", "point", "radius", "semi_axes"),
    "contact.rotation": ("center", "angle", "axis"),
    "initial": ("u0", "sigma0"),
    "time": ("T", "k", "max_cuts", "scheme", "tolerance"),
    "discretization": ("degree", "formulation"),
    "solver": ("predictor", "linear", "petsc_options"),
    "output": ("xdmf", "contact_csv", "figures", "every", "checkpoint_every", "probes"),
}


def test_the_registry_keeps_every_key_the_readers_accepted():
    assert set(registry.TABLES) == set(KEYS_BEFORE_THE_REGISTRY)
    for table, accepted in KEYS_BEFORE_THE_REGISTRY.items():
        assert registry.keys(table) == accepted, (table, registry.keys(table))


def _tables(data: dict, path: str = ""):
    """(key path, table) of every table and array-of-tables element in a parsed scene."""
    yield path, data
    for key, value in data.items():
        child = join(path, key)
        if isinstance(value, dict):
            yield from _tables(value, child)
        elif isinstance(value, list):
            for i, item in enumerate(value):
                if isinstance(item, dict):
                    yield from _tables(item, join(child, i))


def _agrees(entry, used) -> bool:
    """Whether the default a reader used is the registry entry's."""
    if entry.default is REQUIRED or used is REQUIRED:
        return entry.default is used
    if isinstance(entry.default, registry.Varies):
        return not entry.default.values or used in entry.default.values
    return type(used) is type(entry.default) and used == entry.default


def test_each_key_left_out_falls_back_to_the_registry_default():
    """Leave out, one at a time, every key the scenes above give: the default the reader then
    falls back to (REQUIRED included: it reports the key missing) is the registry's."""
    fallbacks = []
    get = Table._get

    def logging_get(self, key, default):
        if key not in self.data:
            fallbacks.append((registry.pattern_of(self.path), key, default))
        return get(self, key, default)

    checked = set()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Table, "_get", logging_get)
        for name, text in TEXTS.items():
            for path, table in list(_tables(tomllib.loads(text))):
                pattern = registry.pattern_of(path)
                if pattern not in registry.TABLES or pattern == "":
                    continue
                for key in list(table):
                    if isinstance(table[key], dict):
                        continue
                    data = tomllib.loads(text)
                    del dict(_tables(data))[path][key]
                    fallbacks.clear()
                    report = Report(f"{name}.toml")
                    read_scene(data, report, Path("."), name)
                    entry = registry.entry(pattern, key)
                    used = [d for p, k, d in fallbacks if (p, k) == (pattern, key)]
                    for default in used:
                        assert _agrees(entry, default), (
                            f"{name}: without {path}.{key} the reader fell back to {default!r}, "
                            f"the registry says {entry.default!r}")
                    if entry.default is REQUIRED:
                        assert used, f"{name}: without {path}.{key} the reader did not ask for it"
                        assert any(p.path == join(path, key) and "missing" in p.message
                                   for p in report.problems), (path, key, report.problems)
                    if used:
                        checked.add((pattern, key))
    required = {(t, e.name) for t, entries in registry.TABLES.items() for e in entries
                if e.default is REQUIRED and e.type != "table" and t != ""}
    # the Gmsh keys need a mesh file; every other required key was left out once above
    assert required - checked == {("mesh", "file"), ("mesh", "dim")}, required - checked
