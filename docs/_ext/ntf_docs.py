"""Sphinx helpers of dolfinx_ntf's site: pages made from the sources at build time, and checks.

Generated (never edited, ignored by git):
    - ``method/``: ``docs/method.md`` split into one page per numbered section, § numbers kept and
      every "§3.4" in the text linked to its section;
    - ``api/``: one page per public name of ``dolfinx_ntf.__all__`` and
      ``dolfinx_ntf.calculix.__all__``, documented through the top-level name (module moves inside
      the package do not touch the site) and grouped by topic;
    - ``_gallery_src/``: the demos as sphinx-gallery examples (their docstring's first line becomes
      the page title).

Checks (warnings, so ``-W`` makes them errors): a public name or a public member without a
docstring; with ``ntf_require_args = True`` also a parameter missing from its ``Args:`` section
(the list of those is written to ``_build/docstring-gaps.txt`` in every build).
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import logging as logging_module
import re
import shutil
import sys
from pathlib import Path

from sphinx.application import Sphinx
from sphinx.util import logging

logger = logging.getLogger(__name__)

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent

#: API pages by topic: (title, module, names). Names of ``__all__`` that no group lists go to
#: "Other names", so a new public name always gets a page.
API_GROUPS: list[tuple[str, str, list[str]]] = [
    (
        "Problem, surfaces and pairs",
        "dolfinx_ntf",
        ["ContactProblem", "ContactPair", "FacetSurface", "NodeSurface", "FaceNodesSurface"],
    ),
    (
        "Pressure-overclosure laws and friction",
        "dolfinx_ntf",
        [
            "PressureOverclosureLaw",
            "LinearLaw",
            "DynamicLinearLaw",
            "ExponentialLaw",
            "TabularLaw",
            "Friction",
            "ContactDamping",
            "SurfaceInteraction",
        ],
    ),
    (
        "Discrete springs",
        "dolfinx_ntf",
        [
            "DiscreteSprings",
            "AxialSpring",
            "DirectionalSpring",
            "LinearSpringLaw",
            "TabularSpringLaw",
        ],
    ),
    ("Incompatible-mode hexahedra (C3D8I)", "dolfinx_ntf", ["IncompatibleModes"]),
    (
        "Thermal contact",
        "dolfinx_ntf",
        [
            "ThermalContactProblem",
            "ThermoMechanicalContact",
            "CellTemperature",
            "GapConductance",
            "solve_staggered",
            "thermal_solver",
            "thermal_strain",
            "thermoelastic_stress",
            "thermal_results",
            "ThermalResults",
            "heat_flux_field",
        ],
    ),
    (
        "Plasticity",
        "dolfinx_ntf",
        ["J2Plasticity", "FiniteStrainJ2Plasticity", "IsotropicHardening", "mandel_strain"],
    ),
    (
        "Rigid master surfaces",
        "dolfinx_ntf",
        ["RigidSurface", "RigidPlane", "RigidSphere", "RigidCylinder", "SignedDistanceSurface"],
    ),
    (
        "Solvers, static and dynamic steps",
        "dolfinx_ntf",
        [
            "ContactNewtonSolver",
            "ContactSNESSolver",
            "NewtonSolver",
            "ActiveSetNewtonSolver",
            "StaticStep",
            "IncrementResult",
            "DynamicStep",
            "kinetic_energy",
            "contact_modes",
            "Modes",
            "ContactSolverError",
            "ContactConvergenceError",
            "ContactDivergenceError",
            "log_progress",
        ],
    ),
    (
        "Analyses made of steps",
        "dolfinx_ntf",
        [
            "AnalysisStep",
            "run_steps",
            "Load",
            "Amplitude",
            "AddPair",
            "RemovePair",
            "ChangeFriction",
            "SetSmallSliding",
        ],
    ),
    (
        "Linear constraints",
        "dolfinx_ntf",
        [
            "LinearConstraint",
            "LinearConstraintBlock",
            "GlobalLinearConstraint",
            "global_constraints",
            "input_node_ids",
            "serendipity_constraints",
            "Tie",
            "tie_constraints",
        ],
    ),
    (
        "Results and post-processing",
        "dolfinx_ntf",
        [
            "contact_results",
            "ContactResults",
            "ContactFields",
            "ContactWriter",
            "contact_force",
            "contact_area",
            "reaction",
            "BoundaryPressure",
        ],
    ),
    ("Elasticity helpers", "dolfinx_ntf", ["small_strain_stress", "component_bc"]),
    (
        "CalculiX decks: running and exporting",
        "dolfinx_ntf.calculix",
        ["run_job", "JobResult", "JobError", "build_model", "write_inp", "compare_job"],
    ),
    (
        "CalculiX decks: reading",
        "dolfinx_ntf.calculix",
        [
            "read_deck",
            "Deck",
            "Step",
            "DeckError",
            "ELEMENT_TYPES",
            "external_faces",
            "face_nodes",
            "node_surface_faces",
            "surface_nodes",
        ],
    ),
    (
        "CalculiX result files",
        "dolfinx_ntf.calculix",
        [
            "read_dat",
            "write_dat",
            "DatBlock",
            "format_block",
            "node_print_blocks",
            "el_print_blocks",
            "contact_print_blocks",
            "read_cel",
            "ContactElementsFile",
            "format_contact_elements",
            "run_ccx",
            "CcxError",
            "read_ccx_dat",
            "dat_block",
            "dat_times",
            "read_sta",
        ],
    ),
]

#: Modules documented whole (their own ``__all__``): what the examples import besides the two
#: top-level namespaces.
API_MODULES: list[tuple[str, str]] = [
    ("Continuum contact in UFL", "dolfinx_ntf.fem.continuum"),
    ("Continuum contact by steps", "dolfinx_ntf.solvers.continuum"),
    ("Measures of a contact solution", "dolfinx_ntf.fem.measures"),
    ("Elasticity in UFL (3D, plane strain, plane stress)", "dolfinx_ntf.fem.elasticity"),
    ("Axisymmetric elasticity in UFL", "dolfinx_ntf.fem.axisymmetric"),
    ("Per-cell 2D formulations (quasi-axisymmetric models)", "dolfinx_ntf.fem.plane_sections"),
    ("Incompatible-mode hexahedra: the numpy kernel", "dolfinx_ntf.kernels.incompatible_modes"),
    ("Wedges as collapsed hexahedra: the numpy kernel", "dolfinx_ntf.kernels.collapsed_wedges"),
    ("ccx's two-point wedge rule: the numpy kernel", "dolfinx_ntf.kernels.wedge_rule"),
    (
        "Strain energy density over increments: the numpy kernel",
        "dolfinx_ntf.kernels.strain_energy",
    ),
    ("Natural frequencies with contact", "dolfinx_ntf.solvers.modes"),
    ("Newton corrections with an earlier factorization", "dolfinx_ntf.solvers.factor_reuse"),
    ("Nodal velocities of dynamic steps (contact damping)", "dolfinx_ntf.contact.velocity"),
    ("XDMF files of hexahedra and wedges", "dolfinx_ntf.outputs.xdmf_cells"),
    ("XDMF files of 18-node prism meshes", "dolfinx_ntf.outputs.prism_xdmf"),
    ("Meshes from gmsh", "dolfinx_ntf.meshes.gmsh_io"),
    ("C3D15's space: the serendipity wedge on 18-node prisms", "dolfinx_ntf.fem.serendipity_wedge"),
    (
        "Faces of 18-node prism meshes: pressures and contact surfaces",
        "dolfinx_ntf.fem.wedge_faces",
    ),
    ("The punch geometry of the demos", "dolfinx_ntf.meshes.punch"),
    ("The Hertz geometry of the demos", "dolfinx_ntf.meshes.hertz"),
    ("The plane-strain Hertz geometry of the demos", "dolfinx_ntf.meshes.cylinder"),
    ("dolfinx 0.5.2 / 0.9 helpers", "dolfinx_ntf.compat"),
]

#: Modules of :data:`API_MODULES` whose public names are checked like ``dolfinx_ntf``'s.
ARGS_CHECKED_MODULES = (
    "dolfinx_ntf.fem.axisymmetric",
    "dolfinx_ntf.fem.continuum",
    "dolfinx_ntf.fem.measures",
    "dolfinx_ntf.fem.plane_sections",
    "dolfinx_ntf.fem.pressure_recovery",
    "dolfinx_ntf.fem.serendipity_wedge",
    "dolfinx_ntf.fem.wedge_faces",
    "dolfinx_ntf.kernels.incompatible_modes",
    "dolfinx_ntf.outputs.prism_xdmf",
    "dolfinx_ntf.kernels.strain_energy",
    "dolfinx_ntf.solvers.continuum",
    "dolfinx_ntf.solvers.factor_reuse",
)


def public_names(module: str) -> list[str]:
    """The names of ``module.__all__`` that get an API page (not ``__version__``)."""
    return [name for name in importlib.import_module(module).__all__ if not name.startswith("__")]


def _write(path: Path, text: str) -> None:
    """Write ``text`` unless the file holds it already (Sphinx and sphinx-gallery go by mtime)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


