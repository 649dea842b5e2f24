"""C3D15 wedges in ``*HEAT TRANSFER`` steps (docs/method.md §39) against ccx 2.20.

The decks are ``tests/data/calculix/c3d15/make_heat.py``'s: the curved C3D15 block of §34 with
temperatures prescribed on its bottom (varying over the face) and its top, steady in ccx's four
increments and transient from 20 (consistent capacity); the ``.dat.ref`` files are ccx 2.20's.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf import compat
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError
from dolfinx_ntf.calculix.job import run_job

DATA = Path(__file__).parent.parent / "data" / "calculix" / "c3d15"
ON_011 = compat.DOLFINX_VERSION >= (0, 11)
NEEDS_011 = pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")


def _run(tmp_path: Path, job: str, comm: MPI.Comm) -> tuple[list, list]:
    """ccx's stored blocks and ours (rank 0's directory for all processes; both on every one)."""
    root = Path(comm.bcast(str(tmp_path), root=0))
    if comm.rank == 0:
        shutil.copy(DATA / f"{job}.inp", root / f"{job}.inp")
    comm.barrier()
    run_job(job, root, comm=comm, progress=False)
    comm.barrier()
    return read_dat(DATA / f"{job}.dat.ref"), read_dat(root / f"{job}.dat")


@pytest.mark.mpi
@NEEDS_011
@pytest.mark.parametrize(
    "job, times",
    [
        ("wedge_heat_steady", [0.25, 0.5, 0.875, 1.0]),  # ccx's increments, ramped temperatures
        ("wedge_heat_transient", [0.05, 0.1, 0.15, 0.2]),  # DIRECT
        ("wedge_cflux_steady", [0.25, 0.5, 0.875, 1.0]),  # *CFLUX ramped with the step
        ("wedge_cflux_transient", [0.05, 0.1, 0.15, 0.2]),  # *CFLUX at once
        ("wedge_cflux_steps", [0.25, 0.5, 0.875, 1.0, 1.5, 2.0]),  # OP=MOD in step 2
        ("wedge_dflux_steady", [0.25, 0.5, 0.875, 1.0]),  # *DFLUX on curved faces
        ("wedge_dflux_transient", [0.05, 0.1, 0.15, 0.2]),
        ("wedge_film_steady", [0.25, 0.5, 0.875, 1.0]),  # *FILM: h ramped, sink at once
        ("wedge_film_transient", [0.05, 0.1, 0.15, 0.2]),
    ],
)
def test_c3d15_heat_matches_ccx(tmp_path, job, times):
    """NT at every node and HFL at ccx's 9 points equal ccx 2.20's printed digits in each of
    its increments (serial and on 2 processes): ccx's 9 points for conduction and capacity,
    the face centres constrained to C3D15's field; ``*CFLUX`` heat flows into nodes (two lines
    on one node add up, a later step's line replaces the value of its node only); ``*DFLUX``
    on curved 6-node triangles and 8-node quadrilaterals (ccx's 3 and 2 x 2 points: 3 x 3 on
    the quadrilaterals is 1.1e-4 off in NT); ``*FILM`` on the same faces (a steady step ramps
    the film coefficient, not the sink temperature: ramping the sink instead is 2.8e-1 off)."""
    ccx, ours = _run(tmp_path, job, MPI.COMM_WORLD)
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in ccx]
    assert [b.time for b in ours if b.name == "NT"] == pytest.approx(times)
    for a, b in zip(ccx, ours):
        np.testing.assert_array_equal(a.labels, b.labels)
        assert a.values.shape == b.values.shape == (a.values.shape[0], 1 if a.name == "NT" else 3)
        scale = np.abs(a.values).max()
        assert np.abs(a.values - b.values).max() <= 1e-6 * scale, (a.name, a.time)


@pytest.mark.skipif(ON_011, reason="dolfinx 0.11 runs C3D15")
def test_c3d15_heat_refused_before_dolfinx_011(tmp_path):
    shutil.copy(DATA / "wedge_heat_steady.inp", tmp_path / "h.inp")
    with pytest.raises(
        NotImplementedError, match=r"h\.inp:\d+: C3D15 \(element 1\).*dolfinx 0\.11"
    ):
        run_job("h", tmp_path, progress=False)


@pytest.mark.mpi
@NEEDS_011
@pytest.mark.parametrize(
    "job, bound",
    [
        ("wedge_coupled", 1e-6),  # U, S, NT, HFL: ccx's printed digits (difference 0)
        ("wedge_coupled_nlgeom", 1e-6),  # tight controls in both: 5.9e-7 of U at worst
    ],
)
def test_c3d15_coupled_matches_ccx(tmp_path, job, bound):
    """A steady coupled step with thermal expansion (the block clamped at its bottom): NT, U,
    RF, HFL and S as ccx 2.20's in its two increments (serial and on 2 processes): ccx's C3D15
    takes the thermal strain from the temperature at each of its 9 points (the element mean
    temperature, C3D8's, is 1e-1 off in U); under NLGEOM subtracted from the displacement
    gradient, with an unsymmetric tangent (the symmetric factorization fails)."""
    ccx, ours = _run(tmp_path, job, MPI.COMM_WORLD)
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in ccx]
    assert {b.name for b in ours} == {"NT", "U", "RF", "HFL", "S"}
    assert sorted({b.time for b in ours}) == [0.5, 1.0]
    for a, b in zip(ccx, ours):
        np.testing.assert_array_equal(a.labels, b.labels)
        scale = np.abs(a.values).max()
        assert np.abs(a.values - b.values).max() <= bound * scale, (a.name, a.time)


@NEEDS_011
def test_c3d15_transient_coupled_step_refused(tmp_path):
    """A transient coupled step with C3D15 (dynamic in its mechanics) is refused naming its
    line."""
    deck = (DATA / "wedge_coupled.inp").read_text()
    steady = "*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE"
    (tmp_path / "c.inp").write_text(deck.replace(steady, "*COUPLED TEMPERATURE-DISPLACEMENT"))
    match = r"c\.inp:\d+: transient \*COUPLED TEMPERATURE-DISPLACEMENT steps with C3D15"
    with pytest.raises(NotImplementedError, match=match):
        run_job("c", tmp_path, progress=False)


def test_cflux_on_another_dof_is_a_deck_error(tmp_path):
    deck = (DATA / "wedge_cflux_steady.inp").read_text().replace("4, 11, 50.", "4, 12, 50.")
    (tmp_path / "f.inp").write_text(deck)
    with pytest.raises(DeckError, match=r"f\.inp:\d+.*degree of freedom must be 11, got 12"):
        run_job("f", tmp_path, progress=False)


@NEEDS_011
def test_cflux_refusals_name_the_line(tmp_path):
    """A *CFLUX with an amplitude, or in a static step, is refused naming its line; a *FILM on
    a face the element does not have is an error naming its line."""
    deck = (
        (DATA / "wedge_cflux_steady.inp").read_text().replace("*CFLUX\n", "*CFLUX, AMPLITUDE=A\n")
    )
    deck = deck.replace("*STEP", "*AMPLITUDE, NAME=A\n0., 0., 1., 1.\n*STEP", 1)
    (tmp_path / "a.inp").write_text(deck)
    with pytest.raises(NotImplementedError, match=r"a\.inp:\d+: \*CFLUX with an AMPLITUDE"):
        run_job("a", tmp_path, progress=False)
    deck = (DATA / "wedge_block.inp").read_text()
    (tmp_path / "s.inp").write_text(deck.replace("*NODE PRINT", "*CFLUX\n4, 11, 50.\n*NODE PRINT"))
    match = r"s\.inp:\d+: \*CFLUX in step 1, which is not .* thermal steps only"
    with pytest.raises(NotImplementedError, match=match):
        run_job("s", tmp_path, progress=False)
    deck = (DATA / "wedge_film_steady.inp").read_text().replace("4, F3,", "4, F6,")
    (tmp_path / "f.inp").write_text(deck)
    with pytest.raises(
        ValueError, match=r"f\.inp:\d+: \*FILM F6: C3D15 elements have faces F1\.\.F5"
    ):
        run_job("f", tmp_path, progress=False)


C3D8_HEAT = """*NODE, NSET=NALL
1, 0., 0., 0.
2, 1., 0., 0.
3, 1., 1., 0.
4, 0., 1., 0.
5, 0., 0., 1.
6, 1., 0., 1.
7, 1., 1., 1.
8, 0., 1., 1.
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
*MATERIAL, NAME=M
*ELASTIC
1000., 0.3
*CONDUCTIVITY
2.
*SOLID SECTION, ELSET=EALL, MATERIAL=M
*STEP
*HEAT TRANSFER, STEADY STATE
*BOUNDARY
1, 11, 11, 100.
*DFLUX
EALL, {label}, 5.
*NODE PRINT, NSET=NALL
NT
*END STEP
"""


@pytest.mark.parametrize(
    "label, error, match",
    [
        ("S2", NotImplementedError, r"d\.inp:\d+: \*DFLUX on C3D8 faces is not supported yet"),
        ("BF", DeckError, r"d\.inp:\d+.*\*DFLUX, BF is not supported yet"),
        ("F2", NotImplementedError, r"d\.inp:\d+: \*FILM on C3D8 faces is not supported yet"),
    ],
)
def test_dflux_refusals_name_the_line(tmp_path, label, error, match):
    """*DFLUX and *FILM on faces of elements other than C3D15, and body fluxes, are refused
    naming the line (any dolfinx)."""
    deck = C3D8_HEAT.format(label=label)
    if label.startswith("F"):
        deck = deck.replace("*DFLUX\nEALL, F2, 5.", "*FILM\nEALL, F2, 20., 5.")
    (tmp_path / "d.inp").write_text(deck)
    with pytest.raises(error, match=match):
        run_job("d", tmp_path, progress=False)
