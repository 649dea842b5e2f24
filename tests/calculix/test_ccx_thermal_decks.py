"""Thermal decks in the deck runner (``*COUPLED TEMPERATURE-DISPLACEMENT``) against ccx 2.20.

docs/method.md §20.8. Two C3D8 bars stacked along z touch at z = 0 (the lower bar's top faces are
the master surface, the upper bar's bottom nodes the slave nodes); the ends are held at two
temperatures and heat crosses the contact through a ``*GAP CONDUCTANCE``. Steady: the closed form
of three resistances in series and ccx's printed temperatures. Transient (the mechanics is dynamic
in ccx's transient coupled step): ccx's increments, temperatures, displacements and contact
displacements. CalculiX's contact8 and contact9 (ccx's own decks) run and agree with ccx 2.20.
"""

from __future__ import annotations

import gzip
import re
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.bar_decks import ids, stacked_bars
from helpers.ccx_runs import largest_differences, run_ccx_and_ours

from dolfinx_ntf.calculix.dat import DatBlock, read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.model import build_model

CCX = pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
SUITE = Path("/usr/share/doc/calculix-ccx-test/examples/test")

#: Conductivity, gap conductance, bar length (each bar, along z) and end temperatures.
K, H, LENGTH, T_LOW, T_HIGH = 2.0, 3.0, 1.0, 300.0, 400.0
#: ccx's field controls at round-off, so that converged solutions are compared.
TIGHT = "*CONTROLS, PARAMETERS=FIELD\n1e-10, 1e-8, , , 1e-10\n"


def bars_deck(
    *,
    procedure: str = "*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE\n1., 1.\n",
    elements: int = 2,
    expansion: float = 0.0,
    nlgeom: bool = False,
    controls: str = TIGHT,
    extra: str = "",
) -> str:
    """Two unit-square bars of ``elements`` C3D8 each, lower z in [-1, 0], upper z in [0, 1]."""
    nodes, cells, layers = stacked_bars(elements, 0.0, LENGTH)
    lower_top, upper_bottom = layers[0, elements], layers[1, 0]
    bottom, top = layers[0, 0], layers[1, elements]
    x0 = [n for layer in layers.values() for n in (layer[0], layer[3])]
    y0 = [n for layer in layers.values() for n in (layer[0], layer[1])]

    element_lines = "\n".join(f"{e + 1}, {ids(c)}" for e, c in enumerate(cells))
    return (
        "*NODE, NSET=NALL\n" + "\n".join(nodes) + "\n"
        "*ELEMENT, TYPE=C3D8, ELSET=EALL\n" + element_lines + "\n"
        f"*ELSET, ELSET=ELOWER\n{elements}\n"
        f"*NSET, NSET=BOTTOM\n{ids(bottom)}\n*NSET, NSET=TOP\n{ids(top)}\n"
        f"*NSET, NSET=SLAVES\n{ids(upper_bottom)}\n*NSET, NSET=X0\n{ids(x0)}\n"
        f"*NSET, NSET=Y0\n{ids(y0)}\n*NSET, NSET=MTOP\n{ids(lower_top)}\n"
        f"*SURFACE, NAME=SLAVE\n{elements + 1}, S1\n*SURFACE, NAME=MASTER\nELOWER, S2\n"
        "*MATERIAL, NAME=M\n*ELASTIC\n1000., 0.\n"
        f"*CONDUCTIVITY\n{K}\n*EXPANSION\n{expansion}\n*DENSITY\n1.\n*SPECIFIC HEAT\n1.\n"
        "*SOLID SECTION, ELSET=EALL, MATERIAL=M\n"
        "*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n"
        f"1.e4, 1., 1.e-3\n*GAP CONDUCTANCE\n{H}\n"
        "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE\nSLAVE, MASTER\n"
        "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 350.\n"
        "*BOUNDARY\nBOTTOM, 1, 3\nX0, 1, 1\nY0, 2, 2\n"
        f"*STEP{', NLGEOM' if nlgeom else ''}\n{procedure}{controls}"
        f"*BOUNDARY\nBOTTOM, 11, 11, {T_HIGH}\nTOP, 11, 11, {T_LOW}\n{extra}"
        "*NODE PRINT, NSET=NALL\nU, NT\n*CONTACT PRINT\nCDIS\n*END STEP\n"
    )


def _run_both(
    tmp_path: Path, name: str, text: str, comm: MPI.Comm = MPI.COMM_SELF
) -> tuple[list[DatBlock], list[DatBlock]]:
    """ccx's and our ``.dat`` blocks of the deck ``text`` (ours run on ``comm``; the files are
    written and read by its rank 0, the others get empty lists)."""
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, name, text, comm)
    if comm.rank != 0:
        return [], []
    return read_dat(ccx_dir / f"{name}.dat"), read_dat(ntf_dir / f"{name}.dat")


# -- reader and model ----------------------------------------------------------------------------


