# SPDX-License-Identifier: MIT
"""Writing a resolved scene back as TOML, with every default spelled out.

A tiny emitter for the scene schema only: strings are TOML basic strings with escapes, floats use
``repr`` (which TOML reads back exactly), plane/box selectors and PETSc options are inline tables,
and expressions are written as their source strings. Reading the output back gives an equal scene.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from typing import Any

from vpcontact.scene.describe import MU_MEANING, choices
from vpcontact.scene.expressions import Expression, ExpressionError, parse
from vpcontact.scene.specs import BoxSelector, ObstacleRotation, ObstacleShape, PlaneSelector

__all__ = ["dump", "key", "value"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_NUMBER = re.compile(r"-?[0-9][0-9.eE+-]*")
_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
            "\r": "\\r"}


def _string(text: str) -> str:
    out = []
    for c in text:
        if c in _ESCAPES:
            out.append(_ESCAPES[c])
        elif ord(c) < 0x20 or ord(c) == 0x7F:
            out.append(f"\\u{ord(c):04x}")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def _expression(expression: Expression) -> str:
    """A number literal if the source is one that reads back the same, else a string."""
    source = expression.source
    if _NUMBER.fullmatch(source):
        try:
            number = tomllib.loads(f"v = {source}")["v"]
            if parse(number, names=()).source == source:
                return source
        except (tomllib.TOMLDecodeError, ExpressionError):
            pass
    return _string(source)


def key(name: str) -> str:
    """A TOML key: bare if possible, else a quoted string."""
    return name if _BARE_KEY.fullmatch(name) else _string(name)


def value(item: Any) -> str:
    """A TOML value for the types a scene holds."""
    if isinstance(item, bool):
        return "true" if item else "false"
    if isinstance(item, (int, float)):
        return repr(item)
    if isinstance(item, str):
        return _string(item)
    if isinstance(item, Expression):
        return _expression(item)
    if isinstance(item, Path):
        return _string(str(item))
    if isinstance(item, (tuple, list)):
        return "[" + ", ".join(value(v) for v in item) + "]"
    if isinstance(item, PlaneSelector):
        entries = {"axis": "xyz"[item.axis], "value": item.value, "tol": item.tol}
        return value({k: v for k, v in entries.items() if v is not None})
    if isinstance(item, BoxSelector):
        return value({"lower": item.lower, "upper": item.upper})
    if isinstance(item, ObstacleShape):
        return value({"shape": item.shape, **dict(item.params)})
    if isinstance(item, ObstacleRotation):
        entries = {"center": item.center, "angle": item.angle, "axis": item.axis}
        return value({k: v for k, v in entries.items() if v is not None})
    if item is None:
        return '"free"'  # a free component of a prescribed displacement
    if isinstance(item, dict):
        if not item:
            return "{}"
        return "{ " + ", ".join(f"{key(k)} = {value(v)}" for k, v in item.items()) + " }"
    raise TypeError(f"cannot write {type(item).__name__} as TOML")


def _table(header: str, entries: dict[str, Any], notes: dict[str, str] | None = None
           ) -> list[str]:
    """The lines of one table; ``notes`` are comments written after their keys' values."""
    notes = notes or {}
    lines = [f"[{header}]"] if header else []
    lines += [f"{key(k)} = {value(v)}" + (f"  # {notes[k]}" if k in notes else "")
              for k, v in entries.items() if v is not None]
    return lines + [""]


def _defaults(scene: Any, table: str) -> dict[str, str]:
    """``{key: "default"}`` for the model choices of ``table`` the scene left to defaults."""
    notes = {"formulation": 'default: "auto" chose it'}
    return {path.split(".")[1]: notes.get(path.split(".")[1], "default")
            for path in scene.defaulted if path.startswith(table + ".")}


def _header(scene: Any) -> list[str]:
    lines = [f"# Resolved scene {scene.name!r} (all defaults written out).",
             f"# {choices(scene)}"]
    if scene.overrides:
        lines.append("# with " + " ".join(f"--set {path}={value(v)}"
                                          for path, v in scene.overrides.items()))
    return lines + [""]


def dump(scene: Any) -> str:
    """The resolved ``scene`` (a :class:`vpcontact.scene.Scene`) as TOML text."""
    mesh, law = scene.mesh, scene.law
    blocks = _header(scene)
    blocks += _table("", {"name": scene.name, "description": scene.description})
    if mesh.builtin:
        blocks += _table("mesh", {"type": mesh.type, "lower": mesh.lower, "upper": mesh.upper,
                                  "cells": mesh.cells, "cell_type": mesh.cell_type,
                                  "diagonal": mesh.diagonal,
                                  "refine": [{"lower": lo, "upper": up} for lo, up in mesh.refine]})
    else:
        blocks += _table("mesh", {"type": mesh.type, "file": mesh.file, "dim": mesh.dim})
    for name, part in scene.boundaries.items():
        blocks += _table(f"boundary.{key(name)}", {
            "kind": part.kind, "tag": part.tag, "plane": part.plane, "box": part.box,
            "where": part.where, "traction": part.traction, "displacement": part.displacement})
    blocks += _table("loads", {"body_force": scene.loads.body_force})
    for point in scene.loads.point:
        blocks += ["[[loads.point]]"] + _table("", {"at": point.at, "force": point.force})
    material = scene.material
    blocks += _table("material", {"E": material.E, "nu": material.nu, "plane": material.plane},
                     _defaults(scene, "material"))
    blocks += _table("law", {"type": law.type, "scheme": law.scheme, "sigma_y": law.sigma_y,
                             "mu_star": law.mu_star, "yield_set": law.yield_set, "a": law.a,
                             "b": law.b}, _defaults(scene, "law"))
    for contact in scene.contacts:
        entries = {
            "type": contact.type, "boundary": contact.boundary, "gap": contact.gap,
            "obstacle": contact.obstacle, "motion": contact.motion,
            "rotation": contact.rotation, "force": contact.force,
            "max_distance": contact.max_distance, "mu": contact.mu,
            "alpha": contact.alpha,
            "normals": None if contact.normals == "body" else contact.normals,
            "friction": None if contact.friction is None else {
                k: v for k, v in (("type", contact.friction.type),
                                  ("coefficient", contact.friction.coefficient),
                                  ("threshold", contact.friction.threshold)) if v is not None}}
        notes = {"mu": MU_MEANING}
        if scene.contact_array:
            blocks += ["[[contact]]"] + _table("", entries, notes)
        else:
            blocks += _table("contact", entries, notes)
    blocks += _table("initial", {"u0": scene.initial.u0, "sigma0": scene.initial.sigma0})
    time = scene.time
    blocks += _table("time", {"T": time.T, "k": time.k, "max_cuts": time.max_cuts,
                                     "scheme": time.scheme, "tolerance": time.tolerance})
    blocks += _table("discretization", {"formulation": scene.formulation, "degree": scene.degree},
                     _defaults(scene, "discretization"))
    blocks += _table("solver", {"predictor": scene.solver.predictor,
                                "linear": scene.solver.linear,
                                "petsc_options": scene.solver.petsc_options})
    output = scene.output
    blocks += _table("output", {"xdmf": output.xdmf, "contact_csv": output.contact_csv,
                                "figures": output.figures, "every": output.every,
                                "checkpoint_every": output.checkpoint_every,
                                "probes": output.probes or None})
    return "\n".join(blocks)