# ---------------------------------------------------------------------------------------------
# The method, one page per section


_SECTION = re.compile(r"^## (\d+)\. (.+)$", re.M)
_SUBSECTION = re.compile(r"^### (\d+)\.(\d+) (.+)$", re.M)
_CITE = re.compile(r"§(\d+(?:\.\d+)?)")


def _slug(title: str) -> str:
    """A file name from a heading: its first five words, lower case."""
    words = re.sub(r"[^a-z0-9 ]+", "", title.lower().replace("'s", "").replace("-", " ")).split()
    return "-".join(words[:5])


def _link_citations(text: str, labels: set[str]) -> str:
    """Turn ``§3.4`` into a link to section 3.4, outside code spans and fenced blocks."""
    out, fenced = [], False
    for line in text.split("\n"):
        if line.startswith("```"):
            fenced = not fenced
        if fenced or line.startswith(("#", "(")):
            out.append(line)
            continue
        pieces = line.split("`")
        for i in range(0, len(pieces), 2):  # even pieces are outside inline code

            def link(m: re.Match) -> str:
                label = "method-" + m.group(1).replace(".", "-")
                return f"{{ref}}`§{m.group(1)} <{label}>`" if label in labels else m.group(0)

            pieces[i] = _CITE.sub(link, pieces[i])
        out.append("`".join(pieces))
    return "\n".join(out)


