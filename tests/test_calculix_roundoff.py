"""Values below their accuracy written as 0 in the deck runner's files (docs/method.md §14.5)."""

import numpy as np

from dolfinx_ntf.calculix.dat import DatBlock, format_block, node_print_blocks
from dolfinx_ntf.calculix.frd import FrdBlock
from dolfinx_ntf.calculix.progress import CvgFile
from dolfinx_ntf.calculix.roundoff import (
    ROUND_OFF,
    clean,
    clean_dat_blocks,
    clean_frd_block,
    clean_ratio,
    clean_totals,
    force_floor,
)


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
