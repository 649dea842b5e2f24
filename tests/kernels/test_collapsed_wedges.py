"""Wedges as collapsed hexahedra (kernels/collapsed_wedges.py, docs/method.md §30 and §32).

The rules dolfinx needs (measured: it aborts otherwise): wedges on a shared triangle repeat the
same corner there; a collapsed edge belongs to one wedge (``shared=False``) or to two wedges with
no common face (``shared=True``).
"""

from collections import Counter
from itertools import combinations

import numpy as np
import pytest

from dolfinx_ntf.kernels.collapsed_wedges import (
    HEXAHEDRON_FACETS,
    WedgeRotationError,
    collapse_wedges,
    collapsed_jacobians,
    rotated_wedges,
    unmatched_neighbours,
    wedge_rotations,
)


def _split_layers(n: int, layers: int) -> tuple[np.ndarray, np.ndarray]:
    """An n x n grid of unit squares, each cut into two triangles, extruded into ``layers``.

    Returns the points and the wedges (counter-clockwise triangles below their copies above).
    """
    k = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = k[:-1, :-1].ravel(), k[1:, :-1].ravel(), k[1:, 1:].ravel(), k[:-1, 1:].ravel()
    triangles = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    i, j = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="ij")
    plane = np.column_stack([i.ravel(), j.ravel()])
    size = plane.shape[0]
    points = np.vstack([np.column_stack([plane, np.full(size, z)]) for z in range(layers + 1)])
    wedges = np.vstack(
        [np.hstack([triangles + z * size, triangles + (z + 1) * size]) for z in range(layers)]
    )
    return points, wedges


def _check_rules(rows: np.ndarray, rotation: np.ndarray, shared: bool) -> None:
    """The collapsed hexahedra obey dolfinx's rules (module docstring)."""
    hexahedra = collapse_wedges(rows, rotation)
    # every triangle shared by two wedges is the same facet (the same repeated corner) in both
    facets = Counter()
    for h in hexahedra.tolist():
        for face in (h[:4], h[4:]):
            facets[tuple(sorted(face))] += 1
    triangles = Counter(frozenset(t) for r in rows.tolist() for t in (r[:3], r[3:]))
    assert sum(v == 2 for v in facets.values()) == sum(v == 2 for v in triangles.values())
    users: dict[frozenset, list[int]] = {}
    for k, h in enumerate(hexahedra.tolist()):
        users.setdefault(frozenset((h[2], h[6])), []).append(k)
    for edge, wedges in users.items():
        assert len(wedges) <= (2 if shared else 1), edge
        if len(wedges) == 2:
            assert len(set(rows[wedges[0]]) & set(rows[wedges[1]])) == 2  # no common face


def test_collapsed_wedges_keep_the_wedge_and_its_orientation():
    points, rows = _split_layers(2, 1)
    rotation = np.arange(rows.shape[0]) % 3
    turned = rotated_wedges(rows, rotation)
    for row, new in zip(rows, turned):  # a cyclic renumbering of both triangles alike
        shift = int(np.flatnonzero(row[:3] == new[0])[0])
        assert np.array_equal(np.roll(row[:3], -shift), new[:3])
        assert np.array_equal(np.roll(row[3:], -shift), new[3:])
    det = collapsed_jacobians(points[collapse_wedges(rows, rotation)])
    assert np.all(det > 0)
    # each wedge's 8 Gauss weights sum to its volume (a unit right triangle times height 1)
    weights = det / 8.0
    np.testing.assert_allclose(weights.sum(axis=1), 0.5, rtol=1e-12)
    mirrored = rows[:, [0, 2, 1, 3, 5, 4]]
    assert np.all(collapsed_jacobians(points[collapse_wedges(mirrored, rotation)]) < 0)


def test_a_stack_of_wedges_is_turned_alike():
    _, rows = _split_layers(1, 4)
    rotation = wedge_rotations(rows)
    _check_rules(rows, rotation, shared=False)


def test_a_split_layer_has_more_wedges_than_edges_for_the_strict_rule():
    _, rows = _split_layers(3, 1)  # 18 wedges, 16 vertical edges
    with pytest.raises(WedgeRotationError, match="apart") as caught:
        wedge_rotations(rows)
    assert 0 <= caught.value.index < rows.shape[0]


