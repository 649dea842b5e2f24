"""Regenerate ``docs/validation.md``: dolfinx_ntf against CalculiX 2.20 and analytical solutions.

Every case is a ccx deck written by ``dolfinx_ntf.calculix.writer.write_inp`` from a problem built
with dolfinx, solved by ``ccx`` and by ``run_job(..., tight=True)``:

- the cross-validation decks of ``tests/data/calculix/crossval/cases.py`` (the ones the test suite
  runs), compared increment by increment with ``dolfinx_ntf.calculix.compare``;
- Hertz: a quarter hemisphere (R = 25 mm, steel) pressed 0.6 mm into a steel block
  (``dolfinx_ntf.meshes.hertz``, coarse mesh); both codes' contact radius and peak pressure against
  ``a = (3FR/4E*)^(1/3)`` and ``p0 = 3F/(2 pi a^2)`` with F from the reactions;
- the contact patch test: a block pressed onto a larger block through non-matching flat faces by a
  uniform pressure, on rollers; the contact pressure must be uniform and equal to the load over the
  current contact area.

It also measures the two ccx behaviours that bound the agreement (see the document): the spring
areas ccx used (from its CELS and CDIS output) against the areas of its own final configuration,
and the equilibrium of an NLGEOM follower pressure.

Serial. Needs ``ccx`` on the PATH. Run from the repository root (about 2 minutes)::

    .venv/bin/python benchmarks/validate.py                   # writes docs/validation.md
    .venv/bin/python benchmarks/validate.py --only hertz patch_hex --output /tmp/v.md
"""

from __future__ import annotations

import argparse
import datetime as dt
import logging
import math
import re
import shutil
import subprocess
import sys
import tempfile
import time
import typing
from dataclasses import dataclass, field
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import gmsh
import numpy as np
import scipy.optimize

import dolfinx
import dolfinx.fem

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.calculix.ccx import CcxError, read_sta, run_ccx
from dolfinx_ntf.calculix.compare import Comparison, compare_job
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import Deck, node_surface_faces, read_deck, surface_nodes
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.writer import (
    TIGHT_FIELD_CONTROLS,
    BoundarySpec,
    OutputSpec,
    PressureSpec,
    StepSpec,
    write_inp,
)
from dolfinx_ntf.kernels.faces import face_type_from_num_nodes
from dolfinx_ntf.kernels.laws import PressureOverclosureLaw
from dolfinx_ntf.kernels.spring_areas import spring_areas
from dolfinx_ntf.meshes import hertz as hz
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh
from dolfinx_ntf.solvers.errors import ContactConvergenceError

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "data" / "calculix" / "crossval"))
import cases  # noqa: E402
import friction_cases  # noqa: E402

sys.path.insert(0, str(ROOT / "tests" / "data" / "calculix" / "dynamic"))
from impact_deck import write_impact_deck  # noqa: E402

__all__ = ["Run", "hertz_deck", "hertz_results", "main", "patch_deck", "patch_results", "run_case"]

COMMAND = ".venv/bin/python benchmarks/validate.py"

# Hertz: units mm, N, MPa (the Hertz demo's steel sphere).
RADIUS, E_STEEL, NU_STEEL, INDENTATION = 25.0, 210_000.0, 0.3, 0.6
# Patch test: pressure on the upper block.
PATCH_PRESSURE = 10.0
_ANALYTIC = ("hertz", "patch_hex", "patch_tet", "patch_hex_nonmatching", "patch_tet_nonmatching")
#: Dynamic decks (docs/method.md §12.4); no spring-area lag estimate (their CELS is the integral).
_DYNAMIC = ("impact_dynamic",)


# ----------------------------------------------------------------------------- running


@dataclass
class Run:
    """One deck solved by both codes."""

    name: str
    description: str
    directory: Path
    deck: Deck
    ccx_time: float
    ntf_time: float
    comparison: Comparison
    ccx_dat: Path
    ntf_dat: Path
    quirk: str = ""
    notes: list[str] = field(default_factory=list)


def run_case(
    name: str,
    description: str,
    write: typing.Callable[[Path], None],
    workdir: Path,
    quirk: str = "",
) -> Run:
    """Write the deck, run ccx in ``<workdir>/<name>/ccx`` and dolfinx_ntf in ``.../ntf``."""
    ccx_dir, ntf_dir = workdir / name / "ccx", workdir / name / "ntf"
    for d in (ccx_dir, ntf_dir):
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir(parents=True)
    write(ccx_dir)
    shutil.copy(ccx_dir / f"{name}.inp", ntf_dir)
    start = time.perf_counter()
    run_ccx(ccx_dir, name, timeout=1200)
    ccx_time = time.perf_counter() - start
    result = run_job(name, ntf_dir, comm=MPI.COMM_SELF, tight=True)
    comparison = compare_job(ccx_dir / f"{name}.dat", result, read_sta(ccx_dir / f"{name}.sta"))
    return Run(
        name,
        description,
        workdir / name,
        read_deck(ccx_dir / f"{name}.inp"),
        ccx_time,
        result.wall_time,
        comparison,
        ccx_dir / f"{name}.dat",
        ntf_dir / f"{name}.dat",
        quirk,
    )


# ----------------------------------------------------------------------------- analytical decks


