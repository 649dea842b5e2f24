"""``*EL FILE`` S, E and PEEQ of C3D6 wedges: the ``.frd`` blocks against ccx 2.20 (method §35).

ccx extrapolates a wedge's two integration points to its six nodes with fixed weights (its odd
nodes 1, 3, 5 take ``1.1455 p1 - 0.1455 p2``, its even nodes the mirror: measured, not the two
triangles) and averages over the elements around each node, wedges and C3D8 alike. The decks are
a single wedge with every node's displacement prescribed (a stress varying along it), the 16-wedge
block of ``test_ccx_wedges.py`` (also with NLGEOM and with an NSET), its mixed wedge + C3D8 block,
the plastic mixed block (also with elastic wedges) and the wedge punch (contact).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_runs import run_ccx_and_ours, run_quietly
from helpers.wedge_decks import wedge_block as _block

from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.elements import C3D6_EXTRAPOLATION
from dolfinx_ntf.calculix.frd import FrdFile, read_frd

needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")

ONE_WEDGE = """*NODE, NSET=NALL
1, 0.0, 0.0, 0.0
2, 1.0, 0.1, 0.0
3, 0.2, 0.9, 0.1
4, 0.1, 0.0, 1.0
5, 1.1, 0.2, 1.2
6, 0.3, 1.0, 0.9
*ELEMENT, TYPE=C3D6, ELSET=EALL
1, 1, 2, 3, 4, 5, 6
*MATERIAL, NAME=EL
*ELASTIC
1000., 0.3
*SOLID SECTION, ELSET=EALL, MATERIAL=EL
*STEP
*STATIC
*BOUNDARY
1, 1, 3, 0.0
2, 1, 1, 0.01
2, 2, 3, 0.0
3, 1, 2, 0.0
3, 3, 3, 0.02
4, 1, 1, -0.01
4, 2, 2, 0.03
4, 3, 3, 0.0
5, 1, 3, 0.015
6, 1, 1, 0.0
6, 2, 2, -0.02
6, 3, 3, 0.005
*EL PRINT, ELSET=EALL
S, E
*EL FILE
S, E
*END STEP
"""

FILE_CARDS = "*EL PRINT, ELSET=EALL\nS, E\n*EL FILE\nS, E\n*NODE FILE\nU\n*END STEP"


ENERGY_KEYS = ", ENER, SDV, ME"


def _deck(case: str) -> str:
    """The deck of ``case``: one (wedge), block (16 wedges), nset (its ``*EL FILE, NSET=TOP``),
    nlgeom, mixed (8 wedges, 4 C3D8), plastic, half-plastic (elastic wedges beside plastic
    C3D8), punch (``wedge_punch.inp``: 12 wedges pressing a C3D8 block); with ``-energy`` the
    ``*EL FILE`` also asks for ENER, SDV and ME (method §41.4), ``one-plastic-energy`` the one
    wedge past yield, ``plastic-nlgeom-energy`` the plastic block under NLGEOM."""
    if case.endswith("-energy"):
        base = case.removesuffix("-energy")
        text = _deck(base.replace("one-plastic", "one").replace("plastic-nlgeom", "plastic"))
        if base == "one-plastic":
            text = text.replace("1000., 0.3\n", "1000., 0.3\n*PLASTIC\n5., 0.\n10., 0.1\n")
        if base == "plastic-nlgeom":
            text = text.replace("*STEP\n", "*STEP, NLGEOM\n")
        head, tail = text.split("*EL FILE\n")
        keys, rest = tail.split("\n", 1)
        return f"{head}*EL FILE\n{keys}{ENERGY_KEYS}\n{rest}"
    if case == "one":
        return ONE_WEDGE
    if case in ("nset", "nlgeom"):
        text = _block(surfaces=False)[0]
        if case == "nlgeom":
            return text.replace("*STEP\n", "*STEP, NLGEOM\n").replace("*END STEP", FILE_CARDS)
        return text.replace("*END STEP", "*EL FILE, NSET=TOP\nS, E\n*END STEP")
    if case == "half-plastic":
        return _half_plastic()
    if case == "punch":
        text = (Path(__file__).parents[1] / "data" / "calculix" / "wedge_punch.inp").read_text()
        cards = "*EL FILE\nS, E\n*NODE FILE\nU\n*CONTACT PRINT"
        return text.replace("*CONTACT PRINT", cards, 1)
    text = _block(surfaces=False, mixed=case in ("mixed", "plastic"))[0]
    if case != "plastic":
        return text.replace("*END STEP", FILE_CARDS)
    text = text.replace("210000., 0.3\n", "210000., 0.3\n*PLASTIC\n300., 0.\n400., 0.1\n")
    text = text.replace("*STATIC\n", "*STATIC\n0.25, 1.\n")
    cards = "*EL PRINT, ELSET=EALL\nS, E, PEEQ\n*EL FILE\nS, E, PE\n*END STEP"
    return text.replace("*END STEP", cards)


def _half_plastic() -> str:
    """The mixed block with plastic C3D8 and elastic wedges, sheared past yield in 4 increments
    (ccx's PE counts the elastic wedges 0 at the nodes they share with the C3D8)."""
    text, wedges = _block(surfaces=False, mixed=True)
    hexahedra = ", ".join(str(len(wedges) + k) for k in range(1, 5))
    wedge_set = ", ".join(str(k) for k in range(1, len(wedges) + 1))
    plastic = (
        f"*ELSET, ELSET=HEX\n{hexahedra}\n*ELSET, ELSET=WED\n{wedge_set}\n"
        "*MATERIAL, NAME=PL\n*ELASTIC\n210000., 0.3\n*PLASTIC\n300., 0.\n400., 0.1\n"
        "*SOLID SECTION, ELSET=HEX, MATERIAL=PL\n*MATERIAL, NAME=EL"
    )
    text = text.replace("*MATERIAL, NAME=EL", plastic)
    text = text.replace("SECTION, ELSET=EALL, MATERIAL=EL", "SECTION, ELSET=WED, MATERIAL=EL")
    text = text.replace("*STATIC\n", "*STATIC\n0.25, 1.\n")
    return text.replace("*END STEP", "*EL FILE\nS, E, PE\n*END STEP")


def _compare_with_ccx(ours: FrdFile, theirs: FrdFile) -> dict[str, float]:
    """Elements and blocks of our file against ccx's (less its ERROR blocks): worst differences.

    Returns the largest difference of each block name relative to its block's largest value.
    """
    np.testing.assert_array_equal(ours.element_ids, theirs.element_ids)
    np.testing.assert_array_equal(ours.element_types, theirs.element_types)  # penta6 = 2
    assert [n.tolist() for n in ours.element_nodes] == [n.tolist() for n in theirs.element_nodes]
    np.testing.assert_array_equal(ours.node_ids, theirs.node_ids)
    blocks = [b for b in theirs.blocks if b.name != "ERROR"]
    assert [(b.name, b.time) for b in ours.blocks] == [(b.name, b.time) for b in blocks]
    worst: dict[str, float] = {}
    for a, b in zip(ours.blocks, blocks):
        np.testing.assert_array_equal(a.nodes, b.nodes)
        assert a.components == b.components
        assert a.values.shape == b.values.shape
        if b.values.size == 0:  # SDV without plastic sections: no components, no values
            continue
        difference = np.abs(a.values - b.values).max() / np.abs(b.values).max()
        worst[a.name] = max(worst.get(a.name, 0.0), float(difference))
    return worst


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize(
    "case", ["one", "block", "nset", "nlgeom", "mixed", "plastic", "half-plastic", "punch"]
)
def test_wedge_frd_against_ccx(tmp_path: Path, case: str) -> None:
    """STRESS, TOSTRAIN and PE of wedges (beside C3D8) are ccx's blocks to their printed digits.

    Measured: the one wedge and PE of the plastic block 0 (every digit), the others within
    5e-6 of the block's largest value (a unit of the last printed digit: the point values differ
    from ccx's in their 7th digit); the elements are ccx's (wedges as frd type 2, six nodes).
    """
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "w", _deck(case))
    theirs, ours = read_frd(ccx_dir / "w.frd"), read_frd(ntf_dir / "w.frd")
    worst = _compare_with_ccx(ours, theirs)
    names = {
        "one": {"STRESS", "TOSTRAIN"},
        "plastic": {"STRESS", "TOSTRAIN", "PE"},
        "half-plastic": {"STRESS", "TOSTRAIN", "PE"},
        "nset": {"STRESS", "TOSTRAIN"},
        "punch": {"DISP", "STRESS", "TOSTRAIN", "FORC", "CONTACT"},
    }
    assert set(worst) == names.get(case, {"DISP", "STRESS", "TOSTRAIN"})
    for name, difference in worst.items():
        assert difference <= 1e-5, (name, difference)
    if case == "one":  # ccx's odd and even nodes: two values, each node's its point's mirror
        stress = theirs.blocks_named("STRESS")[0].values
        np.testing.assert_array_equal(stress[[0, 2, 4]], stress[[0, 0, 0]])
        np.testing.assert_array_equal(stress[[1, 3, 5]], stress[[1, 1, 1]])
        assert np.abs(stress[0] - stress[1]).max() > 0.1 * np.abs(stress).max()
    if case in ("plastic", "half-plastic"):
        assert np.abs(theirs.blocks_named("PE")[-1].values).max() > 1e-3  # the block yielded
    if case == "nset":
        assert theirs.blocks_named("STRESS")[0].nodes.size == 9  # the top's nodes only


