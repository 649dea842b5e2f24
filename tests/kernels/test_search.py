"""Master triangulation, bounding planes and triangle walk (docs/method.md §2.3, §3.2)."""

import numpy as np
import pytest

from dolfinx_ntf.kernels.faces import FACE_TYPES
from dolfinx_ntf.kernels.search import MasterSurface

ALL_TYPES = ["tri3", "quad4", "tri6", "quad8", "quad9"]
QUAD_TYPES = ["quad4", "quad8", "quad9"]


# --------------------------------------------------------------------------- mesh helpers
def _grid_faces(type_name: str, nx: int, ny: int) -> tuple[np.ndarray, np.ndarray]:
    """Faces of an nx x ny patch on a (2nx+1) x (2ny+1) parametric node grid.

    Returns the (F, n) faces and the (num_nodes, 2) parametric (u, v) grid coordinates in cell
    units. Faces are counter-clockwise in (u, v), so they face along x_u x x_v.
    """
    nu, nv = 2 * nx + 1, 2 * ny + 1
    iu, iv = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    uv = np.stack([iu.ravel(), iv.ravel()], axis=1) / 2.0

    def nid(i, j):
        return i * nv + j

    faces = []
    for i in range(0, 2 * nx, 2):
        for j in range(0, 2 * ny, 2):
            c = [nid(i, j), nid(i + 2, j), nid(i + 2, j + 2), nid(i, j + 2)]
            m = [nid(i + 1, j), nid(i + 2, j + 1), nid(i + 1, j + 2), nid(i, j + 1)]
            mc = nid(i + 1, j + 1)
            if type_name == "quad4":
                faces.append(c)
            elif type_name == "quad8":
                faces.append(c + m)
            elif type_name == "quad9":
                faces.append(c + m + [mc])
            elif type_name == "tri3":
                faces += [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
            elif type_name == "tri6":
                faces += [[c[0], c[1], c[2], m[0], m[1], mc], [c[0], c[2], c[3], mc, m[2], m[3]]]
            else:
                raise AssertionError(type_name)
    return np.array(faces, dtype=np.int64), uv


def _face_centres(surface: MasterSurface, coords: np.ndarray) -> np.ndarray:
    """Face points at the parametric centre of each face."""
    ft = surface.face_type
    phi = ft.shape_functions(ft.center)
    return np.einsum("j,fjc->fc", phi, coords[surface.faces])


def _flat(type_name: str, nx: int = 4, ny: int = 3) -> tuple[MasterSurface, np.ndarray]:
    faces, uv = _grid_faces(type_name, nx, ny)
    coords = np.column_stack([uv, np.zeros(len(uv))])
    return MasterSurface(FACE_TYPES[type_name], faces, coords=coords), coords


def _cylinder(type_name: str, radius: float = 2.0, nu: int = 8, nz: int = 4):
    """Patch of the cylinder r = radius, angles [0, 2π/3], outward (radial) normals."""
    faces, uv = _grid_faces(type_name, nu, nz)
    theta = uv[:, 0] * (2 * np.pi / 3) / nu
    coords = np.column_stack([radius * np.cos(theta), radius * np.sin(theta), 0.5 * uv[:, 1]])
    return MasterSurface(FACE_TYPES[type_name], faces, coords=coords), coords


def _wavy(type_name: str, seed: int, nx: int = 6, ny: int = 5):
    """Gently curved surface over an irregular (perturbed) grid."""
    faces, uv = _grid_faces(type_name, nx, ny)
    rng = np.random.default_rng(seed)
    xy = uv.copy()
    interior = (uv[:, 0] > 0) & (uv[:, 0] < nx) & (uv[:, 1] > 0) & (uv[:, 1] < ny)
    # Perturb corner-grid nodes only, then put midside nodes on the straight edges.
    xy[interior] += rng.uniform(-0.2, 0.2, size=(interior.sum(), 2))
    nv = 2 * ny + 1
    grid = xy.reshape(2 * nx + 1, nv, 2)
    grid[1::2, 0::2] = 0.5 * (grid[0:-1:2, 0::2] + grid[2::2, 0::2])
    grid[0::2, 1::2] = 0.5 * (grid[0::2, 0:-1:2] + grid[0::2, 2::2])
    grid[1::2, 1::2] = 0.25 * (
        grid[0:-1:2, 0:-1:2] + grid[2::2, 0:-1:2] + grid[0:-1:2, 2::2] + grid[2::2, 2::2]
    )
    xy = grid.reshape(-1, 2)
    z = 0.4 * np.sin(0.6 * xy[:, 0]) * np.cos(0.5 * xy[:, 1])
    coords = np.column_stack([xy, z])
    return MasterSurface(FACE_TYPES[type_name], faces, coords=coords), coords


def _brute_force(surface: MasterSurface, points: np.ndarray) -> np.ndarray:
    """(N, T) True where a point is inside (all distances <= 0) a triangle's prism."""
    num_tri = surface.triangles.shape[0]
    n = points.shape[0]
    pts = np.repeat(points, num_tri, axis=0)
    tri = np.tile(np.arange(num_tri), n)
    d = surface.plane_distances(pts, tri).reshape(n, num_tri, 3)
    return np.all(d <= 0.0, axis=2)


# --------------------------------------------------------------------------- structure
@pytest.mark.parametrize("type_name", ALL_TYPES)
def test_neighbours_are_symmetric_and_planes_shared(type_name):
    surface, _coords = _wavy(type_name, seed=1)
    tri, nb = surface.triangles, surface.triangle_neighbours
    t, edge = np.nonzero(nb >= 0)
    back = nb[nb[t, edge]]
    assert np.all(np.any(back == t[:, None], axis=1))
    # Boundary edges: only the outer rim of the patch (2(nx+ny) face edges).
    per_edge = FACE_TYPES[type_name].num_nodes // FACE_TYPES[type_name].num_corners
    n_rim = 2 * (6 + 5) * (1 if per_edge == 1 else 2)
    assert np.sum(nb < 0) == n_rim
    # The two triangles of an interior edge see the same plane with opposite sign, exactly.
    rng = np.random.default_rng(0)
    p = rng.uniform(-1, 7, size=(t.size, 3))
    d_t = surface.plane_distances(p, t)[np.arange(t.size), edge]
    nbt = nb[t, edge]
    l_nb = np.argmax(nb[nbt] == t[:, None], axis=1)
    d_nb = surface.plane_distances(p, nbt)[np.arange(t.size), l_nb]
    assert np.array_equal(d_t, -d_nb)
    # The edge node pairs match.
    e_t = np.sort(np.stack([tri[t, edge], tri[t, (edge + 1) % 3]], 1), 1)
    e_nb = np.sort(np.stack([tri[nbt, l_nb], tri[nbt, (l_nb + 1) % 3]], 1), 1)
    assert np.array_equal(e_t, e_nb)


def test_properties_and_nodal_normals_flat():
    surface, _coords = _flat("quad8", 3, 2)
    assert surface.num_faces == 6
    assert surface.triangles.shape == (36, 3)
    np.testing.assert_array_equal(surface.triangle_faces, np.repeat(np.arange(6), 6))
    # quad8 grid: every node except the face-centre ones.
    assert surface.nodes.size == 7 * 5 - 6
    np.testing.assert_allclose(surface.nodal_normals, np.tile([0.0, 0.0, 1.0], (29, 1)))
    np.testing.assert_allclose(surface.triangle_normals, np.tile([0.0, 0.0, 1.0], (36, 1)))


@pytest.mark.parametrize("type_name", QUAD_TYPES)
def test_nodal_normals_cylinder_are_radial(type_name):
    surface, coords = _cylinder(type_name)
    x = coords[surface.nodes]
    radial = x * np.array([1.0, 1.0, 0.0])
    radial /= np.linalg.norm(radial, axis=1)[:, None]
    n = surface.nodal_normals
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    # Nodes away from the patch rim: averaged normals are radial by symmetry.
    theta = np.arctan2(x[:, 1], x[:, 0])
    eps = 1e-9
    inner = (theta > eps) & (theta < 2 * np.pi / 3 - eps) & (x[:, 2] > eps) & (x[:, 2] < 2 - eps)
    assert inner.sum() > 10
    np.testing.assert_allclose(n[inner], radial[inner], atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", n, radial) > 0.9)


def test_nodal_normal_is_average_of_face_normals_at_fold():
    # Two quads folded 90 degrees along the edge (nodes 1, 4): normals +z and +x.
    coords = np.array(
        [[-1, 0, 0], [0, 0, 0], [0, 1, 0], [-1, 1, 0], [0, 0, -1], [0, 1, -1]], dtype=float
    )
    faces = np.array([[0, 1, 2, 3], [1, 4, 5, 2]])
    s = MasterSurface(FACE_TYPES["quad4"], faces, coords=coords)
    n = dict(zip(s.nodes.tolist(), s.nodal_normals))
    np.testing.assert_allclose(n[1], [1 / np.sqrt(2), 0, 1 / np.sqrt(2)])
    np.testing.assert_allclose(n[0], [0, 0, 1])
    np.testing.assert_allclose(n[5], [1, 0, 0])
    # The plane between the two faces bisects the fold (x = z): either side of it.
    p = np.array([[1.0, 0.5, 0.999], [1.0, 0.5, 1.001]])
    np.testing.assert_array_equal(s.locate(p, 0.0), [1, 0])


# --------------------------------------------------------------------------- locating
@pytest.mark.parametrize("type_name", ALL_TYPES)
def test_flat_points_above_and_below_each_face(type_name):
    surface, coords = _flat(type_name)
    centres = _face_centres(surface, coords)
    f = np.arange(surface.num_faces)
    for h in (0.3, -0.3, 5.0, -40.0):
        p = centres + np.array([0.0, 0.0, h])
        np.testing.assert_array_equal(surface.locate(p, 1e-3), f)
    # Random points inside each face (tri3/quad4 bilinear maps are affine here).
    rng = np.random.default_rng(3)
    ft = surface.face_type
    xi = rng.uniform(0.05, 0.45, size=(surface.num_faces, 2))
    if not ft.is_triangle:
        xi = 2 * xi * rng.choice([-1, 1], size=xi.shape)
    phi = ft.shape_functions(xi)
    p = np.einsum("fj,fjc->fc", phi, coords[surface.faces]) + np.array([0, 0, 0.1])
    np.testing.assert_array_equal(surface.locate(p, 0.0), f)


@pytest.mark.parametrize("type_name", ["tri3", "quad4", "quad8"])
def test_points_outside_surface_not_found(type_name):
    surface, _ = _flat(type_name, 4, 3)
    p = np.array(
        [
            [-0.01, 1.5, 0.2],
            [4.01, 1.5, -0.2],
            [2.0, -0.5, 0.0],
            [2.0, 3.2, 3.0],
            [-1.0, -1.0, 0.0],
            [10.0, 10.0, -1.0],
        ]
    )
    np.testing.assert_array_equal(surface.locate(p, 1e-3), -1)
    # Just inside the rim: found.
    q = np.array([[0.01, 1.5, 0.2], [3.99, 1.5, -0.2], [2.0, 0.01, 0.0], [2.0, 2.99, 3.0]])
    assert np.all(surface.locate(q, 1e-3) >= 0)


def test_tolerance_rule_on_interior_edge():
    # Two unit quads [0,1]x[0,1] (face 0) and [1,2]x[0,1] (face 1). A point at y = 0.6 near
    # x = 1 starts in face 0's triangle (2,3,4) (nearest centroid (2/3, 2/3)).
    coords = np.array(
        [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]], dtype=float
    )
    faces = np.array([[0, 1, 4, 3], [1, 2, 5, 4]])
    s = MasterSurface(FACE_TYPES["quad4"], faces, coords=coords)
    tol = 1e-3
    on_edge = np.array([[1.0, 0.6, 0.5]] * 3)
    first = s.locate(on_edge, tol)
    assert first[0] in (0, 1)
    assert np.all(first == first[0])
    np.testing.assert_array_equal(s.locate(on_edge, tol), first)  # deterministic
    assert first[0] == 0  # walk starts in face 0 and δ = 0 violates nothing
    np.testing.assert_array_equal(s.locate(on_edge, 0.0), first)
    # Inside face 1 by less than the tolerance: accepted in the start face 0.
    inside_tol = np.array([[1.0 + 0.5 * tol, 0.6, 0.5]])
    assert s.locate(inside_tol, tol)[0] == 0
    assert s.locate(inside_tol, 0.0)[0] == 1
    # Beyond the tolerance: walks to face 1.
    assert s.locate(np.array([[1.0 + 2 * tol, 0.6, 0.5]]), tol)[0] == 1
    # Per-point tolerances.
    two = np.array([[1.0 + 0.5 * tol, 0.6, 0.5]] * 2)
    np.testing.assert_array_equal(s.locate(two, np.array([tol, 0.0])), [0, 1])


@pytest.mark.parametrize("type_name", QUAD_TYPES)
def test_cylinder_radial_line_through_face_centre(type_name):
    radius = 2.0
    surface, coords = _cylinder(type_name, radius)
    centres = _face_centres(surface, coords)
    theta = np.arctan2(centres[:, 1], centres[:, 0])
    r = np.linspace(0.05, 3.0, 25) * radius
    f = np.tile(np.arange(surface.num_faces), r.size)
    rr = np.repeat(r, surface.num_faces)
    th = np.tile(theta, r.size)
    z = np.tile(centres[:, 2], r.size)
    p = np.column_stack([rr * np.cos(th), rr * np.sin(th), z])
    for tol in (0.0, 1e-3):
        np.testing.assert_array_equal(surface.locate(p, tol), f)


@pytest.mark.parametrize("type_name", ALL_TYPES)
@pytest.mark.parametrize("seed", [0, 1])
def test_prisms_tile_space(type_name, seed):
    surface, _coords = _wavy(type_name, seed)
    rng = np.random.default_rng(10 + seed)
    n = 1500
    xy = rng.uniform([-0.5, -0.5], [6.5, 5.5], size=(n, 2))
    z = 0.4 * np.sin(0.6 * xy[:, 0]) * np.cos(0.5 * xy[:, 1]) + rng.uniform(-0.3, 0.3, size=n)
    p = np.column_stack([xy, z])
    inside = _brute_force(surface, p)
    count = inside.sum(axis=1)
    assert np.all(count <= 1), "prisms overlap near the surface"
    assert np.mean(count == 1) > 0.7
    expected = np.where(count == 1, np.argmax(inside, axis=1), -1)
    tri = surface.locate_triangles(p, 0.0)
    faces = surface.locate(p, 0.0)
    # Away from the rim the walk finds exactly the prism holding the point.
    interior = np.all((xy > 0.3) & (xy < [5.7, 4.7]), axis=1)
    assert interior.sum() > 800
    np.testing.assert_array_equal(tri[interior], expected[interior])
    np.testing.assert_array_equal(faces[interior], surface.triangle_faces[expected[interior]])
    # Near the rim the fixed plane order can step onto a rim plane (no neighbour) before the
    # plane leading to the holding prism: ccx then finds nothing. Otherwise results agree.
    found = tri >= 0
    np.testing.assert_array_equal(tri[found], expected[found])
    np.testing.assert_array_equal(faces[found], surface.triangle_faces[tri[found]])
    assert np.all(tri[expected < 0] == -1)
    assert np.sum(found != (expected >= 0)) <= 0.01 * n


def test_update_follows_motion():
    surface, coords = _flat("quad4", 3, 3)
    p = np.array([[0.5, 0.5, 0.1]])
    assert surface.locate(p, 0.0)[0] == 0
    moved = coords + np.array([1.0, 0.0, 0.0])
    surface.update(moved)
    assert surface.locate(p, 0.0)[0] == -1
    assert surface.locate(p + np.array([1.0, 0, 0]), 0.0)[0] == 0
    # Lifting the surface moves centroids and keeps face-centre points found.
    surface.update(coords + np.array([0.0, 0.0, 7.0]))
    np.testing.assert_allclose(surface.triangle_centroids[:, 2], 7.0)
    assert surface.locate(np.array([[2.5, 1.5, 6.0]]), 0.0)[0] == 7


def test_max_depth_option():
    surface, _coords = _flat("quad4", 2, 2)
    p = np.array([[0.5, 0.5, -0.5], [1.5, 0.5, -100.0], [0.5, 1.5, 50.0], [1.5, 1.5, -0.05]])
    np.testing.assert_array_equal(surface.locate(p, 1e-3), [0, 2, 1, 3])  # ccx: no limit
    np.testing.assert_array_equal(surface.locate(p, 1e-3, max_depth=0.4), [-1, -1, 1, 3])
    np.testing.assert_array_equal(surface.locate(p, 1e-3, max_depth=0.6), [0, -1, 1, 3])
    with pytest.raises(ValueError, match="max_depth"):
        surface.locate(p, 1e-3, max_depth=-1.0)


def test_step_limit():
    # Long thin quads: the point (0.9, 0.5) is in face 0's first triangle, but its nearest
    # centroid is face 1's first triangle; the walk takes two steps (face 1 -> face 0 -> face 0).
    x = np.arange(4.0)
    coords = np.array([[xi, yi, 0.0] for xi in x for yi in (0.0, 10.0)])
    faces = np.array([[2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1] for i in range(3)])
    s = MasterSurface(FACE_TYPES["quad4"], faces, coords=coords)
    p = np.array([[0.9, 0.5, 1.0]])
    assert s.locate_triangles(p, 0.0)[0] == 0
    assert s.locate_triangles(p, 0.0, max_steps=2)[0] == 0
    assert s.locate_triangles(p, 0.0, max_steps=1)[0] == -1
    assert s.locate_triangles(p, 0.0, max_steps=0)[0] == -1


def test_cyclic_walk_finds_nothing():
    # A non-Delaunay flat triangulation in which the walk with the fixed plane order circles
    # around the holding triangle 13 and returns to its start triangle: "already visited" gives
    # no contact (ccx behaviour), although triangle 13's prism holds the point.
    xy = [
        [0.934, 0.207], [0.984, 0.809], [0.148, 0.32], [0.108, 0.305], [0.888, 0.756],
        [0.578, 0.073], [0.211, 0.613], [0.328, 0.453], [0.542, 0.209], [0.15, 0.44],
        [0.487, 0.417], [0.672, 0.533], [0.683, 0.164], [0.289, 0.84],
    ]  # fmt: skip
    tri = [
        [13, 10, 11], [0, 12, 5], [12, 0, 1], [13, 4, 1], [4, 13, 11], [12, 1, 4], [4, 11, 12],
        [5, 2, 3], [8, 12, 11], [8, 11, 10], [12, 8, 2], [12, 2, 5], [2, 10, 7], [2, 8, 10],
        [13, 6, 7], [13, 7, 10], [3, 7, 6], [3, 6, 9], [7, 3, 2], [9, 6, 13],
    ]  # fmt: skip
    coords = np.column_stack([np.array(xy), np.zeros(len(xy))])
    s = MasterSurface(FACE_TYPES["tri3"], np.array(tri), coords=coords)
    q = np.array([[0.265, 0.314, 0.0]])
    d = s.plane_distances(np.repeat(q, len(tri), 0), np.arange(len(tri)))
    np.testing.assert_array_equal(np.flatnonzero(np.all(d <= 0, axis=1)), [13])
    assert s.locate(q, 0.0)[0] == -1
    assert s.locate(q, 1e-3)[0] == -1
    # A point nearer to triangle 13's centroid starts there and is found.
    c = s.triangle_centroids[13]
    assert s.locate(c[None], 0.0)[0] == 13


def test_large_number_of_points():
    surface, _coords = _wavy("quad4", seed=2, nx=60, ny=50)
    rng = np.random.default_rng(5)
    n = 100_000
    xy = rng.uniform([0.0, 0.0], [60.0, 50.0], size=(n, 2))
    z = 0.4 * np.sin(0.6 * xy[:, 0]) * np.cos(0.5 * xy[:, 1]) + rng.uniform(-0.3, 0.3, size=n)
    p = np.column_stack([xy, z])
    faces = surface.locate(p, 1e-3 * np.ones(n))
    assert np.mean(faces >= 0) > 0.99


# --------------------------------------------------------------------------- validity
def test_edge_shared_by_three_faces_t_junction():
    # Two coplanar quads and a vertical one on their common edge (nodes 1, 4).
    coords = np.array(
        [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0], [1, 0, 1], [1, 1, 1]],
        dtype=float,
    )
    faces = np.array([[0, 1, 4, 3], [1, 2, 5, 4], [1, 4, 7, 6]])
    with pytest.raises(ValueError, match=r"'lid'.*nodes 1.*4.*shared by 3 faces"):
        MasterSurface(FACE_TYPES["quad4"], faces, name="lid")
    with pytest.raises(ValueError, match=r"nodes 1 at \[1.0, 0.0, 0.0\], 4 at \[1.0, 1.0, 0.0\]"):
        MasterSurface(FACE_TYPES["quad4"], faces, name="lid", coords=coords)


