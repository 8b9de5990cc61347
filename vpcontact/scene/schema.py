# SPDX-License-Identifier: MIT
"""Validation helpers for scene files: located problems and typed access to TOML tables.

A scene is checked completely before anything is reported: every check appends a
:class:`Problem` (key path, line, message) to a :class:`Report`, and :class:`SceneError` lists them
all, one per line, sorted by line, e.g. ``scene.toml:12: material.E: must be > 0, got -1``.

:class:`Table` wraps one TOML table: it flags unknown keys (with a "did you mean" hint) and offers
typed getters that report a problem and return ``None`` when a value is missing or invalid, so
that reading can go on and find the next problem.
"""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Sequence

from vpcontact.errors import InputError
from vpcontact.scene.expressions import Expression, ExpressionError, parse
from vpcontact.scene.locate import Locator, join, split_path

__all__ = ["REQUIRED", "Problem", "Report", "SceneError", "Table", "at_least", "between",
           "constant_value", "fmt", "greater", "type_name", "unknown_key"]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


#: How the command line's scene-key overrides are written (``--set law.mu_star=50``).
OVERRIDE = "--set"

#: Default meaning "the key must be given".
REQUIRED: Any = _Required()

Check = Callable[[float], "str | None"]


@dataclass(frozen=True)
class Problem:
    """One thing wrong with a scene.

    Attributes:
        path: key path such as ``"material.E"`` or ``"loads.point[0].force"`` ("" for the file).
        line: 1-based line in the scene file, or ``None`` if unknown.
        message: what is wrong, e.g. ``"must be > 0, got -1"``.
        origin: the command-line override (``--set``) the problem comes from, as its key path
            (or its text when it could not be read), instead of a line of the file; else
            ``None``.
    """

    path: str
    line: int | None
    message: str
    origin: str | None = None

    def format(self, file: str) -> str:
        """``file:line: path: message`` (parts that are unknown are left out); for a problem of
        an override, ``--set path: message``."""
        if self.origin is not None:
            where = f"{OVERRIDE} {self.origin}"
            shown = self.path if self.path and self.path != self.origin else ""
        else:
            where = file if self.line is None else f"{file}:{self.line}"
            shown = self.path
        return f"{where}: {shown}: {self.message}" if shown else f"{where}: {self.message}"


class SceneError(InputError):
    """A scene file could not be read or does not describe a valid problem.

    Attributes:
        file: the scene file as shown in the messages.
        problems: all problems found, sorted by line (unknown lines last).
    """

    def __init__(self, problems: Iterable[Problem], file: str = "<scene>"):
        self.file = file
        self.problems = sorted(problems, key=lambda p: (p.line is None, p.line or 0))
        super().__init__("\n".join(p.format(file) for p in self.problems))


class Report:
    """Collects the problems of one scene file.

    Args:
        file: the file name shown in messages.
        locator: line finder of the file's text (``None`` if there is no text).
        overridden: the key paths set on the command line (``--set``); a problem at or under
            one of them is located at the override, not in the file.
    """

    def __init__(self, file: str, locator: Locator | None = None,
                 overridden: Sequence[str] = ()):
        self.file = file
        self.locator = locator
        self.overridden = tuple(overridden)
        self.problems: list[Problem] = []

    def add(self, path: str, message: str) -> None:
        """Record a problem at ``path``."""
        origin = self.origin(path)
        line = (self.locator.line(path) if self.locator is not None and path and origin is None
                else None)
        self.problems.append(Problem(path, line, message, origin))

    def origin(self, path: str) -> str | None:
        """The override that ``path`` belongs to: one set at ``path`` or above it, or one that
        created the table ``path`` lies in (a table the file does not have); else ``None``."""
        if not self.overridden:
            return None
        for key in self.overridden:
            if _within(path, key):
                return key
        created = self._first_missing(path)
        for key in self.overridden:
            if created is not None and _within(key, created):
                return key
        return None

    def _first_missing(self, path: str) -> str | None:
        """The shortest ancestor-or-self of ``path`` that the file does not have."""
        prefix = ""
        for token in split_path(path):
            prefix = prefix + token if token.startswith("[") or not prefix else f"{prefix}.{token}"
            if self.locator is None or self.locator.exact(prefix) is None:
                return prefix
        return None

    def error(self) -> SceneError:
        """A :class:`SceneError` holding the problems collected so far."""
        return SceneError(self.problems, self.file)


