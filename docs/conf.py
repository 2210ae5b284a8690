"""Sphinx configuration of the sigmatau documentation site.

Build (the README's Documentation section; CI runs the same line through .ci/run)::

    python -m pip install -e ".[docs]" && python -m sphinx -W --keep-going -b html docs docs/_build/html

The API reference is generated from the numpydoc docstrings (autosummary, recursive, driven by each
public module's ``__all__``); a check at the end of reading (``check_api_coverage`` below) fails
the build when a name of a public ``__all__`` has no entry in it. The gallery (docs/examples) runs
at build time with sphinx-gallery; the Markdown pages in docs/*.md are read with MyST as they are.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
from pathlib import Path

import sigmatau

HERE = Path(__file__).resolve().parent
PACKAGE = Path(sigmatau.__file__).resolve().parent

# Figures of the gallery and of any module imported while building: no display, no GUI backend.
os.environ.setdefault("MPLBACKEND", "Agg")

# -- project -----------------------------------------------------------------------------------
project = "sigmatau"
author = "sigmatau developers"
copyright = "sigmatau developers (BSD-3-Clause)"
release = sigmatau.__version__
version = ".".join(release.split(".")[:2])

# -- general -----------------------------------------------------------------------------------
extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    # MathJax from the package, not from a CDN: the formulas render offline.
    "sphinx-mathjax-offline",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
# examples/ holds the gallery's sources (sphinx-gallery reads them; its output is auto_examples/).
exclude_patterns = ["_build", "examples", "Thumbs.db", ".DS_Store", "**.ipynb_checkpoints"]
language = "en"
# MyST's dollar math stays off (a `$` in a page stays a plain character); headings get anchors so
# that pages can link to sections.
myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3

# -- API reference: autosummary + autodoc + numpydoc ------------------------------------------
autosummary_generate = True
# The members of a module are its __all__ (re-exported names included), as `from m import *`.
autosummary_ignore_module_all = False
# autosummary imports every submodule of a package it recurses into; ``python -m sigmatau``'s
# __main__ would run the command line.
autosummary_mock_imports = ["sigmatau.__main__"]
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"  # the numpydoc "Parameters" sections say the types
autodoc_inherit_docstrings = False
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = False

# -- HTML ----------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"sigmatau {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_depth": 3,
    "show_toc_level": 2,
    "header_links_before_dropdown": 6,
    "navbar_align": "left",
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version", "theme-version"],
}
html_sidebars = {"index": [], "guide/index": []}
html_show_sourcelink = False

# -- gallery -------------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",  # every example runs at build time
    "ignore_pattern": r"__init__\.py",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "min_reported_time": 0,
    "show_memory": False,
    "plot_gallery": "True",
    "only_warn_on_example_error": False,  # an example that raises fails the build
    "reset_modules": ("matplotlib",),
    "capture_repr": ("_repr_html_", "__repr__"),
    "matplotlib_animations": False,
    "write_computation_times": False,  # the times are in the build log; the page would load scripts from CDNs
}


# -- the API reference covers every public name ---------------------------------------------------
# The public modules are the package's top-level entry points: the package itself, the top layer
# of the layer contract in pyproject.toml (the entry-point modules, `__main__` aside), the
# submodules the package re-exports in its __all__, and these.
EXTRA_PUBLIC_MODULES = ("sigmatau.io", "sigmatau.imu", "sigmatau.prep", "sigmatau.spectral",
                        "sigmatau.compare", "sigmatau.compat.allantools")


def _entry_point_layer() -> set[str]:
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10: every top-level module file but the error layer
        return {f"sigmatau.{info.name}" for info in pkgutil.iter_modules([str(PACKAGE)])
                if not info.ispkg and not info.name.startswith("_") and info.name != "errors"}
    with open(HERE.parent / "pyproject.toml", "rb") as f:
        contracts = tomllib.load(f)["tool"]["importlinter"]["contracts"]
    layers = next(c["layers"] for c in contracts if c.get("type") == "layers")
    return {name.strip() for name in layers[0].split("|")} - {"sigmatau.__main__"}


def public_modules() -> list[str]:
    """Names of the public modules whose ``__all__`` the reference must cover."""
    names = {"sigmatau", *_entry_point_layer(), *EXTRA_PUBLIC_MODULES}
    for name in sigmatau.__all__:
        if isinstance(getattr(sigmatau, name), type(sigmatau)):
            names.add(f"sigmatau.{name}")
    return sorted(names)


def class_aliases() -> dict[str, str]:
    """``{public name: first public name}`` of the classes exported by more than one public module.

    A class gets its full page once, under the first module (the package root first); its other
    public names get a short page pointing there (autodoc would describe one class twice).
    """
    first: dict[int, str] = {}
    aliases: dict[str, str] = {}
    for modname in public_modules():  # "sigmatau" sorts first
        module = importlib.import_module(modname)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name, None)
            if isinstance(obj, type):
                fullname = f"{modname}.{name}"
                aliases[fullname] = first.setdefault(id(obj), fullname)
    return {name: target for name, target in aliases.items() if name != target}


autosummary_context = {"class_aliases": class_aliases()}


def check_api_coverage(app, env) -> None:
    """Warn (an error under -W) for each public module or ``__all__`` name the reference lacks."""
    from sphinx.util import logging

    logger = logging.getLogger("sigmatau.apicheck")
    objects = env.get_domain("py").objects
    missing: list[str] = []
    for modname in public_modules():
        if modname not in objects:
            missing.append(f"{modname} (module)")
            continue
        module = importlib.import_module(modname)
        for name in getattr(module, "__all__", ()):
            if f"{modname}.{name}" not in objects:
                missing.append(f"{modname}.{name}")
    for name in missing:
        logger.warning("public name missing from the API reference: %s", name, type="sigmatau",
                       subtype="api")
    if not missing:
        logger.info("API reference: every name of the public __all__ lists is documented")


# -- constants: the doc comment where they are defined, never their type's docstring ------------
def _attr_doc(name: str, obj: object) -> list[str]:
    """The ``#:`` doc comment of the module of sigmatau that defines ``name`` as ``obj``."""
    import sys

    from sphinx.pycode import ModuleAnalyzer
    from sphinx.errors import PycodeError

    for modname in sorted(m for m in list(sys.modules) if m == "sigmatau" or m.startswith("sigmatau.")):
        if getattr(sys.modules[modname], name, None) is not obj:
            continue
        try:
            docs = ModuleAnalyzer.for_module(modname).find_attr_docs()
        except PycodeError:
            continue
        if ("", name) in docs:
            return list(docs[("", name)])
    return []


