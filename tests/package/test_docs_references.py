# SPDX-License-Identifier: MIT
"""The manual's pointers to tests lead somewhere: every ``tests/….py`` and ``tests/….py::name``
(and the ``::name`` that follow one in the same line) named in ``README.md`` and ``docs/`` is a
file of the suite with a function of that name. The validation page's table is a list of such
pointers; a test renamed or moved without it is caught here."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = next(p for p in Path(__file__).resolve().parents if (p / "vpcontact" / "__init__.py").is_file())
PAGES = sorted([ROOT / "README.md", *(p for p in (ROOT / "docs").rglob("*.md")
                                      if not {"_build", "_generated"} & set(p.parts))])
POINTER = re.compile(r"`(tests/[\w/]+\.py)(?:::(\w+))?`|`::(\w+)`")


def _pointers(page: Path) -> list[tuple[int, str, str | None]]:
    """(line, test file, function or None) for every pointer of a page."""
    found = []
    for number, line in enumerate(page.read_text().splitlines(), 1):
        current = None
        for match in POINTER.finditer(line):
            if match.group(1):
                current = match.group(1)
                found.append((number, current, match.group(2)))
            elif current is not None:
                found.append((number, current, match.group(3)))
    return found


def test_the_validation_page_points_at_tests():
    assert len(_pointers(ROOT / "docs" / "validation.md")) >= 40


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_pointers_to_tests_exist(page):
    broken = []
    for line, file, function in _pointers(page):
        path = ROOT / file
        if not path.is_file():
            broken.append(f"{page.name}:{line}: {file} does not exist")
        elif function and not re.search(rf"^\s*def {function}\(", path.read_text(), re.M):
            broken.append(f"{page.name}:{line}: {file} has no {function}")
    assert broken == [], "\n".join(broken)
