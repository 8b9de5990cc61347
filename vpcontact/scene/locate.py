# SPDX-License-Identifier: MIT
"""Line numbers of the keys of a TOML scene file, for error messages.

:mod:`tomllib` returns plain dictionaries without positions, so this module skims the raw text a
second time (after :mod:`tomllib` has accepted it) and records, for every key path, the line where
it first appears. Key paths are written as in the error messages, e.g. ``material.E``,
``boundary.bottom.plane.value``, ``loads.point[1].force`` (array indices are 0-based) or
``initial.u0[2]``; keys that are not bare TOML keys are double-quoted.

The skim is best effort: a path that was not seen falls back to its closest recorded ancestor
(usually the table header), and :meth:`Locator.line` returns ``None`` when nothing matches.
"""

from __future__ import annotations

import bisect
import re
import tomllib

__all__ = ["Locator", "join", "split_path"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_PATH_TOKEN = re.compile(r'\[\d+\]|"(?:[^"\\]|\\.)*"|[A-Za-z0-9_-]+')
_SCALAR_END = ",]}\n#"


def join(parent: str, key: str | int) -> str:
    """The path of ``key`` (a table key or an array index) inside the value at ``parent``."""
    if isinstance(key, int):
        return f"{parent}[{key}]"
    part = key if _BARE_KEY.fullmatch(key) else _quote(key)
    return f"{parent}.{part}" if parent else part


def split_path(path: str) -> list[str]:
    """The tokens of a path: ``"a.b[1].c"`` -> ``["a", "b", "[1]", "c"]``."""
    return _PATH_TOKEN.findall(path)


def _quote(key: str) -> str:
    out = key.replace("\\", "\\\\").replace('"', '\\"')
    return '"' + "".join(c if c.isprintable() else f"\\u{ord(c):04x}" for c in out) + '"'


def _rejoin(tokens: list[str]) -> str:
    path = ""
    for token in tokens:
        if token.startswith("["):
            path += token
        else:
            path = f"{path}.{token}" if path else token
    return path


class Locator:
    """Maps key paths of one TOML text to 1-based line numbers.

    Args:
        text: the TOML source (assumed to be valid TOML; invalid input just gives fewer lines).
    """

    def __init__(self, text: str):
        self._lines: dict[str, int] = {}
        scanner = _Scanner(text, self._lines)
        try:
            scanner.run()
        except (IndexError, ValueError, RecursionError, tomllib.TOMLDecodeError):
            pass  # keep what was found before the skim got lost

    def line(self, path: str) -> int | None:
        """The line of ``path``, else of its closest recorded ancestor, else ``None``."""
        tokens = split_path(path)
        while tokens:
            found = self._lines.get(_rejoin(tokens))
            if found is not None:
                return found
            tokens.pop()
        return None

    def exact(self, path: str) -> int | None:
        """The line of ``path`` itself, or ``None`` if it was not seen."""
        return self._lines.get(path)


class _Scanner:
    """A skimming TOML reader that records where keys, headers and array items start."""

    def __init__(self, text: str, lines: dict[str, int]):
        self.s = text
        self.i = 0
        self.lines = lines
        self.newlines = [m.start() for m in re.finditer("\n", text)]
        self.aot_counts: dict[str, int] = {}

    # -- positions --------------------------------------------------------------------------
    def line_at(self, pos: int) -> int:
        return bisect.bisect_left(self.newlines, pos) + 1

    def record(self, path: str, pos: int) -> None:
        self.lines.setdefault(path, self.line_at(pos))

    def peek(self, n: int = 1) -> str:
        return self.s[self.i:self.i + n]

    def eof(self) -> bool:
        return self.i >= len(self.s)

    def skip_blank(self, newlines: bool) -> None:
        """Skip spaces, tabs, comments and (if ``newlines``) line breaks."""
        chars = " \t\r\n" if newlines else " \t\r"
        while not self.eof():
            c = self.s[self.i]
            if c in chars:
                self.i += 1
            elif c == "#":
                end = self.s.find("\n", self.i)
                self.i = len(self.s) if end < 0 else end
            else:
                break

    # -- statements ---------------------------------------------------------------------------
    def run(self) -> None:
        table = ""
        while True:
            self.skip_blank(newlines=True)
            if self.eof():
                return
            if self.peek() == "[":
                table = self.header()
            else:
                start = self.i
                path = self.dotted_key(table, start)
                self.expect("=")
                self.value(path)

    def header(self) -> str:
        start = self.i
        array = self.peek(2) == "[["
        self.i += 2 if array else 1
        self.skip_blank(newlines=False)
        keys = self.key_parts()
        self.i += 2 if array else 1
        path = ""
        for n, key in enumerate(keys):
            path = join(path, key)
            last = n == len(keys) - 1
            if array and last:
                index = self.aot_counts.get(path, -1) + 1
                self.aot_counts[path] = index
                self.record(path, start)
                path = join(path, index)
            elif path in self.aot_counts:
                self.record(path, start)
                path = join(path, self.aot_counts[path])
            self.record(path, start)
        return path

    def dotted_key(self, table: str, start: int) -> str:
        path = table
        for key in self.key_parts():
            path = join(path, key)
            self.record(path, start)
        return path

    def key_parts(self) -> list[str]:
        parts = []
        while True:
            self.skip_blank(newlines=False)
            c = self.peek()
            if c in "\"'":
                begin = self.i
                self.skip_string()
                parts.append(tomllib.loads(f"k = {self.s[begin:self.i]}")["k"])
            else:
                match = _BARE_KEY.match(self.s, self.i)
                if match is None:
                    raise ValueError("not a key")
                parts.append(match.group())
                self.i = match.end()
            self.skip_blank(newlines=False)
            if self.peek() != ".":
                return parts
            self.i += 1

    def expect(self, char: str) -> None:
        self.skip_blank(newlines=False)
        if self.peek() != char:
            raise ValueError(f"expected {char!r}")
        self.i += 1

    # -- values -------------------------------------------------------------------------------
    def value(self, path: str) -> None:
        self.skip_blank(newlines=False)
        c = self.peek()
        if c in "\"'":
            self.skip_string()
        elif c == "[":
            self.array(path)
        elif c == "{":
            self.inline_table(path)
        else:
            while not self.eof() and self.s[self.i] not in _SCALAR_END:
                self.i += 1

    def array(self, path: str) -> None:
        self.i += 1
        index = 0
        while True:
            self.skip_blank(newlines=True)
            if self.peek() == "]":
                self.i += 1
                return
            item = join(path, index)
            self.record(item, self.i)
            self.value(item)
            self.skip_blank(newlines=True)
            if self.peek() == ",":
                self.i += 1
            index += 1

    def inline_table(self, path: str) -> None:
        self.i += 1
        while True:
            self.skip_blank(newlines=False)
            if self.peek() == "}":
                self.i += 1
                return
            key_path = self.dotted_key(path, self.i)
            self.expect("=")
            self.value(key_path)
            self.skip_blank(newlines=False)
            if self.peek() == ",":
                self.i += 1

    def skip_string(self) -> None:
        quote = self.peek()
        if self.peek(3) == quote * 3:
            end = self.s.find(quote * 3, self.i + 3)
            while quote == '"' and end > 0 and _escaped(self.s, end):
                end = self.s.find(quote * 3, end + 1)
            if end < 0:
                raise ValueError("unterminated string")
            self.i = end + 3
            for _ in range(2):  # a closing delimiter may be followed by up to two more quotes
                if self.peek() == quote:
                    self.i += 1
            return
        j = self.i + 1
        while j < len(self.s) and self.s[j] != quote:
            j += 2 if quote == '"' and self.s[j] == "\\" else 1
        self.i = j + 1


def _escaped(s: str, pos: int) -> bool:
    """Whether the character at ``pos`` is preceded by an odd number of backslashes."""
    n = 0
    while pos - n - 1 >= 0 and s[pos - n - 1] == "\\":
        n += 1
    return n % 2 == 1
