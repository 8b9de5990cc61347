# SPDX-License-Identifier: MIT
"""Safe expressions of x and t for scene files, compiled to numpy and to UFL.

Scene files are untrusted, so their expressions are parsed with :mod:`ast` and only a whitelist
is accepted: numbers, ``x[i]``, ``t``, ``pi``, ``e``, ``+ - * / **``, comparisons (chains too),
``and or not``, ``a if c else b`` and the functions in :data:`FUNCTIONS`. Nothing is ever
evaluated by Python itself (no eval/exec/compile): the tree is walked. All numbers are floats, so
``9**9**9**9`` is ``inf``, not a hanging big-integer power.
"""

from __future__ import annotations

import ast
import difflib
import math
from dataclasses import dataclass, field
from typing import Iterable, Optional

import numpy as np
import ufl

from vpcontact.errors import InputError

MAX_LENGTH = 2000
MAX_NODES = 500
MAX_DEPTH = 50

#: name -> (arity (None: 2 or more), numpy function, UFL function)
FUNCTIONS = {
    "abs": (1, np.abs, abs), "sqrt": (1, np.sqrt, ufl.sqrt), "exp": (1, np.exp, ufl.exp),
    "log": (1, np.log, ufl.ln), "sin": (1, np.sin, ufl.sin), "cos": (1, np.cos, ufl.cos),
    "tan": (1, np.tan, ufl.tan), "asin": (1, np.arcsin, ufl.asin),
    "acos": (1, np.arccos, ufl.acos), "atan": (1, np.arctan, ufl.atan),
    "sinh": (1, np.sinh, ufl.sinh), "cosh": (1, np.cosh, ufl.cosh),
    "tanh": (1, np.tanh, ufl.tanh), "sign": (1, np.sign, ufl.sign),
    "atan2": (2, np.arctan2, ufl.atan_2), "pow": (2, np.power, lambda a, b: a ** b),
    "min": (None, np.minimum, ufl.min_value), "max": (None, np.maximum, ufl.max_value),
}
CONSTANTS = {"pi": math.pi, "e": math.e}
_COMPARE = {ast.Lt: (np.less, ufl.lt), ast.LtE: (np.less_equal, ufl.le),
            ast.Gt: (np.greater, ufl.gt), ast.GtE: (np.greater_equal, ufl.ge),
            ast.Eq: (np.equal, ufl.eq), ast.NotEq: (np.not_equal, ufl.ne)}
_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
           ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b,
           ast.Pow: lambda a, b: a ** b}


class ExpressionError(InputError):
    """An expression that is not allowed; ``column`` is the 0-based offset of the culprit."""

    def __init__(self, text: str, column: Optional[int], reason: str):
        self.text, self.column, self.reason = text, column, reason
        where = f" at column {column + 1}" if column is not None else ""
        super().__init__(f"{reason}{where} in {text!r}")


@dataclass(frozen=True)
class Expression:
    """A checked expression; evaluate it with :meth:`numpy`, :meth:`ufl` or :meth:`value`."""

    source: str
    names: frozenset
    is_boolean: bool
    components_used: frozenset
    tree: ast.AST = field(repr=False, compare=False)

    @property
    def depends_on_time(self) -> bool:
        return "t" in self.names

    @property
    def is_constant(self) -> bool:
        return not self.names

    def numpy(self, x: np.ndarray, t: float = 0.0) -> np.ndarray:
        """Values at points x of shape (d, N): shape (N,) (bool for conditions)."""
        x = np.asarray(x, dtype=np.float64)
        n = x.shape[1] if x.ndim == 2 else 1
        with np.errstate(all="ignore"):
            out = _Lower(x, float(t), numpy=True).visit(self.tree)
        return np.broadcast_to(np.asarray(out, dtype=bool if self.is_boolean else np.float64),
                               (n,)).copy()

    def ufl(self, x, t):
        """The expression in UFL (a condition for boolean expressions)."""
        out = _Lower(x, t, numpy=False).visit(self.tree)
        return ufl.as_ufl(out) if isinstance(out, float) else out

    def value(self, t: float = 0.0) -> float:
        """The value of an expression without x."""
        if "x" in self.names:
            raise ExpressionError(self.source, None, "a constant is required here; x is not allowed")
        with np.errstate(all="ignore"):
            return float(_Lower(np.zeros((3, 1)), float(t), numpy=True).visit(self.tree))