def hertz_deck(directory: Path) -> None:
    """Quarter hemisphere on a block (coarse mesh), sphere top pushed down, automatic increments."""
    sizes = {key: value * RADIUS for key, value in hz.COARSE.items()}
    mesh, _, ft = mesh_from_gmsh(hz.build_hertz, MPI.COMM_SELF, radius=RADIUS, **sizes)
    V = compat.vector_space(mesh, "Lagrange", 1)
    law = ntf.LinearLaw.with_ccx_defaults(E_STEEL)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, hz.SPHERE_CONTACT),
        ntf.FacetSurface(ft, hz.BLOCK_TOP),
        ntf.SurfaceInteraction(law),
    )
    top = BoundarySpec(ntf.FacetSurface(ft, hz.SPHERE_TOP), (2,), -INDENTATION, name="TOP")
    # ccx diverges with fixed increments (the contact zone grows from one node): automatic ones.
    step = StepSpec(
        boundaries=[top],
        increments=None,
        initial_increment=0.1,
        max_increment=0.25,
        field_controls=TIGHT_FIELD_CONTROLS,
        output=OutputSpec(node_print=("U", "RF")),
    )
    write_inp(
        directory / "hertz.inp",
        displacement_space=V,
        materials=(E_STEEL, NU_STEEL),
        pairs=[pair],
        steps=[step],
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, hz.BLOCK_BOTTOM), name="BASE"),
            BoundarySpec(ntf.FacetSurface(ft, hz.SYMMETRY_X), (0,), name="XSYM"),
            BoundarySpec(ntf.FacetSurface(ft, hz.SYMMETRY_Y), (1,), name="YSYM"),
        ],
        heading=f"Hertz: quarter sphere R={RADIUS} on a block, indentation {INDENTATION}, "
        "LINEAR law (ccx defaults)",
    )


def patch_deck(directory: Path, cell: str, matching: bool = True) -> None:
    """Contact patch test: a block on a block of the same footprint, uniform pressure, rollers.

    Both blocks (one material) slide freely on the planes x = 0, y = 0 and z = -0.5 (rollers), so
    the exact solution is a uniform stress state with the contact pressure equal to the applied one
    over the current contact area, and matching interface nodes stay matched. ``matching``: the
    slave face's grid is the master's (4 x 4 cells); otherwise 3 x 5 cells (no slave node on a
    master edge or triangle diagonal except at the corners: nodes there flip faces at every ccx
    re-pairing, docs/method.md §3.2).
    """
    lower = ((0.0, 0.0, -0.5), (1.0, 1.0, 0.5), (4, 4, 2))
    upper = ((0.0, 0.0, 0.0), (1.0, 1.0, 0.4), (4, 4, 2) if matching else (3, 5, 2))
    V, _ct, ft = cases.blocks([lower, upper], cell=cell)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, cases.facet_tag(1, cases.BOTTOM)),
        ntf.FacetSurface(ft, cases.facet_tag(0, cases.TOP)),
        ntf.SurfaceInteraction(cases.LINEAR),
    )
    top = ntf.FacetSurface(ft, cases.facet_tag(1, cases.TOP))
    step = StepSpec(
        pressures=[PressureSpec(top, PATCH_PRESSURE)],
        increments=2,
        field_controls=TIGHT_FIELD_CONTROLS,
        output=cases._OUTPUT,
    )
    name = ("patch_hex" if cell == "hexahedron" else "patch_tet") + (
        "" if matching else "_nonmatching"
    )
    base = BoundarySpec(ntf.FacetSurface(ft, cases.facet_tag(0, cases.BOTTOM)), (2,), name="BASE")
    write_inp(
        directory / f"{name}.inp",
        displacement_space=V,
        materials=(cases.E1, cases.NU1),
        pairs=[pair],
        fixed=[base, *cases._rollers(ft, [0, 1])],
        steps=[step],
        heading=f"Contact patch test ({cell}): uniform pressure {PATCH_PRESSURE} through "
        "non-matching flat faces, rollers",
    )


# ----------------------------------------------------------------------------- evaluations


def _blocks_at(blocks, name: str, when: float):
    return next(b for b in blocks if b.name == name and abs(b.time - when) < 1e-9 * max(1, when))


