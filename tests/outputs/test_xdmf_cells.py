"""``outputs.xdmf_cells``: collapsed hexahedra as XDMF wedges, and the mixed time series file.

docs/method.md §30.6. Every one of the twelve ways a hexahedron collapses into a wedge gives the
wedge back with VTK's orientation; the file's structure is read back with the standard library's
XML parser (the mesh once, a grid per time step including it by XPointer, the data inline).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers.xdmf import read_xdmf

from dolfinx_ntf.outputs.xdmf_cells import (
    COLLAPSE_PATTERNS,
    XDMF_HEXAHEDRON,
    XDMF_WEDGE,
    MixedXdmfFile,
    collapsed_wedges,
)

#: A wedge: triangle 0-1-2 (normal +z, toward the other) below 3-4-5, slightly skewed.
WEDGE = np.array(
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.1, 0, 1], [1.1, 0, 1.2], [0, 1.1, 0.9]], dtype=float
)


def _collapsed(pattern: tuple, numbering: np.ndarray) -> np.ndarray:
    """The hexahedron of ``pattern`` that holds wedge nodes ``numbering`` (repeats filled)."""
    (a, b), (c, d), vertices = pattern
    cell = np.full(8, -1)
    cell[vertices] = numbering
    for p, q in ((a, b), (c, d)):
        cell[q if cell[q] < 0 else p] = cell[p if cell[q] < 0 else q]
    assert (cell >= 0).all()
    return cell


def _is_vtk_wedge(points: np.ndarray) -> bool:
    normal = np.cross(points[1] - points[0], points[2] - points[0])
    return float(normal @ (points[3:].mean(0) - points[:3].mean(0))) < 0.0


@pytest.mark.parametrize("index", range(12))
@pytest.mark.parametrize("flip", [False, True], ids=["up", "down"])
def test_every_collapse_gives_the_wedge(index: int, flip: bool) -> None:
    """The wedge's triangles, the partners across, VTK's orientation, for all 12 patterns."""
    assert len(COLLAPSE_PATTERNS) == 12
    rng = np.random.default_rng(index)
    numbering = rng.permutation(10)[:6]  # node numbers among 10 points
    order = [0, 2, 1, 3, 5, 4] if flip else list(range(6))  # both orientations as input
    points = np.zeros((10, 3))
    points[numbering] = WEDGE
    cell = _collapsed(COLLAPSE_PATTERNS[index], numbering[order])
    hexahedron = np.arange(8) + 10  # an ordinary hexahedron beside it
    points = np.vstack([points, rng.random((8, 3))])
    wedge, nodes = collapsed_wedges(np.vstack([cell, hexahedron]), points)
    assert wedge.tolist() == [True, False] and nodes.shape == (1, 6)
    got = nodes[0]
    triangles = {frozenset(got[:3].tolist()), frozenset(got[3:].tolist())}
    assert triangles == {frozenset(numbering[:3].tolist()), frozenset(numbering[3:].tolist())}
    partner = dict(zip(numbering[:3].tolist(), numbering[3:].tolist()))
    partner.update({v: k for k, v in partner.items()})
    assert all(partner[int(got[i])] == int(got[i + 3]) for i in range(3))
    assert _is_vtk_wedge(points[got])


def test_cells_repeating_nodes_otherwise_are_refused() -> None:
    points = np.random.default_rng(0).random((8, 3))
    diagonal = np.array([[0, 1, 2, 3, 4, 5, 6, 7], [0, 1, 2, 3, 4, 5, 6, 1]])
    with pytest.raises(ValueError, match="cell 1 repeats nodes"):
        collapsed_wedges(diagonal, points)
    three = np.array([[0, 0, 2, 2, 4, 4, 6, 7]])  # three collapsed edges
    with pytest.raises(ValueError, match="cell 0 repeats nodes"):
        collapsed_wedges(three, points)
    with pytest.raises(ValueError, match=r"shape \(n, 8\)"):
        collapsed_wedges(np.zeros((2, 6), int), points)


def test_file_holds_the_mesh_and_every_step(tmp_path: Path) -> None:
    """Hexahedra and wedges with their nodes, exact coordinates and values; complete after
    each write; bad fields and writes after close refused."""
    rng = np.random.default_rng(1)
    points = np.vstack([WEDGE, rng.random((8, 3)) + 2.0])
    cells = np.array([[0, 1, 2, 2, 3, 4, 5, 5], np.arange(6, 14)])
    path = tmp_path / "mixed.xdmf"
    writer = MixedXdmfFile(path, points, cells)
    read_points, read_cells, steps = read_xdmf(path)  # a valid file before any step
    assert steps == [] and np.array_equal(read_points, points)
    assert [c[0] for c in read_cells] == [XDMF_WEDGE, XDMF_HEXAHEDRON]
    assert set(read_cells[0][1].tolist()) == set(range(6))
    assert _is_vtk_wedge(points[read_cells[0][1]])
    assert read_cells[1][1].tolist() == list(range(6, 14))
    values = [rng.standard_normal((14, 3)) / 3.0 for _ in range(2)]
    for t, u in zip((0.5, 1.0), values):
        writer.write(t, {"u": u, "p": u[:, 0]})
        _, _, steps = read_xdmf(path)
        assert steps[-1]["t"] == t
        assert np.array_equal(steps[-1]["u"], u)  # shortest round-trip decimals: exact
        assert np.array_equal(steps[-1]["p"][:, 0], u[:, 0])
    assert len(steps) == 2
    with pytest.raises(ValueError, match=r"field 'p' must have shape \(14,\)"):
        writer.write(2.0, {"p": np.zeros(3)})
    writer.close()
    with pytest.raises(ValueError, match="is closed"):
        writer.write(2.0, {"u": values[0]})
    with pytest.raises(ValueError, match="must index the 14 points"):
        MixedXdmfFile(tmp_path / "bad.xdmf", points, cells + 1)
