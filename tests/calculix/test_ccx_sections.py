"""An element in two ``*SOLID SECTION``s: the later one holds, as in CalculiX 2.20.

Two C3D8 in a row, both in a stiff section, the second then in a soft one (metalforming's
pattern: steel by element type, then the sheet): the runner prints ccx's U, RF and S, and the
reader gives the earlier section the elements it keeps (docs/method.md §28.1).
"""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_runs import quiet_logs
from helpers.decks import TWO_C3D8

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.job import run_job

DECK = (
    """*NODE, NSET=NALL
"""
    + TWO_C3D8
    + """*ELSET, ELSET=SOFT
2
*MATERIAL, NAME=STIFF
*ELASTIC
1000.0, 0.3
*MATERIAL, NAME=SOFT
*ELASTIC
100.0, 0.3
*SOLID SECTION, ELSET=EALL, MATERIAL=STIFF
*SOLID SECTION, ELSET=SOFT, MATERIAL=SOFT
*BOUNDARY
1, 1, 3
4, 1, 1
4, 3, 3
5, 1, 2
8, 1, 1
*STEP
*STATIC
*CLOAD
9, 1, 1.0
10, 1, 1.0
11, 1, 1.0
12, 1, 1.0
*NODE PRINT, NSET=NALL
U, RF
*EL PRINT, ELSET=EALL
S
*END STEP
"""
)


def test_earlier_section_keeps_the_rest(tmp_path: Path) -> None:
    path = tmp_path / "deck.inp"
    path.write_text(DECK)
    deck = read_deck(path)
    stiff, soft = deck.sections
    assert (stiff.material, soft.material) == ("STIFF", "SOFT")
    assert stiff.elset != "EALL" and deck.elsets[stiff.elset].tolist() == [1]
    assert soft.elset == "SOFT" and deck.elsets["EALL"].tolist() == [1, 2]  # the deck's set


@pytest.mark.serial
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
def test_later_section_holds_as_in_ccx(tmp_path: Path) -> None:
    ccx_dir, ntf_dir = tmp_path / "ccx", tmp_path / "ntf"
    for d in (ccx_dir, ntf_dir):
        d.mkdir()
        (d / "sec.inp").write_text(DECK)
    run_ccx(ccx_dir, "sec", timeout=120)
    with quiet_logs(logging.ERROR):
        result = run_job("sec", ntf_dir, comm=MPI.COMM_SELF, progress=False)
    assert result.completed
    ours, theirs = read_dat(ntf_dir / "sec.dat"), read_dat(ccx_dir / "sec.dat")
    assert [b.name for b in ours] == [b.name for b in theirs] == ["U", "RF", "S"]
    for a, b in zip(ours, theirs):
        np.testing.assert_array_equal(a.labels, b.labels)
        assert np.abs(a.values - b.values).max() <= 1e-6 * np.abs(b.values).max(), a.name
    end = ours[0].values[8:, 0]  # nodes 9..12: the soft element stretches ten times more
    assert end.min() > 5 * ours[0].values[1, 0]
