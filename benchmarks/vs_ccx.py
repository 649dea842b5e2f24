"""dolfinx_ntf against CalculiX 2.20, side by side on the same decks; writes docs/performance.md.

The decks come from ``benchmarks/ccx_decks.py`` (flat punch at several sizes, the tie punch, the
fixed-increment quarter sphere, the cross-validation decks) and from CalculiX's own test suite
(the node-to-surface decks of ``calculix-ccx-test`` that dolfinx_ntf reads, :func:`suite_decks`;
they count as quick decks). Each is written once, then run by
``ccx`` (through ``dolfinx_ntf.calculix.run_ccx``) and by ``python -m dolfinx_ntf run JOB``, each
in its own directory and its own process: one untimed warm-up of each code (it also fills the
form-compiler cache), then ``--runs`` timed runs of each, alternating ccx and dolfinx_ntf so that
a change in the machine's load hits both. A code that fails in the warm-up runs once more, timed,
and its row shows the failure.

Per deck and code:

- wall time: from process start to exit (for dolfinx_ntf this includes Python start-up, imports,
  mesh and form set-up), split for dolfinx_ntf into start-up (outside ``run_job``) and job (the
  ``run_job`` time it prints); the mean over the timed runs, and the CPU time (user + system) of the
  same runs, which a loaded machine inflates less;
- peak memory: the largest resident set size of the process (``ru_maxrss``);
- increments and Newton iterations per converged increment: ccx's from its ``.sta`` file
  (``read_sta``), dolfinx_ntf's from its progress lines (``increment N converged: ..., I
  iterations``); attempts beyond the first of an increment are cutbacks;
- the largest result difference over the increments both codes converged, read from both ``.dat``
  files with ``dolfinx_ntf.calculix.compare``: displacements (all nodes) over ccx's largest
  displacement, contact pressures (slave nodes paired in both) over ccx's largest pressure, and
  whether the same slave nodes carry contact elements;
- for decks that ask for the ``.cel`` contact element sets (the punch decks): both codes' sets
  compared pairing by pairing (``dolfinx_ntf.calculix.cel.compare_cel``), up to ccx's last
  pairing when it fails: the first pairing whose sets differ and, per pairing, the slave nodes
  with another master face or with a contact element in one code only.

Both codes run on one thread (``--threads``: ``OMP_NUM_THREADS`` for ccx, and the OpenMP/OpenBLAS
thread counts for dolfinx_ntf's MUMPS). The checkout's package is byte-compiled first
(``startup.compile_bytecode``), so that its start-up is that of an installed package also where
``PYTHONDONTWRITEBYTECODE`` is set. Serial; needs ``ccx`` on the PATH. From the repository
root::

    .venv/bin/python benchmarks/vs_ccx.py                  # every deck (about 15 minutes)
    .venv/bin/python benchmarks/vs_ccx.py --quick          # the small decks (about 2 minutes)
    .venv/bin/python benchmarks/vs_ccx.py --only tie_punch punch_20 --workdir /tmp/bench
    .venv/bin/python benchmarks/vs_ccx.py --only punch_20 punch_30 --update

A full run replaces this platform's section of ``docs/performance.md`` (other platforms' sections
stay); ``--quick`` and ``--only`` runs print their table and write a report only with
``--output``, or with ``--update``: then only the rows of the decks run now are replaced in this
platform's existing section (of ``--output``, default ``docs/performance.md``), the other rows
stay, and the section says when each row was measured (a ``measured`` column and a note per
update).
"""

from __future__ import annotations

import argparse
import ctypes
import datetime as dt
import json
import os
import platform
import re
import shlex
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import typing
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUTPUT = ROOT / "docs" / "performance.md"
COMMAND = ".venv/bin/python benchmarks/vs_ccx.py"

__all__ = ["DeckResult", "Measurement", "main", "parse_progress", "run_deck", "write_report"]

_CONVERGED = re.compile(r"^ increment (\d+) converged: time ([^,]+), (\d+) iterations")
_ATTEMPT = re.compile(r"^ increment (\d+) attempt (\d+)")
_ERROR = re.compile(r"^\s*\*ERROR:?\s*(.*)")
_JOB_TIME = re.compile(r"^ Wrote .*\((\d+) increments?, ([0-9.]+) s\)")


@dataclass
class Measurement:
    """One run of one code on one deck.

    Attributes:
        code: ``"ccx"`` or ``"dolfinx_ntf"``.
        wall: Wall time [s].
        cpu: User + system CPU time of the process [s].
        peak_rss: Largest resident set size [bytes].
        ok: The run completed (exit status 0, no error).
        error: The failure's message (empty if ``ok``).
        job_time: dolfinx_ntf's own ``run_job`` time (what it prints at the end; NaN otherwise):
            the wall time without Python start-up and imports.
    """

    code: str
    wall: float
    cpu: float
    peak_rss: int
    ok: bool
    error: str = ""
    job_time: float = float("nan")


