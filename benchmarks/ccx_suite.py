"""CalculiX's own node-to-surface test decks: ccx (2.20, or ``$CCX``) against ``dolfinx-ntf run``.

Every deck of the Debian package ``calculix-ccx-test`` (``/usr/share/doc/calculix-ccx-test/examples
/test``, ``.inp`` or ``.inp.gz``) that contains ``TYPE=NODE TO SURFACE`` is run by ``ccx`` and by
``python -m dolfinx_ntf run``, both at the deck's (ccx's default) controls, each in its own
directory. The ``.dat`` blocks both codes printed are matched by block, set and time; for each block
type the table gives the largest difference relative to the largest value of ccx's block. It also
lists whether our run completed, the reason it refused the deck or stopped, and the Newton
iterations of both codes (sum over the converged increments, from the ``.sta`` files, and the
number of increments).

dolfinx_ntf runs every deck in one process (``python -m dolfinx_ntf run JOB1 JOB2 ...``, each job
in its own directory), so that its start-up is paid once; its time per deck is the span of that
job's output, and ``--separate`` runs one process per deck instead (start-up included per deck).

Serial. Needs ``ccx`` on the PATH (``$CCX`` selects another, e.g. ``CCX=ccx-2.23``). Run from the
repository root (``make ccx-suite``, about 15 s)::

    .venv/bin/python benchmarks/ccx_suite.py
    .venv/bin/python benchmarks/ccx_suite.py --only contact1 cubespring --keep /tmp/suite
"""

from __future__ import annotations

import argparse
import gzip
import re
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dolfinx_ntf.calculix.ccx import CcxError, ccx_executable, read_sta
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.frd import read_frd

SUITE = Path("/usr/share/doc/calculix-ccx-test/examples/test")
BLOCKS = ("U", "V", "RF", "S", "NT", "CDIS", "CSTR", "CELS")


@dataclass
class Row:
    """One deck's outcome."""

    deck: str
    runs: str = "no"
    reason: str = ""
    differences: dict[str, float] = field(default_factory=dict)
    compared: int = 0
    ccx_iterations: str = "-"
    ntf_iterations: str = "-"
    ccx_time: float = 0.0
    ntf_time: float = 0.0


def node_to_surface_decks(only: list[str] | None) -> list[tuple[str, str]]:
    """(name, text) of the suite's node-to-surface decks, by name."""
    decks = []
    for source in sorted(SUITE.glob("*.inp*")):
        name = source.name.removesuffix(".gz").removesuffix(".inp")
        if only and name not in only:
            continue
        opener = gzip.open if source.suffix == ".gz" else open
        with opener(source, "rt", encoding="latin-1") as stream:
            text = stream.read()
        if re.search(r"TYPE\s*=\s*NODE\s*TO\s*SURFACE", text, re.IGNORECASE):
            decks.append((name, text))
    return decks


def ccx_version(ccx: str) -> str:
    """The version ``ccx -v`` prints (``2.20``), or ``unknown``."""
    try:
        banner = subprocess.run([ccx, "-v"], capture_output=True, text=True, timeout=30).stdout
        return banner.split("Version", 1)[1].split()[0]
    except (OSError, IndexError, subprocess.SubprocessError):
        return "unknown"


def _iterations(path: Path) -> str:
    if not path.is_file():
        return "-"
    rows = read_sta(path)
    return f"{sum(r.iterations for r in rows)} ({len(rows)} inc)" if rows else "0"


def _reason(output: str) -> str:
    lines = [line.strip() for line in output.splitlines() if "*ERROR" in line]
    if not lines:
        return output.strip().splitlines()[-1][:120] if output.strip() else ""
    text = lines[0].replace("*ERROR:", "").strip()
    return re.sub(r"^\S+\.inp:\d+: ", "", text)[:120]


def compare(ccx_dat: Path, ntf_dat: Path) -> tuple[dict[str, float], int]:
    """Largest relative difference per block type over the blocks both files have."""
    ours = {(b.name, b.set, round(b.time, 6)): b for b in read_dat(ntf_dat)}
    differences: dict[str, float] = {}
    compared = 0
    for block in read_dat(ccx_dat):
        mine = ours.get((block.name, block.set, round(block.time, 6)))
        name = block.name.removesuffix("_TOTAL")
        if mine is None or name not in BLOCKS:
            continue
        if mine.values.shape != block.values.shape or not np.array_equal(mine.labels, block.labels):
            differences[name] = float("inf")  # other rows (e.g. other contact elements)
            continue
        scale = float(np.abs(block.values).max(initial=0.0))
        diff = float(np.abs(mine.values - block.values).max(initial=0.0))
        relative = diff / scale if scale > 0 else diff
        differences[name] = max(differences.get(name, 0.0), relative)
        compared += 1
    return differences, compared


