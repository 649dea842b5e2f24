"""Tests that run CalculiX ``ccx`` 2.20: our writers against its output, our face tables against
the contact elements it writes, and ``run_ccx`` error handling."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from dolfinx_ntf.calculix.ccx import (
    CcxError,
    dat_block,
    dat_times,
    read_ccx_dat,
    read_sta,
    run_ccx,
)
from dolfinx_ntf.calculix.cel import ContactElementsFile, read_cel
from dolfinx_ntf.calculix.dat import DatBlock, contact_print_blocks, format_block, read_dat
from dolfinx_ntf.calculix.deck import ELEMENT_TYPES, face_nodes, read_deck

DATA = Path(__file__).parents[1] / "data" / "calculix"

needs_ccx = [
    pytest.mark.ccx,
    pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed"),
]


def _ccx(func):
    for mark in needs_ccx:
        func = mark(func)
    return func


@pytest.fixture(scope="module")
def two_cubes_run(tmp_path_factory):
    if shutil.which("ccx") is None:
        pytest.skip("CalculiX ccx is not installed")
    jobdir = tmp_path_factory.mktemp("two_cubes")
    shutil.copy(DATA / "two_cubes.inp", jobdir / "two_cubes.inp")
    result = run_ccx(jobdir, "two_cubes", timeout=120)
    return jobdir, result


# ----------------------------------------------------------------------------- without ccx


def test_run_ccx_missing_executable(tmp_path):
    (tmp_path / "job.inp").write_text("*HEADING\nx\n")
    with pytest.raises(CcxError, match=r"'no-such-ccx-binary' not found .*apt-get install"):
        run_ccx(tmp_path, "job", timeout=10, ccx="no-such-ccx-binary")


def test_run_ccx_missing_deck(tmp_path):
    with pytest.raises(ValueError, match=r"deck .*nothere\.inp does not exist"):
        run_ccx(tmp_path, "nothere", timeout=10)


def test_read_ccx_dat_missing(tmp_path):
    with pytest.raises(ValueError, match="did ccx run"):
        read_ccx_dat(tmp_path, "job")


# ----------------------------------------------------------------------------- two cubes


@_ccx
def test_ccx_contact_blocks_match_our_writer(two_cubes_run):
    jobdir, result = two_cubes_run
    assert "Job finished" in result.stdout
    assert (jobdir / "two_cubes.log").read_text() == result.stdout
    text = (jobdir / "two_cubes.dat").read_text()
    blocks = read_ccx_dat(jobdir, "two_cubes")
    assert dat_times(blocks) == [0.5, 1.0]
    contact = [b for b in blocks if b.name in ("CDIS", "CSTR", "CELS", "CNUM", "CELS_TOTAL")]
    assert len(contact) == 10
    for block in contact:
        nodes = block.labels
        if block.name == "CELS_TOTAL":
            cels = dat_block(blocks, "CELS", time=block.time)
            ours = contact_print_blocks("CELS", block.time, cels.labels, cels.values, totals="ONLY")
            np.testing.assert_allclose(ours[0].values, block.values, rtol=1e-6)
            ours = [DatBlock("CELS_TOTAL", block.time, None, nodes, block.values)]
        elif block.name == "CNUM":
            ours = contact_print_blocks("CNUM", block.time, np.arange(int(block.values[0, 0])))
        else:
            ours = contact_print_blocks(block.name, block.time, nodes, block.values)
        (mine,) = ours
        ours_text = format_block(mine)
        # same title line, same number of columns and widths: the text is in ccx's file verbatim
        assert ours_text in text, ours_text
        ours_lines = ours_text.splitlines()
        start = text.splitlines().index(ours_lines[1])
        ccx_lines = text.splitlines()[start - 1 : start - 1 + len(ours_lines)]
        assert ours_lines == ccx_lines
        for ours_line, ccx_line in zip(ours_lines[3:], ccx_lines[3:]):
            assert len(ours_line) == len(ccx_line)
            assert len(ours_line.split()) == len(ccx_line.split())
    # every block (node, element, contact) rewritten from ccx's numbers gives ccx's file
    assert "".join(format_block(b) for b in blocks) == text


@_ccx
def test_ccx_output_matches_stored_reference(two_cubes_run):
    jobdir, _ = two_cubes_run
    fresh, stored = read_ccx_dat(jobdir, "two_cubes"), read_dat(DATA / "two_cubes.dat")
    assert [(b.name, b.set, b.time) for b in fresh] == [(b.name, b.set, b.time) for b in stored]
    for a, b in zip(fresh, stored):
        np.testing.assert_array_equal(a.labels, b.labels)
        scale = max(np.abs(b.values).max(), 1e-300)
        np.testing.assert_allclose(a.values, b.values, rtol=1e-5, atol=1e-9 * scale)
    # contact: clearance -1.5e-5, pressure = F_N / A (compression > 0), four slave nodes
    cdis = dat_block(fresh, "CDIS", time=0.5)
    assert cdis.labels.tolist() == [11, 12, 13, 14]
    assert np.all(cdis.values[:, 0] < 0) and np.all(dat_block(fresh, "CSTR").values[:, 0] > 0)
    sta = read_sta(jobdir / "two_cubes.sta")
    assert [(r.step, r.increment, r.total_time) for r in sta] == [(1, 1, 0.5), (1, 2, 1.0)]
    assert all(r.iterations >= 2 for r in sta)


@_ccx
def test_ccx_cel_matches_our_writer(two_cubes_run, tmp_path):
    jobdir, _ = two_cubes_run
    deck = read_deck(jobdir / "two_cubes.inp")
    ccx = read_cel(jobdir / "two_cubes.cel")
    writer = ContactElementsFile(tmp_path / "ours.cel", deck.num_elements)
    master = face_nodes(deck, "MASTER")
    groups: dict[str, list[int]] = {}
    for element in ccx:
        groups.setdefault(element.set, []).append(element.nodes[1])
    for name, slaves in groups.items():
        step, increment, attempt, iteration = (int(p[2:]) for p in name.split("_")[1:])
        writer.write(np.repeat(master, len(slaves), axis=0), slaves, step=step,
                     increment=increment, attempt=attempt, iteration=iteration)  # fmt: skip
    assert (tmp_path / "ours.cel").read_text() == (jobdir / "two_cubes.cel").read_text()


# ----------------------------------------------------------------------------- face tables


_HEX = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float
)
_TET = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
_MIDS = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
_REFERENCE = {
    "C3D8": _HEX,
    "C3D4": _TET,
    "C3D10": np.vstack([_TET] + [(_TET[a] + _TET[b]) / 2 for a, b in _MIDS]),
}
# Node sets of the faces, from the manual's *SURFACE table (orientation ignored).
_MANUAL = {
    "C3D8": [[1, 2, 3, 4], [5, 8, 7, 6], [1, 5, 6, 2], [2, 6, 7, 3], [3, 7, 8, 4], [4, 8, 5, 1]],
    "C3D4": [[1, 2, 3], [1, 4, 2], [2, 4, 3], [3, 4, 1]],
    "C3D10": [[1, 2, 3], [1, 4, 2], [2, 4, 3], [3, 4, 1]],
}


def _face_deck(type_name: str, face: int) -> str:
    """A master element of ``type_name`` whose face ``face`` is touched by a small slave brick."""
    x = _REFERENCE[type_name]
    corners = x[np.array(_MANUAL[type_name][face - 1]) - 1]
    centre = corners.mean(axis=0)
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    num_corners = 8 if type_name == "C3D8" else 4
    if normal @ (centre - x[:num_corners].mean(axis=0)) < 0:
        normal = -normal  # outward, from the geometry alone
    t1 = corners[0] - centre
    t1 -= (t1 @ normal) * normal
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(normal, t1)
    xi = _HEX  # slave brick: bottom face on the master face, (t1, t2, normal) right-handed
    in_plane = (xi[:, :1] - 0.5) * t1 + (xi[:, 1:2] - 0.5) * t2
    slave = centre + 0.1 * (in_plane + xi[:, 2:] * normal)
    lines = ["*NODE"]
    lines += [f"{i + 1}, {p[0]:.12g}, {p[1]:.12g}, {p[2]:.12g}" for i, p in enumerate(x)]
    lines += [f"{101 + i}, {p[0]:.12g}, {p[1]:.12g}, {p[2]:.12g}" for i, p in enumerate(slave)]
    lines += [f"*ELEMENT, TYPE={type_name}, ELSET=EALL",
              "1, " + ", ".join(str(i + 1) for i in range(len(x))),
              "*ELEMENT, TYPE=C3D8, ELSET=EALL",
              "2, " + ", ".join(str(101 + i) for i in range(8)),
              "*NSET, NSET=MNODES", *(str(i + 1) for i in range(len(x))),
              "*MATERIAL, NAME=M", "*ELASTIC", "1000., 0.3",
              "*SOLID SECTION, ELSET=EALL, MATERIAL=M",
              "*SURFACE, NAME=MASTER", f"1, S{face}",
              "*SURFACE, NAME=SLAVE", "2, S1",
              "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE", "SLAVE, MASTER",
              "*SURFACE INTERACTION, NAME=SI",
              "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", "1.0e5, 1.0, 1.0e-3",
              "*STEP", "*STATIC", "1., 1.", "*BOUNDARY", "MNODES, 1, 3"]  # fmt: skip
    push = -1e-3 * normal
    lines += [f"{n}, {d + 1}, {d + 1}, {push[d]:.12g}" for n in range(105, 109) for d in range(3)]
    lines += ["*NODE FILE, CONTACT ELEMENTS", "U", "*END STEP"]
    return "\n".join(lines) + "\n"


FACE_CASES = [(t, k + 1) for t in ("C3D8", "C3D4", "C3D10") for k in range(len(_MANUAL[t]))]


@_ccx
@pytest.mark.parametrize("type_name, face", FACE_CASES, ids=[f"{t}-S{k}" for t, k in FACE_CASES])
def test_face_tables_match_ccx_contact_elements(tmp_path, type_name, face):
    """ccx's .cel lists the master face corners in its internal (outward) order: ours must match."""
    (tmp_path / "face.inp").write_text(_face_deck(type_name, face))
    run_ccx(tmp_path, "face", timeout=120)
    elements = read_cel(tmp_path / "face.cel")
    assert elements, "ccx generated no contact element"
    deck = read_deck(tmp_path / "face.inp")
    expected = face_nodes(deck, "MASTER")[0][: ELEMENT_TYPES[type_name].face_corners]
    table = ELEMENT_TYPES[type_name].faces[face - 1]
    np.testing.assert_array_equal(expected, table[: len(expected)] + 1)
    for element in elements:
        n = element.nodes
        corners = [n[3], n[0], n[2], n[5]] if element.type == "C3D6" else list(n[:3])
        assert corners == expected.tolist()
        assert n[-1] in range(101, 105) or n[1] in range(101, 105)