@dataclass
class Progress:
    """What a code's output says about its increments.

    Attributes:
        iterations: Newton iterations of each converged increment, in order.
        attempts: Attempts of each converged increment (1: no cutback).
    """

    iterations: list[int] = field(default_factory=list)
    attempts: list[int] = field(default_factory=list)


@dataclass
class DeckResult:
    """Both codes on one deck.

    Attributes:
        name, description: The deck.
        dofs: Displacement dofs of the deck (3 per node).
        runs: Every measurement, warm-up first, in run order.
        ccx, ntf: Increments and iterations of the last run of each code.
        displacement, pressure: Largest relative differences over common increments (NaN when
            nothing could be compared).
        same_contact: Same slave nodes with contact elements in every common increment.
        common_increments: Increments both codes converged.
        comparison_error: Why results could not be compared (empty if they could).
        cel: Both codes' ``.cel`` files compared pairing by pairing (ccx's sets, in order; None
            without both files): :func:`dolfinx_ntf.calculix.cel.compare_cel`.
        measured: When the deck's runs started (UTC).
    """

    name: str
    description: str
    dofs: int
    runs: list[Measurement] = field(default_factory=list)
    ccx: Progress = field(default_factory=Progress)
    ntf: Progress = field(default_factory=Progress)
    displacement: float = float("nan")
    pressure: float = float("nan")
    same_contact: bool | None = None
    common_increments: int = 0
    comparison_error: str = ""
    cel: list[typing.Any] | None = None
    measured: dt.datetime | None = None

    def timed(self, code: str) -> list[Measurement]:
        """Timed runs of ``code`` (the warm-up excluded)."""
        runs = [m for m in self.runs if m.code == code]
        return runs[1:]

    def failure(self, code: str) -> str:
        """The error of ``code``'s last run, empty if it completed."""
        runs = [m for m in self.runs if m.code == code]
        return "" if not runs or runs[-1].ok else runs[-1].error

    def mean_wall(self, code: str) -> float:
        """Mean wall time of the timed runs (NaN without any)."""
        runs = self.timed(code)
        return statistics.fmean(m.wall for m in runs) if runs else float("nan")

    def mean_cpu(self, code: str) -> float:
        """Mean CPU time of the timed runs (NaN without any)."""
        runs = self.timed(code)
        return statistics.fmean(m.cpu for m in runs) if runs else float("nan")

    def mean_job_time(self) -> float:
        """Mean ``run_job`` time of dolfinx_ntf's timed runs (NaN without any)."""
        runs = self.timed("dolfinx_ntf")
        return statistics.fmean(m.job_time for m in runs) if runs else float("nan")

    def mean_startup(self) -> float:
        """Mean start-up of dolfinx_ntf's timed runs: wall time outside ``run_job`` (Python,
        imports, and the exit), NaN without any."""
        runs = self.timed("dolfinx_ntf")
        return statistics.fmean(m.wall - m.job_time for m in runs) if runs else float("nan")

    def peak_memory(self, code: str) -> int:
        """Largest peak RSS over all runs of ``code`` [bytes]."""
        return max((m.peak_rss for m in self.runs if m.code == code), default=0)


# ----------------------------------------------------------------------------- running


def _thread_env(threads: int) -> dict[str, str]:
    """Environment with every thread count of the linear algebra set to ``threads``."""
    value = str(threads)
    return dict(os.environ, OMP_NUM_THREADS=value, OPENBLAS_NUM_THREADS=value,
                MKL_NUM_THREADS=value, CCX_NPROC_EQUATION_SOLVER=value)  # fmt: skip


def _measured(record: Path, command: list[str]) -> list[str]:
    """``command`` run through this file's small launcher, which writes its measurement to
    ``record``.

    A process's peak RSS counts the memory of the process it was forked from, so the command must
    be started by a small process (a bare Python), not by the benchmark itself.
    """
    return [sys.executable, "-S", str(Path(__file__).resolve()), "--measure", str(record), "--",
            *command]  # fmt: skip


def _die_with_parent() -> None:
    """Ask Linux to kill this (child) process when its parent, the launcher, dies."""
    pr_set_pdeathsig = 1
    ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGKILL)


def _launch(record: Path, command: list[str]) -> int:
    """Run ``command`` (same cwd, environment and output), write wall and CPU time and peak RSS
    to ``record`` as JSON; returns its exit status for the launcher to exit with."""
    start = time.perf_counter()
    proc = subprocess.Popen(command, preexec_fn=_die_with_parent)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    code = os.waitstatus_to_exitcode(status)
    proc.returncode = code
    record.write_text(json.dumps({"wall": wall, "cpu": usage.ru_utime + usage.ru_stime,
                                  "peak_rss": usage.ru_maxrss * 1024, "status": code}))  # fmt: skip
    return code if code >= 0 else 128 - code


def _record(code: str, record: Path, ok: bool, error: str) -> Measurement:
    if not record.is_file():
        return Measurement(code, float("nan"), float("nan"), 0, False, error or "no measurement")
    data = json.loads(record.read_text())
    return Measurement(code, data["wall"], data["cpu"], data["peak_rss"], ok, error)


