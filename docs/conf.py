"""Sphinx configuration of dolfinx_ntf's site (``make docs``; Debian's Sphinx 5.3 and 8.1 alike)."""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent))

import ntf_docs  # noqa: E402
from sphinx_gallery.sorting import FileNameSortKey  # noqa: E402

import dolfinx_ntf  # noqa: E402

project = "dolfinx_ntf"
author = "dolfinx_ntf contributors"
copyright = "dolfinx_ntf contributors"
release = version = dolfinx_ntf.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "ntf_docs",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = master_doc = "index"
exclude_patterns = [
    "_build",
    "_gallery_src",
    "_templates",
    "method.md",  # built as method/ (one page per section)
    "demos/*.ipynb",
    "demos/*.py",
    "demos/*.zip",
    "demos/*.md5",
    "demos/*.json",
]
templates_path = ["_templates"]

# Every cross-reference must resolve; types from other packages are not documented here.
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|npt|numpy\.typing|dolfinx|ufl|basix|petsc4py|PETSc|mpi4py|MPI)(\..*)?"),
    (
        r"py:.*",
        r"(collections\.abc|typing|pathlib|logging|os|io|enum|dataclasses|subprocess|types)\..*",
    ),
    (r"py:.*", r"(NDArray|ArrayLike|Callable|Sequence|Iterable|Mapping|Path|Any|NoneType)"),
]

# MyST: Markdown pages, $math$, ::: fences, anchors for ## and ### headings.
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

# autodoc through the top-level names; Google-style docstrings.
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_preserve_defaults = True
autosummary_generate = False
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False
napoleon_attr_annotations = True
python_use_unqualified_type_names = True
add_module_names = False

# The demos as tutorials, run on their coarse meshes (about 2 minutes in all on 2 cores).
sphinx_gallery_conf = {
    "examples_dirs": ["_gallery_src"],
    "gallery_dirs": ["demos"],
    "filename_pattern": r".*\.py",
    "reset_argv": ntf_docs.demo_argv,
    "image_scrapers": (ntf_docs.DemoFigures(), "matplotlib"),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": FileNameSortKey,
    "min_reported_time": 1,
}

# Sphinx 8 cannot pickle the gallery's callables (demo_argv, DemoFigures): the configuration is
# re-read in every build (-E anyway).
suppress_warnings = ["config.cache"]

html_theme = "furo"
html_title = f"dolfinx_ntf {release}"
html_static_path = []
html_show_sourcelink = False

# Docstring faults the site shows but the package has not fixed yet (each a regular expression on
# "location: message"; dropped warnings go to _build/known-warnings.txt). Fix the docstring, then
# remove its line: an entry that matches nothing fails the build.
ntf_known_warnings: list[str] = []

# Every argument of a public callable is described in its docstring (docstring-gaps.txt lists any
# that is not, and the build fails on it).
ntf_require_args = True
