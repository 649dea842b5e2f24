"""Implicit dynamic steps (CalculiX ``*DYNAMIC``): the HHT alpha method with contact springs.

:class:`DynamicStep` integrates ``M a + f(u) = f_ext(t)`` in time with the alpha method of Hilber,
Hughes and Taylor (docs/method.md §12), ``f`` being everything the :class:`ContactProblem`
assembles: the user's residual form and the contact springs. The inertia enters the problem's
residual and Jacobian as an extra term (``ContactProblem.extra_terms``), so the same
:class:`ContactNewtonSolver` iterates, with the springs in the same Newton loop and on CalculiX's
pairing schedule.
"""

from __future__ import annotations

import logging
import math
import typing
from dataclasses import dataclass

from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.contact.velocity import NodeVelocity
from dolfinx_ntf.solvers.errors import ContactConvergenceError
from dolfinx_ntf.solvers.steps import (
    IncrementResult,
    IncrementSolver,
    LoadControl,
    Step,
    no_load,
)

__all__ = ["CCX_ALPHA", "DynamicStep", "kinetic_energy", "newmark_parameters"]

logger = logging.getLogger("dolfinx_ntf")

#: CalculiX's default ``ALPHA`` of ``*DYNAMIC``.
CCX_ALPHA = -0.05


def newmark_parameters(alpha: float) -> tuple[float, float]:
    """Newmark's ``(beta, gamma)`` of the HHT method: ``((1 - alpha)^2/4, 1/2 - alpha)``."""
    return (1.0 - alpha) ** 2 / 4.0, 0.5 - alpha


def kinetic_energy(mass: ufl.Form, velocity: dolfinx.fem.Function) -> float:
    """``v^T M v / 2`` for the mass form ``mass`` (``rho inner(w, v) dx``), v = ``velocity``.

    Collective. Compiles the form at every call; in a loop, compile ``rho inner(v, v) dx / 2``
    once instead.
    """
    form = dolfinx.fem.form(ufl.action(ufl.action(mass, velocity), velocity))
    comm = velocity.function_space.mesh.comm
    return 0.5 * comm.allreduce(dolfinx.fem.assemble_scalar(form))


