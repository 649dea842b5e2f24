"""dolfinx_ntf.kernels.faces: shape functions, weights, triangulation, quadrature, clamp."""

import numpy as np
import pytest

from dolfinx_ntf.kernels.faces import (
    FACE_TYPES,
    QUAD4,
    QUAD8,
    QUAD9,
    TRI3,
    TRI6,
    FaceType,
    face_points,
    face_tangents,
    face_type_from_num_nodes,
    film_matrices,
    flux_flows,
)

ALL = list(FACE_TYPES.values())
IDS = [ft.name for ft in ALL]


def _random_inside(ft: FaceType, n: int, rng: np.random.Generator) -> np.ndarray:
    if ft.is_triangle:
        u = rng.random((n, 2))
        flip = u.sum(axis=1) > 1.0
        u[flip] = 1.0 - u[flip]
        return u
    return rng.uniform(-1.0, 1.0, (n, 2))


def _flat_coords(ft: FaceType) -> np.ndarray:
    """A flat face in the plane z = 0 whose geometry is an affine map of the parameter plane."""
    a = np.array([[1.3, 0.4], [-0.2, 0.9]])
    xy = ft.node_parameters @ a.T + np.array([0.5, -1.0])
    return np.column_stack([xy, np.zeros(ft.num_nodes)])


def _reference_area(ft: FaceType) -> float:
    return 0.5 if ft.is_triangle else 4.0


def test_registry_and_lookup():
    assert set(FACE_TYPES) == {"tri3", "quad4", "tri6", "quad8", "quad9"}
    for n, ft in [(3, TRI3), (4, QUAD4), (6, TRI6), (8, QUAD8), (9, QUAD9)]:
        assert face_type_from_num_nodes(n) is ft
        assert ft.num_nodes == n
        assert ft.node_parameters.shape == (n, 2)
        assert ft.area_weights.shape == (n,)
    for bad in (2, 5, 7, 10):
        with pytest.raises(ValueError, match=str(bad)):
            face_type_from_num_nodes(bad)


def test_arrays_are_read_only():
    with pytest.raises(ValueError):
        QUAD4.node_parameters[0, 0] = 3.0


def test_node_layout():
    np.testing.assert_array_equal(QUAD4.node_parameters, [[-1, -1], [1, -1], [1, 1], [-1, 1]])
    np.testing.assert_array_equal(TRI3.node_parameters, [[0, 0], [1, 0], [0, 1]])
    np.testing.assert_array_equal(TRI6.node_parameters[3:], [[0.5, 0], [0.5, 0.5], [0, 0.5]])
    np.testing.assert_array_equal(QUAD8.node_parameters[4:], [[0, -1], [1, 0], [0, 1], [-1, 0]])
    np.testing.assert_array_equal(QUAD9.node_parameters[8], [0, 0])
    # tri3 shape functions are exactly (1-ξ-η, ξ, η).
    xi = np.array([[0.2, 0.3], [0.7, 0.1]])
    np.testing.assert_allclose(
        TRI3.shape_functions(xi), [[0.5, 0.2, 0.3], [0.2, 0.7, 0.1]], atol=1e-15
    )
    np.testing.assert_allclose(TRI3.center, [1 / 3, 1 / 3])
    np.testing.assert_allclose(QUAD8.center, [0, 0])


