"""One run of a benchmark's ``--driver`` child process, shared by job_phases.py and startup.py.

Both time a deck run in a process of its own: the script runs itself with ``--driver JOB`` in the
deck's directory, on one thread (``OMP_NUM_THREADS`` and ``OPENBLAS_NUM_THREADS`` = 1) with the
checkout first on ``PYTHONPATH``, and the child prints its measurements as one JSON line on its
standard error behind a marker word.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import NamedTuple


class DriverRun(NamedTuple):
    """What one driver run gave: its JSON, its standard output and when it was spawned."""

    data: object
    stdout: str
    start: float


def run_driver(
    script: str,
    deck: Path,
    workdir: Path,
    checkout: Path,
    marker: str,
    extra_env: dict[str, str] | None = None,
) -> DriverRun:
    """Run ``python script --driver DECK_STEM`` in ``workdir`` and read its measurements.

    Args:
        script: the benchmark file whose ``--driver`` mode times the run.
        deck: the deck (its stem names the job; its name, errors).
        workdir: where the job runs (the deck's directory).
        checkout: the source tree put first on ``PYTHONPATH``.
        marker: the word before the JSON on the child's last such standard-error line.
        extra_env: more environment variables for the child (e.g. ``PETSC_OPTIONS``).

    Returns:
        The JSON of the last marked line, the child's standard output and the spawn time
        (``time.time()`` just before the process starts).

    Raises:
        RuntimeError: the child failed or printed no marked line (with its standard error's end).
    """
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(checkout), env.get("PYTHONPATH")]))
    env.update(extra_env or {})
    start = time.time()
    done = subprocess.run(
        [sys.executable, script, "--driver", deck.stem],
        cwd=workdir,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    prefix = marker + " "
    lines = [line for line in done.stderr.splitlines() if line.startswith(prefix)]
    if done.returncode != 0 or not lines:
        raise RuntimeError(f"{deck.name}: exit {done.returncode}\n{done.stderr[-2000:]}")
    return DriverRun(json.loads(lines[-1][len(prefix) :]), done.stdout, start)