def split_method(source: Path, target: Path) -> list[str]:
    """Split ``method.md`` at its ``## N.`` headings into ``target/NN-slug.md`` and an index."""
    text = source.read_text()
    heads = list(_SECTION.finditer(text))
    intro = text[: heads[0].start()]
    labels = {f"method-{m.group(1)}" for m in heads}
    labels |= {f"method-{m.group(1)}-{m.group(2)}" for m in _SUBSECTION.finditer(text)}
    pages = []
    for k, head in enumerate(heads):
        end = heads[k + 1].start() if k + 1 < len(heads) else len(text)
        body = text[head.end() : end]
        body = _SUBSECTION.sub(
            lambda m: (
                f"(method-{m.group(1)}-{m.group(2)})=\n## {m.group(1)}.{m.group(2)} {m.group(3)}"
            ),
            body,
        )
        name = f"{int(head.group(1)):02d}-{_slug(head.group(2))}"
        page = f"(method-{head.group(1)})=\n# {head.group(1)}. {head.group(2)}\n{body}"
        _write(target / f"{name}.md", _link_citations(page, labels))
        pages.append(name)
    title, _, rest = intro.partition("\n")
    rest = re.sub(r"\nContents:.*?\n\n", "\n", rest, flags=re.S)  # the toctree lists them
    toc = "\n".join(pages)
    index = (
        f"{title}\n{_link_citations(rest, labels)}\n```{{toctree}}\n:maxdepth: 2\n\n{toc}\n```\n"
    )
    _write(target / "index.md", index)
    for stale in target.glob("*.md"):
        if stale.stem not in pages and stale.stem != "index":
            stale.unlink()
    return pages