def test_explicit_formulas():
    rng = np.random.default_rng(0)
    xi = rng.uniform(-1, 1, (20, 2))
    x, y = xi[:, 0], xi[:, 1]
    # quad8 corner 1 and midside 5, quad9 centre.
    np.testing.assert_allclose(
        QUAD8.shape_functions(xi)[:, 0], 0.25 * (1 - x) * (1 - y) * (-x - y - 1), atol=1e-15
    )
    np.testing.assert_allclose(
        QUAD8.shape_functions(xi)[:, 4], 0.5 * (1 - x * x) * (1 - y), atol=1e-15
    )
    np.testing.assert_allclose(
        QUAD9.shape_functions(xi)[:, 8], (1 - x * x) * (1 - y * y), atol=1e-15
    )
    t = _random_inside(TRI6, 20, rng)
    l1, l2, l3 = 1 - t[:, 0] - t[:, 1], t[:, 0], t[:, 1]
    phi = TRI6.shape_functions(t)
    np.testing.assert_allclose(phi[:, 0], l1 * (2 * l1 - 1), atol=1e-15)
    np.testing.assert_allclose(phi[:, 4], 4 * l2 * l3, atol=1e-15)


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_partition_of_unity_and_kronecker(ft):
    rng = np.random.default_rng(1)
    xi = _random_inside(ft, 50, rng) * 1.5  # also outside the domain
    phi = ft.shape_functions(xi)
    np.testing.assert_allclose(phi.sum(axis=-1), 1.0, atol=1e-13)
    np.testing.assert_allclose(ft.shape_derivatives(xi).sum(axis=-2), 0.0, atol=1e-13)
    np.testing.assert_allclose(ft.shape_second_derivatives(xi).sum(axis=-2), 0.0, atol=1e-13)
    np.testing.assert_allclose(
        ft.shape_functions(ft.node_parameters), np.eye(ft.num_nodes), atol=1e-14
    )
    # Linear completeness: Σ φ_j ξ_j = ξ.
    np.testing.assert_allclose(phi @ ft.node_parameters, xi, atol=1e-13)


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_shapes_broadcast(ft):
    xi = np.zeros((2, 5, 2))
    assert ft.shape_functions(xi).shape == (2, 5, ft.num_nodes)
    assert ft.shape_derivatives(xi).shape == (2, 5, ft.num_nodes, 2)
    assert ft.shape_second_derivatives(xi).shape == (2, 5, ft.num_nodes, 3)
    assert ft.shape_functions(np.zeros(2)).shape == (ft.num_nodes,)
    with pytest.raises(ValueError, match="xi"):
        ft.shape_functions(np.zeros((4, 3)))


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_derivatives_vs_finite_differences(ft):
    rng = np.random.default_rng(2)
    xi = _random_inside(ft, 20, rng)
    h = 1e-6
    e = np.eye(2) * h
    d1 = ft.shape_derivatives(xi)
    d2 = ft.shape_second_derivatives(xi)
    for k in range(2):
        fd = (ft.shape_functions(xi + e[k]) - ft.shape_functions(xi - e[k])) / (2 * h)
        np.testing.assert_allclose(d1[..., k], fd, atol=1e-8)
    fd_xx = (ft.shape_derivatives(xi + e[0]) - ft.shape_derivatives(xi - e[0])) / (2 * h)
    fd_yy = (ft.shape_derivatives(xi + e[1]) - ft.shape_derivatives(xi - e[1])) / (2 * h)
    np.testing.assert_allclose(d2[..., 0], fd_xx[..., 0], atol=1e-7)
    np.testing.assert_allclose(d2[..., 1], fd_xx[..., 1], atol=1e-7)
    np.testing.assert_allclose(d2[..., 1], fd_yy[..., 0], atol=1e-7)
    np.testing.assert_allclose(d2[..., 2], fd_yy[..., 1], atol=1e-7)
    if ft in (TRI3,):
        np.testing.assert_array_equal(d2, 0.0)
    if ft is QUAD4:
        np.testing.assert_array_equal(d2[..., [0, 2]], 0.0)
        assert np.abs(d2[..., 1]).max() > 0.1


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_shape_function_increments(ft):
    rng = np.random.default_rng(5)
    xi = _random_inside(ft, 30, rng)
    dxi = rng.normal(size=(30, 2)) * np.logspace(-12, 0, 30)[:, None]
    inc = ft.shape_function_increments(xi, dxi)
    np.testing.assert_allclose(
        inc, ft.shape_functions(xi + dxi) - ft.shape_functions(xi), atol=1e-14
    )
    # Relative accuracy for tiny increments: first-order term dominates.
    lin = np.einsum("mjd,md->mj", ft.shape_derivatives(xi), dxi)
    tiny = np.abs(dxi).max(axis=1) < 1e-9
    size = np.abs(dxi[tiny]).max(axis=1)[:, None]
    np.testing.assert_allclose(inc[tiny] / size, lin[tiny] / size, atol=1e-8)
    assert np.any(np.abs(inc[tiny]) > 0)


