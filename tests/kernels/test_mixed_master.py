"""A master surface of 8-node quadrilaterals and 6-node triangles (docs/method.md §38.8).

One triangulation and one search over both kinds (:class:`MasterSurface` with ``more``): the
walk crosses from one kind to the other, and the nodal normals at the nodes both kinds share sum
the unit normals of all faces around them, as ccx's one surface does.
"""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.faces import QUAD8, TRI6
from dolfinx_ntf.kernels.search import MasterFaceGroup, MasterSurface


def _surface(slope: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A quad8 face on [0, 1]^2 beside two tri6 faces on [1, 2] x [0, 1], folded at x = 1.

    The triangles rise as ``z = slope (x - 1)``. Returns coordinates, quad8 and tri6 faces.
    """
    index: dict[tuple, int] = {}
    points: list[tuple] = []

    def node(x: float, y: float) -> int:
        key = (round(x, 9), round(y, 9))
        if key not in index:
            index[key] = len(points)
            points.append((x, y, slope * max(x - 1.0, 0.0)))
        return index[key]

    def mid(a: tuple, b: tuple) -> int:
        return node((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)

    q = [(0, 0), (1, 0), (1, 1), (0, 1)]
    quad = [node(*p) for p in q] + [mid(q[i], q[(i + 1) % 4]) for i in range(4)]
    tris = []
    for t in (((1, 0), (2, 0), (2, 1)), ((1, 0), (2, 1), (1, 1))):
        tris.append([node(*p) for p in t] + [mid(t[i], t[(i + 1) % 3]) for i in range(3)])
    return np.array(points, float), np.array([quad]), np.array(tris)


def test_search_walks_across_the_two_kinds():
    """Points over the quadrilateral and over each triangle find their face, from any start."""
    x, quad, tris = _surface(0.0)
    master = MasterSurface(QUAD8, quad, more=((TRI6, tris),), coords=x)
    assert master.num_faces == 3
    np.testing.assert_array_equal(master.group_offsets, [0, 1, 3])
    assert master.faces.shape == (3, 8) and np.all(master.faces[1:, 6:] == -1)
    points = np.array([[0.3, 0.6, 0.05], [1.8, 0.2, -0.05], [1.2, 0.8, 0.02], [2.5, 0.5, 0.0]])
    expected = [0, 1, 2, -1]
    np.testing.assert_array_equal(master.locate(points, 1e-9), expected)
    for start in range(3):  # walks from every face, across the fold between the kinds
        found = master.locate(points, 1e-9, start_faces=np.full(4, start))
        np.testing.assert_array_equal(found, expected)
    # the patches: every face touches the others at a corner, across the kinds
    _, patch = master.face_patches(np.array([0]))
    assert sorted(patch.tolist()) == [0, 1, 2]


@pytest.mark.parametrize("slope", [0.0, 0.7])
def test_nodal_normals_sum_both_kinds(slope):
    """At the fold the nodal normal is the normalized sum of the unit normals of the faces of
    both kinds around the node (the quadrilateral's and one or two triangles')."""
    x, quad, tris = _surface(slope)
    master = MasterSurface(QUAD8, quad, more=((TRI6, tris),), coords=x)
    flat = np.array([0.0, 0.0, 1.0])
    tilted = np.array([-slope, 0.0, 1.0]) / np.hypot(slope, 1.0)
    count_quad = np.isin(master.nodes, quad).astype(float)
    count_tri = np.array([np.sum(tris == n) for n in master.nodes], float)
    expected = count_quad[:, None] * flat + count_tri[:, None] * tilted
    expected /= np.linalg.norm(expected, axis=1)[:, None]
    np.testing.assert_allclose(master.nodal_normals, expected, atol=1e-14)
    if slope:  # the fold's nodes differ from both kinds' own normals
        fold = np.isclose(x[master.nodes, 0], 1.0)
        assert np.all(np.abs(master.nodal_normals[fold] - flat).max(axis=1) > 0.05)
        assert np.all(np.abs(master.nodal_normals[fold] - tilted).max(axis=1) > 0.05)


def test_one_kind_is_unchanged():
    """Without ``more`` (or with an empty group) the surface is the one-type surface."""
    x, _, tris = _surface(0.7)
    one = MasterSurface(TRI6, tris, coords=x)
    empty = MasterSurface(TRI6, tris, coords=x, more=((QUAD8, np.zeros((0, 8), np.int64)),))
    for name in ("faces", "triangles", "triangle_faces", "triangle_neighbours", "nodal_normals"):
        np.testing.assert_array_equal(getattr(one, name), getattr(empty, name))


def test_a_face_of_the_other_kind_is_checked():
    """A malformed face of the added kind is an error naming the surface."""
    _, quad, tris = _surface(0.0)
    with pytest.raises(ValueError, match=r"'m': faces must have shape \(F, 6\) for tri6"):
        MasterSurface(QUAD8, quad, more=((TRI6, tris[:, :5]),), name="m")
    flipped = tris.copy()
    flipped[0, [1, 2]] = flipped[0, [2, 1]]
    flipped[0, [3, 5]] = flipped[0, [5, 3]]
    with pytest.raises(ValueError, match="inconsistently oriented"):
        MasterSurface(QUAD8, quad, more=((TRI6, flipped),), name="m")


def test_groups_share_one_search_and_follow_the_surface():
    """The views of the two types: each keeps its own faces (group numbers, -1 for the other
    type's), a point is in at most one group, and a search after the surface moved (the same
    points) is a new one."""
    x, quad, tris = _surface(0.0)
    master = MasterSurface(QUAD8, quad, more=((TRI6, tris),), coords=x)
    quads, triangles = MasterFaceGroup.groups(master, "m")
    assert (quads.face_type, triangles.face_type) == (QUAD8, TRI6)
    points = np.array([[0.3, 0.6, 0.05], [1.8, 0.2, -0.05], [1.2, 0.8, 0.02]])
    for view in (quads, triangles):
        view.update(x)
    np.testing.assert_array_equal(quads.locate(points, 1e-9), [0, -1, -1])
    np.testing.assert_array_equal(triangles.locate(points, 1e-9), [-1, 0, 1])
    _, patch = triangles.face_patches(np.array([0]))
    assert sorted(patch.tolist()) == [0, 1]  # its own type's faces only, in its numbering
    moved = x + np.array([1.0, 0.0, 0.0])  # the surface slides by 1 in x under the points
    for view in (quads, triangles):
        view.update(moved)
    np.testing.assert_array_equal(quads.locate(points, 1e-9), [-1, 0, 0])
    np.testing.assert_array_equal(triangles.locate(points, 1e-9), [-1, -1, -1])
