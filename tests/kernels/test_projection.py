"""dolfinx_ntf.kernels.projection: closest point of a face over its closed parametric domain."""

import numpy as np
import pytest
from scipy.optimize import minimize

from dolfinx_ntf.kernels.faces import (
    FACE_TYPES,
    QUAD4,
    QUAD8,
    QUAD9,
    TRI3,
    TRI6,
    FaceType,
    face_points,
)
from dolfinx_ntf.kernels.projection import project_points

ALL = list(FACE_TYPES.values())
IDS = [ft.name for ft in ALL]


# ----------------------------------------------------------------------------- helpers


def _distorted_faces(ft: FaceType, num: int, amp: float, rng: np.random.Generator) -> np.ndarray:
    """Faces close to the parametric domain placed in z = 0, with random node perturbations."""
    base = np.column_stack([ft.node_parameters, np.zeros(ft.num_nodes)])
    return base[None] + amp * rng.normal(size=(num, ft.num_nodes, 3))


def _sample_parameters(ft: FaceType, num: int, rng: np.random.Generator, scale: float = 1.0):
    """Parameters in the domain shrunk (scale < 1) or enlarged (scale > 1) about its centre."""
    if ft.is_triangle:
        u = rng.random((num, 2))
        flip = u.sum(axis=1) > 1
        u[flip] = 1 - u[flip]
    else:
        u = rng.uniform(-1, 1, (num, 2))
    return ft.center + scale * (u - ft.center)


def _sq_dist(ft, coords, pts, xi):
    return np.sum((pts - face_points(ft, coords, xi)) ** 2, axis=-1)


def _tangents(ft, coords, xi):
    jac = np.swapaxes(ft.shape_derivatives(xi), -1, -2) @ coords
    return jac[..., 0, :], jac[..., 1, :]


def _constraints(ft: FaceType):
    """Domain as A ξ ≤ b."""
    if ft.is_triangle:
        return np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, 1.0]]), np.array([0.0, 0.0, 1.0])
    return np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]), np.ones(4)


def _kkt(ft, coords, pts, xi, act_tol=1e-13):
    """Relative KKT residual and most negative relative multiplier of min ½|x - q(ξ)|²."""
    q_xi, q_eta = _tangents(ft, coords, xi)
    r = pts - face_points(ft, coords, xi)
    g = -np.stack([np.sum(r * q_xi, axis=1), np.sum(r * q_eta, axis=1)], axis=1)
    scale = np.linalg.norm(r, axis=1) * np.hypot(
        np.linalg.norm(q_xi, axis=1), np.linalg.norm(q_eta, axis=1)
    )
    scale = np.maximum(scale, 1e-300)
    a, b = _constraints(ft)
    res = np.zeros(len(xi))
    lam_min = np.zeros(len(xi))
    for i in range(len(xi)):
        act = np.abs(a @ xi[i] - b) <= act_tol
        if not act.any():
            res[i] = np.linalg.norm(g[i])
            continue
        lam = np.linalg.lstsq(a[act].T, -g[i], rcond=None)[0]
        res[i] = np.linalg.norm(a[act].T @ lam + g[i])
        lam_min[i] = min(lam.min(), 0.0)
    return res / scale, lam_min / scale


def _assert_kkt(ft, coords, pts, xi):
    """The KKT conditions of the closest-point problem hold to round-off at ``xi``."""
    res, lam_min = _kkt(ft, coords, pts, xi)
    assert res.max() < 1e-11 and lam_min.min() > -1e-12


