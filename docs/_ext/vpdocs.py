# SPDX-License-Identifier: MIT
"""Local Sphinx extension: pages generated from the code when the manual is built.

* ``_generated/scene_keys.md``: the scene-key reference, from the registry
  :mod:`vpcontact.scene.keys` (the lists the scene reader checks files against).
* ``_generated/demos/<demo>.md``: one literate page per script in ``demos/``: the module
  docstring as the page's prose, then the script itself (``literalinclude``; nothing is run).

The files are rewritten only when their text changes, so incremental builds stay incremental.
"""

from __future__ import annotations

import ast
from pathlib import Path

from vpcontact.scene.keys import reference_markdown

ROOT = Path(__file__).resolve().parents[2]


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def demo_page(script: Path, out_dir: Path) -> str:
    """The Markdown page of one demo script: its docstring, then its code."""
    docstring = ast.get_docstring(ast.parse(script.read_text(encoding="utf-8"))) or ""
    lines = docstring.splitlines()
    if not lines or not lines[0].startswith("# "):
        lines = [f"# {script.stem}", ""] + lines
    relative = Path("..", "..", "..", "demos", script.name) if out_dir.name == "demos" else script
    lines += ["", "## The script", "",
              f"Run it with `.venv/bin/python demos/{script.name}` (`--help` lists its options; "
              "under `CI=1` it uses small meshes).", "",
              f"```{{literalinclude}} {relative.as_posix()}", ":language: python",
              ":linenos:", "```", ""]
    return "\n".join(lines)


def generate(app) -> None:
    out = Path(app.srcdir) / "_generated"
    _write(out / "scene_keys.md", reference_markdown())
    scripts = sorted((ROOT / "demos").glob("*.py"))
    entries = []
    for script in scripts:
        _write(out / "demos" / f"{script.stem}.md", demo_page(script, out / "demos"))
        entries.append(script.stem)
    index = ["# Demos", "",
             "Literate scripts in `demos/`: each page is the script's header (the model, the data, "
             "what the figures show and what could be extended) followed by its code. The test "
             "suite runs every demo (`tests/demos/test_demos.py`).", "",
             "```{toctree}", ":maxdepth: 1", ""] + entries + ["```", ""]
    _write(out / "demos" / "index.md", "\n".join(index))


def setup(app):
    app.connect("builder-inited", generate)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