ENERGY_CASES = {
    # case: (.frd blocks, the largest difference allowed relative to each block's largest value)
    "one-energy": ({"STRESS", "TOSTRAIN", "MESTRAIN", "ENER", "SDV"}, 1e-9),
    "one-plastic-energy": ({"STRESS", "TOSTRAIN", "MESTRAIN", "ENER", "SDV"}, 1e-9),
    "nlgeom-energy": ({"DISP", "STRESS", "TOSTRAIN", "MESTRAIN", "ENER", "SDV"}, 1e-5),
    "plastic-energy": ({"STRESS", "TOSTRAIN", "MESTRAIN", "PE", "ENER", "SDV"}, 1e-5),
    "plastic-nlgeom-energy": ({"STRESS", "TOSTRAIN", "MESTRAIN", "PE", "ENER", "SDV"}, 1e-5),
    "half-plastic-energy": ({"STRESS", "TOSTRAIN", "MESTRAIN", "PE", "ENER", "SDV"}, 1e-5),
}


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("case", list(ENERGY_CASES))
def test_wedge_energy_state_and_mechanical_strain_frd(tmp_path: Path, case: str) -> None:
    """``*EL FILE`` ENER, SDV and ME of wedges: ccx 2.20 extrapolates them from the two points
    as S and E (method §41.4); ours are its blocks (the one wedge to every printed digit, the
    blocks within a unit of the last printed digit of their values, as S).

    Without ``*PLASTIC`` ccx's ``SDV`` block has no components; with it the wedges yielded.
    """
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "w", _deck(case))
    theirs, ours = read_frd(ccx_dir / "w.frd"), read_frd(ntf_dir / "w.frd")
    worst = _compare_with_ccx(ours, theirs)
    names, tolerance = ENERGY_CASES[case]
    assert set(worst) | {"SDV"} == names, worst
    for name, difference in worst.items():
        assert difference <= tolerance, (name, difference)
    state = theirs.blocks_named("SDV")[-1]
    plastic = "plastic" in case
    assert (state.values.shape[1] == 13) == plastic
    if plastic:
        assert np.abs(state.values[:, 0]).max() > 1e-3  # the equivalent plastic strain
    energy = theirs.blocks_named("ENER")[-1].values
    assert energy.min() > 0.0 and energy.max() > 1.01 * energy.min()