# -- messages -------------------------------------------------------------------------------

def _within(path: str, ancestor: str) -> bool:
    """Whether ``path`` is ``ancestor`` or lies below it (``a.b``, ``a[0]`` below ``a``)."""
    return path == ancestor or path.startswith((ancestor + ".", ancestor + "["))


def fmt(value: Any) -> str:
    """A number or value as written in messages (``-1.0`` -> ``-1``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    if isinstance(value, str):
        return repr(value if len(value) <= 60 else value[:57] + "...")
    return repr(value)


def type_name(value: Any) -> str:
    """``"a string"``, ``"an integer"``, ``"a table"`` ... for messages about wrong types."""
    names = {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
             list: "an array", dict: "a table"}
    return names.get(type(value), "a date/time")


def greater(bound: float) -> Check:
    """Check ``value > bound``."""
    return lambda v: None if v > bound else f"must be > {fmt(bound)}, got {fmt(v)}"


def at_least(bound: float) -> Check:
    """Check ``value >= bound``."""
    return lambda v: None if v >= bound else f"must be >= {fmt(bound)}, got {fmt(v)}"


def between(low: float, high: float, closed: str = "()") -> Check:
    """Check that the value lies in the interval ``(low, high)``, ``(low, high]`` ...

    Args:
        closed: two characters, ``(``/``[`` and ``)``/``]``.
    """
    def check(v: float) -> str | None:
        above = v >= low if closed[0] == "[" else v > low
        below = v <= high if closed[1] == "]" else v < high
        if above and below:
            return None
        return f"must lie in {closed[0]}{fmt(low)}, {fmt(high)}{closed[1]}, got {fmt(v)}"
    return check


def unknown_key(key: str, allowed: Sequence[str]) -> str:
    """"unknown key 'k'; did you mean 'x'?" (or the list of allowed keys)."""
    close = difflib.get_close_matches(key, list(allowed), n=1, cutoff=0.6)
    if close:
        return f"unknown key {key!r}; did you mean {close[0]!r}?"
    return f"unknown key {key!r}; expected one of: {', '.join(allowed) or '(none)'}"


def _number(value: Any) -> tuple[float | None, str | None]:
    """(value as float, None) or (None, message) for a TOML number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None, f"expected a number, got {type_name(value)} ({fmt(value)})"
    try:
        number = float(value)
    except OverflowError:
        return None, "number too large"
    if not math.isfinite(number):
        return None, f"must be finite, got {fmt(number)}"
    return number, None


# -- tables ---------------------------------------------------------------------------------

