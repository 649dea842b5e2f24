"""``*PLASTIC`` in the deck runner against CalculiX 2.20 (docs/method.md §21.6).

A bar of two C3D8 on symmetry rollers pulled past yield, then partly unloaded (U and RF at every
increment), and a plastic block pressed and dragged by an elastic punch with friction
(``friction_cases``' meshes, tight controls: U, CDIS and CSTR), each without NLGEOM (ccx's
small-strain radial return) and with it (Simo's finite-strain law, docs/method.md §21.7). The
refusals (steps mixing NLGEOM and small strain, kinematic hardening) and the reader's
checks of the table are tested without ccx. PEEQ and E (``*EL PRINT``, ``*EL FILE``) of a plastic
C3D8 beside an elastic one and of the punch deck against ccx's ``.dat`` and ``.frd`` files
(docs/method.md §21.6).
"""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from cases import BOTTOM, PUNCH, TOP, blocks, facet_tag
from helpers.ccx_runs import quiet_logs, run_quietly
from helpers.decks import SHEET_ELASTIC, SHEET_PLASTIC, mixed_sections, pulled_bar

import dolfinx_ntf as ntf
from dolfinx_ntf.calculix.ccx import read_sta, run_ccx
from dolfinx_ntf.calculix.compare import compare_job
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.frd import read_frd
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.writer import (
    TIGHT_FIELD_CONTROLS,
    BoundarySpec,
    OutputSpec,
    PressureSpec,
    StepSpec,
    write_inp,
)

needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")

OUTPUT = OutputSpec(node_print=("U",), contact_print=("CDIS", "CSTR", "CELS", "CNUM"))
#: The sheet's table of CalculiX's metalforming deck (yield strain 0.01, hardening 166.7).
SHEET = SHEET_ELASTIC + SHEET_PLASTIC

HEADING = "two C3D8 on symmetry rollers pulled to 5 % strain (yield at 1 %), then back to 4 %"


def _bar(material: str, nlgeom: str = "") -> str:
    """Two C3D8 of ``material`` on symmetry rollers pulled to 5 % strain, then back to 4 %."""
    return pulled_bar(
        f"*MATERIAL, NAME=SHEET\n{material}*SOLID SECTION, ELSET=EALL, MATERIAL=SHEET\n",
        "*NODE PRINT, NSET=NALL\nU, RF\n*EL PRINT, ELSET=EALL\nS\n",
        nlgeom,
        heading=HEADING,
    )


def _both(text: str, name: str, tmp_path: Path, **options):
    """Write ``text`` as deck ``name``, run it by ccx and by the runner; both directories."""
    ccx_dir, ntf_dir = tmp_path / "ccx", tmp_path / "ntf"
    for d in (ccx_dir, ntf_dir):
        d.mkdir()
        (d / f"{name}.inp").write_text(text)
    run_ccx(ccx_dir, name, timeout=300)
    result = run_quietly(name, ntf_dir, **options)
    assert result.completed
    return ccx_dir, ntf_dir, result


def _largest_difference(ccx_dat: Path, ntf_dat: Path, name: str) -> tuple[float, int]:
    """Largest difference of block ``name`` over every increment, relative to its largest value."""
    ours = [b for b in read_dat(ntf_dat) if b.name == name]
    theirs = [b for b in read_dat(ccx_dat) if b.name == name]
    assert len(ours) == len(theirs) > 0
    worst = 0.0
    for a, b in zip(ours, theirs):
        assert a.time == pytest.approx(b.time, abs=1e-12)
        np.testing.assert_array_equal(a.labels, b.labels)
        scale = np.abs(b.values).max()
        worst = max(worst, np.abs(a.values - b.values).max() / scale)
    return worst, len(ours)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