def test_reader_reads_the_thermal_cards(tmp_path):
    deck_text = bars_deck(
        procedure="*COUPLED TEMPERATURE-DISPLACEMENT, ALPHA=-0.1\n0.1, 1., 1e-3, 0.5, 20.\n"
    )
    (tmp_path / "bars.inp").write_text(deck_text)
    deck = read_deck(tmp_path / "bars.inp")
    step = deck.steps[0]
    assert (step.coupled.steady, step.coupled.deltmx, step.coupled.alpha) == (False, 20.0, -0.1)
    assert (step.static.initial_increment, step.static.period, step.static.maximum) == (
        0.1,
        1.0,
        0.5,
    )
    assert [(b.target, b.first_dof, b.value) for b in step.temperatures] == [
        ("BOTTOM", 11, T_HIGH),
        ("TOP", 11, T_LOW),
    ]
    assert all(b.first_dof != 11 for b in step.boundaries)
    (initial,) = deck.initial_temperatures
    assert initial.value == 350.0 and initial.nodes.size == 24
    assert deck.interactions["SI"].extra["*GAP CONDUCTANCE"] == ((H,),)


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("BOTTOM, 11, 11, 400.0", "BOTTOM, 1, 11, 400.0", r"degree of freedom 11 is not"),
        ("BOTTOM, 11, 11, 400.0", "BOTTOM, 11, 12, 400.0", r"dof 11 \(temperature\) cannot"),
        ("NALL, 350.", "NALL, 11, 350.", r"TYPE=TEMPERATURE data line: node or node set, temp"),
        ("STEADY STATE", "ALPHA=-0.5", r"ALPHA must be in \[-1/3, 0\]"),
        ("1., 1.\n*CONTROLS", "1., -1.\n*CONTROLS", r"period must be > 0"),
        (f"*CONDUCTIVITY\n{K}\n", f"*CONDUCTIVITY\n{K}, 0.\n{K}, 100.\n",
         r"temperature-dependent \*CONDUCTIVITY of material M \(several data lines\) in a deck "
         r"whose temperatures change"),  # method §41.2: the table's second line
    ],
)  # fmt: skip
def test_reader_errors_name_the_line(tmp_path, old, new, match):
    text = bars_deck()
    assert old in text
    (tmp_path / "bad.inp").write_text(text.replace(old, new, 1))
    with pytest.raises(DeckError, match=match) as info:
        read_deck(tmp_path / "bad.inp")
    assert re.search(r"bad\.inp:\d+", str(info.value))


@pytest.mark.parametrize(
    ("old", "new", "error", "match"),
    [
        ("*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE", "*STATIC", NotImplementedError,
         r"supported in \*COUPLED TEMPERATURE-DISPLACEMENT and \*HEAT TRANSFER steps only"),
        (f"*CONDUCTIVITY\n{K}\n", "", ValueError, r"material M needs \*CONDUCTIVITY"),
        ("*BOUNDARY\nBOTTOM, 11", "*BOUNDARY, AMPLITUDE=A\nBOTTOM, 11", NotImplementedError,
         r"dof 11 with an AMPLITUDE"),
        (", STEADY STATE\n1., 1.\n", "\n0.1, 1., , , 5.\n", NotImplementedError,
         r"DELTMX .* is not supported yet"),
    ],
)  # fmt: skip
def test_model_refuses_what_it_cannot_do(tmp_path, old, new, error, match):
    text = bars_deck().replace(old, new, 1)
    if "AMPLITUDE=A" in text:
        text = text.replace("*MATERIAL", "*AMPLITUDE, NAME=A\n0., 0., 1., 1.\n*MATERIAL", 1)
    (tmp_path / "bad.inp").write_text(text)
    with pytest.raises(error, match=match):
        build_model(read_deck(tmp_path / "bad.inp"), MPI.COMM_SELF)


# -- against the closed form and ccx --------------------------------------------------------------


