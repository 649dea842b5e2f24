"""``*HEAT TRANSFER`` decks in the deck runner against a closed form and ccx 2.20.

docs/method.md §20.9. Two C3D8 bars stacked along z (lower z in [-1, 0], upper from ``gap`` up)
with their ends held at two temperatures; heat crosses the node-to-surface contact through a
``*GAP CONDUCTANCE``. The mechanics is not solved: the springs are those of the undeformed
geometry. CalculiX's contact7 (C3D8I cubes, transient) runs and agrees with ccx 2.20.
"""

from __future__ import annotations

import gzip
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
STEADY = "*HEAT TRANSFER, STEADY STATE\n1., 1.\n"


def bars_deck(
    procedure: str = STEADY,
    *,
    gap: float = 0.0,
    conductance: str = f"{H}",
    slope: float = 1e4,
    node_slaves: bool = False,
    expansion: float = 0.0,
    extra: str = "",
) -> str:
    """Two unit-square bars of 2 C3D8 each; the upper one's bottom face (or nodes) is the slave."""
    nodes, cells, layers = stacked_bars(2, gap, LENGTH)
    slave = (
        "*SURFACE, NAME=SLAVE, TYPE=NODE\nSLAVES\n"
        if node_slaves
        else "*SURFACE, NAME=SLAVE\n3, S1\n"
    )
    return (
        "*NODE, NSET=NALL\n" + "\n".join(nodes) + "\n"
        "*ELEMENT, TYPE=C3D8, ELSET=EALL\n"
        + "\n".join(f"{e + 1}, {ids(c)}" for e, c in enumerate(cells))
        + "\n*ELSET, ELSET=ELOWER\n2\n"
        f"*NSET, NSET=BOTTOM\n{ids(layers[0, 0])}\n*NSET, NSET=TOP\n{ids(layers[1, 2])}\n"
        f"*NSET, NSET=SLAVES\n{ids(layers[1, 0])}\n"
        f"{slave}*SURFACE, NAME=MASTER\nELOWER, S2\n"
        f"*MATERIAL, NAME=M\n*ELASTIC\n1000., 0.\n*CONDUCTIVITY\n{K}\n*EXPANSION\n{expansion}\n"
        "*DENSITY\n1.\n*SPECIFIC HEAT\n1.\n*SOLID SECTION, ELSET=EALL, MATERIAL=M\n"
        "*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n"
        f"{slope}, 1.\n*GAP CONDUCTANCE\n{conductance}\n"
        "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE\nSLAVE, MASTER\n"
        "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 350.\n*BOUNDARY\nBOTTOM, 1, 3\n"
        f"*STEP\n{procedure}*BOUNDARY\nBOTTOM, 11, 11, {T_HIGH}\nTOP, 11, 11, {T_LOW}\n{extra}"
        "*NODE PRINT, NSET=NALL\nNT\n*END STEP\n"
    )


def _run_both(
    tmp_path: Path, name: str, text: str, comm: MPI.Comm = MPI.COMM_SELF
) -> tuple[list[DatBlock], list[DatBlock], int]:
    """ccx's and our ``.dat`` blocks and our largest number of springs (rank 0; others: [])."""
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, name, text, comm)
    if comm.rank != 0:
        return [], [], 0
    rows = _cvg_rows(ntf_dir / f"{name}.cvg")
    springs = max((int(line.split()[4]) for line in rows), default=0)
    return read_dat(ccx_dir / f"{name}.dat"), read_dat(ntf_dir / f"{name}.dat"), springs


def _cvg_rows(path: Path) -> list[str]:
    """The iteration rows of a ``.cvg`` file (step, increment, attempt, iteration, springs...)."""
    return [line for line in path.read_text().splitlines() if line.split()[:1] == ["1"]]


# -- reader and model ----------------------------------------------------------------------------