def _run_ntf(directory: Path, job: str, threads: int, timeout: float) -> Measurement:
    """``python -m dolfinx_ntf run JOB`` of this checkout in ``directory``, measured; output in
    ``ntf.log``."""
    log, record = directory / "ntf.log", directory / "ntf.measure.json"
    record.unlink(missing_ok=True)
    command = _measured(record, [sys.executable, "-m", "dolfinx_ntf", "run", job])
    env = _thread_env(threads)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    with log.open("w") as out:
        proc = subprocess.Popen(command, cwd=directory, env=env, stdout=out,
                                stderr=subprocess.STDOUT)  # fmt: skip
        try:
            code = proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            return _record("dolfinx_ntf", record, False, f"timed out after {timeout:g} s")
    lines = log.read_text(errors="replace").splitlines()
    error = ""
    if code != 0:
        messages = [m.group(1) for m in map(_ERROR.match, lines) if m]
        error = f"exit status {code}: " + (messages[0] if messages else f"see {log}")
    measurement = _record("dolfinx_ntf", record, code == 0, error)
    times = [float(m.group(2)) for m in map(_JOB_TIME.match, lines) if m]
    if times:
        measurement.job_time = times[-1]
    return measurement


def _run_ccx(directory: Path, job: str, threads: int, timeout: float) -> Measurement:
    """ccx through ``run_ccx``, with the launcher in front of the ccx executable."""
    from dolfinx_ntf.calculix.ccx import CcxError, ccx_executable, run_ccx

    record, wrapper = directory / "ccx.measure.json", directory / "ccx-measured"
    record.unlink(missing_ok=True)
    command = " ".join(shlex.quote(c) for c in _measured(record, [ccx_executable()]))
    wrapper.write_text(f'#!/bin/sh\nexec {command} "$@"\n')
    wrapper.chmod(0o755)
    error = ""
    try:
        run_ccx(directory, job, timeout=timeout, threads=threads, ccx=str(wrapper))
    except CcxError as failure:
        error = _ccx_error(str(failure))
    return _record("ccx", record, not error, error)


def _ccx_error(message: str) -> str:
    """ccx's first ``*ERROR`` message (ccx wraps it over lines), else the first line."""
    lines = [line.strip() for line in message.splitlines()]
    first = next((k for k, line in enumerate(lines) if "*ERROR" in line), None)
    if first is None:
        return lines[0] if lines else "ccx failed"
    text = [lines[first]]
    for line in lines[first + 1 : first + 3]:
        if not line or "*" in line:
            break
        text.append(line)
    return " ".join(text)


def parse_progress(text: str) -> Progress:
    """Converged increments of dolfinx_ntf's progress lines: iterations and attempts of each.

    Reads ``increment N attempt A`` and ``increment N converged: time T, I iterations, ...``
    (``dolfinx_ntf.solvers.steps.StaticStep``); later fields of the line are ignored.
    """
    progress = Progress()
    attempt = 1
    for line in text.splitlines():
        started = _ATTEMPT.match(line)
        if started:
            attempt = int(started.group(2))
            continue
        done = _CONVERGED.match(line)
        if done:
            progress.iterations.append(int(done.group(3)))
            progress.attempts.append(attempt)
    return progress


def _ccx_progress(sta: Path) -> Progress:
    from dolfinx_ntf.calculix.ccx import read_sta

    rows = read_sta(sta) if sta.is_file() else []
    return Progress([r.iterations for r in rows], [r.attempt for r in rows])


def _compare(result: DeckResult, ccx_dir: Path, ntf_dir: Path) -> None:
    """Fill the result differences from both ``.dat`` files."""
    from dolfinx_ntf.calculix.ccx import read_sta
    from dolfinx_ntf.calculix.compare import ccx_increments, compare_increments

    job = result.name
    _compare_cel(result, ccx_dir / f"{job}.cel", ntf_dir / f"{job}.cel")
    ccx_dat, ntf_dat = ccx_dir / f"{job}.dat", ntf_dir / f"{job}.dat"
    if not (ccx_dat.is_file() and ntf_dat.is_file()):
        result.comparison_error = "no .dat file"
        return
    sta = ccx_dir / f"{job}.sta"
    try:
        comparison = compare_increments(
            ccx_increments(ccx_dat, read_sta(sta) if sta.is_file() else None),
            ccx_increments(ntf_dat),
        )
    except ValueError as error:
        result.comparison_error = str(error)
        return
    result.common_increments = len(comparison.increments)
    if comparison.increments:
        result.displacement = comparison.relative_displacement
        result.pressure = comparison.relative_pressure
        result.same_contact = comparison.same_contact_elements


def _compare_cel(result: DeckResult, ccx_cel: Path, ntf_cel: Path) -> None:
    """Fill ``result.cel`` from both ``.cel`` files (when both codes wrote one)."""
    from dolfinx_ntf.calculix.cel import compare_cel

    if ccx_cel.is_file() and ntf_cel.is_file():
        result.cel = compare_cel(ccx_cel, ntf_cel)


