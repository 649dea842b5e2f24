"""The stable search's tie-break (docs/method.md §3.2): a frame intrinsic to master and slave picks
the same faces under node renumbering and rigid rotation and translation of the model."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dolfinx_ntf.kernels.faces import QUAD4, TRI3
from dolfinx_ntf.kernels.search import MasterSurface
from dolfinx_ntf.kernels.tie_frame import frame_from_moments, point_moments, triangle_moments


def _grid(nx, ny, h=1.0, skip=()):
    """Flat quad4 grid (cells (a, b) not in ``skip``), outward normal +z; node id i + (nx+1) j."""
    j, i = np.divmod(np.arange((nx + 1) * (ny + 1)), nx + 1)
    coords = np.stack([h * i, h * j, np.zeros(i.size)], axis=1).astype(float)
    node = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1).T  # node[i, j]
    faces = [
        [node[a, b], node[a + 1, b], node[a + 1, b + 1], node[a, b + 1]]
        for a in range(nx)
        for b in range(ny)
        if (a, b) not in skip
    ]
    return coords, np.array(faces)


def _ties(nx, ny, h=1.0, lower=(1, 1), upper=(3, 4)):
    """Slave points on grid vertices and edge midpoints of a rectangle of the grid: all ties."""
    x = np.arange(2 * lower[0], 2 * upper[0] + 1) * 0.5 * h
    y = np.arange(2 * lower[1], 2 * upper[1] + 1) * 0.5 * h
    px, py = np.meshgrid(x, y, indexing="ij")
    return np.stack([px.ravel(), py.ravel(), np.zeros(px.size)], axis=1)


def _locate(coords, faces, points, use_frame):
    master = MasterSurface(QUAD4, faces, coords=coords)
    frame = None
    if use_frame:
        origin, moments = master.surface_moments()
        frame = frame_from_moments(
            moments + point_moments(points, np.ones(len(points)), origin), origin
        )
        assert frame is not None
    return master.locate(points, 1e-3, tie_frame=frame)


def _rotated_renumbered(coords, faces, points, seed):
    rng = np.random.default_rng(seed)
    rotation = Rotation.random(random_state=seed).as_matrix()
    shift = rng.uniform(-50.0, 50.0, 3)
    perm = rng.permutation(coords.shape[0])  # new id of each old node
    new_coords = np.empty_like(coords)
    new_coords[perm] = coords @ rotation.T + shift
    order = rng.permutation(faces.shape[0])  # new face k is old face order[k]
    return new_coords, perm[faces][order], points @ rotation.T + shift, order


# An L-shaped master without symmetry (4 x 3 cells, two corner cells missing), slave points over
# its vertices and edges.
SKIP = ((3, 2), (3, 1))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_stable_tie_break_invariant_under_rotation_and_renumbering(seed):
    coords, faces = _grid(4, 3, skip=SKIP)
    points = _ties(4, 3, lower=(1, 1), upper=(3, 2))
    reference = _locate(coords, faces, points, use_frame=True)
    assert np.all(reference >= 0)
    new_coords, new_faces, new_points, order = _rotated_renumbered(coords, faces, points, seed)
    found = _locate(new_coords, new_faces, new_points, use_frame=True)
    np.testing.assert_array_equal(order[found], reference)


def test_position_rule_depends_on_the_rotation():
    """The global-axes rule (CalculiX mode, and main's stable mode before) fails the test above:
    the ties are real and the choice matters."""
    coords, faces = _grid(4, 3, skip=SKIP)
    points = _ties(4, 3, lower=(1, 1), upper=(3, 2))
    reference = _locate(coords, faces, points, use_frame=False)
    differ = 0
    for seed in range(4):
        new_coords, new_faces, new_points, order = _rotated_renumbered(coords, faces, points, seed)
        found = _locate(new_coords, new_faces, new_points, use_frame=False)
        differ += np.count_nonzero(order[found] != reference)
    assert differ > 0


def test_frame_moves_with_the_model():
    coords, faces = _grid(4, 3, skip=SKIP)
    master = MasterSurface(QUAD4, faces, coords=coords)
    origin, moments = master.surface_moments()
    frame = frame_from_moments(moments, origin)
    rotation = Rotation.random(random_state=7).as_matrix()
    shift = np.array([3.0, -2.0, 10.0])
    moved = MasterSurface(QUAD4, faces, coords=coords @ rotation.T + shift)
    origin2, moments2 = moved.surface_moments()
    frame2 = frame_from_moments(moments2, origin2)
    np.testing.assert_allclose(frame2.origin, frame.origin @ rotation.T + shift, atol=1e-12)
    np.testing.assert_allclose(frame2.axes, frame.axes @ rotation.T, atol=1e-12)


def test_triangle_moments_are_exact():
    """Against the centroid rule on a fine sub-triangulation of one triangle (error O(1/n^2))."""
    a, b, c = np.array([0.1, 0.2, 0.3]), np.array([1.3, 0.1, -0.2]), np.array([0.4, 0.9, 0.5])
    origin = np.array([0.2, -0.1, 0.05])
    n = 200
    u, v = (w.ravel() for w in np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
    up = u + v < n
    down = u + v < n - 1
    # centroids (barycentric s, t) of the upward and downward sub-triangles, each of area A/n^2
    st = (
        np.concatenate(
            [
                np.stack([u[up] + 1 / 3, v[up] + 1 / 3], 1),
                np.stack([u[down] + 2 / 3, v[down] + 2 / 3], 1),
            ]
        )
        / n
    )
    points = a + st[:, :1] * (b - a) + st[:, 1:] * (c - a)
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a))
    exact = triangle_moments(a[None], b[None], c[None], origin)
    rule = point_moments(points, np.full(len(points), area / n**2), origin)
    assert exact[0] == pytest.approx(area)
    np.testing.assert_allclose(rule[:40], exact[:40], rtol=1e-4, atol=1e-4 * np.abs(exact).max())
    np.testing.assert_allclose(exact[40:], 0.5 * np.cross(b - a, c - a))


def test_symmetric_model_has_no_frame():
    """A square master with a centred slave: a half turn maps the model onto itself."""
    coords, faces = _grid(4, 4)
    master = MasterSurface(QUAD4, faces, coords=coords)
    origin, moments = master.surface_moments()
    points = _ties(4, 4, lower=(1, 1), upper=(3, 3))
    assert (
        frame_from_moments(moments + point_moments(points, np.ones(len(points)), origin), origin)
        is None
    )
    # the L-shaped master alone (tri3 faces): a frame
    coords, quads = _grid(4, 3, skip=SKIP)
    tri = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    surface = MasterSurface(TRI3, tri, coords=coords)
    assert frame_from_moments(*surface.surface_moments()[::-1]) is not None
