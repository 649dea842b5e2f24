"""Tests of the ccx ``.dat`` and ``.cel`` writers/readers against stored ccx 2.20 output.

``tests/data/calculix/two_cubes.dat`` and ``two_cubes.cel`` were written by ccx 2.20 for
``two_cubes.inp``; the writers must reproduce them byte for byte from the numbers they contain.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dolfinx_ntf.calculix.cel import ContactElementsFile, format_contact_elements, read_cel
from dolfinx_ntf.calculix.dat import (
    DatBlock,
    contact_print_blocks,
    el_print_blocks,
    format_block,
    format_e13,
    format_time,
    increment_heading,
    node_print_blocks,
    read_dat,
    step_heading,
    write_dat,
)
from dolfinx_ntf.calculix.deck import face_nodes, read_deck

DATA = Path(__file__).parents[1] / "data" / "calculix"
CCX_DAT = DATA / "two_cubes.dat"


# ----------------------------------------------------------------------------- number formats


@pytest.mark.parametrize(
    "value, text",
    [
        (0.0, " 0.000000E+00"),
        (-1.501435e-05, "-1.501435E-05"),
        (149.1437, " 1.491437E+02"),
        (9.9999996e-5, " 1.000000E-04"),  # rounding carries into the exponent
        (-2.5e-30, "-2.500000E-30"),
        (1.234e-100, " 1.234000-100"),  # gfortran drops the E for 3-digit exponents
        (-1.0e100, "-1.000000+100"),
        (float("nan"), "          NaN"),
    ],
)
def test_format_e13(value, text):
    assert format_e13(value) == text
    assert len(format_e13(value)) == 13


@pytest.mark.parametrize(
    "value, text",
    [
        (0.5, " 0.5000000E+00"),
        (1.0, " 0.1000000E+01"),
        (12.5, " 0.1250000E+02"),
        (0.0, " 0.0000000E+00"),
        (1e-3, " 0.1000000E-02"),
        (0.99999999, " 0.1000000E+01"),
    ],
)
def test_format_time(value, text):
    assert format_time(value) == text


def test_format_time_rejects_nan():
    with pytest.raises(ValueError, match="finite"):
        format_time(float("nan"))


# ----------------------------------------------------------------------------- ccx reference


def test_read_ccx_dat_blocks():
    blocks = read_dat(CCX_DAT)
    names = [b.name for b in blocks]
    per_time = ["U", "RF", "RF", "RF_TOTAL", "S", "CDIS", "CSTR", "CELS", "CNUM", "CELS_TOTAL"]
    assert names == per_time * 2
    assert [b.time for b in blocks] == [0.5] * 10 + [1.0] * 10
    u = blocks[0]
    assert u.set == "NALL" and u.labels.tolist() == [*range(1, 9), *range(11, 19)]
    np.testing.assert_allclose(u.values[4], [-3.464183e-05, -3.464183e-05, -1.616619e-04])
    s = blocks[4]
    assert s.labels.shape == (16, 2) and s.labels[9].tolist() == [2, 2]
    cdis, cstr, cels, cnum, total = blocks[5:10]
    assert cdis.set is None and cdis.labels.tolist() == [11, 12, 13, 14]
    np.testing.assert_allclose(cdis.values[:, 0], -1.501435e-05)
    np.testing.assert_allclose(cstr.values[:, 0], 149.1437)
    assert cels.values.shape == (4, 1)
    assert cnum.values.tolist() == [[4.0]] and cnum.labels.size == 0
    np.testing.assert_allclose(total.values, [[2.800671e-04]])
    assert blocks[3].rows == [(0.0, -3.108624e-15, 37.30659)]
    assert cdis.rows[0] == (11, -1.501435e-05, 0.0, 0.0)


def test_read_dat_skips_ccx_223_step_headers(tmp_path):
    """ccx 2.23 heads each step and increment with ``S T E P`` and ``INCREMENT`` lines."""
    text = CCX_DAT.read_text(encoding="latin-1")
    second = text.index(" displacements (vx,vy,vz) for set NALL and time  0.1000000E+01")
    headed = tmp_path / "two_cubes_223.dat"
    headed.write_text(
        f"\n{'S T E P       1':>39}\n\n\n{'INCREMENT     1':>47}\n\n{text[:second]}"
        f"{'INCREMENT     2':>47}\n\n\n{text[second:]}",
        encoding="latin-1",
    )
    expected, got = read_dat(CCX_DAT), read_dat(headed)
    assert [(b.name, b.time, b.set) for b in got] == [(b.name, b.time, b.set) for b in expected]
    for a, b in zip(got, expected):
        assert np.array_equal(a.labels, b.labels) and np.array_equal(a.values, b.values)


def test_reader_reads_ccx_2_23_cels_title(tmp_path):
    """ccx 2.23 titles CELS ``contact spring energy ... for all``; the rows are read as CELS."""
    text = CCX_DAT.read_text(encoding="latin-1")
    renamed = tmp_path / "two_cubes_223_cels.dat"
    renamed.write_text(
        text.replace(" contact print energy (slave node,energy) forall ",
                     " contact spring energy (slave node,energy) for all "),
        encoding="latin-1",
    )  # fmt: skip
    expected = [b for b in read_dat(CCX_DAT) if b.name == "CELS"]
    got = [b for b in read_dat(renamed) if b.name == "CELS"]
    assert expected and len(got) == len(expected)
    for a, b in zip(got, expected):
        assert a.time == b.time and np.array_equal(a.values, b.values)


def test_ccx_2_23_format_round_trips(tmp_path):
    """``write_dat(..., ccx="2.23")`` with 2.23's step and increment lines reads back the blocks."""
    blocks = read_dat(CCX_DAT)
    path = tmp_path / "two_cubes_223.dat"
    first = [b for b in blocks if b.time == 0.5]
    write_dat(path, first, ccx="2.23", heading=step_heading(1) + increment_heading(1))
    write_dat(path, blocks[len(first) :], append=True, ccx="2.23", heading=increment_heading(2))
    text = path.read_text()
    # the lines as ccx 2.23 writes them (``S T E P`` ends column 39, ``INCREMENT`` column 47)
    assert text.startswith(f"\n{'S T E P       1':>39}\n\n\n{'INCREMENT     1':>47}\n\n\n ")
    assert f"\n\n{'INCREMENT     2':>47}\n\n\n " in text
    assert "contact spring energy (slave node,energy) for all" in text
    assert "contact print energy" not in text
    again = read_dat(path)
    assert [(b.name, b.time, b.set) for b in again] == [(b.name, b.time, b.set) for b in blocks]
    with pytest.raises(ValueError, match="ccx format"):
        write_dat(path, blocks, ccx="2.22")


