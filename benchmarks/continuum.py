"""Node-to-face springs against UFL penalty and Nitsche on the Hertz sphere; docs/comparison.md.

The Hertz sphere of ``demos/compare_continuum.py`` (R = 25 mm, steel, pushed 0.3 mm onto a rigid
plane in 4 increments) at three mesh levels (``size_fine`` / R = 0.02, 0.013, 0.0085: about 5k,
13k and 33k dofs for the sphere), every method on the same sphere cells:

- ``ntf-rigid``: node-to-face springs against ``RigidPlane`` (K = 10 E);
- ``ntf-active``: the same with the active-set Newton (docs/method.md §15.5);
- ``ntf-meshed``: node-to-face springs against the clamped meshed block (its dofs count; skipped
  above ``--max-meshed-dofs``);
- ``penalty``: UFL penalty (k = 10 E);
- ``nitsche``: Nitsche, gamma0 = 10, theta = 1.

Sweeps on the middle level: K and k in {5, 10, 50, 100} E, gamma0 in {1, 10, 100}, theta in
{1, 0, -1}. Every run is compared with Hertz at its own force (errors of a and p0, fitted; a from
the contact area; the nodes bracketing the edge; the largest nodal recovered pressure), with its
largest penetration, Newton iterations per increment and the time split (bulk assembly, contact,
linear solve; wall-clock on a shared machine). Writes ``docs/comparison-<dolfinx>.png`` (errors
of a and p0 against h) and replaces this dolfinx version's section of ``docs/comparison.md``.
Serial; from the repository root::

    .venv/bin/python benchmarks/continuum.py            # about 10 minutes on 2 shared cores
    .venv/bin/python benchmarks/continuum.py --quick    # coarse mesh and the first level only
    .venv/bin/python benchmarks/continuum.py --no-sweeps --methods ntf-rigid penalty nitsche
"""

from __future__ import annotations

import argparse
import datetime as dt
import importlib.util
import json
import platform
import re
import sys
import time
from pathlib import Path

import numpy as np

import dolfinx

ROOT = Path(__file__).resolve().parents[1]
LEVELS = (0.02, 0.013, 0.0085)
SWEEP_LEVEL = 1
SWEEPS = (
    [("ntf-rigid", {"penalty": k}) for k in (5.0, 50.0, 100.0)]
    + [("penalty", {"penalty": k}) for k in (5.0, 50.0, 100.0)]
    + [("nitsche", {"gamma0": g}) for g in (1.0, 100.0)]
    + [("nitsche", {"theta": t}) for t in (0, -1)]
)
#: Stiffer springs on the finest level: node-to-face nearer Hertz, with less penalty error.
FINEST_EXTRA = [("ntf-rigid", {"penalty": k}) for k in (50.0, 100.0)]


