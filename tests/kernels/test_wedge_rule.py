"""ccx's two-point C3D6 rule on collapsed hexahedra (kernels/wedge_rule.py, §30.5)."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.wedge_rule import (
    DOLFINX_HEXAHEDRON,
    NUM_CLASSES,
    VTK_HEXAHEDRON,
    collapse_classes,
    collapses,
    wedge_rule,
)

VERTICES = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=float)


def _hex_map(nodes: np.ndarray, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Trilinear map of ``[0, 1]^3`` (dolfinx's vertex order): position and Jacobian at ``xi``."""
    x, y, z = xi
    n = np.array([(x if v[0] else 1 - x) * (y if v[1] else 1 - y) * (z if v[2] else 1 - z)
                  for v in VERTICES])  # fmt: skip
    dn = np.empty((8, 3))
    for i, v in enumerate(VERTICES):
        f = [(t if v[a] else 1 - t) for a, t in enumerate(xi)]
        d = [1.0 if v[a] else -1.0 for a in range(3)]
        dn[i] = [d[0] * f[1] * f[2], f[0] * d[1] * f[2], f[0] * f[1] * d[2]]
    return n @ nodes, nodes.T @ dn


def _collapsed_cell(rule_class: int) -> np.ndarray:
    """Vertex numbers 0..7 of a hexahedron with the face of ``rule_class`` collapsed."""
    c, rest = divmod(rule_class, 4)
    k, s = divmod(rest, 2)
    f = [a for a in range(3) if a != c][k]
    cell = np.arange(8)
    for v in range(8):
        if VERTICES[v, f] == s and VERTICES[v, c] == 1:
            cell[v] = v - (1 << c)  # the edge along c shrinks to its first vertex
    return cell


@pytest.mark.parametrize("rule_class", range(NUM_CLASSES))
def test_classes_found(rule_class: int) -> None:
    cells = np.array([_collapsed_cell(rule_class), np.arange(8)])
    assert collapse_classes(cells).tolist() == [rule_class, -1]
    crossed = np.arange(8)
    crossed[[1, 4]] = [0, 0]  # two edges from vertex 0, not parallel
    assert collapse_classes(crossed[None]).tolist() == [-1]
    one = np.arange(8)
    one[1] = 0  # one edge only
    assert collapse_classes(one[None]).tolist() == [-1]


@pytest.mark.parametrize("rule_class", range(NUM_CLASSES))
def test_rule_is_ccx_wedge_rule(rule_class: int) -> None:
    """The points map to the triangle's centroid at ccx's thickness Gauss points; weights x |J|
    equal ccx's wedge weights x its Jacobian; a quadratic in the thickness integrates exactly."""
    rng = np.random.default_rng(rule_class)
    cell = _collapsed_cell(rule_class)
    unique = np.unique(cell)
    points, weights = wedge_rule(rule_class)
    c, rest = divmod(rule_class, 4)
    f = [a for a in range(3) if a != c][rest // 2]
    t = 3 - c - f
    # a prism: a random triangle (bottom, t = 0) translated by a random vector (top)
    shift = np.zeros(3)
    shift[t] = 1.0
    shift += 0.2 * rng.standard_normal(3)
    corners = {
        v: VERTICES[v] + 0.15 * rng.standard_normal(3) for v in unique if VERTICES[v, t] == 0
    }
    corners.update({v + (1 << t): corners[v] + shift for v in list(corners)})
    nodes = np.array([corners[v] for v in cell])
    bottom = np.array([corners[v] for v in corners if VERTICES[v, t] == 0])
    assert bottom.shape == (3, 3)
    total = 0.0
    for p, w, gauss in zip(points, weights, (-1.0, 1.0) / np.sqrt(3.0)):
        x, J = _hex_map(nodes, p)
        # ccx's point: the triangle's centroid at the Gauss point of the thickness in [-1, 1]
        np.testing.assert_allclose(x, bottom.mean(axis=0) + (1 + gauss) / 2 * shift, atol=1e-12)
        total += w * np.linalg.det(J)
    volume = 0.5 * np.linalg.norm(np.cross(bottom[1] - bottom[0], bottom[2] - bottom[0]))
    volume *= abs(shift @ np.cross(bottom[1] - bottom[0], bottom[2] - bottom[0])) / (2 * volume)
    assert np.isclose(total, volume, rtol=1e-12)  # the prism's volume, as ccx's rule gives it
    assert np.isclose(weights.sum(), 0.75)


def test_bad_class() -> None:
    with pytest.raises(ValueError, match=r"collapse class must be in 0\.\.11"):
        wedge_rule(12)


@pytest.mark.parametrize("rule_class", range(NUM_CLASSES))
def test_one_source_for_both_vertex_numberings(rule_class: int) -> None:
    """A collapse has one class in dolfinx's and VTK's numbering (the rule's and the XDMF
    writer's), and its wedge is the same six corners: the triangles at the two ends of the
    thickness axis, partners across it."""
    dolfinx_cell = _collapsed_cell(rule_class)
    # VTK vertex j sits at VTK_HEXAHEDRON[j]: dolfinx's vertex x + 2 y + 4 z
    vtk_cell = dolfinx_cell[VTK_HEXAHEDRON @ np.array([1, 2, 4])]
    assert collapse_classes(vtk_cell[None], VTK_HEXAHEDRON).tolist() == [rule_class]
    assert collapse_classes(dolfinx_cell[None]).tolist() == [rule_class]
    for vertices, cell in ((DOLFINX_HEXAHEDRON, dolfinx_cell), (VTK_HEXAHEDRON, vtk_cell)):
        (collapse,) = [c for c in collapses(vertices) if c.rule_class == rule_class]
        wedge = np.array(collapse.wedge)
        c, rest = divmod(rule_class, 4)
        t = 3 - c - [a for a in range(3) if a != c][rest // 2]
        assert set(vertices[wedge[:3], t].tolist()) == {vertices[wedge[0], t]}  # one triangle
        assert (vertices[wedge[3:], t] == 1 - vertices[wedge[:3], t]).all()  # partners across
        assert np.unique(cell[wedge]).size == 6  # the six distinct nodes of the cell
    assert len({c.rule_class for c in collapses(VTK_HEXAHEDRON)}) == NUM_CLASSES


def test_other_repeats_have_no_class() -> None:
    """A collapsed cell that repeats a further node is no wedge (-1), in both numberings."""
    cell = _collapsed_cell(0)
    assert collapse_classes(cell[None]).tolist() == [0]
    free = [v for v in range(8) if (cell == v).sum() == 1 and cell[v] == v]  # not collapsed
    assert len(free) == 4
    cell[free[-1]] = cell[free[0]]  # a third repeat
    assert collapse_classes(cell[None]).tolist() == [-1]
    assert collapse_classes(cell[None], VTK_HEXAHEDRON).tolist() == [-1]