def test_writer_reproduces_ccx_file_byte_for_byte(tmp_path):
    blocks = read_dat(CCX_DAT)
    write_dat(tmp_path / "copy.dat", blocks)
    assert (tmp_path / "copy.dat").read_bytes() == CCX_DAT.read_bytes()


def test_print_block_builders_reproduce_ccx(tmp_path):
    """Rebuild every block from ccx's numbers with the request-level builders."""
    ccx = read_dat(CCX_DAT)
    rebuilt = []
    for time in (0.5, 1.0):
        at = {(b.name, b.set): b for b in ccx if b.time == time}
        u = at["U", "NALL"]
        rebuilt += node_print_blocks("U", "NALL", time, u.labels, u.values)
        rebuilt += node_print_blocks("RF", "NALL", time, at["RF", "NALL"].labels,
                                     at["RF", "NALL"].values)  # fmt: skip
        fix = at["RF", "FIX"]
        rf_fix = node_print_blocks("RF", "FIX", time, fix.labels, fix.values, totals="YES")
        # ccx sums in its own order: take its total (last digit may differ from ours)
        np.testing.assert_allclose(rf_fix[1].values, at["RF_TOTAL", "FIX"].values, rtol=1e-6,
                                   atol=1e-6 * np.abs(fix.values).max())  # fmt: skip
        rebuilt += [rf_fix[0], at["RF_TOTAL", "FIX"]]
        s = at["S", "EALL"]
        rebuilt += el_print_blocks("S", "EALL", time, [1, 2], s.values.reshape(2, 8, 6))
        nodes = at["CDIS", None].labels
        rebuilt += contact_print_blocks("CDIS", time, nodes, at["CDIS", None].values)
        rebuilt += contact_print_blocks("CSTR", time, nodes, at["CSTR", None].values)
        rebuilt += contact_print_blocks("CELS", time, nodes, at["CELS", None].values[:, 0])
        rebuilt += contact_print_blocks("CNUM", time, nodes)
        cels_total = contact_print_blocks("CELS", time, nodes, at["CELS", None].values,
                                          totals="ONLY")  # fmt: skip
        assert [b.name for b in cels_total] == ["CELS_TOTAL"]
        np.testing.assert_allclose(cels_total[0].values, at["CELS_TOTAL", None].values, rtol=1e-6)
        rebuilt.append(at["CELS_TOTAL", None])
    text = "".join(format_block(b) for b in rebuilt)
    assert text == CCX_DAT.read_text()


