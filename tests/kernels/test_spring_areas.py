"""Tests of face areas, spring areas (docs/method.md §2.2) and their derivatives (pure numpy)."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.faces import FACE_TYPES, QUAD4, QUAD8, QUAD9, TRI3, TRI6
from dolfinx_ntf.kernels.spring_areas import (
    face_area_gradients,
    face_areas,
    spring_area_gradients,
    spring_areas,
)


def _grid(nx: int, ny: int) -> np.ndarray:
    """Nodes of a unit-square grid, node id i + (nx + 1) j at (i/nx, j/ny, 0)."""
    x, y = np.meshgrid(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1), indexing="xy")
    return np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)


def _quad_faces(nx: int, ny: int) -> np.ndarray:
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="xy")
    n0 = (i + (nx + 1) * j).ravel()
    return np.stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1], axis=1)


def _tri_faces(nx: int, ny: int) -> np.ndarray:
    q = _quad_faces(nx, ny)  # split along the (0, 2) diagonal: lower-left to upper-right
    return np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])


def _fine_area(face_type, face_coords: np.ndarray, order: int = 60) -> np.ndarray:
    """Reference face areas by a fine rule, independent of the face type's own quadrature."""
    x, w = np.polynomial.legendre.leggauss(order)
    px, py = np.meshgrid(x, x, indexing="ij")
    wts = np.outer(w, w).ravel()
    pts = np.stack([px.ravel(), py.ravel()], axis=1)
    if face_type.is_triangle:  # collapsed square (Duffy) onto the unit triangle
        u, v = (pts[:, 0] + 1) / 2, (pts[:, 1] + 1) / 2
        pts = np.stack([u, v * (1 - u)], axis=1)
        wts = wts * (1 - u) / 4
    dphi = face_type.shape_derivatives(pts)  # (q, n, 2)
    t = np.einsum("qjd,fjc->fqdc", dphi, face_coords)
    return np.linalg.norm(np.cross(t[:, :, 0], t[:, :, 1]), axis=-1) @ wts


def _face_nodes(face_type, scale: np.ndarray = np.array([2.0, 3.0])) -> np.ndarray:
    """Nodes of a flat face in the plane z = 1 with area scale[0]*scale[1]*(domain area)/4."""
    xi = face_type.node_parameters
    return np.stack([scale[0] * xi[:, 0], scale[1] * xi[:, 1], np.ones(len(xi))], axis=1)


def _dense(slave_index, node, grad, num_slaves, num_nodes) -> np.ndarray:
    out = np.zeros((num_slaves, num_nodes, 3))
    out[slave_index, node] = grad
    return out


# ----------------------------------------------------------------------------- face areas


@pytest.mark.parametrize("name", sorted(FACE_TYPES))
def test_flat_face_area_exact(name):
    ft = FACE_TYPES[name]
    coords = _face_nodes(ft)[None]
    expected = 6.0 * (0.5 if ft.is_triangle else 4.0)
    np.testing.assert_allclose(face_areas(ft, coords), [expected], rtol=1e-14)
    # a rigid rotation does not change the area
    c, s = np.cos(0.7), np.sin(0.7)
    rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    np.testing.assert_allclose(face_areas(ft, coords @ rot.T), [expected], rtol=1e-13)


def test_warped_quad4_area():
    coords = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0.3], [0, 1, 0]]], dtype=float)
    area = face_areas(QUAD4, coords)[0]
    # independent 2x2 Gauss evaluation of |x_ξ × x_η| of the bilinear hyperbolic paraboloid
    g = 1 / np.sqrt(3)
    expected = 0.0
    for a in (-g, g):
        for b in (-g, g):
            u, v = (a + 1) / 2, (b + 1) / 2  # z = 0.3 u v on the unit square
            n = np.array([-0.3 * v, -0.3 * u, 1.0])
            expected += np.linalg.norm(n) / 4  # Jacobian 1/4 of [-1,1]^2 -> [0,1]^2
    assert area == pytest.approx(expected, rel=1e-14)
    fine = _fine_area(QUAD4, coords)[0]
    assert fine > 1.0
    assert area == pytest.approx(fine, rel=2e-4)
    assert area != pytest.approx(fine, rel=1e-9)  # 2x2 Gauss is not exact on a warped face


@pytest.mark.parametrize("ft", [TRI6, QUAD8, QUAD9], ids=lambda f: f.name)
def test_curved_quadratic_face_area(ft):
    rng = np.random.default_rng(3)
    coords = _face_nodes(ft, np.array([1.0, 1.0]))
    coords[:, 2] += 0.05 * rng.standard_normal(len(coords))
    area = face_areas(ft, coords[None])[0]
    assert area == pytest.approx(_fine_area(ft, coords[None])[0], rel=1e-3)