@pytest.mark.serial
def test_wedge_nodal_values_are_the_extrapolated_points(tmp_path: Path) -> None:
    """A lone wedge's ``.frd`` values are ``C3D6_EXTRAPOLATION`` of its printed point values.

    The point values are known to 7 digits, the nodal ones printed to 6: within 2e-6.
    """
    (tmp_path / "w.inp").write_text(ONE_WEDGE)
    assert run_quietly("w", tmp_path).completed
    points = {b.name: b.values for b in read_dat(tmp_path / "w.dat")}
    frd = read_frd(tmp_path / "w.frd")
    assert frd.element_types.tolist() == [2]
    assert frd.element_nodes[0].tolist() == [1, 2, 3, 4, 5, 6]
    for key, name in (("S", "STRESS"), ("E", "TOSTRAIN")):
        block = frd.blocks_named(name)[0]
        np.testing.assert_array_equal(block.nodes, np.arange(1, 7))
        expected = C3D6_EXTRAPOLATION @ points[key][:, [0, 1, 2, 3, 5, 4]]
        scale = np.abs(expected).max()
        assert np.abs(block.values - expected).max() <= 2e-6 * scale, name
        # not the mean of the two points, nor one value through the thickness
        assert np.abs(block.values[0] - points[key].mean(axis=0)[[0, 1, 2, 3, 5, 4]]).max() > (
            1e-2 * scale
        )


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("case", ["block", "punch", "nlgeom-energy", "plastic-energy"])
def test_wedge_frd_on_processes(tmp_path: Path, case: str) -> None:
    """The 16-wedge block's, the wedge punch's and (with ENER, SDV and ME) the NLGEOM block's
    and the plastic mixed block's ``.frd`` on any number of processes: ccx's blocks, and on 2
    processes the serial run's file after its header (every byte)."""
    comm = MPI.COMM_WORLD
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "w", _deck(case), comm=comm)
    if comm.rank == 0:
        worst = _compare_with_ccx(read_frd(ntf_dir / "w.frd"), read_frd(ccx_dir / "w.frd"))
        assert max(worst.values()) <= 1e-5, worst
        serial = ntf_dir.parent / "serial"
        serial.mkdir()
        (serial / "w.inp").write_text(_deck(case))
        assert run_quietly("w", serial).completed

        def body(path: Path) -> list[str]:
            lines = path.read_text().splitlines()
            return lines[next(i for i, line in enumerate(lines) if line.startswith("    2C")) :]

        assert body(ntf_dir / "w.frd") == body(serial / "w.frd")
    comm.barrier()
