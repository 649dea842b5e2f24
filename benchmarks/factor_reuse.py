"""Reusing factorizations against fresh ones: ``--factorization reuse`` against ``fresh``.

Every deck runs twice in one ``python -m dolfinx_ntf run JOB1 JOB2 ...`` per path (start-up paid
once per path): with a fresh factorization per Newton iteration (the exact path) and with GMRES
preconditioned by an earlier factorization (``dolfinx_ntf.solvers.factor_reuse``). For each deck
the table gives the Newton iterations per increment of both paths (``.sta``), whether the ``.dat``
files are byte-identical, and the largest difference of the printed ``.dat`` values relative to
the largest value of their block (``dolfinx_ntf.calculix.dat.read_dat``), over all blocks.

Decks: the ``.inp`` files under ``tests/data/calculix``, CalculiX's node-to-surface test decks
(``benchmarks/ccx_suite.py``), the cross-validation decks
(``tests/data/calculix/crossval/cases.py``) and ``benchmarks/ccx_decks.py``'s ``punch_10``,
``punch_20`` and ``quarter_sphere_coarse`` (``--decks`` picks others of its decks).

With ``--time DECK ...`` it times ``benchmarks/ccx_decks.py`` decks instead: ``--runs``
alternating runs of ``python -m dolfinx_ntf run --factorization fresh|auto JOB`` after a warm-up
of each, one thread, each a process of its own; median wall and CPU (user + system) of the
process, and the 1-minute load average.

    .venv/bin/python benchmarks/factor_reuse.py                 # all of them
    .venv/bin/python benchmarks/factor_reuse.py --only suite    # only CalculiX's decks
    .venv/bin/python benchmarks/factor_reuse.py --time punch_20 punch_30 --runs 3
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT))

from dolfinx_ntf.calculix.ccx import read_sta  # noqa: E402
from dolfinx_ntf.calculix.dat import read_dat  # noqa: E402

PATHS = ("fresh", "reuse")


def collect_decks(root: Path, groups: list[str], bench: list[str]) -> list[tuple[str, Path]]:
    """(group, deck directory/name without .inp) of the decks, each written into its directory."""
    decks: list[tuple[str, Path]] = []

    def add(group: str, name: str, text: str) -> None:
        directory = root / f"{group}-{name}"
        directory.mkdir(parents=True, exist_ok=True)
        (directory / f"{name}.inp").write_text(text, encoding="latin-1")
        decks.append((group, directory / name))

    if "tests" in groups:
        for path in sorted((ROOT / "tests" / "data" / "calculix").rglob("*.inp")):
            if "include" in path.parts:
                continue  # included by other decks
            directory = root / f"tests-{path.stem}"
            directory.mkdir(parents=True, exist_ok=True)
            for sibling in path.parent.iterdir():  # *INCLUDE'd files next to the deck
                if sibling.is_file():
                    (directory / sibling.name).write_bytes(sibling.read_bytes())
            decks.append(("tests", directory / path.stem))
    if "suite" in groups:
        import ccx_suite

        for name, text in ccx_suite.node_to_surface_decks(None):
            add("suite", name, text)
    if "crossval" in groups:
        sys.path.insert(0, str(ROOT / "tests" / "data" / "calculix" / "crossval"))
        import cases

        for case in cases.CASES:
            directory = root / f"crossval-{case.name}"
            directory.mkdir(parents=True, exist_ok=True)
            case.write(directory)
            decks.append(("crossval", directory / case.name))
    if "bench" in groups:
        import ccx_decks

        for deck in ccx_decks.select_decks(bench):
            directory = root / f"bench-{deck.name}"
            directory.mkdir(parents=True, exist_ok=True)
            deck.write(directory)
            decks.append(("bench", directory / deck.name))
    return decks


def run_batch(decks: list[Path], path: str) -> float:
    """Run ``decks`` in one process with ``--factorization path``; its CPU time (children)."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    before = os.times()
    subprocess.run(
        [sys.executable, "-m", "dolfinx_ntf", "run", "--factorization", path, *map(str, decks)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    after = os.times()
    return (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )


def timed_run(deck: Path, path: str) -> tuple[float, float, str]:
    """One ``python -m dolfinx_ntf run --factorization path`` of ``deck``: wall and CPU seconds,
    the dofs it printed."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    before, start = os.times(), time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "dolfinx_ntf", "run", "--factorization", path, deck.name],
        cwd=deck.parent,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    wall, after = time.perf_counter() - start, os.times()
    if done.returncode != 0:
        raise RuntimeError(f"{deck.name} ({path}): exit {done.returncode}\n{done.stderr[-2000:]}")
    cpu = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    dofs = re.search(r"(\d+) dofs", done.stdout + done.stderr)
    return wall, cpu, dofs.group(1) if dofs else "-"


def time_decks(root: Path, names: list[str], runs: int) -> list[str]:
    """Markdown rows: each deck's median wall and CPU with fresh and reused factorizations."""
    import statistics

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from startup import compile_bytecode

    compile_bytecode(ROOT)
    rows = ["| deck | dofs | wall fresh [s] | wall auto [s] | CPU fresh [s] | CPU auto [s] | "
            "CPU auto / fresh | load |", "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for _, deck in collect_decks(root, ["bench"], names):
        dofs = timed_run(deck, "fresh")[2]  # warm-up
        timed_run(deck, "auto")
        loads = [os.getloadavg()[0]]
        measured: dict[str, list[tuple[float, float, str]]] = {"fresh": [], "auto": []}
        for _ in range(runs):
            for path in measured:
                measured[path].append(timed_run(deck, path))
        loads.append(os.getloadavg()[0])
        wall = {p: statistics.median(r[0] for r in m) for p, m in measured.items()}
        cpu = {p: statistics.median(r[1] for r in m) for p, m in measured.items()}
        ratio = cpu["auto"] / cpu["fresh"]
        rows.append(f"| `{deck.name}` | {dofs} | {wall['fresh']:.2f} | {wall['auto']:.2f} | "
                    f"{cpu['fresh']:.2f} | {cpu['auto']:.2f} | {ratio:.2f} | "
                    f"{min(loads):.1f}-{max(loads):.1f} |")  # fmt: skip
        print(rows[-1], flush=True)
    return rows


def largest_change(first: Path, second: Path) -> float:
    """Largest difference of the printed values over the blocks, relative to each block's largest
    value; inf when the blocks differ in shape or labels."""
    if not (first.is_file() and second.is_file()):
        return float("inf")
    ours = read_dat(second)
    theirs = read_dat(first)
    if len(ours) != len(theirs):
        return float("inf")
    worst = 0.0
    for a, b in zip(theirs, ours):
        if a.values.shape != b.values.shape or not np.array_equal(a.labels, b.labels):
            return float("inf")
        scale = float(np.abs(a.values).max(initial=0.0))
        diff = float(np.abs(a.values - b.values).max(initial=0.0))
        worst = max(worst, diff / scale if scale > 0 else diff)
    return worst


def iterations(sta: Path) -> str:
    """Newton iterations per increment from a ``.sta`` file."""
    if not sta.is_file():
        return "-"
    return ", ".join(str(row.iterations) for row in read_sta(sta)) or "-"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", default=["tests", "suite", "crossval", "bench"],
                        help="deck groups: tests, suite, crossval, bench")  # fmt: skip
    parser.add_argument("--decks", nargs="+", default=["punch_10", "punch_20",
                        "quarter_sphere_coarse"], help="benchmarks/ccx_decks.py decks")  # fmt: skip
    parser.add_argument("--keep", type=Path, help="run in this directory and keep the files")
    parser.add_argument("--time", nargs="+", metavar="DECK", help="time these ccx_decks decks")
    parser.add_argument("--runs", type=int, default=3, help="timed runs per path (--time)")
    args = parser.parse_args(argv)
    if args.time:
        with tempfile.TemporaryDirectory() as scratch:
            rows = time_decks(args.keep or Path(scratch), args.time, args.runs)
        print("\n".join(rows))
        return 0
    with tempfile.TemporaryDirectory() as scratch:
        root = args.keep or Path(scratch)
        decks = collect_decks(root / "fresh", args.only, args.decks)
        copies = collect_decks(root / "reuse", args.only, args.decks)
        load = os.getloadavg()[0]
        start = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
        cpu = {
            "fresh": run_batch([d for _, d in decks], "fresh"),
            "reuse": run_batch([d for _, d in copies], "reuse"),
        }
        rows = ["| group | deck | iterations fresh | iterations reuse | .dat identical | "
                "largest change |", "|---|---|---|---|---|---|"]  # fmt: skip
        worst, same, total, equal_iterations = 0.0, 0, 0, 0
        for (group, fresh), (_, reuse) in zip(decks, copies):
            fresh_dat, reuse_dat = fresh.with_suffix(".dat"), reuse.with_suffix(".dat")
            its = (iterations(fresh.with_suffix(".sta")), iterations(reuse.with_suffix(".sta")))
            identical = (
                fresh_dat.is_file()
                and reuse_dat.is_file()
                and fresh_dat.read_bytes() == reuse_dat.read_bytes()
            )
            if not (fresh_dat.is_file() or reuse_dat.is_file()):  # refused by both paths
                rows.append(f"| {group} | `{fresh.name}` | - | - | no .dat (refused) | - |")
                continue
            change = 0.0 if identical else largest_change(fresh_dat, reuse_dat)
            worst = max(worst, change)
            same += identical
            total += 1
            equal_iterations += its[0] == its[1]
            rows.append(f"| {group} | `{fresh.name}` | {its[0]} | {its[1]} | "
                        f"{'yes' if identical else 'no'} | {change:.1e} |")  # fmt: skip
    print("\n".join(rows))
    print(
        f"\n{total} decks that ran ({start} UTC, 1-min load {load:.1f} to "
        f"{os.getloadavg()[0]:.1f}): "
        f"{equal_iterations} with the same Newton iterations, {same} with byte-identical .dat "
        f"files, largest change of a printed value {worst:.1e} (relative to its block's largest); "
        f"CPU of the batch: fresh {cpu['fresh']:.1f} s, reuse {cpu['reuse']:.1f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