def test_reader_reads_heat_transfer(tmp_path):
    (tmp_path / "h.inp").write_text(bars_deck("*HEAT TRANSFER\n0.1, 2., 1e-3, 0.5\n"))
    step = read_deck(tmp_path / "h.inp").steps[0]
    assert step.coupled.heat and not step.coupled.steady and step.coupled.deltmx is None
    assert (step.static.initial_increment, step.static.period, step.static.minimum) == (
        0.1,
        2.0,
        1e-3,
    )
    assert step.static.maximum == 0.5
    (tmp_path / "s.inp").write_text(bars_deck())
    step = read_deck(tmp_path / "s.inp").steps[0]
    assert step.coupled.heat and step.coupled.steady


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("*HEAT TRANSFER, STEADY STATE", "*HEAT TRANSFER, ALPHA=-0.1", r"ALPHA"),
        ("STEADY STATE\n1., 1.", "STEADY STATE\n1., -1.", r"\*HEAT TRANSFER period must be > 0"),
        ("STEADY STATE\n1., 1.", "STEADY STATE\n1., 1., , , , 3.",
         r"\*HEAT TRANSFER data line: initial increment"),
    ],
)  # fmt: skip
def test_reader_errors_name_the_line(tmp_path, old, new, match):
    text = bars_deck()
    assert old in text
    (tmp_path / "bad.inp").write_text(text.replace(old, new, 1))
    with pytest.raises(DeckError, match=match) as info:
        read_deck(tmp_path / "bad.inp")
    assert "bad.inp:" in str(info.value)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda t: t.replace("*END STEP\n", "*END STEP\n*STEP\n*COUPLED TEMPERATURE-DISPLACEMENT"
                             "\n1., 1.\n*END STEP\n"),
         r"\*HEAT TRANSFER and \*COUPLED TEMPERATURE-DISPLACEMENT steps in one deck"),
        (lambda t: t.replace("TYPE=C3D8,", "TYPE=C3D8I,").replace(
            "*HEAT TRANSFER", "*COUPLED TEMPERATURE-DISPLACEMENT"),
         r"\*COUPLED TEMPERATURE-DISPLACEMENT with C3D8I elements is not supported yet"),
        (lambda t: t.replace("*HEAT TRANSFER\n0.1, 1.\n", "*HEAT TRANSFER\n0.1, 1., , , 5.\n"),
         r"DELTMX .* is not supported yet"),
        (lambda t: t.replace("*BOUNDARY\nBOTTOM, 11", "*BOUNDARY\nBOTTOM, 3, 3, 0.5\nBOTTOM, 11"),
         r"bad\.inp:\d+: a prescribed displacement \(0\.5\) in a \*HEAT TRANSFER deck"),
    ],
)  # fmt: skip
def test_model_refuses_what_it_cannot_do(tmp_path, change, match):
    text = change(bars_deck("*HEAT TRANSFER\n0.1, 1.\n"))
    (tmp_path / "bad.inp").write_text(text)
    with pytest.raises(NotImplementedError, match=match):
        build_model(read_deck(tmp_path / "bad.inp"), MPI.COMM_SELF)


# -- against the closed form and ccx --------------------------------------------------------------


