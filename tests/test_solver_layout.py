# SPDX-License-Identifier: MIT
"""The step solver's layout (issue 44): the step solver and the problem name no preconditioner
of ``vpcontact/solver/pc/`` (they come from its one factory); no module of the solver's
linear-algebra side is over 600 lines nor has a function over 80; none imports vpcontact inside a
function; and the preconditioners import no circle (``coarse_schur`` and ``p_multigrid``)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import vpcontact.solver

SOLVER = Path(vpcontact.solver.__file__).resolve().parent
PC = SOLVER / "pc"
#: the solver's modules that compose SNES and its linear solvers (the problem's own module and
#: the time loop's are checked with the problem's restructuring)
OWN = sorted([*(SOLVER / name for name in (
    "step_solver.py", "step_options.py", "assembly.py", "convergence.py", "retries.py",
    "line_search.py",
    "vi_bounds.py", "vi_solver.py", "vi_linear.py", "linear.py", "near_nullspace.py",
    "snes_options.py", "option_reads.py", "__init__.py")), *PC.glob("*.py")])
PRECONDITIONERS = ("p_multigrid", "star_smoother", "star_schur", "coarse_schur", "fieldsplit",
                   "PMultigrid", "StarSmoother", "StarSchur", "CoarseSchur",
                   "BlockPreconditioner", "CoarseSpace")


def _tree(path: Path) -> ast.Module:
    return ast.parse(path.read_text(), filename=str(path))


def _code_names(path: Path) -> str:
    """The module's code without its docstrings and comments: names and strings."""
    tree = _tree(path)
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if (isinstance(body, list) and body and isinstance(body[0], ast.Expr)
                and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)):
            body[0] = ast.Pass()
    return ast.unparse(tree)


@pytest.mark.parametrize("name", ["step_solver.py", "problem.py"])
def test_the_step_solver_and_the_problem_name_no_preconditioner(name):
    code = _code_names(SOLVER / name)
    named = [pc for pc in PRECONDITIONERS if re.search(rf"\b{pc}\b", code)]
    assert not named, f"{name} names {named}: ask vpcontact.solver.pc's factory instead"


@pytest.mark.parametrize("path", OWN, ids=lambda p: p.name)
def test_modules_and_functions_are_small(path):
    lines = len(path.read_text().splitlines())
    assert lines <= 600, f"{path.name}: {lines} lines"
    long = [(node.name, node.end_lineno - node.lineno + 1) for node in ast.walk(_tree(path))
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
            and node.end_lineno - node.lineno + 1 > 80]
    assert not long, f"{path.name}: functions over 80 lines {long}"


@pytest.mark.parametrize("path", OWN, ids=lambda p: p.name)
def test_no_function_local_vpcontact_import(path):
    local = [(node.name, sub.lineno) for node in ast.walk(_tree(path))
             if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
             for sub in ast.walk(node)
             if (isinstance(sub, ast.ImportFrom) and (sub.module or "").startswith("vpcontact"))
             or (isinstance(sub, ast.Import)
                 and any(alias.name.startswith("vpcontact") for alias in sub.names))]
    assert not local, f"{path.name}: vpcontact imported inside functions at {local}"


def _imports(path: Path) -> set[str]:
    """The vpcontact modules ``path`` imports (``from a import b`` counts as a.b where a.b is a
    module of this package)."""
    found = set()
    for node in ast.walk(_tree(path)):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name.startswith("vpcontact"))
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("vpcontact"):
            for alias in node.names:
                module = f"{node.module}.{alias.name}"
                as_path = SOLVER.parents[1] / Path(*module.split("."))
                is_module = (as_path.with_suffix(".py").exists()
                             or (as_path / "__init__.py").exists())
                found.add(module if is_module else node.module)
    return found


def _module(path: Path) -> str:
    parts = path.resolve().relative_to(SOLVER.parents[1]).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def test_the_step_solver_s_modules_import_no_circle():
    """Among the step solver's modules and the preconditioners (``from a import b`` counted as
    an import of the module a.b): no circle, and coarse_schur does not import p_multigrid."""
    graph = {_module(path): _imports(path) for path in OWN if path != SOLVER / "__init__.py"}

    def reaches(start: str, goal: str, seen: set) -> bool:
        for nxt in graph.get(start, ()):
            if nxt == goal or (nxt not in seen and reaches(nxt, goal, seen | {nxt})):
                return True
        return False

    circles = [module for module in graph if reaches(module, module, set())]
    assert not circles, f"import circles through {circles}"
    assert "vpcontact.solver.pc.p_multigrid" not in graph["vpcontact.solver.pc.coarse_schur"]
