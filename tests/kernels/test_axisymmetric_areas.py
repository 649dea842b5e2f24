"""Axisymmetric spring areas (dolfinx_ntf.kernels.edges.axisymmetric_edge_spring_areas), numpy."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.edges import (
    LINE2,
    LINE3,
    EdgeType,
    axisymmetric_edge_spring_areas,
    ccx_edge_spring_areas,
    edge_spring_area_gradients,
    edge_spring_areas,
)


def _chain(edge_type: EdgeType, r: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edges along the polyline of corner points (r, z): line3 adds the midpoints."""
    corners = np.stack([r, z], axis=1)
    num = corners.shape[0] - 1
    if edge_type.num_nodes == 2:
        return corners, np.stack([np.arange(num), np.arange(1, num + 1)], axis=1)
    mid = 0.5 * (corners[:-1] + corners[1:])
    coords = np.vstack([corners, mid])
    edges = np.stack([np.arange(num), np.arange(1, num + 1), corners.shape[0] + np.arange(num)], 1)
    return coords, edges


@pytest.mark.parametrize("edge_type", [LINE2, LINE3], ids=["line2", "line3"])
def test_ring_areas_sum_to_the_surface_of_revolution(edge_type: EdgeType) -> None:
    """A graded flat disc (from the axis) and a cone: Σ A_p = pi R² and pi (r1 + r2) L exactly."""
    r = np.array([0.0, 0.1, 0.25, 0.5, 1.0])
    coords, edges = _chain(edge_type, r, np.zeros_like(r))
    nodes = np.arange(coords.shape[0])
    areas = axisymmetric_edge_spring_areas(edge_type, edges, coords, nodes)
    assert areas.sum() == pytest.approx(np.pi, rel=1e-13)
    # The axis node: a line2 share 2 pi L²/6; a line3 corner's consistent share is 0 (not < 0).
    if edge_type is LINE2:
        assert areas[0] == pytest.approx(2 * np.pi * 0.1**2 / 6, rel=1e-13)
    else:
        assert areas[0] == 0.0
    assert np.all(areas[1:] > 0) and np.all(np.isfinite(areas))
    r2, z2 = np.array([0.5, 1.0, 2.0]), np.array([0.0, 1.0, 3.0])
    coords, edges = _chain(edge_type, r2, z2)
    areas = axisymmetric_edge_spring_areas(edge_type, edges, coords, np.arange(coords.shape[0]))
    lengths = np.hypot(np.diff(r2), np.diff(z2))
    assert areas.sum() == pytest.approx(np.pi * np.sum((r2[:-1] + r2[1:]) * lengths), rel=1e-13)


def test_ring_areas_are_the_consistent_loads_of_a_uniform_pressure() -> None:
    """line2: A_p = 2 pi Σ_e L_e (2 r_p + r_q)/6; inside a uniform mesh 2 pi r_p L_p."""
    r = np.array([0.0, 0.2, 0.4, 0.6, 1.0])
    coords, edges = _chain(LINE2, r, np.zeros_like(r))
    areas = axisymmetric_edge_spring_areas(LINE2, edges, coords, np.arange(r.size))
    expected = np.zeros_like(r)
    for i, j in edges:
        length = r[j] - r[i]
        expected[i] += 2 * np.pi * length * (2 * r[i] + r[j]) / 6
        expected[j] += 2 * np.pi * length * (2 * r[j] + r[i]) / 6
    np.testing.assert_allclose(areas, expected, rtol=1e-13)
    assert areas[0] == pytest.approx(2 * np.pi * 0.2**2 / 6, rel=1e-13)  # on the axis: not 0
    tributary = edge_spring_areas(LINE2, edges, coords, np.arange(r.size))
    assert areas[1] == pytest.approx(2 * np.pi * r[1] * tributary[1], rel=1e-13)
    assert areas[2] == pytest.approx(2 * np.pi * r[2] * tributary[2], rel=1e-13)


def test_ring_areas_of_a_curved_line3_edge() -> None:
    """An arc of a unit circle (one line3 edge, to t = pi/8): the cap's area 2 pi (1 - cos t)."""
    t = np.array([0.0, np.pi / 8, np.pi / 16])
    coords = np.stack([np.sin(t), 1 - np.cos(t)], axis=1)
    areas = axisymmetric_edge_spring_areas(LINE3, np.array([[0, 1, 2]]), coords, np.arange(3))
    assert areas.sum() == pytest.approx(2 * np.pi * (1 - np.cos(np.pi / 8)), rel=1e-3)


def test_slave_nodes_off_the_edges_and_negative_radii() -> None:
    coords, edges = _chain(LINE2, np.array([0.0, 1.0]), np.zeros(2))
    areas = axisymmetric_edge_spring_areas(LINE2, edges, np.vstack([coords, [5.0, 5.0]]), [0, 2])
    assert areas[1] == 0.0 and areas[0] > 0.0
    coords[0, 0] = -1e-12  # round-off across the axis: clamped
    assert np.isfinite(axisymmetric_edge_spring_areas(LINE2, edges, coords, [0, 1])).all()
    coords[0, 0] = -0.01
    with pytest.raises(ValueError, match=r"need r = x\[0\] >= 0; 1 slave edge.*node 0"):
        axisymmetric_edge_spring_areas(LINE2, edges, coords, [0, 1])


