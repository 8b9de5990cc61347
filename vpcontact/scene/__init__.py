# SPDX-License-Identifier: MIT
"""Stage 1, the scene: a TOML file in, a validated :class:`Scene` and then a built :class:`Model` out.

* :func:`load` / :func:`loads_text` read an untrusted scene file (``tomllib``), check every key
  and value and raise one :class:`SceneError` listing all problems with their lines
  (:mod:`.files`, with :mod:`.read` and :mod:`.physics` reading the tables, :mod:`.schema`
  the typed checks, :mod:`.locate` the line numbers, :mod:`.specs` the frozen section
  dataclasses, :mod:`.write` the TOML written back by ``vpcontact show``).
* Expressions of x and t in a scene (loads, gaps, obstacles) are parsed against a whitelist and
  compiled to numpy and UFL without ``eval`` (:mod:`.expressions`).
* :func:`build` turns a :class:`Scene` into a :class:`Model`: the dolfinx mesh, the tagged
  boundary parts and the :class:`~vpcontact.solver.QuasistaticProblem` (:mod:`.builder`).

The bundled scenes (:func:`bundled`) are the TOML files in ``bundled/``.
"""

from vpcontact.scene.builder import Model, build
from vpcontact.scene.expressions import Expression, ExpressionError, parse
from vpcontact.scene.files import (DEFAULT_SCENE, MAX_BYTES, BoundaryPart, BoxSelector, ContactSpec,
                                  InitialSpec, LawSpec, LoadSpec, MaterialSpec, MeshSpec,
                                  OutputSpec, PlaneSelector, PointLoad, Problem, Scene, SceneError,
                                  SolverSpec, TimeSpec, bundled, load, load_bundled,
                                  loads_text, resolve)

__all__ = ["DEFAULT_SCENE", "MAX_BYTES", "BoundaryPart", "BoxSelector", "ContactSpec", "Expression",
           "ExpressionError", "InitialSpec", "LawSpec", "LoadSpec", "MaterialSpec", "MeshSpec",
           "Model", "OutputSpec", "PlaneSelector", "PointLoad", "Problem", "Scene", "SceneError",
           "SolverSpec", "TimeSpec", "build", "bundled", "load", "load_bundled", "loads_text", "parse", "resolve"]
