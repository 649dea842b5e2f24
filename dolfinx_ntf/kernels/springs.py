"""Node-to-face spring elements: residual and consistent tangent, vectorized.

The method is described in docs/method.md §5 (forces) and §6 (tangent).

A spring joins one slave node p to one master face with nodes x_0..x_{n-1}. Its element node
order is ``[master 0..n-1, slave]`` and its element dofs are ``3*k + c``. Everything is evaluated
in the current configuration on the face fixed by the pairing:

- the slave node is projected onto the face (closest point over the closed parametric domain),
  giving ξ*, q = Σ φ_j x_j, r = x_p − q, m = q_ξ × q_η, n = m/|m| and the clearance g = r·n;
- the overclosure is d = −(g − gap_shift) and the normal force F_N = ``law.spring_force(d, A)``;
- the internal forces are f_p = −F_N n on the slave node and f_j = −φ_j f_p on master node j.

The tangent is the exact derivative of these forces with respect to the 3(n+1) nodal positions
(nodes move with u, so ∂/∂u = ∂/∂x), with the spring area A held constant as in CalculiX. It
includes the projection derivatives ∂ξ/∂x, ∂n/∂x, ∂g/∂x and the ∂φ_j/∂x terms of the master
forces. For an interior projection (r ∥ n) the forces are the gradient of the spring energy
A P(d(x)) with P' = p, so this exact tangent is symmetric up to rounding; ``symmetric=True`` then
only removes rounding noise.

Clamped projections: when the closest point lies on an edge of the parametric domain (the slave
node is beside the face) the edge constraint is treated as active and ∂ξ/∂x is the exact
derivative of the constrained closest point (the parameter along the edge moves, the other is
fixed); at a corner ∂ξ/∂x = 0. There r is not ∥ n and the exact tangent is unsymmetric. CalculiX
instead uses the interior-projection formula everywhere (docs/method.md §6.1,
``interior_projection=True``); both coincide for interior projections, the normal contact
situation.

Friction (docs/method.md §11): the kinematics and their derivatives (``_Kinematics``: ∂ξ/∂x,
∂m/∂x, ∂n/∂x, ∂g/∂x) are computed once, ``friction.tangential_forces`` adds the tangential force
F_T to f_p and its derivative to ∂f_p/∂x, and ``_element_stiffness`` turns *any* slave force f_p
and its derivative into the element matrix (docs/method.md §6.1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dolfinx_ntf.kernels.contact_damping import DampingForce, DampingInput, damping_forces
from dolfinx_ntf.kernels.faces import FaceType, face_coords_array
from dolfinx_ntf.kernels.friction import FrictionInput, TangentialForce, tangential_forces
from dolfinx_ntf.kernels.laws import PressureOverclosureLaw
from dolfinx_ntf.kernels.projection import project_points

__all__ = ["MeshedMasterSprings", "SpringEvaluation", "evaluate_springs"]

# A parametric constraint counts as active when the projection lies within this distance of it and
# its Lagrange multiplier (relative to |q_ξ|² + |q_η|²) exceeds _MULTIPLIER_TOL.
_BOUNDARY_TOL = 1e-10
_MULTIPLIER_TOL = 1e-10

# Outward unit normals c (in the (ξ, η) plane) of the domain edges, and the offsets o such that the
# constraint reads c·ξ <= o.
_QUAD_CONSTRAINTS = (np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]), np.ones(4))
_TRIANGLE_CONSTRAINTS = (
    np.array([[-1.0, 0.0], [0.0, -1.0], [np.sqrt(0.5), np.sqrt(0.5)]]),
    np.array([0.0, 0.0, np.sqrt(0.5)]),
)


@dataclass
class SpringEvaluation:
    """Residual (and tangent) of N springs.

    Attributes:
        xi: (N, 2) parametric coordinates of the projection point.
        phi: (N, n) master shape functions at ``xi``.
        normal: (N, 3) unit master normal ``n = m/|m|`` at ``xi`` (out of the master body).
        gap: (N,) clearance g = r·n (negative = penetration), without the gap shift.
        overclosure: (N,) d = −(g − gap_shift).
        normal_force: (N,) F_N (positive = compression).
        area: (N,) spring area used: the given area, or the CalculiX fallback where it was 0.
        forces: (N, n+1, 3) internal forces, node order [master 0..n-1, slave].
        force_per_area: (N, n+1, 3) ``forces / area``, i.e. ∂forces/∂A when F_N = A p(d): the
            linearized-area option adds ``outer(force_per_area[k], dA/dx_q)`` to block (k, q).
        stiffness: (N, 3(n+1), 3(n+1)) ∂forces/∂x with dof ``3k + c``, or None if not asked for.
        tangential: Friction results (docs/method.md §11), or None without friction.
        dxi: (N, n+1, 2, 3) ∂ξ/∂x with the tangent (else None); the thermal springs' coupling to
            the displacement (docs/method.md §20).
        dpressure: (N, n+1, 3) ∂p/∂x of the pressure p = F_N/A with the tangent (else None).
        damping: Contact damping results (docs/method.md §29), or None without damping.
    """

    xi: np.ndarray
    phi: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    overclosure: np.ndarray
    normal_force: np.ndarray
    area: np.ndarray
    forces: np.ndarray
    force_per_area: np.ndarray
    stiffness: np.ndarray | None
    tangential: TangentialForce | None = None
    dxi: np.ndarray | None = None
    dpressure: np.ndarray | None = None
    damping: DampingForce | None = None


@dataclass
class _Kinematics:
    """Projection kinematics of N springs and, optionally, their derivatives.

    Element nodes k = 0..n (slave last). ``weights`` w_k = ∂r/∂x_k at fixed ξ (−φ_j, then +1) and
    ``dphi`` are the shape-function derivatives, zero for the slave node.
    """

    xi: np.ndarray  # (N, 2)
    phi: np.ndarray  # (N, n)
    weights: np.ndarray  # (N, n+1)
    dphi: np.ndarray  # (N, n+1, 2)
    r: np.ndarray  # (N, 3)
    m: np.ndarray  # (N, 3)
    m_norm: np.ndarray  # (N,)
    normal: np.ndarray  # (N, 3)
    gap: np.ndarray  # (N,)
    dxi: np.ndarray | None = None  # (N, n+1, 2, 3)  ∂ξ_α/∂x_k
    dm: np.ndarray | None = None  # (N, n+1, 3, 3)  ∂m_i/∂x_kc
    dnormal: np.ndarray | None = None  # (N, n+1, 3, 3)  ∂n_i/∂x_kc
    dgap: np.ndarray | None = None  # (N, n+1, 3)  ∂g/∂x_kc


def evaluate_springs(
    face_type: FaceType,
    master_coords: np.ndarray,
    slave_coords: np.ndarray,
    areas: np.ndarray,
    law: PressureOverclosureLaw,
    *,
    gap_shift: float | np.ndarray = 0.0,
    xi0: np.ndarray | None = None,
    tangent: bool = True,
    symmetric: bool = False,
    area_fallback: bool = True,
    friction: FrictionInput | None = None,
    interior_projection: bool = False,
    damping: DampingInput | None = None,
) -> SpringEvaluation:
    """Evaluate internal forces and tangent of N node-to-face springs (docs/method.md §5, §6).

    Args:
        face_type: Type of all master faces.
        master_coords: (N, n, 3) current coordinates of the master face nodes (CalculiX order).
        slave_coords: (N, 3) current coordinates of the slave nodes.
        areas: (N,) spring areas A_p (held constant in the tangent).
        law: Pressure-overclosure law; ``law.spring_force(d, A)`` gives F_N and dF_N/dd.
        gap_shift: Scalar or (N,) shift g0(1 − τ) subtracted from the clearance (initial
            overlap, docs/method.md §3.5).
        xi0: Optional (N, 2) start points for the projection (e.g. the previous ξ).
        tangent: Compute the stiffness matrix.
        symmetric: Return (K + Kᵀ)/2, as CalculiX does without friction, instead of the exact
            tangent (which is unsymmetric only for projections clamped to the face boundary).
        area_fallback: Where A_p = 0 (a slave node without slave face), use CalculiX's fallback
            ``A_p = |m|/2`` for a 3-node master face and ``4|m|`` otherwise, m at the projection
            point (docs/method.md §2.2). If False, such springs carry no force.
        friction: Friction state and parameters: adds the tangential force F_T to f_p and its
            derivative to the tangent (docs/method.md §11); the tangent is then never symmetrized.
        interior_projection: Differentiate every projection as an interior one, also where it is
            clamped to the face boundary, as CalculiX does (its Newton path; docs/method.md §6.1).
        damping: Nodal velocities and damping constants: adds the damping force ``c A P v_rel``
            to f_p and its derivative (through the velocities' ``rate``, the projection, the
            normal and a fallback area) to the tangent (docs/method.md §29); the tangent is then
            never symmetrized.

    Returns:
        The evaluation; ``stiffness`` is None if ``tangent`` is False.

    Raises:
        ValueError: On arrays of wrong shape or non-finite values, negative areas, degenerate master
            faces (m = 0) or a singular projection (slave node at a centre of curvature).
    """
    master, slave, area, shift = _check_input(
        face_type, master_coords, slave_coords, areas, gap_shift
    )
    xi = _polish_collapsed(
        face_type, master, slave, project_points(face_type, master, slave, xi0=xi0)
    )
    kin = _kinematics(
        face_type,
        master,
        slave,
        np.asarray(xi, dtype=float),
        derivatives=tangent,
        interior_projection=interior_projection,
    )

    fallback = np.zeros(area.shape, dtype=bool)
    factor = 0.5 if face_type.num_nodes == 3 else 4.0
    if area_fallback:
        fallback = area == 0.0
        if np.any(fallback):
            area = np.where(fallback, factor * kin.m_norm, area)

    overclosure = -(kin.gap - shift)
    force, dforce = law.spring_force(overclosure, area)
    force = np.asarray(force, dtype=float) * np.ones_like(area)
    dforce = np.asarray(dforce, dtype=float) * np.ones_like(area)
    _check_finite("normal force from the law", force)
    _check_finite("normal force derivative from the law", dforce)

    slave_force = -force[:, None] * kin.normal  # f_p
    tangential = None
    if friction is not None:
        tangential = tangential_forces(
            kin.weights,
            kin.normal,
            force,
            area,
            friction,
            dphi=kin.dphi,
            dxi=kin.dxi,
            dnormal=kin.dnormal,
            dnormal_force=None if kin.dgap is None else -dforce[:, None, None] * kin.dgap,
        )
        slave_force = slave_force + tangential.force
        symmetric = False
    damped = None
    if damping is not None:
        damped = _damping(kin, area, damping, fallback, factor)
        slave_force = slave_force + damped.force
        symmetric = False
    forces = kin.weights[:, :, None] * slave_force[:, None, :]
    force_per_area = _force_per_area(forces, force, area, overclosure, kin.weights, kin.normal, law)

    stiffness = None
    if tangent:
        # ∂f_p/∂x_k = −∂F_N/∂x_k n − F_N ∂n/∂x_k, with ∂F_N/∂x_k = dF_N/dd · (−∂g/∂x_k).
        dslave_force = (dforce[:, None] * kin.normal)[:, None, :, None] * kin.dgap[:, :, None, :]
        dslave_force -= force[:, None, None, None] * kin.dnormal
        if tangential is not None:
            dslave_force += tangential.dforce
        if damped is not None:
            dslave_force += damped.dforce
        stiffness = _element_stiffness(kin, slave_force, dslave_force)
        _check_finite("stiffness", stiffness)
        if symmetric:
            stiffness = 0.5 * (stiffness + stiffness.transpose(0, 2, 1))

    return SpringEvaluation(
        xi=kin.xi,
        phi=kin.phi,
        normal=kin.normal,
        gap=kin.gap,
        overclosure=overclosure,
        normal_force=force,
        area=area,
        forces=forces,
        force_per_area=force_per_area,
        stiffness=stiffness,
        tangential=tangential,
        dxi=kin.dxi,
        dpressure=None
        if kin.dgap is None
        else -np.divide(dforce, area, out=np.zeros_like(area), where=area > 0)[:, None, None]
        * kin.dgap,
        damping=damped,
    )


def _damping(
    kin: _Kinematics, area: np.ndarray, damping: DampingInput, fallback: np.ndarray, factor: float
) -> DampingForce:
    """The damping force at the kinematics ``kin``; the fallback areas ``factor |m|`` vary."""
    darea = None
    if kin.dm is not None and np.any(fallback):  # d|m|/dx = n . dm/dx
        darea = np.einsum("ni,nkic->nkc", kin.normal, kin.dm) * (factor * fallback)[:, None, None]
    return damping_forces(
        kin.weights,
        kin.normal,
        area,
        damping,
        dphi=kin.dphi,
        dxi=kin.dxi,
        dnormal=kin.dnormal,
        darea=darea,
    )


def _check_input(
    face_type: FaceType,
    master_coords: np.ndarray,
    slave_coords: np.ndarray,
    areas: np.ndarray,
    gap_shift: float | np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Validate shapes and values; return float arrays (master, slave, area, gap_shift)."""
    master = face_coords_array(face_type, master_coords, "master_coords", rows="N")
    num = master.shape[0]
    slave = np.asarray(slave_coords, dtype=float)
    if slave.shape != (num, 3):
        raise ValueError(f"slave_coords must have shape ({num}, 3), got {slave.shape}")
    area = np.asarray(areas, dtype=float)
    if area.shape != (num,):
        raise ValueError(f"areas must have shape ({num},), got {area.shape}")
    shift = np.asarray(gap_shift, dtype=float)
    if shift.ndim == 0:
        shift = np.full(num, float(shift))
    elif shift.shape != (num,):
        raise ValueError(f"gap_shift must be a scalar or have shape ({num},), got {shift.shape}")
    _check_finite("master_coords", master)
    _check_finite("slave_coords", slave)
    _check_finite("areas", area)
    _check_finite("gap_shift", shift)
    negative = np.flatnonzero(area < 0.0)
    if negative.size:
        raise ValueError(
            f"areas must be >= 0; negative at springs {negative[:10].tolist()} "
            f"(values {area[negative[:10]].tolist()})"
        )
    return master, slave, area, shift


