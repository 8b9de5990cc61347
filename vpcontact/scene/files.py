# SPDX-License-Identifier: MIT
"""Scene files: a contact problem described in TOML, loaded, validated and resolved.

A scene file names a mesh, the parts of its boundary (clamped Γ1, traction Γ2, contact Γ3), the
loads, the material and its rate-type law σ̇ = E ε̇ + G(σ, ε), the contact condition, the
initial state, the time interval and step, and what to write::

    [mesh]
    type = "rectangle"
    cells = [32, 32]

    [boundary.top]
    kind = "clamped"
    plane = { axis = "y", value = 1.0 }

    [material]
    E = 1e8
    nu = 0.3

    [time]
    T = 1.0
    k = 0.02

Scene files are untrusted input: :func:`load` reads them with :mod:`tomllib`, checks every key
and value (types, ranges, expressions, cross references) and raises one :class:`SceneError`
listing all problems with their lines, e.g. ``scene.toml:12: material.E: must be > 0, got -1``.
The result is a frozen :class:`Scene` with every default filled in; it builds nothing (the
builder turns it into dolfinx objects) and can report located errors later through
:meth:`Scene.error`. The bundled scenes (:func:`bundled`) reproduce the paper's examples.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

from vpcontact.scene import overrides as cli_overrides
from vpcontact.scene import write
from vpcontact.scene.locate import Locator
from vpcontact.scene.read import contact_key, read_scene
from vpcontact.scene.schema import OVERRIDE, Problem, Report, SceneError
from vpcontact.scene.specs import (BoundaryPart, BoxSelector, ContactSpec, InitialSpec, LawSpec,
                                   LoadSpec, MaterialSpec, MeshSpec, OutputSpec, PlaneSelector,
                                   PointLoad, SolverSpec, TimeSpec)

__all__ = ["DEFAULT_SCENE", "MAX_BYTES", "BoundaryPart", "BoxSelector", "ContactSpec",
           "InitialSpec", "LawSpec", "LoadSpec", "MaterialSpec", "MeshSpec", "OutputSpec",
           "PlaneSelector", "PointLoad", "Problem", "Scene", "SceneError", "SolverSpec",
           "TimeSpec", "bundled", "load", "loads_text", "resolve"]

#: The scene used when none is named.
DEFAULT_SCENE = "indentation_relaxation"
#: Largest scene file accepted, in bytes.
MAX_BYTES = 1_000_000
SCENES_DIR = Path(__file__).parent / "bundled"
_TOML_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)\s*$")
_TOML_END = re.compile(r"\s*\(at end of document\)\s*$")


@dataclass(frozen=True)
class Scene:
    """A validated scene with all defaults filled in.

    Two scenes compare equal when they describe the same problem (``path``, ``hash`` and the
    line locator are not compared).

    Attributes:
        name: scene name (default: the file's stem).
        description: free text.
        path: the scene file (``<string>`` for text).
        dim: spatial dimension d.
        mesh: the mesh.
        boundaries: boundary parts by name, in file order.
        loads: body force and point loads.
        material: E, ν, 2-D model.
        law: the rate-type law.
        contacts: the contact parts' conditions, in file order (empty without contact).
        contact_array: the scene wrote them as ``[[contact]]`` (keys ``contact[i].…``) rather
            than one ``[contact]`` table.
        initial: u_0 and σ_0.
        time: T, k and the allowed step halvings.
        formulation: ``"displacement"`` or ``"mixed"`` (resolved from ``"auto"``).
        degree: polynomial degree of the displacement.
        solver: predictor and PETSc options.
        output: what to write.
        hash: sha256 (hex) of the file's bytes (followed by the overrides, when any).
        overrides: the keys set on the command line (``--set``), path → value, in the order
            given (``summary.json`` records them).
        defaulted: the key paths of the model choices left to their defaults (``law.type``,
            ``law.yield_set``, ``material.plane``, ``discretization.formulation``), which
            ``show`` and the run's first line mark (:func:`vpcontact.scene.describe.choices`).
    """

    name: str
    description: str
    path: Path = field(compare=False)
    dim: int
    mesh: MeshSpec
    boundaries: dict[str, BoundaryPart]
    loads: LoadSpec
    material: MaterialSpec
    law: LawSpec
    contacts: tuple[ContactSpec, ...]
    initial: InitialSpec
    time: TimeSpec
    degree: int
    solver: SolverSpec
    output: OutputSpec
    formulation: str = "displacement"
    contact_array: bool = False
    hash: str = field(default="", compare=False)
    locator: Locator | None = field(default=None, compare=False, repr=False)
    overrides: dict[str, Any] = field(default_factory=dict, compare=False)
    defaulted: frozenset[str] = field(default=frozenset(), compare=False)

    @property
    def contact(self) -> ContactSpec:
        """The first contact part's condition (type ``"none"`` without contact)."""
        return self.contacts[0] if self.contacts else ContactSpec()

    def contact_key(self, index: int) -> str:
        """The scene key of the ``index``-th contact table (``contact`` or ``contact[i]``)."""
        return contact_key(index, self.contact_array)

    def contact_part(self, boundary: str | None) -> tuple[int, ContactSpec]:
        """(index, condition) of the contact table on the boundary part ``boundary`` (None: the
        first)."""
        for i, spec in enumerate(self.contacts):
            if boundary is None or spec.boundary == boundary:
                return i, spec
        raise KeyError(boundary)

    def where(self, path: str) -> str:
        """``"file:line"`` of a key path such as ``"boundary.bottom"`` (``"file"`` if unknown;
        ``"--set path"`` for a key set on the command line)."""
        report = self._report()
        origin = report.origin(path)
        if origin is not None:
            return f"{OVERRIDE} {origin}"
        line = self.locator.line(path) if self.locator is not None else None
        return str(self.path) if line is None else f"{self.path}:{line}"

    def _report(self) -> Report:
        """An empty report that locates key paths in this scene's file and overrides."""
        return Report(str(self.path), self.locator, tuple(self.overrides))

    def error(self, path: str, message: str) -> SceneError:
        """A :class:`SceneError` located at a key path, for problems found after loading.

        Example: ``raise scene.error("boundary.bottom", "selects no facets")``.
        """
        report = self._report()
        report.add(path, message)
        return report.error()

    def errors(self, problems: dict[str, str]) -> SceneError:
        """:meth:`error` for several problems at once (key path → message), each located."""
        report = self._report()
        for path, message in problems.items():
            report.add(path, message)
        return report.error()

    def to_toml(self) -> str:
        """The resolved scene as TOML (all defaults written out); reading it gives an equal scene."""
        return write.dump(self)


def load(path: str | os.PathLike, overrides: Sequence[str] = ()) -> Scene:
    """Read, validate and resolve a scene file.

    Args:
        path: the scene file.
        overrides: ``KEY=VALUE`` texts that set scene keys over the file's
            (:mod:`vpcontact.scene.overrides`), checked and located like the file's own.

    Raises:
        SceneError: the file cannot be read (missing, larger than :data:`MAX_BYTES`, not UTF-8)
            or does not describe a valid scene; it lists every problem found.
    """
    path = Path(path)
    try:
        if not path.is_file():
            raise _file_error(path, "no such scene file")
        if path.stat().st_size > MAX_BYTES:
            raise _file_error(path, f"scene file larger than {MAX_BYTES} bytes")
        data = path.read_bytes()
    except OSError as err:
        raise _file_error(path, f"cannot read the scene file: {err.strerror or err}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data[:err.start].count(b"\n") + 1
        raise SceneError([Problem("", line, f"not UTF-8 text (byte {err.start})")],
                         str(path)) from None
    return _resolve_text(text, data, path, overrides)


def loads_text(text: str, path: str | os.PathLike = "<string>",
               overrides: Sequence[str] = ()) -> Scene:
    """Validate and resolve a scene given as TOML text.

    Args:
        text: the TOML source.
        path: shown in messages; relative Gmsh files are found next to it.
        overrides: ``KEY=VALUE`` texts, as for :func:`load`.

    Raises:
        SceneError: listing every problem found.
    """
    return _resolve_text(text, text.encode("utf-8", "surrogatepass"), Path(path), overrides)


def _file_error(path: Path, message: str) -> SceneError:
    return SceneError([Problem("", None, message)], str(path))


def _resolve_text(text: str, data: bytes, path: Path, overrides: Sequence[str] = ()) -> Scene:
    file = str(path)
    if len(data) > MAX_BYTES:
        raise _file_error(path, f"scene text larger than {MAX_BYTES} bytes")
    try:
        table = tomllib.loads(text.removeprefix("\ufeff"))
    except tomllib.TOMLDecodeError as err:
        raise SceneError([_syntax_problem(str(err), text)], file) from None
    except RecursionError:
        raise _file_error(path, "TOML syntax error: values nested too deeply") from None
    locator = Locator(text)
    parsed = [cli_overrides.parse(o) for o in overrides]
    given = {o.path: o.value for o in parsed if isinstance(o, cli_overrides.Override)}
    report = Report(file, locator, tuple(given))
    report.problems += [o for o in parsed if isinstance(o, Problem)]
    report.problems += cli_overrides.apply(table, [o for o in parsed
                                                   if isinstance(o, cli_overrides.Override)])
    fields = read_scene(table, report, path.parent, _default_name(path))
    if report.problems:
        raise report.error()
    if given:  # the run is the file and its overrides: a checkpoint of another is not resumed
        data += b"\n" + OVERRIDE.encode() + b" " + json.dumps(given, default=str).encode()
    return Scene(**fields, path=path, hash=hashlib.sha256(data).hexdigest(), locator=locator,
                 overrides=given)


def _syntax_problem(message: str, text: str) -> Problem:
    """A problem from a tomllib message such as ``Invalid value (at line 3, column 5)``."""
    position = _TOML_POSITION.search(message)
    if position is not None:
        reason = message[:position.start()]
        return Problem("", int(position.group(1)),
                       f"TOML syntax error: {reason} (column {position.group(2)})")
    if _TOML_END.search(message):
        reason = _TOML_END.sub("", message)
        return Problem("", text.count("\n") + 1, f"TOML syntax error: {reason} (at end of file)")
    return Problem("", None, f"TOML syntax error: {message}")


def _default_name(path: Path) -> str:
    """The file's stem, made a valid scene name (``scene`` for text)."""
    stem = re.sub(r"[^A-Za-z0-9_.-]", "_", path.stem)[:64]
    return stem if re.match(r"[A-Za-z0-9]", stem) else "scene"


def bundled() -> dict[str, Path]:
    """The scenes shipped with vpcontact, by name (``vpcontact/scene/bundled/<name>.toml``)."""
    return {p.stem: p for p in sorted(SCENES_DIR.glob("*.toml"))}


def load_bundled(name: str, cells: Sequence[int] | None = None,
                 k: float | None = None) -> Scene:
    """A bundled scene with its built-in mesh's ``cells`` and its step ``k`` replaced (the demos
    run coarser versions of theirs)."""
    path = bundled()[name]
    text = path.read_text()
    if cells is not None:
        text = re.sub(r"(?m)^cells = .*$", f"cells = [{', '.join(str(c) for c in cells)}]", text)
    if k is not None:
        text = re.sub(r"(?m)^k = .*$", f"k = {k}", text)
    return loads_text(text, path)


def resolve(name_or_path: str | os.PathLike) -> Path:
    """The scene file meant by a bundled scene's name (e.g. ``"signorini_2d"``) or a file path.

    An existing file wins over a bundled scene of the same name.

    Raises:
        SceneError: neither a file nor a bundled scene; the message lists the bundled names.
    """
    path = Path(name_or_path)
    if path.is_file():
        return path
    scenes = bundled()
    name = path.stem if path.suffix == ".toml" and path.parent == Path(".") else str(name_or_path)
    if name in scenes:
        return scenes[name]
    raise _file_error(path, f"no such scene file, and no bundled scene named {str(name_or_path)!r}"
                            f"; bundled scenes: {', '.join(scenes) or '(none)'}")
