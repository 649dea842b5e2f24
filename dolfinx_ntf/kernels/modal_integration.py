"""Exact integration of damped modal equations under a load linear over each increment.

Each mode ``i`` of a modal superposition obeys ``q'' + 2 zeta_i omega_i q' + omega_i^2 q = f_i(t)``
with ``f_i`` the modal force (the load vector projected on the mass-normalized mode). When
``f_i`` is linear within an increment, the state at its end is the exponential of one constant
4x4 matrix applied to ``(q, q', f, f')`` at its start: exact for any damping (under-, critically
and over-damped alike), which is CalculiX's ``*MODAL DYNAMIC`` integration (docs/method.md §25).
Pure numpy and scipy; all modes at once.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import scipy.linalg

__all__ = ["increment_propagator", "modal_increment", "rayleigh_modal_damping"]


def rayleigh_modal_damping(eigenvalues: npt.ArrayLike, alpha: float, beta: float) -> np.ndarray:
    """The modal damping ``c_i = alpha + beta omega_i^2`` of ``C = alpha M + beta K``.

    ``c_i = 2 zeta_i omega_i``: the viscous damping ratio is ``zeta_i = alpha / (2 omega_i) +
    beta omega_i / 2`` (CalculiX's ``*MODAL DAMPING, RAYLEIGH``). Defined for rigid modes too.

    Args:
        eigenvalues: ``omega_i^2`` [rad^2/time^2], shape (n,).
        alpha: Coefficient of the mass matrix [1/time].
        beta: Coefficient of the stiffness matrix [time].

    Returns:
        ``c_i`` [1/time], shape (n,).
    """
    eigenvalues = np.asarray(eigenvalues, dtype=float)
    if not np.all(np.isfinite(eigenvalues)) or not (np.isfinite(alpha) and np.isfinite(beta)):
        raise ValueError(
            f"rayleigh_modal_damping: non-finite eigenvalue or coefficient ({eigenvalues}, "
            f"alpha={alpha}, beta={beta})"
        )
    return alpha + beta * eigenvalues


def increment_propagator(
    eigenvalues: npt.ArrayLike, damping: npt.ArrayLike, dt: float
) -> np.ndarray:
    """The matrices that advance ``(q, q', f, f')`` over an increment ``dt``, shape (n, 2, 4).

    The first two rows of ``exp(A dt)``, ``A = [[0, 1, 0, 0], [-omega^2, -c, 1, 0], [0, 0, 0, 1],
    [0, 0, 0, 0]]``: ``(q, q')(t + dt) = P @ (q, q', f(t), f')`` for the modal equation
    ``q'' + c q' + omega^2 q = f`` and a force ``f(t + s) = f(t) + f' s``, exactly.

    Args:
        eigenvalues: ``omega_i^2`` [rad^2/time^2], shape (n,).
        damping: Modal damping ``c_i = 2 zeta_i omega_i`` [1/time], shape (n,) or scalar, >= 0.
        dt: Increment [time], > 0.
    """
    eigenvalues = np.asarray(eigenvalues, dtype=float)
    damping = np.broadcast_to(np.asarray(damping, dtype=float), eigenvalues.shape)
    if not dt > 0.0 or not np.isfinite(dt):
        raise ValueError(f"increment_propagator: the increment must be finite and > 0, got {dt}")
    if np.any(damping < 0.0) or not np.all(np.isfinite(damping)):
        raise ValueError(
            f"increment_propagator: modal damping must be finite and >= 0, got {damping}"
        )
    A = np.zeros((eigenvalues.size, 4, 4))
    A[:, 0, 1] = 1.0
    A[:, 1, 0] = -eigenvalues
    A[:, 1, 1] = -damping
    A[:, 1, 2] = 1.0
    A[:, 2, 3] = 1.0
    return scipy.linalg.expm(A * dt)[:, :2, :]


def modal_increment(
    propagator: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    f_start: np.ndarray,
    f_end: np.ndarray,
    dt: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Modal displacements and velocities at the end of an increment, shapes (n,).

    Args:
        propagator: :func:`increment_propagator` of the increment ``dt``, shape (n, 2, 4).
        q: Modal displacements at its start.
        v: Modal velocities at its start.
        f_start: Modal forces at its start.
        f_end: Modal forces at its end (linear in between).
        dt: The increment [time].
    """
    state = np.stack([q, v, f_start, (f_end - f_start) / dt], axis=1)
    end = np.einsum("nij,nj->ni", propagator, state)
    return end[:, 0], end[:, 1]