def _check_finite(what: str, values: np.ndarray) -> None:
    """Raise ValueError naming the first springs where ``values`` is not finite."""
    values = np.asarray(values)
    with np.errstate(over="ignore", invalid="ignore"):
        if values.size == 0 or np.isfinite(values.sum()):  # fast path, no temporary array
            return
    if np.all(np.isfinite(values)):  # the sum overflowed
        return
    bad = np.flatnonzero(~np.all(np.isfinite(values.reshape(values.shape[0], -1)), axis=1))
    raise ValueError(f"{what} is not finite at springs {bad[:10].tolist()}")


def _force_per_area(
    forces: np.ndarray,
    force: np.ndarray,
    area: np.ndarray,
    overclosure: np.ndarray,
    weights: np.ndarray,
    normal: np.ndarray,
    law: PressureOverclosureLaw,
) -> np.ndarray:
    """forces/A, with the limit −p(d) w_k n where A = 0 (needs ``law.pressure``)."""
    positive = area > 0.0
    per_area = np.zeros_like(forces)
    per_area[positive] = forces[positive] / area[positive, None, None]
    if not np.all(positive):
        zero = ~positive
        pressure = np.asarray(law.pressure(overclosure[zero]), dtype=float)
        per_area[zero] = -(weights[zero, :, None] * (pressure[:, None] * normal[zero])[:, None, :])
    return per_area