def _brute_force(ft: FaceType, coords: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Global minimizer: dense parameter grid, then a bounded/constrained local refinement."""
    m = 161
    t = np.linspace(-1, 1, m) if not ft.is_triangle else np.linspace(0, 1, m)
    gx, gy = np.meshgrid(t, t, indexing="ij")
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    if ft.is_triangle:
        grid = grid[grid.sum(axis=1) <= 1 + 1e-12]
    phi = ft.shape_functions(grid)  # (G, n)
    out = np.empty((len(pts), 2))
    a, _b = _constraints(ft)
    for i in range(len(pts)):
        q = phi @ coords[i]
        start = grid[np.argmin(np.sum((q - pts[i]) ** 2, axis=1))]

        def fun(x, i=i):
            r = pts[i] - ft.shape_functions(x) @ coords[i]
            jac = ft.shape_derivatives(x).T @ coords[i]
            return 0.5 * r @ r, -(jac @ r)

        bounds = [(0, 1), (0, 1)] if ft.is_triangle else [(-1, 1), (-1, 1)]
        cons = [{"type": "ineq", "fun": lambda x: 1 - x[0] - x[1], "jac": lambda x: -a[2]}]
        res = minimize(
            fun,
            start,
            jac=True,
            method="SLSQP",
            bounds=bounds,
            constraints=cons if ft.is_triangle else (),
            options={"ftol": 1e-15, "maxiter": 200},
        )
        out[i] = ft.clamp(res.x)
    return out


def _compass(ft: FaceType, coords: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """CalculiX's compass search (docs/method.md §3.3; square domain, folded for triangles)."""
    num = len(pts)
    s = np.zeros((num, 2))

    def to_face(sq):
        if not ft.is_triangle:
            return sq
        x, y = sq[:, 0], sq[:, 1]
        low = (x + y <= 0)[:, None]
        lower = np.column_stack([(x + 1) / 2, (y + 1) / 2])
        upper = np.column_stack([(1 - y) / 2, (1 - x) / 2])
        return np.where(low, lower, upper)

    def f(sq):
        return _sq_dist(ft, coords, pts, to_face(sq))

    h = np.full(num, 0.1)
    fc = f(s)
    active = np.ones(num, dtype=bool)
    moves = [(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1) if (i, j) != (0, 0)]
    while active.any():
        best, best_f = s.copy(), fc.copy()
        for move in moves:
            cand = s + h[:, None] * np.array(move, dtype=float)
            inside = np.all(np.abs(cand) <= 1.0 + 1e-15, axis=1)
            fv = np.where(inside, f(np.clip(cand, -1, 1)), np.inf)
            better = active & (fv < best_f)
            best[better], best_f[better] = cand[better], fv[better]
        moved = active & (best_f < fc)
        s[moved], fc[moved] = best[moved], best_f[moved]
        h[active & ~moved] /= 10.0
        active &= h > 0.99e-8
    return to_face(s)


def _spherical_cap(ft: FaceType, radius: float, half_width: float) -> np.ndarray:
    """A face on the sphere of given radius about the origin, around the +z pole, outward normal."""
    xy = ft.node_parameters * half_width
    if ft.is_triangle:
        xy = (ft.node_parameters - ft.center) * half_width
    z = np.sqrt(radius**2 - np.sum(xy**2, axis=1))
    return np.column_stack([xy, z])


# ----------------------------------------------------------------------------- tests


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_interior_projection_is_orthogonal(ft):
    rng = np.random.default_rng(10)
    num = 400
    coords = _distorted_faces(ft, num, 0.05, rng)
    xi_true = _sample_parameters(ft, num, rng, scale=0.8)
    q_xi, q_eta = _tangents(ft, coords, xi_true)
    n = np.cross(q_xi, q_eta)
    n /= np.linalg.norm(n, axis=1)[:, None]
    h = rng.uniform(0.01, 0.2, num) * rng.choice([-1.0, 1.0], num)
    pts = face_points(ft, coords, xi_true) + h[:, None] * n
    xi = project_points(ft, coords, pts)
    np.testing.assert_allclose(xi, xi_true, atol=1e-10)
    r = pts - face_points(ft, coords, xi)
    q_xi, q_eta = _tangents(ft, coords, xi)
    rn = np.linalg.norm(r, axis=1)
    assert np.all(np.abs(np.sum(r * q_xi, axis=1)) <= 1e-12 * rn * np.linalg.norm(q_xi, axis=1))
    assert np.all(np.abs(np.sum(r * q_eta, axis=1)) <= 1e-12 * rn * np.linalg.norm(q_eta, axis=1))


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_kkt_for_arbitrary_points(ft):
    # Strongly distorted faces, points anywhere (inside, outside, above, below): the result is in
    # the closed domain and satisfies the KKT conditions of the constrained minimization.
    rng = np.random.default_rng(11)
    num = 1500
    coords = _distorted_faces(ft, num, 0.15, rng)
    spread = 0.6 if ft.is_triangle else 1.5
    pts = coords.mean(axis=1) + spread * rng.normal(size=(num, 3))
    xi = project_points(ft, coords, pts)
    assert xi.shape == (num, 2)
    assert np.all(np.isfinite(xi))
    assert np.all(ft.contains(xi))
    _assert_kkt(ft, coords, pts, xi)
    # A sizeable share of the minima lies on the boundary, so edges and corners are exercised.
    a, b = _constraints(ft)
    on_boundary = np.any(np.abs(xi @ a.T - b) <= 1e-13, axis=1)
    assert 0.2 < on_boundary.mean() < 0.95


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_matches_brute_force_outside(ft):
    rng = np.random.default_rng(12)
    num = 30
    coords = _distorted_faces(ft, num, 0.03, rng)
    # Feet outside the face (beyond edges and corners) and points far above/below.
    xi_foot = _sample_parameters(ft, num, rng, scale=2.5)
    height = rng.uniform(-3.0, 3.0, num)
    pts = face_points(ft, coords, ft.clamp(xi_foot))
    pts[:, :2] += (xi_foot - ft.clamp(xi_foot)) * (1.0 if ft.is_triangle else 0.5)
    pts[:, 2] += height
    xi = project_points(ft, coords, pts)
    ref = _brute_force(ft, coords, pts)
    f, f_ref = _sq_dist(ft, coords, pts, xi), _sq_dist(ft, coords, pts, ref)
    assert np.all(f <= f_ref * (1 + 1e-12) + 1e-14)
    np.testing.assert_allclose(xi, ref, atol=1e-6)
    _assert_kkt(ft, coords, pts, xi)


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_far_points(ft):
    # Far from a (curved) face the distance is dominated by the height function x̂·q(ξ), which
    # has several local maxima on a wavy face; use flat faces (in-plane distortion) and the
    # convex side of a spherical cap, where the closest point is unique.
    rng = np.random.default_rng(23)
    num = 20
    flat = _distorted_faces(ft, num, 0.1, rng)
    flat[:, :, 2] = 0.0
    cap = np.repeat(_spherical_cap(ft, radius=3.0, half_width=1.0)[None], num, axis=0)
    coords = np.concatenate([flat, cap])
    lateral = rng.uniform(-3, 3, (2 * num, 2))
    height = rng.choice([-1e3, -50.0, 50.0, 1e3], 2 * num)
    height[num:] = np.abs(height[num:]) + 3.0
    pts = np.column_stack([lateral, height])
    pts[num:, :2] *= np.abs(height[num:, None]) / 3.0  # keep the cap points' directions varied
    xi = project_points(ft, coords, pts)
    ref = _brute_force(ft, coords, pts)
    # The reference is only as good as SLSQP on f ~ 1e6: compare loosely, then check KKT tightly.
    np.testing.assert_allclose(xi, ref, atol=1e-4)
    f, f_ref = _sq_dist(ft, coords, pts, xi), _sq_dist(ft, coords, pts, ref)
    assert np.all(f <= f_ref * (1 + 1e-14))
    _assert_kkt(ft, coords, pts, xi)


def test_exact_edge_and_corner_cases():
    square = np.array([[[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]], dtype=float)
    pts = np.array([[2.0, 0.3, 5.0], [3.0, -4.0, -2.0], [-0.25, 7.0, 0.0], [0.1, 0.2, -9.0]])
    xi = project_points(QUAD4, np.repeat(square, 4, axis=0), pts)
    np.testing.assert_allclose(xi, [[1, 0.3], [1, -1], [-0.25, 1], [0.1, 0.2]], atol=1e-14)
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], dtype=float)
    pts = np.array([[1.0, 1.0, 0.3], [-1.0, -2.0, 0.0], [2.0, -1.0, 4.0], [-3.0, 0.4, 1.0]])
    xi = project_points(TRI3, np.repeat(tri, 4, axis=0), pts)
    np.testing.assert_allclose(xi, [[0.5, 0.5], [0, 0], [1, 0], [0, 0.4]], atol=1e-14)


