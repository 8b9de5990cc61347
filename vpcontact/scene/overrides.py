# SPDX-License-Identifier: MIT
"""Command-line overrides of scene keys: ``vpcontact run SCENE --set time.k=0.01``.

An override ``KEY=VALUE`` names any key of a scene by its path, written as the reader's
messages write it (``law.mu_star``, ``mesh.cells``, ``boundary.top.plane.value``,
``contact[1].mu``, ``initial.u0[0]``), and gives the value as a TOML value (``0.01``,
``[32, 16]``, ``"strain"``, ``{ type = "coulomb", coefficient = 0.3 }``); a value that is not
TOML is taken as a bare string (``material.plane=strain``, ``law.sigma_y=sqrt(10)``).

The overrides are set in the parsed file before it is read (tables on their way are created
when the file has none), so they are checked exactly like the file's own keys; a problem at or
under an overridden key is located at the override (``--set law.mu_sta: unknown key
'mu_sta'; did you mean 'mu_star'?``) instead of a line of the file
(:meth:`vpcontact.scene.schema.Report.origin`).
"""

from __future__ import annotations

import copy
import re
import tomllib
from dataclasses import dataclass
from typing import Any, Iterable

from vpcontact.scene.locate import join
from vpcontact.scene.schema import Problem, type_name

__all__ = ["Override", "apply", "parse"]

_KEY = r'(?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*")'
_PATH = re.compile(rf"{_KEY}(?:\.{_KEY}|\[\d+\])*")
_TOKEN = re.compile(rf"\[(\d+)\]|({_KEY})")


@dataclass(frozen=True)
class Override:
    """One ``--set KEY=VALUE``.

    Attributes:
        path: the key path, written as the reader writes paths (``contact[0].mu``).
        value: the value as TOML reads it (a bare word: the string).
    """

    path: str
    value: Any


def parse(text: str) -> Override | Problem:
    """The override ``KEY=VALUE`` in ``text``, or the :class:`Problem` that it is not one."""
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        return Problem("", None, "takes KEY=VALUE with KEY a scene key such as time.k",
                       origin=text)
    if not _PATH.fullmatch(key):
        return Problem("", None, f"{key!r} is not a key path (keys joined by '.', array items "
                                 "as [i], e.g. law.mu_star or contact[1].mu)", origin=text)
    return Override(_canonical(key), _value(raw.strip()))


def _tokens(path: str) -> list[str | int]:
    """``'contact[1]."a b".c'`` -> ``["contact", 1, "a b", "c"]``."""
    tokens: list[str | int] = []
    for index, key in _TOKEN.findall(path):
        if index:
            tokens.append(int(index))
        else:
            tokens.append(tomllib.loads(f"k = {key}")["k"] if key.startswith('"') else key)
    return tokens


def _canonical(path: str) -> str:
    out = ""
    for token in _tokens(path):
        out = join(out, token)
    return out


def _value(raw: str) -> Any:
    """A TOML value, or the text itself (a bare word such as ``strain``)."""
    try:
        return tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        return raw


def apply(data: dict, overrides: Iterable[Override]) -> list[Problem]:
    """Set every override in ``data`` (a parsed scene file, changed in place), in order (a later
    override of the same key wins); return the problems of those that cannot be set (a key
    below a value that is not a table, an array item that does not exist)."""
    problems = []
    for override in overrides:
        message = _set(data, _tokens(override.path), override.value)
        if message is not None:
            problems.append(Problem(override.path, None, message, origin=override.path))
    return problems


def _set(data: dict, tokens: list[str | int], value: Any) -> str | None:
    """Set ``value`` at ``tokens`` in ``data``; the reason it cannot be set, or ``None``."""
    node: Any = data
    path = ""
    for token, following in zip(tokens, tokens[1:] + [None]):
        if isinstance(token, int):
            if not isinstance(node, list):
                return f"{path} is {type_name(node)}, not an array: {path}[{token}] does not exist"
            if token >= len(node):
                return f"{path} has {len(node)} item(s): no item [{token}]"
        elif not isinstance(node, dict):
            hint = f" (name an item, e.g. {path}[0].{token})" if isinstance(node, list) else ""
            return f"{path} is {type_name(node)}, not a table{hint}"
        if following is None:
            node[token] = copy.deepcopy(value)  # (a later override of an item changes the copy)
            return None
        if isinstance(token, str) and token not in node:
            if isinstance(following, int):
                return f"{join(path, token)} is not in the scene: no item [{following}] to set"
            node[token] = {}
        path = join(path, token)
        node = node[token]
    return None
