"""CalculiX's own contact-damping decks contdamp1 and contdamp2 against ccx 2.20 (§29).

Both hold a SPRINGA from a fixed node to node 2, which belongs to no element and is the slave
node of a node-to-surface pair (``*SURFACE, TYPE=NODE``) with ``*CONTACT DAMPING`` (contdamp1:
normal; contdamp2: ``TANGENT FRACTION=1``, the motion tangential to the master face); a C3D8
mass tied to node 2 by ``*EQUATION``; ``*DYNAMIC, DIRECT``, 100 increments, ``*NODE PRINT`` U
and V every 10. Nodes 1 and 2 get their dofs from carrier cells (§29.6). ccx 2.20 runs each deck
in a scratch directory; every printed U and V block agrees within 1e-6 of its largest value
(measured: 0, every printed digit, with ccx's initial acceleration of docs/method.md §12.7; U
3.3e-7 and V 1.7e-5 with the exact start; ccx's 200 Newton iterations in 100 increments), serial
and on 2 processes.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_runs import run_ccx_and_ours

from dolfinx_ntf.calculix.dat import read_dat

SUITE = Path("/usr/share/doc/calculix-ccx-test/examples/test")
COMM = MPI.COMM_WORLD

pytestmark = [
    pytest.mark.mpi,
    pytest.mark.ccx,
    pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed"),
]


@pytest.mark.parametrize("deck", ["contdamp1", "contdamp2"])
def test_contdamp_deck_matches_ccx(tmp_path, deck):
    source = SUITE / f"{deck}.inp"
    if not source.exists():
        pytest.skip(f"{source} is not installed (Debian package calculix-ccx-test)")
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, deck, lambda d: shutil.copy(source, d), COMM)
    if COMM.rank != 0:
        return
    ccx, ours = read_dat(ccx_dir / f"{deck}.dat"), read_dat(ntf_dir / f"{deck}.dat")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in ccx]
    assert {b.name for b in ccx} == {"U", "V"} and len(ccx) == 20
    for a, b in zip(ccx, ours):
        np.testing.assert_array_equal(a.labels, b.labels)
        scale = np.abs(a.values).max()
        assert scale > 0.0
        assert np.abs(a.values - b.values).max() <= 1e-6 * scale, (a.name, a.time)
    # node 2 (on its carrier cell) moves with the mass through *EQUATION
    last = [b for b in ours if b.name == "U"][-1]
    assert last.values[1, 0] == pytest.approx(last.values[2, 0], rel=1e-12)
