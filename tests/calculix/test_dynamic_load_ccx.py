"""A ``*DYNAMIC`` step with a load from its start, against ccx 2.20 (docs/method.md §12.7).

ccx 2.20 starts a dynamic step with the acceleration of an alpha-method increment of a tenth of
the initial increment, ``(M + beta (1 + alpha) h^2 K) a_0 = f_ext - f(u_0)``, not with the exact
``M a_0 = f_ext - f(u_0)``. The deck (``tests/data/calculix/dynamic/loaded_column_deck.py``): a
column of two C3D8 under a ``*CLOAD`` or its weight (``GRAV``) from the step start, increments of
0.03 over a lowest period of about 0.2. The deck runner's default reproduces ccx's printed digits
(1e-6 of the largest displacement asserted; measured 0 in every case); the exact start differs
from ccx by 8.3e-5 (increments of 0.01) to 1.0e-3 of the largest displacement (asserted above
2e-4 on the first case, so that the comparison can tell the two apart).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_runs import run_ccx_and_ours
from loaded_column_deck import loaded_column_deck

from dolfinx_ntf.calculix.ccx import read_sta
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.job import run_job

COMM = MPI.COMM_WORLD

pytestmark = [
    pytest.mark.ccx,
    pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed"),
]

CASES = {
    "cload": {},
    "grav": {"load": "GRAV"},
    "alpha0_automatic": {"alpha": 0.0, "direct": False},
    "alpha_third_velocity": {"alpha": -0.3, "velocity": True},
    "small_increments": {"increment": 0.01},
    "nlgeom": {"nlgeom": True},
    # the first increment (0.03) shortened to the first point: ccx keeps 0.02 and starts from a
    # tenth of it (measured: 4e-4 with a tenth of 0.03, increments 0.02, 0.03, ... before)
    "first_time_point": {"direct": False, "time_points": "0.02, 0.05, 0.1, 0.2, 0.3"},
}


def _run(root: Path, text: str, initial_acceleration: str = "ccx") -> tuple[list, list]:
    """ccx's and the runner's U blocks of the deck ``text`` (ccx on rank 0)."""
    ccx_dir, ntf_dir = run_ccx_and_ours(
        root, "column", text, COMM, tight=True, initial_acceleration=initial_acceleration
    )
    if COMM.rank != 0:
        return [], []
    blocks = [[b for b in read_dat(d / "column.dat") if b.name == "U"] for d in (ccx_dir, ntf_dir)]
    ccx, ntf = blocks
    assert [b.time for b in ccx] == pytest.approx([b.time for b in ntf], rel=1e-6) and ccx
    return ccx, ntf


def _largest_difference(ccx: list, ntf: list) -> float:
    """The largest difference of U over the run, in units of the run's largest displacement."""
    scale = max(np.abs(b.values).max() for b in ccx)
    for a, b in zip(ccx, ntf):
        np.testing.assert_array_equal(a.labels, b.labels)
    return max(np.abs(a.values - b.values).max() for a, b in zip(ccx, ntf)) / scale


@pytest.mark.mpi
@pytest.mark.parametrize("case", CASES)
def test_load_from_step_start_matches_ccx(tmp_path, case):
    """Every increment's U equals ccx's to 1e-6 of the largest (ccx prints 7 digits)."""
    root = Path(COMM.bcast(str(tmp_path), root=0))
    ccx, ntf = _run(root, loaded_column_deck(**CASES[case]))
    if COMM.rank != 0:
        return
    assert _largest_difference(ccx, ntf) <= 1e-6
    assert max(np.abs(b.values[:, 2]).max() for b in ccx) > 1e-3  # the column moved
    ccx_sta, ntf_sta = (read_sta(root / side / "column.sta") for side in ("ccx", "ntf"))
    assert len(ccx_sta) == len(ntf_sta)
    np.testing.assert_allclose([r.step_time for r in ntf_sta], [r.step_time for r in ccx_sta])


@pytest.mark.serial
def test_exact_initial_acceleration_differs_from_ccx(tmp_path):
    """``initial_acceleration="exact"`` (the Python API's start) is not ccx's: 8.5e-4 here."""
    ccx, ntf = _run(tmp_path, loaded_column_deck(), initial_acceleration="exact")
    assert _largest_difference(ccx, ntf) > 2e-4


def test_unknown_initial_acceleration_is_named(tmp_path):
    with pytest.raises(ValueError, match="initial_acceleration 'lumped'"):
        run_job("column", tmp_path, comm=MPI.COMM_SELF, initial_acceleration="lumped")