def _iteration(set_name: str) -> str:
    """``in<i> it<n>`` of a ``.cel`` set name (``contactelements_st1_in1_at1_it3``)."""
    parts = dict(re.findall(r"_(st|in|at|it)(\d+)", set_name))
    text = f"in{parts.get('in', '?')} it{parts.get('it', '?')}"
    return text + (f" (attempt {parts['at']})" if parts.get("at", "1") != "1" else "")


def cel_lines(results: list[DeckResult]) -> list[str]:
    """Per deck with both ``.cel`` files: the pairings compared, the first that differs and how
    many slave nodes have another master face (or a contact element in one code only)."""
    rows = [r for r in results if r.cel is not None]
    if not rows:
        return []
    lines = [
        "| deck | pairings compared | first that differs | slave nodes differing per pairing "
        "(other face / ccx only / dolfinx_ntf only) |",
        "|---|---|---|---|",
    ]
    for r in rows:
        first = next((d for d in r.cel if d.count), None)
        per = ", ".join(
            f"{_iteration(d.set)}: {len(d.other_face)}/{len(d.only_first)}/{len(d.only_second)}"
            for d in r.cel
            if d.count
        )
        lines.append(
            f"| `{r.name}` | {len(r.cel)} | "
            f"{'none' if first is None else _iteration(first.set)} | {per or 'identical'} |"
        )
    return lines


def run_deck(
    deck: typing.Any, workdir: Path, *, runs: int = 2, threads: int = 1, timeout: float = 1800.0
) -> DeckResult:
    """Write ``deck``, run both codes (warm-up, then ``runs`` alternating timed runs), compare."""
    from dolfinx_ntf.calculix.deck import read_deck

    base = workdir / deck.name
    shutil.rmtree(base, ignore_errors=True)
    ccx_dir, ntf_dir = base / "ccx", base / "ntf"
    for directory in (ccx_dir, ntf_dir):
        directory.mkdir(parents=True)
    deck.write(ccx_dir)
    shutil.copy(ccx_dir / f"{deck.name}.inp", ntf_dir)
    dofs = 3 * int(read_deck(ccx_dir / f"{deck.name}.inp").node_ids.size)
    result = DeckResult(deck.name, deck.description, dofs)
    result.measured = dt.datetime.now(dt.timezone.utc)
    runners = {"ccx": (_run_ccx, ccx_dir), "dolfinx_ntf": (_run_ntf, ntf_dir)}
    for attempt in range(runs + 1):  # the warm-up, then the timed runs
        for code, (runner, directory) in runners.items():
            earlier = [m for m in result.runs if m.code == code]
            if earlier and not earlier[0].ok and len(earlier) >= 2:
                continue  # failed in the warm-up and once timed: enough
            measurement = runner(directory, deck.name, threads, timeout)
            result.runs.append(measurement)
            what = "warm-up" if attempt == 0 else f"run {attempt}"
            status = "ok" if measurement.ok else f"FAILED: {measurement.error}"
            print(f"  {deck.name} {code} {what}: {measurement.wall:.2f} s, "
                  f"{measurement.peak_rss / 2**20:.0f} MB, {status}", flush=True)  # fmt: skip
    result.ccx = _ccx_progress(ccx_dir / f"{deck.name}.sta")
    result.ntf = parse_progress((ntf_dir / "ntf.log").read_text(errors="replace"))
    _compare(result, ccx_dir, ntf_dir)
    return result


# ----------------------------------------------------------------------------- environment


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def _memory_gib() -> float:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) / 2**20
    except OSError:
        pass
    return float("nan")


def _os_name() -> str:
    try:
        fields = dict(
            line.split("=", 1)
            for line in Path("/etc/os-release").read_text().splitlines()
            if "=" in line
        )
        return fields.get("PRETTY_NAME", "").strip('"') or platform.platform()
    except OSError:
        return platform.platform()


def _ccx_version() -> str:
    from dolfinx_ntf.calculix.ccx import CcxError, ccx_executable

    try:
        banner = subprocess.run([ccx_executable(), "-v"], capture_output=True, text=True,
                                timeout=30).stdout  # fmt: skip
        return banner.split("Version", 1)[1].split()[0]
    except (OSError, IndexError, subprocess.SubprocessError, CcxError):
        return "unknown"


def environment() -> dict[str, str]:
    """Versions and machine, detected now."""
    from petsc4py import PETSc

    import dolfinx

    return {
        "os": _os_name(),
        "dolfinx": dolfinx.__version__,
        "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion()),
        "ccx": _ccx_version(),
        "python": platform.python_version(),
        "cpu": _cpu_model(),
        "cores": str(os.cpu_count()),
        "memory": f"{_memory_gib():.0f} GiB",
    }


# ----------------------------------------------------------------------------- report