def test_area_weights():
    for ft in ALL:
        assert ft.area_weights.sum() == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(TRI3.area_weights, 1 / 3)
    np.testing.assert_allclose(QUAD4.area_weights, 1 / 4)
    np.testing.assert_allclose(TRI6.area_weights, [1 / 999] * 3 + [332 / 999] * 3)
    np.testing.assert_allclose(QUAD8.area_weights, [0.01] * 4 + [0.24] * 4)
    np.testing.assert_allclose(QUAD9.area_weights, [1 / 36] * 4 + [1 / 9] * 4 + [4 / 9])


# Exact polynomial degree (total degree for triangles, per direction for quads) of each rule.
_DEGREES = {"tri3": 1, "quad4": 3, "tri6": 2, "quad8": 5, "quad9": 5}


def _exact_monomial_integral(ft: FaceType, a: int, b: int) -> float:
    from math import factorial

    if ft.is_triangle:
        return factorial(a) * factorial(b) / factorial(a + b + 2)

    def one_d(p: int) -> float:
        return 0.0 if p % 2 else 2.0 / (p + 1)

    return one_d(a) * one_d(b)


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_quadrature_degree(ft):
    pts, w = ft.quadrature_points, ft.quadrature_weights
    assert pts.shape == (len(w), 2)
    assert {"tri3": 1, "quad4": 4, "tri6": 3, "quad8": 9, "quad9": 9}[ft.name] == len(w)
    assert w.sum() == pytest.approx(_reference_area(ft), rel=1e-14)
    assert np.all(ft.contains(pts))
    deg = _DEGREES[ft.name]
    for a in range(deg + 2):
        for b in range(deg + 2):
            exact_ok = (a + b <= deg) if ft.is_triangle else (a <= deg and b <= deg)
            val = np.sum(w * pts[:, 0] ** a * pts[:, 1] ** b)
            ref = _exact_monomial_integral(ft, a, b)
            if exact_ok:
                assert val == pytest.approx(ref, abs=1e-14), (a, b)
    # And the next degree is not integrated exactly (the rule is not stronger than claimed).
    if ft.is_triangle:
        a, b = deg + 1, 0
    else:
        a, b = deg + 1, 0
    val = np.sum(w * pts[:, 0] ** a * pts[:, 1] ** b)
    assert abs(val - _exact_monomial_integral(ft, a, b)) > 1e-6


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_triangulation_covers_flat_face(ft):
    coords = _flat_coords(ft)
    tri = ft.triangles
    assert tri.min() >= 0 and tri.max() < ft.num_nodes
    # Every node is used.
    assert set(tri.ravel()) == set(range(ft.num_nodes))
    p = coords[tri]  # (t, 3, 3)
    m_tri = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    # Face normal from the quadrature rule (flat face: constant).
    q_xi, q_eta = face_tangents(ft, coords, ft.quadrature_points)
    m = np.cross(q_xi, q_eta)
    face_area = np.sum(ft.quadrature_weights * np.linalg.norm(m, axis=-1))
    n = m[0] / np.linalg.norm(m[0])
    # All sub-triangles oriented like the face, with positive area.
    assert np.all(m_tri @ n > 1e-12)
    assert 0.5 * np.sum(m_tri @ n) == pytest.approx(face_area, rel=1e-13)
    # Reference check: in parameter space the triangles tile the domain.
    par = ft.node_parameters[tri]
    e1, e2 = par[:, 1] - par[:, 0], par[:, 2] - par[:, 0]
    signed = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert np.all(signed > 0)
    assert signed.sum() == pytest.approx(_reference_area(ft))