def _kinematics(
    face_type: FaceType,
    master: np.ndarray,
    slave: np.ndarray,
    xi: np.ndarray,
    *,
    derivatives: bool,
    interior_projection: bool = False,
) -> _Kinematics:
    """Projection-point kinematics and (optionally) their exact derivatives w.r.t. the nodes."""
    num = master.shape[0]
    phi = face_type.shape_functions(xi)  # (N, n)
    q = (phi[:, None, :] @ master)[:, 0]
    r = slave - q
    at_collapse, xi_frame = _collapsed_corners(face_type, master, xi)
    dphi_master = face_type.shape_derivatives(xi_frame)  # (N, n, 2)
    tangents = dphi_master.transpose(0, 2, 1) @ master  # (N, 2, 3): q_ξ, q_η
    m = np.cross(tangents[:, 0], tangents[:, 1])
    m_norm = np.linalg.norm(m, axis=1)
    degenerate = np.flatnonzero(~(m_norm > 0.0))
    if degenerate.size:
        raise ValueError(
            f"degenerate master face (q_xi x q_eta = 0 at the projection point) at springs "
            f"{degenerate[:10].tolist()}"
        )
    normal = m / m_norm[:, None]
    gap = np.einsum("ni,ni->n", r, normal)

    weights = np.concatenate([-phi, np.ones((num, 1))], axis=1)
    dphi = np.concatenate([dphi_master, np.zeros((num, 1, 2))], axis=1)
    kin = _Kinematics(xi, phi, weights, dphi, r, m, m_norm, normal, gap)
    if not derivatives:
        return kin

    # Second derivatives q_αβ as (N, 2, 2, 3).
    d2 = face_type.shape_second_derivatives(xi_frame).transpose(0, 2, 1) @ master  # (N, 3, 3)
    second = np.stack([np.stack([d2[:, 0], d2[:, 1]], 1), np.stack([d2[:, 1], d2[:, 2]], 1)], 1)

    # Projection derivatives (docs/method.md §6.1). Stationarity r·q_α = 0 gives H δξ = Σ_k b_k δx_k
    # with H_αβ = q_α·q_β − r·q_αβ and b_kα = w_k q_α + φ_k,α r; δξ = G b_k with G = H⁻¹ inside the
    # domain, restricted to the free direction on an edge and zero at a corner.
    hessian = tangents @ tangents.transpose(0, 2, 1) - (second @ r[:, None, :, None])[..., 0]
    compliance = _projection_compliance(
        face_type, xi, hessian, r, tangents, interior_projection, held=at_collapse
    )
    rhs = weights[:, :, None, None] * tangents[:, None] + dphi[..., None] * r[:, None, None, :]
    dxi = compliance[:, None] @ rhs  # (N, n+1, 2, 3)

    # ∂m/∂x_k = φ_k,ξ (δ × q_η) + φ_k,η (q_ξ × δ) + Σ_β (q_ξβ × q_η + q_ξ × q_ηβ) ∂ξ_β/∂x_k.
    skew_eta = _skew(tangents[:, 1])  # S(a) b = a × b
    skew_xi = _skew(tangents[:, 0])
    dm_dxi = np.cross(second[:, 0], tangents[:, 1, None, :]) + np.cross(
        tangents[:, 0, None, :], second[:, 1]
    )  # (N, 2[β], 3)
    dm = (
        -dphi[:, :, 0, None, None] * skew_eta[:, None]
        + dphi[:, :, 1, None, None] * skew_xi[:, None]
        + dm_dxi.transpose(0, 2, 1)[:, None] @ dxi
    )
    # ∂n = (I − n⊗n) ∂m / |m|.
    projector = np.eye(3) - normal[:, :, None] * normal[:, None, :]
    dnormal = (projector / m_norm[:, None, None])[:, None] @ dm
    # ∂g = n·∂r + r·∂n with ∂r/∂x_k = w_k I − Σ_β q_β ⊗ ∂ξ_β/∂x_k and n·q_β = 0.
    dgap = weights[:, :, None] * normal[:, None, :] + (r[:, None, None, :] @ dnormal)[:, :, 0]

    kin.dxi, kin.dm, kin.dnormal, kin.dgap = dxi, dm, dnormal, dgap
    return kin