# ---------------------------------------------------------------------------------------------
# API reference


def _directive(module: str, name: str) -> str:
    obj = getattr(importlib.import_module(module), name)
    if inspect.isclass(obj):
        extra = "   :show-inheritance:\n" if issubclass(obj, Exception) else ""
        own_bases = [b for b in obj.__mro__[1:-1] if b.__module__.startswith("dolfinx_ntf.")]
        if own_bases and not issubclass(obj, Exception):  # members a package base holds
            extra += "   :inherited-members:\n"
        return f".. autoclass:: {module}.{name}\n   :members:\n{extra}"
    if callable(obj):
        return f".. autofunction:: {module}.{name}\n"
    doc = _data_doc(obj, name)
    body = "\n".join(f"   {line}" for line in doc.splitlines())
    return f".. py:data:: {module}.{name}\n   :type: {type(obj).__name__}\n\n{body}\n"


def _data_doc(obj: object, name: str) -> str:
    """The ``#:`` comment of the module that assigns ``name`` (data has no docstring of its own)."""
    from sphinx.pycode import ModuleAnalyzer

    for module in sorted(m for m in sys.modules if m.startswith("dolfinx_ntf")):
        if getattr(sys.modules[module], name, None) is obj:
            try:
                docs = ModuleAnalyzer.for_module(module).find_attr_docs()
            except Exception:  # no source (a compiled or a namespace module)
                continue
            if ("", name) in docs:
                return "\n".join(docs["", name]).strip()
    return ""


def write_api(target: Path) -> None:
    """One page per public name, grouped on ``api/index.rst`` (names no group lists included)."""
    import dolfinx_ntf

    listed = {(module, name) for _, module, names in API_GROUPS for name in names}
    groups = [(t, m, [n for n in names if n in public_names(m)]) for t, m, names in API_GROUPS]
    for module in ("dolfinx_ntf", "dolfinx_ntf.calculix"):
        other = [n for n in public_names(module) if (module, n) not in listed]
        if other:
            groups.append((f"Other names of {module}", module, other))
    pages = set()
    lines = [
        "API reference",
        "=============",
        "",
        f"dolfinx_ntf {dolfinx_ntf.__version__}. Every public name of ``dolfinx_ntf`` "
        "(``import dolfinx_ntf as ntf``) and of ``dolfinx_ntf.calculix``, by topic, then the "
        "modules the examples import besides them.",
        "",
    ]
    for title, module, names in groups:
        lines += [title, "-" * len(title), "", f".. currentmodule:: {module}", ""]
        mod = importlib.import_module(module)
        data = [n for n in names if not callable(getattr(mod, n))]
        lines += [".. autosummary::", "   :nosignatures:", ""]
        lines += [f"   {name}" for name in names if name not in data]
        lines += [""] + [
            f"- :py:data:`{module}.{name}`: {_data_doc(getattr(mod, name), name)}" for name in data
        ]
        lines += ["", ".. toctree::", "   :hidden:", ""]
        for name in names:
            page = f"{module}.{name}"
            pages.add(page)
            lines.append(f"   {page}")
            heading = name if module == "dolfinx_ntf" else f"calculix.{name}"
            _write(
                target / f"{page}.rst",
                f"{heading}\n{'=' * len(heading)}\n\n{_directive(module, name)}",
            )
        lines.append("")
    title = "Modules"
    lines += [title, "-" * len(title), "", ".. toctree::", "   :maxdepth: 1", ""]
    lines.append("   types")
    pages.add("types")
    write_types(target)
    for title, module in API_MODULES:
        pages.add(module)
        lines.append(f"   {title} <{module}>")
        heading = module
        _write(
            target / f"{module}.rst",
            f"{heading}\n{'=' * len(heading)}\n\n.. automodule:: {module}\n   :members:\n",
        )
    _write(target / "index.rst", "\n".join(lines) + "\n")
    for stale in target.glob("*.rst"):
        if stale.stem not in pages and stale.stem != "index":
            stale.unlink()


