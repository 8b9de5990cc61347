# SPDX-License-Identifier: MIT
"""Reading the physics tables of a scene: ``[law]`` and ``[contact]``.

* ``[law]``: σ̇ = E ε̇ + G(σ, ε) with G = 0 (``elastic``), Perzyna's
  G = -(1/μ*) E(σ - P_K σ) (``perzyna``) or G = aσ + bε (``linear``).
* ``[contact]``: Signorini's condition u_ν ≤ g (a gap g(x) or a rigid obstacle {φ ≤ 0}) or normal
  compliance σ_ν = -(1/μ)(u_ν - g)_+^α (paper eq. (15)); ``[[contact]]``, an array of such
  tables, for several contact parts (each on its own boundary part).
"""

from __future__ import annotations

from vpcontact.scene.expressions import Expression
from vpcontact.scene.keys import default, keys
from vpcontact.scene.schema import (Check, Table, at_least, between, constant_value, greater,
                                    type_name)
from vpcontact.scene.locate import join
from vpcontact.scene.specs import (SHAPES, ContactSpec, FrictionSpec, LawSpec, ObstacleRotation,
                                   ObstacleShape)

__all__ = ["CONTACT_KEYS", "LAW_KEYS", "read_contacts", "read_law"]

# The keys each table accepts come from the registry (vpcontact/scene/keys.py), which the
# manual's scene-key reference is generated from.
LAW_KEYS = keys("law")
CONTACT_KEYS = keys("contact")
FRICTION_KEYS = keys("contact.friction")
ROTATION_KEYS = keys("contact.rotation")
#: The keys of a built-in obstacle shape's table: "shape" and every shape's parameters.
OBSTACLE_KEYS = keys("contact.obstacle")
LAW_TYPES = ("elastic", "perzyna", "linear")
SCHEMES = ("explicit", "implicit", "linearized")
DEFAULT_SCHEME = {"elastic": "explicit", "perzyna": "implicit", "linear": "explicit"}
PERZYNA_KEYS = ("sigma_y", "mu_star", "yield_set")
LINEAR_KEYS = ("a", "b")
CONTACT_TYPES = ("none", "signorini", "normal_compliance")
DEFAULT_MAX_DISTANCE = default("contact", "max_distance")
#: The gap of a normal-compliance part that gives neither gap nor foundation surface (the
#: foundation touches the face at the start); a Signorini part must give one or an obstacle.
COMPLIANT_GAP = 0


def read_law(top: Table, dim: int | None) -> LawSpec:
    """``[law]`` (absent: elastic)."""
    t = top.section("law", LAW_KEYS)
    law = t.choice("type", LAW_TYPES, default("law", "type"))
    scheme = t.choice("scheme", SCHEMES, DEFAULT_SCHEME.get(law, "explicit"))
    if law != "perzyna":
        for key in PERZYNA_KEYS:
            t.forbid(key, "only for type = 'perzyna'")
    if law != "linear":
        for key in LINEAR_KEYS:
            t.forbid(key, "only for type = 'linear'")
    if law == "perzyna":
        return LawSpec(law, scheme, sigma_y=_constant(t, "sigma_y", greater(0)),
                       mu_star=_constant(t, "mu_star", greater(0)),
                       yield_set=_yield_set(t, dim))
    if law == "linear":
        return LawSpec(law, scheme, a=_constant(t, "a"), b=_constant(t, "b"))
    return LawSpec(law, scheme)


def _yield_set(t: Table, dim: int | None) -> str | None:
    """Von Mises by default in every dimension (a default must not change meaning with the
    dimension); 3-D scenes may name the paper's printed set instead, whose uniaxial yield
    stress is σ_Y/√2."""
    if dim == 3 or dim is None:
        return t.choice("yield_set", ("paper", "von_mises"), default("law", "yield_set"))
    if t.data.get("yield_set", "von_mises") != "von_mises":
        t.add("yield_set", "only 'von_mises' is available in 1-D and 2-D (|σ| ≤ σ_Y in 1-D, "
                           "von Mises in plane stress and plane strain); 'paper' is a 3-D "
                           "option")
        return None
    return "von_mises"


def _constant(t: Table, key: str, check: Check | None = None) -> Expression | None:
    """A required constant expression (a number or e.g. ``"sqrt(10)"``), finite and checked."""
    expression = t.expr(key, (), None)
    if expression is None:
        return None
    value = constant_value(t.report, t.at(key), expression)
    message = check(value) if value is not None and check is not None else None
    if message is not None:
        t.add(key, message)
    return expression if value is not None and message is None else None


