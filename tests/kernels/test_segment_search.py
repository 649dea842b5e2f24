"""The 2D master curve's search (docs/method.md §3.2 in 2D): the walk, depth limit, ties, errors."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from dolfinx_ntf.kernels.edges import LINE2
from dolfinx_ntf.kernels.segment_search import MasterCurve

#: Five nodes on the line y = 0 (x = 0 .. 4), the body below: edges run in -x (body on the left).
COORDS = np.column_stack([np.arange(5.0), np.zeros(5)])
EDGES = np.array([[i + 1, i] for i in range(4)])


def _curve(order=None) -> MasterCurve:
    edges = EDGES if order is None else EDGES[list(order)]
    return MasterCurve(LINE2, edges, name="line", coords=COORDS)


def test_walk_finds_the_edge_holding_each_point():
    curve = _curve()
    points = np.array([[0.3, 0.1], [1.7, -0.2], [3.5, 0.0], [3.99, 0.05], [5.5, 0.0]])
    located = curve.locate(points, 1e-9)
    assert [tuple(EDGES[f]) if f >= 0 else None for f in located] == [
        (1, 0), (2, 1), (4, 3), (4, 3), None,
    ]  # fmt: skip


def test_depth_limit_rejects_deep_points():
    curve = _curve()
    points = np.array([[1.5, -0.05], [1.5, -0.5]])
    assert (curve.locate(points, 1e-9, max_depth=0.1) >= 0).tolist() == [True, False]
    assert (curve.locate(points, 1e-9) >= 0).tolist() == [True, True]


def test_point_above_a_master_node_takes_the_edge_first_in_position_order():
    """A point exactly above node x = 1, 2 or 3 is held by both edges at that node; the edge whose
    midpoint comes first in (x, y) order takes it, whatever the order of the edges."""
    points = np.array([[1.0, 0.1], [2.0, 0.0], [3.0, -0.1]])
    for order in itertools.permutations(range(4)):
        curve = _curve(order)
        held = curve.faces[curve.locate(points, 1e-9)]
        assert held.tolist() == [[1, 0], [2, 1], [3, 2]], order


def test_branching_and_degenerate_curves_are_refused():
    with pytest.raises(ValueError, match="node 1 starts or ends more than one edge"):
        MasterCurve(LINE2, np.array([[1, 0], [1, 2]]), coords=COORDS)
    coords = COORDS.copy()
    coords[2] = coords[1]
    with pytest.raises(ValueError, match="edge 1 is degenerate"):
        MasterCurve(LINE2, EDGES, coords=coords)