# ----------------------------------------------------------------------------- failures


@_ccx
def test_run_ccx_reports_input_errors(tmp_path):
    # ccx 2.20 exits with status 0 here but prints *ERROR
    (tmp_path / "bad.inp").write_text("*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D8\n1, 1, 2, 3\n")
    with pytest.raises(CcxError, match=r"ccx reported 1 error\(s\) .*\*ERROR reading \*ELEMENT"):
        run_ccx(tmp_path, "bad", timeout=60)


@_ccx
def test_run_ccx_reports_exit_status(tmp_path):
    text = (DATA / "two_cubes.inp").read_text().replace(", TYPE=NODE TO SURFACE", "")
    (tmp_path / "notype.inp").write_text(text)
    with pytest.raises(CcxError, match=r"exit status \d+ .*notype\.inp; last output:\n"):
        run_ccx(tmp_path, "notype", timeout=60)
    assert "no TYPE specified" in (tmp_path / "notype.log").read_text()


_ORDER_STEPS = """*STEP
*STATIC
0.5, 1.0
*BOUNDARY
FIX, 1, 3
TOP, 1, 2
TOP, 3, 3, -0.001
*NODE PRINT, NSET=TOP
U
*CONTACT PRINT, TOTALS=YES
CNUM, CELS
*NODE PRINT, NSET=FIX, TOTALS=ONLY
RF
*EL PRINT, ELSET=EALL
S
*END STEP
*STEP
*STATIC
1.0, 1.0
*NODE PRINT, NSET=FIX, TOTALS=YES
RF, U
*END STEP
"""