class _Inertia:
    """The HHT terms added to the problem's residual and Jacobian (docs/method.md §12.1).

    The residual of the problem, ``r(u) = f(u) - f_ext(t_{n+1})``, becomes
    ``r(u) + (M a(u) - alpha r_n) / (1 + alpha)`` with the Newmark acceleration
    ``a(u) = (u - u_n - dt v_n - dt^2 (1/2 - beta) a_n) / (beta dt^2)``, and the Jacobian gains
    ``M / (beta dt^2 (1 + alpha))``. In both, the mass matrix is ``M_bc``: ``M`` without the rows
    and columns of constrained dofs. As in CalculiX, prescribed motion then exerts no inertial
    force on the free dofs next to it. The complete ``M`` gives the force scale ``M v_n/dt``.
    """

    def __init__(self, M: PETSc.Mat, M_bc: PETSc.Mat, alpha: float) -> None:
        self.M, self.M_bc, self.alpha = M, M_bc, alpha
        self.beta, self.gamma = newmark_parameters(alpha)
        self.prediction: PETSc.Vec = M.createVecRight()
        self.last_residual: PETSc.Vec = M.createVecLeft()  # r_n, zero at constrained dofs
        self._acceleration = M.createVecRight()
        self._force = M.createVecLeft()
        self._momentum_rate = M.createVecLeft()  # M v_n / dt: the force scale of the motion
        self.dt = 0.0
        self.enabled = True

    def predict(self, u_n: np.ndarray, v_n: np.ndarray, a_n: np.ndarray, dt: float) -> None:
        """Set the increment: ``u_n + dt v_n + dt^2 (1/2 - beta) a_n`` (owned values)."""
        self.dt = dt
        self.prediction.array[:] = u_n + dt * v_n + dt * dt * (0.5 - self.beta) * a_n
        self._acceleration.array[:] = v_n / dt
        self.M.mult(self._acceleration, self._momentum_rate)
        self._force.zeroEntries()

    def velocity_offset(self, v_n: np.ndarray, a_n: np.ndarray) -> tuple[np.ndarray, float]:
        """``(v0, rate)`` with the Newmark velocity ``v(x) = v0 + rate x`` of this increment.

        ``v = v_n + dt ((1 - gamma) a_n + gamma a(x))``, ``rate = gamma/(beta dt)`` (owned values).
        """
        rate = self.gamma / (self.beta * self.dt)
        return v_n + self.dt * (1.0 - self.gamma) * a_n - rate * self.prediction.array_r, rate

    def acceleration(self, x: np.ndarray) -> np.ndarray:
        """Newmark acceleration of the owned displacement values ``x``."""
        return (x - self.prediction.array_r) / (self.beta * self.dt * self.dt)

    def add_to_residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """``b += (M_bc a(x) - alpha r_n) / (1 + alpha)`` (constrained rows are reset later)."""
        if not self.enabled:
            return
        self._acceleration.array[:] = self.acceleration(x.array_r)
        self.M_bc.mult(self._acceleration, self._force)
        b.array[:] += (self._force.array_r - self.alpha * self.last_residual.array_r) / (
            1.0 + self.alpha
        )

    def force_sum(self) -> tuple[float, int]:
        """Sum of ``|M a| + |M v_n|/dt`` over the owned dofs, and their number.

        ``M v_n/dt``, the force that stops the motion within the increment, keeps the
        force-scaled convergence test meaningful in free flight, where ``M a`` and the internal
        forces vanish.
        """
        if not self.enabled:
            return 0.0, 0
        values = np.abs(self._force.array_r) + np.abs(self._momentum_rate.array_r)
        return float(values.sum()), int(values.size)

    def add_to_jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """``A += M / (beta dt^2 (1 + alpha))``, constrained rows and columns left out."""
        if not self.enabled:
            return
        scale = 1.0 / (self.beta * self.dt * self.dt * (1.0 + self.alpha))
        A.axpy(scale, self.M_bc, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

    def destroy(self) -> None:
        """Destroy the PETSc objects."""
        for obj in (
            self.M,
            self.M_bc,
            self.prediction,
            self.last_residual,
            self._acceleration,
            self._force,
            self._momentum_rate,
        ):
            obj.destroy()


@dataclass
class DynamicStep(Step):
    """An implicit dynamic step of ``period`` (CalculiX ``*DYNAMIC``), docs/method.md §12.

    The HHT alpha method with CalculiX's default ``alpha = -0.05`` (Newmark
    ``beta = (1 - alpha)^2/4``, ``gamma = 1/2 - alpha``); the contact springs are part of the
    internal force, so they enter at the same time levels as the bulk forces, and the initial
    overlap acts in full from the first increment (no ramp, docs/method.md §3.5). The step holds
    configuration only, except that it reads the initial velocity and acceleration from
    ``velocity``/``acceleration`` and leaves the final ones there. While it runs, the problem's
    ``node_velocity`` is the Newmark velocity, so pairs with ``ContactDamping`` are damped
    (docs/method.md §29).

    Args:
        mass: Bilinear mass form on the displacement space, e.g.
            ``rho * ufl.inner(ufl.TrialFunction(V), ufl.TestFunction(V)) * ufl.dx``.
        set_load: Called with the step time at the end of each increment (and with 0 at the
            start), like :class:`~dolfinx_ntf.StaticStep`'s; default: no time-dependent load.
        period: Step time.
        initial_increment, min_increment, max_increment: Time increment sizes; the default
            minimum is CalculiX's, the initial increment or 1e-5 of the period, the smaller.
        fixed: Keep ``initial_increment`` (CalculiX ``DIRECT``); a failed increment stops the step.
        alpha: HHT parameter in ``[-1/3, 0]``: 0 is the trapezoidal rule (no numerical damping),
            lower values damp high frequencies more.
        velocity: Initial velocity (a Function on the displacement space), overwritten with the
            velocity at the end of the step; None: start at rest.
        acceleration: Where to leave the acceleration (a Function on the displacement space); read
            as the initial acceleration when ``initial_acceleration`` is False.
        initial_acceleration: Solve ``M a_0 = f_ext(0) - f(u_0)`` at the start (CalculiX does), with
            zero acceleration at constrained dofs and at ``u_0`` as it is (prescribed values that
            jump at the start are left out, as in CalculiX).
        cutback_factor, divergence_cutback_factor, growth_factor, growth_iterations: Automatic
            increments as in :class:`~dolfinx_ntf.StaticStep` (no CalculiX impact rules).
        on_increment: Called with the :class:`~dolfinx_ntf.IncrementResult` of each converged
            increment (``velocity``/``acceleration`` then hold that increment's values).
        time_points: Step times the increments end on (CalculiX ``*TIME POINTS``,
            docs/method.md §27), as :class:`~dolfinx_ntf.StaticStep`'s.
    """

    mass: ufl.Form
    set_load: LoadControl = no_load
    period: float = 1.0
    initial_increment: float = 0.01
    min_increment: float | None = None
    max_increment: float | None = None
    fixed: bool = False
    alpha: float = CCX_ALPHA
    velocity: dolfinx.fem.Function | None = None
    acceleration: dolfinx.fem.Function | None = None
    initial_acceleration: bool = True
    cutback_factor: float = 0.5
    divergence_cutback_factor: float = 0.25
    growth_factor: float = 1.5
    growth_iterations: int = 4
    on_increment: typing.Callable[[IncrementResult], None] | None = None
    time_points: typing.Sequence[float] | None = None

    def _check_own(self, owner: str) -> None:
        """The mass form and ``alpha``."""
        if not isinstance(self.mass, ufl.Form) or len(self.mass.arguments()) != 2:
            raise TypeError(
                f"{owner}: mass must be a bilinear UFL form such as "
                "rho*inner(TrialFunction(V), TestFunction(V))*dx, got "
                f"{validation.describe(self.mass)}"
            )
        if not (isinstance(self.alpha, (int, float)) and -1.0 / 3.0 <= self.alpha <= 0.0):
            raise ValueError(f"{owner}: alpha must be in [-1/3, 0] (ccx), got {self.alpha!r}")

    def minimum_increment(self) -> float | None:
        """The minimum increment, CalculiX's default when none is given."""
        if self.min_increment is not None:
            return self.min_increment
        return min(self.initial_increment, 1e-5 * self.period)

    def _run(
        self, solver: IncrementSolver, u: dolfinx.fem.Function, start_time: float
    ) -> list[IncrementResult]:
        """Add the inertia terms to the problem for the run, integrate, remove them."""
        problem = solver.problem
        V = u.function_space
        self._check_mass_space(V)
        velocity = self._state_function(self.velocity, V, "velocity")
        acceleration = self._state_function(self.acceleration, V, "acceleration")
        mass = dolfinx.fem.form(self.mass)
        inertia = _Inertia(
            dolfinx.fem.petsc.assemble_matrix(mass),
            dolfinx.fem.petsc.assemble_matrix(mass, problem.bcs, 0.0),
            float(self.alpha),
        )
        for matrix in (inertia.M, inertia.M_bc):
            matrix.assemble()
        problem.extra_terms.append(inertia)
        offset = dolfinx.fem.Function(V)  # v = offset + rate u: the contact damping's (§29)
        offset.x.array[:] = velocity.x.array
        problem.node_velocity = NodeVelocity(offset, 0.0)
        try:
            return self._integrate(
                solver, problem, u, velocity, acceleration, mass, inertia, start_time
            )
        finally:
            problem.extra_terms.remove(inertia)
            problem.node_velocity = None
            inertia.destroy()

    def _check_mass_space(self, V: dolfinx.fem.FunctionSpace) -> None:
        """Both arguments of the mass form must live on the displacement space of ``u``."""
        for argument in self.mass.arguments():
            space = argument.ufl_function_space()
            if space.ufl_element() != V.ufl_element() or space.ufl_domain() != V.mesh.ufl_domain():
                raise ValueError(
                    "DynamicStep: mass must be a form on the displacement space of u "
                    f"({V.ufl_element()} on its mesh), but its "
                    f"{'trial' if argument.number() else 'test'} function is on "
                    f"{space.ufl_element()}"
                    + ("" if space.ufl_domain() == V.mesh.ufl_domain() else " of another mesh")
                )

    @staticmethod
    def _state_function(
        given: dolfinx.fem.Function | None, V: dolfinx.fem.FunctionSpace, name: str
    ) -> dolfinx.fem.Function:
        if given is None:
            return dolfinx.fem.Function(V)
        validation.check_type(given, dolfinx.fem.Function, f"DynamicStep: {name}")
        index_map = V.dofmap.index_map
        size = (index_map.size_local + index_map.num_ghosts) * V.dofmap.index_map_bs
        if given.x.array.size != size:
            raise ValueError(
                f"DynamicStep: {name} must be a Function on the displacement space of u"
            )
        return given

    def _integrate(
        self,
        solver: IncrementSolver,
        problem: ContactProblem,
        u: dolfinx.fem.Function,
        velocity: dolfinx.fem.Function,
        acceleration: dolfinx.fem.Function,
        mass: compat.Form,
        inertia: _Inertia,
        start_time: float,
    ) -> list[IncrementResult]:
        x = compat.petsc_vector(u)
        owned = x.getLocalSize()
        problem.begin_step()
        self.set_load(0.0)
        problem.begin_increment(0.0, static=False)
        if self.initial_acceleration:  # from u_0 as it is, a jump of prescribed values left out
            _static_residual(problem, inertia, x, start=True)
            _initial_acceleration(mass, problem, inertia.last_residual, acceleration)
        _static_residual(problem, inertia, x)  # r_0 of the alpha method, with such a jump

        def start(t_new: float, dt: float, u_start: np.ndarray) -> None:
            problem.begin_increment(t_new / self.period, static=False)
            dolfinx.fem.petsc.set_bc(x, problem.bcs)  # prescribed values at t_{n+1}
            x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            inertia.predict(
                u_start[:owned], velocity.x.array[:owned], acceleration.x.array[:owned], dt
            )
            node_velocity = problem.node_velocity
            v0, node_velocity.rate = inertia.velocity_offset(
                velocity.x.array[:owned], acceleration.x.array[:owned]
            )
            node_velocity.offset.x.array[:owned] = v0
            node_velocity.offset.x.scatter_forward()

        def converged(dt: float, u_start: np.ndarray) -> None:
            self._advance(u, velocity, acceleration, inertia, owned)
            _static_residual(problem, inertia, x)

        return self._increments(solver, u, start, converged, start_time)

    @staticmethod
    def _advance(
        u: dolfinx.fem.Function,
        velocity: dolfinx.fem.Function,
        acceleration: dolfinx.fem.Function,
        inertia: _Inertia,
        owned: int,
    ) -> None:
        """Newmark update of velocity and acceleration after a converged increment."""
        a_new = inertia.acceleration(u.x.array[:owned])
        a_old = acceleration.x.array[:owned]
        dt, gamma = inertia.dt, inertia.gamma
        velocity.x.array[:owned] += dt * ((1.0 - gamma) * a_old + gamma * a_new)
        acceleration.x.array[:owned] = a_new
        velocity.x.scatter_forward()
        acceleration.x.scatter_forward()


def _static_residual(
    problem: ContactProblem, inertia: _Inertia, x: PETSc.Vec, *, start: bool = False
) -> None:
    """``r_n = f(u_n) - f_ext(t_n)`` into ``inertia.last_residual``, zero at constrained dofs.

    ``start``: at the start of the step, at ``u_0`` as it is: prescribed values that differ from
    ``u_0`` (a jump at the step start) do not enter (no lifting), as in CalculiX (docs/method.md
    §12.1).
    """
    bcs = problem.bcs
    inertia.enabled = False
    try:
        if start:
            problem.bcs = []
        residual = x.duplicate()
        problem.form(x)
        problem.assemble_residual(x, residual)
        inertia.last_residual.array[:] = residual.array_r
        residual.destroy()
    finally:
        inertia.enabled = True
        problem.bcs = bcs
    dolfinx.fem.petsc.set_bc(inertia.last_residual, problem.bcs, None, 0.0)
    if not math.isfinite(inertia.last_residual.norm()):
        raise ContactConvergenceError("the residual of the converged state is not finite")


def _initial_acceleration(
    mass: compat.Form,
    problem: ContactProblem,
    residual: PETSc.Vec,
    acceleration: dolfinx.fem.Function,
) -> None:
    """Solve ``M a_0 = -r_0`` (zero at constrained dofs) by a direct solver.

    With linear constraints (``problem.elimination``) in the constrained space, as the residual
    ``r_0`` is: ``T'^T M T'`` with a unit diagonal at dependent dofs, whose values then follow
    from the independent ones (C3D20's centres, the midside nodes of C3D8 cells beside them).
    """
    M = dolfinx.fem.petsc.assemble_matrix(mass, problem.bcs)
    M.assemble()
    if problem.elimination is not None:
        reduced = problem.elimination.project(M, diagonal=1.0)
        M.destroy()
        M = reduced
    ksp = PETSc.KSP().create(problem.u.function_space.mesh.comm)
    ksp.setOperators(M)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    rhs = residual.copy()
    rhs.scale(-1.0)
    a0 = compat.petsc_vector(acceleration)
    ksp.solve(rhs, a0)
    if ksp.getConvergedReason() < 0:
        raise ValueError(
            "DynamicStep: the mass matrix cannot be factored (is the density positive everywhere? "
            "a node without mass needs a constraint to one)"
        )
    if problem.elimination is not None:
        problem.elimination.expand(a0)
    acceleration.x.scatter_forward()
    for obj in (ksp, M, rhs):
        obj.destroy()
