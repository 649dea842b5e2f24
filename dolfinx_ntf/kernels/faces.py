"""Master/slave face types: shape functions, ccx spring-area weights, triangulation, quadrature.

Pure numpy. Every face type uses CalculiX's face-local node order (corners counter-clockwise seen
from outside the body, then midside nodes), so that ``m = q_ξ × q_η`` points out of the body:

- tri3: φ = (1-ξ-η, ξ, η) on the unit triangle ``ξ, η ≥ 0, ξ + η ≤ 1``;
- tri6: corners as tri3, then midside nodes 4 on 1-2, 5 on 2-3, 6 on 3-1;
- quad4: bilinear on ``[-1, 1]^2``, node 1 at (-1,-1), 2 at (1,-1), 3 at (1,1), 4 at (-1,1);
- quad8: serendipity, then midside nodes 5 on 1-2, 6 on 2-3, 7 on 3-4, 8 on 4-1;
- quad9: biquadratic Lagrange, nodes as quad8 plus node 9 at the centre.

Shape functions are stored as coefficients on the nine monomials ``ξ^a η^b`` (a, b ≤ 2),
obtained by inverting the nodal Vandermonde matrix of each type's monomial space; derivatives
of any order are then exact coefficient maps. Face-local node indices are 0-based everywhere.

Choice for quad9 (no CalculiX analogue): its master triangulation is a fan of 8 triangles around
the centre node, ``(corner, midside, centre)`` and ``(midside, corner, centre)``, so the centre node
takes part in the search geometry of a curved face; its spring-area weights are the tensor
products of Simpson's rule (1/36 corners, 1/9 midside, 4/9 centre).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "FACE_TYPES",
    "QUAD4",
    "QUAD8",
    "QUAD8_GAUSS2",
    "QUAD9",
    "TRI3",
    "TRI6",
    "FaceType",
    "face_coords_array",
    "face_points",
    "face_tangents",
    "face_type_from_num_nodes",
    "film_matrices",
    "flux_flows",
    "pressure_forces",
    "pressure_stiffness",
]

# Monomial basis ξ^a η^b shared by all face types; row k of a coefficient matrix multiplies it.
_EXPONENTS = np.array([(a, b) for a in range(3) for b in range(3)], dtype=int)  # (9, 2)
_MONOMIAL_INDEX = {(int(a), int(b)): k for k, (a, b) in enumerate(_EXPONENTS)}


def _derivative_map(axis: int) -> np.ndarray:
    """Matrix D (9, 9): D @ C holds the coefficients of ∂C/∂ξ (axis 0) or ∂C/∂η (axis 1)."""
    d = np.zeros((9, 9))
    for k, (a, b) in enumerate(_EXPONENTS):
        power = (a, b)[axis]
        if power == 0:
            continue
        lowered = (a - 1, b) if axis == 0 else (a, b - 1)
        d[_MONOMIAL_INDEX[lowered], k] = power
    return d


_D_XI = _derivative_map(0)
_D_ETA = _derivative_map(1)


def _monomials(xi: np.ndarray) -> np.ndarray:
    """Evaluate the nine monomials ξ^a η^b at ``xi`` (..., 2) -> (..., 9)."""
    x = xi[..., 0]
    y = xi[..., 1]
    one = np.ones_like(x)
    xp = (one, x, x * x)
    yp = (one, y, y * y)
    return np.stack([xp[a] * yp[b] for a, b in _EXPONENTS], axis=-1)


def _monomial_increments(xi: np.ndarray, dxi: np.ndarray) -> np.ndarray:
    """Increments of the nine monomials from ``xi`` to ``xi + dxi``, in factored form."""
    x, y = xi[..., 0], xi[..., 1]
    dx, dy = dxi[..., 0], dxi[..., 1]
    zero = np.zeros(np.broadcast(x, dx).shape)
    one = np.ones_like(zero)
    y1 = y + dy
    xp = (one, x, x * x)
    yp1 = (one, y1, y1 * y1)
    dxp = (zero, dx + zero, dx * (2.0 * x + dx))
    dyp = (zero, dy + zero, dy * (2.0 * y + dy))
    # Δ(AB) = ΔA·B' + A·ΔB.
    return np.stack([dxp[a] * yp1[b] + xp[a] * dyp[b] for a, b in _EXPONENTS], axis=-1)


def _as_parameters(xi: np.ndarray | list | tuple) -> np.ndarray:
    """Validate parametric coordinates: float array with a last axis of length 2."""
    arr = np.asarray(xi, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValueError(f"parametric coordinates xi must have shape (..., 2), got {arr.shape}")
    return arr


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class FaceType:
    """A face type: node layout, shape functions, ccx weights, triangulation and area quadrature.

    Attributes:
        name: ``"tri3"``, ``"quad4"``, ``"tri6"``, ``"quad8"`` or ``"quad9"``.
        num_nodes: Number of face nodes n.
        num_corners: Number of corner nodes (3 or 4); corners come first.
        is_triangle: Whether the parametric domain is the unit triangle (else ``[-1, 1]^2``).
        node_parameters: (n, 2) parametric coordinates of the nodes.
        area_weights: (n,) ccx spring-area weights w (docs/method.md §2.2), summing to 1.
        triangles: (t, 3) face-local node triples of the master triangulation (docs/method.md
            §2.3), each oriented like the face.
        quadrature_points: (q, 2) points of the face-area rule.
        quadrature_weights: (q,) weights of the face-area rule; they sum to the area of the
            parametric domain (1/2 or 4), so ``|f| = Σ_q w_q |q_ξ × q_η|(ξ_q)``.
    """

    name: str
    num_nodes: int
    num_corners: int
    is_triangle: bool
    node_parameters: np.ndarray
    area_weights: np.ndarray
    triangles: np.ndarray
    quadrature_points: np.ndarray
    quadrature_weights: np.ndarray
    _coefficients: np.ndarray = field(repr=False)

    @property
    def center(self) -> np.ndarray:
        """Parametric centre of the face, (0, 0) for quads and (1/3, 1/3) for triangles."""
        return np.array([1.0 / 3.0, 1.0 / 3.0]) if self.is_triangle else np.zeros(2)

    def shape_functions(self, xi: np.ndarray) -> np.ndarray:
        """Shape functions φ_j at ``xi`` (..., 2) -> (..., n)."""
        return _monomials(_as_parameters(xi)) @ self._coefficients

    def shape_derivatives(self, xi: np.ndarray) -> np.ndarray:
        """First derivatives at ``xi`` (..., 2) -> (..., n, 2), last axis [∂/∂ξ, ∂/∂η]."""
        m = _monomials(_as_parameters(xi))
        c = self._coefficients
        return np.stack([m @ (_D_XI @ c), m @ (_D_ETA @ c)], axis=-1)

    def shape_second_derivatives(self, xi: np.ndarray) -> np.ndarray:
        """Second derivatives at ``xi`` (..., 2) -> (..., n, 3), last axis [ξξ, ξη, ηη]."""
        m = _monomials(_as_parameters(xi))
        c = self._coefficients
        return np.stack(
            [m @ (_D_XI @ _D_XI @ c), m @ (_D_XI @ _D_ETA @ c), m @ (_D_ETA @ _D_ETA @ c)],
            axis=-1,
        )

    def shape_function_increments(self, xi: np.ndarray, dxi: np.ndarray) -> np.ndarray:
        """φ(ξ + Δξ) - φ(ξ) for ``xi``, ``dxi`` (..., 2) -> (..., n), without cancellation.

        Accurate relative to ``|Δξ|`` even for tiny increments (line searches, projections).
        """
        xi = _as_parameters(xi)
        dxi = _as_parameters(dxi)
        return _monomial_increments(xi, dxi) @ self._coefficients

    def contains(self, xi: np.ndarray, tol: float = 0.0) -> np.ndarray:
        """Whether ``xi`` (..., 2) lies in the closed parametric domain, enlarged by ``tol``."""
        xi = _as_parameters(xi)
        x, y = xi[..., 0], xi[..., 1]
        if self.is_triangle:
            return (x >= -tol) & (y >= -tol) & (x + y <= 1.0 + tol)
        return (np.abs(x) <= 1.0 + tol) & (np.abs(y) <= 1.0 + tol)

    def clamp(self, xi: np.ndarray) -> np.ndarray:
        """Nearest point (Euclidean, in parameter space) of the closed domain to ``xi`` (..., 2).

        Points inside are returned unchanged (as a copy).
        """
        xi = _as_parameters(xi)
        if not self.is_triangle:
            return np.clip(xi, -1.0, 1.0)
        return _clamp_unit_triangle(xi)


def _clamp_unit_triangle(xi: np.ndarray) -> np.ndarray:
    """Euclidean projection onto the unit triangle: the nearest of the three edge projections."""
    out = xi.copy()
    inside = (xi[..., 0] >= 0.0) & (xi[..., 1] >= 0.0) & (xi[..., 0] + xi[..., 1] <= 1.0)
    if np.all(inside):
        return out
    # Edges as (start, direction) in the parameter plane.
    edges = (
        (np.array([0.0, 0.0]), np.array([1.0, 0.0])),
        (np.array([1.0, 0.0]), np.array([-1.0, 1.0])),
        (np.array([0.0, 1.0]), np.array([0.0, -1.0])),
    )
    best = None
    best_d2 = None
    for start, direction in edges:
        t = ((xi - start) @ direction) / (direction @ direction)
        cand = start + np.clip(t, 0.0, 1.0)[..., None] * direction
        if best is None:
            best, best_d2 = cand, np.sum((xi - cand) ** 2, axis=-1)
            continue
        d2 = np.sum((xi - cand) ** 2, axis=-1)
        closer = d2 < best_d2
        best = np.where(closer[..., None], cand, best)
        best_d2 = np.where(closer, d2, best_d2)
    out = np.where(inside[..., None], xi, best)
    # The hypotenuse projection can miss ξ+η ≤ 1 by one ulp; enforce the domain exactly.
    over = out[..., 0] + out[..., 1] - 1.0
    fix = over > 0.0
    if np.any(fix):
        out[..., 0] = np.where(fix, out[..., 0] - over, out[..., 0])
        out[..., 0] = np.maximum(out[..., 0], 0.0)
    return out


def _make_face_type(
    name: str,
    num_corners: int,
    is_triangle: bool,
    node_parameters: list,
    monomials: list,
    area_weights: list,
    triangles: list,
    quadrature_points: np.ndarray,
    quadrature_weights: np.ndarray,
) -> FaceType:
    """Build a FaceType; the shape functions are the nodal basis of the given monomial space."""
    params = np.array(node_parameters, dtype=float)
    n = len(params)
    vander = np.stack([params[:, 0] ** a * params[:, 1] ** b for a, b in monomials], axis=1)
    inv = np.linalg.inv(vander)  # (m, n): column j are the coefficients of φ_j
    # All coefficients are multiples of 1/4: snap away the round-off of the inversion.
    snapped = np.round(inv * 4.0) / 4.0
    assert np.allclose(snapped, inv, atol=1e-12), name
    coefficients = np.zeros((9, n))
    for row, (a, b) in zip(snapped, monomials):
        coefficients[_MONOMIAL_INDEX[(a, b)]] = row
    weights = np.array(area_weights, dtype=float)
    return FaceType(
        name=name,
        num_nodes=n,
        num_corners=num_corners,
        is_triangle=is_triangle,
        node_parameters=_readonly(params),
        area_weights=_readonly(weights),
        triangles=_readonly(np.array(triangles, dtype=np.int64)),
        quadrature_points=_readonly(np.asarray(quadrature_points, dtype=float)),
        quadrature_weights=_readonly(np.asarray(quadrature_weights, dtype=float)),
        _coefficients=_readonly(coefficients),
    )


def _gauss_square(order: int) -> tuple[np.ndarray, np.ndarray]:
    """Tensor Gauss-Legendre rule on [-1, 1]^2 with ``order`` points per direction."""
    x, w = np.polynomial.legendre.leggauss(order)
    px, py = np.meshgrid(x, x, indexing="ij")
    wx, wy = np.meshgrid(w, w, indexing="ij")
    return np.stack([px.ravel(), py.ravel()], axis=1), (wx * wy).ravel()


_TRI_CORNERS = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
_TRI_MIDS = [(0.5, 0.0), (0.5, 0.5), (0.0, 0.5)]
_QUAD_CORNERS = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
_QUAD_MIDS = [(0.0, -1.0), (1.0, 0.0), (0.0, 1.0), (-1.0, 0.0)]

_Q1, _W1 = _gauss_square(2)
_Q3, _W3 = _gauss_square(3)

TRI3 = _make_face_type(
    "tri3",
    3,
    True,
    _TRI_CORNERS,
    [(0, 0), (1, 0), (0, 1)],
    [1 / 3] * 3,
    [(0, 1, 2)],
    np.array([[1 / 3, 1 / 3]]),
    np.array([0.5]),
)

QUAD4 = _make_face_type(
    "quad4",
    4,
    False,
    _QUAD_CORNERS,
    [(0, 0), (1, 0), (0, 1), (1, 1)],
    [1 / 4] * 4,
    [(0, 1, 3), (1, 2, 3)],
    _Q1,
    _W1,
)

TRI6 = _make_face_type(
    "tri6",
    3,
    True,
    _TRI_CORNERS + _TRI_MIDS,
    [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)],
    [1 / 999] * 3 + [332 / 999] * 3,
    [(0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5)],
    # Degree-2 rule with interior points.
    np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]),
    np.full(3, 1 / 6),
)

QUAD8 = _make_face_type(
    "quad8",
    4,
    False,
    _QUAD_CORNERS + _QUAD_MIDS,
    [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (2, 1), (1, 2)],
    [1 / 100] * 4 + [24 / 100] * 4,
    [(0, 4, 7), (4, 1, 5), (6, 5, 2), (7, 6, 3), (7, 4, 6), (4, 5, 6)],
    _Q3,
    _W3,
)

#: ``QUAD8`` with ccx's 2 x 2 Gauss points for the face area ``|f|`` of the spring areas: ccx's
#: rule on the quadrilateral faces of C3D15 (3 x 3 on C3D20's; docs/method.md §38). Its name
#: stays ``"quad8"``: the layout, weights and triangles are QUAD8's; not in ``FACE_TYPES``.
QUAD8_GAUSS2 = dataclasses.replace(
    QUAD8, quadrature_points=_readonly(_Q1.copy()), quadrature_weights=_readonly(_W1.copy())
)

QUAD9 = _make_face_type(
    "quad9",
    4,
    False,
    _QUAD_CORNERS + _QUAD_MIDS + [(0.0, 0.0)],
    [(int(a), int(b)) for a, b in _EXPONENTS],
    [1 / 36] * 4 + [1 / 9] * 4 + [4 / 9],
    [(0, 4, 8), (4, 1, 8), (1, 5, 8), (5, 2, 8), (2, 6, 8), (6, 3, 8), (3, 7, 8), (7, 0, 8)],
    _Q3,
    _W3,
)

FACE_TYPES: dict[str, FaceType] = {ft.name: ft for ft in (TRI3, QUAD4, TRI6, QUAD8, QUAD9)}
_BY_NUM_NODES = {ft.num_nodes: ft for ft in FACE_TYPES.values()}


def face_type_from_num_nodes(n: int) -> FaceType:
    """The face type with ``n`` nodes (3, 4, 6, 8 or 9 are unique).

    Raises:
        ValueError: If no face type has ``n`` nodes.
    """
    try:
        return _BY_NUM_NODES[int(n)]
    except (KeyError, TypeError, ValueError):
        raise ValueError(
            f"no face type with {n!r} nodes (expected one of {sorted(_BY_NUM_NODES)})"
        ) from None


def face_coords_array(
    face_type: FaceType, face_coords: np.ndarray, what: str = "face_coords", rows: str = "F"
) -> np.ndarray:
    """``face_coords`` as a float array of shape (rows, n, 3), else a ValueError naming ``what``."""
    coords = np.asarray(face_coords, dtype=float)
    n = face_type.num_nodes
    if coords.ndim != 3 or coords.shape[1:] != (n, 3):
        raise ValueError(
            f"{what} must have shape ({rows}, {n}, 3) for {face_type.name} faces, "
            f"got {coords.shape}"
        )
    return coords


def _check_coords(face_type: FaceType, face_coords: np.ndarray) -> np.ndarray:
    coords = np.asarray(face_coords, dtype=float)
    if coords.ndim < 2 or coords.shape[-2:] != (face_type.num_nodes, 3):
        raise ValueError(
            f"face_coords must have shape (..., {face_type.num_nodes}, 3) for "
            f"{face_type.name}, got {coords.shape}"
        )
    return coords


def face_points(face_type: FaceType, face_coords: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Points q(ξ) = Σ_j φ_j(ξ) x_j of faces (..., n, 3) at parameters (..., 2) -> (..., 3)."""
    coords = _check_coords(face_type, face_coords)
    phi = face_type.shape_functions(xi)
    return (phi[..., None, :] @ coords)[..., 0, :]