def read_contacts(top: Table, dim: int | None) -> tuple[tuple[ContactSpec | None, ...], bool]:
    """``[contact]`` or ``[[contact]]``: (the contact parts' specs, in file order — ``None`` for a
    table whose type is invalid; empty without contact or with type none —, whether the scene
    wrote an array of tables)."""
    raw = top.data.get("contact")
    if raw is None:
        return (), False
    if isinstance(raw, list):
        specs = []
        for i, item in enumerate(raw):
            where = join(top.at("contact"), i)
            if not isinstance(item, dict):
                top.report.add(where, f"expected a table, got {type_name(item)}")
                specs.append(None)
                continue
            t = Table(top.report, where, item, CONTACT_KEYS)
            if t.data.get("type") == "none":
                t.add("type", "'none' is for a single [contact] table; leave this one out")
                specs.append(None)
                continue
            specs.append(_read_contact(t, dim))
        if not raw:
            top.add("contact", "an empty array: give at least one [[contact]] table")
        return tuple(specs), True
    t = top.table("contact", CONTACT_KEYS)
    if t is None:
        return (None,), False
    spec = _read_contact(t, dim)
    return ((), False) if spec is not None and spec.type == "none" else ((spec,), False)


def _read_contact(t: Table, dim: int | None) -> ContactSpec | None:
    """One contact table; ``None`` if its type is invalid."""
    kind = t.choice("type", CONTACT_TYPES)
    if kind is None:
        return None
    if kind == "none":
        for key in CONTACT_KEYS[1:]:
            t.forbid(key, "not used with type = 'none'")
        return ContactSpec()
    boundary = t.string("boundary")
    if kind == "signorini":
        for key in ("mu", "alpha"):
            t.forbid(key, "only for type = 'normal_compliance'")
    else:
        t.forbid("normals", "only for type = 'signorini' (a rigid obstacle's normals)")
    if not t.has("obstacle"):
        t.forbid("normals", "only with an obstacle (a gap alone has no surface to take "
                            "normals from)")
    if t.has("force"):
        t.forbid("normals", "not with an obstacle driven by a force (its equation balances "
                            "the forces along the body's normals only)")
    normals = t.choice("normals", ("body", "obstacle"), default("contact", "normals"))
    if dim == 1 and normals == "obstacle":
        t.add("normals", "a 1-D body touches at its end point, along its own axis: the "
                         "obstacle's normal there is the body's (leave normals out)")
    if dim == 1 and t.has("friction"):
        t.forbid("friction", "a 1-D body has no tangential direction to slip in")
    friction = _friction(t, dim) if t.has("friction") and dim != 1 else None
    if t.has("obstacle"):
        if t.has("gap"):
            t.add("gap", "give either gap or obstacle, not both")
        if kind == "normal_compliance":
            for key in ("motion", "rotation", "force"):
                t.forbid(key, "a foundation surface stays where it is (moving obstacles are "
                              "for type = 'signorini')")
        if t.has("force"):
            for key in ("motion", "rotation"):
                t.forbid(key, "an obstacle driven by a force moves along the force (give "
                              "either force or a prescribed motion)")
        obstacle = _obstacle(t, dim, moving=kind == "signorini" and not t.has("force"))
        moves = kind == "signorini"
        motion = t.exprs("motion", ("t",), dim, dim) if t.has("motion") and moves else None
        rotation = _rotation(t, dim) if t.has("rotation") and moves else None
        force = t.exprs("force", ("t",), dim, dim) if t.has("force") and moves else None
        return ContactSpec(kind, boundary, obstacle=obstacle, motion=motion, rotation=rotation,
                           force=force, friction=friction, normals=normals,
                           max_distance=t.number("max_distance", DEFAULT_MAX_DISTANCE,
                                                 check=greater(0)),
                           mu=t.number("mu", check=greater(0)) if kind != "signorini" else None,
                           alpha=(t.number("alpha", default("contact", "alpha"),
                                           check=between(0.0, 1.0, "(]"))
                                  if kind != "signorini" else None))
    t.forbid("max_distance", "only with an obstacle")
    t.forbid("motion", "only with an obstacle")
    t.forbid("rotation", "only with an obstacle")
    t.forbid("force", "only with an obstacle")
    if kind == "signorini":
        if not t.has("gap"):
            t.report.add(t.path, "a Signorini part needs a gap or an obstacle: without either "
                                 "it has no foundation to touch; write gap = 0 for a rigid "
                                 "foundation that touches this face at the start, or give "
                                 "the obstacle")
        gap = _gap(t, dim) if t.has("gap") else None
        return ContactSpec(kind, boundary, gap=gap, friction=friction)
    return ContactSpec(kind, boundary, gap=_gap(t, dim), mu=t.number("mu", check=greater(0)),
                       alpha=t.number("alpha", default("contact", "alpha"),
                                      check=between(0.0, 1.0, "(]")),
                       friction=friction)