def test_spec_triangulations():
    np.testing.assert_array_equal(TRI3.triangles, [[0, 1, 2]])
    np.testing.assert_array_equal(QUAD4.triangles, [[0, 1, 3], [1, 2, 3]])
    np.testing.assert_array_equal(TRI6.triangles, [[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])
    np.testing.assert_array_equal(
        QUAD8.triangles, [[0, 4, 7], [4, 1, 5], [6, 5, 2], [7, 6, 3], [7, 4, 6], [4, 5, 6]]
    )
    assert QUAD9.triangles.shape == (8, 3)
    assert np.all(QUAD9.triangles[:, 2] == 8)


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_face_area_of_scaled_flat_face(ft):
    # Flat affine face scaled by 2: area = 4 * reference area * |det A|.
    coords = _flat_coords(ft) * 2.0
    q_xi, q_eta = face_tangents(ft, coords, ft.quadrature_points)
    area = np.sum(ft.quadrature_weights * np.linalg.norm(np.cross(q_xi, q_eta), axis=-1))
    det = abs(np.linalg.det(np.array([[1.3, 0.4], [-0.2, 0.9]])))
    assert area == pytest.approx(4.0 * det * _reference_area(ft), rel=1e-13)


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_face_points_and_tangents(ft):
    rng = np.random.default_rng(3)
    coords = rng.normal(size=(7, ft.num_nodes, 3))
    xi = _random_inside(ft, 7, rng)
    q = face_points(ft, coords, xi)
    assert q.shape == (7, 3)
    np.testing.assert_allclose(q, np.einsum("ij,ijc->ic", ft.shape_functions(xi), coords))
    # Nodes interpolate.
    for j in range(ft.num_nodes):
        xj = np.broadcast_to(ft.node_parameters[j], (7, 2))
        np.testing.assert_allclose(face_points(ft, coords, xj), coords[:, j], atol=1e-13)
    q_xi, q_eta = face_tangents(ft, coords, xi)
    h = 1e-6
    fd_xi = (
        face_points(ft, coords, xi + np.array([h, 0])) - face_points(ft, coords, xi - [h, 0])
    ) / (2 * h)
    fd_eta = (
        face_points(ft, coords, xi + np.array([0, h])) - face_points(ft, coords, xi - [0, h])
    ) / (2 * h)
    np.testing.assert_allclose(q_xi, fd_xi, atol=1e-8)
    np.testing.assert_allclose(q_eta, fd_eta, atol=1e-8)
    with pytest.raises(ValueError, match="face_coords"):
        face_points(ft, coords[:, :-1], xi)


def test_outward_normal_convention():
    # Face of the unit cube at z = 1 seen from outside (+z): corners counter-clockwise from above.
    coords = np.array([[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float)
    q_xi, q_eta = face_tangents(QUAD4, coords, np.zeros(2))
    assert np.cross(q_xi, q_eta)[2] > 0
    q_xi, q_eta = face_tangents(TRI3, coords[:3], np.array([0.2, 0.2]))
    assert np.cross(q_xi, q_eta)[2] > 0


@pytest.mark.parametrize("ft", [TRI3, QUAD4], ids=["triangle", "quad"])
def test_clamp(ft):
    rng = np.random.default_rng(4)
    xi = rng.uniform(-3, 3, (400, 2))
    c = ft.clamp(xi)
    assert np.all(ft.contains(c))
    inside = ft.contains(xi)
    np.testing.assert_array_equal(c[inside], xi[inside])
    # Nearest point: no sampled domain point is closer.
    samples = _random_inside(ft, 1000, rng)
    boundary = ft.clamp(rng.uniform(-3, 3, (2000, 2)))
    cand = np.concatenate([samples, boundary, ft.node_parameters])
    d_clamp = np.linalg.norm(xi - c, axis=1)
    d_min = np.min(np.linalg.norm(xi[:, None, :] - cand[None], axis=-1), axis=1)
    assert np.all(d_clamp <= d_min + 1e-12)
    # Clamp is idempotent.
    np.testing.assert_array_equal(ft.clamp(c), c)


def test_clamp_triangle_cases():
    xi = np.array([[2.0, 2.0], [-1.0, -1.0], [3.0, -1.0], [-1.0, 0.5], [0.6, 0.6], [0.2, 0.3]])
    expected = np.array([[0.5, 0.5], [0.0, 0.0], [1.0, 0.0], [0.0, 0.5], [0.5, 0.5], [0.2, 0.3]])
    np.testing.assert_allclose(TRI3.clamp(xi), expected, atol=1e-15)
    np.testing.assert_array_equal(QUAD4.clamp([[2.0, -0.5], [-3, 3]]), [[1.0, -0.5], [-1, 1]])


def test_flux_flows_of_flat_faces():
    """A uniform flux on a flat face: the consistent flows (quad8: -A/12 at the corners, A/3 at
    the midsides; tri6: 0 and A/3, times q), summing to q A; ccx's 2 x 2 rule on quad8 and the
    3-point rule on tri6 are exact there; a curved face's flows sum to q times its area."""
    q = np.array([3.0, -2.0])
    square = 2.0 * QUAD8.node_parameters  # flat, side 2 then 4 (A = 16)
    quad = np.stack([np.column_stack([square, np.zeros(8)]) * s for s in (1.0, 2.0)])
    rule = (np.array([[x, y] for y in (-1, 1) for x in (-1, 1)]) / np.sqrt(3.0), np.ones(4))
    flows = flux_flows(QUAD8, quad, q, rule)
    areas = np.array([16.0, 64.0])
    corner, mid = np.repeat(-(q * areas)[:, None] / 12.0, 4, axis=1), (q * areas)[:, None] / 3.0
    np.testing.assert_allclose(flows[:, :4], corner, rtol=1e-13)
    np.testing.assert_allclose(flows[:, 4:], np.repeat(mid, 4, axis=1), rtol=1e-13)
    tri = np.column_stack([TRI6.node_parameters, np.zeros(6)])[None] * 2.0  # A = 2
    flows = flux_flows(TRI6, tri, q[:1])
    np.testing.assert_allclose(flows[0, :3], 0.0, atol=1e-14)
    np.testing.assert_allclose(flows[0, 3:], np.full(3, 3.0 * 2.0 / 3.0), rtol=1e-13)
    curved = quad[:1].copy()
    curved[0, 4:, 2] = 0.3  # midsides lifted: a curved face
    flows = flux_flows(QUAD8, curved, q[:1])  # the face type's own 3 x 3 rule
    q_xi, q_eta = face_tangents(QUAD8, curved[0], QUAD8.quadrature_points)
    area = np.sum(QUAD8.quadrature_weights * np.linalg.norm(np.cross(q_xi, q_eta), axis=-1))
    assert area > 16.0
    np.testing.assert_allclose(flows.sum(), q[0] * area, rtol=1e-13)


@pytest.mark.parametrize("ft", [TRI6, QUAD8], ids=["tri6", "quad8"])
def test_film_matrices_are_face_masses(ft):
    """Symmetric, row sums the consistent flows of a unit flux (``M 1`` is :func:`flux_flows`);
    positive semi-definite of rank ``min(n, points)`` on a curved face (tri6's 3 points give
    rank 3, quad8's 3 x 3 points a positive definite matrix)."""
    coords = np.column_stack([ft.node_parameters, np.zeros(ft.num_nodes)])
    coords[ft.num_corners :, 2] = 0.2  # curved
    M = film_matrices(ft, coords[None])[0]
    np.testing.assert_allclose(M, M.T, atol=1e-15)
    np.testing.assert_allclose(M.sum(axis=1), flux_flows(ft, coords[None], [1.0])[0], rtol=1e-13)
    eigenvalues = np.linalg.eigvalsh(M)
    assert eigenvalues.min() > -1e-14 * eigenvalues.max()
    rank = min(ft.num_nodes, ft.quadrature_points.shape[0])
    assert np.count_nonzero(eigenvalues > 1e-12 * eigenvalues.max()) == rank
