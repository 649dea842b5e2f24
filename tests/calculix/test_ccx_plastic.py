"""``*PLASTIC`` in the deck runner against CalculiX 2.20 (docs/method.md §21.6).

A bar of two C3D8 on symmetry rollers pulled past yield, then partly unloaded (U and RF at every
increment), and a plastic block pressed and dragged by an elastic punch with friction
(``friction_cases``' meshes, tight controls: U, CDIS and CSTR), each without NLGEOM (ccx's
small-strain radial return) and with it (Simo's finite-strain law, docs/method.md §21.7). The
refusals (steps mixing NLGEOM and small strain, kinematic hardening) and the reader's
checks of the table are tested without ccx.
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
from helpers.decks import TWO_C3D8

import dolfinx_ntf as ntf
from dolfinx_ntf.calculix.ccx import read_sta, run_ccx
from dolfinx_ntf.calculix.compare import compare_job
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
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

#: The sheet's table of CalculiX's metalforming deck (yield strain 0.01, hardening 166.7).
OUTPUT = OutputSpec(node_print=("U",), contact_print=("CDIS", "CSTR", "CELS", "CNUM"))
SHEET = "*ELASTIC\n5000.0, 0.3\n*PLASTIC\n50.0, 0.0\n100.0, 0.3\n"

BAR = (
    """*HEADING
two C3D8 on symmetry rollers pulled to 5 % strain (yield at 1 %), then back to 4 %
*NODE, NSET=NALL
"""
    + TWO_C3D8
    + """*NSET, NSET=X0
1, 4, 5, 8
*NSET, NSET=Y0
1, 2, 5, 6, 9, 11
*NSET, NSET=Z0
1, 2, 3, 4, 9, 10
*NSET, NSET=END
9, 10, 11, 12
*MATERIAL, NAME=SHEET
{material}*SOLID SECTION, ELSET=EALL, MATERIAL=SHEET
*BOUNDARY
X0, 1, 1
Y0, 2, 2
Z0, 3, 3
*STEP{nlgeom}
*STATIC
0.125, 1.0
*CONTROLS, PARAMETERS=FIELD
1e-10, 1e-08, , , 1e-10, 1e-05, 1e-08, 1e-12
*BOUNDARY
END, 1, 1, 0.1
*NODE PRINT, NSET=NALL
U, RF
*EL PRINT, ELSET=EALL
S
*END STEP
*STEP{nlgeom}
*STATIC
0.25, 1.0
*CONTROLS, PARAMETERS=FIELD
1e-10, 1e-08, , , 1e-10, 1e-05, 1e-08, 1e-12
*BOUNDARY
END, 1, 1, 0.08
*NODE PRINT, NSET=NALL
U, RF
*EL PRINT, ELSET=EALL
S
*END STEP
"""
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
    text = BAR.format(material=SHEET, nlgeom="")
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
    text = BAR.format(material=SHEET, nlgeom=", NLGEOM")
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
    text = BAR.format(material=SHEET, nlgeom="")
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
    text = BAR.format(material="*ELASTIC\n5000.0, 0.3\n" + table, nlgeom="")
    path = tmp_path / "deck.inp"
    path.write_text(text)
    with pytest.raises(DeckError, match=what) as info:
        read_deck(path)
    assert "deck.inp:" in str(info.value)


def test_reader_keeps_the_table(tmp_path: Path) -> None:
    path = tmp_path / "deck.inp"
    path.write_text(BAR.format(material=SHEET, nlgeom=""))
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
    text = BAR.format(material=SHEET, nlgeom=nlgeom)
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
