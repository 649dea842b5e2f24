"""Running CalculiX ``ccx`` and reading what it wrote.

``run_ccx`` runs ``ccx -i jobname`` in a job directory with ``OMP_NUM_THREADS=1`` (reproducible
and polite on shared machines) and turns every failure into a ``CcxError`` that shows the tail
of ccx's output. ccx 2.20 exits with status 0 after some input errors, so a run also fails when
its output contains ``*ERROR``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from .dat import DatBlock, read_dat

__all__ = [
    "CcxError",
    "StaIncrement",
    "ccx_executable",
    "dat_block",
    "dat_times",
    "read_ccx_dat",
    "read_sta",
    "run_ccx",
]

_TAIL_LINES = 30


class CcxError(RuntimeError):
    """ccx is missing, failed, timed out or reported an error."""


def ccx_executable(ccx: str | None = None) -> str:
    """Path of the ccx binary (``ccx`` argument, else ``$CCX``, else ``ccx`` on PATH).

    Raises:
        CcxError: ccx cannot be found.
    """
    name = ccx or os.environ.get("CCX") or "ccx"
    found = shutil.which(name)
    if found is None:
        raise CcxError(
            f"CalculiX executable {name!r} not found on PATH; install it with "
            "'apt-get install calculix-ccx' or set $CCX"
        )
    return found


def _tail(text: str, lines: int = _TAIL_LINES) -> str:
    kept = [line for line in text.splitlines() if line.strip()][-lines:]
    return "\n".join("    " + line for line in kept)


def run_ccx(
    jobdir: str | Path,
    jobname: str,
    *,
    timeout: float = 600.0,
    ccx: str | None = None,
    threads: int = 1,
) -> subprocess.CompletedProcess:
    """Run ``ccx -i jobname`` in ``jobdir`` and return the completed process.

    Output (stdout and stderr merged) is also saved to ``jobdir/jobname.log``.

    Args:
        jobdir: directory holding ``jobname.inp``; ccx writes its results there.
        jobname: deck name without ``.inp``.
        timeout: seconds before the run is killed.
        ccx: ccx executable (default: ``$CCX`` or ``ccx`` on PATH).
        threads: ``OMP_NUM_THREADS`` for ccx.

    Raises:
        ValueError: ``jobdir/jobname.inp`` does not exist.
        CcxError: ccx missing, timed out, exited with an error status or printed ``*ERROR``.
    """
    jobdir = Path(jobdir)
    deck = jobdir / f"{jobname}.inp"
    if not deck.is_file():
        raise ValueError(f"ccx input deck {deck} does not exist")
    executable = ccx_executable(ccx)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_EQUATION_SOLVER=str(threads))
    command = [executable, "-i", jobname]
    try:
        result = subprocess.run(
            command,
            cwd=jobdir,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            errors="replace",
            timeout=timeout,
            check=False,
        )
    except subprocess.TimeoutExpired as exc:
        output = (
            exc.stdout
            if isinstance(exc.stdout, str)
            else (exc.stdout or b"").decode(errors="replace")
        )
        raise CcxError(
            f"ccx timed out after {timeout} s on {deck}; last output:\n{_tail(output)}"
        ) from None
    (jobdir / f"{jobname}.log").write_text(result.stdout)
    if result.returncode != 0:
        raise CcxError(
            f"ccx failed with exit status {result.returncode} on {deck}; last output:\n"
            f"{_tail(result.stdout)}"
        )
    if "*ERROR" in result.stdout:
        errors = [line for line in result.stdout.splitlines() if "*ERROR" in line]
        raise CcxError(
            f"ccx reported {len(errors)} error(s) on {deck} (first: {errors[0].strip()}); "
            f"last output:\n{_tail(result.stdout)}"
        )
    return result


def read_ccx_dat(jobdir: str | Path, jobname: str) -> list[DatBlock]:
    """Blocks of ``jobdir/jobname.dat``.

    Raises:
        ValueError: the file is missing or unreadable as a ``.dat`` file.
    """
    path = Path(jobdir) / f"{jobname}.dat"
    if not path.is_file():
        raise ValueError(f"ccx result file {path} does not exist (did ccx run?)")
    return read_dat(path)


def dat_times(blocks: list[DatBlock], name: str | None = None) -> list[float]:
    """Distinct block times in file order (of blocks called ``name`` if given)."""
    times: list[float] = []
    for block in blocks:
        if (name is None or block.name == name) and block.time not in times:
            times.append(block.time)
    return times


def dat_block(
    blocks: list[DatBlock], name: str, *, time: float | None = None, set: str | None = None
) -> DatBlock:
    """The block called ``name`` (at ``time``, for ``set``); the last such one if ``time`` is None.

    ``blocks`` are those :func:`read_ccx_dat` or :func:`read_dat` returned.

    Raises:
        ValueError: no such block, or several for the same time and set.
    """
    found = [
        b
        for b in blocks
        if b.name == name
        and (time is None or abs(b.time - time) <= 1e-7 * max(1.0, abs(time)))
        and (set is None or b.set == set.upper())
    ]
    if not found:
        where = f" at time {time}" if time is not None else ""
        where += f" for set {set}" if set is not None else ""
        raise ValueError(f"no .dat block {name}{where}")
    if time is not None and len(found) > 1:
        raise ValueError(f"{len(found)} .dat blocks {name} at time {time}; give the set")
    return found[-1]


@dataclass(frozen=True)
class StaIncrement:
    """One row of ccx's ``.sta`` file: a converged increment."""

    step: int
    increment: int
    attempt: int
    iterations: int
    total_time: float
    step_time: float
    increment_time: float


def read_sta(path: str | Path) -> list[StaIncrement]:
    """Converged increments listed in the ccx ``.sta`` file at ``path`` (iterations each)."""
    rows: list[StaIncrement] = []
    for line in Path(path).read_text(encoding="latin-1").splitlines():
        fields = line.split()
        if len(fields) != 7 or not fields[0].isdigit():
            continue
        try:
            rows.append(
                StaIncrement(
                    int(fields[0]),
                    int(fields[1]),
                    int(fields[2]),
                    int(fields[3]),
                    float(fields[4]),
                    float(fields[5]),
                    float(fields[6]),
                )
            )
        except ValueError:
            continue
    return rows