def test_warped_quad():
    # Non-planar bilinear quad (one corner lifted), points all around it.
    rng = np.random.default_rng(13)
    face = np.array([[0, 0, 0], [2, 0, 0], [2, 1.5, 0.9], [0, 1, 0]], dtype=float)
    num = 40
    coords = np.repeat(face[None], num, axis=0)
    pts = rng.uniform([-1.5, -1.5, -3], [3.5, 3, 3], (num, 3))
    xi = project_points(QUAD4, coords, pts)
    ref = _brute_force(QUAD4, coords, pts)
    np.testing.assert_allclose(xi, ref, atol=1e-6)
    _assert_kkt(QUAD4, coords, pts, xi)


@pytest.mark.parametrize("ft", [TRI6, QUAD8, QUAD9], ids=["tri6", "quad8", "quad9"])
def test_curved_quadratic_faces(ft):
    rng = np.random.default_rng(14)
    face = _spherical_cap(ft, radius=2.0, half_width=0.8)
    num = 40
    coords = np.repeat(face[None], num, axis=0)
    # Points near the cap on both sides, and inside the sphere short of its centre.
    directions = rng.normal(size=(num, 3))
    directions[:, 2] = np.abs(directions[:, 2]) + 1.5
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    pts = directions * rng.uniform(0.8, 3.0, num)[:, None]
    xi = project_points(ft, coords, pts)
    ref = _brute_force(ft, coords, pts)
    np.testing.assert_allclose(xi, ref, atol=1e-6)
    _assert_kkt(ft, coords, pts, xi)


