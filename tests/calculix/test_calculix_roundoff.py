"""Values below their accuracy written as 0 in the deck runner's files (docs/method.md §14.5)."""

import dataclasses
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf import LinearLaw
from dolfinx_ntf.calculix import roundoff
from dolfinx_ntf.calculix.dat import DatBlock, format_block, node_print_blocks, read_dat
from dolfinx_ntf.calculix.frd import FrdBlock
from dolfinx_ntf.calculix.job import ContactRows, run_job
from dolfinx_ntf.calculix.progress import CvgFile
from dolfinx_ntf.calculix.roundoff import (
    FIELD_ROUND_OFF,
    ROUND_OFF,
    FieldAccuracy,
    clean,
    clean_contact,
    clean_dat_blocks,
    clean_frd_block,
    clean_ratio,
    clean_totals,
    element_sizes,
    force_floor,
    largest_modulus,
    law_accuracy,
    zero_below,
)

DYNAMIC = Path(__file__).parents[1] / "data" / "calculix" / "dynamic"


def test_round_off_of_a_block_is_zero_and_the_rest_untouched():
    values = np.array([[2.0, -3.1e-17, 2.5 * ROUND_OFF], [-1.5 * ROUND_OFF, 4e-3, np.nan]])
    out = clean(values)
    assert out[0, 1] == 0.0 and out[1, 0] == 0.0  # at most ROUND_OFF * 2.0
    assert out[0, 2] == values[0, 2] and out[1, 1] == values[1, 1] and out[0, 0] == 2.0
    assert np.isnan(out[1, 2])  # kept, and not taken as the largest
    assert values[0, 1] == -3.1e-17  # a copy
    assert np.array_equal(clean(np.zeros((0, 3))), np.zeros((0, 3)))


def test_forces_within_the_newton_residual_are_zero():
    forces = np.array([[100.0, 0.0, -1e-7], [3e-6, 5e-5, -50.0]])
    floor = force_floor(forces, residual=1e-5)
    assert floor == 1e-5 + ROUND_OFF * 100.0
    out = clean(forces, floor)
    assert out[0, 2] == 0.0 and out[1, 0] == 0.0  # residual-sized: within the accuracy
    assert out[1, 1] == 5e-5 and out[1, 2] == -50.0  # a reaction above it is kept
    blocks = node_print_blocks("RF", "NALL", 1.0, [1, 2], out, totals="YES")
    (total,) = [b for b in clean_totals(blocks, 2, floor) if b.name == "RF_TOTAL"]
    assert np.array_equal(total.values, [[100.0, 5e-5, -50.0]])  # 5e-5 > 2 * floor
    (total,) = [b for b in clean_totals(blocks, 4, floor) if b.name == "RF_TOTAL"]
    assert total.values[0, 1] == 0.0  # 5e-5 <= 4 * floor


def test_dat_blocks_print_zero_and_keep_counts():
    block = DatBlock("U", 1.0, "NALL", np.array([5]), np.array([[1e-3, -2.2e-19, 0.0]]))
    count = DatBlock("CNUM", 1.0, None, np.zeros(0, np.int64), np.array([[3.0]]))
    cleaned, kept = clean_dat_blocks([block, count])
    assert format_block(cleaned).splitlines()[-1].split()[2] == "0.000000E+00"
    assert "-2.200000E-19" in format_block(block)
    assert kept is count


def test_frd_contact_columns_are_cleaned_by_unit():
    # a clearance of 1e-7 next to pressures of 1e4: real (its own column group's largest)
    values = np.array([[-1e-7, 0.0, 0.0, 1e4, 0.0, 0.0], [-2e-7, 0.0, 0.0, 5e-12, 0.0, 0.0]])
    block = FrdBlock("CONTACT", (), 1, 1, 1.0, np.array([3, 4]), values)
    out = clean_frd_block(block).values
    assert out[0, 0] == -1e-7 and out[1, 0] == -2e-7
    assert out[1, 3] == 0.0 and out[0, 3] == 1e4
    disp = FrdBlock("DISP", (), 1, 1, 1.0, np.array([3]), np.array([[1.0, 1e-12, 2e-7]]))
    assert np.array_equal(clean_frd_block(disp).values, [[1.0, 0.0, 2e-7]])
    empty = FrdBlock("CONTACT", (), 1, 1, 1.0, np.zeros(0, int), np.zeros((0, 6)))
    assert clean_frd_block(empty) is empty


def test_cvg_ratios_at_round_off_are_zero(tmp_path):
    assert clean_ratio(6.8e-14, 100.0) == 0.0
    assert clean_ratio(1e-3, 100.0) == 1e-5
    assert clean_ratio(1.0, 0.0) == 0.0
    cvg = CvgFile(tmp_path / "job.cvg")
    cvg.rows(1, 1, 1, [(1, 4, 0.5, 10.0, 1e-3, 0.1), (2, 4, 6.8e-15, 10.0, 1e-16, 0.1)])
    first, last = tmp_path.joinpath("job.cvg").read_text().splitlines()[-2:]
    assert first.split()[5:7] == ["0.5000E+01", "0.1000E+01"]
    assert last.split()[5:7] == ["0.0000E+00", "0.0000E+00"]