@pytest.mark.mpi
@pytest.mark.ccx
@CCX
def test_steady_bars_agree_with_closed_form_and_ccx(tmp_path):
    """Steady heat flow through the bars and the conductance: ``q = dT/(2 L/k + 1/h)``.

    The temperature is linear in each bar (the element is exact) and jumps by ``q/h`` at the
    contact (the matching meshes pass the node-to-face patch test: each slave node's spring
    carries its quarter of the face).
    """
    deck_text = bars_deck(extra="*EL PRINT, ELSET=EALL\nHFL\n")
    ccx, ntf = _run_both(tmp_path, "bars", deck_text, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank != 0:
        return
    worst = largest_differences(ccx, ntf)
    assert worst["NT"] < 1e-6  # ccx prints 7 digits
    assert worst["HFL"] < 1e-6
    (nt,) = [b for b in ntf if b.name == "NT"]
    q = (T_HIGH - T_LOW) / (2 * LENGTH / K + 1 / H)
    (hfl,) = [b for b in ntf if b.name == "HFL"]  # -k grad T at the 8 points of the 4 elements
    assert hfl.values.shape == (32, 3)
    np.testing.assert_allclose(hfl.values, np.tile([0.0, 0.0, q], (32, 1)), rtol=0, atol=1e-9 * q)
    deck = read_deck(Path(str(tmp_path)) / "ntf" / "bars.inp")
    z = deck.node_coords[deck.node_index(nt.labels), 2]
    upper = np.isin(nt.labels, deck.nsets["SLAVES"])  # the upper bar's nodes at z = 0
    expected = np.where(
        (z < 0) | (np.isclose(z, 0.0) & ~upper),
        T_HIGH - q * (z + LENGTH) / K,
        T_LOW + q * (LENGTH - z) / K,
    )
    np.testing.assert_allclose(nt.values[:, 0], expected, rtol=1e-10)
    assert np.ptp(expected) == pytest.approx(T_HIGH - T_LOW)


@pytest.mark.mpi
@pytest.mark.ccx
@CCX
def test_transient_bars_agree_with_ccx(tmp_path):
    """A transient coupled step (backward Euler, dynamic mechanics with HHT, NLGEOM, thermal
    expansion pressing the bars together): temperatures, displacements and contact displacements.

    Fixed increments (DIRECT): ccx's automatic ones would follow its dynamic impact rules here
    (docs/method.md §12.4), which the runner does not reproduce; contact8 and contact9 check the
    automatic increments. ccx's default controls: with round-off ones ccx does not converge on
    this deck (its contact iterations contract by about 0.7 each), so the differences in U and
    CDIS are ccx's convergence error (measured 1.3e-4 and 2.9e-3, in the first increment; NT
    2.5e-7).
    """
    text = bars_deck(
        procedure="*COUPLED TEMPERATURE-DISPLACEMENT, DIRECT\n0.01, 0.1\n",
        expansion=1e-4,
        nlgeom=True,
        controls="",
    )
    # both bars heat from 300 and expand against the held ends: the contact closes
    text = text.replace("TOP, 11, 11", "TOP, 3, 3\nTOP, 11, 11").replace("NALL, 350.", "NALL, 300.")
    ccx, ntf = _run_both(tmp_path, "tbars", text, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank != 0:
        return
    assert len({b.time for b in ccx}) == 10
    worst = largest_differences(ccx, ntf)
    assert worst["NT"] < 1e-6
    assert worst["U"] < 1e-3
    assert worst["CDIS"] < 1e-2


def _ccx_deck(name: str, tight: bool) -> str:
    """ccx's deck ``name`` with U and NT printed (and round-off field controls if ``tight``)."""
    path = SUITE / f"{name}.inp"
    if path.exists():
        text = path.read_text(encoding="latin-1")
    else:
        with gzip.open(f"{path}.gz", "rt", encoding="latin-1") as stream:
            text = stream.read()
    prints = "*NODE PRINT, NSET=NALL\nU, NT\n*EL PRINT, ELSET=EALL\nHFL\n" + (
        TIGHT if tight else ""
    )
    return text.replace("*CONTACT PRINT", prints + "*CONTACT PRINT", 1)


@pytest.mark.serial
@pytest.mark.ccx
@CCX
@pytest.mark.skipif(not list(SUITE.glob("contact9.inp*")), reason="calculix-ccx-test missing")
def test_contact9_agrees_with_ccx(tmp_path):
    """contact9 (gap conductance, mechanical and thermal contact, NLGEOM, transient): ccx's 57
    increments; converged to round-off in both codes, U, NT and CDIS agree to 1e-5 (measured
    1.2e-7, 5e-9, 1.2e-7 of the run's largest values). With ccx's default controls (its own
    convergence error, up to 5.5e-3 in U against its converged answer) our converged run is off
    ccx's by the same amount."""
    ccx, ntf = _run_both(tmp_path, "contact9", _ccx_deck("contact9", tight=True))
    assert len({b.time for b in ccx}) == 57
    worst = largest_differences(ccx, ntf)
    assert worst["U"] < 1e-5 and worst["NT"] < 1e-5 and worst["CDIS"] < 1e-5
    assert worst["HFL"] < 1e-5  # the reference configuration's flux, as ccx's (measured 2.5e-8)


@pytest.mark.serial
@pytest.mark.ccx
@CCX
@pytest.mark.skipif(not list(SUITE.glob("contact8.inp*")), reason="calculix-ccx-test missing")
def test_contact8_agrees_with_ccx(tmp_path):
    """contact8 (gap conductance without contact pressure): with ccx's default controls, the
    same 57 increments, the same contact elements at each, U, NT and CDIS within 1e-3 of the
    run's largest value (measured 5.0e-4, 2.1e-4, 2.8e-4: ccx's convergence error, the
    amount by which ccx's own answer moves when its controls are tightened)."""
    ccx, ntf = _run_both(tmp_path, "contact8", _ccx_deck("contact8", tight=False))
    assert len({b.time for b in ccx}) == 57
    worst = largest_differences(ccx, ntf)
    assert worst["U"] < 1e-3 and worst["NT"] < 1e-3 and worst["CDIS"] < 1e-3
    assert worst["HFL"] < 1e-3
