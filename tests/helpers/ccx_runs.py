"""A deck run by ccx and by the deck runner side by side, and their ``.dat`` blocks compared.

``run_ccx_and_ours`` writes the deck into ``ccx/`` and ``ntf/`` below a test's directory and runs
both codes (ours on ``comm``, ccx on rank 0); ``largest_differences`` compares the blocks by name;
``quiet_logs`` keeps the deck runner's progress lines out of a test's log.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable, Iterator
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import DatBlock
from dolfinx_ntf.calculix.job import JobResult, run_job


def run_ccx_and_ours(
    directory: Path,
    name: str,
    deck: str | Callable[[Path], object],
    comm: MPI.Comm = MPI.COMM_SELF,
    **job_options,
) -> tuple[Path, Path]:
    """Run a deck as job ``name`` by ccx and by ``run_job``: ``(ccx_dir, ntf_dir)``.

    ``deck`` is the deck's text (written as ``name.inp``) or a function that writes the deck (and
    the files it includes) into a directory; ``job_options`` go to ``run_job`` (e.g. ``tight``).
    Rank 0's ``directory`` is used by all processes; our run must complete.
    """
    root = Path(comm.bcast(str(directory), root=0))
    ccx_dir, ntf_dir = root / "ccx", root / "ntf"
    if comm.rank == 0:
        for d in (ccx_dir, ntf_dir):
            d.mkdir()
            if isinstance(deck, str):
                (d / f"{name}.inp").write_text(deck)
            else:
                deck(d)
        run_ccx(ccx_dir, name, timeout=120)
    comm.barrier()
    with quiet_logs():
        assert run_job(name, ntf_dir, comm=comm, progress=False, **job_options).completed
    return ccx_dir, ntf_dir


@contextlib.contextmanager
def quiet_logs(level: int = logging.WARNING) -> Iterator[None]:
    """dolfinx_ntf's logger at ``level`` for the block (no progress lines in the test log)."""
    logger = logging.getLogger("dolfinx_ntf")
    previous = logger.level
    logger.setLevel(level)
    try:
        yield
    finally:
        logger.setLevel(previous)


def run_quietly(name: str, directory: Path, **options) -> JobResult:
    """``run_job`` on one process without progress, its log at ERROR (``options`` go to it)."""
    with quiet_logs(logging.ERROR):
        return run_job(name, directory, comm=MPI.COMM_SELF, progress=False, **options)


def largest_differences(ccx: list[DatBlock], ntf: list[DatBlock]) -> dict[str, float]:
    """Largest difference per block name relative to ccx's largest value of that name (the run;
    absolute where that is zero); blocks without rows are left out.

    The blocks must be the same: names, times and rows (node numbers) in the same order.
    """
    assert [(b.name, b.labels.tolist()) for b in ntf] == [(b.name, b.labels.tolist()) for b in ccx]
    for a, b in zip(ccx, ntf):
        assert b.time == pytest.approx(a.time, rel=1e-6)
    scale: dict[str, float] = {}
    for a in ccx:
        if a.values.size:
            scale[a.name] = max(scale.get(a.name, 0.0), float(np.abs(a.values).max()))
    worst: dict[str, float] = {}
    for a, b in zip(ccx, ntf):
        if a.values.size:
            d = float(np.abs(a.values - b.values).max()) / (scale[a.name] or 1.0)
            worst[a.name] = max(worst.get(a.name, 0.0), d)
    return worst