def test_field_accuracy_carries_the_displacement_round_off():
    accuracy = FieldAccuracy.of(coordinates=2.0, displacement=0.01, modulus=1346.0, sizes=(0.5, 3))
    assert accuracy.length == FIELD_ROUND_OFF * 2.01
    assert accuracy.stress == pytest.approx(FIELD_ROUND_OFF * 1346.0 * 0.01 / 0.5, rel=1e-15)
    assert accuracy.force == pytest.approx(accuracy.stress * 9.0, rel=1e-15)
    none = FieldAccuracy.of(2.0, 0.01, 1346.0, (0.0, 0.0))  # no element: no bound
    assert none.stress == 0.0 and none.force == 0.0
    assert largest_modulus([(1000.0, 0.3), (10.0, 0.0)]) == pytest.approx(1000 * 0.7 / 0.52)
    assert largest_modulus([]) == 0.0
    x = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0.3, 0.2, 0.1]])
    # 0-3 (0.374) lies in no element: 1-3 is the smallest, 0-2 the largest
    sizes = element_sizes(x, np.array([[0, 1, 2], [1, 2, 3]]))
    assert sizes == pytest.approx((np.sqrt(0.54), np.sqrt(2.0)))
    assert element_sizes(x, np.array([[0, 1, 2, 3]]))[0] == pytest.approx(np.sqrt(0.14))
    assert element_sizes(x, np.zeros((0, 4), int)) == (0.0, 0.0)


def test_pressure_and_energy_accuracy_follow_the_law():
    law = LinearLaw(slope=1e5, tension=1.0).dynamic()  # no tension: p = 0 for d <= 0
    d, area, length = np.array([-1e-18, 0.0, 1e-3]), np.array([0.25, 0.25, 0.5]), 1e-12
    dp, de = law_accuracy(law, d, area, length)
    assert dp[0] == pytest.approx(law.pressure(d[0] + length), rel=1e-12)  # p(d - length) = 0
    slope = law.pressure_derivative(d[2])
    assert dp[2] == pytest.approx(slope * length, rel=1e-3)
    assert de[2] == pytest.approx(area[2] * law.pressure(d[2]) * length, rel=1e-3)
    assert np.all(de[:2] > 0.0) and np.all(de[:2] < dp[:2] * length)


def test_zero_below_a_floor_without_the_block_rule():
    values = np.array([[1e-13, 2.0], [3e-12, np.nan]])
    assert np.array_equal(zero_below(values, 1e-12), [[0.0, 2.0], [3e-12, np.nan]], equal_nan=True)
    assert np.array_equal(zero_below(values[:, 0], [1e-14, 5e-12]), [1e-13, 0.0])  # per row
    assert zero_below(np.zeros((0, 3)), 1.0).shape == (0, 3)


def test_contact_values_within_their_accuracy_are_zero():
    rows = ContactRows(
        "S-M",
        np.array([3, 4]),
        clearance=np.array([-1.7e-18, -2e-4]),
        pressure=np.array([4.3e-14, 20.0]),
        energy=np.array([2.3e-33, 1e-3]),
        master_faces=np.zeros((2, 4), int),
        slip=np.array([[1e-15, 0.0], [1e-5, -3e-13]]),
        shear=np.zeros((2, 2)),
        accuracy=(2e-12, np.array([5e-8, 5e-8]), np.array([1e-20, 1e-20])),
    )
    out = clean_contact(rows)
    assert np.array_equal(out.clearance, [0.0, -2e-4])
    assert np.array_equal(out.pressure, [0.0, 20.0])
    assert np.array_equal(out.energy, [0.0, 1e-3])
    assert np.array_equal(out.slip, [[0.0, 0.0], [1e-5, 0.0]])
    assert rows.clearance[0] == -1.7e-18  # a copy
    bare = dataclasses.replace(rows, accuracy=None)
    assert clean_contact(bare) is bare


@pytest.mark.parametrize("field_round_off", [FIELD_ROUND_OFF, 0.0])
def test_a_body_in_free_flight_prints_zero_stresses(tmp_path, monkeypatch, field_round_off):
    """The block falls freely until it touches the base at t = 0.01 exactly: its stresses are
    round-off only (2e-16 of ``M U / h``), and so are the clearance and pressure at t = 0.01.
    Without the displacement's accuracy (0.0) they print as round-off digits."""
    monkeypatch.setattr(roundoff, "FIELD_ROUND_OFF", field_round_off)
    from impact_deck import write_impact_deck

    path = write_impact_deck(tmp_path, "impact", period=0.012, increment=1e-3)
    text = path.read_text().replace("*END STEP", "*EL PRINT, ELSET=EALL\nS\n*END STEP")
    path.write_text(text)
    result = run_job("impact", tmp_path, comm=MPI.COMM_SELF, progress=False)
    blocks = read_dat(result.dat)
    stresses = {b.time: np.abs(b.values).max() for b in blocks if b.name == "S"}
    (touch,) = [b for b in blocks if b.name == "CDIS" and b.time == pytest.approx(0.01)]
    free = [s for t, s in stresses.items() if t < 0.01 + 1e-9]
    if field_round_off:
        assert len(free) == 10 and max(free) == 0.0
        assert np.all(touch.values[:, 0] == 0.0)
        assert stresses[max(stresses)] > 1e-3  # in contact: real stresses
    else:
        assert min(free) > 0.0 and max(free) < 1e-13
        assert np.all(touch.values[:, 0] != 0.0)