def _friction(t: Table, dim: int | None) -> FrictionSpec | None:
    """``friction = { type = "coulomb", coefficient = 0.3 }`` or
    ``{ type = "tresca", threshold = "<expression of x>" }``."""
    f = t.table("friction", FRICTION_KEYS)
    if f is None:
        return None
    kind = f.choice("type", ("coulomb", "tresca"))
    if kind == "coulomb":
        f.forbid("threshold", "only for type = 'tresca' (Coulomb's threshold is coefficient × "
                              "the contact pressure)")
        coefficient = f.number("coefficient", check=at_least(0))
        return None if coefficient is None else FrictionSpec(kind, coefficient=coefficient)
    if kind == "tresca":
        f.forbid("coefficient", "only for type = 'coulomb'")
        threshold = f.expr("threshold", ("x",), dim)
        if threshold is not None and threshold.is_constant:
            value = constant_value(f.report, f.at("threshold"), threshold)
            message = at_least(0)(value) if value is not None else None
            if message is not None:
                f.add("threshold", message)
                return None
        return None if threshold is None else FrictionSpec(kind, threshold=threshold)
    return None


def _obstacle(t: Table, dim: int | None, moving: bool) -> Expression | ObstacleShape | None:
    """``obstacle``: a level-set expression φ(x) (φ(x, t) for a moving rigid obstacle) or a
    built-in shape ``{ shape = "sphere", center = [...], radius = R }`` (see ``SHAPES``)."""
    if not isinstance(t.data.get("obstacle"), dict):
        return t.expr("obstacle", ("x", "t") if moving else ("x",), dim)
    s = t.table("obstacle", OBSTACLE_KEYS)
    shape = s.choice("shape", tuple(SHAPES))
    if shape is None:
        return None
    for key in s.data:
        if key != "shape" and key not in SHAPES[shape]:
            s.add(key, f"not a parameter of shape {shape!r} (its parameters: "
                       f"{', '.join(SHAPES[shape])})")
    params = []
    for key in SHAPES[shape]:
        if key == "radius":
            value = s.number("radius", check=greater(0))
        elif key == "axis" and dim is not None and dim < 3:
            s.forbid("axis", "a cylinder's axis is the z axis in 2-D (a circle)")
            continue
        else:
            value = s.numbers(key, dim)
            if value is not None and key in ("normal", "axis") and not any(value):
                s.add(key, "must not be the zero vector")
                value = None
            if value is not None and key == "semi_axes" and min(value) <= 0:
                s.report.add(join(s.at(key), int(min(range(len(value)), key=value.__getitem__))),
                             "semi-axes must be > 0")
                value = None
        if value is None:
            return None
        params.append((key, value))
    return ObstacleShape(shape, tuple(params))


def _rotation(t: Table, dim: int | None) -> ObstacleRotation | None:
    """``rotation = { center = [...], angle = "expr of t", axis = [...] }`` (``axis`` in 3-D
    only: a 2-D rotation is about the point ``center``, counter-clockwise)."""
    if dim == 1:
        t.add("rotation", "a 1-D obstacle cannot rotate (use motion)")
        return None
    r = t.table("rotation", ROTATION_KEYS)
    if r is None:
        return None
    center = r.numbers("center", dim)
    angle = r.expr("angle", ("t",), dim)
    axis = None
    if dim == 2:
        r.forbid("axis", "a 2-D rotation is about the point 'center' (in the plane)")
    elif dim == 3:
        axis = r.numbers("axis", 3)
        if axis is not None and not any(axis):
            r.add("axis", "must not be the zero vector")
        if axis is None or not any(axis):
            return None
    if center is None or angle is None:
        return None
    return ObstacleRotation(tuple(center), angle, None if axis is None else tuple(axis))


def _gap(t: Table, dim: int | None) -> Expression | None:
    """The initial gap g(x) (normal compliance: default 0); a constant gap must be ≥ 0."""
    gap = t.expr("gap", ("x",), dim, COMPLIANT_GAP)
    if gap is None or not gap.is_constant:
        return gap
    value = constant_value(t.report, t.at("gap"), gap)
    message = at_least(0)(value) if value is not None else None
    if message is not None:
        t.add("gap", message)
    return gap if value is not None and message is None else None