def test_edge_shared_by_three_quadratic_faces():
    faces, _ = _grid_faces("quad8", 2, 1)
    # Third face on the corner edge between faces 0 and 1 (corner nodes faces[0][1], [0][2]).
    a, b = faces[0][1], faces[0][2]
    extra = np.array([[a, b, 100, 101, faces[0][5], 102, 103, 104]])
    with pytest.raises(ValueError, match="shared by 3 faces"):
        MasterSurface(FACE_TYPES["quad8"], np.vstack([faces, extra]))


def test_inconsistent_orientation():
    faces = np.array([[0, 1, 4, 3], [1, 4, 5, 2]])  # second face reversed
    with pytest.raises(ValueError, match=r"'m'.*nodes 1, 4.*inconsistently oriented"):
        MasterSurface(FACE_TYPES["quad4"], faces, name="m")
    tri = np.array([[0, 1, 2], [0, 1, 3]])
    with pytest.raises(ValueError, match="inconsistently oriented"):
        MasterSurface(FACE_TYPES["tri3"], tri)


def test_bad_input():
    quad = FACE_TYPES["quad4"]
    with pytest.raises(ValueError, match=r"shape \(F, 4\)"):
        MasterSurface(quad, np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match="no faces"):
        MasterSurface(quad, np.zeros((0, 4), dtype=int))
    with pytest.raises(ValueError, match="negative"):
        MasterSurface(quad, np.array([[0, 1, -2, 3]]))
    with pytest.raises(ValueError, match="repeats a node"):  # [0, 1, 1, 3]: a wedge's triangle
        MasterSurface(quad, np.array([[0, 1, 0, 3]]))  # (tests/kernels/test_degenerate_faces.py)
    with pytest.raises(ValueError, match="integer"):
        MasterSurface(quad, np.array([[0.0, 1.0, 2.0, 3.0]]))
    s = MasterSurface(quad, np.array([[0, 1, 2, 3]]))
    with pytest.raises(RuntimeError, match="update"):
        s.locate(np.zeros((1, 3)), 0.0)
    with pytest.raises(ValueError, match="num_nodes > 3"):
        s.update(np.zeros((3, 3)))
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    with pytest.raises(ValueError, match=r"degenerate|zero normal"):
        s.update(np.zeros((4, 3)))
    s.update(square)
    with pytest.raises(ValueError, match=r"points must have shape"):
        s.locate(np.zeros((2, 2)), 0.0)
    with pytest.raises(ValueError, match=r"tolerances\[1\]"):
        s.locate(np.zeros((2, 3)), np.array([0.0, -1.0]))
    with pytest.raises(ValueError, match=r"points\[0\]"):
        s.locate(np.array([[np.nan, 0, 0]]), 0.0)
    assert s.locate(np.zeros((0, 3)), 0.0).shape == (0,)