def _hinted_classes(obj: object) -> set[type]:
    """The classes of dolfinx_ntf named in the type hints of ``obj`` and of its public members."""
    import typing

    targets = [obj]
    if inspect.isclass(obj):
        targets = [obj.__init__] + [
            v.fget if isinstance(v, property) else v for _, v in _members(obj)
        ]
        if dataclasses.is_dataclass(obj):
            targets.append(obj)
    found: set[type] = set()

    def walk(hint: object) -> None:
        if inspect.isclass(hint) and hint.__module__.startswith("dolfinx_ntf"):
            found.add(hint)
        for arg in typing.get_args(hint):
            walk(arg)

    for target in targets:
        try:
            hints = typing.get_type_hints(target)
        except Exception:  # unresolvable string annotations: nothing to link
            continue
        for hint in hints.values():
            walk(hint)
    return found


#: Classes the type hints cannot reveal (public attributes annotated in ``__init__``, hints that
#: do not resolve at run time) but docstrings of public names refer to; they get a page too.
EXTRA_TYPES: list[str] = [
    "dolfinx_ntf.contact.problem.ResidualTerm",
    "dolfinx_ntf.contact.problem.ElementTerm",
    "dolfinx_ntf.contact.problem.MaterialHistory",
    "dolfinx_ntf.contact.thermal.HeatElementTerm",
    "dolfinx_ntf.kernels.gap_conductance.ThermalSpringEvaluation",
    "dolfinx_ntf.contact.pairing.Pairing",
    "dolfinx_ntf.solvers.convergence.ForceScaledTest",
    "dolfinx_ntf.solvers.convergence.DivergenceRule",
    "dolfinx_ntf.solvers.convergence.ExtraPairings",
    "dolfinx_ntf.solvers.line_search.LineSearch",
    "dolfinx_ntf.calculix.compare.Comparison",
    "dolfinx_ntf.calculix.compare.IncrementComparison",
]


def auxiliary_types() -> list[type]:
    """Non-public classes that public signatures take or return, transitively (they get a page)."""
    public = {
        id(getattr(importlib.import_module(m), n))
        for m in ("dolfinx_ntf", "dolfinx_ntf.calculix")
        for n in public_names(m)
    }
    todo = [
        getattr(importlib.import_module(m), n)
        for m in ["dolfinx_ntf", "dolfinx_ntf.calculix"] + [m for _, m in API_MODULES]
        for n in public_names(m)
    ]
    documented = {f"{m}.{n}" for _, m in API_MODULES for n in public_names(m)}
    seen: dict[str, type] = {}
    for key in EXTRA_TYPES:
        module, name = key.rsplit(".", 1)
        seen[key] = getattr(importlib.import_module(module), name)
        todo.append(seen[key])
    while todo:
        for cls in _hinted_classes(todo.pop()):
            key = f"{cls.__module__}.{cls.__qualname__}"
            if id(cls) not in public and key not in seen and key not in documented:
                seen[key] = cls
                todo.append(cls)
    return [seen[key] for key in sorted(seen, key=lambda k: k.rsplit(".", 1)[-1])]


_AUXILIARY: list[type] = []


def _auxiliary() -> list[type]:
    if not _AUXILIARY:
        _AUXILIARY.extend(auxiliary_types())
    return _AUXILIARY


def write_types(target: Path) -> None:
    """``api/types.rst``: the auxiliary types, documented where they are defined."""
    title = "Types the public names take and return"
    lines = [
        title,
        "=" * len(title),
        "",
        "Classes that are not imported from ``dolfinx_ntf`` or ``dolfinx_ntf.calculix`` but appear "
        "in their signatures (found from the type hints when the site is built).",
        "",
    ]
    for cls in _auxiliary():
        lines += [f".. autoclass:: {cls.__module__}.{cls.__qualname__}", "   :members:", ""]
    _write(target / "types.rst", "\n".join(lines))


