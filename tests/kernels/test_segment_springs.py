"""Tests of the 2D node-to-segment springs (dolfinx_ntf.kernels.segment_springs), pure numpy."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.spring_differences import nodal_differences

from dolfinx_ntf.kernels.edges import EDGE_TYPES, LINE2, LINE3, EdgeType, edge_spring_areas
from dolfinx_ntf.kernels.laws import ExponentialLaw, LinearLaw, TabularLaw
from dolfinx_ntf.kernels.segment_springs import evaluate_segment_springs, project_onto_edges

LAWS = {
    "linear": LinearLaw(slope=1.0e3, tension=0.5, c0=1e-3),
    "exponential": ExponentialLaw(c0=0.2, p0=3.0),
    "tabular": TabularLaw([0.0, 50.0, 400.0], [0.0, 0.05, 0.2]),
}


def _edges(edge_type: EdgeType, num: int, rng: np.random.Generator, bow: float) -> np.ndarray:
    """(num, n, 2) rotated, translated edges of length ~2; line3 bowed by ``bow``."""
    coords = np.zeros((num, edge_type.num_nodes, 2))
    coords[:, 0, 0], coords[:, 1, 0] = -1.0, 1.0
    coords[:, :2] += 0.05 * rng.uniform(-1, 1, (num, 2, 2))
    if edge_type.num_nodes == 3:
        coords[:, 2] = 0.5 * (coords[:, 0] + coords[:, 1]) + [0.0, bow]
    angle = rng.uniform(0, 2 * np.pi, num)
    rot = np.stack([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]).transpose(
        2, 0, 1
    )
    return np.einsum("nij,nkj->nki", rot, coords) + rng.uniform(-5, 5, (num, 1, 2))


def _slaves(edge_type: EdgeType, edges: np.ndarray, xi: np.ndarray, gap: np.ndarray) -> np.ndarray:
    """Points at clearance ``gap`` along the normal of the edge points ``xi``."""
    q = np.einsum("nj,njc->nc", edge_type.shape_functions(xi[:, None]), edges)
    t = np.einsum("nj,njc->nc", edge_type.shape_derivatives(xi[:, None]), edges)
    normal = np.stack([t[:, 1], -t[:, 0]], axis=1) / np.linalg.norm(t, axis=1)[:, None]
    return q + gap[:, None] * normal


def _fd_stiffness(edge_type, master, slave, areas, law, h=1e-6, **options):
    """Central differences of the forces by the 2(n+1) nodal coordinates."""
    n = edge_type.num_nodes
    x = np.concatenate([master, slave[:, None]], axis=1)  # (N, n+1, 2)

    def forces(y: np.ndarray) -> np.ndarray:
        return evaluate_segment_springs(
            edge_type, y[:, :n], y[:, n], areas, law, tangent=False, **options
        ).forces

    return nodal_differences(forces, (x,), h)


@pytest.mark.parametrize("law_name", sorted(LAWS))
@pytest.mark.parametrize("edge_name", sorted(EDGE_TYPES))
def test_tangent_matches_finite_differences_inside(edge_name: str, law_name: str) -> None:
    """Interior projections: the exact tangent equals central differences and is symmetric."""
    edge_type, law = EDGE_TYPES[edge_name], LAWS[law_name]
    rng = np.random.default_rng(3)
    num = 12
    master = _edges(edge_type, num, rng, bow=0.25)
    xi = rng.uniform(-0.8, 0.8, num)
    slave = _slaves(edge_type, master, xi, rng.uniform(-0.04, -0.005, num))
    areas = rng.uniform(0.5, 1.5, num)
    ev = evaluate_segment_springs(edge_type, master, slave, areas, law)
    fd = _fd_stiffness(edge_type, master, slave, areas, law)
    scale = np.abs(ev.stiffness).max(axis=(1, 2))[:, None, None]
    assert np.all(ev.normal_force > 0)
    assert np.max(np.abs(ev.stiffness - fd) / scale) < 1e-6
    assert np.max(np.abs(ev.stiffness - ev.stiffness.transpose(0, 2, 1)) / scale) < 1e-9


@pytest.mark.parametrize("edge_name", sorted(EDGE_TYPES))
def test_tangent_matches_finite_differences_clamped(edge_name: str) -> None:
    """Slave nodes beside the edge ends: ξ fixed at ±1, the exact tangent still matches."""
    edge_type, law = EDGE_TYPES[edge_name], LAWS["linear"]
    rng = np.random.default_rng(5)
    num = 10
    master = _edges(edge_type, num, rng, bow=0.2)
    end = np.where(np.arange(num) % 2, 1.0, -1.0)
    slave = _slaves(edge_type, master, end, np.full(num, -0.02))
    t_end = np.einsum("nj,njc->nc", edge_type.shape_derivatives(end[:, None]), master)
    slave += 0.05 * end[:, None] * t_end / np.linalg.norm(t_end, axis=1)[:, None]  # beyond
    ev = evaluate_segment_springs(edge_type, master, slave, np.ones(num), law)
    assert np.array_equal(ev.xi[:, 0], end)
    fd = _fd_stiffness(edge_type, master, slave, np.ones(num), law)
    scale = np.abs(ev.stiffness).max(axis=(1, 2))[:, None, None]
    assert np.max(np.abs(ev.stiffness - fd) / scale) < 1e-6


def test_flat_edge_gap_normal_and_forces() -> None:
    """A node 0.01 below the middle of the edge (0,0)-(2,0) of a body above it."""
    law = LinearLaw(slope=100.0, tension=1.0)
    master = np.array([[[0.0, 0.0], [2.0, 0.0]]])  # body on the left of 0->1: above
    slave = np.array([[0.5, 0.01]])
    ev = evaluate_segment_springs(LINE2, master, slave, np.array([2.0]), law)
    assert np.allclose(ev.normal, [[0.0, -1.0]])
    assert ev.gap[0] == pytest.approx(-0.01)
    assert ev.xi[0, 0] == pytest.approx(-0.5)
    force = float(law.spring_force(np.array([0.01]), np.array([2.0]))[0][0])
    assert force > 0.0
    assert ev.normal_force[0] == pytest.approx(force)
    assert np.allclose(ev.forces[0, -1], [0.0, force])  # pushes the slave node out (upwards)
    assert np.allclose(ev.forces[0, :2].sum(axis=0), [0.0, -force])  # equal and opposite
    assert np.allclose(ev.forces[0, :2, 1], [-0.75 * force, -0.25 * force])  # φ = (3/4, 1/4)


def test_quadratic_projection_is_closest_point() -> None:
    """line3: the projection is the closest point of a densely sampled arc."""
    rng = np.random.default_rng(7)
    master = _edges(LINE3, 20, rng, bow=0.4)
    slave = master[:, 2] + rng.uniform(-0.6, 0.6, (20, 2))
    xi = project_onto_edges(LINE3, master, slave)[:, 0]
    samples = np.linspace(-1, 1, 20001)
    points = np.einsum("sj,njc->nsc", LINE3.shape_functions(samples[:, None]), master)
    best = samples[np.argmin(np.linalg.norm(points - slave[:, None], axis=2), axis=1)]
    assert np.max(np.abs(xi - best)) < 2e-4


def test_edge_spring_areas_are_tributary_lengths() -> None:
    """Nodes 0-1-2 on a polyline with edges of length 1 and 3; line3 takes Simpson's weights."""
    coords = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 3.0, 0.0], [0.5, 0.0, 0.0]])
    areas = edge_spring_areas(LINE2, np.array([[0, 1], [1, 2]]), coords, np.array([0, 1, 2]))
    assert np.allclose(areas, [0.5, 2.0, 1.5])
    quadratic = edge_spring_areas(LINE3, np.array([[0, 1, 3]]), coords, np.array([3, 0, 1]))
    assert np.allclose(quadratic, [2 / 3, 1 / 6, 1 / 6])