def test_plastic_bar_agrees_with_ccx(tmp_path: Path) -> None:
    """Small strain: U, RF and S of every increment at 1e-6 (ccx prints 7 digits); it yields."""
    text = _bar(SHEET, "")
    ccx_dir, ntf_dir, result = _both(text, "bar", tmp_path, tight=True)
    for block in ("U", "RF", "S"):
        worst, count = _largest_difference(ccx_dir / "bar.dat", ntf_dir / "bar.dat", block)
        assert count > 2  # ccx's increments (the same times): not one linear increment per step
        assert worst < 1e-6, (block, worst)
    forces = [b for b in read_dat(ntf_dir / "bar.dat") if b.name == "RF"]
    loaded = next(b for b in forces if b.time == pytest.approx(1.0))  # the end of step 1
    end = np.isin(loaded.labels, [9, 10, 11, 12])
    # 5 % strain: 50 + E H / (E + H) (0.05 - 0.01) on the unit section (four nodes' RF)
    hardening = 50.0 / 0.3
    expected = 50.0 + 5000.0 * hardening / (5000.0 + hardening) * 0.04
    assert loaded.values[end, 0].sum() == pytest.approx(expected, rel=1e-6)
    # unloaded elastically by 1 % strain: E 0.01 less, the plastic strain stays
    assert forces[-1].values[end, 0].sum() == pytest.approx(expected - 50.0, rel=1e-6)
    law = result.model.plasticity[0]
    assert np.all(law.equivalent_plastic_strain > 0.03)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
def test_plastic_bar_agrees_with_ccx_under_nlgeom(tmp_path: Path) -> None:
    """NLGEOM (Simo's finite-strain law): U, RF, S of every increment at 1e-6; the end force is
    not the small-strain one (the cross-section shrinks), the law is the finite-strain one."""
    text = _bar(SHEET, ", NLGEOM")
    ccx_dir, ntf_dir, result = _both(text, "bar", tmp_path, tight=True)
    for block in ("U", "RF", "S"):
        worst, count = _largest_difference(ccx_dir / "bar.dat", ntf_dir / "bar.dat", block)
        assert count > 2
        assert worst < 1e-6, (block, worst)
    assert type(result.model.plasticity[0]).__name__ == "FiniteStrainJ2Plasticity"
    forces = [b for b in read_dat(ntf_dir / "bar.dat") if b.name == "RF"]
    loaded = next(b for b in forces if b.time == pytest.approx(1.0))
    end = np.isin(loaded.labels, [9, 10, 11, 12])
    hardening = 50.0 / 0.3
    small = 50.0 + 5000.0 * hardening / (5000.0 + hardening) * 0.04
    assert abs(loaded.values[end, 0].sum() - small) > 1e-3 * small