class Table:
    """Typed, reporting access to one TOML table.

    Args:
        report: where problems go.
        path: the table's key path (``""`` for the top level).
        data: the table as returned by :mod:`tomllib`.
        keys: the keys this table may hold (others are reported as unknown).
    """

    def __init__(self, report: Report, path: str, data: dict, keys: Sequence[str]):
        self.report = report
        self.path = path
        self.data = data
        for key in data:
            if key not in keys:
                report.add(join(path, key), unknown_key(key, keys))

    def at(self, key: str | int) -> str:
        """The path of ``key`` in this table."""
        return join(self.path, key)

    def has(self, key: str) -> bool:
        """Whether ``key`` is given."""
        return key in self.data

    def add(self, key: str, message: str) -> None:
        """Report a problem at ``key``."""
        self.report.add(self.at(key), message)

    def forbid(self, key: str, reason: str) -> None:
        """Report ``key`` as not allowed here (if given), e.g. "only for type = 'gmsh'"."""
        if key in self.data:
            self.add(key, f"not allowed: {reason}")

    def _get(self, key: str, default: Any) -> tuple[bool, Any]:
        """(True, raw value) if given; (False, default) otherwise (reporting missing keys)."""
        if key in self.data:
            return True, self.data[key]
        if default is REQUIRED:
            self.add(key, f"missing required key {key!r}")
            return False, None
        return False, default

    def number(self, key: str, default: Any = REQUIRED, check: Check | None = None) -> Any:
        """A finite number (int or float, not bool) as float, or ``default``/``None``."""
        given, raw = self._get(key, default)
        if not given:
            return raw
        number, message = _number(raw)
        if message is None and check is not None:
            message = check(number)
        if message is not None:
            self.add(key, message)
            return None
        return number

    def integer(self, key: str, default: Any = REQUIRED, check: Check | None = None) -> Any:
        """An integer (not bool), or ``default``/``None``."""
        given, raw = self._get(key, default)
        if not given:
            return raw
        if isinstance(raw, bool) or not isinstance(raw, int):
            self.add(key, f"expected an integer, got {type_name(raw)} ({fmt(raw)})")
            return None
        message = check(raw) if check is not None else None
        if message is not None:
            self.add(key, message)
            return None
        return raw

    def boolean(self, key: str, default: Any = REQUIRED) -> Any:
        """``true``/``false``, or ``default``/``None``."""
        given, raw = self._get(key, default)
        if given and not isinstance(raw, bool):
            self.add(key, f"expected true or false, got {type_name(raw)} ({fmt(raw)})")
            return None
        return raw

    def string(self, key: str, default: Any = REQUIRED, pattern: str | None = None,
               max_length: int = 10_000) -> Any:
        """A string (optionally matching a regular expression), or ``default``/``None``."""
        given, raw = self._get(key, default)
        if not given:
            return raw
        if not isinstance(raw, str):
            self.add(key, f"expected a string, got {type_name(raw)} ({fmt(raw)})")
            return None
        if len(raw) > max_length:
            self.add(key, f"string too long ({len(raw)} characters, at most {max_length})")
            return None
        if pattern is not None and not re.fullmatch(pattern, raw):
            self.add(key, f"{fmt(raw)} must match {pattern}")
            return None
        return raw

    def choice(self, key: str, choices: Sequence[Any], default: Any = REQUIRED) -> Any:
        """One of ``choices`` (strings or ints), or ``default``/``None``."""
        given, raw = self._get(key, default)
        if not given:
            return raw
        if not any(raw == c and type(raw) is type(c) for c in choices):
            options = ", ".join(fmt(c) for c in choices)
            self.add(key, f"must be one of {options}; got {fmt(raw)}")
            return None
        return raw

    def numbers(self, key: str, length: int | None, default: Any = REQUIRED,
                integer: bool = False, check: Check | None = None) -> Any:
        """An array of ``length`` numbers (ints if ``integer``) as a tuple, or ``default``/``None``.

        ``length`` ``None`` means the length is unknown (any length is accepted).
        """
        given, raw = self._get(key, default)
        if not given:
            return raw
        what = "integers" if integer else "numbers"
        if not isinstance(raw, list):
            self.add(key, f"expected an array of {_count(length)}{what}, got {type_name(raw)}")
            return None
        if length is not None and len(raw) != length:
            self.add(key, f"expected {length} {what}, got {len(raw)}")
            return None
        values, ok = [], True
        for i, item in enumerate(raw):
            if integer and (isinstance(item, bool) or not isinstance(item, int)):
                value, message = None, f"expected an integer, got {type_name(item)} ({fmt(item)})"
            elif integer:
                value, message = item, None
            else:
                value, message = _number(item)
            if message is None and check is not None:
                message = check(value)
            if message is not None:
                self.report.add(join(self.at(key), i), message)
                ok = False
            values.append(value)
        return tuple(values) if ok else None

    def expr(self, key: str, names: Sequence[str], dim: int | None, default: Any = REQUIRED,
             condition: bool = False) -> Any:
        """An :class:`Expression` in ``names`` (a number or an expression string).

        Args:
            condition: require a boolean expression (``x[0] > 1``) instead of a value.
        """
        given, raw = self._get(key, default)
        if not given:
            return raw if not isinstance(raw, (int, float, str)) else parse(raw, names=names)
        return _expression(self.report, self.at(key), raw, names, dim, condition)

    def exprs(self, key: str, names: Sequence[str], dim: int | None, length: int | None,
              default: Any = REQUIRED, free: bool = False) -> Any:
        """A tuple of ``length`` value expressions; ``default`` may be a tuple of numbers. With
        ``free``, an entry ``"free"`` stands for no value (``None``), and one entry at least
        must be a value."""
        given, raw = self._get(key, default)
        if not given:
            return raw if raw is None else tuple(parse(v, names=names) for v in raw)
        if not isinstance(raw, list):
            self.add(key, f"expected an array of {_count(length)}numbers or expression strings, "
                          f"got {type_name(raw)}")
            return None
        if length is not None and len(raw) != length:
            self.add(key, f"expected {length} components, got {len(raw)}")
            return None
        if free and raw and all(item == "free" for item in raw):
            self.add(key, "every component is 'free': give a value to at least one")
            return None
        items = [None if free and item == "free" else
                 _expression(self.report, join(self.at(key), i), item, names, dim, False)
                 for i, item in enumerate(raw)]
        bad = [i for i, item in enumerate(items)
               if item is None and not (free and raw[i] == "free")]
        return None if bad else tuple(items)

    def section(self, key: str, keys: Sequence[str], required: bool = False) -> Table:
        """The sub-table ``key``; an empty table (all defaults) if it is absent or invalid."""
        found = self.table(key, keys, required=required)
        return found if found is not None else Table(self.report, self.at(key), {}, keys)

    def table(self, key: str, keys: Sequence[str], required: bool = False) -> Table | None:
        """The sub-table ``key`` (``None`` if absent or not a table)."""
        if key not in self.data:
            if required:
                self.add(key, f"missing required table [{self.at(key)}]")
            return None
        raw = self.data[key]
        if not isinstance(raw, dict):
            self.add(key, f"expected a table, got {type_name(raw)}")
            return None
        return Table(self.report, self.at(key), raw, keys)