def hertz_results(deck: Deck, dat: Path) -> dict[str, float]:
    """Force, contact radius and peak pressure of a Hertz run, and Hertz's values for that force.

    F is four times the vertical base reaction of the quarter model. The contact radius and peak
    pressure come from a least-squares fit of ``p0 sqrt(1 - r^2/a^2)`` to the nodal pressures of
    all slave nodes out to 1.5 a (zero where a node has no contact element), with r the reference
    radius of the node; ``p_max`` is the largest nodal pressure.
    """
    blocks = read_dat(dat)
    end = max(b.time for b in blocks)
    rf, cstr = _blocks_at(blocks, "RF", end), _blocks_at(blocks, "CSTR", end)
    base = np.isin(rf.labels, deck.nsets["BASE"])
    force = 4.0 * float(rf.values[base, 2].sum())
    e_star = E_STEEL / (2.0 * (1.0 - NU_STEEL**2))
    a_hertz = (3.0 * force * RADIUS / (4.0 * e_star)) ** (1.0 / 3.0)
    p0_hertz = 3.0 * force / (2.0 * math.pi * a_hertz**2)
    slaves = surface_nodes(deck, deck.contact_pairs[0].slave)
    xy = deck.node_coords[deck.node_index(slaves)][:, :2]
    r = np.hypot(xy[:, 0], xy[:, 1])
    p = np.zeros(slaves.size)
    p[np.searchsorted(slaves, cstr.labels)] = cstr.values[:, 0]
    near = r < 1.5 * a_hertz
    r, p = r[near], p[near]

    def residual(params: np.ndarray) -> np.ndarray:
        a, peak = params
        return peak * np.sqrt(np.clip(1.0 - (r / a) ** 2, 0.0, None)) - p

    fit = scipy.optimize.least_squares(
        residual, x0=[a_hertz, p0_hertz], x_scale=[a_hertz, p0_hertz]
    )
    a_fit, p0_fit = (float(v) for v in fit.x)
    return {
        "force": force,
        "a_hertz": a_hertz,
        "p0_hertz": p0_hertz,
        "a_fit": a_fit,
        "p0_fit": p0_fit,
        "p_max": float(p.max()),
        "springs": int(cstr.labels.size),
    }


def patch_results(deck: Deck, dat: Path) -> dict[str, float]:
    """Uniformity of the contact pressure, its value and the resultant of a patch-test run.

    The spring areas ``A_i`` are recomputed from the printed final configuration (docs/method.md
    §2.2); their sum is the current area of the slave face, so the exact pressure is the load (``p``
    times the reference area 1, small strain) over that sum.
    """
    blocks = read_dat(dat)
    end = max(b.time for b in blocks)
    u, cstr = _blocks_at(blocks, "U", end), _blocks_at(blocks, "CSTR", end)
    pair = deck.contact_pairs[0]
    x = deck.node_coords.copy()
    x[deck.node_index(u.labels)] += u.values
    faces, slaves = node_surface_faces(deck, pair.slave), surface_nodes(deck, pair.slave)
    area = spring_areas(
        face_type_from_num_nodes(faces.shape[1]), deck.node_index(faces), x, deck.node_index(slaves)
    )[np.searchsorted(slaves, cstr.labels)]
    p = cstr.values[:, 0]
    load = PATCH_PRESSURE * 1.0
    return {
        "springs": int(p.size),
        "slaves": int(slaves.size),
        "mean": float(p.mean()),
        "expected": load / float(area.sum()),
        "uniformity": float(np.abs(p / p.mean() - 1.0).max()),
        "resultant": float(np.sum(area * p) / load - 1.0),
    }


def _law(deck: Deck, name: str) -> PressureOverclosureLaw:
    behavior = deck.interactions[name].behavior
    kind = behavior.pressure_overclosure
    if kind == "EXPONENTIAL":
        return ntf.ExponentialLaw(*behavior.values)
    if kind == "LINEAR":
        youngs = next(iter(deck.materials.values())).elastic[0]
        return ntf.LinearLaw.with_ccx_defaults(youngs, *behavior.values)
    return ntf.TabularLaw(behavior.table[:, 0], behavior.table[:, 1])


def spring_area_lag(deck: Deck, dat: Path) -> float:
    """Largest ``|A_used / A(final) - 1|`` over increments and closed springs of a ``.dat`` file.

    ``A_used`` is the spring area behind the printed energy, ``CELS / e(d)`` with ``e`` the law's
    energy per unit area at the printed overclosure ``d = -CDIS``; ``A(final)`` is the spring area
    (docs/method.md §2.2) of the printed final configuration of the increment. Springs with less
    than 1e-3 of the largest energy are skipped (their energy has few printed digits).
    """
    blocks = read_dat(dat)
    pair_of = {}
    for pair in deck.contact_pairs:
        for node in surface_nodes(deck, pair.slave):
            pair_of[int(node)] = pair
    worst = 0.0
    for u in (b for b in blocks if b.name == "U"):
        cdis, cels = _blocks_at(blocks, "CDIS", u.time), _blocks_at(blocks, "CELS", u.time)
        x = deck.node_coords.copy()
        x[deck.node_index(u.labels)] += u.values
        keep = cels.values[:, 0] > 1e-3 * np.abs(cels.values[:, 0]).max(initial=0.0)
        for pair in deck.contact_pairs:  # a handful of pairs
            rows = keep & np.array([pair_of[int(n)] is pair for n in cdis.labels], dtype=bool)
            if not rows.any():
                continue
            faces = node_surface_faces(deck, pair.slave)
            slaves = surface_nodes(deck, pair.slave)
            area = spring_areas(
                face_type_from_num_nodes(faces.shape[1]),
                deck.node_index(faces),
                x,
                deck.node_index(slaves),
            )
            final = area[np.searchsorted(slaves, cdis.labels[rows])]
            d = -cdis.values[rows, 0]
            used = cels.values[rows, 0] / _law(deck, pair.interaction).energy(d, np.ones_like(d))
            worst = max(worst, float(np.abs(used / final - 1.0).max()))
    return worst


# ----------------------------------------------------------------------------- report


def _fmt(value: float) -> str:
    return (
        "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.1e}"
    )