def _prepare(name: str, text: str, root: Path) -> tuple[Path, Path]:
    """The deck's ccx and ntf directories, each with its copy of the deck."""
    ccx_dir, ntf_dir = root / name / "ccx", root / name / "ntf"
    for directory in (ccx_dir, ntf_dir):
        directory.mkdir(parents=True, exist_ok=True)
        (directory / f"{name}.inp").write_text(text, encoding="latin-1")
    return ccx_dir, ntf_dir


def run_ccx_deck(name: str, text: str, root: Path, timeout: float) -> Row:
    """Run one deck with ccx: the row with ccx's time and iterations."""
    row = Row(name)
    ccx_dir, _ = _prepare(name, text, root)
    start = time.perf_counter()
    try:
        subprocess.run(
            [ccx_executable(), "-i", name], cwd=ccx_dir, capture_output=True, timeout=timeout
        )
    except subprocess.TimeoutExpired:
        pass
    row.ccx_time = time.perf_counter() - start
    row.ccx_iterations = _iterations(ccx_dir / f"{name}.sta")
    return row


def _finish(row: Row, root: Path, output: str, code: int) -> None:
    """Our side of ``row`` from the job's output and exit status, and the .dat comparison."""
    ccx_dir, ntf_dir = root / row.deck / "ccx", root / row.deck / "ntf"
    row.runs = {0: "yes"}.get(code, "stopped" if code == 2 else "refused")
    if code != 0:
        row.reason = _reason(output)
    row.ntf_iterations = _iterations(ntf_dir / f"{row.deck}.sta")
    ccx_dat, ntf_dat = ccx_dir / f"{row.deck}.dat", ntf_dir / f"{row.deck}.dat"
    if ccx_dat.is_file() and ntf_dat.is_file():
        row.differences, row.compared = compare(ccx_dat, ntf_dat)
    ccx_frd, ntf_frd = ccx_dir / f"{row.deck}.frd", ntf_dir / f"{row.deck}.frd"
    if not row.compared and row.runs == "yes" and ccx_frd.is_file() and ntf_frd.is_file():
        row.differences, row.compared = compare_frd(ccx_frd, ntf_frd)  # no .dat block printed


def compare_frd(ccx_frd: Path, ntf_frd: Path) -> tuple[dict[str, float], int]:
    """Like :func:`compare` on the ``.frd`` blocks DISP (column U) and CONTACT (CDIS, CSTR), for
    decks that print no ``.dat`` block (scheibe2n2f); the count is marked ``frd``."""
    ours, theirs = read_frd(ntf_frd), read_frd(ccx_frd)
    differences: dict[str, float] = {}
    compared = 0
    for name, columns in (
        ("DISP", {"U": slice(0, 3)}),
        ("CONTACT", {"CDIS": slice(0, 3), "CSTR": slice(3, 6)}),
    ):
        for mine, block in zip(ours.blocks_named(name), theirs.blocks_named(name)):
            compared += 1
            for column, part in columns.items():
                if not np.array_equal(mine.nodes, block.nodes):
                    differences[column] = float("inf")
                    continue
                scale = float(np.abs(block.values[:, part]).max(initial=0.0))
                diff = float(np.abs(mine.values[:, part] - block.values[:, part]).max(initial=0.0))
                relative = diff / scale if scale > 0 else diff
                differences[column] = max(differences.get(column, 0.0), relative)
    return differences, -compared