@pytest.mark.parametrize("type_name", ["tri3", "quad4", "tri6"])
def test_ties_pick_the_same_faces_under_renumbering_and_translation(type_name):
    """Points exactly above master nodes and edge midpoints are ties between faces; the face a
    point gets depends on neither the numbering of nodes and faces nor the origin."""
    faces, uv = _grid_faces(type_name, 4, 4)
    coords = np.column_stack([uv, np.zeros(len(uv))])
    grid = np.arange(0.5, 4.0, 0.5)
    points = np.array([[x, y, 0.05] for x in grid for y in grid])

    def chosen(faces, coords, points):
        surface = MasterSurface(FACE_TYPES[type_name], faces, coords=coords)
        face = surface.locate(points, 1e-3)
        assert np.all(face >= 0)
        return np.round(coords[faces[face]].mean(axis=1) - coords.min(axis=0), 12)

    reference = chosen(faces, coords, points)
    rng = np.random.default_rng(3)
    node_order = rng.permutation(len(coords))
    new_id = np.empty_like(node_order)
    new_id[node_order] = np.arange(len(coords))
    face_order = rng.permutation(len(faces))
    shift = np.array([12.5, -3.25, 7.0])
    renumbered = chosen(new_id[faces[face_order]], coords[node_order] + shift, points + shift)
    np.testing.assert_array_equal(renumbered, reference)