def _demo():
    spec = importlib.util.spec_from_file_location(
        "_compare", ROOT / "demos" / "compare_continuum.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _label(method: str, params: dict) -> str:
    base = {"penalty": 10.0, "gamma0": 10.0, "theta": 1}
    if method.startswith("ntf") or method == "penalty":
        keys = ["penalty"]
    elif method == "nitsche":
        keys = ["gamma0", "theta"]
    return method + "".join(
        f" {'K' if method.startswith('ntf') else 'k' if k == 'penalty' else k}="
        f"{params.get(k, base[k]):g}{' E' if k == 'penalty' else ''}"
        for k in keys
    )


def run(
    levels: tuple[float, ...],
    sweeps: bool,
    max_meshed_dofs: int,
    extra_only: bool = False,
    methods: tuple[str, ...] | None = None,
) -> list[dict]:
    """Every method at every level, then the sweeps; returns one row per run."""
    demo = _demo()
    rows = []
    for index, level in enumerate(levels):
        if extra_only and index != len(levels) - 1:
            continue
        start = time.perf_counter()
        meshes = demo.make_meshes(level)
        mesh_time = time.perf_counter() - start
        cases = [] if extra_only else [(m, {}) for m in methods or demo.METHODS]
        if sweeps and index == SWEEP_LEVEL:
            cases += SWEEPS
        if sweeps and index == len(levels) - 1:
            cases += FINEST_EXTRA
        for method, params in cases:
            if method == "ntf-meshed":
                dofs = 3 * meshes["two-body"][0].topology.index_map(0).size_global
                if dofs > max_meshed_dofs:
                    print(f"h/R = {level}: ntf-meshed skipped ({dofs} dofs)", flush=True)
                    continue
            try:
                row = demo.run(method, meshes, **params)
            except (RuntimeError, ValueError) as error:  # a failed run is a result too
                row = {"method": method, "failed": str(error)}
            row.update(level=level, label=_label(method, params), mesh_time=mesh_time)
            rows.append(row)
            print(_line(row), flush=True)
    return rows


def _line(r: dict) -> str:
    if "failed" in r:
        return f"{r['level']:<7g} {r['label']:<26} FAILED: {r['failed']}"
    return (
        f"{r['level']:<7g} {r['label']:<26} {r['dofs']:>6} {r['force']:>9.4g} "
        f"{r['a_error']:>+7.2%} {r['a_area_error']:>+7.2%} {r['p0_error']:>+7.2%} "
        f"{r['p_max_error']:>+7.2%} {1e3 * r['penetration']:>7.2f} "
        f"{','.join(map(str, r['iterations'])):<10} {r['time']:>6.1f} {r['time_bulk']:>6.1f} "
        f"{r['time_contact']:>6.1f} {r['time_solve']:>6.1f}"
    )


HEADER = (
    "| h/R | method | dofs | F [kN] | a fit | a area | a bracket [mm] | p0 fit | p max | "
    "pen. [um] | F(p_h)/F-1 | iterations | time [s] | bulk | contact | solve |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
)


def _table(rows: list[dict]) -> str:
    lines = []
    for r in rows:
        if "failed" in r:
            lines.append(f"| {r['level']:g} | {r['label']} | failed: {r['failed']} |" + " |" * 13)
            continue
        lines.append(
            f"| {r['level']:g} | {r['label']} | {r['dofs']} | {r['force'] / 1e3:.2f} | "
            f"{r['a_error']:+.2%} | {r['a_area_error']:+.2%} | "
            f"{r['a_last_closed']:.3f}-{r['a_first_open']:.3f} (a = {r['a_hertz']:.3f}) | "
            f"{r['p0_error']:+.2%} | {r['p_max_error']:+.2%} | {1e3 * r['penetration']:.2f} | "
            f"{r['pressure_force_error']:+.1e} | {','.join(map(str, r['iterations']))} | "
            f"{r['time']:.1f} | {r['time_bulk']:.1f} | {r['time_contact']:.1f} | "
            f"{r['time_solve']:.1f} |"
        )
    return HEADER + "\n".join(lines) + "\n"


def _plot(rows: list[dict], path: Path, title: str) -> None:
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    base = [r for r in rows if "failed" not in r and r["label"].split()[0] == r["method"]]
    default = {}
    for r in base:
        if r["label"] in (
            "ntf-rigid K=10 E",
            "ntf-active K=10 E",
            "ntf-meshed K=10 E",
            "penalty k=10 E",
            "nitsche gamma0=10 theta=1",
        ):
            default.setdefault(r["label"], []).append(r)
    for label, runs in default.items():
        runs.sort(key=lambda r: r["level"])
        h = [r["level"] for r in runs]
        for ax, key in zip(axes, ("a_error", "p0_error")):
            ax.semilogx(h, [100 * r[key] for r in runs], "o-", label=label)
    for ax, what in zip(axes, ("contact radius a (fit)", "peak pressure p0 (fit)")):
        ax.set_xlabel("fine mesh size h / R")
        ax.set_ylabel(f"error of {what} against Hertz [%]")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _section(rows: list[dict], png: Path, total: float, measured: str) -> str:
    version = dolfinx.__version__
    with open("/etc/os-release") as f:
        release = re.search(r'PRETTY_NAME="(.*)"', f.read()).group(1)
    return (
        f"<!-- dolfinx {version} start -->\n"
        f"## dolfinx {version} ({release}, Python {platform.python_version()}, numpy "
        f"{np.__version__})\n\n"
        f"Measured {measured} with `benchmarks/continuum.py` on a shared 2-core machine "
        f"(wall-clock times, other jobs running; {total / 60:.1f} min in all).\n\n"
        + _table(rows)
        + f"\n![errors of a and p0 against h]({png.name})\n"
        + f"<!-- dolfinx {version} end -->\n"
    )


def _write(section: str, version: str) -> Path:
    path = ROOT / "docs" / "comparison.md"
    text = path.read_text() if path.exists() else ""
    v = re.escape(version)
    pattern = re.compile(rf"<!-- dolfinx {v} start -->.*?<!-- dolfinx {v} end -->\n", re.S)
    text = pattern.sub(lambda _: section, text) if pattern.search(text) else text + "\n" + section
    path.write_text(text)
    return path


def main(argv: list[str] | None = None) -> list[dict]:
    """Run the benchmark and write the report."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="coarse mesh, one level, no sweeps")
    parser.add_argument("--max-meshed-dofs", type=int, default=50_000)
    parser.add_argument("--json", type=Path, default=None, help="also write the rows here")
    parser.add_argument(
        "--extra-only",
        type=Path,
        default=None,
        metavar="JSON",
        help="run only the finest level's extra cases and add them to the rows of JSON",
    )
    parser.add_argument(
        "--replot", type=Path, default=None, metavar="JSON", help="report the rows of JSON, no runs"
    )
    parser.add_argument("--levels", type=float, nargs="+", default=list(LEVELS), help="h / R")
    parser.add_argument("--methods", nargs="+", default=None, help="default: all")
    parser.add_argument("--no-sweeps", action="store_true", help="no parameter sweeps")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    levels = (0.04,) if args.quick else tuple(args.levels)
    if args.replot:
        rows = json.loads(args.replot.read_text())
        mtime = dt.datetime.fromtimestamp(args.replot.stat().st_mtime, dt.timezone.utc)
        return _report(rows, sum(r.get("time", 0.0) for r in rows), f"{mtime:%Y-%m-%d %H:%M} UTC")
    previous = json.loads(args.extra_only.read_text()) if args.extra_only else []
    rows = previous + run(
        levels,
        sweeps=not (args.quick or args.no_sweeps),
        max_meshed_dofs=args.max_meshed_dofs,
        extra_only=args.extra_only is not None,
        methods=tuple(args.methods) if args.methods else None,
    )
    total = time.perf_counter() - start + sum(r.get("time", 0.0) for r in previous)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=float))
    if args.quick:
        print(_table(rows))
        return rows
    return _report(rows, total, f"{dt.datetime.now(dt.timezone.utc):%Y-%m-%d %H:%M} UTC")


def _report(rows: list[dict], total: float, measured: str) -> list[dict]:
    """Plot and write this dolfinx version's section of docs/comparison.md."""
    version = dolfinx.__version__
    png = ROOT / "docs" / f"comparison-dolfinx-{version}.png"
    _plot(rows, png, f"Hertz sphere on a rigid plane, dolfinx {version}")
    print(f"wrote {_write(_section(rows, png, total, measured), version)} and {png}")
    return rows


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
