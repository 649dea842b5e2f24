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
    WedgeRotationError,
    collapse_wedges,
    collapsed_jacobians,
    rotated_wedges,
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
