# SPDX-License-Identifier: MIT
"""Docstrings and comments name modules and objects that exist: every dotted ``vpcontact.…``
reference in the package resolves by import and attribute lookup (file names such as
``.vpcontact.lock`` are not references)."""

import importlib
import re
from pathlib import Path

import vpcontact

PACKAGE = Path(vpcontact.__file__).parent
REFERENCE = re.compile(r"(?<![\w./])vpcontact(?:\.[A-Za-z_]\w*)+")


def _resolves(reference: str) -> bool:
    parts = reference.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def test_every_dotted_reference_in_the_package_resolves():
    broken = sorted({(str(path.relative_to(PACKAGE.parent)), ref)
                     for path in PACKAGE.rglob("*.py")
                     for ref in REFERENCE.findall(path.read_text())
                     if not _resolves(ref)})
    assert not broken, f"references to modules or objects that do not exist: {broken}"
