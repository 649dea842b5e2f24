"""``*MODAL DYNAMIC`` with ``*MODAL DAMPING, RAYLEIGH``: ccx 2.20 against the deck runner.

contact5 and contact5lin (ccx's own decks: two C3D20 cantilevers 0.5 apart, the upper one pushed
onto the lower one by a step load, 20 modes, ``alpha = 15000``) and their variants without the
contact pair, printing every increment under ccx 2.20's increment rules (docs/method.md §25).
Measured on the two decks: U within 1.1e-9 and V within 2.8e-8 of the largest printed value (the
printed digits); on the variants, every increment printed, within 4.8e-7 (2.0e-6 on 2 processes).
ccx 2.20 applies no contact force in the step: the loaded beam passes through the other one,
and its output is the same with or without the contact pair (asserted below, on ccx alone).
The runner follows it. Serial and on 2 processes (ccx on rank 0).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_suite import suite_file_exists, suite_text

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.job import run_job

COMM = MPI.COMM_WORLD
PAIR = "*CONTACT PAIR,INTERACTION=SI1,TYPE=NODE TO SURFACE\nSslav,Smast\n"
INCREMENTS = "*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.\n1.E-05,0.176e-4,1.E-15,1.E-06\n"

pytestmark = [
    pytest.mark.ccx,
    pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed"),
    pytest.mark.skipif(
        not suite_file_exists("contact5.inp"), reason="calculix-ccx-test is not installed"
    ),
]


def _deck(name: str) -> str:
    return suite_text(f"{name}.inp")


def _both(directory: Path, job: str, text: str) -> tuple[dict, dict]:
    """Run ``text`` with ccx (rank 0) and the runner (all ranks): blocks by (name, time)."""
    if COMM.rank == 0:
        (directory / "ccx").mkdir()
        (directory / "ntf").mkdir()
        (directory / "ccx" / f"{job}.inp").write_text(text)
        (directory / "ntf" / f"{job}.inp").write_text(text)
        run_ccx(directory / "ccx", job)
    COMM.barrier()
    result = run_job(job, directory / "ntf", comm=COMM, progress=False)
    assert result.completed
    if COMM.rank != 0:
        return {}, {}
    ccx = {(b.name, b.time): b for b in read_dat(directory / "ccx" / f"{job}.dat")}
    ours = {(b.name, b.time): b for b in read_dat(directory / "ntf" / f"{job}.dat")}
    return ccx, ours


def _assert_blocks_agree(ccx: dict, ours: dict, rtol: float) -> None:
    assert list(ours) == list(ccx)  # the same blocks at the same times, in order
    for key, block in ccx.items():
        np.testing.assert_array_equal(ours[key].labels, block.labels)
        scale = np.abs(block.values).max()
        assert np.abs(ours[key].values - block.values).max() <= rtol * scale, key


@pytest.mark.mpi
@pytest.mark.parametrize("job", ["contact5", "contact5lin"])
def test_ccx_decks_agree_with_ccx(tmp_path, job):
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    ccx, ours = _both(directory, job, _deck(job))
    if COMM.rank == 0:
        assert {name for name, _ in ccx} == {"U", "V"}
        _assert_blocks_agree(ccx, ours, 1e-6)  # measured 1.1e-9 (U), 2.8e-8 (V)


@pytest.mark.mpi
@pytest.mark.parametrize(
    "procedure, times, start",
    [
        # fixed increments (a bare DIRECT is not recognized by 2.20): not cut at the end
        ("*MODAL DYNAMIC,DIRECT\n3.E-06,1.e-5\n", [3e-6, 6e-6, 9e-6, 12e-6], 2.0),
        # DIRECT=NO: each increment 1.5 times the last, the last one cut at the period
        (
            "*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.\n1.E-06,1.e-5\n",
            [1e-6, 2.5e-6, 4.75e-6, 8.125e-6, 1e-5],
            0.0,
        ),
        # the initial increment above the maximum is kept, then the maximum
        (
            "*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.\n3.E-06,0.6e-5,1e-15,1e-6\n",
            [3e-6, 4e-6, 5e-6, 6e-6],
            0.0,
        ),
    ],
)
def test_increments_and_values_without_contact_agree_with_ccx(tmp_path, procedure, times, start):
    """Printing every increment (FREQUENCY=1), with ``start > 0`` after a static step (no loads).

    ccx starts the modal step at the frequency step's start: the frequency step takes no time.
    The printed times have 7 digits: the increments are read where the step starts at 0.
    """
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    text = _deck("contact5").replace(PAIR, "").replace(INCREMENTS, procedure)
    text = text.replace("FREQUENCY=100", "FREQUENCY=1")
    if start > 0.0:
        static = f"*STEP\n*STATIC\n0.5,{start}\n*END STEP\n*STEP\n*FREQUENCY"
        text = text.replace("*STEP\n*FREQUENCY", static)
    ccx, ours = _both(directory, "beams", text)
    if COMM.rank == 0:
        printed = np.array([t for name, t in ccx if name == "U"])
        assert printed == pytest.approx(start + np.array(times), rel=1e-6, abs=1e-12)
        # measured 4.8e-7 serial, 2.0e-6 on 2 processes: U at the first increment, whose largest
        # value is small (the modes' round-off from the eigensolver shows relatively more)
        _assert_blocks_agree(ccx, ours, 1e-5)


@pytest.mark.serial
def test_ccx_applies_no_contact_force_in_a_modal_dynamic_step(tmp_path):
    """The measurement behind the runner's choice: ccx 2.20's result is the same without the pair.

    Over 6e-5 the loaded beam's tip moves about 1.04 towards the other beam, twice the gap of 0.5.
    """
    text = _deck("contact5").replace(
        INCREMENTS, INCREMENTS.replace("1.E-05,0.176e-4", "1.E-06,0.6e-4")
    )
    text = text.replace("FREQUENCY=100", "FREQUENCY=5")
    for job, deck in (("pair", text), ("nopair", text.replace(PAIR, ""))):
        (tmp_path / f"{job}.inp").write_text(deck)
        run_ccx(tmp_path, job)
    with_pair, without = read_dat(tmp_path / "pair.dat"), read_dat(tmp_path / "nopair.dat")
    assert len(with_pair) == len(without) == 24  # U and V at 12 times
    for a, b in zip(with_pair, without):
        np.testing.assert_array_equal(a.values, b.values)
    deepest = max(-b.values[:, 1].min() for b in with_pair if b.name == "U")
    assert deepest > 1.0  # the tip of the loaded beam, through the gap of 0.5


@pytest.mark.serial
@pytest.mark.parametrize(
    "change, message",
    [
        ("*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.", r"\*MODAL DYNAMIC, STEADY STATE is not supported"),
        ("*FREQUENCY,STORAGE=YES", r"needs the modes of an earlier \*FREQUENCY, STORAGE=YES"),
        ("*MODAL DAMPING,RAYLEIGH", r"\*MODAL DAMPING without RAYLEIGH"),
        ("*CLOAD", r"\*CLOAD with AMPLITUDE=A1 in a \*MODAL DYNAMIC step"),
        ("*NODE PRINT", r"DIRECT=NO needs DELTMX"),
    ],
)
def test_unsupported_modal_cards_are_refused_with_their_line(tmp_path, change, message):
    text = _deck("contact5")
    replaced = {
        "*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.": "*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.,STEADY STATE",
        "*FREQUENCY,STORAGE=YES": "*FREQUENCY",
        "*MODAL DAMPING,RAYLEIGH": "*MODAL DAMPING",
        "*CLOAD": "*AMPLITUDE,NAME=A1\n0.,0.,1.,1.\n*CLOAD,AMPLITUDE=A1",
        "*NODE PRINT": "*NODE PRINT",
    }[change]
    text = text.replace(change, replaced, 1)
    if change == "*NODE PRINT":
        text = text.replace("DIRECT=NO,DELTMX=1.", "DIRECT=NO")
    (tmp_path / "bad.inp").write_text(text)
    with pytest.raises(DeckError, match=r"bad\.inp:\d+: .*" + message):
        read_deck(tmp_path / "bad.inp")