# ----------------------------------------------------------------------------- spring areas


def test_unit_square_quad4():
    nx, ny = 4, 2
    coords = _grid(nx, ny)
    faces = _quad_faces(nx, ny)
    slaves = np.arange(len(coords))
    areas = spring_areas(QUAD4, faces, coords, slaves)
    cell = 1.0 / (nx * ny)
    i, j = slaves % (nx + 1), slaves // (nx + 1)
    on_x = (i == 0) | (i == nx)
    on_y = (j == 0) | (j == ny)
    expected = np.where(on_x & on_y, cell / 4, np.where(on_x | on_y, cell / 2, cell))
    np.testing.assert_allclose(areas, expected, rtol=1e-14)
    assert areas.sum() == pytest.approx(1.0, rel=1e-14)


def test_unit_square_tri3_and_slave_order():
    n = 3
    coords = _grid(n, n)
    faces = _tri_faces(n, n)
    slaves = np.arange(len(coords))
    areas = spring_areas(TRI3, faces, coords, slaves)
    h2 = 1.0 / n**2
    interior = [5, 6, 9, 10]
    np.testing.assert_allclose(areas[interior], h2, rtol=1e-14)  # 6 triangles each
    assert areas[0] == pytest.approx(h2 / 3)  # 2 triangles at the diagonal's start
    assert areas[n] == pytest.approx(h2 / 6)  # 1 triangle
    assert areas[1] == pytest.approx(h2 / 2)  # edge node: 3 triangles
    assert np.all(areas[[0, n, 1]] < h2)
    assert areas.sum() == pytest.approx(1.0, rel=1e-14)
    # a subset in arbitrary order, plus a node on no face, follows the given order
    coords_plus = np.vstack([coords, [[5.0, 5.0, 5.0]]])
    subset = np.array([16, 10, 0, 3])
    np.testing.assert_allclose(
        spring_areas(TRI3, faces, coords_plus, subset), [0.0, h2, h2 / 3, h2 / 6], rtol=1e-14
    )


@pytest.mark.parametrize(
    ("ft", "corner", "mid", "centre"),
    [
        (TRI6, 1 / 999, 332 / 999, None),
        (QUAD8, 1 / 100, 24 / 100, None),
        (QUAD9, 1 / 36, 1 / 9, 4 / 9),
    ],
    ids=["tri6", "quad8", "quad9"],
)
def test_quadratic_weights(ft, corner, mid, centre):
    coords = _face_nodes(ft)
    area = face_areas(ft, coords[None])[0]
    faces = np.arange(ft.num_nodes)[None]
    areas = spring_areas(ft, faces, coords, np.arange(ft.num_nodes))
    np.testing.assert_allclose(areas[: ft.num_corners], corner * area, rtol=1e-14)
    np.testing.assert_allclose(areas[ft.num_corners : 8 if ft is QUAD9 else None], mid * area)
    if centre is not None:
        assert areas[8] == pytest.approx(centre * area)
    assert areas.sum() == pytest.approx(area, rel=1e-14)


def test_current_configuration_and_empty_input():
    coords = _grid(1, 1)
    faces = _quad_faces(1, 1)
    stretched = coords * np.array([2.0, 3.0, 1.0])
    np.testing.assert_allclose(spring_areas(QUAD4, faces, stretched, [0, 3]), [1.5, 1.5])
    empty_faces = np.zeros((0, 4), dtype=np.int64)
    np.testing.assert_array_equal(spring_areas(QUAD4, empty_faces, coords, [0, 1]), [0.0, 0.0])
    assert spring_areas(QUAD4, faces, coords, np.array([], dtype=np.int64)).shape == (0,)
    rows, nodes, grads = spring_area_gradients(QUAD4, empty_faces, coords, [0, 1])
    assert rows.shape == nodes.shape == (0,) and grads.shape == (0, 3)


# ----------------------------------------------------------------------------- gradients


