# SPDX-License-Identifier: MIT
"""The safe expression evaluator: numpy and UFL agree, hostile or malformed text is refused with
its column, and random input never escapes as anything but ExpressionError."""

import math
import random
import time

import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh as dmesh
from mpi4py import MPI

from vpcontact.scene import ExpressionError, parse

VALID = [
    "1 + 2*x[0] - x[1]**2 / 4",
    "sqrt(1 + x[0]**2) * exp(-t) + log(2 + x[1])",
    "sin(pi*x[0]) * cos(x[1]) + tan(0.3) + atan2(x[1] + 1, x[0] + 2)",
    "x[0] if x[1] > 0.5 else -x[0]",
    "1.0 if 0.25 < x[0] <= 0.75 and not x[1] < 0.1 else 0.0",
    "min(x[0], x[1], 0.3) + max(x[0], 2*x[1]) + abs(x[0] - 0.5)",
    "sinh(x[0]) + cosh(x[1]) + tanh(t) + sign(x[0] - 0.5) + pow(x[1] + 1, 1.5)",
    "asin(x[0] / 2) + acos(x[1] / 2) + atan(x[0]) + e**x[1]",
    "-10*t",
    3.5,
    2,
]


@pytest.fixture(scope="module")
def square():
    return dmesh.create_unit_square(MPI.COMM_WORLD, 6, 6)


@pytest.mark.parametrize("text", VALID)
def test_numpy_and_ufl_agree_at_quadrature_points(square, text):
    expr = parse(text, dim=2)
    t = fem.Constant(square, 0.7)
    if expr.is_constant:  # no domain to evaluate on: a UFL literal
        assert float(expr.ufl(ufl.SpatialCoordinate(square), t)) == expr.value()
        return
    points = np.array([[0.2, 0.3], [0.6, 0.1], [0.25, 0.65]])  # reference triangle points
    compiled = fem.Expression(expr.ufl(ufl.SpatialCoordinate(square), t), points)
    num_cells = square.topology.index_map(2).size_local
    cells = np.arange(num_cells, dtype=np.int32)
    from_ufl = compiled.eval(cells).reshape(-1)
    xq = fem.Expression(ufl.SpatialCoordinate(square), points).eval(cells).reshape(-1, 2)
    from_numpy = expr.numpy(xq.T, 0.7)
    assert from_numpy.shape == (len(xq),)
    assert np.allclose(from_ufl, from_numpy, rtol=1e-13, atol=1e-13)


def test_assembled_integral_of_a_polynomial():
    mesh = dmesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    expr = parse("3*x[0]**2 + 2*x[1]*t", dim=2)
    t = fem.Constant(mesh, 2.0)
    local = fem.assemble_scalar(fem.form(expr.ufl(ufl.SpatialCoordinate(mesh), t) * ufl.dx))
    assert mesh.comm.allreduce(local, op=MPI.SUM) == pytest.approx(1.0 + 2.0)


def test_properties_and_constants():
    e = parse("x[0] + 2*t", dim=3)
    assert e.names == {"x", "t"} and e.depends_on_time and not e.is_constant
    assert e.components_used == {0} and not e.is_boolean
    c = parse("sqrt(10)", names=())
    assert c.is_constant and c.value() == pytest.approx(math.sqrt(10))
    assert parse("x[1] > 0 or x[0] < 1").is_boolean
    assert parse("10*t", names=("t",)).value(0.5) == 5.0
    assert parse("9**9**9**9", names=()).value() == math.inf  # floats: no big-integer power
    cond = parse("x[0] < 0.5").numpy(np.array([[0.2, 0.8], [0.0, 0.0]]))
    assert cond.dtype == bool and cond.tolist() == [True, False]