def _fmt(value: float, spec: str = ".2f") -> str:
    return "-" if value != value else format(value, spec)


def _iterations(progress: Progress) -> str:
    if not progress.iterations:
        return "-"
    text = ", ".join(str(i) for i in progress.iterations)
    cutbacks = sum(a - 1 for a in progress.attempts)
    return text + (f" (+{cutbacks} cutbacks)" if cutbacks else "")


def _cell(result: DeckResult, code: str, value: str) -> str:
    failure = result.failure(code)
    return f"**failed** ({value})" if failure else value


def table(results: list[DeckResult]) -> list[str]:
    """The Markdown table of the report (also printed)."""
    lines = [
        "| deck | dofs | increments ccx / dolfinx_ntf | Newton iterations per increment: ccx "
        "| dolfinx_ntf | wall [s] ccx | dolfinx_ntf (start-up + job) | time ratio "
        "| peak memory [MB] ccx "
        "| dolfinx_ntf | max Δu / max u | max Δp / max p | same contact elements |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        ccx_wall, ntf_wall = r.mean_wall("ccx"), r.mean_wall("dolfinx_ntf")
        ratio = ntf_wall / ccx_wall if not (r.failure("ccx") or r.failure("dolfinx_ntf")) else None
        same = "-" if r.same_contact is None else ("yes" if r.same_contact else "no")
        if r.common_increments and r.same_contact is not None:
            plural = "s" if r.common_increments > 1 else ""
            same += f" ({r.common_increments} common increment{plural})"
        lines.append(
            f"| `{r.name}` | {r.dofs} | {len(r.ccx.iterations)} / {len(r.ntf.iterations)} "
            f"| {_cell(r, 'ccx', _iterations(r.ccx))} "
            f"| {_cell(r, 'dolfinx_ntf', _iterations(r.ntf))} "
            f"| {_fmt(ccx_wall)} | {_fmt(ntf_wall)} ({_fmt(r.mean_startup())} + "
            f"{_fmt(r.mean_job_time())}) "
            f"| {'-' if ratio is None else _fmt(ratio)} "
            f"| {r.peak_memory('ccx') / 2**20:.0f} | {r.peak_memory('dolfinx_ntf') / 2**20:.0f} "
            f"| {_fmt(r.displacement, '.1e')} | {_fmt(r.pressure, '.1e')} | {same} |"
        )
    return lines


def _stamp(when: dt.datetime | None) -> str:
    return "-" if when is None else f"{when:%Y-%m-%d %H:%M}"


def _details(results: list[DeckResult]) -> list[str]:
    lines = [
        "| deck | measured [UTC] | ccx wall [s] per timed run | mean CPU [s] "
        "| dolfinx_ntf wall [s] per timed run | mean CPU [s] | of which start-up [s] "
        "| `run_job` [s] | CPU time ratio |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        cells = [_stamp(r.measured)]
        for code in ("ccx", "dolfinx_ntf"):
            runs = r.timed(code)
            cells.append(", ".join(_fmt(m.wall) for m in runs) or "-")
            cells.append(_fmt(r.mean_cpu(code)))
        cells.append(_fmt(r.mean_startup()))
        cells.append(_fmt(r.mean_job_time()))
        both = not (r.failure("ccx") or r.failure("dolfinx_ntf"))
        cells.append(_fmt(r.mean_cpu("dolfinx_ntf") / r.mean_cpu("ccx")) if both else "-")
        lines.append(f"| `{r.name}` | " + " | ".join(cells) + " |")
    return lines


def _failures(results: list[DeckResult]) -> list[str]:
    lines = []
    for r in results:
        for code in ("ccx", "dolfinx_ntf"):
            if r.failure(code):
                lines.append(f"- `{r.name}`, {code}: {r.failure(code)}")
        if r.comparison_error:
            lines.append(f"- `{r.name}`: results not compared: {r.comparison_error}")
    return lines


def section(results: list[DeckResult], env: dict[str, str], loads: list[float],
            started: dt.datetime, runs: int, threads: int) -> list[str]:  # fmt: skip
    """This platform's section of the report."""
    busy = max(loads, default=0.0) > 1.5
    load_text = (
        f"1-minute load average before and after each deck: {min(loads, default=0):.2f} to "
        f"{max(loads, default=0):.2f} (the benchmark itself accounts for about 1)"
    )
    if busy:
        load_text += (
            f"; the machine ({env['cores']} cores) was shared with other work, so wall times are "
            "those of a loaded machine: both codes alternate and share the load, and the CPU "
            "times below are less affected"
        )
    out = [
        f"## {env['os']}: dolfinx {env['dolfinx']}, PETSc {env['petsc']}",
        "",
        f"Measured {started:%Y-%m-%d %H:%M} UTC with ccx {env['ccx']} and Python {env['python']} "
        f"on {env['cpu']} ({env['cores']} cores, {env['memory']}), {threads} thread(s) per code, "
        f"one warm-up and {runs} alternating timed runs per code. {load_text}.",
        "",
        *table(results),
        "",
    ]
    failures = _failures(results)
    if failures:
        out += ["Failures:", "", *failures, ""]
    cel = cel_lines(results)
    if cel:
        out += [_CEL_INTRO, "", *cel, ""]
    out += ["Timed runs:", "", *_details(results), ""]
    return out


_CEL_INTRO = (
    "Contact element sets (`.cel`), ccx's pairings against dolfinx_ntf's, iteration by "
    "iteration (up to ccx's last pairing when it fails):"
)

_HEADER = [
    "# Performance: dolfinx_ntf against CalculiX 2.20",
    "",
    f"Generated by `{COMMAND}` (`make benchmark-ccx`); do not edit by hand. Each section is one "
    "machine and Debian release; a full run replaces its own section.",
    "",
    "Decks (`benchmarks/ccx_decks.py`, written by `write_inp`; units mm, N, MPa):",
    "",
    "- `tie_punch`: a 6 x 6 C3D8 steel punch on a 10 x 10 aluminium block whose slave nodes on "
    "x, y = 30, 50, 70 lie exactly above master nodes and edges (the deck is symmetric, so they "
    "stay there), LINEAR law K = 1e7, sigma_inf = 3, top pushed down in one increment, "
    '`*CONTROLS, PARAMETERS=FIELD` R_n = C_n = 1e-9. ccx 2.20 stops on it ("solution seems to '
    'diverge"): its own re-pairings move the three slave nodes above master vertices on the '
    "diagonals between diagonally opposite faces at every iteration, and its residual stalls at "
    "1.5e-6 of the average force.",
    "- `punch_10`, `punch_20`, `punch_30`: the same punch at 4.7k, 29k and 81k dofs with ccx's "
    "default controls (with 1e-9 ccx stalls the same way, at 1.4e-7 on `punch_20`).",
    "- `quarter_sphere`: a C3D4 steel quarter sphere of radius 10 (h = 0.15 at the pole) pushed "
    "0.12 into a steel block in 4 fixed increments (`*STATIC, DIRECT`), same law, ccx's default "
    "controls; `quarter_sphere_coarse`: h = 0.3, pushed 0.14. Their gmsh meshes are pinned in "
    "`meshes/` (which code converges depends on the mesh, and gmsh 4.8 and 4.13 differ).",
    "- the cross-validation decks of `tests/data/calculix/crossval/cases.py` (controls "
    "tightened to R_n = 1e-10).",
    "- the node-to-surface decks of CalculiX's own test suite (Debian package "
    "`calculix-ccx-test`, as `make ccx-suite` runs them) that dolfinx_ntf reads, at their own "
    "controls.",
    "",
    "Both codes run the same `.inp` file on one thread: ccx 2.20 as `ccx -i JOB` "
    "(`dolfinx_ntf.calculix.run_ccx`), dolfinx_ntf as `python -m dolfinx_ntf run JOB` with the "
    "deck's controls and its default options (from 10 000 dofs on, Newton corrections after the "
    "first reuse an earlier factorization: docs/method.md §31). Columns: Newton iterations of "
    "each converged increment (ccx's `.sta` file, "
    "dolfinx_ntf's progress lines; a failed run lists its converged increments); mean wall time "
    "of the timed runs from process start to exit (dolfinx_ntf's includes Python start-up, "
    "imports and form loading, with the form cache warm), and for dolfinx_ntf how it splits "
    "into start-up (everything outside `run_job`: Python, imports, the exit) and the job "
    "(`run_job`: deck, model, forms, solution, files); the time ratio dolfinx_ntf / ccx; "
    "peak resident memory of each process; "
    "the largest difference over the increments both codes converged, displacements over ccx's "
    "largest displacement and contact pressures over ccx's largest pressure "
    "(`dolfinx_ntf.calculix.compare`), and whether the same slave nodes carry contact elements. "
    "A failed run shows as **failed**, with its message below the table. For the punch decks, "
    "a second table compares both codes' `.cel` contact element sets pairing by pairing "
    "(`dolfinx_ntf.calculix.cel.compare_cel`).",
    "",
]


def write_report(path: Path, key: str, lines: list[str]) -> None:
    """Write ``lines`` as the section ``key`` of ``path``, keeping the other sections."""
    begin, end = f"<!-- vs_ccx section: {key} -->", f"<!-- /vs_ccx section: {key} -->"
    sections: list[str] = []
    if path.is_file():
        found = re.findall(r"(<!-- vs_ccx section: (.*?) -->.*?<!-- /vs_ccx section: \2 -->)",
                           path.read_text(), flags=re.S)  # fmt: skip
        sections = [text for text, name in found if name != key]
    sections.append("\n".join([begin, *lines, end]))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(_HEADER) + "\n" + "\n\n".join(sorted(sections)) + "\n")


def read_section(path: Path, key: str) -> list[str] | None:
    """The lines of section ``key`` of ``path`` (without its markers), None if it has none."""
    if not path.is_file():
        return None
    begin, end = f"<!-- vs_ccx section: {key} -->", f"<!-- /vs_ccx section: {key} -->"
    text = path.read_text()
    if begin not in text or end not in text:
        return None
    return text.split(begin, 1)[1].split(end, 1)[0].strip("\n").split("\n")


_ROW = re.compile(r"^\| `([^`]+)` \|")
_FAILURE = re.compile(r"^- `([^`]+)`")
_MEASURED = re.compile(r"^Measured (\d{4}-\d\d-\d\d \d\d:\d\d) UTC")
_UPDATE_NOTE = "Updated (`--update`): "


@dataclass
class _Section:
    """A platform section (:func:`section`) split into its parts, rows by deck name."""

    title: str
    notes: list[str]
    table_head: list[str]
    rows: dict[str, str]
    failures: dict[str, list[str]]
    details_head: list[str]
    details: dict[str, str]
    cel_head: list[str]
    cel: dict[str, str]


def _parse_section(lines: list[str]) -> _Section:
    """Split a section written by :func:`section` (or merged by :func:`merge_section`)."""
    notes: list[str] = []
    tables: list[list[str]] = []
    failures: dict[str, list[str]] = {}
    current: list[str] | None = None
    for line in lines[1:]:
        if line.startswith("|"):
            if current is None:
                current = []
                tables.append(current)
            current.append(line)
            continue
        current = None
        failure = _FAILURE.match(line)
        if failure:
            failures.setdefault(failure.group(1), []).append(line)
        elif line and line not in ("Failures:", "Timed runs:") and not tables:
            notes.append(line)
    if not lines or not lines[0].startswith("## ") or len(tables) not in (2, 3):
        raise ValueError(
            "not a vs_ccx section (a '## ' title and two or three tables expected: results, "
            "the .cel comparison if any, timed runs)"
        )

    def rows(table: list[str]) -> dict[str, str]:
        return {m.group(1): line for line in table[2:] if (m := _ROW.match(line))}

    cel_head, cel = (tables[1][:2], rows(tables[1])) if len(tables) == 3 else ([], {})
    details_head, details = tables[-1][:2], rows(tables[-1])
    if "measured" not in details_head[0]:  # written before the column existed: the run's date
        stamp = next((m.group(1) for m in map(_MEASURED.match, notes) if m), "-")
        details_head = [
            details_head[0].replace("| deck |", "| deck | measured [UTC] |", 1),
            details_head[1] + "---|",
        ]
        details = {n: line.replace(" | ", f" | {stamp} | ", 1) for n, line in details.items()}
    return _Section(lines[0], notes, tables[0][:2], rows(tables[0]), failures, details_head,
                    details, cel_head, cel)  # fmt: skip


def _update_note_decks(note: str) -> set[str]:
    return set(re.findall(r"`([^`]+)`", note[len(_UPDATE_NOTE) :].split(" re-measured", 1)[0]))


def merge_section(old: list[str], new: list[str], order: typing.Sequence[str] = ()) -> list[str]:
    """Section ``old`` with the rows of the decks of section ``new`` replaced or added.

    The other rows stay; a note names the re-measured decks with the new run's date, machine and
    load, and every row of the timed-runs table has its date. Decks are listed in ``order`` (names
    not in it last).

    Raises:
        ValueError: The sections are of different versions (titles differ) or not sections.
    """
    before, now = _parse_section(old), _parse_section(new)
    if before.title != now.title:
        raise ValueError(
            f"the existing section is {before.title[3:]!r}, this run {now.title[3:]!r}: "
            "run every deck instead of --update"
        )
    names = list(now.rows)
    rows, details = {**before.rows, **now.rows}, {**before.details, **now.details}
    failures = {n: v for n, v in before.failures.items() if n not in names}
    failures.update(now.failures)
    rank = {name: k for k, name in enumerate(order)}
    ordered = sorted(rows, key=lambda n: rank.get(n, len(rank)))
    notes = [
        n
        for n in before.notes
        if not (n.startswith(_UPDATE_NOTE) and _update_note_decks(n) <= set(names))
    ]
    measured = next((n for n in now.notes if _MEASURED.match(n)), "")
    listed = ", ".join(f"`{n}`" for n in names)
    notes.append(f"{_UPDATE_NOTE}{listed} re-m{measured[1:]}")
    out = [now.title, ""]
    for note in notes:
        out += [note, ""]
    out += [*now.table_head, *(rows[n] for n in ordered), ""]
    failed = [line for n in ordered for line in failures.get(n, [])]
    if failed:
        out += ["Failures:", "", *failed, ""]
    cel = {**before.cel, **now.cel}
    if cel:
        head = now.cel_head or before.cel_head
        out += [_CEL_INTRO, "", *head, *(cel[n] for n in ordered if n in cel), ""]
    out += ["Timed runs:", "", *now.details_head, *(details[n] for n in ordered if n in details)]
    return [*out, ""]


# ----------------------------------------------------------------------------- main


def suite_decks() -> list[typing.Any]:
    """CalculiX's own node-to-surface test decks that dolfinx_ntf reads (``calculix-ccx-test``,
    as ``benchmarks/ccx_suite.py`` finds them), as quick decks of the benchmark; none without the
    package. The refused ones are left out (``make ccx-suite`` lists them and why)."""
    import ccx_decks
    import ccx_suite

    from dolfinx_ntf.calculix.deck import read_deck

    if not ccx_suite.SUITE.is_dir():
        return []
    known = {d.name for d in ccx_decks.DECKS}
    decks = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, text in ccx_suite.node_to_surface_decks(None):
            path = Path(tmp) / f"{name}.inp"
            path.write_text(text, encoding="latin-1")
            try:
                read_deck(path)
            except (ValueError, NotImplementedError):
                continue
            if name in known:
                raise ValueError(f"suite deck {name} has the name of a benchmark deck")

            def write(directory: Path, name: str = name, text: str = text) -> None:
                (directory / f"{name}.inp").write_text(text, encoding="latin-1")

            decks.append(ccx_decks.BenchDeck(name, f"calculix-ccx-test: {name}", write, True))
    return decks


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", metavar="DECK", help="run these decks only")
    parser.add_argument("--quick", action="store_true", help="small decks only")
    parser.add_argument("--workdir", type=Path, help="keep decks and results here")
    parser.add_argument("--output", type=Path, help=f"report (default for full runs: "
                        f"{DEFAULT_OUTPUT.relative_to(ROOT)})")  # fmt: skip
    parser.add_argument("--update", action="store_true",
                        help="replace only the rows of the decks run now in this platform's "
                        "existing section of the report (default docs/performance.md)")  # fmt: skip
    parser.add_argument("--runs", type=int, default=2, help="timed runs per code (at least 2)")
    parser.add_argument("--threads", type=int, default=1, help="threads per code")
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds per run")
    return parser


def main(argv: typing.Sequence[str] | None = None) -> list[DeckResult]:
    """Run the benchmark; returns the results."""
    args = _parser().parse_args(argv)
    if args.runs < 2:
        raise SystemExit(f"--runs must be at least 2, got {args.runs}")
    if args.threads < 1:
        raise SystemExit(f"--threads must be at least 1, got {args.threads}")
    if shutil.which(os.environ.get("CCX", "ccx")) is None:
        raise SystemExit("ccx not found: apt-get install calculix-ccx (or set $CCX)")
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import ccx_decks
    from startup import compile_bytecode

    compile_bytecode(ROOT)

    suite = suite_decks()
    by_name = {d.name: d for d in suite}
    try:
        decks = ccx_decks.select_decks(
            [n for n in args.only if n not in by_name] if args.only else None, quick=args.quick
        )
    except ValueError as error:
        raise SystemExit(f"{error}, {', '.join(by_name)}") from None
    decks += [d for d in suite if args.only is None or d.name in args.only]
    output = args.output
    if output is None and (args.update or not (args.only or args.quick)):
        output = DEFAULT_OUTPUT
    env = environment()
    key = f"{env['os']} / dolfinx {env['dolfinx']}"
    if args.update:  # before the long run: the section must be of these versions
        old = read_section(output, key)
        title = section([], env, [], dt.datetime.now(dt.timezone.utc), args.runs, args.threads)[0]
        if old is not None and old[0] != title:
            raise SystemExit(f"--update: {output} has {old[0][3:]!r}, this machine is "
                             f"{title[3:]!r}: run every deck instead")  # fmt: skip
    started = dt.datetime.now(dt.timezone.utc)
    print(f"vs_ccx: {len(decks)} decks; {env['os']}, dolfinx {env['dolfinx']}, PETSc "
          f"{env['petsc']}, ccx {env['ccx']}, {env['cores']} cores", flush=True)  # fmt: skip
    results, loads = [], []
    with tempfile.TemporaryDirectory() as tmp:
        workdir = args.workdir or Path(tmp)
        for deck in decks:
            loads.append(os.getloadavg()[0])
            print(f"{deck.name}: {deck.description}", flush=True)
            results.append(run_deck(deck, workdir, runs=args.runs, threads=args.threads,
                                    timeout=args.timeout))  # fmt: skip
            loads.append(os.getloadavg()[0])
    lines = section(results, env, loads, started, args.runs, args.threads)
    print("\n".join(lines))
    if output is not None:
        old = read_section(output, key) if args.update else None
        if old is not None:
            try:
                order = [d.name for d in (*ccx_decks.DECKS, *suite)]
                lines = merge_section(old, lines, order)
            except ValueError as error:
                raise SystemExit(f"--update: {error}") from None
        write_report(output, key, lines)
        print(f"wrote {output}")
    return results


if __name__ == "__main__":
    if sys.argv[1:2] == ["--measure"]:  # the launcher: stdlib only, see _measured
        sys.exit(_launch(Path(sys.argv[2]), sys.argv[4:]))
    main()
