# SPDX-License-Identifier: MIT
"""The tests' shared scenes: TOML files under ``tests/scenes/``, read as text.

A scene file may hold placeholders, ``${key}`` (:class:`string.Template`), where the tests that
use it vary a value or a line: :func:`scene_text` fills them from its keyword arguments, as
plain text, so the scene a test runs is exactly the file with those values written in. Tests
that change a scene further do it on the returned text (``str.replace``), as before.

In a test function, the fixtures ``scene_text`` and ``scene_path`` (tests/conftest.py) give
these functions; module-level code (parametrize lists, helpers) imports them from here.
"""

from __future__ import annotations

import string
from pathlib import Path

#: The folder of the shared scene files.
SCENES = Path(__file__).resolve().parents[1] / "scenes"


def scene_path(name: str) -> Path:
    """The file of the shared scene ``name`` (``tests/scenes/<name>.toml``)."""
    path = SCENES / f"{name}.toml"
    if not path.is_file():
        known = sorted(p.stem for p in SCENES.glob("*.toml"))
        raise FileNotFoundError(f"no shared scene {name!r} in {SCENES} (there are: {known})")
    return path


def placeholders(name: str) -> set[str]:
    """The ``${key}`` placeholders of the scene ``name``."""
    return set(string.Template(scene_path(name).read_text()).get_identifiers())


def scene_text(name: str, /, **values) -> str:
    """The text of the shared scene ``name`` with its placeholders filled from ``values``.

    Every placeholder of the file must be given, and only those (a ``KeyError`` or a
    ``TypeError`` names the others): a test states each value it varies. A value is written
    in as ``str(value)``: give TOML text (``'"linearized"'`` for a string, ``'0.3'`` or ``0.3``
    for a number, whole lines for optional keys, ``""`` for none).
    """
    text = scene_path(name).read_text()
    wanted = placeholders(name)
    unknown = sorted(set(values) - wanted)
    if unknown:
        raise TypeError(f"scene {name!r} has no placeholder {unknown} (it has {sorted(wanted)})")
    missing = sorted(wanted - set(values))
    if missing:
        raise KeyError(f"scene {name!r} needs values for {missing}")
    return string.Template(text).substitute({k: str(v) for k, v in values.items()}) if wanted \
        else text
