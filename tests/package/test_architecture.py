# SPDX-License-Identifier: MIT
"""The package's shape, as issue 44 fixed it: checked on the source, so that it cannot drift back.

- no import circle between vpcontact's modules (module-level imports, read with :mod:`ast`);
- no function-local ``vpcontact`` import outside ``cli.py`` (they hide circles);
- no module over 600 lines, no function over 80;
- the step solver and the problem name none of the preconditioners of ``solver/pc``;
- the friction laws' names (``"coulomb"``, ``"tresca"``) only in the friction module and the
  scene reader; ``solver/`` and ``output/`` never ask whether a part has friction or what kind
  of contact it is.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

PACKAGE = next(p / "vpcontact" for p in Path(__file__).resolve().parents
               if (p / "vpcontact" / "__init__.py").is_file())
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 80


def _modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module of the package."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join(parts)] = path
    return found


MODULES = _modules()


def _package_of(name: str) -> str:
    return name if MODULES[name].name == "__init__.py" else name.rsplit(".", 1)[0]


def _targets(name: str, node: ast.ImportFrom | ast.Import) -> list[str]:
    """The package modules an import statement of module ``name`` loads."""
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names if alias.name in MODULES]
    base = node.module or ""
    if node.level:
        anchor = _package_of(name).split(".")
        anchor = anchor[:len(anchor) - (node.level - 1)]
        base = ".".join(anchor + ([base] if base else []))
    if not base.startswith("vpcontact"):
        return []
    out = []
    for alias in node.names:
        sub = f"{base}.{alias.name}"
        if sub in MODULES:
            out.append(sub)  # a submodule
        elif base in MODULES:
            out.append(base)  # a name from the module (or the package's __init__)
    return out


def _imports(name: str) -> tuple[set[str], list[tuple[int, str]]]:
    """(modules imported at module level, [(line, target)] of imports inside functions)."""
    tree = ast.parse(MODULES[name].read_text())
    top: set[str] = set()
    local: list[tuple[int, str]] = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                for target in _targets(name, child):
                    (local.append((child.lineno, target)) if in_function else top.add(target))
            inside = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef))
            if isinstance(child, ast.If) and _is_type_checking(child.test):
                continue  # typing-only imports are not executed
            visit(child, inside)

    visit(tree, False)
    top.discard(name)
    return top, local


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            connect(v)
    return found


def test_no_import_circles():
    graph = {name: _imports(name)[0] for name in MODULES}
    assert _cycles(graph) == [], "modules that import each other (directly or round a circle)"


def test_cycle_finder_finds_a_circle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_function_local_package_imports():
    found = [f"{MODULES[name].relative_to(PACKAGE.parent)}:{line}: {target}"
             for name in MODULES if name != "vpcontact.cli"
             for line, target in _imports(name)[1]]
    assert found == [], "imports of vpcontact inside functions:\n" + "\n".join(found)


def test_module_and_function_sizes():
    long_modules, long_functions = [], []
    for name, path in MODULES.items():
        text = path.read_text()
        lines = text.count("\n")
        if lines > MAX_MODULE_LINES:
            long_modules.append(f"{path.relative_to(PACKAGE.parent)}: {lines} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                length = node.end_lineno - node.lineno + 1
                if length > MAX_FUNCTION_LINES:
                    long_functions.append(
                        f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {node.name} {length}")
    assert long_modules == [], f"modules over {MAX_MODULE_LINES} lines: {long_modules}"
    assert long_functions == [], f"functions over {MAX_FUNCTION_LINES} lines: {long_functions}"


def _source(relative: str) -> str:
    return (PACKAGE / relative).read_text()


@pytest.mark.parametrize("owner", ["solver/step_solver.py", "solver/problem.py"])
def test_step_solver_and_problem_name_no_preconditioner(owner):
    pc = PACKAGE / "solver" / "pc"
    assert pc.is_dir(), "the research preconditioners live in vpcontact/solver/pc/"
    # the preconditioners' modules (not the package's plumbing: its factory and context)
    names = {p.stem for p in pc.glob("*.py")} - {"__init__", "factory", "context"}
    names |= {"p_multigrid", "star_smoother", "star_schur", "coarse_schur", "PMultigrid",
              "StarSmoother", "StarSchur", "CoarseSchur", "BlockPreconditioner"}
    text = _source(owner)
    named = sorted(n for n in names if re.search(rf"\b{n}\b", text))
    assert named == [], f"{owner} names preconditioners {named}"


def _is_friction_home(path: Path) -> bool:
    relative = path.relative_to(PACKAGE).as_posix()
    return "friction" in relative or relative.startswith("scene/")


def test_friction_laws_named_only_at_home():
    found = [f"{path.relative_to(PACKAGE.parent)}:{i}"
             for path in MODULES.values() if not _is_friction_home(path)
             for i, line in enumerate(path.read_text().splitlines(), 1)
             if re.search(r"""["'](coulomb|tresca)["']""", line, re.IGNORECASE)]
    assert found == [], f"friction laws named outside their module and the scene reader: {found}"


#: what a switch on friction or on the contact kind looks like in code
SWITCHES = re.compile(r"""getattr\([^)]*["']friction["']|\.friction\b|\bisinstance\([^)]*"""
                      r"""(Signorini|NormalCompliance|Coulomb|Tresca|Friction)""")


@pytest.mark.parametrize("folder", ["solver", "output"])
def test_no_friction_or_contact_kind_switches(folder):
    found = []
    for path in sorted((PACKAGE / folder).rglob("*.py")):
        code = _code_only(path.read_text())
        found += [f"{path.relative_to(PACKAGE.parent)}:{i}: {line.strip()}"
                  for i, line in enumerate(code.splitlines(), 1) if SWITCHES.search(line)]
    assert found == [], "switches on friction or the contact kind:\n" + "\n".join(found)


def _code_only(text: str) -> str:
    """``text`` with comments and docstrings blanked (line numbers kept)."""
    tree = ast.parse(text)
    lines = text.splitlines()
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) and isinstance(
                getattr(body[0], "value", None), ast.Constant) and isinstance(body[0].value.value, str):
            for i in range(body[0].lineno - 1, body[0].end_lineno):
                lines[i] = ""
    return "\n".join(re.sub(r"#.*$", "", line) for line in lines)