def face_tangents(
    face_type: FaceType, face_coords: np.ndarray, xi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Tangent vectors (q_ξ, q_η), each (..., 3), of faces (..., n, 3) at parameters (..., 2).

    ``q_ξ × q_η`` points out of the body for faces in CalculiX node order.
    """
    coords = _check_coords(face_type, face_coords)
    dphi = face_type.shape_derivatives(xi)
    q = np.swapaxes(dphi, -1, -2) @ coords
    return q[..., 0, :], q[..., 1, :]


def _at_rule_points(
    face_type: FaceType, face_coords: np.ndarray, rule: tuple[np.ndarray, np.ndarray] | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points ``(q, 2)``, weights ``(q,)``, shape functions ``(q, n)`` and tangents ``(F, q, 3)``.

    ``rule`` as for :func:`pressure_forces` (None: the face type's area rule).
    """
    coords = face_coords_array(face_type, face_coords)
    if rule is None:
        rule = (face_type.quadrature_points, face_type.quadrature_weights)
    xi, weights = (np.asarray(a, dtype=float) for a in rule)
    q_xi, q_eta = face_tangents(face_type, coords[:, None], xi[None])
    return xi, weights, face_type.shape_functions(xi), q_xi, q_eta


def _areas_at_rule_points(
    face_type: FaceType, face_coords: np.ndarray, rule: tuple[np.ndarray, np.ndarray] | None
) -> tuple[np.ndarray, np.ndarray]:
    """Weighted area elements ``w_q |q_ξ × q_η|`` ``(F, q)`` and shape functions ``(q, n)``."""
    _, weights, phi, q_xi, q_eta = _at_rule_points(face_type, face_coords, rule)
    return np.linalg.norm(np.cross(q_xi, q_eta), axis=-1) * weights[None, :], phi


def pressure_forces(
    face_type: FaceType,
    face_coords: np.ndarray,
    pressure: np.ndarray,
    rule: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Consistent nodal forces ``(F, n, 3)`` of a uniform pressure on each of ``F`` faces.

    ``f_j = -p Σ_q w_q φ_j(ξ_q) (q_ξ × q_η)(ξ_q)``: a pressure pushes against the outward
    normal of faces in CalculiX node order. ``rule``: points ``(q, 2)`` and weights ``(q,)`` in
    the face's parameters; default the face type's area rule (tri6: 3 points, quad8: 3 x 3
    Gauss). Exact for flat faces with straight edges.
    """
    _, weights, phi, q_xi, q_eta = _at_rule_points(face_type, face_coords, rule)
    normal = np.cross(q_xi, q_eta) * weights[None, :, None]
    return -np.asarray(pressure, dtype=float)[:, None, None] * np.einsum("qn,fqd->fnd", phi, normal)


def flux_flows(
    face_type: FaceType,
    face_coords: np.ndarray,
    flux: np.ndarray,
    rule: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Consistent nodal heat flows ``(F, n)`` of a uniform flux into each of ``F`` faces.

    ``h_j = q Σ_q w_q φ_j(ξ_q) |q_ξ × q_η|(ξ_q)`` (CalculiX's ``*DFLUX``: positive into the
    body). ``rule`` as for :func:`pressure_forces`.
    """
    area, phi = _areas_at_rule_points(face_type, face_coords, rule)
    return np.asarray(flux, dtype=float)[:, None] * (area @ phi)


def film_matrices(
    face_type: FaceType,
    face_coords: np.ndarray,
    rule: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """``(F, n, n)`` face mass matrices ``Σ_q w_q φ_i φ_j |q_ξ × q_η|`` of ``F`` faces.

    Times a film coefficient ``h``: the Jacobian of CalculiX's ``*FILM`` heat flow
    ``h (T - T_sink)`` out of the face. ``rule`` as for :func:`pressure_forces`.
    """
    area, phi = _areas_at_rule_points(face_type, face_coords, rule)
    return np.einsum("fq,qi,qj->fij", area, phi, phi)


def _skew(v: np.ndarray) -> np.ndarray:
    """``(..., 3, 3)`` matrices ``[v]_x`` with ``[v]_x w = v x w``."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def pressure_stiffness(
    face_type: FaceType,
    face_coords: np.ndarray,
    pressure: np.ndarray,
    rule: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """``(F, 3n, 3n)`` derivative of :func:`pressure_forces` by the face's node coordinates.

    A follower pressure (on the current faces): ``d(q_ξ x q_η)/dx_k = b_k [q_ξ]_x - a_k
    [q_η]_x`` with ``a_k, b_k`` the shape derivatives of node ``k``; not symmetric.
    """
    xi, weights, phi, q_xi, q_eta = _at_rule_points(face_type, face_coords, rule)
    dphi = face_type.shape_derivatives(xi)  # (q, n, 2)
    # (F, q, n, 3, 3): d n_q / d x_k
    dn = (
        dphi[None, :, :, 1, None, None] * _skew(q_xi)[:, :, None]
        - dphi[None, :, :, 0, None, None] * _skew(q_eta)[:, :, None]
    )
    k = np.einsum("q,qj,fqkab->fjakb", weights, phi, dn)  # (F, n, 3, n, 3)
    n = face_type.num_nodes
    return -np.asarray(pressure, dtype=float)[:, None, None] * k.reshape(-1, 3 * n, 3 * n)