def constant_value(report: Report, path: str, expression: Expression) -> float | None:
    """The value of a constant expression, or ``None`` (reported) if it is not finite."""
    try:
        value = float(expression.value())
    except (ExpressionError, ArithmeticError, ValueError, TypeError) as err:
        report.add(path, f"cannot evaluate {fmt(expression.source)}: {err}")
        return None
    if not math.isfinite(value):
        report.add(path, f"must be finite, got {fmt(value)} from {fmt(expression.source)}")
        return None
    return value


def _count(length: int | None) -> str:
    return "" if length is None else f"{length} "


def _expression(report: Report, path: str, raw: Any, names: Sequence[str], dim: int | None,
                condition: bool) -> Expression | None:
    """Parse one expression value, reporting wrong types and :class:`ExpressionError`."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
        report.add(path, f"expected a number or an expression string, got {type_name(raw)}")
        return None
    if isinstance(raw, int) and abs(raw) > 2 ** 63:
        report.add(path, "number too large")
        return None
    allowed = ", ".join(names) if names else "none (a constant)"
    try:
        expression = parse(raw, names=tuple(names), dim=dim)
    except RecursionError:
        report.add(path, f"expression nested too deeply: {fmt(str(raw))}")
        return None
    except ExpressionError as err:
        column = f" at column {err.column + 1}" if err.column is not None else ""
        report.add(path, f"invalid expression {fmt(str(raw))}{column}: {err.reason} "
                         f"(variables allowed here: {allowed})")
        return None
    if condition and not expression.is_boolean:
        report.add(path, f"must be a condition such as 'x[0] > 1', got {fmt(str(raw))}")
        return None
    if not condition and expression.is_boolean:
        report.add(path, f"must be a value, not a condition, got {fmt(str(raw))}")
        return None
    return expression