def parse(text, *, names: Iterable[str] = ("x", "t"), dim: Optional[int] = None) -> Expression:
    """Check ``text`` (a string or a number) and return it as an :class:`Expression`."""
    if isinstance(text, bool) or not isinstance(text, (str, int, float)):
        raise ExpressionError(repr(text), None, f"expected a number or an expression string, "
                              f"got {type(text).__name__}")
    source = text if isinstance(text, str) else repr(float(text))
    if not source.strip():
        raise ExpressionError(source, None, "empty expression")
    if len(source) > MAX_LENGTH:
        raise ExpressionError(source[:40] + "...", None, f"expression longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(source.strip(), mode="eval").body
    except SyntaxError as err:
        raise ExpressionError(source, (err.offset or 1) - 1, "syntax error") from None
    except (RecursionError, MemoryError, ValueError):
        raise ExpressionError(source, None, "expression too deeply nested") from None
    checker = _Checker(source, frozenset(names), dim)
    kind = checker.check(tree, 0)
    return Expression(source, frozenset(checker.used), kind == "bool",
                      frozenset(checker.components), tree)


class _Checker:
    """Walks the tree once: whitelist, names, arity, types ('num' or 'bool'), size limits."""

    def __init__(self, source: str, allowed: frozenset, dim: Optional[int]):
        self.source, self.allowed, self.dim = source, allowed, dim
        self.used: set = set()
        self.components: set = set()
        self.nodes = 0

    def fail(self, node, reason: str):
        raise ExpressionError(self.source, getattr(node, "col_offset", None), reason)

    def want(self, node, depth: int, kind: str, what: str) -> None:
        if self.check(node, depth) != kind:
            self.fail(node, f"{what} must be {'a condition' if kind == 'bool' else 'a number'}")

    def check(self, node, depth: int) -> str:
        self.nodes += 1
        if self.nodes > MAX_NODES:
            self.fail(node, f"expression has more than {MAX_NODES} parts")
        if depth > MAX_DEPTH:
            self.fail(node, f"expression nested deeper than {MAX_DEPTH}")
        d = depth + 1
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                self.fail(node, f"only numbers are allowed as literals, got {node.value!r}")
            try:
                float(node.value)
            except OverflowError:
                self.fail(node, "number literal too large")
            return "num"
        if isinstance(node, ast.Name):
            return self.name(node)
        if isinstance(node, ast.Subscript):
            return self.subscript(node)
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.Not):
                self.want(node.operand, d, "bool", "the operand of 'not'")
                return "bool"
            if not isinstance(node.op, (ast.UAdd, ast.USub)):
                self.fail(node, "operator not allowed")
            self.want(node.operand, d, "num", "the operand of a sign")
            return "num"
        if isinstance(node, ast.BinOp):
            if type(node.op) not in _BINARY:
                self.fail(node, f"operator '{type(node.op).__name__}' not allowed (use + - * / **)")
            self.want(node.left, d, "num", "an arithmetic operand")
            self.want(node.right, d, "num", "an arithmetic operand")
            return "num"
        if isinstance(node, ast.BoolOp):
            for value in node.values:
                self.want(value, d, "bool", "an operand of 'and'/'or'")
            return "bool"
        if isinstance(node, ast.Compare):
            for op in node.ops:
                if type(op) not in _COMPARE:
                    self.fail(node, "only < <= > >= == != comparisons are allowed")
            for value in [node.left, *node.comparators]:
                self.want(value, d, "num", "a compared value")
            return "bool"
        if isinstance(node, ast.IfExp):
            self.want(node.test, d, "bool", "the test of 'if'")
            self.want(node.body, d, "num", "a branch of 'if'")
            self.want(node.orelse, d, "num", "a branch of 'if'")
            return "num"
        if isinstance(node, ast.Call):
            return self.call(node, d)
        self.fail(node, f"'{type(node).__name__}' is not allowed in an expression")

    def name(self, node: ast.Name) -> str:
        if node.id in CONSTANTS:
            return "num"
        if node.id == "x" and "x" in self.allowed:
            self.fail(node, "x must be indexed, e.g. x[0]")
        if node.id in ("x", "t") and node.id not in self.allowed:
            why = "must not depend on time" if node.id == "t" else "must not depend on position"
            self.fail(node, f"'{node.id}' is not allowed here: this expression {why}")
        if node.id == "t":
            self.used.add("t")
            return "num"
        known = sorted((self.allowed - {"x"}) | set(CONSTANTS) | set(FUNCTIONS))
        hint = ["t"] if node.id == "time" and "t" in self.allowed else \
            difflib.get_close_matches(node.id, known, 1)
        suggestion = f"; did you mean '{hint[0]}'?" if hint else ""
        self.fail(node, f"unknown name '{node.id}' (allowed: x[i], t, pi, e and functions)"
                        f"{suggestion}")

    def subscript(self, node: ast.Subscript) -> str:
        if not (isinstance(node.value, ast.Name) and node.value.id == "x"):
            self.fail(node, "only x[i] may be indexed")
        if "x" not in self.allowed:
            self.fail(node, "'x' is not allowed here: this expression must not depend on position")
        index = node.slice
        if not (isinstance(index, ast.Constant) and type(index.value) is int and index.value >= 0):
            self.fail(node, "x[i] needs a non-negative integer i")
        if self.dim is not None and index.value >= self.dim:
            self.fail(node, f"x[{index.value}] does not exist in {self.dim}-D")
        if index.value > 2:
            self.fail(node, f"x[{index.value}] does not exist (at most x[2])")
        self.used.add("x")
        self.components.add(index.value)
        return "num"

    def call(self, node: ast.Call, depth: int) -> str:
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            name = node.func.id if isinstance(node.func, ast.Name) else "this"
            hint = difflib.get_close_matches(name, list(FUNCTIONS), 1)
            self.fail(node, f"unknown function '{name}'" + (f"; did you mean '{hint[0]}'?" if hint else ""))
        if node.keywords:
            self.fail(node, "keyword arguments are not allowed")
        arity = FUNCTIONS[node.func.id][0]
        n = len(node.args)
        if (arity is None and n < 2) or (arity is not None and n != arity):
            need = "2 or more" if arity is None else str(arity)
            self.fail(node, f"{node.func.id}() takes {need} argument(s), got {n}")
        for arg in node.args:
            if isinstance(arg, ast.Starred):
                self.fail(arg, "starred arguments are not allowed")
            self.want(arg, depth, "num", f"an argument of {node.func.id}()")
        return "num"


