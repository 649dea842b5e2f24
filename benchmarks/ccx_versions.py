"""Two ccx versions on the same decks: what changed between ccx 2.20 and 2.23 (method.md §13.6).

Runs two ccx executables (default ``ccx``, the 2.20 oracle, and ``ccx-2.23``, Debian sid's) on the
cross-validation decks (``tests/data/calculix/crossval``: ``cases.py`` and ``friction_cases.py``)
and on the node-to-surface decks of ``calculix-ccx-test`` (``benchmarks/ccx_suite.py``), each in
its own directory, and compares what they wrote:

- ``.dat``: blocks matched by name, set and time; per block type the largest difference relative to
  the largest value of the old version's block (``inf``: other rows); block titles that only one
  version wrote;
- ``.frd``: the header lines of the result blocks (``-4`` and ``-5`` records) that only one version
  wrote, and per block the largest relative difference of the values;
- ``.sta``: Newton iterations summed over the converged increments (increments).

Serial. Needs both executables on the PATH. From the repository root::

    .venv/bin/python benchmarks/ccx_versions.py
    .venv/bin/python benchmarks/ccx_versions.py --new ccx-2.23 --only contact1 hex_sliding_block
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dolfinx_ntf.calculix.ccx import read_sta
from dolfinx_ntf.calculix.dat import read_dat

ROOT = Path(__file__).resolve().parent.parent
DAT_BLOCKS = ("U", "RF", "S", "CDIS", "CSTR", "CELS")
_NUMBER_RE = re.compile(r"[-+]?\d*\.\d+(?:[Ee][-+]?\d+)?")


@dataclass
class Outcome:
    """One deck run by both versions and what differs."""

    deck: str
    status: tuple[str, str] = ("-", "-")
    iterations: tuple[str, str] = ("-", "-")
    dat: dict[str, float] = field(default_factory=dict)
    frd: dict[str, float] = field(default_factory=dict)
    titles: tuple[list[str], list[str]] = ([], [])
    headers: tuple[list[str], list[str]] = ([], [])


def crossval_decks(directory: Path) -> list[tuple[str, Path]]:
    """Write the cross-validation decks into ``directory``; (name, deck) pairs."""
    sys.path.insert(0, str(ROOT / "tests" / "data" / "calculix" / "crossval"))
    import cases
    import friction_cases

    decks = []
    for case in (*cases.CASES, *friction_cases.CASES):
        case.write(directory)
        decks.append((case.name, directory / f"{case.name}.inp"))
    return decks


def suite_decks(directory: Path) -> list[tuple[str, Path]]:
    """The node-to-surface decks of ``calculix-ccx-test``, written into ``directory``."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import ccx_suite

    decks = []
    for name, text in ccx_suite.node_to_surface_decks(None):
        path = directory / f"{name}.inp"
        path.write_text(text, encoding="latin-1")
        decks.append((name, path))
    return decks


def run(executable: str, deck: Path, directory: Path, timeout: float) -> str:
    """Run ``executable -i`` on a copy of ``deck`` in ``directory``; ok, error or timeout."""
    directory.mkdir(parents=True, exist_ok=True)
    shutil.copy(deck, directory / deck.name)
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_EQUATION_SOLVER="1")
    try:
        done = subprocess.run([executable, "-i", deck.stem], cwd=directory, env=env,
                              capture_output=True, text=True, errors="replace",
                              timeout=timeout)  # fmt: skip
    except subprocess.TimeoutExpired:
        return "timeout"
    errors = [line for line in done.stdout.splitlines() if "*ERROR" in line]
    return "error" if errors or done.returncode != 0 else "ok"


def _iterations(path: Path) -> str:
    rows = read_sta(path) if path.is_file() else []
    return f"{sum(r.iterations for r in rows)} ({len(rows)})" if rows else "-"


def _titles(path: Path) -> list[str]:
    """The distinct block titles of a ``.dat`` file, times and step/increment numbers left out."""
    seen: dict[str, None] = {}
    for line in path.read_text(encoding="latin-1").splitlines():
        tokens = line.split()
        if not tokens or re.fullmatch(r"-?\d+|-?\d*\.\d.*", tokens[0]):
            continue
        seen[re.sub(r"\s+\d+$", " N", _NUMBER_RE.sub("T", line).rstrip())] = None
    return list(seen)


def compare_dat(old: Path, new: Path) -> dict[str, float]:
    """Largest relative difference per block type over the blocks both ``.dat`` files have."""
    theirs = {(b.name, b.set, round(b.time, 6)): b for b in read_dat(new)}
    out: dict[str, float] = {}
    for block in read_dat(old):
        other = theirs.get((block.name, block.set, round(block.time, 6)))
        if other is None:
            continue
        same_rows = np.array_equal(other.labels, block.labels)
        if other.values.shape != block.values.shape or not same_rows:
            out[block.name] = float("inf")
            continue
        scale = float(np.abs(block.values).max(initial=0.0))
        diff = float(np.abs(other.values - block.values).max(initial=0.0))
        out[block.name] = max(out.get(block.name, 0.0), diff / scale if scale > 0 else diff)
    return out


