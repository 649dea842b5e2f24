"""A deck run by ccx and by the deck runner side by side, and their ``.dat`` blocks compared.

``run_ccx_and_ours`` writes the deck into ``ccx/`` and ``ntf/`` below a test's directory and runs
both codes (ours on ``comm``, ccx on rank 0); ``largest_differences`` compares the blocks by name.
"""

from __future__ import annotations

import logging
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import DatBlock
from dolfinx_ntf.calculix.job import run_job


def run_ccx_and_ours(
    directory: Path, name: str, text: str, comm: MPI.Comm = MPI.COMM_SELF
) -> tuple[Path, Path]:
    """Run the deck ``text`` as job ``name`` by ccx and by ``run_job``: ``(ccx_dir, ntf_dir)``.

    Rank 0's ``directory`` is used by all processes; our run must complete.
    """
    root = Path(comm.bcast(str(directory), root=0))
    ccx_dir, ntf_dir = root / "ccx", root / "ntf"
    if comm.rank == 0:
        for d in (ccx_dir, ntf_dir):
            d.mkdir()
            (d / f"{name}.inp").write_text(text)
        run_ccx(ccx_dir, name, timeout=120)
    comm.barrier()
    logger = logging.getLogger("dolfinx_ntf")
    level = logger.level
    logger.setLevel(logging.WARNING)
    try:
        assert run_job(name, ntf_dir, comm=comm, progress=False).completed
    finally:
        logger.setLevel(level)
    return ccx_dir, ntf_dir


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
