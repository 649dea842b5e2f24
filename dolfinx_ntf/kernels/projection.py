"""Closest point of a face to a point, over the closed parametric domain (docs/method.md §3.3).

CalculiX minimizes ``f(ξ) = ½|x - q(ξ)|²`` by a compass search started at the face centre, to
about 1e-8 in parameter space. We find the same kind of local minimum to near machine precision
with a vectorized, safeguarded Newton method:

- the Hessian is the full one, ``H_ab = q_a·q_b - r·q_ab``, shifted to be positive definite when
  it is not (far points on the concave side of curved faces);
- each step solves the quadratic model *exactly over the domain* (a 2D convex QP: the unconstrained
  minimizer if it is inside, else the best point of the domain edges), so active edges and corners
  are handled without active-set bookkeeping and every iterate stays feasible;
- on an edge where the true Hessian is convex along the edge, the step is the exact 1D Newton
  step along it, so convergence to boundary minima stays quadratic;
- steps are capped at a quarter of the domain width (following the descent path from the centre,
  like the compass search) and backtracked until the Armijo condition holds; steps of a shifted
  (non-convex) model may be stretched up to the cap first. Decreases of f are computed as
  ``-Δq·r + ½|Δq|²`` with Δq from exact shape-function increments, so they stay accurate near
  convergence and for points far from the face;
- a stationary point with negative curvature (e.g. a point below the centre of a concave face,
  where the centre is a maximum of the distance) is probed like a compass step and left for a
  lower neighbour.

Coordinates are shifted to each face's centroid first, so the result does not lose digits for
meshes far from the origin.
"""

from __future__ import annotations

import numpy as np

from dolfinx_ntf.kernels.faces import FaceType, face_coords_array

__all__ = ["project_points"]

# Newton safeguards.
_ARMIJO = 1e-4
_MAX_BACKTRACKS = 40
_NEWTON_TRUST = 1e-6  # Newton steps below this are taken without line search (quadratic regime)
_STAGNATION = 1e-10  # steps below this that stop shrinking mean round-off level
_PD_MIN = 1e-10  # H counts as positive definite if λ_min > _PD_MIN * (|q_ξ|² + |q_η|²)
_SHIFT = 1e-3  # otherwise shift to λ_min = _SHIFT * (|q_ξ|² + |q_η|²)
_NEG_CURVATURE = 1e-8  # probe stationary points with λ_min < -_NEG_CURVATURE * (...)
_PROBE_ROUNDS = 3
_DEGENERATE = 1e-12  # face area below this times its squared size is degenerate


def project_points(
    face_type: FaceType,
    face_coords: np.ndarray,
    points: np.ndarray,
    *,
    xi0: np.ndarray | None = None,
    tol: float = 1e-14,
    max_iter: int = 50,
) -> np.ndarray:
    """Parameters of the closest point of each face to its point, over the closed domain.

    Args:
        face_type: Type of all faces.
        face_coords: (N, n, 3) node coordinates of the faces, CalculiX face order.
        points: (N, 3) points to project, one per face.
        xi0: Optional (N, 2) or (2,) start parameters (clamped into the domain); default the face
            centre, (0, 0) for quads as CalculiX, and (1/3, 1/3) for triangles (CalculiX's folded
            square search effectively starts at (1/2, 1/2), on the hypotenuse).
        tol: Newton stops when a step is below this in parameter space (max norm).
        max_iter: Maximum Newton iterations per point and probing round.

    Returns:
        (N, 2) parameters ξ* in the closed domain. For points whose foot lies outside the face
        this is a boundary point, where ``r = x - q`` is not orthogonal to the face.

    Raises:
        ValueError: On wrong shapes, non-finite input or degenerate (zero-area) faces.
    """
    xi, _ = _project(face_type, face_coords, points, xi0=xi0, tol=tol, max_iter=max_iter)
    return xi