def test_contact_block_layout_literal():
    text = "".join(
        format_block(b)
        for b in contact_print_blocks("CDIS", 0.5, [11, 102], [[-1.5e-5, 0, 0], [2.0, 1e-3, -4]])
    )
    assert text == (
        "\n"
        " relative contact displacement (slave node,normal,tang1,tang2) for all contact elements"
        " and time 0.5000000E+00\n"
        "\n"
        "        11 -1.500000E-05  0.000000E+00  0.000000E+00\n"
        "       102  2.000000E+00  1.000000E-03 -4.000000E+00\n"
    )


def test_empty_contact_blocks_like_ccx():
    # ccx 2.20 with no contact element: title and blank lines only; CNUM prints 0
    blocks = contact_print_blocks("CSTR", 2.0, [], np.zeros((0, 3)))
    blocks += contact_print_blocks("CELS", 2.0, [], np.zeros(0), totals="YES")
    blocks += contact_print_blocks("CNUM", 2.0, [])
    text = "".join(format_block(b) for b in blocks)
    assert text == (
        "\n contact stress (slave node,press,tang1,tang2) for all contact elements and time"
        " 0.2000000E+01\n\n"
        "\n contact print energy (slave node,energy) forall contact elements and time"
        " 0.2000000E+01\n\n"
        "\n total contact spring energy for time  0.2000000E+01\n\n        0.000000E+00\n"
        "\n total number of contact elements for time  0.2000000E+01\n\n                0\n"
    )


def test_totals_semantics():
    nodes, forces = [3, 1], [[1.0, 2.0, 3.0], [0.5, -2.0, 1.0]]
    only = node_print_blocks("RF", "FIX", 1.0, nodes, forces, totals="only")
    assert [b.name for b in only] == ["RF_TOTAL"]
    np.testing.assert_allclose(only[0].values, [[1.5, 0.0, 4.0]])
    u_blocks = node_print_blocks("U", "FIX", 1.0, nodes, forces, totals="YES")
    assert [b.name for b in u_blocks] == ["U"]
    cels = contact_print_blocks("CELS", 1.0, [5, 6], [1.0, 2.0], totals="YES")
    assert [b.name for b in cels] == ["CELS", "CELS_TOTAL"]
    assert cels[1].values.tolist() == [[3.0]]