def _punch_deck(directory: Path, nlgeom: bool = False) -> None:
    """The block of ``friction_cases`` made of the sheet metal, pressed and dragged by a punch."""
    V, ct, ft = blocks([((0.0, 0.0, -0.5), (1.0, 1.0, 0.5), (4, 4, 2)), PUNCH])
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, facet_tag(1, BOTTOM)),
        ntf.FacetSurface(ft, facet_tag(0, TOP)),
        ntf.SurfaceInteraction(
            ntf.LinearLaw(slope=50 * 5000.0, tension=5000.0 / 70000.0, c0=1e-3),
            ntf.Friction(0.3, 2500.0),
        ),
    )
    top = ntf.FacetSurface(ft, facet_tag(1, TOP))

    def step(increments: int, **kwargs) -> StepSpec:
        return StepSpec(increments=increments, field_controls=TIGHT_FIELD_CONTROLS,
                        output=OUTPUT, **kwargs)  # fmt: skip

    steps = [
        step(4, boundaries=[BoundarySpec(top, (0, 1), 0.0, name="TOP")],
             pressures=[PressureSpec(top, 120.0)]),
        step(3, boundaries=[BoundarySpec(top, (0,), 2e-3, name="DRAG")]),
    ]  # fmt: skip
    path = directory / "plastic_punch.inp"
    write_inp(
        path,
        displacement_space=V,
        materials={1: (5000.0, 0.3), 2: (210000.0, 0.3)},
        cell_tags=ct,
        pairs=[pair],
        fixed=[BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE")],
        steps=steps,
        heading="elastic C3D8 punch pressed (120) into a plastic block, then dragged (mu 0.3)",
    )
    text = path.read_text()
    elastic = "*MATERIAL, NAME=M_E1\n*ELASTIC\n"
    start = text.index(elastic)
    line_end = text.index("\n", start + len(elastic)) + 1
    text = text[:line_end] + "*PLASTIC\n50.0, 0.0\n100.0, 0.3\n" + text[line_end:]
    if nlgeom:
        text = text.replace("*STEP, NLGEOM=NO", "*STEP, NLGEOM")
    path.write_text(text)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("nlgeom", [False, True], ids=["small", "nlgeom"])
def test_plastic_block_under_punch_agrees_with_ccx(nlgeom: bool, tmp_path: Path) -> None:
    """U, CDIS and CSTR of every increment, pressed and dragged; points yield."""
    ccx_dir, ntf_dir = tmp_path / "ccx", tmp_path / "ntf"
    for d in (ccx_dir, ntf_dir):
        d.mkdir()
        _punch_deck(d, nlgeom)
    assert ("NLGEOM=NO" in (ccx_dir / "plastic_punch.inp").read_text()) != nlgeom
    run_ccx(ccx_dir, "plastic_punch", timeout=300)
    result = run_quietly("plastic_punch", ntf_dir, tight=True)
    assert result.completed
    comparison = compare_job(
        ccx_dir / "plastic_punch.dat", result, read_sta(ccx_dir / "plastic_punch.sta")
    )
    why = comparison.summary()
    assert comparison.same_increments and comparison.same_contact_elements, why
    assert comparison.relative_displacement <= 1e-6, why
    assert comparison.relative_pressure <= 1e-5, why
    assert comparison.relative_clearance <= 1e-5, why
    assert comparison.relative_slip <= 1e-5 and comparison.relative_shear <= 1e-5, why
    law = result.model.plasticity[0]
    assert law.equivalent_plastic_strain.max() > 1e-3  # the block yields under the punch
    assert np.any(law.equivalent_plastic_strain == 0.0)  # and stays elastic elsewhere


# -- refusals and the reader (no ccx) -------------------------------------------------------------


def _refusal(text: str, tmp_path: Path) -> str:
    (tmp_path / "deck.inp").write_text(text)
    with pytest.raises(NotImplementedError) as info:
        run_quietly("deck", tmp_path)
    return str(info.value)


@pytest.mark.serial
def test_mixed_nlgeom_with_plastic_is_refused(tmp_path: Path) -> None:
    text = _bar(SHEET, "")
    first = text.index("*STEP")
    second = text.index("*STEP", first + 1)
    text = text[:second] + "*STEP, NLGEOM" + text[second + len("*STEP") :]
    line = text.splitlines().index("*STEP, NLGEOM") + 1
    message = _refusal(text, tmp_path)
    assert f"deck.inp:{line}:" in message and "mixes NLGEOM" in message


@pytest.mark.parametrize(
    ("table", "what"),
    [
        ("*PLASTIC, HARDENING=KINEMATIC\n50.0, 0.0\n", "HARDENING=KINEMATIC is not supported"),
        ("*PLASTIC\n50.0, 0.1\n", "must be 0"),
        ("*PLASTIC\n50.0, 0.0\n60.0, 0.2\n70.0, 0.1\n", "must increase"),
        ("*PLASTIC\n-50.0, 0.0\n", "yield stress > 0"),
        ("*PLASTIC\n50.0, 0.0, 20.0\n40.0, 0.0, 100.0\n", "temperature-dependent"),
        ("*PLASTIC\n", "needs a data line"),
    ],
)
def test_bad_plastic_tables_are_refused(table: str, what: str, tmp_path: Path) -> None:
    text = _bar("*ELASTIC\n5000.0, 0.3\n" + table, "")
    path = tmp_path / "deck.inp"
    path.write_text(text)
    with pytest.raises(DeckError, match=what) as info:
        read_deck(path)
    assert "deck.inp:" in str(info.value)


def test_reader_keeps_the_table(tmp_path: Path) -> None:
    path = tmp_path / "deck.inp"
    path.write_text(_bar(SHEET, ""))
    material = read_deck(path).materials["SHEET"]
    assert material.plastic == ((50.0, 0.0), (100.0, 0.3))
    assert material.elastic == (5000.0, 0.3)


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("nlgeom", ["", ", NLGEOM"], ids=["small", "nlgeom"])
def test_plastic_bar_on_all_processes(nlgeom: str, tmp_path: Path) -> None:
    """The bar on 1 or 2 processes (one element each): the .dat blocks ccx prints, U and RF of
    every increment, within 1e-6 of the block's largest value (rank 0 compares)."""
    comm = MPI.COMM_WORLD
    root = Path(comm.bcast(str(tmp_path), root=0))
    text = _bar(SHEET, nlgeom)
    ccx_dir, ntf_dir = root / "ccx", root / "ntf"
    if comm.rank == 0:
        for d in (ccx_dir, ntf_dir):
            d.mkdir()
            (d / "bar.inp").write_text(text)
        run_ccx(ccx_dir, "bar", timeout=300)
    comm.barrier()
    with quiet_logs(logging.ERROR):
        result = run_job("bar", ntf_dir, comm=comm, progress=False, tight=True)
    assert result.completed
    yielded = comm.allreduce(
        float(result.model.plasticity[0].equivalent_plastic_strain.max(initial=0.0)), op=MPI.MAX
    )
    assert yielded > 0.03
    if comm.rank == 0:
        ours, theirs = read_dat(ntf_dir / "bar.dat"), read_dat(ccx_dir / "bar.dat")
        assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
        for a, b in zip(ours, theirs):
            np.testing.assert_array_equal(a.labels, b.labels)
            assert np.abs(a.values - b.values).max() <= 1e-6 * np.abs(b.values).max(), a.name


# -- PEEQ (docs/method.md §21.6) ------------------------------------------------------------------

#: Element 1 of the bar plastic, element 2 elastic (ccx prints PEEQ 0 there); S, E and PEEQ
#: printed, U, RF, S, E and PEEQ (by its other name PE, as ccx's test deck beampiso2) written to
#: the .frd.


def _mixed_bar(nlgeom: str) -> str:
    return pulled_bar(
        mixed_sections(),
        "*NODE PRINT, NSET=NALL\nU, RF\n*EL PRINT, ELSET=EALL\nS, E, PEEQ\n*NODE FILE\nU, RF\n"
        "*EL FILE\nS, E, PE\n",
        nlgeom,
        heading=HEADING,
    )


#: Requests added to the punch deck's steps: E and PEEQ printed and written beside the others.
PEEQ_REQUESTS = (
    "*EL PRINT, ELSET=EALL\nS, E, PEEQ\n*NODE FILE\nU, RF\n*EL FILE\nS, E, PEEQ\n"
    "*CONTACT FILE\nCDIS, CSTR\n*END STEP"
)


def _peeq_text(path: Path) -> list[list[str]]:
    """The lines (title, then rows) of every PEEQ block of a ``.dat`` file."""
    blocks: list[list[str]] = []
    for line in path.read_text().splitlines():
        if "equivalent plastic strain" in line:
            blocks.append([line])
        elif blocks and line.strip() and "time" in line:
            blocks.append([])  # another block: closes the PEEQ block
        elif blocks and line.strip() and blocks[-1]:
            blocks[-1].append(line)
    return [b for b in blocks if b]


def _check_peeq(ccx_dir: Path, ntf_dir: Path, name: str) -> float:
    """PEEQ of the ``.dat`` and ``.frd`` files against ccx's; the largest PEEQ printed.

    Titles byte for byte, rows byte for byte where the printed values agree (and at least half
    of them do), the others within 1e-6 of the strains' scale (the largest PEEQ plus the sheet's
    yield strain 0.01: a stress known to 1e-6 gives the plastic strain to 1e-6 of the strain);
    the ``.frd`` blocks in ccx's order (less ccx's ERROR estimate, not written) and ``PE``
    within its 5 digits.
    """
    ours, theirs = _peeq_text(ntf_dir / f"{name}.dat"), _peeq_text(ccx_dir / f"{name}.dat")
    assert len(ours) == len(theirs) > 2
    same = total = 0
    for a, b in zip(ours, theirs):
        assert a[0] == b[0]  # the title: set and time
        assert len(a) == len(b)
        for row_a, row_b in zip(a[1:], b[1:]):
            ra, rb = row_a.split(), row_b.split()
            assert ra[:2] == rb[:2]  # element, point
            total += 1
            if float(ra[2]) == float(rb[2]):
                same += 1
                assert row_a == row_b
    assert same >= total / 2, (same, total)
    blocks = [b for b in read_dat(ntf_dir / f"{name}.dat") if b.name == "PEEQ"]
    references = [b for b in read_dat(ccx_dir / f"{name}.dat") if b.name == "PEEQ"]
    largest = max(np.abs(b.values).max() for b in references)
    for a, b in zip(blocks, references):
        assert a.set == b.set == "EALL"
        np.testing.assert_array_equal(a.labels, b.labels)
        assert np.abs(a.values - b.values).max() <= 1e-6 * (largest + 0.01)
    frd, reference = read_frd(ntf_dir / f"{name}.frd"), read_frd(ccx_dir / f"{name}.frd")
    assert [b.name for b in frd.blocks] == [b.name for b in reference.blocks if b.name != "ERROR"]
    nodal = reference.blocks_named("PE")
    assert len(nodal) == len(blocks)
    top = max(np.abs(b.values).max() for b in nodal)
    for a, b in zip(frd.blocks_named("PE"), nodal):
        assert a.components == b.components == ("PE",)
        np.testing.assert_array_equal(a.nodes, b.nodes)
        assert np.abs(a.values - b.values).max() <= 2e-5 * top
    return largest


def _check_strains(ccx_dir: Path, ntf_dir: Path, name: str) -> None:
    """E of the ``.dat`` (within 1e-6 of the largest strain, titles byte for byte) and the
    ``.frd`` (``TOSTRAIN`` within its 5 digits) against ccx's (small strain, or Green-Lagrange
    under NLGEOM; tensor shears)."""
    ours = [b for b in read_dat(ntf_dir / f"{name}.dat") if b.name == "E"]
    theirs = [b for b in read_dat(ccx_dir / f"{name}.dat") if b.name == "E"]
    assert len(ours) == len(theirs) > 2
    largest = max(np.abs(b.values).max() for b in theirs)
    for a, b in zip(ours, theirs):
        assert (a.set, a.time) == (b.set, b.time)
        np.testing.assert_array_equal(a.labels, b.labels)
        assert np.abs(a.values - b.values).max() <= 1e-6 * largest
    titles = [
        [line for line in (d / f"{name}.dat").read_text().splitlines() if " strains (" in line]
        for d in (ntf_dir, ccx_dir)
    ]
    assert titles[0] == titles[1]
    nodal = read_frd(ccx_dir / f"{name}.frd").blocks_named("TOSTRAIN")
    top = max(np.abs(b.values).max() for b in nodal)
    ours_nodal = read_frd(ntf_dir / f"{name}.frd").blocks_named("TOSTRAIN")
    assert len(ours_nodal) == len(nodal) == len(ours)
    for a, b in zip(ours_nodal, nodal):
        assert a.components == b.components == ("EXX", "EYY", "EZZ", "EXY", "EYZ", "EZX")
        np.testing.assert_array_equal(a.nodes, b.nodes)
        assert np.abs(a.values - b.values).max() <= 2e-5 * top


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("nlgeom", ["", ", NLGEOM"], ids=["small", "nlgeom"])
def test_peeq_of_bar_agrees_with_ccx(nlgeom: str, tmp_path: Path) -> None:
    """``*EL PRINT PEEQ, E`` and ``*EL FILE PE, E`` of a plastic C3D8 beside an elastic one."""
    text = _mixed_bar(nlgeom)
    ccx_dir, ntf_dir, result = _both(text, "bar", tmp_path, tight=True)
    largest = _check_peeq(ccx_dir, ntf_dir, "bar")
    _check_strains(ccx_dir, ntf_dir, "bar")
    assert largest > 0.03  # element 1 yields
    last = [b for b in read_dat(ntf_dir / "bar.dat") if b.name == "PEEQ"][-1]
    assert np.all(last.values[last.labels[:, 0] == 2] == 0.0)  # the elastic element
    law = result.model.plasticity[0]
    printed = np.sort(last.values[last.labels[:, 0] == 1, 0])
    committed = np.sort(law.equivalent_plastic_strain)
    assert np.allclose(printed, committed, rtol=1e-6, atol=0.0)  # what the law committed


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("nlgeom", [False, True], ids=["small", "nlgeom"])
def test_peeq_of_block_under_punch_agrees_with_ccx(nlgeom: bool, tmp_path: Path) -> None:
    """PEEQ and E of the plastic block pressed and dragged by the punch (.dat, .frd)."""
    ccx_dir, ntf_dir = tmp_path / "ccx", tmp_path / "ntf"
    for d in (ccx_dir, ntf_dir):
        d.mkdir()
        _punch_deck(d, nlgeom)
        path = d / "plastic_punch.inp"
        path.write_text(path.read_text().replace("*END STEP", PEEQ_REQUESTS))
    run_ccx(ccx_dir, "plastic_punch", timeout=300)
    result = run_quietly("plastic_punch", ntf_dir, tight=True)
    assert result.completed
    assert _check_peeq(ccx_dir, ntf_dir, "plastic_punch") > 1e-3
    _check_strains(ccx_dir, ntf_dir, "plastic_punch")


def test_peeq_requests_are_read(tmp_path: Path) -> None:
    """PE is PEEQ in ``*EL PRINT`` and ``*EL FILE``; keys not built (ZZS) are still refused."""
    path = tmp_path / "deck.inp"
    path.write_text(_mixed_bar("").replace("S, E, PEEQ\n", "S, PE\n"))
    step = read_deck(path).steps[0]
    assert [r.keys for r in step.prints if r.kind == "EL"] == [("S", "PEEQ")]
    assert [r.keys for r in step.file_requests if r.kind == "EL"] == [("S", "E", "PEEQ")]
    path.write_text(_mixed_bar("").replace("S, E, PEEQ\n", "S, ZZS\n"))
    with pytest.raises(DeckError, match="key ZZS is not supported yet"):
        read_deck(path)


@pytest.mark.serial
def test_strains_of_c3d8i_are_refused(tmp_path: Path) -> None:
    """E of C3D8I (its condensed modes' strains were not measured against ccx): refused."""
    text = _mixed_bar("").replace(SHEET_PLASTIC, "")
    text = text.replace("TYPE=C3D8,", "TYPE=C3D8I,")
    line = text.splitlines().index("*EL PRINT, ELSET=EALL") + 1
    message = _refusal(text, tmp_path)
    assert f"deck.inp:{line}: *EL PRINT E (strains)" in message and "C3D8I" in message


@pytest.mark.serial
def test_no_peeq_block_without_plastic_sections(tmp_path: Path) -> None:
    """ccx 2.20 prints and writes no PEEQ when no section is plastic (measured): nor do we."""
    text = _mixed_bar("").replace(SHEET_PLASTIC, "")
    (tmp_path / "bar.inp").write_text(text)
    result = run_quietly("bar", tmp_path)
    assert result.completed and not result.model.plasticity
    names = {b.name for b in read_dat(tmp_path / "bar.dat")}
    assert "S" in names and "PEEQ" not in names
    frd = {b.name for b in read_frd(tmp_path / "bar.frd").blocks}
    assert "STRESS" in frd and "PE" not in frd


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
def test_peeq_on_all_processes(tmp_path: Path) -> None:
    """The mixed bar under NLGEOM on 1 or 2 processes (the plastic and the elastic element on
    different ones): PEEQ and E in the .dat and .frd files as ccx's (rank 0 compares)."""
    comm = MPI.COMM_WORLD
    root = Path(comm.bcast(str(tmp_path), root=0))
    ccx_dir, ntf_dir = root / "ccx", root / "ntf"
    if comm.rank == 0:
        for d in (ccx_dir, ntf_dir):
            d.mkdir()
            (d / "bar.inp").write_text(_mixed_bar(", NLGEOM"))
        run_ccx(ccx_dir, "bar", timeout=300)
    comm.barrier()
    logger = logging.getLogger("dolfinx_ntf")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        result = run_job("bar", ntf_dir, comm=comm, progress=False, tight=True)
    finally:
        logger.setLevel(level)
    assert result.completed
    if comm.rank == 0:
        assert _check_peeq(ccx_dir, ntf_dir, "bar") > 0.03
        _check_strains(ccx_dir, ntf_dir, "bar")