@pytest.mark.parametrize("edge_type", [LINE2, LINE3], ids=lambda e: e.name)
def test_fallback_area_of_faceless_nodes(edge_type):
    """A = 0: |q_xi| (default), times a factor, and as a ring times 2 pi r at the projection
    point (ccx's 4|m| of an expanded master face, docs/method.md §26.3); given areas unchanged."""
    rng = np.random.default_rng(3)
    edges = _edges(edge_type, 6, rng, 0.1) + np.array([20.0, 0.0])  # radius ~20
    xi = rng.uniform(-0.8, 0.8, 6)
    slaves = _slaves(edge_type, edges, xi, np.full(6, -0.01))
    areas = np.array([0.0, 0.0, 0.0, 1.5, 0.0, 2.5])
    law = LAWS["exponential"]
    plain = evaluate_segment_springs(edge_type, edges, slaves, areas, law, tangent=False)
    q = np.einsum("nj,njc->nc", edge_type.shape_functions(plain.xi), edges)
    t = np.einsum("nj,njc->nc", edge_type.shape_derivatives(plain.xi), edges)
    length = np.linalg.norm(t, axis=1)
    zero = areas == 0.0
    np.testing.assert_allclose(plain.area[zero], length[zero], rtol=1e-12)
    ring = evaluate_segment_springs(
        edge_type, edges, slaves, areas, law, tangent=False, fallback_factor=2.0,
        fallback_ring=True,
    )  # fmt: skip
    expected = 2.0 * length * 2 * np.pi * q[:, 0]
    np.testing.assert_allclose(ring.area[zero], expected[zero], rtol=1e-12)
    np.testing.assert_array_equal(ring.area[~zero], areas[~zero])
    ratio = ring.normal_force[zero] / plain.normal_force[zero]
    np.testing.assert_allclose(ratio, (expected / length)[zero], rtol=1e-12)  # F = A p(d)