def read_frd(path: Path) -> tuple[list[str], dict[str, list[tuple[np.ndarray, np.ndarray]]]]:
    """Header records (``-4``, ``-5``) and each result block's (node labels, values), by name."""
    headers: list[str] = []
    blocks: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    name, labels, values = None, [], []

    def close() -> None:
        if name is not None and labels:
            blocks.setdefault(name, []).append((np.array(labels), np.array(values)))

    for line in path.read_text(encoding="latin-1").splitlines():
        key = line[:3]
        if key == " -4":
            close()
            name, labels, values = line.split()[1], [], []
            headers.append(line.rstrip())
        elif key == " -5":
            headers.append(line.rstrip())
        elif key == " -1" and name is not None:
            labels.append(int(line[3:13]))
            body = line[13:]
            values.append([float(body[i : i + 12]) for i in range(0, len(body.rstrip()), 12)])
        elif key == " -3":
            close()
            name = None
    close()
    return headers, blocks


def compare_frd(old: Path, new: Path) -> tuple[dict[str, float], tuple[list[str], list[str]]]:
    """Per result block name the largest relative difference; header records only one file has."""
    old_headers, old_blocks = read_frd(old)
    new_headers, new_blocks = read_frd(new)
    out: dict[str, float] = {}
    for name, series in old_blocks.items():
        for (labels, values), other in zip(series, new_blocks.get(name, [])):
            if other[1].shape != values.shape or not np.array_equal(other[0], labels):
                out[name] = float("inf")
                continue
            scale = float(np.abs(values).max(initial=0.0))
            diff = float(np.abs(other[1] - values).max(initial=0.0))
            out[name] = max(out.get(name, 0.0), diff / scale if scale > 0 else diff)
    only_old = list(dict.fromkeys(h for h in old_headers if h not in new_headers))
    only_new = list(dict.fromkeys(h for h in new_headers if h not in old_headers))
    return out, (only_old, only_new)


def compare_deck(name: str, deck: Path, root: Path, old: str, new: str, timeout: float) -> Outcome:
    """Run both versions on one deck and compare their files."""
    dirs = (root / "old" / name, root / "new" / name)
    outcome = Outcome(name)
    outcome.status = tuple(run(exe, deck, d, timeout) for exe, d in zip((old, new), dirs))
    outcome.iterations = tuple(_iterations(d / f"{deck.stem}.sta") for d in dirs)
    dats = [d / f"{deck.stem}.dat" for d in dirs]
    if all(p.is_file() for p in dats):
        outcome.dat = compare_dat(*dats)
        titles = [_titles(p) for p in dats]
        outcome.titles = ([t for t in titles[0] if t not in titles[1]],
                          [t for t in titles[1] if t not in titles[0]])  # fmt: skip
    frds = [d / f"{deck.stem}.frd" for d in dirs]
    if all(p.is_file() for p in frds):
        outcome.frd, outcome.headers = compare_frd(*frds)
    return outcome


def _largest(differences: dict[str, float]) -> str:
    if not differences:
        return "-"
    name = max(differences, key=differences.get)
    return f"{differences[name]:.1e} ({name})"


def report(outcomes: list[Outcome], old: str, new: str) -> str:
    """A markdown table, then the titles and header records that only one version wrote."""
    head = ["deck", f"{old} / {new}", "iterations (increments)", *DAT_BLOCKS, "other .dat", ".frd"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for o in outcomes:
        cells = [o.deck, " / ".join(o.status), " / ".join(o.iterations)]
        cells += [f"{o.dat[k]:.1e}" if k in o.dat else "-" for k in DAT_BLOCKS]
        cells += [
            _largest({k: v for k, v in o.dat.items() if k not in DAT_BLOCKS}),
            _largest(o.frd),
        ]
        lines.append("| " + " | ".join(cells) + " |")
    for label, pick in ((".dat titles", lambda o: o.titles), (".frd headers", lambda o: o.headers)):
        seen: dict[tuple[str, str], list[str]] = {}
        for o in outcomes:
            for side, texts in zip((old, new), pick(o)):
                for text in texts:
                    seen.setdefault((side, text), []).append(o.deck)
        if seen:
            lines += ["", f"{label} written by one version only:"]
            lines += [f"- {side}: `{text}` ({len(d)} decks)" for (side, text), d in seen.items()]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", default="ccx", help="older ccx (default ccx)")
    parser.add_argument("--new", default="ccx-2.23", help="newer ccx (default ccx-2.23)")
    parser.add_argument("--only", nargs="*", help="deck names (default: all)")
    parser.add_argument("--keep", type=Path, help="run in this directory and keep the files")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per run")
    args = parser.parse_args(argv)
    for exe in (args.old, args.new):
        if shutil.which(exe) is None:
            print(f"{exe} not found on PATH", file=sys.stderr)
            return 1
    with tempfile.TemporaryDirectory() as scratch:
        root = args.keep or Path(scratch)
        (root / "decks").mkdir(parents=True, exist_ok=True)
        decks = crossval_decks(root / "decks") + suite_decks(root / "decks")
        outcomes = []
        for name, deck in decks:
            if args.only and name not in args.only:
                continue
            outcomes.append(compare_deck(name, deck, root, args.old, args.new, args.timeout))
            print(f"  {name}: {' / '.join(outcomes[-1].status)}", file=sys.stderr)
    print(report(outcomes, args.old, args.new))
    return 0


if __name__ == "__main__":
    sys.exit(main())
