"""The package's layout follows docs/architecture.md.

The layer contracts themselves (dependencies point down, no cycles) are import-linter's job
(`lint-imports`, run by .ci/run); these tests check what it does not: private names stay inside
their subpackage, the top of the package holds only the public entry points, and every layer says
what it holds and may import.
"""

from __future__ import annotations

import ast
from pathlib import Path

import sigmatau

PACKAGE = Path(sigmatau.__file__).parent
SUBPACKAGES = {"core", "uncertainty", "stats", "noise", "prep", "spectral", "compare", "imu", "io", "pipeline", "report",
               "scale", "cli", "compat", "stream"}
#: The public paths users import (README, docs, ``sigmatau.__all__``), kept at the top.
ENTRY_POINTS = {"__init__", "__main__", "_version", "errors", "analysis", "batch", "checks", "chunked",
                "confidence", "datasets", "filterchain", "generate", "noiseid", "outputs", "plots", "units"}


def _module_name(path: Path) -> list[str]:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return parts[:-1] if parts[-1] == "__init__" else parts


def _imports(path: Path):
    """``(target module parts, imported name)`` of every ``from … import …`` in ``path``."""
    here = _module_name(path)
    package = here if path.name == "__init__.py" else here[:-1]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level:
            base = package[: len(package) - (node.level - 1)]
            target = base + (node.module.split(".") if node.module else [])
        else:
            target = (node.module or "").split(".")
        if target[0] == "sigmatau":
            for alias in node.names:
                yield target, alias.name


def _subpackage(parts: list[str]) -> str:
    return parts[1] if len(parts) > 1 and parts[1] in SUBPACKAGES else ""


def _private(parts: list[str], name: str) -> bool:
    dunder = name.startswith("__") and name.endswith("__")
    return (name.startswith("_") and not dunder) or any(
        p.startswith("_") and not (p.startswith("__") and p.endswith("__")) and p != "_version" for p in parts[1:])


def test_no_private_name_crosses_a_subpackage():
    crossing = []
    for path in sorted(PACKAGE.rglob("*.py")):
        mine = _subpackage(_module_name(path))
        for target, name in _imports(path):
            if _private(target, name) and _subpackage(target) != mine:
                crossing.append(f"{'.'.join(_module_name(path))}: from {'.'.join(target)} import {name}")
    assert crossing == []


def test_the_top_of_the_package_holds_only_the_entry_points():
    top_modules = {p.stem for p in PACKAGE.glob("*.py")}
    folders = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert top_modules == ENTRY_POINTS
    assert folders == SUBPACKAGES


def test_every_layer_says_what_it_holds_and_may_import():
    for name in sorted(SUBPACKAGES):
        doc = ast.get_docstring(ast.parse((PACKAGE / name / "__init__.py").read_text(encoding="utf-8"))) or ""
        assert "may import" in doc.lower() and len(doc) > 150, name


def test_lint_imports_as_the_readme_prints_it():
    """`lint-imports` (README, Documentation): the layer contracts of pyproject.toml hold."""
    import os
    import shutil
    import subprocess
    import sys

    import pytest

    readme = (PACKAGE.parents[1] / "README.md").read_text(encoding="utf-8")
    assert "`lint-imports`" in readme
    bin_dir = Path(sys.executable).parent
    exe = shutil.which("lint-imports", path=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}")
    if exe is None:
        pytest.skip("import-linter is not installed (it comes with the test extra)")
    run = subprocess.run(["bash", "-c", "lint-imports"], cwd=PACKAGE.parents[1], capture_output=True, text=True,
                         env=dict(os.environ, PATH=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}"),
                         timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    assert "0 broken" in run.stdout