def test_round_trip_through_read_dat(tmp_path):
    rng = np.random.default_rng(0)
    blocks = (
        node_print_blocks("U", "NALL", 0.25, [1, 5, 3], rng.normal(size=(3, 3)) * 1e-4)
        + node_print_blocks("RF", "FIX", 0.25, [7, 2], rng.normal(size=(2, 3)) * 1e3, totals="YES")
        + el_print_blocks("S", "EALL", 0.25, [4, 9], rng.normal(size=(2, 4, 6)) * 1e2)
        + contact_print_blocks("CDIS", 0.25, [11, 12], rng.normal(size=(2, 3)) * 1e-5)
        + contact_print_blocks("CSTR", 0.25, [11, 12], rng.normal(size=(2, 3)) * 1e2)
        + contact_print_blocks("CELS", 0.25, [11, 12], rng.random(2), totals="YES")
        + contact_print_blocks("CNUM", 0.25, [11, 12])
        + node_print_blocks("U", "NALL", 12.5, [1], [[1e-120, -3e105, 0.0]])
    )
    write_dat(tmp_path / "job.dat", blocks)
    back = read_dat(tmp_path / "job.dat")
    assert [(b.name, b.set, b.time) for b in back] == [(b.name, b.set, b.time) for b in blocks]
    for original, read in zip(blocks, back):
        np.testing.assert_array_equal(read.labels, original.labels)
        # 7 significant digits survive the round trip
        np.testing.assert_allclose(read.values, original.values, rtol=5e-7, atol=0)
    # and writing what was read gives the same file
    write_dat(tmp_path / "again.dat", back)
    assert (tmp_path / "again.dat").read_text() == (tmp_path / "job.dat").read_text()
    write_dat(tmp_path / "job.dat", blocks[:1], append=True)
    assert len(read_dat(tmp_path / "job.dat")) == len(blocks) + 1


def test_peeq_block_like_ccx(tmp_path):
    """The PEEQ block as ccx 2.20 wrote it for the bar of test_ccx_plastic (no blank before
    ``for``: the set name is read all the same)."""
    text = (
        "\n equivalent plastic strain (elem, integ.pnt.,pe)for set EALL and time  0.1000000E+01"
        "\n\n         1   1  6.854688E-02\n         1   2  5.857536E-02\n         2   1  "
        "0.000000E+00\n"
    )
    values = np.array([[[6.854688e-02], [5.857536e-02]], [[0.0], [0.0]]])
    (block,) = el_print_blocks("PEEQ", "EALL", 1.0, [1, 2], values)
    assert format_block(block).startswith(text)
    path = tmp_path / "peeq.dat"
    write_dat(path, [block])
    (read,) = read_dat(path)
    assert (read.name, read.set, read.time) == ("PEEQ", "EALL", 1.0)
    np.testing.assert_array_equal(read.labels, [[1, 1], [1, 2], [2, 1], [2, 2]])
    np.testing.assert_array_equal(read.values, values.reshape(-1, 1))
    with pytest.raises(ValueError, match=r"\(2, q, 1\)"):
        el_print_blocks("PEEQ", "EALL", 1.0, [1, 2], np.zeros((2, 8, 6)))


def test_writer_input_errors():
    with pytest.raises(ValueError, match="U, V, RF or NT"):
        node_print_blocks("HFL", "N", 1.0, [1], [[0, 0, 0]])
    with pytest.raises(ValueError, match=r"NT: values must have shape \(1, 1\)"):
        node_print_blocks("NT", "N", 1.0, [1], [[0, 0, 0]])
    with pytest.raises(ValueError, match=r"shape \(2, 3\)"):
        node_print_blocks("U", "N", 1.0, [1, 2], [[0, 0], [0, 0]])
    with pytest.raises(ValueError, match="CDIS, CSTR, CELS or CNUM"):
        contact_print_blocks("CF", 1.0, [1], [[0, 0, 0]])
    with pytest.raises(ValueError, match="totals must be"):
        contact_print_blocks("CELS", 1.0, [1], [0.0], totals="MAYBE")
    with pytest.raises(ValueError, match=r"shape \(1, q, 6\)"):
        el_print_blocks("S", "E", 1.0, [1], np.zeros((1, 8, 3)))
    with pytest.raises(ValueError, match=r"unknown \.dat block"):
        format_block(DatBlock("XYZ", 1.0, None, np.zeros(0), np.zeros((1, 1))))
    with pytest.raises(ValueError, match="needs a set name"):
        format_block(DatBlock("U", 1.0, None, np.array([1]), np.zeros((1, 3))))


