"""``*MODAL DYNAMIC`` with ``*MODAL DAMPING, RAYLEIGH``: ccx 2.20 against the deck runner.

contact5 and contact5lin (ccx's own decks in Debian 12's suite: two C3D20 cantilevers 0.5 apart,
the upper one pushed onto the lower one by a step load, 20 modes, ``alpha = 15000``; Debian 13's
and sid's suites ship a surface-to-surface contact5 instead) and a generated deck of the same
kind (two C3D8 cantilevers, ``helpers.ccx_suite.two_beams_deck``, every release), printing every
increment under ccx 2.20's increment rules (docs/method.md §25).
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
from helpers.ccx_runs import run_ccx_and_ours
from helpers.ccx_suite import node_to_surface_suite_deck, suite_text, two_beams_deck

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.job import run_job

COMM = MPI.COMM_WORLD
VARIABLE = "*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.\n1.E-06,0.6e-4,1.E-15,1.E-06"

pytestmark = [
    pytest.mark.ccx,
    pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed"),
]
SUITE = pytest.mark.skipif(
    not node_to_surface_suite_deck("contact5"),
    reason="no node-to-surface contact5 (Debian 12's calculix-ccx-test) installed",
)


def _deck(name: str) -> str:
    return suite_text(f"{name}.inp")


def _both(directory: Path, job: str, text: str) -> tuple[dict, dict]:
    """Run ``text`` with ccx (rank 0) and the runner (all ranks): blocks by (name, time)."""
    ccx_dir, ntf_dir = run_ccx_and_ours(directory, job, text, COMM)
    if COMM.rank != 0:
        return {}, {}
    ccx = {(b.name, b.time): b for b in read_dat(ccx_dir / f"{job}.dat")}
    ours = {(b.name, b.time): b for b in read_dat(ntf_dir / f"{job}.dat")}
    return ccx, ours


def _assert_blocks_agree(ccx: dict, ours: dict, rtol: float) -> None:
    assert list(ours) == list(ccx)  # the same blocks at the same times, in order
    for key, block in ccx.items():
        np.testing.assert_array_equal(ours[key].labels, block.labels)
        scale = np.abs(block.values).max()
        assert np.abs(ours[key].values - block.values).max() <= rtol * scale, key


@SUITE
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
def test_increments_and_values_agree_with_ccx(tmp_path, procedure, times, start):
    """The generated two beams, every increment printed; ``start > 0``: after a static step.

    ccx starts the modal step at the frequency step's start: the frequency step takes no time.
    The printed times have 7 digits: the increments are read where the step starts at 0.
    """
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    text = two_beams_deck(procedure)
    if start > 0.0:
        static = f"*STEP\n*STATIC\n0.5,{start}\n*END STEP\n*STEP\n*FREQUENCY"
        text = text.replace("*STEP\n*FREQUENCY", static)
    ccx, ours = _both(directory, "beams", text)
    if COMM.rank == 0:
        printed = np.array([t for name, t in ccx if name == "U"])
        assert printed == pytest.approx(start + np.array(times), rel=1e-6, abs=1e-12)
        # measured 4.8e-7 serial, 2.0e-6 on 2 processes on contact5's beams: U at the first
        # increment, whose largest value is small (the modes' round-off shows relatively more)
        _assert_blocks_agree(ccx, ours, 1e-5)


@pytest.mark.mpi
def test_two_beams_with_their_pair_agree_with_ccx(tmp_path):
    """Over 6e-5 (every 5th increment printed): the loaded beam passes the other, as in ccx."""
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    ccx, ours = _both(directory, "beams", two_beams_deck(VARIABLE, frequency=5))
    if COMM.rank == 0:
        assert len(ccx) == 24
        _assert_blocks_agree(ccx, ours, 1e-5)


@pytest.mark.serial
def test_ccx_applies_no_contact_force_in_a_modal_dynamic_step(tmp_path):
    """The measurement behind the runner's choice, on ccx alone.

    The generated two beams over 6e-5: the output is the same with and without the pair, while
    the loaded tip moves 0.74 towards a beam 0.5 away. The same pair acts in a static step: under
    twice the load the lower beam is pushed down.
    """
    decks = {
        "pair": two_beams_deck(VARIABLE, frequency=5),
        "nopair": two_beams_deck(VARIABLE, frequency=5, pair=False),
        "static": two_beams_deck("*STATIC\n0.1,1.", modes=2)
        .replace("*MODAL DAMPING, RAYLEIGH\n, , 15000., 0.\n", "")
        .replace("U, V", "U")
        .replace("TIP, 2, -7.", "TIP, 2, -14.")
        .replace("*STEP\n*FREQUENCY, STORAGE=YES\n2\n*END STEP\n", ""),
    }
    for job, deck in decks.items():
        (tmp_path / f"{job}.inp").write_text(deck)
        run_ccx(tmp_path, job)
    with_pair, without = read_dat(tmp_path / "pair.dat"), read_dat(tmp_path / "nopair.dat")
    assert len(with_pair) == len(without) == 24  # U and V at 12 times
    for a, b in zip(with_pair, without):
        np.testing.assert_array_equal(a.values, b.values)
    deepest = max(-b.values[:, 1].min() for b in with_pair if b.name == "U")
    assert deepest > 0.7  # the tip of the loaded beam, through the gap of 0.5
    static = [b for b in read_dat(tmp_path / "static.dat") if b.name == "U"][-1]
    lower = static.labels <= 81  # the lower beam's nodes
    assert static.values[lower, 1].min() < -0.1  # pushed down through the closed springs


@SUITE
@pytest.mark.serial
def test_ccx_applies_no_contact_force_in_contact5(tmp_path):
    """contact5 over 6e-5 (every 5th increment): the same with and without its pair."""
    text = suite_text("contact5.inp").replace("1.E-05,0.176e-4", "1.E-06,0.6e-4")
    text = text.replace("FREQUENCY=100", "FREQUENCY=5")
    pair = "*CONTACT PAIR,INTERACTION=SI1,TYPE=NODE TO SURFACE\nSslav,Smast\n"
    assert pair in text
    for job, deck in (("pair", text), ("nopair", text.replace(pair, ""))):
        (tmp_path / f"{job}.inp").write_text(deck)
        run_ccx(tmp_path, job)
    with_pair, without = read_dat(tmp_path / "pair.dat"), read_dat(tmp_path / "nopair.dat")
    assert len(with_pair) == len(without) == 24
    for a, b in zip(with_pair, without):
        np.testing.assert_array_equal(a.values, b.values)
    assert max(-b.values[:, 1].min() for b in with_pair if b.name == "U") > 1.0


@pytest.mark.serial
@pytest.mark.parametrize(
    "change, replaced, message",
    [
        ("*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.", "*MODAL DYNAMIC,DIRECT=NO,DELTMX=1.,STEADY STATE",
         r"\*MODAL DYNAMIC, STEADY STATE is not supported"),
        ("*FREQUENCY, STORAGE=YES", "*FREQUENCY",
         r"needs the modes of an earlier \*FREQUENCY, STORAGE=YES"),
        ("*MODAL DAMPING, RAYLEIGH", "*MODAL DAMPING", r"\*MODAL DAMPING without RAYLEIGH"),
        ("*CLOAD", "*AMPLITUDE,NAME=A1\n0.,0.,1.,1.\n*CLOAD,AMPLITUDE=A1",
         r"\*CLOAD with AMPLITUDE=A1 in a \*MODAL DYNAMIC step"),
        ("DIRECT=NO,DELTMX=1.", "DIRECT=NO", r"DIRECT=NO needs DELTMX"),
        ("*STEP, INC=100000", "*STEP, INC=100000\n*BOUNDARY\nFIX, 1, 1, 0.1",
         r"\*BOUNDARY in a \*MODAL DYNAMIC step \(base motion\)"),
        ("*STEP\n*FREQUENCY", "*STEP\n*STATIC\n*CLOAD\nTIP, 1, 1.\n*END STEP\n*STEP\n*FREQUENCY",
         r"\*MODAL DYNAMIC after a step with loads"),
    ],
)  # fmt: skip
def test_unsupported_modal_cards_are_refused_with_their_line(tmp_path, change, replaced, message):
    text = two_beams_deck(VARIABLE)
    assert change in text
    (tmp_path / "bad.inp").write_text(text.replace(change, replaced, 1))
    with pytest.raises(DeckError, match=r"bad\.inp:\d+: .*" + message):
        read_deck(tmp_path / "bad.inp")


def test_velocity_prints_outside_modal_dynamic_steps_are_refused(tmp_path):
    text = two_beams_deck(VARIABLE).replace(
        "*STEP\n*FREQUENCY",
        "*STEP\n*STATIC\n*NODE PRINT, NSET=NALL\nV\n*END STEP\n*STEP\n*FREQUENCY",
    )
    (tmp_path / "v.inp").write_text(text)
    with pytest.raises(
        NotImplementedError,
        match=r"v\.inp:\d+: \*NODE PRINT V .* \*DYNAMIC and \*MODAL DYNAMIC steps",
    ):
        run_job("v", tmp_path, progress=False)