@pytest.mark.parametrize("ft", [QUAD4, TRI6, QUAD8, QUAD9], ids=["quad4", "tri6", "quad8", "quad9"])
def test_point_beyond_centre_of_curvature_leaves_the_centre(ft):
    # Below a cap, beyond the sphere centre: the face centre is a *maximum* of the distance
    # (stationary, zero gradient); the closest points are on the boundary.
    if ft is QUAD4:
        face = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=float)
        # Warped: z = (1 + ξη)/4. For this point the centre is a stationary saddle of the
        # distance (Hessian eigenvalues 4.625 and -0.625).
        face[[0, 2], 2] = 0.5
        pt = np.array([[0.0, 0.0, -5.0]])
    else:
        face = _spherical_cap(ft, radius=1.0, half_width=0.5)
        pt = np.array([[0.0, 0.0, -0.5]]) if not ft.is_triangle else None
        if ft.is_triangle:
            # Point on the axis through the face centre, beyond the sphere centre.
            centre = face_points(ft, face[None], ft.center[None])[0]
            pt = -0.5 * centre[None] / np.linalg.norm(centre)
    coords = face[None]
    xi = project_points(ft, coords, pt)
    ref = _brute_force(ft, coords, pt)
    f, f_ref = _sq_dist(ft, coords, pt, xi), _sq_dist(ft, coords, pt, ref)
    f_centre = _sq_dist(ft, coords, pt, ft.center[None])
    assert f[0] < f_centre[0] - 1e-3
    assert f[0] == pytest.approx(f_ref[0], rel=1e-9)
    _assert_kkt(ft, coords, pt, xi)


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_agrees_with_ccx_compass_search(ft):
    # docs/method.md §3.3: the compass search from the centre; near points, mildly distorted faces.
    rng = np.random.default_rng(15)
    num = 300
    coords = _distorted_faces(ft, num, 0.03, rng)
    xi_near = _sample_parameters(ft, num, rng, scale=1.4)
    pts = face_points(ft, coords, ft.clamp(xi_near)) + rng.uniform(-0.3, 0.3, (num, 3))
    xi = project_points(ft, coords, pts)
    np.testing.assert_allclose(xi, _compass(ft, coords, pts), atol=1e-7)


def test_translation_invariance_and_large_coordinates():
    rng = np.random.default_rng(16)
    num = 200
    coords = _distorted_faces(QUAD8, num, 0.05, rng)
    pts = rng.normal(size=(num, 3))
    xi = project_points(QUAD8, coords, pts)
    shift = np.array([1e6, -3e5, 2e5])
    xi_far = project_points(QUAD8, coords + shift, pts + shift)
    np.testing.assert_allclose(xi_far, xi, atol=1e-8)
    # Scaling the whole configuration does not change the parameters either.
    np.testing.assert_allclose(project_points(QUAD8, 1e-3 * coords, 1e-3 * pts), xi, atol=1e-11)