@pytest.mark.parametrize("edge_type", [LINE2, LINE3], ids=["line2", "line3"])
@pytest.mark.parametrize("axisymmetric", [False, True], ids=["plane", "axisymmetric"])
def test_area_gradients_match_finite_differences(edge_type: EdgeType, axisymmetric: bool) -> None:
    """∂A_p/∂x_q of every slave node against central differences (linearize_area in 2D)."""
    rng = np.random.default_rng(3)
    r = np.array([0.0, 0.3, 0.7, 1.2])
    coords, edges = _chain(edge_type, r, 0.2 * rng.standard_normal(r.size))
    coords = coords + 0.03 * rng.standard_normal(coords.shape)
    coords[0, 0] = 0.05  # near the axis (on it, r may not decrease)
    slaves = np.arange(coords.shape[0] - 1)  # the last node is on an edge but not a slave

    def areas(x: np.ndarray) -> np.ndarray:
        if axisymmetric:
            return axisymmetric_edge_spring_areas(edge_type, edges, x, slaves)
        return 2.5 * edge_spring_areas(edge_type, edges, x, slaves)

    index, node, gradient = edge_spring_area_gradients(
        edge_type, edges, coords, slaves, thickness=1.0 if axisymmetric else 2.5,
        axisymmetric=axisymmetric,
    )  # fmt: skip
    dense = np.zeros((slaves.size, coords.shape[0], 2))
    dense[index, node] = gradient
    fd = np.zeros_like(dense)
    h = 1e-6
    for q in range(coords.shape[0]):
        for c in range(2):
            plus, minus = coords.copy(), coords.copy()
            plus[q, c] += h
            minus[q, c] -= h
            fd[:, q, c] = (areas(plus) - areas(minus)) / (2 * h)
    np.testing.assert_allclose(dense, fd, rtol=0, atol=1e-7 * np.abs(fd).max())
    assert np.abs(dense).max() > 0.1


def test_ccx_shares_give_each_node_of_a_line2_ring_half_the_edge() -> None:
    """ccx's CAX weights: the same total as the consistent shares, split equally per edge."""
    r = np.array([0.0, 0.1, 0.25, 0.5, 1.0])
    z = np.array([0.0, 0.05, 0.0, 0.1, 0.0])
    coords, edges = _chain(LINE2, r, z)
    nodes = np.arange(coords.shape[0])
    ccx = ccx_edge_spring_areas(LINE2, edges, coords, nodes, axisymmetric=True)
    consistent = axisymmetric_edge_spring_areas(LINE2, edges, coords, nodes)
    assert ccx.sum() == pytest.approx(consistent.sum(), rel=1e-13)  # 2 pi ∫ r ds either way
    lengths = np.linalg.norm(np.diff(coords, axis=0), axis=1)
    halves = np.pi * lengths * (r[:-1] + r[1:]) / 2  # half the ring area of each edge
    expected = np.concatenate([halves, [0.0]]) + np.concatenate([[0.0], halves])
    np.testing.assert_allclose(ccx, expected, rtol=1e-13)
    # the node nearer the axis gets more than its consistent share, the outer one less
    assert ccx[0] > consistent[0] and ccx[-1] < consistent[-1]


def test_ccx_shares_of_line3_edges() -> None:
    """26/100, 26/100, 48/100 of each line3 edge's length times the thickness, or ring area."""
    r = np.array([0.2, 0.5, 1.0])
    z = np.array([0.0, 0.1, 0.0])
    coords, edges = _chain(LINE3, r, z)
    nodes = np.arange(coords.shape[0])
    plane = ccx_edge_spring_areas(LINE3, edges, coords, nodes, thickness=0.5)
    lengths = 0.5 * edge_spring_areas(LINE3, edges, coords, np.arange(coords.shape[0]))
    assert plane.sum() == pytest.approx(lengths.sum(), rel=1e-13)
    length = np.linalg.norm(np.diff(coords[:3], axis=0), axis=1)  # straight edges
    np.testing.assert_allclose(plane[3:], 0.5 * 0.48 * length, rtol=1e-13)  # midside nodes
    np.testing.assert_allclose(plane[0], 0.5 * 0.26 * length[0], rtol=1e-13)
    ring = ccx_edge_spring_areas(LINE3, edges, coords, nodes, axisymmetric=True)
    consistent = axisymmetric_edge_spring_areas(LINE3, edges, coords, nodes)
    assert ring.sum() == pytest.approx(consistent.sum(), rel=1e-13)
    totals = 2 * np.pi * length * (r[:-1] + r[1:]) / 2  # ring area of each straight edge
    np.testing.assert_allclose(ring[3:], 0.48 * totals, rtol=1e-13)