@pytest.mark.mpi
@pytest.mark.ccx
@CCX
def test_steady_bars_agree_with_closed_form_and_ccx(tmp_path):
    """Steady heat flow through the bars and the conductance: ``q = dT/(2 L/k + 1/h)``, the
    temperature linear in each bar with the jump ``q/h`` at the contact; ccx's NT and HFL."""
    text = bars_deck(extra="*EL PRINT, ELSET=EALL\nHFL\n")
    ccx, ntf, springs = _run_both(tmp_path, "bars", text, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank != 0:
        return
    assert springs == 4
    worst = largest_differences(ccx, ntf)
    assert worst["NT"] < 1e-6 and worst["HFL"] < 1e-6  # ccx prints 7 digits
    q = (T_HIGH - T_LOW) / (2 * LENGTH / K + 1 / H)
    (hfl,) = [b for b in ntf if b.name == "HFL"]
    np.testing.assert_allclose(hfl.values, np.tile([0.0, 0.0, q], (32, 1)), rtol=0, atol=1e-9 * q)
    (nt,) = [b for b in ntf if b.name == "NT"]
    deck = read_deck(Path(str(tmp_path)) / "ntf" / "bars.inp")
    z = deck.node_coords[deck.node_index(nt.labels), 2]
    upper = np.isin(nt.labels, deck.nsets["SLAVES"])
    expected = np.where(
        (z < 0) | (np.isclose(z, 0.0) & ~upper),
        T_HIGH - q * (z + LENGTH) / K,
        T_LOW + q * (LENGTH - z) / K,
    )
    np.testing.assert_allclose(nt.values[:, 0], expected, rtol=1e-10)


@pytest.mark.mpi
@pytest.mark.ccx
@CCX
def test_transient_bars_agree_with_ccx(tmp_path):
    """A transient heat transfer step with ccx's automatic increments (0.01, 0.01, 0.015, ...,
    at most 0.05): the same 14 increment times and NT to ccx's printed digits (node-based slave
    surface: ccx's node areas, §2.2)."""
    text = bars_deck("*HEAT TRANSFER\n0.01, 0.5, , 0.05\n", node_slaves=True)
    ccx, ntf, springs = _run_both(tmp_path, "tbars", text, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank != 0:
        return
    assert springs == 4
    times = [b.time for b in ccx]
    assert len(times) == 14 and times[:3] == pytest.approx([0.01, 0.02, 0.035])
    assert largest_differences(ccx, ntf)["NT"] < 1e-6


@pytest.mark.mpi
@pytest.mark.ccx
@CCX
def test_steady_ramp_and_pressure_table_agree_with_ccx(tmp_path):
    """A steady step in 4 increments (the prescribed temperatures ramp from the initial ones)
    with a conductance table over pressure: ccx looks it up at the LINEAR law's slope (§20.1)."""
    text = bars_deck(
        "*HEAT TRANSFER, STEADY STATE\n0.25, 1.\n", conductance="20., 0.\n220., 100.", slope=50.0
    )
    ccx, ntf, springs = _run_both(tmp_path, "ramp", text, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank != 0:
        return
    assert springs == 4 and len(ccx) == 4
    assert largest_differences(ccx, ntf)["NT"] < 1e-6
    q = (T_HIGH - T_LOW) / (2 * LENGTH / K + 1 / 120.0)  # h(p = 50) = 120
    (last,) = [b for b in ntf if b.time == 1.0]
    jump = last.values[8:16, 0].reshape(2, 4)  # lower bar's top, upper bar's bottom nodes
    np.testing.assert_allclose(jump[0] - jump[1], q / 120.0, rtol=0, atol=1e-4)  # 7 digits of 350


@pytest.mark.mpi
@pytest.mark.ccx
@CCX
def test_open_gap_is_not_closed_by_expansion(tmp_path):
    """A gap of 1e-3 and thermal expansion that would close it (ccx's heat transfer step has no
    mechanics): no springs, as ccx, and ccx's temperatures."""
    text = bars_deck("*HEAT TRANSFER\n0.1, 1.\n", gap=1e-3, expansion=1e-3, node_slaves=True)
    ccx, ntf, springs = _run_both(tmp_path, "gap", text, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank != 0:
        return
    assert springs == 0
    assert largest_differences(ccx, ntf)["NT"] < 1e-6


@pytest.mark.mpi
@pytest.mark.ccx
@CCX
@pytest.mark.skipif(not list(SUITE.glob("contact7.inp*")), reason="calculix-ccx-test missing")
def test_contact7_agrees_with_ccx(tmp_path):
    """contact7 (C3D8I cubes, transient, ``*CONTROLS`` of the time incrementation): ccx's 10
    increments and NT to its printed digits (measured: equal in every digit)."""
    path = SUITE / "contact7.inp"
    if path.exists():
        text = path.read_text(encoding="latin-1")
    else:
        with gzip.open(f"{path}.gz", "rt", encoding="latin-1") as stream:
            text = stream.read()
    ccx, ntf, springs = _run_both(tmp_path, "contact7", text, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank != 0:
        return
    assert springs == 4 and len(ccx) == 10
    assert largest_differences(ccx, ntf)["NT"] < 1e-6