def document_constants(app, what, name, obj, options, lines) -> None:
    """A re-exported constant shows the comment that documents it where it is defined."""
    if what not in ("data", "attribute") or isinstance(obj, type) or callable(obj):
        return
    type_doc = getattr(type(obj), "__doc__", None)
    type_doc = " ".join(type_doc.split()) if isinstance(type_doc, str) else ""
    own = " ".join(" ".join(lines).split())
    if own and own not in type_doc:
        return  # documented where autodoc looked
    lines[:] = _attr_doc(name.rpartition(".")[2], obj)


# -- the Notes page lists every Markdown page at the top of docs/ ---------------------------------
NOTES_PAGE = "guide/notes"


def notes_toctree(app, docname, source) -> None:
    """Append to guide/notes.md a toctree of docs/*.md (index aside), so that a new page joins it."""
    if docname == NOTES_PAGE:
        pages = sorted(p.stem for p in HERE.glob("*.md") if p.stem != "index")
        source[0] += "\n```{toctree}\n:maxdepth: 1\n\n" + "".join(f"/{page}\n" for page in pages) + "```\n"


def notes_outdated(app, env, added, changed, removed) -> list[str]:
    """Read the Notes page again on every build: a page added to docs/ since the last build
    changes its toctree although its own file did not change."""
    return [NOTES_PAGE]


def setup(app):
    app.connect("source-read", notes_toctree)
    app.connect("env-get-outdated", notes_outdated)
    app.connect("autodoc-process-docstring", document_constants, priority=100)  # before numpydoc
    app.connect("env-check-consistency", check_api_coverage)