@pytest.mark.parametrize("name", sorted(FACE_TYPES))
def test_face_area_gradients_fd(name):
    ft = FACE_TYPES[name]
    rng = np.random.default_rng(7)
    base = _face_nodes(ft, np.array([1.0, 1.5]))
    coords = base[None] + 0.1 * rng.standard_normal((3, ft.num_nodes, 3))
    grads = face_area_gradients(ft, coords)
    assert grads.shape == (3, ft.num_nodes, 3)
    h = 1e-6
    fd = np.zeros_like(grads)
    for j in range(ft.num_nodes):
        for c in range(3):
            step = np.zeros_like(coords)
            step[:, j, c] = h
            fd[:, j, c] = (face_areas(ft, coords + step) - face_areas(ft, coords - step)) / (2 * h)
    np.testing.assert_allclose(grads, fd, rtol=1e-6, atol=1e-8)
    # translation invariance: the gradients of each face sum to zero
    np.testing.assert_allclose(grads.sum(axis=1), 0.0, atol=1e-12)


def test_face_area_gradients_degenerate_face():
    coords = np.zeros((1, 4, 3))
    grads = face_area_gradients(QUAD4, coords)
    assert np.all(np.isfinite(grads)) and np.all(grads == 0.0)
    assert face_areas(QUAD4, coords)[0] == 0.0


@pytest.mark.parametrize("kind", ["quad4", "tri3"])
def test_spring_area_gradients_fd(kind):
    n = 2
    rng = np.random.default_rng(11)
    coords = _grid(n, n) + 0.05 * rng.standard_normal((9, 3))
    ft, faces = (QUAD4, _quad_faces(n, n)) if kind == "quad4" else (TRI3, _tri_faces(n, n))
    slaves = np.array([4, 0, 7, 2])
    rows, nodes, grads = spring_area_gradients(ft, faces, coords, slaves)
    keys = rows * len(coords) + nodes
    assert np.all(np.diff(keys) > 0)  # unique and sorted
    dense = _dense(rows, nodes, grads, len(slaves), len(coords))
    h = 1e-6
    fd = np.zeros_like(dense)
    for q in range(len(coords)):
        for c in range(3):
            plus, minus = coords.copy(), coords.copy()
            plus[q, c] += h
            minus[q, c] -= h
            fd[:, q, c] = (
                spring_areas(ft, faces, plus, slaves) - spring_areas(ft, faces, minus, slaves)
            ) / (2 * h)
    np.testing.assert_allclose(dense, fd, rtol=1e-6, atol=1e-8)
    # the corner node 0 shares faces only with nodes 0, 1, 3 and 4 (quad) or fewer
    assert set(nodes[rows == 1]) <= {0, 1, 3, 4}
    assert np.abs(dense).sum() > 0.1


def test_spring_area_gradients_quadratic_fd():
    rng = np.random.default_rng(5)
    coords = _face_nodes(QUAD8) + 0.1 * rng.standard_normal((8, 3))
    faces = np.arange(8)[None]
    slaves = np.array([6, 1])
    rows, nodes, grads = spring_area_gradients(QUAD8, faces, coords, slaves)
    face_grad = face_area_gradients(QUAD8, coords[None])[0]
    dense = _dense(rows, nodes, grads, 2, 8)
    np.testing.assert_allclose(dense[0], 0.24 * face_grad, rtol=1e-14)
    np.testing.assert_allclose(dense[1], 0.01 * face_grad, rtol=1e-14)


# ----------------------------------------------------------------------------- errors


def test_errors():
    coords = _grid(1, 1)
    faces = _quad_faces(1, 1)
    with pytest.raises(ValueError, match=r"face_coords must have shape \(F, 4, 3\) for quad4"):
        face_areas(QUAD4, np.zeros((2, 3, 3)))
    with pytest.raises(ValueError, match="face_coords of face 1 are not finite"):
        face_area_gradients(TRI3, np.stack([np.zeros((3, 3)), np.full((3, 3), np.nan)]))
    with pytest.raises(ValueError, match=r"faces must have shape \(F, 3\) for tri3"):
        spring_areas(TRI3, faces, coords, [0])
    with pytest.raises(ValueError, match="node id 7 at local position 2"):
        spring_areas(QUAD4, np.array([[0, 1, 7, 3]]), coords, [0])
    with pytest.raises(ValueError, match="node id -1"):
        spring_area_gradients(QUAD4, np.array([[0, 1, -1, 3]]), coords, [0])
    with pytest.raises(ValueError, match="lists node 3 more than once"):
        spring_areas(QUAD4, faces, coords, [3, 1, 3])
    with pytest.raises(ValueError, match="integer node ids"):
        spring_areas(QUAD4, faces.astype(float), coords, [0])
    with pytest.raises(ValueError, match="slave_nodes must be a 1-D integer array"):
        spring_areas(QUAD4, faces, coords, [[0, 1]])
    with pytest.raises(ValueError, match=r"coords must have shape \(num_nodes, 3\)"):
        spring_areas(QUAD4, faces, coords[:, :2], [0])