@pytest.mark.parametrize("text, message", [
    ("__import__('os')", r"unknown function '__import__'"),
    ("().__class__", r"'Attribute' is not allowed"),
    ("x.__class__", r"'Attribute' is not allowed"),
    ("lambda: 1", r"'Lambda' is not allowed"),
    ("[1, 2]", r"'List' is not allowed"),
    ("'a'", r"only numbers are allowed"),
    ("x[0:1]", r"x\[i\] needs a non-negative integer"),
    ("x[-1]", r"x\[i\] needs a non-negative integer"),
    ("x[2]", r"x\[2\] does not exist in 2-D"),
    ("open('f')", r"unknown function 'open'"),
    ("print(1)", r"unknown function 'print'"),
    ("sqr(2)", r"unknown function 'sqr'; did you mean 'sqrt'\?"),
    ("time * 2", r"unknown name 'time'.*did you mean 't'\?"),
    ("y + 1", r"unknown name 'y' .*at column 1"),
    ("1 + (x[0]", r"syntax error"),
    ("x + 1", r"x must be indexed"),
    ("True + 1", r"only numbers are allowed"),
    ("(x[0] < 1) + 2", r"an arithmetic operand must be a number"),
    ("1 if x[0] else 2", r"the test of 'if' must be a condition"),
    ("atan2(1)", r"atan2\(\) takes 2 argument\(s\), got 1"),
    ("max(1)", r"max\(\) takes 2 or more"),
    ("sqrt(x=1)", r"keyword arguments are not allowed"),
    ("x[0] % 2", r"operator 'Mod' not allowed"),
    ("", r"empty expression"),
    ("   ", r"empty expression"),
    ("1" * 2001, r"longer than 2000 characters"),
    ("-" * 300 + "1", r"nested deeper than 50|more than 500 parts|too deeply nested"),
    ("+".join(["x[0]"] * 400), r"more than 500 parts|nested deeper"),
])
def test_refused_with_a_reason(text, message):
    with pytest.raises(ExpressionError, match=message):
        parse(text, dim=2)


def test_column_of_the_culprit():
    with pytest.raises(ExpressionError) as info:
        parse("1 + 2*foo", dim=2)
    assert info.value.column == 6 and "at column 7" in str(info.value)


@pytest.mark.parametrize("names, text, message", [
    (("x",), "x[0] * t", r"'t' is not allowed here: this expression must not depend on time"),
    (("t",), "x[0] * t", r"'x' is not allowed here: this expression must not depend on position"),
    ((), "t", r"'t' is not allowed here"),
])
def test_names_of_the_context(names, text, message):
    with pytest.raises(ExpressionError, match=message):
        parse(text, names=names, dim=2)


@pytest.mark.parametrize("value", [None, [1, 2], True, {"a": 1}])
def test_non_expression_values(value):
    with pytest.raises(ExpressionError, match="expected a number or an expression string"):
        parse(value)


def test_value_refuses_position_dependence():
    with pytest.raises(ExpressionError, match="a constant is required"):
        parse("x[0]").value()


def test_random_text_only_ever_raises_expression_error():
    """Seeded fuzzing over a grammar-like alphabet: parse or ExpressionError, fast, nothing else."""
    rng = random.Random(20261123)
    atoms = ["x[0]", "x[1]", "x[7]", "t", "pi", "e", "1", "2.5", "1e308", "0", "sqrt", "max",
             "min", "atan2", "__class__", "import", "lambda", "os", "'s'", "[", "]", "(", ")",
             "+", "-", "*", "/", "**", "<", "==", "and", "or", "not", "if", "else", ",", ".",
             ":", "%", "@", "~", "x", "y", "9" * 50, " "]
    parsed = 0
    for _ in range(3000):
        text = " ".join(rng.choice(atoms) for _ in range(rng.randint(1, 12)))
        start = time.perf_counter()
        try:
            expr = parse(text, dim=2)
        except ExpressionError:
            pass
        else:
            parsed += 1
            with np.errstate(all="ignore"):
                expr.numpy(np.array([[0.1, 0.9], [0.2, 0.4]]), 0.3)
        assert time.perf_counter() - start < 1.0, text
    assert parsed > 50, "the fuzzer must also produce valid expressions"
