"""Modal superposition: the dynamic response of a structure as a combination of its modes.

:class:`ModalDynamics` integrates the modal equations ``q_i'' + c_i q_i' + omega_i^2 q_i = f_i(t)``
of the mass-normalized modes of :func:`~dolfinx_ntf.solvers.modes.contact_modes` (or
:func:`~dolfinx_ntf.solvers.modes.solve_modes`) exactly for modal forces ``f_i = phi_i^T F`` that
are linear within each increment (CalculiX's ``*MODAL DYNAMIC``, docs/method.md §25). The damping
is Rayleigh's ``C = alpha M + beta K`` (``c_i = alpha + beta omega_i^2``, ``*MODAL DAMPING,
RAYLEIGH``) or given per mode. The response starts from rest and is a perturbation about the
state the modes were computed at. All methods are collective on the modes' communicator.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import numpy.typing as npt

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.kernels.modal_integration import (
    increment_propagator,
    modal_increment,
    rayleigh_modal_damping,
)
from dolfinx_ntf.solvers.modes import Modes

__all__ = ["ModalDynamics", "RayleighDamping", "modal_forces"]


@dataclasses.dataclass(frozen=True)
class RayleighDamping:
    """``C = alpha M + beta K``: CalculiX's ``*MODAL DAMPING, RAYLEIGH``.

    Attributes:
        alpha: Coefficient of the mass matrix [1/time] (damps the low modes).
        beta: Coefficient of the stiffness matrix [time] (damps the high modes).
    """

    alpha: float = 0.0
    beta: float = 0.0

    def modal(self, eigenvalues: npt.ArrayLike) -> np.ndarray:
        """The modal damping ``c_i = alpha + beta omega_i^2`` [1/time].

        Args:
            eigenvalues: ``omega_i^2`` of the modes.
        """
        return rayleigh_modal_damping(eigenvalues, self.alpha, self.beta)


def modal_forces(modes: Modes, force: dolfinx.fem.Function) -> np.ndarray:
    """``f_i = phi_i^T F`` of a nodal force vector ``F`` (e.g. concentrated loads). Collective.

    Args:
        modes: The mass-normalized modes.
        force: The force vector as a Function on the modes' space (dof values are forces).

    Returns:
        The modal forces, shape (number of modes,).
    """
    if not modes.modes:
        raise ValueError("modal_forces: no modes")
    if force.function_space != modes.modes[0].function_space:
        raise ValueError("modal_forces: the force must live on the modes' function space")
    F = compat.petsc_vector(force)
    return np.array([compat.petsc_vector(mode).dot(F) for mode in modes.modes])


class ModalDynamics:
    """The modal coordinates of a response from rest and their exact integration.

    Args:
        modes: Mass-normalized modes (``phi^T M phi = 1``).
        damping: :class:`RayleighDamping`, or the modal damping ``c_i = 2 zeta_i omega_i`` per
            mode (shape (n,)); default none.

    Attributes:
        time: Time since the start [time].
        q: Modal displacements, shape (n,).
        v: Modal velocities, shape (n,).
        force: Modal forces at ``time``, shape (n,) (zero at the start).
    """

    def __init__(
        self, modes: Modes, damping: RayleighDamping | npt.ArrayLike | None = None
    ) -> None:
        if not modes.modes:
            raise ValueError("ModalDynamics: no modes")
        self.modes = modes
        eigenvalues = np.asarray(modes.eigenvalues, dtype=float)
        if isinstance(damping, RayleighDamping):
            self.damping = damping.modal(eigenvalues)
        elif damping is None:
            self.damping = np.zeros_like(eigenvalues)
        else:
            self.damping = np.asarray(damping, dtype=float)
            if self.damping.shape != eigenvalues.shape:
                raise ValueError(
                    f"ModalDynamics: {self.damping.size} damping values for "
                    f"{eigenvalues.size} modes"
                )
        self.time = 0.0
        self.q = np.zeros_like(eigenvalues)
        self.v = np.zeros_like(eigenvalues)
        self.force = np.zeros_like(eigenvalues)
        self._propagators: dict[float, np.ndarray] = {}

    def advance(
        self, dt: float, force_end: npt.ArrayLike, force_start: npt.ArrayLike | None = None
    ) -> None:
        """Advance by ``dt`` with modal forces linear from ``force_start`` to ``force_end``.

        ``force_start`` defaults to the forces at the end of the last increment; a step load
        applied at the start of an increment is ``force_start = force_end``.

        Args:
            dt: The increment [time], > 0.
            force_end: Modal forces at ``time + dt``, shape (n,).
            force_start: Modal forces at ``time``, shape (n,).
        """
        end = np.asarray(force_end, dtype=float)
        start = self.force if force_start is None else np.asarray(force_start, dtype=float)
        if end.shape != self.q.shape or start.shape != self.q.shape:
            raise ValueError(f"ModalDynamics.advance: modal forces need shape {self.q.shape}")
        if not (np.all(np.isfinite(end)) and np.all(np.isfinite(start))):
            raise ValueError("ModalDynamics.advance: non-finite modal force")
        propagator = self._propagators.get(dt)
        if propagator is None:
            propagator = increment_propagator(self.modes.eigenvalues, self.damping, dt)
            self._propagators = {dt: propagator}  # increments repeat: keep the last one
        self.q, self.v = modal_increment(propagator, self.q, self.v, start, end, dt)
        self.time += dt
        self.force = end.copy()

    def combine(self, coefficients: np.ndarray, out: dolfinx.fem.Function) -> None:
        """``out = sum_i coefficients_i phi_i`` (e.g. ``q`` for displacements, ``v`` velocities).

        Args:
            coefficients: One value per mode.
            out: A Function on the modes' space, overwritten (ghosts included).
        """
        out.x.array[:] = 0.0
        for value, mode in zip(coefficients, self.modes.modes):
            out.x.array[:] += value * mode.x.array

    def displacement(self, out: dolfinx.fem.Function) -> None:
        """The physical displacement ``sum_i q_i phi_i`` into ``out``.

        Args:
            out: A Function on the modes' space.
        """
        self.combine(self.q, out)

    def velocity(self, out: dolfinx.fem.Function) -> None:
        """The physical velocity ``sum_i q_i' phi_i`` into ``out``.

        Args:
            out: A Function on the modes' space.
        """
        self.combine(self.v, out)