def run_ntf_deck(row: Row, root: Path, timeout: float) -> None:
    """Run one deck with ``python -m dolfinx_ntf run`` in its own process (``--separate``)."""
    start = time.perf_counter()
    try:
        done = subprocess.run(
            [sys.executable, "-m", "dolfinx_ntf", "run", row.deck],
            cwd=root / row.deck / "ntf",
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        output, code = done.stdout + done.stderr, done.returncode
    except subprocess.TimeoutExpired:
        output, code = f"*ERROR: timed out after {timeout:.0f} s", -1
    row.ntf_time = time.perf_counter() - start
    _finish(row, root, output, code)


_JOB = re.compile(r"^ Job \d+/\d+: (\S+)$")
_SUMMARY = re.compile(r"^ \d+ jobs, \d+ done:$")
_STATUS = re.compile(r"^   (\S+): .* \(exit (-?\d+)\)$")


def run_ntf_batch(rows: list[Row], root: Path, timeout: float) -> float:
    """Run every deck in one ``python -m dolfinx_ntf run JOB1 JOB2 ...`` (start-up paid once).

    Each row gets its job's status, output (from its ``Job`` line to the next one) and time (the
    same span). Returns the wall time of the whole process.
    """
    jobs = [str(root / r.deck / "ntf" / r.deck) for r in rows]
    by_job = dict(zip(jobs, rows))
    outputs: dict[str, list[str]] = {job: [] for job in jobs}
    started: dict[str, float] = {}
    codes: dict[str, int] = {}
    current: str | None = None
    start = time.perf_counter()
    # unbuffered, stderr into stdout: every line lands under its job's header
    with subprocess.Popen(
        [sys.executable, "-u", "-m", "dolfinx_ntf", "run", *jobs],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    ) as process:
        timer = threading.Timer(timeout * max(len(jobs), 1), process.kill)
        timer.start()
        try:
            for line in process.stdout:
                line = line.rstrip("\n")
                now = time.perf_counter()
                job = _JOB.match(line)
                if job or _SUMMARY.match(line):
                    if current is not None:
                        by_job[current].ntf_time = now - started[current]
                    current = job.group(1) if job else None
                    if current is not None:
                        started[current] = now
                    continue
                status = _STATUS.match(line)
                if current is None and status and status.group(1) in by_job:
                    codes[status.group(1)] = int(status.group(2))
                elif current is not None:
                    outputs[current].append(line)
        finally:
            timer.cancel()
    wall = time.perf_counter() - start
    if current is not None:  # killed or crashed within a job
        by_job[current].ntf_time = time.perf_counter() - started[current]
    for job, row in by_job.items():
        code = codes.get(job, -1)
        text = "\n".join(outputs[job]) or f"*ERROR: no status (the batch stopped, exit {code})"
        _finish(row, root, text, code)
    return wall


def table(rows: list[Row]) -> str:
    """The result table (markdown)."""
    head = ["deck", "runs", "refusal / stop reason", *BLOCKS, "blocks", "ccx iter", "ntf iter"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r.deck, r.runs, r.reason or "-"]
        cells += [f"{r.differences[k]:.1e}" if k in r.differences else "-" for k in BLOCKS]
        compared = f"{-r.compared} (frd)" if r.compared < 0 else str(r.compared)
        cells += [compared, r.ccx_iterations, r.ntf_iterations]
        lines.append("| " + " | ".join(c.replace("|", "/") for c in cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", help="deck names (default: all)")
    parser.add_argument("--keep", type=Path, help="run in this directory and keep the files")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per run")
    parser.add_argument(
        "--separate",
        action="store_true",
        help="one dolfinx_ntf process per deck (default: one `run JOB1 JOB2 ...` for all)",
    )
    args = parser.parse_args(argv)
    try:
        ccx = ccx_executable()
    except CcxError:
        ccx = None
    if ccx is None or not SUITE.is_dir():
        print("needs ccx (or $CCX) and the package calculix-ccx-test", file=sys.stderr)
        return 1
    version = ccx_version(ccx)
    decks = node_to_surface_decks(args.only)
    with tempfile.TemporaryDirectory() as scratch:
        root = args.keep or Path(scratch)
        rows = [run_ccx_deck(name, text, root, args.timeout) for name, text in decks]
        if args.separate or len(rows) == 1:  # one job: `run` prints no job header nor status
            for row in rows:
                run_ntf_deck(row, root, args.timeout)
            wall = sum(row.ntf_time for row in rows)
        else:
            wall = run_ntf_batch(rows, root, args.timeout)
        for row in rows:
            print(f"  {row.deck}: {row.runs} ({row.ccx_time:.2f} s ccx, {row.ntf_time:.2f} s ntf)",
                  file=sys.stderr)  # fmt: skip
        how = "one process per deck" if args.separate else "one process for all decks"
        print(f"  ccx {sum(r.ccx_time for r in rows):.1f} s, dolfinx_ntf {wall:.1f} s ({how})",
              file=sys.stderr)  # fmt: skip
    print(
        f"ccx {version} against dolfinx-ntf run on the {len(rows)} node-to-surface decks of "
        f"calculix-ccx-test, both at the deck's controls.\nColumns U..CELS: largest |ours - ccx| "
        "over each printed .dat block of that type, relative to the largest |value| of ccx's "
        "block (inf: the blocks have different rows); blocks: number of blocks compared (frd: a "
        "deck printing no .dat block, its .frd DISP and CONTACT blocks compared instead); "
        "iterations: Newton iterations summed over the converged increments (increments).\n"
    )
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