#: The repeated corner's barycentric share above which the projection onto a collapsed face is
#: polished (elsewhere the collapsed square is well conditioned and ``xi`` is kept as it was).
_POLISH_SHARE = 0.99
#: How far towards the face centre the frame of a point on a collapsed edge is taken.
_COLLAPSE_NUDGE = 1e-3
#: Parametric distance from a collapsed edge within which a point counts as on it (closer, the
#: projection's Hessian is singular to round-off: its q_ξ·q_ξ scales with the distance squared).
_COLLAPSE_REACH = 1e-6


def _polish_collapsed(
    face_type: FaceType, master: np.ndarray, slave: np.ndarray, xi: np.ndarray
) -> np.ndarray:
    """``xi`` on quad4 faces with a repeated corner made the triangle's exact projection.

    Near the repeated corner the collapsed square squeezes the parameter along the collapsed
    edge: the projection's test ``r·q_α`` stops with ``r`` still sloping in the plane, which
    makes the projection's Hessian indefinite there (docs/method.md §32.3). Where the repeated
    corner's share is at least ``_POLISH_SHARE`` the parameters are taken from the barycentric
    coordinates of the triangle's closest point instead (the repeated
    corner's share sets the coordinate across the collapsed edge, the ratio of the other two the
    one along it, kept where the point is the repeated corner itself).
    """
    if face_type.num_nodes != 4 or xi.shape[0] == 0:
        return xi
    nodes = face_type.node_parameters  # (4, 2) corners of the square
    out = np.array(xi, dtype=float)
    for i in range(4):
        j, k, m = (i + 1) % 4, (i + 2) % 4, (i + 3) % 4  # k-m: the edge opposite i-j
        rows = np.flatnonzero(np.all(master[:, i] == master[:, j], axis=1))
        if rows.size == 0:
            continue
        a, b, c = master[rows, k], master[rows, m], master[rows, i]  # c: the repeated node
        normal = np.cross(b - a, c - a)
        area2 = np.einsum("ni,ni->n", normal, normal)
        good = area2 > 0.0
        p = slave[rows]
        lam_b = np.einsum("ni,ni->n", np.cross(p - a, c - a), normal) / np.where(good, area2, 1.0)
        lam_c = np.einsum("ni,ni->n", np.cross(b - a, p - a), normal) / np.where(good, area2, 1.0)
        lam_a = 1.0 - lam_b - lam_c
        outside = good & ~((lam_a >= 0.0) & (lam_b >= 0.0) & (lam_c >= 0.0))
        if np.any(outside):  # the closest point of the triangle is on an edge
            lam = _closest_on_edges(a[outside], b[outside], c[outside], p[outside])
            lam_a[outside], lam_b[outside], lam_c[outside] = lam.T
        # near the repeated corner only (a flat, zero-area triangle keeps the projection's xi)
        polish = good & (lam_c >= _POLISH_SHARE)
        if not np.any(polish):
            continue
        across = (nodes[i] + nodes[j]) / 2.0 - (nodes[k] + nodes[m]) / 2.0  # to the collapsed edge
        across /= np.linalg.norm(across)
        along = nodes[k] - nodes[m]
        along /= np.linalg.norm(along)
        s_across = 2.0 * lam_c - 1.0
        rest = lam_a + lam_b
        t_k = nodes[k] @ along  # +1 or -1: node k's coordinate along the edge
        old_t = out[rows] @ along
        t_along = np.where(
            rest > 0.0, t_k * (2.0 * lam_a / np.where(rest > 0, rest, 1.0) - 1.0), old_t
        )
        centre = (nodes[k] + nodes[m] + nodes[i] + nodes[j]) / 4.0
        new = centre + s_across[:, None] * across + t_along[:, None] * along
        out[rows[polish]] = new[polish]
    return out