def test_read_dat_errors(tmp_path):
    bad = tmp_path / "bad.dat"
    bad.write_text("\n displacements (vx,vy,vz) for set A and time  0.1000000E+01\n\n  1  x  y z\n")
    with pytest.raises(ValueError, match=r"bad\.dat:4: bad number 'x'"):
        read_dat(bad)
    bad.write_text("\n displacements (vx,vy,vz) for set A and time  0.1000000E+01\n\n oops\n")
    with pytest.raises(ValueError, match=r"bad\.dat:4: not a \.dat block title or row"):
        read_dat(bad)
    bad.write_text("         1  0.000000E+00\n")
    with pytest.raises(ValueError, match=r"bad\.dat:1: data row before any block title"):
        read_dat(bad)


def test_read_dat_unknown_block(tmp_path):
    """A block without a name here is named by its title; E and ME (ccx 2.20's) are known."""
    path = tmp_path / "e.dat"
    row = (
        "\n\n         1   1  1.000000E+00  2.000000E+00  3.000000E+00  4.000000E+00  5.000000E+00"
        "  6.000000E+00\n"
    )
    path.write_text(
        "\n some other values (elem, integ.pnt.,a,b,c,d,e,f) for set EALL and time  0.1000000E+01"
        + row
        + "\n strains (elem, integ.pnt.,exx,eyy,ezz,exy,exz,eyz) for set EALL and time  "
        "0.1000000E+01"
        + row
        + "\n mechanical strains (elem, integ.pnt.,exx,eyy,ezz,exy,exz,eyz) for set EALL and time "
        " 0.1000000E+01" + row
    )
    unknown, strains, mechanical = read_dat(path)
    assert unknown.name == "some other values" and unknown.set == "EALL" and unknown.time == 1.0
    assert unknown.labels.tolist() == [[1, 1]] and unknown.values.tolist() == [[1, 2, 3, 4, 5, 6]]
    assert strains.name == "E" and strains.set == "EALL"
    assert strains.values.tolist() == [[1, 2, 3, 4, 5, 6]]
    assert mechanical.name == "ME" and mechanical.values.tolist() == [[1, 2, 3, 4, 5, 6]]
    assert path.read_text().endswith(format_block(mechanical))


def test_energy_and_state_variable_blocks():
    """ENER and SDV rows as ccx 2.20 writes them: SDV of any width, no values without *PLASTIC
    (the rows' labels only), 13 with it on one line."""
    energy = el_print_blocks("ENER", "EALL", 0.125, [1], np.full((1, 2, 1), 0.09765625))[0]
    assert format_block(energy) == (
        "\n internal energy density (elem, integ.pnt.,energy) for set EALL and time  "
        "0.1250000E+00\n\n         1   1  9.765625E-02\n         1   2  9.765625E-02\n"
    )
    empty = el_print_blocks("SDV", "EALL", 1.0, [1, 2], np.zeros((2, 1, 0)))[0]
    assert format_block(empty) == (
        "\n internal state variables (elem, integ.pnt.,values) for set EALL and time  "
        "0.1000000E+01\n\n         1   1\n         2   1\n"
    )
    values = np.zeros((1, 1, 13))
    values[0, 0, :3] = (4.184164e-03, 4.18391e-03, -2.091955e-03)
    full = format_block(el_print_blocks("SDV", "EALL", 0.25, [1], values)[0]).splitlines()[-1]
    assert (
        full == "         1   1  4.184164E-03  4.183910E-03 -2.091955E-03" + "  0.000000E+00" * 10
    )
    with pytest.raises(ValueError, match="must be one of"):
        el_print_blocks("ZZS", "EALL", 1.0, [1], np.zeros((1, 1, 1)))


# ----------------------------------------------------------------------------- .cel


def test_cel_writer_reproduces_ccx_file(tmp_path):
    deck = read_deck(DATA / "two_cubes.inp")
    master = face_nodes(deck, "MASTER")
    ccx = read_cel(DATA / "two_cubes.cel")
    assert len(ccx) == 20 and ccx[0].number == 3 and ccx[-1].number == 22
    writer = ContactElementsFile(tmp_path / "two_cubes.cel", deck.num_elements)
    groups: dict[str, list[int]] = {}
    for element in ccx:
        groups.setdefault(element.set, []).append(element.nodes[1])
    for name, slaves in groups.items():
        step, increment, attempt, iteration = (int(p[2:]) for p in name.split("_")[1:])
        faces = np.repeat(master, len(slaves), axis=0)
        numbers = writer.write(faces, slaves, step=step, increment=increment, attempt=attempt,
                               iteration=iteration)  # fmt: skip
        assert numbers.size == len(slaves)
    assert (tmp_path / "two_cubes.cel").read_bytes() == (DATA / "two_cubes.cel").read_bytes()