def _iterations(comparison: Comparison, side: str) -> str:
    values = [getattr(c, f"{side}_iterations") for c in comparison.increments]
    text = ",".join("?" if v is None else str(v) for v in values)
    return text if len(text) <= 24 else text[:21] + "..."


def _size(deck: Deck) -> str:
    (etype, block), *_ = deck.elements.items()
    slaves = sum(surface_nodes(deck, p.slave).size for p in deck.contact_pairs)
    return f"{etype}: {deck.node_ids.size} nodes, {block.ids.size} el., {slaves} slave nodes"


def _cross_table(runs: list[Run]) -> list[str]:
    lines = [
        "| deck | size | common increments | Δu / max u | Δp / max p | Δg / max g | ΔE / max E "
        "| same contact elements | Newton iterations ccx | dolfinx_ntf | ccx [s] "
        "| dolfinx_ntf [s] |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for run in runs:
        c = run.comparison
        common = f"{len(c.increments)}"
        if not c.same_increments:
            common += f" (ccx {len(c.increments) + len(c.ccx_only)}, dolfinx_ntf "
            common += f"{len(c.increments) + len(c.ntf_only)})"
        same = "yes" if c.same_contact_elements else "no: " + "; ".join(c.contact_differences())
        lines.append(
            f"| `{run.name}` | {_size(run.deck)} | {common} | {_fmt(c.relative_displacement)} "
            f"| {_fmt(c.relative_pressure)} | {_fmt(c.relative_clearance)} "
            f"| {_fmt(c.relative_energy)} | {same} | {_iterations(c, 'ccx')} "
            f"| {_iterations(c, 'ntf')} | {run.ccx_time:.2f} | {run.ntf_time:.2f} |"
        )
    return lines


def _friction_table(runs: list[Run]) -> list[str]:
    lines = [
        "| deck | common increments | Δu / max u | Δp / max p | Δg / max g | ΔE / max E "
        "| Δslip / max slip | Δτ / max τ | same contact elements | ccx [s] | dolfinx_ntf [s] |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for run in runs:
        c = run.comparison
        lines.append(
            f"| `{run.name}` | {len(c.increments)}{'' if c.same_increments else ' (differ)'} "
            f"| {_fmt(c.relative_displacement)} | {_fmt(c.relative_pressure)} "
            f"| {_fmt(c.relative_clearance)} | {_fmt(c.relative_energy)} "
            f"| {_fmt(c.relative_slip)} | {_fmt(c.relative_shear)} "
            f"| {'yes' if c.same_contact_elements else 'no'} | {run.ccx_time:.2f} "
            f"| {run.ntf_time:.2f} |"
        )
    return lines


def _per_increment(run: Run) -> list[str]:
    lines = [
        "| time | Δu / max u | Δp / max p | same contact elements (ccx / dolfinx_ntf) |",
        "|---|---|---|---|",
    ]
    for c in run.comparison.increments:
        lines.append(
            f"| {c.time:.4g} | {_fmt(c.relative_displacement)} | {_fmt(c.relative_pressure)} "
            f"| {'yes' if c.same_contact_elements else 'no'} ({c.ccx_contact.size} / "
            f"{c.ntf_contact.size}) |"
        )
    return lines


def _environment() -> str:
    try:
        banner = subprocess.run(["ccx", "-v"], capture_output=True, text=True, timeout=30).stdout
        ccx = "ccx " + banner.split("Version", 1)[1].split()[0]
    except (OSError, IndexError):
        ccx = "ccx (version unknown)"
    with open("/etc/os-release") as release:
        os_name = (
            dict(line.rstrip("\n").split("=", 1) for line in release if "=" in line)
            .get("PRETTY_NAME", "unknown OS")
            .strip('"')
        )
    return (
        f"{ccx}, dolfinx {dolfinx.__version__}, PETSc {PETSc.Sys.getVersion()}, "
        f"gmsh {gmsh.__version__}, {os_name}, {dt.date.today().isoformat()}"
    )


def _table_rows(lines: typing.Sequence[str]) -> dict[str, str]:
    """Rows of the report's tables by their first cell (a deck name), wall-time columns dropped."""
    rows = {}
    for line in lines:
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("| `") and len(cells) == 12:  # the cross-check tables
            rows[cells[0]] = " | ".join(cells[:10])
    return rows


def _release_comparison(lines: list[str], other_path: Path, other_text: str) -> list[str]:
    """A section comparing this report's tables with another release's report."""
    ours, theirs = _table_rows(lines), _table_rows(other_text.splitlines())
    environment = next(
        (
            line.split("do not edit by hand (", 1)[1].rstrip(").")
            for line in other_text.splitlines()
            if "do not edit by hand (" in line
        ),
        "unknown",
    )
    same = [name for name in ours if theirs.get(name) == ours[name]]
    different = [name for name in ours if name in theirs and theirs[name] != ours[name]]
    missing = [name for name in ours if name not in theirs]
    out = [
        "## The other Debian release",
        "",
        f"The same report made on the other supported release ({environment}; "
        f"`{other_path.name}`), compared row by row without the wall times:",
        "",
        f"- identical: {', '.join(same) or 'none'}",
    ]
    if different:
        out.append(f"- different: {', '.join(different)}")
    failed = {
        cells[0]: cells[2]
        for cells in (
            [c.strip() for c in line.strip().strip("|").split("|")]
            for line in other_text.split("## Cases that did not run", 1)[-1].splitlines()
            if "## Cases that did not run" in other_text and line.startswith("| `")
        )
    }
    for name in missing:
        why = f"did not run there: {failed[name]}" if name in failed else "not in the other report"
        out.append(f"- {name}: {why}")
    out += [
        "",
        "The `hertz` deck is meshed by gmsh, and the two releases' gmsh versions make different "
        "meshes of it, so its row is not expected to match; all other decks are built without "
        "gmsh.",
        "",
    ]
    return out


_KEPT = re.compile(r"<!-- kept section: (.*?) -->.*?<!-- /kept section: \1 -->\n", re.S)


def kept_sections(path: Path) -> list[str]:
    """Sections of an existing report that a regeneration keeps, markers included.

    A section between ``<!-- kept section: NAME -->`` and ``<!-- /kept section: NAME -->`` is
    measured by another command (it says which) and written by hand from its output.
    """
    if not path.exists():
        return []
    return [m.group(0) for m in _KEPT.finditer(path.read_text())]


def write_report(path: Path, runs: dict[str, Run], extra: dict[str, typing.Any]) -> None:
    """Write the Markdown report (the kept sections of the existing one stay, before the last)."""
    kept = kept_sections(path)
    cross = [runs[c.name] for c in cases.CASES if c.name in runs]
    analytic = [runs[n] for n in _ANALYTIC if n in runs]
    out = [
        "# Validation: dolfinx_ntf against CalculiX 2.20 and analytical solutions",
        "",
        f"Generated by `{COMMAND}` (about 30 s; needs `ccx`); do not edit by hand "
        f"({_environment()}).",
        "",
        "Every case is a ccx deck that `dolfinx_ntf.calculix.writer.write_inp` wrote from a "
        "problem "
        "built with dolfinx. `ccx` solves it with `*CONTROLS, PARAMETERS=FIELD` tightened "
        "(`TIGHT_FIELD_CONTROLS`: residuals of 1e-10 of the average force; ccx's defaults leave "
        "results off by up to 1e-4), and `run_job(..., tight=True)` solves the same file. Results "
        "are read from both `.dat` files (ccx prints 7 significant digits) and compared at every "
        "common increment by `dolfinx_ntf.calculix.compare`. Differences are relative to the "
        "largest value of ccx's increment: displacement u (all nodes), contact pressure p (CSTR), "
        "clearance g (CDIS) and spring energy E (CELS), for the slave nodes with a contact element "
        "on both sides. Wall times: ccx 2.20 on one thread; `run_job` including model building "
        "and form compilation when the cache is cold.",
        "",
        "## Cross-checks",
        "",
        "The decks of `tests/data/calculix/crossval/cases.py`, run by "
        "`tests/calculix/test_ccx_crossval.py` "
        "with the bounds 1e-6 (u) and 1e-5 (p, g, E).",
        "",
        *_cross_table(cross),
        "",
        "| deck | what it covers |",
        "|---|---|",
        *(f"| `{r.name}` | {r.description} |" for r in cross),
        "",
    ]
    friction = [runs[c.name] for c in friction_cases.CASES if c.name in runs]
    if friction:
        out += [
            "## Friction and analyses made of steps",
            "",
            "The decks of `tests/data/calculix/crossval/friction_cases.py`, run by "
            "`tests/calculix/test_ccx_friction.py` with the same bounds; "
            "slip and τ are the tangential "
            "columns of CDIS and CSTR (docs/method.md §11.4), E includes ccx 2.20's friction "
            "energy.",
            "",
            *_friction_table(friction),
            "",
            "| deck | what it covers |",
            "|---|---|",
            *(f"| `{r.name}` | {r.description} |" for r in friction),
            "",
            "CalculiX's own frictional decks (`friction1`, `friction2` of calculix-ccx-test) run "
            "at ccx's default controls in `tests/calculix/test_ccx_friction.py`: "
            "`friction2` agrees to the "
            "printed digits, `friction1` within 6e-5 (normal columns) and 1e-3 (tangential), "
            "both codes being converged to ccx's default R_n = 0.005 only.",
            "",
        ]
    if analytic:
        out += [
            "The analytical cases below also run in both codes:",
            "",
            *_cross_table(analytic),
            "",
        ]
    if "hertz" in runs:
        out += [
            "The Hertz deck uses automatic incrementation (ccx diverges with fixed increments "
            "while "
            "the contact zone grows from one node), so the two codes choose different increments "
            "and are compared at the times they share:",
            "",
            *_per_increment(runs["hertz"]),
            "",
        ]
    dynamic = [runs[n] for n in _DYNAMIC if n in runs]
    if dynamic:
        out += [
            "## Dynamic steps",
            "",
            "`impact_dynamic` (`tests/data/calculix/dynamic/impact_deck.py`, also run by "
            "`tests/calculix/test_dynamic_ccx.py`): a C3D8 block moving at 1 onto a clamped base "
            "(gap "
            "0.0102), `*DYNAMIC, DIRECT` with ccx's default ALPHA and increments of 5e-4 over "
            "0.08 (impact, bounce, second contact), LINEAR law with ccx's defaults (no tension in "
            "dynamics), `*INITIAL CONDITIONS, TYPE=VELOCITY`, tight controls (docs/method.md "
            "§12). ccx's automatic increments are not compared: its impact rules differ "
            "(docs/method.md §12.4). Springs that are open carry no force in dynamics, so a "
            "spring that only one code created at the cutoff changes nothing.",
            "",
            *_cross_table(dynamic),
            "",
        ]
    out += [
        "## What bounds the agreement",
        "",
        "1. **Printed digits.** ccx writes 7 significant digits: displacements cannot agree better "
        "than about 5e-7 of the largest one.",
        "2. **Spring areas of an earlier iterate (ccx).** Both codes re-pair (and recompute the "
        "spring areas, docs/method.md §2.2, §3.1) at the start of Newton iterations 2-8 and check "
        "convergence after the solve, so an increment ends with the areas of the iterate before "
        "its last correction. ccx accepts that last correction even when it is large (up to 0.3 % "
        "of the increment's displacement in these decks, the CORR. column of its `.cvg` file, "
        "tightened controls notwithstanding); `run_job(tight=True)` goes on until it is "
        "negligible. The areas each code used can be read back from its output (CELS / e(d) with d "
        "= -CDIS); below, their largest relative difference from the spring areas of the printed "
        "final configuration of each increment (about 1e-6 is the printing noise of this "
        "estimate). A node-based slave (`hex_tabular_nodal`) collects area from the lateral faces "
        "of the rim (docs/method.md §2.1), whose areas change with the vertical strain, so the lag "
        "shows most there; it is largest in first increments, where the last correction is "
        "largest, and it shrinks with smaller increments (the deck uses 4; with 2 the pressure "
        "differs by 1.0e-5). Increments that need more than 8 iterations keep the areas of "
        "iteration 8 in both codes, by design (Hertz: 5e-2), so there the two codes agree only if "
        "their iterates 8 do.",
        "",
        "| deck | ccx: max abs(A_used/A_final - 1) | dolfinx_ntf |",
        "|---|---|---|",
        *(
            f"| `{r.name}` | {_fmt(extra['lag'][r.name][0])} | {_fmt(extra['lag'][r.name][1])} |"
            for r in cross + analytic
            if r.name in extra["lag"]
        ),
        "",
    ]
    if "balance" in extra:
        ccx_b, ntf_b = extra["balance"]
        out += [
            "3. **NLGEOM follower pressure (ccx).** With NLGEOM, ccx's reactions at its converged "
            "state differ from the pressure integrated over its own final (flat, C3D4) faces; "
            "dolfinx_ntf's match to the printed digits. `tet_nlgeom_pressure`, sum of the base "
            "reactions over the follower load, minus 1:",
            "",
            "| time | ccx | dolfinx_ntf |",
            "|---|---|---|",
            *(f"| {t:.4g} | {b1:+.1e} | {b2:+.1e} |" for (t, b1), (_, b2) in zip(ccx_b, ntf_b)),
            "",
            "Its displacements therefore agree to 2e-6 only; the test allows 3e-6 for this deck "
            "and "
            "checks that the imbalance is ccx's.",
            "",
        ]
    out += [
        "4. **Frozen contact sets.** Both codes pair at iterations 2-8 only and then keep the "
        "contact elements (docs/method.md §3.1, §9), so an increment can converge with different "
        "contact elements depending on the Newton path: the Hertz run at t = 0.4 above. Decks with "
        "fixed increments give both codes the same path in practice; all cross-validation decks "
        "have the same contact elements in every increment.",
        "5. **Slave nodes on master edges** flip faces at every re-pairing in ccx (docs/method.md "
        "§3.2) and can stall its Newton iterations; the cross-validation decks place slave nodes "
        "at least 0.009 away from master edges.",
        "6. **Exact ties.** A slave node equally near the sub-triangle centroids of two master "
        "faces (above a master node or edge) gets the face CalculiX gives it where ccx's "
        "floating-point distances tell the centroids apart (docs/method.md §3.6): on the two "
        "decks of `tests/data/calculix/ties` (21 such nodes each) the first `.cel` set is ccx's "
        "(`tests/calculix/test_ccx_ties.py`). Where the rounded distances are equal too, "
        "ccx's choice "
        "depends on its element numbering and is not reproduced: on the punch decks of "
        "`benchmarks/vs_ccx.py`, whose `.cel` sets it compares pairing by pairing, 2 of 49 "
        "slave nodes (`tie_punch`), 2 of 121 (`punch_10`), 13 of 441 (`punch_20`) and 5 of 961 "
        "(`punch_30`) have another face than in ccx in iteration 1, and at most 1 (the punch "
        "centre) in later iterations; the contact pressures then differ from ccx's by at most "
        "7.7e-7 of the largest.",
        "",
    ]
    if "hertz_values" in extra:
        h = extra["hertz_values"]
        out += [
            "## Hertz",
            "",
            f"Quarter hemisphere, R = {RADIUS:g} mm, E = {E_STEEL:g} MPa, nu = {NU_STEEL:g} for "
            f"both bodies (E* = E / (2 (1 - nu^2))), top pushed down {INDENTATION:g} mm, LINEAR "
            "law with ccx's defaults (K = 50 E), coarse mesh of `dolfinx_ntf.meshes.hertz` (C3D4). "
            "F is "
            "four times the base reaction; a = (3FR/4E*)^(1/3) and p0 = 3F/(2 pi a^2) are "
            "Hertz's values for that F; the computed radius and peak come from a least-squares "
            "fit of p0 sqrt(1 - r^2/a^2) to the nodal pressures (reference radii); p_max is the "
            "largest nodal pressure.",
            "",
            "| code | F [N] | contact elements | a Hertz [mm] | a fit | p0 Hertz [MPa] | p0 fit "
            "| p_max |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for code, v in h.items():
            out.append(
                f"| {code} | {v['force']:.5g} | {v['springs']} | {v['a_hertz']:.4g} | "
                f"{v['a_fit']:.4g} ({v['a_fit'] / v['a_hertz'] - 1:+.1%}) | {v['p0_hertz']:.5g} | "
                f"{v['p0_fit']:.5g} ({v['p0_fit'] / v['p0_hertz'] - 1:+.1%}) | {v['p_max']:.5g} "
                f"({v['p_max'] / v['p0_hertz'] - 1:+.1%}) |"
            )
        out += [
            "",
            "The coarse mesh resolves the contact radius with about four elements, so the fitted "
            "profile, not the nodal values, is the meaningful comparison; the two codes agree "
            "with each other to the digits shown.",
            "",
        ]
    if "patch_values" in extra:
        out += [
            "## Contact patch test",
            "",
            f"A 1 x 1 x 0.4 block on a 1 x 1 x 0.5 block (4 x 4 x 2 cells), pressure "
            f"{PATCH_PRESSURE:g} on top, one material (E = {cases.E1:g}, nu = {cases.NU1:g}), both "
            "blocks on rollers (x = 0, y = 0 and the base z = -0.5): the exact stress is uniform "
            "and the contact pressure is the load over the current contact area (the sum of the "
            "spring areas of the final configuration). Matching decks give "
            "the upper block 4 x 4 x 2 cells, the non-matching ones 3 x 5 x 2. Uniformity is "
            "max abs(p_i / mean p - 1); the resultant is sum(A_i p_i) over the load, minus 1.",
            "",
            "| deck | code | contact elements / slave nodes | mean p | load / area | uniformity "
            "| resultant |",
            "|---|---|---|---|---|---|---|",
        ]
        for name, per_code in extra["patch_values"].items():
            for code, v in per_code.items():
                out.append(
                    f"| `{name}` | {code} | {v['springs']} / {v['slaves']} | {v['mean']:.7g} | "
                    f"{v['expected']:.7g} | {v['uniformity']:.1e} | {v['resultant']:+.1e} |"
                )
        out += [
            "",
            "On matching meshes both codes pass to the printed digits. On non-matching meshes "
            "neither does, identically: a one-pass node-to-face method hands each slave node's "
            "force to the master nodes through the shape functions at the projection point, which "
            "is not the consistent nodal load of a uniform pressure on the master faces, so the "
            "master deforms unevenly and the pressure follows (the classical failure of one-pass "
            "node-to-segment contact in the patch test, Taylor and Papadopoulos 1991). The "
            "resultant still balances the load (to the tilt of the deformed master faces).",
            "",
        ]
    out += [section.rstrip("\n") + "\n" for section in kept]
    out += [
        "## Cross-checking your own problem",
        "",
        "Any problem built with dolfinx_ntf's objects can be exported and run in both codes "
        "(each in its own directory: both write `JOB.dat`):",
        "",
        "```python",
        "import shutil",
        "from pathlib import Path",
        "from dolfinx_ntf.calculix.ccx import CcxError, read_sta, run_ccx",
        "from dolfinx_ntf.calculix.compare import compare_job",
        "from dolfinx_ntf.calculix.job import run_job",
        "from dolfinx_ntf.calculix.writer import TIGHT_FIELD_CONTROLS, BoundarySpec, PressureSpec",
        "from dolfinx_ntf.calculix.writer import StepSpec, write_inp",
        "",
        "# V: vector P1/P2 space; cell_tags, facet_tags; pair: a dolfinx_ntf.ContactPair",
        "for folder in ('ccx', 'ntf'):",
        "    Path(folder).mkdir(exist_ok=True)",
        "top, bottom = ntf.FacetSurface(facet_tags, TOP), ntf.FacetSurface(facet_tags, BOTTOM)",
        "step = StepSpec(pressures=[PressureSpec(top, 10.0)], increments=4,",
        "                field_controls=TIGHT_FIELD_CONTROLS)",
        "fixed = [BoundarySpec(bottom)]  # and whatever else holds the bodies (rollers...)",
        "write_inp('ccx/job.inp', displacement_space=V, materials={1: (E1, nu1), 2: (E2, nu2)},",
        "          cell_tags=cell_tags, pairs=[pair], fixed=fixed, steps=[step])",
        "shutil.copy('ccx/job.inp', 'ntf/job.inp')",
        "run_ccx('ccx', 'job')",
        "result = run_job('job', 'ntf', tight=True)",
        "print(compare_job('ccx/job.dat', result, read_sta('ccx/job.sta')).summary())",
        "```",
        "",
    ]
    if extra.get("other") is not None:
        out += _release_comparison(out, *extra["other"])
    failures = extra.get("failures", {})
    if failures:
        out += [
            "## Cases that did not run",
            "",
            "| case | what | error |",
            "|---|---|---|",
            *(f"| `{name}` | {what} | {error} |" for name, (what, error) in failures.items()),
            "",
        ]
    path.write_text("\n".join(out))


# ----------------------------------------------------------------------------- main


def main(argv: typing.Sequence[str] | None = None) -> dict[str, Run]:
    """Run every case (or ``--only`` some) and write the report."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", type=Path, default=ROOT / "docs" / "validation.md")
    parser.add_argument("--workdir", type=Path, default=None, help="keep the runs here")
    parser.add_argument("--only", nargs="*", default=None, help="case names")
    parser.add_argument(
        "--other-release",
        type=Path,
        default=None,
        help="the report made on the other Debian release, to compare with",
    )
    args = parser.parse_args(argv)
    if MPI.COMM_WORLD.size > 1:
        raise SystemExit("validate.py runs in serial")
    if shutil.which("ccx") is None:
        raise SystemExit("ccx not found: apt-get install calculix-ccx")
    logging.getLogger("dolfinx_ntf").setLevel(logging.WARNING)

    definitions = [(c.name, c.description, c.write, c.quirk) for c in cases.CASES]
    definitions += [(c.name, c.description, c.write, c.quirk) for c in friction_cases.CASES]
    frictional = {c.name for c in friction_cases.CASES}
    definitions += [
        (
            "hertz",
            "Hertz: quarter sphere on a block, C3D4, LINEAR, automatic increments",
            hertz_deck,
            "",
        ),
        ("patch_hex", "Patch test, C3D8, matching", lambda d: patch_deck(d, "hexahedron"), ""),
        ("patch_tet", "Patch test, C3D4, matching", lambda d: patch_deck(d, "tetrahedron"), ""),
        (
            "patch_hex_nonmatching",
            "Patch test, C3D8, non-matching",
            lambda d: patch_deck(d, "hexahedron", False),
            "",
        ),
        (
            "patch_tet_nonmatching",
            "Patch test, C3D4, non-matching",
            lambda d: patch_deck(d, "tetrahedron", False),
            "",
        ),
        (
            "impact_dynamic",
            "Block hitting a base: C3D8, *DYNAMIC DIRECT, LINEAR, initial velocity",
            lambda d: write_impact_deck(d, "impact_dynamic", gap=0.0102),
            "",
        ),
    ]
    if args.only:
        unknown = set(args.only) - {d[0] for d in definitions}
        if unknown:
            raise SystemExit(f"unknown case(s) {sorted(unknown)}")
        definitions = [d for d in definitions if d[0] in args.only]

    with tempfile.TemporaryDirectory() as tmp:
        workdir = args.workdir or Path(tmp)
        runs: dict[str, Run] = {}
        extra: dict[str, typing.Any] = {"lag": {}, "other": None}
        if args.other_release is not None:
            extra["other"] = (args.other_release, args.other_release.read_text())
        extra["failures"] = {}
        for name, description, write, quirk in definitions:
            start = time.perf_counter()
            try:
                run = run_case(name, description, write, workdir, quirk)
            except (CcxError, ContactConvergenceError) as error:
                lines = str(error).replace(f"{workdir}/", "").splitlines()
                errors = [line.strip() for line in lines if "*ERROR" in line]
                extra["failures"][name] = (description, " ".join([lines[0], *errors[-1:]]))
                print(f"{name}: failed: {extra['failures'][name][1]}", flush=True)
                continue
            runs[name] = run
            if name in _DYNAMIC or name in frictional:  # CELS: no area estimate from it
                print(f"{name}: {time.perf_counter() - start:.1f} s; {run.comparison.summary()}")
                continue
            extra["lag"][name] = (
                spring_area_lag(run.deck, run.ccx_dat),
                spring_area_lag(run.deck, run.ntf_dat),
            )
            print(
                f"{name}: {time.perf_counter() - start:.1f} s; {run.comparison.summary()}",
                flush=True,
            )
        if "tet_nlgeom_pressure" in runs:
            run = runs["tet_nlgeom_pressure"]
            deck_path = run.directory / "ccx" / f"{run.name}.inp"
            extra["balance"] = (
                cases.pressure_balance(deck_path, run.ccx_dat),
                cases.pressure_balance(deck_path, run.ntf_dat),
            )
        if "hertz" in runs:
            run = runs["hertz"]
            extra["hertz_values"] = {
                "ccx": hertz_results(run.deck, run.ccx_dat),
                "dolfinx_ntf": hertz_results(run.deck, run.ntf_dat),
            }
        patches = {n: runs[n] for n in _ANALYTIC[1:] if n in runs}
        if patches:
            extra["patch_values"] = {
                n: {
                    "ccx": patch_results(r.deck, r.ccx_dat),
                    "dolfinx_ntf": patch_results(r.deck, r.ntf_dat),
                }
                for n, r in patches.items()
            }
        args.output.parent.mkdir(parents=True, exist_ok=True)
        write_report(args.output, runs, extra)
    print(f"wrote {args.output}")
    return runs


if __name__ == "__main__":
    main()
