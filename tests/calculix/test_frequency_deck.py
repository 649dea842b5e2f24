"""contact5's ``*FREQUENCY`` step (C3D20, constraint elimination) against ccx's ``.dat.ref``.

Serial and on all processes (``-m mpi``); no ccx needed: the reference is the one ccx ships.
"""

from __future__ import annotations

from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_suite import node_to_surface_suite_deck, suite_text

from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.modal_dat import read_frequency_output

COMM = MPI.COMM_WORLD

pytestmark = pytest.mark.skipif(
    not node_to_surface_suite_deck("contact5"),
    reason="no node-to-surface contact5 (Debian 12's calculix-ccx-test) installed",
)


@pytest.mark.mpi
def test_contact5_frequency_step_matches_its_reference(tmp_path):
    """The deck's second step (*MODAL DYNAMIC, test_modal_dynamic_ccx.py) is cut off.

    The modes come in degenerate groups (two equal beams, two bending planes): participation
    factors differ inside a group (any basis of it is right), the effective masses summed over a
    whole group do not.
    """
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    if COMM.rank == 0:
        text = suite_text("contact5.inp")
        (directory / "c5.inp").write_text(text[: text.index("*STEP,INC=1000000")])
        reference = suite_text("contact5.dat.ref")
        (directory / "reference.dat").write_text(reference)
    COMM.barrier()
    result = run_job("c5", directory, comm=COMM, progress=False)
    assert result.completed
    if COMM.rank != 0:
        return
    ref = read_frequency_output((directory / "reference.dat").read_text())
    ours = read_frequency_output((directory / "c5.dat").read_text())
    assert ours.eigenvalues.shape == ref.eigenvalues.shape == (20, 4)
    np.testing.assert_allclose(ours.eigenvalues, ref.eigenvalues, rtol=1e-6)  # measured: equal
    np.testing.assert_allclose(result.eigenvalues, ref.eigenvalues[:, 0], rtol=1e-6)
    groups = np.unique(np.round(ref.eigenvalues[:, 0] / ref.eigenvalues[0, 0], 5),
                       return_inverse=True)[1]  # fmt: skip
    for group in np.unique(groups)[:-1]:  # the last group may go on beyond mode 20
        members = groups == group
        np.testing.assert_allclose(
            ours.effective_mass[members].sum(axis=0),
            ref.effective_mass[members].sum(axis=0),
            rtol=1e-4,
            atol=1e-12,
        )
    assert ours.total_text == ref.total_text  # the total effective mass, all digits
