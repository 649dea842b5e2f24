"""Coulomb friction of node-to-face springs: return map, tangential force and its tangent.

Pure numpy, vectorized over N springs (docs/method.md §11.1). For each spring, with element nodes
``k = 0..n`` (master face nodes, then the slave node) and weights ``w_k`` (``-phi_j`` for master
node ``j``, ``+1`` for the slave):

- relative displacement at the projection point ``a = sum_k w_k u_k = u_p - sum_j phi_j u_j``;
- increment since the start of the increment ``s = a - a_n``;
- accumulated relative tangential displacement ``t = t_n + s - (s.n) n`` (only the increment is
  projected onto the current tangent plane, as CalculiX does);
- elastic part ``t_e = t - t_p,n``, trial force ``F_tr = K_t t_e`` with ``K_t = lambda A``;
- limit ``F_s = mu |F_N|`` (CalculiX), or ``mu max(F_N, 0)`` without friction in tension;
- stick (``|F_tr| < (1 - SLIP_TIE) F_s``, or ``t_e`` zero up to round-off): ``F_T = F_tr``, slip
  unchanged;
- slip: ``e = t_e/|t_e|``, ``F_T = F_s e``, ``t_p = t_p,n + (|F_tr| - F_s)/K_t e``.

``F_T`` is added to the slave node's internal force ``f_p = -F_N n + F_T``. Vectors have
``d = normal.shape[1]`` components: 3 for the node-to-face springs, 2 for the node-to-segment
springs of 2D meshes (one tangent direction, the same return map; docs/method.md §17). The tangent
``dF_T/dx_k`` comes in two forms: ``"ccx"`` holds the projection point fixed in ``ds/dx``
(CalculiX's element matrix) and ``"consistent"`` (default) also differentiates ``phi_j(xi)`` in
``a``, which makes it the exact derivative of the force (checked against finite differences).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "TANGENT_MODES",
    "FrictionInput",
    "TangentialForce",
    "output_tangents",
    "tangential_forces",
]

#: Tangent forms of :func:`tangential_forces`.
TANGENT_MODES = ("consistent", "ccx")

#: ccx's threshold for the choice of the first output tangent (docs/method.md §11.4).
_TANGENT_SWITCH = 1.5231e-6
#: Relative band below the friction limit where a trial force already slips (docs/method.md
#: §11.1). A node that slipped starts the next increment with ``|F_tr| = F_s`` up to round-off;
#: without the band round-off would pick its tangent (stick or slip), differently on different
#: partitions of the mesh (docs/method.md §14.6).
SLIP_TIE = 1e-8
#: Relative size, against the displacements it is computed from, below which the elastic
#: tangential displacement ``t_e`` is round-off: the spring sticks (``F_T = F_tr``, about 0).
#: Otherwise a spring without normal force would stick or slip (and get one tangent or another)
#: as round-off makes ``t_e`` exactly zero or not (docs/method.md §14.6).
ROUND_OFF = 1e-12


@dataclass
class FrictionInput:
    """What the tangential force of N springs needs besides the normal kinematics.

    Attributes:
        displacements: ``(N, n+1, d)`` displacements ``u_k`` of the element nodes (master face
            nodes, then the slave node); ``d = 3``, or 2 on a 2D mesh.
        a_start, t_start, slip_start: ``(N, d)`` relative displacement ``a_n``, accumulated
            tangential relative displacement ``t_n`` and slip ``t_p,n`` at the start of the
            increment.
        mu: Friction coefficient (scalar or ``(N,)``).
        stick_slope: ``lambda`` [force/length^3] (scalar or ``(N,)``); ``K_t = lambda A``.
        in_tension: Friction limit ``mu |F_N|`` (CalculiX: friction also under linear-law
            tension) instead of ``mu max(F_N, 0)``.
        tangent_mode: ``"consistent"`` or ``"ccx"`` (see the module docstring).
        force_stick: CalculiX's elastic first iteration (docs/method.md §33.4): the force and
            the state stick whatever the trial force (``F_T = F_tr``, ``t_p = t_p,n``); the
            tangent is the slip one where the increment-start trial ``K_t (t_n - t_p,n)``
            slips, else the stick one.
    """

    displacements: np.ndarray
    a_start: np.ndarray
    t_start: np.ndarray
    slip_start: np.ndarray
    mu: float | np.ndarray
    stick_slope: float | np.ndarray
    in_tension: bool = False
    tangent_mode: str = "consistent"
    force_stick: bool = False


@dataclass
class TangentialForce:
    """Friction results of N springs.

    Attributes:
        force: ``(N, d)`` tangential internal force ``F_T`` on the slave node (the force the slave
            exerts on the master; the master exerts ``-F_T`` on the slave).
        dforce: ``(N, n+1, d, d)`` ``dF_T_i/dx_kc``, or None without tangent.
        a, t, slip: ``(N, d)`` new state values (relative displacement, accumulated tangential
            relative displacement, slip).
        elastic: ``(N, d)`` ``t_e = t - t_p,n``.
        limit: ``(N,)`` ``F_s``.
        sliding: ``(N,)`` True where the spring slips (its force; never with ``force_stick``).
        energy: ``(N,)`` elastic energy of the tangential spring, ``|F_T|^2 / (2 K_t)``.
    """

    force: np.ndarray
    dforce: np.ndarray | None
    a: np.ndarray
    t: np.ndarray
    slip: np.ndarray
    elastic: np.ndarray
    limit: np.ndarray
    sliding: np.ndarray
    energy: np.ndarray


def _per_spring(value: float | np.ndarray, num: int, name: str) -> np.ndarray:
    array = np.broadcast_to(np.asarray(value, dtype=float), (num,)).copy()
    if not np.all(np.isfinite(array)) or np.any(array < 0.0):
        raise ValueError(f"friction: {name} must be finite and >= 0, got {array[:5].tolist()}")
    return array


def tangential_forces(
    weights: np.ndarray,
    normal: np.ndarray,
    normal_force: np.ndarray,
    area: np.ndarray,
    data: FrictionInput,
    *,
    dphi: np.ndarray | None = None,
    dxi: np.ndarray | None = None,
    dnormal: np.ndarray | None = None,
    dnormal_force: np.ndarray | None = None,
) -> TangentialForce:
    """Return map and tangential force of N springs (docs/method.md §11.1, §11.2).

    Args:
        weights: ``(N, n+1)`` ``w_k`` (``-phi_j``, then 1).
        normal: ``(N, d)`` unit master normal at the projection point (``d = 3``, or 2 for the
            springs of a 2D mesh, whose tangent plane is the line of the edge's tangent).
        normal_force: ``(N,)`` ``F_N`` (compression positive).
        area: ``(N,)`` spring area ``A_p``.
        data: State and parameters.
        dphi: ``(N, n+1, p)`` shape-function derivatives by the ``p = d - 1`` face parameters
            (zero for the slave); tangent only.
        dxi: ``(N, n+1, p, d)`` ``dxi_alpha/dx_kc``; tangent only.
        dnormal: ``(N, n+1, d, d)`` ``dn_i/dx_kc``; tangent only.
        dnormal_force: ``(N, n+1, d)`` ``dF_N/dx_kc``; tangent only.

    Returns:
        The :class:`TangentialForce`; ``dforce`` is None unless all four derivatives are given.
    """
    if data.tangent_mode not in TANGENT_MODES:
        raise ValueError(
            f"friction: tangent_mode must be one of {TANGENT_MODES}, got {data.tangent_mode!r}"
        )
    num = weights.shape[0]
    mu = _per_spring(data.mu, num, "mu")
    k_t = _per_spring(data.stick_slope, num, "stick_slope") * area
    u = np.asarray(data.displacements, dtype=float)
    a = np.einsum("nk,nki->ni", weights, u)
    s = a - data.a_start
    s_n = np.einsum("ni,ni->n", s, normal)
    t = data.t_start + s - s_n[:, None] * normal
    elastic = t - data.slip_start
    trial = k_t[:, None] * elastic
    trial_norm = np.linalg.norm(trial, axis=1)
    sign = np.sign(normal_force) if data.in_tension else (normal_force > 0).astype(float)
    limit = mu * (np.abs(normal_force) if data.in_tension else np.maximum(normal_force, 0.0))
    magnitude = sum(
        np.linalg.norm(v, axis=1) for v in (a, data.a_start, data.t_start, data.slip_start)
    )
    settled = trial_norm <= ROUND_OFF * k_t * magnitude  # includes |F_tr| = 0
    sliding = ~settled & (trial_norm >= (1.0 - SLIP_TIE) * limit)
    elastic_norm = np.linalg.norm(elastic, axis=1)
    tangent_sliding = sliding  # where the tangent is the slip one
    if data.force_stick:  # ccx's elastic first iteration (docs/method.md §33.4)
        tangent_sliding = _slipping_at_start(data, k_t, limit, magnitude) & (elastic_norm > 0.0)
        sliding = np.zeros_like(sliding)
    direction = np.zeros_like(elastic)
    direction[sliding] = elastic[sliding] / elastic_norm[sliding, None]
    force = trial.copy()
    force[sliding] = limit[sliding, None] * direction[sliding]
    slip = data.slip_start.copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        increment = np.where(sliding, (trial_norm - limit) / k_t, 0.0)
    slip[sliding] += increment[sliding, None] * direction[sliding]
    force_norm = np.linalg.norm(force, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        energy = np.where(k_t > 0.0, 0.5 * force_norm**2 / k_t, 0.0)

    dforce = None
    if dphi is not None and dxi is not None and dnormal is not None and dnormal_force is not None:
        eye = np.eye(normal.shape[1])
        # ds_i/dx_kc = w_k delta_ic (- sum_alpha U_alpha,i dxi_alpha/dx_kc in consistent mode),
        # U_alpha = sum_j dphi_j/dxi_alpha u_j = -da/dxi_alpha.
        ds = weights[:, :, None, None] * eye
        if data.tangent_mode == "consistent":
            along = np.einsum("nka,nki->nai", dphi, u)  # U_alpha
            ds = ds - np.einsum("nai,nkac->nkic", along, dxi)
        # dt = (I - n n) ds - n (s . dn) - (s.n) dn
        projector = eye - normal[:, :, None] * normal[:, None, :]
        dt = np.einsum("nij,nkjc->nkic", projector, ds)
        dt -= normal[:, None, :, None] * np.einsum("ni,nkic->nkc", s, dnormal)[:, :, None, :]
        dt -= s_n[:, None, None, None] * dnormal
        dforce = k_t[:, None, None, None] * dt
        slips = tangent_sliding
        if np.any(slips):
            scale = limit[slips] / elastic_norm[slips]
            e = elastic[slips] / elastic_norm[slips, None]
            radial = eye - e[:, :, None] * e[:, None, :]
            dlimit = (
                mu[slips, None, None] * dnormal_force[slips]
                if data.tangent_mode == "ccx"
                else (mu * sign)[slips, None, None] * dnormal_force[slips]
            )
            dforce[slips] = (
                scale[:, None, None, None] * np.einsum("nij,nkjc->nkic", radial, dt[slips])
                + e[:, None, :, None] * dlimit[:, :, None, :]
            )
    return TangentialForce(
        force=force,
        dforce=dforce,
        a=a,
        t=t,
        slip=slip,
        elastic=elastic,
        limit=limit,
        sliding=sliding,
        energy=energy,
    )


def _slipping_at_start(
    data: FrictionInput, k_t: np.ndarray, limit: np.ndarray, magnitude: np.ndarray
) -> np.ndarray:
    """``(N,)`` True where the trial force at the increment start (``s = 0``) slips.

    CalculiX's forced stick acts on the force and the state only (``springforc_n2f``); its
    tangent of that iteration is evaluated at the increment start, where the trial force is
    ``K_t (t_n - t_p,n)``: a node that slipped at the end of the last increment slips there
    (docs/method.md §33.4).
    """
    start = np.linalg.norm(k_t[:, None] * (data.t_start - data.slip_start), axis=1)
    return (start > ROUND_OFF * k_t * magnitude) & (start >= (1.0 - SLIP_TIE) * limit)


def output_tangents(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CalculiX's output directions ``(t1, t2)`` of CDIS/CSTR for unit normals ``(N, 3)``.

    ``t1`` is ``e_x`` projected onto the tangent plane (``e_z`` where ``1 - |n_x| < 1.5231e-6``),
    normalized; ``t2 = n x t1`` (docs/method.md §11.4).
    """
    normal = np.asarray(normal, dtype=float)
    along_x = 1.0 - np.abs(normal[:, 0]) < _TANGENT_SWITCH
    axis = np.zeros_like(normal)
    axis[~along_x, 0] = 1.0
    axis[along_x, 2] = 1.0
    t1 = axis - np.einsum("ni,ni->n", axis, normal)[:, None] * normal
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return t1, np.cross(normal, t1)