def _project(
    face_type: FaceType,
    face_coords: np.ndarray,
    points: np.ndarray,
    *,
    xi0: np.ndarray | None,
    tol: float,
    max_iter: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Projection returning ``(xi, iterations)``; iterations counts Newton steps per point."""
    coords, pts = _validate(face_type, face_coords, points)
    num = coords.shape[0]
    if max_iter < 1:
        raise ValueError(f"max_iter must be at least 1, got {max_iter}")
    if not tol >= 0.0:
        raise ValueError(f"tol must be non-negative, got {tol}")

    centroid = coords.mean(axis=1)
    nodes = coords - centroid[:, None, :]
    pts = pts - centroid
    size2 = np.sum((nodes.max(axis=1) - nodes.min(axis=1)) ** 2, axis=1)
    _check_degenerate(face_type, nodes, size2)

    if xi0 is None:
        xi = np.broadcast_to(face_type.center, (num, 2)).copy()
    else:
        start = np.asarray(xi0, dtype=float)
        if start.shape not in ((2,), (num, 2)):
            raise ValueError(f"xi0 must have shape (2,) or ({num}, 2), got {start.shape}")
        if not np.all(np.isfinite(start)):
            raise ValueError(f"xi0 has non-finite entries at rows {_rows(~np.isfinite(start))}")
        xi = face_type.clamp(np.broadcast_to(start, (num, 2))).copy()

    iterations = np.zeros(num, dtype=np.int64)
    todo = np.arange(num)
    width = 1.0 if face_type.is_triangle else 2.0
    for _ in range(_PROBE_ROUNDS + 1):
        if todo.size == 0:
            break
        args = (face_type, nodes[todo], pts[todo])
        xi[todo], its = _newton(*args, xi[todo], size2[todo], tol, max_iter, width)
        iterations[todo] += its
        xi[todo], improved = _probe(*args, xi[todo], size2[todo], width)
        todo = todo[improved]

    if not np.all(np.isfinite(xi)):  # pragma: no cover - guarded by the checks above
        bad = _rows(~np.isfinite(xi))
        raise RuntimeError(f"projection produced non-finite parameters for faces {bad}")
    return face_type.clamp(xi), iterations


def _rows(mask: np.ndarray) -> str:
    """Short text listing the first rows where ``mask`` holds (any over trailing axes)."""
    mask = np.asarray(mask)
    if mask.ndim > 1:
        mask = mask.reshape(mask.shape[0], -1).any(axis=1)
    rows = np.flatnonzero(mask)
    text = ", ".join(str(i) for i in rows[:10])
    return text + (f", ... ({rows.size} in all)" if rows.size > 10 else "")


def _validate(
    face_type: FaceType, face_coords: np.ndarray, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    coords = face_coords_array(face_type, face_coords, rows="N")
    pts = np.asarray(points, dtype=float)
    if pts.shape != (coords.shape[0], 3):
        raise ValueError(f"points must have shape ({coords.shape[0]}, 3), got {pts.shape}")
    if not np.all(np.isfinite(coords)):
        bad = _rows(~np.isfinite(coords))
        raise ValueError(f"face_coords has non-finite entries for faces {bad}")
    if not np.all(np.isfinite(pts)):
        raise ValueError(f"points has non-finite entries at rows {_rows(~np.isfinite(pts))}")
    return coords, pts


def _check_degenerate(face_type: FaceType, nodes: np.ndarray, size2: np.ndarray) -> None:
    """Raise if a face has (numerically) zero area."""
    qp = face_type.quadrature_points
    dphi = face_type.shape_derivatives(qp)  # (q, n, 2)
    tang = np.swapaxes(dphi, 1, 2).reshape(-1, face_type.num_nodes) @ nodes  # (F, 2q, 3)
    jac = np.linalg.norm(np.cross(tang[:, 0::2], tang[:, 1::2]), axis=-1)
    area = jac @ face_type.quadrature_weights
    bad = ~(area > _DEGENERATE * size2)
    if np.any(bad):
        raise ValueError(f"degenerate (zero-area) {face_type.name} faces: {_rows(bad)}")


def _residual(face_type: FaceType, nodes: np.ndarray, pts: np.ndarray, xi: np.ndarray):
    """R = x - q, phi, tangents J (M, 2, 3) and second derivatives K (M, 3, 3) at ``xi``."""
    phi = face_type.shape_functions(xi)
    r = pts - (phi[:, None, :] @ nodes)[:, 0]
    jac = np.swapaxes(face_type.shape_derivatives(xi), 1, 2) @ nodes
    hess = np.swapaxes(face_type.shape_second_derivatives(xi), 1, 2) @ nodes
    return r, phi, jac, hess


def _decrease(
    face_type: FaceType, nodes: np.ndarray, r: np.ndarray, xi: np.ndarray, step: np.ndarray
) -> np.ndarray:
    """f(ξ + step) - f(ξ) as -Δq·r + ½|Δq|², accurate relative to the step even if |r| ≫ |Δq|."""
    dq = (face_type.shape_function_increments(xi, step)[:, None, :] @ nodes)[:, 0]
    return -np.sum(dq * r, axis=1) + 0.5 * np.sum(dq * dq, axis=1)


def _hessian(r: np.ndarray, jac: np.ndarray, hess: np.ndarray, size2: np.ndarray) -> tuple:
    """Derivatives of f = ½|r|²: ``(g, a, b, c, lam, v, scale)``.

    g (M, 2) is the gradient, H = [[a, b], [b, c]] the full Hessian, lam its smallest eigenvalue
    with unit eigenvector v (M, 2), and scale = |q_ξ|² + |q_η|² (bounded below) its natural size.
    """
    q1, q2 = jac[:, 0], jac[:, 1]
    g = -np.stack([np.sum(r * q1, axis=1), np.sum(r * q2, axis=1)], axis=1)
    a = np.sum(q1 * q1, axis=1) - np.sum(r * hess[:, 0], axis=1)
    b = np.sum(q1 * q2, axis=1) - np.sum(r * hess[:, 1], axis=1)
    c = np.sum(q2 * q2, axis=1) - np.sum(r * hess[:, 2], axis=1)
    scale = np.maximum(np.sum(q1 * q1, axis=1) + np.sum(q2 * q2, axis=1), 1e-8 * size2)
    mean = 0.5 * (a + c)
    rad = np.hypot(0.5 * (a - c), b)
    lam = mean - rad
    # Eigenvector of lam: the better conditioned of (b, lam - a) and (lam - c, b).
    v1 = np.stack([b, lam - a], axis=1)
    v2 = np.stack([lam - c, b], axis=1)
    n1 = np.linalg.norm(v1, axis=1)
    n2 = np.linalg.norm(v2, axis=1)
    v = np.where((n1 >= n2)[:, None], v1, v2)
    nv = np.maximum(n1, n2)
    v = np.where((nv > 0)[:, None], v / np.where(nv > 0, nv, 1.0)[:, None], [1.0, 0.0])
    return g, a, b, c, lam, v, scale


def _qp_step(
    face_type: FaceType,
    xi: np.ndarray,
    g: np.ndarray,
    hessian: tuple[np.ndarray, np.ndarray, np.ndarray],
    shift: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Step minimizing the quadratic model over the domain, and whether it is a Newton step.

    The model is g·d + ½ dᵀ(H + shift I)d with H = [[a, b], [b, c]]; the shift makes it convex,
    so its minimizer over the polygon is the free minimizer if that is inside, else the best point
    of the edges. When ξ already lies on the edge holding the minimizer and the true H is convex
    along that edge, the edge step is redone with the true H (1D Newton on the active edge), so
    the shift does not slow down convergence to boundary minima.

    Returns:
        d (M, 2) with ξ + d in the domain, and ``exact`` (M,): d minimizes a true (unshifted)
        convex model, so the full step is the natural trial step.
    """
    a, b, c = hessian
    sa, sc = a + shift, c + shift
    shifted = shift > 0.0
    det = sa * sc - b * b
    d_free = -np.stack([sc * g[:, 0] - b * g[:, 1], sa * g[:, 1] - b * g[:, 0]], axis=1)
    d_free /= det[:, None]
    inside = face_type.contains(xi + d_free)
    exact = ~shifted
    if np.all(inside):
        return d_free, exact

    def quad_form(ha, hb, hc, u, w):
        return (
            ha * u[..., 0] * w[..., 0]
            + hb * (u[..., 0] * w[..., 1] + u[..., 1] * w[..., 0])
            + (hc * u[..., 1] * w[..., 1])
        )

    best = d_free.copy()
    best_val = np.where(inside, -np.inf, np.inf)
    corners = face_type.node_parameters[: face_type.num_corners]
    for k in range(face_type.num_corners):
        start = corners[k]
        edge = corners[(k + 1) % face_type.num_corners] - start
        ee = edge @ edge
        d0 = start - xi
        ge = g @ edge
        t = -(ge + quad_form(sa, b, sc, d0, edge)) / quad_form(sa, b, sc, edge, edge)
        d = d0 + np.clip(t, 0.0, 1.0)[:, None] * edge
        val = np.sum(g * d, axis=1) + 0.5 * quad_form(sa, b, sc, d, d)
        better = val < best_val
        # ξ on this edge already and H convex along it: 1D Newton with the true Hessian.
        offset = np.abs(d0[:, 0] * edge[1] - d0[:, 1] * edge[0]) / ee
        curv = quad_form(a, b, c, edge, edge)
        on_convex_edge = (offset <= 1e-14) & (curv > _PD_MIN * np.abs(sa + sc) * ee)
        t_true = -(ge + quad_form(a, b, c, d0, edge)) / np.where(on_convex_edge, curv, 1.0)
        d = np.where(on_convex_edge[:, None], d0 + np.clip(t_true, 0.0, 1.0)[:, None] * edge, d)
        best[better] = d[better]
        best_val[better] = val[better]
        exact = np.where(better, on_convex_edge | ~shifted, exact)
    return best, exact


def _newton(
    face_type: FaceType,
    nodes: np.ndarray,
    pts: np.ndarray,
    xi: np.ndarray,
    size2: np.ndarray,
    tol: float,
    max_iter: int,
    width: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Safeguarded Newton iterations from ``xi``; returns the final ξ and the iteration counts."""
    xi = xi.copy()
    iterations = np.zeros(xi.shape[0], dtype=np.int64)
    prev = np.full(xi.shape[0], np.inf)
    active = np.arange(xi.shape[0])
    cap = 0.25 * width
    for _ in range(max_iter):
        if active.size == 0:
            break
        x = xi[active]
        nd = nodes[active]
        r, _, jac, hess = _residual(face_type, nd, pts[active], x)
        g, a, b, c, lam, _, scale = _hessian(r, jac, hess, size2[active])
        shift = np.where(lam > _PD_MIN * scale, 0.0, _SHIFT * scale - lam)
        d, exact = _qp_step(face_type, x, g, (a, b, c), shift)
        dnorm = np.max(np.abs(d), axis=1)
        # Newton steps start at the full step; steps of a shifted (non-convex) model may be
        # stretched up to the cap, since the true function falls faster than the model.
        alpha = cap / np.where(dnorm > 0, dnorm, 1.0)
        alpha = np.where(exact, np.minimum(1.0, alpha), alpha)

        # Backtracking (projected) line search, except for small Newton steps: there f decreases
        # by less than the round-off of keeping ξ on a slanted edge (|g|·ulp), so the test is
        # meaningless, and the step is reliable.
        idx = np.flatnonzero(~exact | (alpha * dnorm > _NEWTON_TRUST))
        for _ in range(_MAX_BACKTRACKS):
            if idx.size == 0:
                break
            xs = x[idx]
            step = face_type.clamp(xs + alpha[idx, None] * d[idx]) - xs
            df = _decrease(face_type, nd[idx], r[idx], xs, step)
            ok = (df < 0.0) & (df <= _ARMIJO * np.minimum(np.sum(g[idx] * step, axis=1), 0.0))
            idx = idx[~ok]
            alpha[idx] *= 0.5
        failed = np.zeros(active.size, dtype=bool)
        failed[idx] = True  # no decrease found: stationary to working precision
        alpha[failed] = 0.0

        new = face_type.clamp(x + alpha[:, None] * d)
        snorm = np.max(np.abs(new - x), axis=1)
        xi[active] = new
        iterations[active] += 1
        done = failed | (snorm <= tol) | ((snorm <= _STAGNATION) & (snorm >= 0.5 * prev[active]))
        prev[active] = snorm
        active = active[~done]
    return xi, iterations


def _probe(
    face_type: FaceType,
    nodes: np.ndarray,
    pts: np.ndarray,
    xi: np.ndarray,
    size2: np.ndarray,
    width: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Move points sitting at negative curvature to their best lower compass neighbour.

    Returns the updated ξ and a mask of the points that moved (to be re-minimized).
    """
    xi = xi.copy()
    moved = np.zeros(xi.shape[0], dtype=bool)
    r, _phi, jac, hess = _residual(face_type, nodes, pts, xi)
    _, _, _, _, lam, v, scale = _hessian(r, jac, hess, size2)
    idx = np.flatnonzero(lam < -_NEG_CURVATURE * scale)
    if idx.size == 0:
        return xi, moved
    h = 0.01 * width
    s = 1.0 / np.sqrt(2.0)
    dirs = [v[idx], -v[idx]] + [
        np.broadcast_to(np.array(e, dtype=float), (idx.size, 2))
        for e in ((1, 0), (-1, 0), (0, 1), (0, -1), (s, s), (-s, -s), (s, -s), (-s, s))
    ]
    best = xi[idx].copy()
    best_df = np.zeros(idx.size)
    for direction in dirs:
        trial = face_type.clamp(xi[idx] + h * direction)
        df = _decrease(face_type, nodes[idx], r[idx], xi[idx], trial - xi[idx])
        better = df < best_df
        best[better] = trial[better]
        best_df[better] = df[better]
    rnorm = np.linalg.norm(r[idx], axis=1)
    root = np.sqrt(scale[idx])
    noise = 1e-13 * h * root * (rnorm + h * root)
    improved = best_df < -noise
    xi[idx[improved]] = best[improved]
    moved[idx[improved]] = True
    return xi, moved