class _Lower(ast.NodeVisitor):
    """Evaluates a checked tree with numpy arrays or builds its UFL expression."""

    def __init__(self, x, t, numpy: bool):
        self.x, self.t, self.np = x, t, numpy

    def visit_Constant(self, node):
        return float(node.value)

    def visit_Name(self, node):
        return CONSTANTS[node.id] if node.id in CONSTANTS else self.t

    def visit_Subscript(self, node):
        return self.x[node.slice.value]

    def visit_UnaryOp(self, node):
        value = self.visit(node.operand)
        if isinstance(node.op, ast.Not):
            return np.logical_not(value) if self.np else ufl.Not(value)
        return -value if isinstance(node.op, ast.USub) else value

    def visit_BinOp(self, node):
        left, right = self.visit(node.left), self.visit(node.right)
        if self.np and isinstance(node.op, ast.Pow):
            return np.power(np.float64(left), right)  # floats: inf, never big integers
        if self.np and isinstance(node.op, ast.Div):
            return np.divide(np.float64(left), right)
        return _BINARY[type(node.op)](left, right)

    def visit_BoolOp(self, node):
        values = [self.visit(v) for v in node.values]
        out = values[0]
        for v in values[1:]:
            if self.np:
                out = (np.logical_and if isinstance(node.op, ast.And) else np.logical_or)(out, v)
            else:
                out = (ufl.And if isinstance(node.op, ast.And) else ufl.Or)(out, v)
        return out

    def visit_Compare(self, node):
        values = [self.visit(node.left)] + [self.visit(c) for c in node.comparators]
        out = None
        for op, a, b in zip(node.ops, values[:-1], values[1:]):
            np_op, ufl_op = _COMPARE[type(op)]
            term = np_op(a, b) if self.np else ufl_op(a, b)
            if out is None:
                out = term
            else:
                out = np.logical_and(out, term) if self.np else ufl.And(out, term)
        return out

    def visit_IfExp(self, node):
        test, body, orelse = self.visit(node.test), self.visit(node.body), self.visit(node.orelse)
        return np.where(test, body, orelse) if self.np else ufl.conditional(test, body, orelse)

    def visit_Call(self, node):
        _, np_f, ufl_f = FUNCTIONS[node.func.id]
        args = [self.visit(a) for a in node.args]
        f = np_f if self.np else ufl_f
        if node.func.id in ("min", "max"):
            out = args[0]
            for a in args[1:]:
                out = f(out, a)
            return out
        if not self.np and all(isinstance(a, float) for a in args):
            return float(FUNCTIONS[node.func.id][1](*args))
        return f(*args)
