"""Cross-validation against CalculiX 2.20: ccx and dolfinx_ntf run the same generated decks.

The decks (``tests/data/calculix/crossval/cases.py``) are small contact problems built with dolfinx
and exported by ``write_inp`` with ``*CONTROLS, PARAMETERS=FIELD`` tightened, so that ccx converges
to round-off like ``run_job(..., tight=True)``. Per converged increment the test asserts:

    - the same increments (times) and the same contact elements (slave nodes);
    - displacements within 1e-6 of the largest displacement of the increment;
    - contact pressure (CSTR) within 1e-5 of the largest pressure, and the spring energy (CELS)
      within 1e-5 of the largest energy;
    - clearance (CDIS) within 1e-5 of the largest |clearance|. The clearance of a closed spring is
      its penetration p/K, set by the law like the pressure, so the same relative bound applies;
      absolute differences are about 1e-9 here, at the level of the displacement differences.

ccx prints 7 significant digits, so displacements cannot agree better than about 5e-7 of the
largest one. The remaining differences are ccx's: its converged increment keeps quantities from
the iterate before its last Newton correction (the spring areas of the last pairing, docs/method.md
§3.1 and §6.3; NLGEOM follower pressures), see ``docs/validation.md``. A case whose tolerance had to
be relaxed says which quirk and why (``Case.quirk``).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import cases
import numpy as np
import pytest
from helpers.ccx_runs import quiet_logs

from dolfinx_ntf.calculix.ccx import read_sta, run_ccx
from dolfinx_ntf.calculix.compare import (
    IncrementResults,
    ccx_increments,
    compare_increments,
    compare_job,
)
from dolfinx_ntf.calculix.dat import contact_print_blocks, node_print_blocks, write_dat
from dolfinx_ntf.calculix.deck import node_surface_faces, read_deck
from dolfinx_ntf.calculix.job import run_job

pytestmark = pytest.mark.serial

needs_ccx = [
    pytest.mark.ccx,
    pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed"),
]

#: Default tolerances, relative to the largest value of the increment (see the module docstring).
TOLERANCES = {"displacement": 1e-6, "pressure": 1e-5, "clearance": 1e-5, "energy": 1e-5}


def _run_both(case: cases.Case, tmp_path: Path):
    """Write the deck, run ccx in ``ccx/`` and dolfinx_ntf in ``ntf/``; returns the comparison."""
    ccx_dir, ntf_dir = tmp_path / "ccx", tmp_path / "ntf"
    ccx_dir.mkdir()
    case.write(ccx_dir)
    ntf_dir.mkdir()
    shutil.copy(ccx_dir / f"{case.name}.inp", ntf_dir)
    run_ccx(ccx_dir, case.name, timeout=120)
    with quiet_logs():
        result = run_job(case.name, ntf_dir, comm=MPI.COMM_SELF, tight=True)
    assert result.completed
    comparison = compare_job(
        ccx_dir / f"{case.name}.dat", result, read_sta(ccx_dir / f"{case.name}.sta")
    )
    return comparison, ccx_dir, ntf_dir


@pytest.mark.parametrize("case", cases.CASES, ids=[c.name for c in cases.CASES])
@needs_ccx[0]
@needs_ccx[1]
def test_ccx_and_dolfinx_ntf_agree(case: cases.Case, tmp_path: Path):
    """Same increments, contact elements, displacements, pressures, clearances and energies."""
    comparison, ccx_dir, ntf_dir = _run_both(case, tmp_path)
    why = f"{case.name}: {comparison.summary()}"

    assert comparison.same_increments, why
    assert len(comparison.increments) >= 2, why
    assert comparison.same_contact_elements, why
    assert any(c.ccx_contact.size for c in comparison.increments), f"{case.name}: no contact at all"
    for c in comparison.increments:
        assert c.missing_nodes.size == 0, why
        assert c.ccx_iterations is not None and c.ntf_iterations is not None

    tolerances = {**TOLERANCES, **case.tolerances}
    assert comparison.relative_displacement <= tolerances["displacement"], why
    assert comparison.relative_pressure <= tolerances["pressure"], why
    assert comparison.relative_clearance <= tolerances["clearance"], why
    assert comparison.relative_energy <= tolerances["energy"], why

    if case.quirk == cases.NLGEOM_PRESSURE_QUIRK:
        # The relaxed tolerance is ccx's: dolfinx_ntf's reactions balance the follower pressure on
        # its final faces to the printed digits, ccx's do not.
        deck = ccx_dir / f"{case.name}.inp"
        ccx_balance = cases.pressure_balance(deck, ccx_dir / f"{case.name}.dat")
        ntf_balance = cases.pressure_balance(deck, ntf_dir / f"{case.name}.dat")
        assert max(abs(b) for _, b in ntf_balance) < 1e-7, ntf_balance
        assert max(abs(b) for _, b in ccx_balance) > 5e-7, ccx_balance


@pytest.mark.parametrize("name", ["hex20_nodal", "hex20_cylinder"])
@needs_ccx[0]
@needs_ccx[1]
def test_c3d20_decks_take_ccx_iterations(name: str, tmp_path: Path):
    """At the deck's controls the deck runner takes ccx's Newton iterations on these C3D20 decks.

    They start with a slave node on its master face and press by a prescribed displacement: before
    the midside nodes kept the deck's coordinates and the centres moved with the prescribed nodes
    in the first iteration (docs/method.md §13.1, §13.5), they took 5, 2 and 3, 4, 3 (ccx 3, 2 and
    3, 3, 3).
    """
    (case,) = [c for c in cases.CASES if c.name == name]
    case.write(tmp_path)
    run_ccx(tmp_path, name, timeout=120)
    ccx = [i.iterations for i in read_sta(tmp_path / f"{name}.sta")]
    with quiet_logs():
        result = run_job(name, tmp_path, comm=MPI.COMM_SELF)
    assert result.completed
    assert [i.iterations for i in result.increments] == ccx


def test_cases_cover_the_required_features(tmp_path: Path):
    """The deck set covers what the cross-validation promises (issue 3, section 4)."""
    element_types, laws, slave_types = set(), set(), set()
    nlgeom, pair_counts, increments, curved = set(), set(), [], False
    for case in cases.CASES:
        case.write(tmp_path)
        deck = read_deck(tmp_path / f"{case.name}.inp")
        element_types |= set(deck.elements)
        pair_counts.add(len(deck.contact_pairs))
        for pair in deck.contact_pairs:
            laws.add(deck.interactions[pair.interaction].behavior.pressure_overclosure)
            slave_types.add(deck.surfaces[pair.slave].type)
            faces = node_surface_faces(deck, pair.master)
            x = deck.node_coords[deck.node_index(faces[:, :3])]
            normal = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
            normal /= np.linalg.norm(normal, axis=1)[:, None]
            curved |= bool(np.ptp(normal, axis=0).max() > 1e-3)
        for step in deck.steps:
            nlgeom.add(step.nlgeom)
            increments.append(round(step.static.period / step.static.initial_increment))
            assert step.field_controls()["R_n"] <= 1e-10, f"{case.name}: ccx tolerances not tight"
    assert {"C3D4", "C3D8"} <= element_types
    assert {"EXPONENTIAL", "LINEAR", "TABULAR"} <= laws
    assert nlgeom == {True, False}
    assert max(increments) >= 3
    assert slave_types == {"ELEMENT", "NODE"}
    assert max(pair_counts) >= 2
    assert curved
    assert len(cases.CASES) >= 6


# ----------------------------------------------------------------------------- compare.py alone


def _increment(time, u, contact, clearance, pressure, energy=None, iterations=None):
    ids = np.arange(1, len(u) + 1)
    energy = None if energy is None else np.asarray(energy, float)
    return IncrementResults(time, ids, np.asarray(u, float), np.asarray(contact),
                            np.asarray(clearance, float), np.asarray(pressure, float), energy,
                            iterations)  # fmt: skip


def test_compare_increments_differences_and_scales():
    u = [[0.0, 0.0, -1.0], [0.1, 0.0, -2.0], [0.0, 0.0, 0.0]]
    ccx = [_increment(0.5, u, [3, 1], [-1e-4, 2e-4], [10.0, -0.5], [1.0, 2.0], 3),
           _increment(1.0, u, [3, 1], [-1e-4, 2e-4], [10.0, -0.5], [1.0, 2.0], 2)]  # fmt: skip
    u2 = np.array(u)
    u2[1, 2] += 4e-6
    ntf = [_increment(0.5, u2, [1, 3], [2e-4, -1e-4 + 3e-9], [-0.5, 10.0 - 2e-4], [2.0, 1.0], 5),
           _increment(1.0 + 1e-9, u, [3], [-1e-4], [10.0], [1.0], 4)]  # fmt: skip
    result = compare_increments(ccx, ntf)
    assert result.same_increments and len(result.increments) == 2
    first, second = result.increments
    # contact rows are matched by slave node, not by row order
    assert first.same_contact_elements
    assert first.relative_displacement == pytest.approx(4e-6 / 2.0)
    assert first.relative_pressure == pytest.approx(2e-4 / 10.0)
    assert first.relative_clearance == pytest.approx(3e-9 / 2e-4)
    assert first.relative_energy == 0.0
    assert (first.ccx_iterations, first.ntf_iterations) == (3, 5)
    assert not second.same_contact_elements and not result.same_contact_elements
    assert result.contact_differences() == [
        "time 1: ccx only [1], dolfinx_ntf only [] (2 vs 1 elements)"
    ]
    assert result.relative_displacement == pytest.approx(2e-6)
    assert "ccx only [1]" in result.summary()


def test_compare_increments_unmatched_times_and_repeated_slaves():
    u = [[0.0, 0.0, 1.0]]
    ccx = [
        _increment(0.5, u, [1], [0.0], [1.0]),
        _increment(1.0, u, [1, 1], [0.0, 0.0], [1.0, 3.0]),
    ]
    ntf = [
        _increment(1.0, u, [1, 1], [0.0, 0.0], [1.0, 3.0]),
        _increment(1.5, u, [1], [0.0], [1.0]),
    ]
    result = compare_increments(ccx, ntf)
    assert result.ccx_only == (0.5,) and result.ntf_only == (1.5,) and not result.same_increments
    (common,) = result.increments
    assert common.relative_pressure == 0.0  # a node in two pairs: rows matched in order
    assert np.isnan(common.energy) and result.relative_energy == 0.0


def test_ccx_increments_reads_dat_blocks(tmp_path: Path):
    blocks = []
    for time, scale in ((0.5, 1.0), (1.0, 2.0)):
        blocks += node_print_blocks(
            "U", "NALL", time, [2, 1], scale * np.array([[0, 0, 1], [0, 0, 2]])
        )
        blocks += contact_print_blocks("CDIS", time, [5, 4], [[-1e-4, 0, 0], [2e-4, 0, 0]])
        blocks += contact_print_blocks("CSTR", time, [5, 4], [[3.0, 0, 0], [-0.1, 0, 0]])
        blocks += contact_print_blocks("CELS", time, [5, 4], [1e-3, 2e-3])
        blocks += contact_print_blocks("CNUM", time, [5, 4])
    write_dat(tmp_path / "job.dat", blocks)
    first, second = ccx_increments(tmp_path / "job.dat")
    np.testing.assert_array_equal(second.node_ids, [1, 2])
    np.testing.assert_allclose(second.displacements, [[0, 0, 4], [0, 0, 2]])
    np.testing.assert_array_equal(first.contact_nodes, [5, 4])
    np.testing.assert_allclose(first.clearance, [-1e-4, 2e-4])
    np.testing.assert_allclose(first.pressure, [3.0, -0.1])
    np.testing.assert_allclose(first.energy, [1e-3, 2e-3])
    assert first.time == 0.5 and first.iterations is None
    write_dat(tmp_path / "bad.dat", [b for b in blocks if b.name != "CSTR"])
    with pytest.raises(ValueError, match=r"no CSTR block at time 0\.5"):
        ccx_increments(tmp_path / "bad.dat")