def _expected_names(step) -> list[tuple[str, str | None]]:
    """Block names and sets ccx writes per output time, from the parsed requests."""
    names = []
    for request in step.prints:
        for key in request.keys:
            if key == "RF":
                names += [("RF", request.set)] if request.totals != "ONLY" else []
                names += [("RF_TOTAL", request.set)] if request.totals != "NO" else []
            elif key == "CELS":
                names += [("CELS", None)] if request.totals != "ONLY" else []
                names += [("CELS_TOTAL", None)] if request.totals != "NO" else []
            else:
                names.append((key, request.set))
    return names


@_ccx
def test_print_order_and_carry_over_match_ccx(tmp_path):
    """Step.prints (card order, ccx's carry-over between steps) is the order of ccx's blocks."""
    base = (DATA / "two_cubes.inp").read_text()
    text = base[: base.index("*STEP")] + _ORDER_STEPS
    (tmp_path / "order.inp").write_text(text)
    run_ccx(tmp_path, "order", timeout=120)
    deck = read_deck(tmp_path / "order.inp")
    blocks = read_ccx_dat(tmp_path, "order")
    times = dat_times(blocks)
    assert times == [0.5, 1.0, 2.0]
    step_of_time = {0.5: deck.steps[0], 1.0: deck.steps[0], 2.0: deck.steps[1]}
    for time in times:
        got = [(b.name, b.set) for b in blocks if b.time == time]
        assert got == _expected_names(step_of_time[time]), time
    # step 2 keeps the contact and element prints of step 1 before its new node print
    assert [p.kind for p in deck.steps[1].prints] == ["CONTACT", "EL", "NODE"]