@pytest.mark.parametrize(("n", "layers"), [(3, 1), (6, 3), (20, 1), (12, 4)])
def test_the_shared_rule_places_extruded_triangulations(n, layers):
    _, rows = _split_layers(n, layers)
    rotation = wedge_rotations(rows, shared=True)
    _check_rules(rows, rotation, shared=True)
    # the same rows give the same rotations (a seeded search)
    assert np.array_equal(rotation, wedge_rotations(rows, shared=True))


def test_the_shared_rule_refuses_more_stacks_than_twice_the_lines():
    """The 20 triangles of 6 points, one wedge each: 20 stacks for 6 vertical lines, each line
    the collapsed edge of at most two: no rotation exists, the search stops and names a wedge."""
    triangles = np.array(list(combinations(range(6), 3)))
    rows = np.hstack([triangles, triangles + 6])
    with pytest.raises(WedgeRotationError, match="at most two wedges") as caught:
        wedge_rotations(rows, shared=True)
    assert 0 <= caught.value.index < rows.shape[0]


@pytest.mark.parametrize("shared", [False, True])
def test_no_wedges_need_no_rotation(shared):
    rotation = wedge_rotations(np.zeros((0, 6), np.int64), shared=shared)
    assert rotation.shape == (0,)


# dolfinx's tensor order of a hexahedron's corners as (i, j, k) offsets
_TENSOR = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)])


def _grid_cells(n: int, layers: int, split: np.ndarray) -> np.ndarray:
    """Hexahedra of an n x n x layers grid (dolfinx order); where ``split`` (per cell), two
    collapsed wedges (dolfinx order, collapsed on the ``b``-``B`` or ``d``-``D`` edge) instead."""

    def vid(i, j, k):
        return i + (n + 1) * (j + (n + 1) * k)

    cells = []
    for index, (k, j, i) in enumerate(np.ndindex(layers, n, n)):
        h = [vid(i + a, j + b, k + c) for a, b, c in _TENSOR]
        if not split[index]:
            cells.append(h)
            continue
        v0, v1, v2, v3, v4, v5, v6, v7 = h  # the square v0 v1 v3 v2 cut along v0-v3
        cells += [[v0, v1, v3, v3, v4, v5, v7, v7], [v0, v2, v3, v3, v4, v6, v7, v7]]
    return np.array(cells, dtype=np.int64)


def _brute_force(cells: np.ndarray) -> set[tuple[int, int]]:
    """Pairs sharing three distinct vertices without two equal sorted facet lists (loops)."""
    keys = [{tuple(sorted(c[f].tolist())) for f in HEXAHEDRON_FACETS} for c in cells]
    return {
        (i, j)
        for i, j in combinations(range(len(cells)), 2)
        if len(set(cells[i].tolist()) & set(cells[j].tolist())) >= 3 and not keys[i] & keys[j]
    }


def test_a_conforming_mesh_has_no_unmatched_neighbours():
    """Hexahedra only, and wedges split alike in every layer (stacked triangles match)."""
    assert unmatched_neighbours(_grid_cells(3, 2, np.zeros(18, bool))).shape == (0, 2)
    assert unmatched_neighbours(_grid_cells(3, 2, np.ones(18, bool))).shape == (0, 2)


def test_wedge_triangles_on_a_quadrilateral_are_unmatched_neighbours():
    """A hexahedron below a split one: its top quadrilateral lies on the two wedge triangles."""
    cells = _grid_cells(1, 2, np.array([False, True]))
    assert unmatched_neighbours(cells).tolist() == [[0, 1], [0, 2]]
    # a triangle repeating another corner (10, 11, 11, 12 below 10, 11, 12, 12): unmatched too
    upper, lower = [10, 11, 12, 12, 20, 21, 22, 22], [0, 1, 1, 2, 10, 11, 11, 12]
    assert unmatched_neighbours(np.array([upper, lower])).tolist() == [[0, 1]]
    assert unmatched_neighbours(np.array([upper, [0, 1, 2, 2, 10, 11, 12, 12]])).size == 0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_unmatched_neighbours_equal_the_brute_force(seed):
    """Random mixes of hexahedra and split cells over 3 x 3 x 3: the loops' pairs."""
    split = np.random.default_rng(seed).random(27) < 0.5
    cells = _grid_cells(3, 3, split)
    pairs = unmatched_neighbours(cells)
    assert {tuple(p) for p in pairs.tolist()} == _brute_force(cells)
    assert len(pairs) > 0