def _closest_on_edges(a: np.ndarray, b: np.ndarray, c: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``(N, 3)`` barycentric coordinates (of a, b, c) of the edge points nearest ``p``."""
    best = np.full(p.shape[0], np.inf)
    lam = np.zeros((p.shape[0], 3))
    for first, second in ((0, 1), (1, 2), (2, 0)):
        x0, x1 = (a, b, c)[first], (a, b, c)[second]
        edge = x1 - x0
        u = np.einsum("ni,ni->n", p - x0, edge) / np.einsum("ni,ni->n", edge, edge)
        u = np.clip(u, 0.0, 1.0)
        distance = np.linalg.norm(p - x0 - u[:, None] * edge, axis=1)
        closer = distance < best
        best = np.where(closer, distance, best)
        lam[closer] = 0.0
        lam[closer, first] = 1.0 - u[closer]
        lam[closer, second] = u[closer]
    return lam


def _collapsed_corners(
    face_type: FaceType, master: np.ndarray, xi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Springs at the repeated corner of a collapsed quad4 face; where their frame is taken.

    There ``q_ξ x q_η = 0`` (docs/method.md §32). The face is a triangle (a collapsed wedge's,
    §30) and the point its vertex: the frame (q_ξ, q_η, m) is taken towards the centre (by
    ``_COLLAPSE_NUDGE``), where the flat collapsed face has the triangle's normal, and with the
    repeated node's two slots summed the normal's derivatives are the triangle's (``|m|`` and
    ``∂m`` both vanish linearly towards the collapsed edge). The projection is held at the
    vertex (``∂ξ/∂x = 0``, as at a corner). Elsewhere the frame is at ``xi`` itself.
    """
    at = np.zeros(xi.shape[0], dtype=bool)
    if face_type.num_nodes != 4 or xi.shape[0] == 0:
        return at, xi
    nodes = face_type.node_parameters  # (4, 2)
    for i in range(4):
        j = (i + 1) % 4
        repeated = np.all(master[:, i] == master[:, j], axis=1)
        if not np.any(repeated):
            continue
        # on the edge i-j: the point is the repeated corner itself
        direction = nodes[j] - nodes[i]
        offset = xi - nodes[i]
        along = offset @ direction / (direction @ direction)
        across = offset - along[:, None] * direction
        at |= repeated & (np.abs(across).max(axis=1) <= _COLLAPSE_REACH)
    if not np.any(at):
        return at, xi
    frame = np.array(xi, dtype=float)
    frame[at] += _COLLAPSE_NUDGE * (face_type.center - frame[at])
    return at, frame


def _projection_compliance(
    face_type: FaceType,
    xi: np.ndarray,
    hessian: np.ndarray,
    r: np.ndarray,
    tangents: np.ndarray,
    interior_only: bool = False,
    held: np.ndarray | None = None,
) -> np.ndarray:
    """The (N, 2, 2) map G with δξ = G b: H⁻¹, t⊗t/(t·H t) on an active edge, 0 at a corner.

    With ``interior_only`` every point takes H⁻¹ (CalculiX's tangent at clamped projections);
    ``held`` points (the repeated corner of a collapsed face, :func:`_collapsed_corners`) take 0.

    An edge constraint c·ξ <= o is active when ξ lies on it and its Lagrange multiplier is
    positive (the unconstrained closest point is outside the domain). With γ_α = r·q_α, the
    multiplier is c·γ on an edge; at a corner the two multipliers solve γ = λ_a c_a + λ_b c_b.
    """
    normals, offsets = _TRIANGLE_CONSTRAINTS if face_type.is_triangle else _QUAD_CONSTRAINTS
    grad = np.einsum("ni,nai->na", r, tangents)  # γ_α = r·q_α = −∂(|r|²/2)/∂ξ_α
    tol = _MULTIPLIER_TOL * np.einsum("nai,nai->n", tangents, tangents)
    on = [o - xi @ c <= _BOUNDARY_TOL for c, o in zip(normals, offsets)]
    active = [on_i & (grad @ c > tol) for on_i, c in zip(on, normals)]
    for a in range(len(normals)):
        for b in range(a + 1, len(normals)):
            det = normals[a][0] * normals[b][1] - normals[a][1] * normals[b][0]
            corner = on[a] & on[b]
            if abs(det) < 1e-12 or not np.any(corner):
                continue
            g = grad[corner]
            lam_a = (g[:, 0] * normals[b][1] - g[:, 1] * normals[b][0]) / det
            lam_b = (normals[a][0] * g[:, 1] - normals[a][1] * g[:, 0]) / det
            active[a][corner] = lam_a > tol[corner]
            active[b][corner] = lam_b > tol[corner]
    num_active = np.zeros(len(xi), dtype=int) if interior_only else np.sum(active, axis=0)
    edge_normal = np.zeros((len(xi), 2))
    for c, active_i in zip(normals, active):
        edge_normal[active_i] = c

    if held is not None:
        num_active = np.where(held, 2, num_active)  # held like a corner
    compliance = np.zeros_like(hessian)
    interior = num_active == 0
    h = hessian[interior]
    det = h[:, 0, 0] * h[:, 1, 1] - h[:, 0, 1] * h[:, 1, 0]
    singular = ~(det > 1e-14 * np.einsum("nii->n", h) ** 2)
    if np.any(singular):
        bad = np.flatnonzero(interior)[singular]
        raise ValueError(
            "singular projection (slave node at a centre of curvature of its master face) at "
            f"springs {bad[:10].tolist()}"
        )
    inverse = np.empty_like(h)
    inverse[:, 0, 0] = h[:, 1, 1]
    inverse[:, 1, 1] = h[:, 0, 0]
    inverse[:, 0, 1] = -h[:, 0, 1]
    inverse[:, 1, 0] = -h[:, 1, 0]
    compliance[interior] = inverse / det[:, None, None]

    edge = num_active == 1
    if np.any(edge):
        t = np.stack([-edge_normal[edge, 1], edge_normal[edge, 0]], axis=1)
        tht = np.einsum("na,nab,nb->n", t, hessian[edge], t)
        if np.any(~(tht > 0.0)):
            bad = np.flatnonzero(edge)[~(tht > 0.0)]
            raise ValueError(f"singular edge projection at springs {bad[:10].tolist()}")
        compliance[edge] = t[:, :, None] * t[:, None, :] / tht[:, None, None]
    # Corners (num_active >= 2): ξ is fixed, compliance stays 0.
    return compliance


def _skew(a: np.ndarray) -> np.ndarray:
    """(N, 3, 3) cross-product matrices S(a) with S(a) b = a × b."""
    s = np.zeros((*a.shape[:-1], 3, 3))
    s[..., 0, 1], s[..., 0, 2] = -a[..., 2], a[..., 1]
    s[..., 1, 0], s[..., 1, 2] = a[..., 2], -a[..., 0]
    s[..., 2, 0], s[..., 2, 1] = -a[..., 1], a[..., 0]
    return s


def _element_stiffness(
    kin: _Kinematics, slave_force: np.ndarray, dslave_force: np.ndarray
) -> np.ndarray:
    """Element matrix from any slave force f_p and its derivative ∂f_p/∂x_l (docs/method.md §6.1).

    Forces are f_k = w_k f_p (w = −φ_j for master nodes, 1 for the slave), so
    ∂f_k/∂x_l = w_k ∂f_p/∂x_l + f_p ⊗ Σ_α ∂w_k/∂ξ_α ∂ξ_α/∂x_l with ∂w_k/∂ξ_α = −φ_k,α.
    """
    num, nodes = kin.weights.shape
    # (N, k, i, l, c)
    blocks = kin.weights[:, :, None, None, None] * dslave_force.transpose(0, 2, 1, 3)[:, None]
    dxi = kin.dxi.transpose(0, 2, 1, 3).reshape(num, 2, 3 * nodes)
    dphi_dxi = (kin.dphi @ dxi).reshape(num, nodes, nodes, 3)  # (N, k, l, c)
    blocks -= slave_force[:, None, :, None, None] * dphi_dxi[:, :, None, :, :]
    return blocks.reshape(num, 3 * nodes, 3 * nodes)


class MeshedMasterSprings:
    """The springs of a master made of mesh faces: plain :func:`evaluate_springs`.

    Base of the meshed master surfaces (``MasterSurface``, the exchanged ``MasterPatch``), giving
    them the ``evaluate_springs`` of the :class:`~dolfinx_ntf.kernels.master.ContactMaster` role.
    """

    def evaluate_springs(
        self,
        face_type: FaceType,
        master_coords: np.ndarray,
        slave_coords: np.ndarray,
        areas: np.ndarray,
        law: PressureOverclosureLaw,
        *,
        gap_shift: float | np.ndarray = 0.0,
        xi0: np.ndarray | None = None,
        tangent: bool = True,
        symmetric: bool = False,
        friction: FrictionInput | None = None,
        interior_projection: bool = False,
        damping: DampingInput | None = None,
    ) -> SpringEvaluation:
        """:func:`evaluate_springs` on faces of this master."""
        return evaluate_springs(
            face_type,
            master_coords,
            slave_coords,
            areas,
            law,
            gap_shift=gap_shift,
            xi0=xi0,
            tangent=tangent,
            symmetric=symmetric,
            friction=friction,
            interior_projection=interior_projection,
            damping=damping,
        )
