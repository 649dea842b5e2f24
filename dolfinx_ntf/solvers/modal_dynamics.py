"""Modal superposition: the dynamic response of a structure as a combination of its modes.

:class:`ModalDynamics` integrates the modal equations ``q_i'' + c_i q_i' + omega_i^2 q_i = f_i(t)``
of the mass-normalized modes of :func:`~dolfinx_ntf.solvers.modes.contact_modes` (or
:func:`~dolfinx_ntf.solvers.modes.solve_modes`) exactly for modal forces ``f_i = phi_i^T F`` that
are linear within each increment (CalculiX's ``*MODAL DYNAMIC``, docs/method.md §25). The damping
is Rayleigh's ``C = alpha M + beta K`` (``c_i = alpha + beta omega_i^2``, ``*MODAL DAMPING,
RAYLEIGH``) or given per mode. The response starts from rest and is a perturbation about the
state the modes were computed at. :class:`ModalContactForces` adds the forces of a
:class:`~dolfinx_ntf.ContactProblem`'s springs as nonlinear loads, evaluated at the current
physical displacement and projected on the modes (:meth:`ModalDynamics.advance_with_contact`
iterates them to the end of each increment). All methods are collective on the modes'
communicator.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import numpy.typing as npt

import dolfinx.fem

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.kernels.modal_integration import (
    increment_propagator,
    modal_increment,
    rayleigh_modal_damping,
)
from dolfinx_ntf.solvers.errors import ContactConvergenceError
from dolfinx_ntf.solvers.modes import Modes

__all__ = ["ModalContactForces", "ModalDynamics", "RayleighDamping", "modal_forces"]


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
        self._load = np.zeros_like(eigenvalues)  # the load part of force (with contact)
        self._contact: np.ndarray | None = None  # the springs' part at ``time``

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

    def advance_with_contact(
        self,
        dt: float,
        force_end: npt.ArrayLike,
        contact: ModalContactForces,
        *,
        force_start: npt.ArrayLike | None = None,
        rtol: float = 1e-8,
        max_iterations: int = 50,
    ) -> int:
        """Advance by ``dt`` with the springs' modal forces iterated to the increment's end.

        The load is linear from ``force_start`` to ``force_end``; the springs' force is linear
        from its value at the start to its value at the end state, found by Newton iterations on
        ``f = f_c(q_end(f))`` with the springs' modal tangent ``-Phi^T K_c Phi``, until the guess
        and the force at the end state differ by at most ``rtol`` of the largest modal force.
        Returns the iterations taken.

        Args:
            dt: The increment [time], > 0.
            force_end: Modal load at ``time + dt``.
            contact: The springs' modal forces.
            force_start: Modal load at ``time`` (default: the last ``force_end``).
            rtol: Convergence tolerance, relative to the largest modal force.
            max_iterations: Iterations before :class:`ContactConvergenceError` (a smaller
                increment helps).

        Raises:
            ContactConvergenceError: No convergence within ``max_iterations``.
        """
        load_end = np.asarray(force_end, dtype=float)
        load_start = self._load if force_start is None else np.asarray(force_start, dtype=float)
        if self._contact is None:
            self._contact = contact(self.q)
        start = load_start + self._contact
        guess = self._contact.copy()
        q0, v0, time0 = self.q, self.v, self.time
        change = np.inf
        for iteration in range(1, max_iterations + 1):
            self.q, self.v, self.time = q0, v0, time0
            self.advance(dt, load_end + guess, start)
            new, stiffness = contact.evaluate(self.q)
            scale = max(np.abs(new).max(), np.abs(load_end).max(), np.abs(guess).max())
            residual = guess - new
            change = np.abs(residual).max()
            if change <= rtol * scale:
                self._contact, self._load = new, load_end.copy()
                self.force = load_end + new
                return iteration
            # Newton on g(f) = f - f_c(q_end(f)): dq_end/df_end = P[:, 0, 3] / dt per mode
            sensitivity = self._propagators[dt][:, 0, 3] / dt
            jacobian = np.eye(len(guess)) + stiffness * sensitivity[None, :]
            guess = guess - np.linalg.solve(jacobian, residual)
        raise ContactConvergenceError(
            f"ModalDynamics.advance_with_contact: the springs' modal forces did not converge in "
            f"{max_iterations} iterations (last change {change:.3e}); take a smaller increment "
            f"than {dt}"
        )


class ModalContactForces:
    """The springs' forces projected on the modes, at the displacement ``u0 + sum q_i phi_i``.

    ``u0`` is the problem's displacement when this object is made (the state the modes were
    computed at, e.g. a preloaded one); the forces are relative to the springs' forces there
    (which the static loads balance), ``f_c = -Phi^T (r(u) - r(u0))`` with ``r`` the springs'
    contribution to the residual. Each call re-pairs at the new displacement (node-to-face
    search, as a Newton iteration does) and leaves the problem's ``u`` there. Use the modes of
    the bulk stiffness (``contact_modes(..., springs=False)``): the springs' stiffness enters
    through these forces.

    Args:
        problem: The contact problem (converged at ``u0``).
        modes: The mass-normalized modes on the problem's space.
    """

    def __init__(self, problem: ContactProblem, modes: Modes) -> None:
        validation.check_type(problem, ContactProblem, "ModalContactForces: problem")
        if not modes.modes or modes.modes[0].function_space != problem.u.function_space:
            raise ValueError("ModalContactForces: the modes must live on the problem's space")
        self.problem, self.modes = problem, modes
        self.u0 = problem.u.x.array.copy()
        self._work = dolfinx.fem.Function(problem.u.function_space)
        self.reference = np.zeros(len(modes.modes))
        self.reference = self(np.zeros(len(modes.modes)))

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """``-Phi^T (r(u0 + Phi q) - r(u0))``, shape (number of modes,). Collective.

        Args:
            q: Modal displacements.
        """
        return self._forces(q, tangent=False)[0]

    def evaluate(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The modal forces and their derivative ``-Phi^T K_c Phi`` (n, n). Collective.

        ``K_c`` is the springs' tangent at the pairing of ``u0 + Phi q``, the problem's: exact
        with ``linearize_area=True`` (each evaluation re-pairs, so the spring areas follow the
        displacement), without the area terms otherwise (docs/method.md §6.3).

        Args:
            q: Modal displacements.
        """
        forces, stiffness = self._forces(q, tangent=True)
        assert stiffness is not None
        return forces, stiffness

    def _forces(self, q: np.ndarray, *, tangent: bool) -> tuple[np.ndarray, np.ndarray | None]:
        problem = self.problem
        problem.u.x.array[:] = self.u0
        for value, mode in zip(q, self.modes.modes):
            problem.u.x.array[:] += value * mode.x.array
        problem.u.x.scatter_forward()
        problem.pair()
        blocks = problem.evaluate(tangent=tangent)
        vector = compat.petsc_vector(self._work)
        with vector.localForm() as local:
            local.set(0.0)
        problem.assembler.add_to_vector(vector, blocks)
        phis = [compat.petsc_vector(m) for m in self.modes.modes]
        forces = np.array([-phi.dot(vector) for phi in phis]) - self.reference
        if not tangent:
            return forces, None
        A = problem.ensure_matrix()
        A.zeroEntries()
        problem.assembler.add_to_matrix(A, blocks)
        A.assemble()
        product = A.createVecLeft()
        stiffness = np.zeros((len(phis), len(phis)))
        for j, phi in enumerate(phis):
            A.mult(phi, product)
            stiffness[:, j] = [-other.dot(product) for other in phis]
        product.destroy()
        return forces, stiffness