def _own_doc(obj: object) -> str:
    """The docstring written for ``obj`` (not a dataclass's generated signature, not inherited)."""
    doc = obj.__dict__.get("__doc__") if inspect.isclass(obj) else getattr(obj, "__doc__", None)
    if inspect.isclass(obj) and dataclasses.is_dataclass(obj) and doc:
        if doc.startswith(f"{obj.__name__}("):
            return ""
    return (doc or "").strip()


def _members(cls: type) -> list[tuple[str, object]]:
    """Public methods and properties defined on ``cls`` itself (what ``:members:`` shows)."""
    out = []
    for name, value in cls.__dict__.items():
        if name.startswith("_"):
            continue
        if isinstance(value, (staticmethod, classmethod)):
            value = value.__func__
        if inspect.isfunction(value) or isinstance(value, property):
            out.append((name, value))
    return out


def _parameters(obj: object) -> list[str]:
    """Parameter names a docstring should describe (no self, no ``*args``/``**kwargs``)."""
    try:
        target = obj.__init__ if inspect.isclass(obj) else obj
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return []
    skip = (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
    return [
        p.name
        for p in sig.parameters.values()
        if p.name not in ("self", "cls") and p.kind not in skip
    ]


def _documented_args(obj: object) -> str:
    doc = _own_doc(obj)
    if inspect.isclass(obj):
        doc += "\n" + (getattr(obj.__init__, "__doc__", None) or "")
    return doc


def check_docstrings(app: Sphinx) -> None:
    """Warn on public names and members without a docstring; list undocumented arguments."""
    gaps = []
    for module in ("dolfinx_ntf", "dolfinx_ntf.calculix", *ARGS_CHECKED_MODULES):
        mod = importlib.import_module(module)
        for name in public_names(module):
            obj = getattr(mod, name)
            where = f"{module}.{name}"
            if not (inspect.isclass(obj) or callable(obj)):
                if not _data_doc(obj, name):
                    logger.warning(f"{where} has no docstring (a #: comment where it is assigned)")
                continue
            if not _own_doc(obj):
                logger.warning(f"{where} has no docstring")
            candidates = [(where, obj)]
            if inspect.isclass(obj) and not dataclasses.is_dataclass(obj):
                for member, value in _members(obj):
                    if not _own_doc(value):
                        logger.warning(f"{where}.{member} has no docstring")
                    if inspect.isfunction(value):
                        candidates.append((f"{where}.{member}", value))
            for label, func in candidates:
                doc = _documented_args(func)
                missing = [p for p in _parameters(func) if not re.search(rf"\b{p}\b", doc)]
                if missing:
                    gaps.append(f"{label}: {', '.join(missing)}")
    report = Path(app.outdir).parent / "docstring-gaps.txt"
    report.parent.mkdir(parents=True, exist_ok=True)
    report.write_text("".join(f"{line}\n" for line in gaps))
    if gaps:
        message = f"{len(gaps)} public callables do not describe every argument (see {report})"
        if app.config.ntf_require_args:
            for line in gaps:
                logger.warning(f"arguments not described: {line}")
        else:
            logger.info(message)


# ---------------------------------------------------------------------------------------------
# Demos as a gallery


def copy_demos(source: Path, target: Path) -> None:
    """Copy ``demos/*.py`` for sphinx-gallery, the docstring's first line underlined as title."""
    names = []
    for demo in sorted(source.glob("*.py")):
        text = demo.read_text()
        match = re.match(r'(\s*"""\s*)([^\n]+)\n', text)
        if match is None:
            raise RuntimeError(f"{demo} has no docstring to make its tutorial's title")
        title = match.group(2).strip().rstrip(".")
        text = f"{match.group(1)}{title}\n{'=' * len(title)}\n{text[match.end() :]}"
        _write(target / demo.name, text)
        names.append(demo.name)
    _write(target / "README.txt", (DOCS / "_templates" / "demos-intro.rst").read_text())
    for stale in target.glob("*.py"):
        if stale.name not in names:
            stale.unlink()


def demo_output(script: str) -> Path:
    """Where the demo ``script`` writes its files during the build (its ``--output``)."""
    return DOCS / "_build" / "demo-output" / Path(script).stem


def demo_argv(gallery_conf: dict, script_vars: dict) -> list[str]:
    """The demos run on their coarse meshes in the build, writing into ``demo_output``."""
    argv = ["--coarse"]
    if '"--output"' in Path(script_vars["src_file"]).read_text():
        out = demo_output(script_vars["src_file"])
        if out.exists():
            shutil.rmtree(out)
        argv += ["--output", str(out)]
    return argv


class DemoFigures:
    """sphinx-gallery image scraper: the PNG files a demo saved (the demos close their figures)."""

    def __repr__(self) -> str:
        # sphinx-gallery keys its cache on the repr of the configuration.
        return "DemoFigures"

    def __call__(self, block: tuple, block_vars: dict, gallery_conf: dict) -> str:
        """Copy the PNGs written since the last block next to the page; return their rST.

        Each figure gets the page's width, one below the other (sphinx-gallery would shrink the
        figures of one block into a row of thumbnails).
        """
        from sphinx_gallery.scrapers import figure_rst

        out = demo_output(block_vars["src_file"])
        seen = block_vars.setdefault("ntf_seen_png", set())
        new = sorted(p for p in out.glob("*.png") if p not in seen) if out.exists() else []
        paths = []
        for png, path in zip(new, block_vars["image_path_iterator"]):
            shutil.copyfile(png, path)
            seen.add(png)
            paths.append(path)
        return "".join(figure_rst([path], gallery_conf["src_dir"]) for path in paths)


def _exit_status_as_error() -> None:
    """A demo's ``sys.exit(0)`` ends its page, a nonzero status fails the build."""
    from sphinx_gallery import gen_rst

    original = gen_rst._exec_once
    if getattr(original, "ntf_wrapped", False):
        return

    def exec_once(*args, **kwargs):
        run = original(*args, **kwargs)

        def guarded():
            try:
                return run()
            except SystemExit as exit:
                if exit.code not in (0, None):
                    raise RuntimeError(f"the demo exited with status {exit.code}") from None

        return guarded

    exec_once.ntf_wrapped = True
    gen_rst._exec_once = exec_once


def resolve_moved(app: Sphinx, env: object, node: object, contnode: object) -> object:
    """Resolve ``dolfinx_ntf.<module>.Name`` (type hints, docstrings) to the page of a public name.

    Type hints name the defining module; the site documents the name where users import it, so
    module moves inside the package change nothing here.
    """
    target = node.get("reftarget", "")
    if node.get("refdomain") != "py":
        return None
    name = target.rsplit(".", 1)[-1]
    if not target.startswith("dolfinx_ntf."):
        aux = {cls.__name__: f"{cls.__module__}.{cls.__qualname__}" for cls in _auxiliary()}
        if target not in aux:
            return None
        domain = env.get_domain("py")
        return domain.resolve_xref(
            env, node["refdoc"], app.builder, node["reftype"], aux[target], node, contnode
        )
    for module in ("dolfinx_ntf", "dolfinx_ntf.calculix"):
        if name in public_names(module) and target != f"{module}.{name}":
            domain = env.get_domain("py")
            return domain.resolve_xref(
                env,
                node["refdoc"],
                app.builder,
                node["reftype"],
                f"{module}.{name}",
                node,
                contnode,
            )
    return None


class KnownWarnings(logging_module.Filter):
    """Drop the warnings ``ntf_known_warnings`` lists (docstring faults left for later).

    Each entry is a regular expression searched in "location: message". The dropped warnings are
    written to ``_build/known-warnings.txt``; an entry that matched nothing is itself a warning,
    so the list only shrinks.
    """

    def __init__(self, patterns: list[str], report: Path) -> None:
        super().__init__()
        self.patterns = [re.compile(p) for p in patterns]
        self.used: set[int] = set()
        self.seen: set[str] = set()
        self.report = report
        report.parent.mkdir(parents=True, exist_ok=True)
        report.write_text("")

    def filter(self, record: logging_module.LogRecord) -> bool:
        """False for a listed warning (after writing it to the report)."""
        if record.levelno < logging_module.WARNING:
            return True
        from sphinx.util.logging import get_node_location

        location = getattr(record, "location", None)
        if location is not None and not isinstance(location, str):
            location = get_node_location(location) if hasattr(location, "source") else ""
        text = f"{location or ''}: {record.getMessage()}"
        for k, pattern in enumerate(self.patterns):
            if pattern.search(text):
                self.used.add(k)
                if text not in self.seen:
                    self.seen.add(text)
                    with self.report.open("a") as out:
                        out.write(text + "\n")
                return False
        return True


def install_known_warnings(app: Sphinx, config: object) -> None:
    """Put the ``KnownWarnings`` filter first on Sphinx's warning handlers."""
    known = KnownWarnings(config.ntf_known_warnings, Path(app.outdir).parent / "known-warnings.txt")
    app.ntf_known = known
    for handler in logging_module.getLogger("sphinx").handlers:
        handler.filters.insert(0, known)


def unused_known_warnings(app: Sphinx, exception: Exception | None) -> None:
    """Warn about ``ntf_known_warnings`` entries nothing matched (fixed faults: remove them)."""
    known = getattr(app, "ntf_known", None)
    if exception is None and known is not None:
        for k, pattern in enumerate(known.patterns):
            if k not in known.used:
                logger.warning(f"ntf_known_warnings entry matched nothing: {pattern.pattern}")


def _method_labels() -> set[str]:
    text = (DOCS / "method.md").read_text()
    labels = {f"method-{m.group(1)}" for m in _SECTION.finditer(text)}
    return labels | {f"method-{m.group(1)}-{m.group(2)}" for m in _SUBSECTION.finditer(text)}


def link_docstring_citations(
    app: Sphinx, what: str, name: str, obj: object, options: object, lines: list[str]
) -> None:
    """Link the "§3.4" citations of a docstring to the method's section (not inside literals)."""
    labels = getattr(app, "ntf_method_labels", None)
    if labels is None:
        labels = app.ntf_method_labels = _method_labels()

    def link(m: re.Match) -> str:
        label = "method-" + m.group(1).replace(".", "-")
        return f":ref:`§{m.group(1)} <{label}>`" if label in labels else m.group(0)

    for k, line in enumerate(lines):
        if "§" not in line:
            continue
        pieces = line.split("``")
        for i in range(0, len(pieces), 2):  # even pieces are outside inline literals
            pieces[i] = _CITE.sub(link, pieces[i])
        lines[k] = "``".join(pieces)


def prepare(app: Sphinx, config: object) -> None:
    """Write the generated sources before anything reads them."""
    sys.path.insert(0, str(ROOT))
    split_method(DOCS / "method.md", DOCS / "method")
    write_api(DOCS / "api")
    copy_demos(ROOT / "demos", DOCS / "_gallery_src")
    _exit_status_as_error()


def setup(app: Sphinx) -> dict:
    """Register the generators (config-inited) and the docstring check (builder-inited)."""
    app.add_config_value("ntf_require_args", False, "env")
    app.add_config_value("ntf_known_warnings", [], "env")
    app.connect("config-inited", install_known_warnings, priority=10)
    app.connect("build-finished", unused_known_warnings)
    app.connect("config-inited", prepare, priority=100)
    app.connect("builder-inited", check_docstrings)
    app.connect("missing-reference", resolve_moved)
    app.connect("autodoc-process-docstring", link_docstring_citations)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