def test_cel_triangles_and_limits(tmp_path):
    text = format_contact_elements(
        55, np.array([[1, 3, 2, 7, 6, 5]]), [101], step=2, increment=3, attempt=1, iteration=4
    )
    assert text == (
        "*ELEMENT,TYPE=C3D4,ELSET=contactelements_st2_in3_at1_it4\n"
        "          55 ,           1 ,           3 ,           2 ,         101\n"
    )
    assert format_contact_elements(1, np.zeros((0, 4), int), [], step=1, increment=1, attempt=1,
                                   iteration=1) == ""  # fmt: skip
    with pytest.raises(ValueError, match=r"iteration number 1000 .* 1\.\.999"):
        format_contact_elements(1, [[1, 2, 3]], [4], step=1, increment=1, attempt=1, iteration=1000)
    with pytest.raises(ValueError, match="3, 4, 6, 8 or 9 nodes"):
        format_contact_elements(1, [[1, 2]], [4], step=1, increment=1, attempt=1, iteration=1)
    writer = ContactElementsFile(tmp_path / "j.cel", 10)
    first = writer.write([[1, 2, 3, 4]], [9], step=1, increment=1, attempt=1, iteration=1)
    second = writer.write([[1, 2, 3, 4], [1, 2, 3, 4]], [9, 8], step=1, increment=1, attempt=1,
                          iteration=2)  # fmt: skip
    assert first.tolist() == [11] and second.tolist() == [12, 13]
    elements = read_cel(tmp_path / "j.cel")
    assert [(e.type, e.number, e.nodes) for e in elements] == [
        ("C3D6", 11, (2, 9, 3, 1, 9, 4)),
        ("C3D6", 12, (2, 9, 3, 1, 9, 4)),
        ("C3D6", 13, (2, 8, 3, 1, 8, 4)),
    ]
    ContactElementsFile(tmp_path / "j.cel", 10)  # a new run truncates the file
    assert read_cel(tmp_path / "j.cel") == []


def _awkward_values(rows: int, columns: int) -> np.ndarray:
    """Random magnitudes from 1e-110 to 1e110, with NaN, infinities, -0 and rounding edges."""
    rng = np.random.default_rng(7)
    values = rng.standard_normal((rows, columns)) * 10.0 ** rng.integers(-110, 110, (rows, columns))
    edges = [np.nan, np.inf, -np.inf, -0.0, 0.0, 9.99999951e99, 9.9999994e99, 1e-99,
             9.9999996e-100, 5e-324, 1e100, -1.0000005e-5]  # fmt: skip
    values[: len(edges), 0] = edges
    return values


@pytest.mark.parametrize(
    "name, set_name, labels, columns",
    [("CELS", None, 1, 1), ("U", "ALL", 1, 3), ("S", "ALL", 2, 6)],
)
def test_block_rows_are_formatted_value_by_value(name, set_name, labels, columns):
    """The one-format-per-block rows equal ``I10[ I3]`` + `` 1PE13.6`` per value (format_e13)."""
    values = _awkward_values(2000, columns)
    ids = np.random.default_rng(8).integers(0, 10**9, (2000, labels))
    block = DatBlock(name, 1.0, set_name, ids if labels == 2 else ids[:, 0], values)
    expected = [
        f"{row_ids[0]:10d}" + (f" {row_ids[1]:3d}" if labels == 2 else "")
        + "".join(" " + format_e13(v) for v in row)
        for row_ids, row in zip(ids.tolist(), values)
    ]  # fmt: skip
    assert format_block(block).splitlines()[3:] == expected
