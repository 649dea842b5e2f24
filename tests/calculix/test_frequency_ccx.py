"""A ``*FREQUENCY`` step after a static contact step, run by ccx 2.20 and the deck runner.

The deck is the cross-validation case ``hex_linear_pressure`` (a C3D8 punch pressed onto a block)
with densities and a ``*FREQUENCY`` step appended. ccx 2.20 has no contact elements in that step
(its ``.dat`` prints 0 of them and the punch floats: a zero eigenvalue), so the runner uses the
bulk stiffness alone (docs/method.md §16). Measured: the nonzero eigenvalues, effective modal masses
and total effective masses agree in all 7 printed digits; participation factors and the modes'
printed displacements up to the sign.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from mpi4py import MPI

import cases
import numpy as np
import pytest
from helpers.ccx_runs import quiet_logs

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.modal_dat import format_e16

pytestmark = [
    pytest.mark.serial,
    pytest.mark.ccx,
    pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed"),
]

TITLES = ("E I G E N V A L U E", "P A R T I C I P A T I O N", "E F F E C T I V E   M O D A L")


def _frequency_deck(directory: Path) -> None:
    """``modes.inp``: the punch deck with densities 2.5 and 1.5 and a 6-mode *FREQUENCY step."""
    cases._hex_linear_pressure(directory)
    text = (directory / "hex_linear_pressure.inp").read_text()
    text = text.replace("*MATERIAL, NAME=M_E1\n", "*MATERIAL, NAME=M_E1\n*DENSITY\n2.5\n")
    text = text.replace("*MATERIAL, NAME=M_E2\n", "*MATERIAL, NAME=M_E2\n*DENSITY\n1.5\n")
    text = text.rstrip("\n") + "\n*STEP\n*FREQUENCY,STORAGE=YES\n6\n*END STEP\n"
    (directory / "modes.inp").write_text(text)


def _block(path: Path, title: str) -> np.ndarray:
    """The numeric rows (mode number dropped) of the block whose title contains ``title``."""
    lines = path.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if title in line)
    rows, seen = [], False
    for line in lines[start + 1 :]:
        fields = line.split()
        if fields and re.fullmatch(r"\d+", fields[0]):
            rows.append([float(f) for f in fields[1:]])
            seen = True
        elif seen:
            break
    return np.array(rows)


def test_frequency_step_after_contact_matches_ccx(tmp_path):
    ccx_dir, ntf_dir = tmp_path / "ccx", tmp_path / "ntf"
    ccx_dir.mkdir()
    ntf_dir.mkdir()
    _frequency_deck(ccx_dir)
    shutil.copy(ccx_dir / "modes.inp", ntf_dir)
    run_ccx(ccx_dir, "modes", timeout=120)
    with quiet_logs():
        result = run_job("modes", ntf_dir, comm=MPI.COMM_SELF)
    assert result.completed and result.eigenvalues.size == 6
    ccx_dat, ntf_dat = ccx_dir / "modes.dat", ntf_dir / "modes.dat"
    a, b = _block(ccx_dat, TITLES[0]), _block(ntf_dat, TITLES[0])
    assert a.shape == b.shape == (6, 4)
    scale = np.abs(a[:, 0]).max()
    floating = np.abs(a[:, 0]) < 1e-9 * scale  # the punch's free motion along z
    assert floating.tolist() == [True] + [False] * 5
    assert np.abs(b[floating, 0]).max() < 1e-9 * scale
    np.testing.assert_allclose(b[~floating], a[~floating], rtol=1e-6)  # 7 printed digits
    factors_a, factors_b = _block(ccx_dat, TITLES[1]), _block(ntf_dat, TITLES[1])
    np.testing.assert_allclose(np.abs(factors_b), np.abs(factors_a), rtol=1e-5, atol=1e-9)
    mass_a, mass_b = _block(ccx_dat, TITLES[2]), _block(ntf_dat, TITLES[2])
    np.testing.assert_allclose(mass_b, mass_a, rtol=1e-5, atol=1e-12)
    total = "T O T A L   E F F E C T I V E   M A S S"
    assert (
        ccx_dat.read_text().split(total)[1].split("\n")[4]
        == (ntf_dat.read_text().split(total)[1].split("\n")[4])
    )
    # Each mode's *NODE PRINT (carried over from the static step) up to the mode's sign
    # (ARPACK's and SLEPc's are arbitrary); measured within 2e-13 of the largest value.
    modes_a, modes_b = (
        [b for b in read_dat(path) if b.name == "U" and b.time == pytest.approx(2.0)]
        for path in (ccx_dat, ntf_dat)
    )
    assert len(modes_a) == len(modes_b) == 6
    for a_mode, b_mode in zip(modes_a, modes_b):
        np.testing.assert_array_equal(a_mode.labels, b_mode.labels)
        sign = np.sign((a_mode.values * b_mode.values).sum())
        scale = np.abs(a_mode.values).max()
        assert np.abs(a_mode.values - sign * b_mode.values).max() <= 1e-6 * scale
    assert ccx_dat.read_text().count("N U M B E R") == ntf_dat.read_text().count("N U M B E R")


@pytest.mark.parametrize(
    "value, text",
    [(13102.19, "   0.1310219E+05"), (-1.950676e-4, "  -0.1950676E-03"), (0.0, "   0.0000000E+00"),
     (0.99999999, "   0.1000000E+01")],
)  # fmt: skip
def test_e16_format_is_fortrans(value, text):
    assert format_e16(value) == text


def test_frequency_ranges_and_modal_dynamic_after_loads_are_refused(tmp_path):
    _frequency_deck(tmp_path)
    deck = (tmp_path / "modes.inp").read_text()
    (tmp_path / "range.inp").write_text(
        deck.replace("*FREQUENCY,STORAGE=YES\n6", "*FREQUENCY\n6,1.,5.")
    )
    with pytest.raises(DeckError, match="frequency range"):
        read_deck(tmp_path / "range.inp")
    modal = deck + "*STEP\n*MODAL DYNAMIC\n1e-3,1.\n*END STEP\n"
    (tmp_path / "modal.inp").write_text(modal)
    # the static step's loads: ccx removes them in the modal step (test_modal_dynamic_ccx.py)
    with pytest.raises(DeckError, match=r"modal\.inp:\d+: \*MODAL DYNAMIC after a step with loads"):
        read_deck(tmp_path / "modal.inp")
    assert read_deck(tmp_path / "modes.inp").steps[-1].frequency.num_eigenvalues == 6


def test_stress_prints_of_modes_are_refused_before_running(tmp_path):
    _frequency_deck(tmp_path)
    deck = (tmp_path / "modes.inp").read_text()
    deck = deck.replace("*FREQUENCY,STORAGE=YES\n6\n", "*FREQUENCY\n6\n*EL PRINT, ELSET=E1\nS\n")
    (tmp_path / "stress.inp").write_text(deck)
    with pytest.raises(NotImplementedError, match=r"\*EL PRINT S in the \*FREQUENCY step"):
        run_job("stress", tmp_path, comm=MPI.COMM_SELF)


def test_frequency_under_nlgeom_is_refused(tmp_path):
    _frequency_deck(tmp_path)
    deck = (tmp_path / "modes.inp").read_text().replace("*STEP, NLGEOM=NO", "*STEP, NLGEOM")
    (tmp_path / "nlgeom.inp").write_text(deck)
    with pytest.raises(DeckError, match=r"\*FREQUENCY with NLGEOM .* is not supported yet"):
        read_deck(tmp_path / "nlgeom.inp")
