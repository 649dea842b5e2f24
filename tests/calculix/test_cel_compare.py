"""Comparing two ``.cel`` files pairing by pairing (``dolfinx_ntf.calculix.cel.compare_cel``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import vs_ccx

from dolfinx_ntf.calculix.cel import ContactElementsFile, cel_pairings, compare_cel, read_cel

QUADS = np.array([[1, 2, 3, 4], [2, 5, 6, 3]])
TRI = np.array([[1, 2, 3]])


def _write(path: Path, pairings: list[tuple[np.ndarray, list[int]]]) -> Path:
    out = ContactElementsFile(path, 10)
    for iteration, (faces, slaves) in enumerate(pairings, start=1):
        out.write(faces, slaves, step=1, increment=1, attempt=1, iteration=iteration)
    return path


def test_pairings_give_each_slave_node_its_face_corners(tmp_path):
    path = _write(tmp_path / "a.cel", [(QUADS[[0, 1]], [11, 12])])
    tri = ContactElementsFile(tmp_path / "t.cel", 0)
    tri.write(TRI, [7], step=1, increment=2, attempt=1, iteration=1)
    assert cel_pairings(read_cel(path)) == {
        "contactelements_st1_in1_at1_it1": {
            11: frozenset({1, 2, 3, 4}),
            12: frozenset({2, 5, 6, 3}),
        }
    }
    assert cel_pairings(read_cel(tmp_path / "t.cel")) == {
        "contactelements_st1_in2_at1_it1": {7: frozenset({1, 2, 3})}
    }


def test_differences_are_counted_per_pairing_over_the_first_files_sets(tmp_path):
    ccx = _write(tmp_path / "ccx.cel", [(QUADS[[0, 1]], [11, 12]), (QUADS[[0, 0]], [11, 12])])
    ours = _write(
        tmp_path / "ours.cel",
        [(QUADS[[0, 1]], [11, 12]), (QUADS[[1, 0]], [11, 13]), (QUADS[[0]], [11])],
    )
    first, second = compare_cel(ccx, ours)  # ours has a third pairing ccx never reached
    assert first.count == 0 and first.set.endswith("_it1")
    assert second.other_face == (11,)
    assert second.only_first == (12,) and second.only_second == (13,)
    assert second.count == 3
    assert [d.count for d in compare_cel(ccx, ccx)] == [0, 0]


def test_malformed_contact_elements_are_rejected(tmp_path):
    path = tmp_path / "bad.cel"
    path.write_text("*ELEMENT,TYPE=C3D6,ELSET=s\n 1, 2, 3, 4, 5, 6, 7\n")
    with pytest.raises(ValueError, match=r"contact element 1 \(C3D6, nodes \[2, 3, 4, 5, 6, 7\]\)"):
        cel_pairings(read_cel(path))
    twice = _write(tmp_path / "twice.cel", [(QUADS[[0, 1]], [11, 11])])
    with pytest.raises(ValueError, match=r"slave node 11 has two contact elements"):
        cel_pairings(read_cel(twice))


def test_benchmark_lists_the_first_pairing_that_differs(tmp_path):
    ccx = _write(tmp_path / "ccx.cel", [(QUADS[[0, 1]], [11, 12])] * 3)
    ours = _write(
        tmp_path / "ours.cel", [(QUADS[[0, 1]], [11, 12])] + [(QUADS[[1, 1]], [11, 12])] * 2
    )
    result = vs_ccx.DeckResult("tie", "a tie deck", 3)
    vs_ccx._compare_cel(result, ccx, ours)
    (_, _, row) = vs_ccx.cel_lines([result])
    assert row == "| `tie` | 3 | in1 it2 | in1 it2: 1/0/0, in1 it3: 1/0/0 |"
    same = vs_ccx.DeckResult("same", "", 3)
    vs_ccx._compare_cel(same, ccx, ccx)
    assert vs_ccx.cel_lines([same])[2] == "| `same` | 3 | none | identical |"
    assert vs_ccx.cel_lines([vs_ccx.DeckResult("none", "", 3)]) == []
