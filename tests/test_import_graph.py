# SPDX-License-Identifier: MIT
"""The package's import graph, read from the source without importing it: no import circles
between vpcontact's modules (module-level imports), and the model, the outputs, the studies and
the problem's side of the solver import vpcontact at module level only (a function-local import
hides a circle, or stands for one)."""

from __future__ import annotations

import ast
from pathlib import Path

#: the package's folder (the first parent of this file's folder that holds it)
PACKAGE = next(p / "vpcontact" for p in Path(__file__).resolve().parents
               if (p / "vpcontact" / "__init__.py").is_file())
#: the modules whose vpcontact imports must all be at module level: the model, the outputs and
#: the problem's side of the solver (the step solver and its preconditioners have their own
#: restructuring, issue 44)
MODULE_LEVEL_ONLY = ("vpcontact.model.", "vpcontact.output.", "vpcontact.solver.problem",
                     "vpcontact.solver.builders", "vpcontact.solver.support_forces",
                     "vpcontact.solver.time_scheme", "vpcontact.solver.bdf2",
                     "vpcontact.solver.stepping", "vpcontact.solver.error_estimate",
                     "vpcontact.solver.held", "vpcontact.solver.loads",
                     "vpcontact.solver.dirichlet", "vpcontact.solver.variables",
                     "vpcontact.studies.")


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in PACKAGE.rglob("*.py")}


def _imported(node: ast.AST, module: str, modules: dict) -> set[str]:
    """The vpcontact modules an import statement loads (``from a import b`` loads a, and a.b
    where that is a module)."""
    names = set()
    if isinstance(node, ast.Import):
        names = {alias.name for alias in node.names}
    elif isinstance(node, ast.ImportFrom):
        base = node.module or ""
        if node.level:
            package = module.split(".")
            if not modules[module].name == "__init__.py":
                package = package[:-1]
            package = package[:len(package) - node.level + 1]
            base = ".".join(package + ([base] if base else []))
        names = {base} | {f"{base}.{alias.name}" for alias in node.names}
    return {n for n in names if n in modules}


def _graph(top_level_only: bool = True):
    modules = _modules()
    graph, local = {}, {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        top = set()
        for node in tree.body:
            if isinstance(node, ast.If):  # (if TYPE_CHECKING: …)
                continue
            top |= _imported(node, name, modules)
        graph[name] = top - {name}
        inner = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for sub in ast.walk(node):
                    inner |= _imported(sub, name, modules)
        local[name] = inner
    return graph, local


def _cycles(graph: dict) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, result = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                result.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return result


def _without_packages(graph: dict) -> dict:
    """The graph between modules, a package's __init__ left out where it only re-exports (an
    import of ``vpcontact.model.x`` runs ``vpcontact.model`` first, but that is no circle of
    the modules' own)."""
    packages = {n for n in graph if (PACKAGE.parent / n.replace(".", "/") / "__init__.py").is_file()}
    return {n: {m for m in deps if m not in packages} for n, deps in graph.items()
            if n not in packages}


def test_no_import_circles():
    graph, _ = _graph()
    cycles = _cycles(_without_packages(graph))
    assert not cycles, f"import circles: {cycles}"


def test_no_function_local_imports():
    _, local = _graph()
    found = {m: sorted(deps) for m, deps in local.items()
             if deps and m.startswith(MODULE_LEVEL_ONLY)}
    assert not found, f"function-local vpcontact imports: {found}"