@pytest.mark.parametrize("ft", ALL, ids=IDS)
def test_points_on_the_face_and_at_nodes(ft):
    rng = np.random.default_rng(17)
    coords = _distorted_faces(ft, ft.num_nodes, 0.05, rng)
    # Each face's point is one of its own nodes.
    pts = coords[np.arange(ft.num_nodes), np.arange(ft.num_nodes)]
    xi = project_points(ft, coords, pts)
    np.testing.assert_allclose(xi, ft.node_parameters, atol=1e-9)
    assert np.all(np.isfinite(xi))


def test_start_point():
    rng = np.random.default_rng(18)
    num = 50
    coords = _distorted_faces(QUAD9, num, 0.05, rng)
    pts = rng.normal(size=(num, 3))
    xi = project_points(QUAD9, coords, pts)
    np.testing.assert_allclose(project_points(QUAD9, coords, pts, xi0=xi), xi, atol=1e-13)
    np.testing.assert_allclose(
        project_points(QUAD9, coords, pts, xi0=np.array([5.0, -5.0])), xi, atol=1e-9
    )
    with pytest.raises(ValueError, match="xi0"):
        project_points(QUAD9, coords, pts, xi0=np.zeros((num, 3)))


def test_collapsed_quad_is_not_degenerate():
    # A quad with two coincident nodes has a singular Jacobian at one corner but a positive area.
    face = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0]], dtype=float)
    rng = np.random.default_rng(19)
    num = 30
    coords = np.repeat(face[None], num, axis=0)
    pts = rng.uniform([-0.5, -0.5, -1], [1.5, 1.5, 1], (num, 3))
    xi = project_points(QUAD4, coords, pts)
    assert np.all(np.isfinite(xi))
    f = _sq_dist(QUAD4, coords, pts, xi)
    f_ref = _sq_dist(QUAD4, coords, pts, _brute_force(QUAD4, coords, pts))
    assert np.all(f <= f_ref + 1e-12)


def test_degenerate_faces_raise():
    rng = np.random.default_rng(20)
    coords = _distorted_faces(QUAD4, 5, 0.05, rng)
    coords[3] = np.array([[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]])  # on a line
    with pytest.raises(ValueError, match=r"degenerate.*\b3\b"):
        project_points(QUAD4, coords, np.zeros((5, 3)))
    coords[3] = 1.0  # a single point
    with pytest.raises(ValueError, match=r"\b3\b"):
        project_points(QUAD4, coords, np.zeros((5, 3)))


def test_bad_input():
    coords = _distorted_faces(TRI3, 4, 0.05, np.random.default_rng(21))
    with pytest.raises(ValueError, match="face_coords"):
        project_points(QUAD4, coords, np.zeros((4, 3)))
    with pytest.raises(ValueError, match="points"):
        project_points(TRI3, coords, np.zeros((3, 3)))
    pts = np.zeros((4, 3))
    pts[2, 1] = np.nan
    with pytest.raises(ValueError, match=r"points.*\b2\b"):
        project_points(TRI3, coords, pts)
    coords[1, 0, 0] = np.inf
    with pytest.raises(ValueError, match=r"face_coords.*\b1\b"):
        project_points(TRI3, coords, np.zeros((4, 3)))


def test_empty_batch():
    assert project_points(QUAD8, np.zeros((0, 8, 3)), np.zeros((0, 3))).shape == (0, 2)


def test_batch_of_ten_thousand_points():
    """A large mixed batch stays finite and inside the domain
    (timing: benchmarks/contact_phases.py)."""
    rng = np.random.default_rng(22)
    num = 10_000
    coords = _distorted_faces(QUAD8, num, 0.05, rng)
    xi_near = _sample_parameters(QUAD8, num, rng, scale=1.3)
    pts = face_points(QUAD8, coords, QUAD8.clamp(xi_near)) + rng.uniform(-0.3, 0.3, (num, 3))
    xi = project_points(QUAD8, coords, pts)
    assert np.all(np.isfinite(xi))
    assert np.all(QUAD8.contains(xi, 1e-14))
