"""The continuum contact solver as a step's solver: load stepping, cutbacks, progress lines.

:class:`~dolfinx_ntf.fem.continuum.ContinuumNewton` solves UFL contact residuals (penalty,
Nitsche) on its own. :class:`ContinuumIncrementSolver` wraps it as the steps' solver
(:class:`~dolfinx_ntf.solvers.steps.IncrementSolver`), so that :class:`~dolfinx_ntf.StaticStep` and
:func:`~dolfinx_ntf.run_steps` drive it like the springs' solvers: ``set_load`` and
:class:`~dolfinx_ntf.Load` values per increment, a cutback when a solve fails, one progress line
per increment on ``"dolfinx_ntf"``. The steps' calls on the problem (pairing at an increment's
start, the friction state at its end) are, for a UFL residual, only the obstacles' motion
(:class:`ContinuumProblem`).
"""

from __future__ import annotations

import typing

from petsc4py import PETSc

import dolfinx.fem

from dolfinx_ntf import compat, validation
from dolfinx_ntf.fem.continuum import ContinuumNewton, ContinuumNewtonError, RigidObstacle
from dolfinx_ntf.solvers.errors import (
    ContactConvergenceError,
    ContactDivergenceError,
    ContactSolverError,
)

__all__ = ["ContinuumIncrementSolver", "ContinuumProblem"]

#: The step error of each kind of :class:`~dolfinx_ntf.fem.continuum.ContinuumNewtonError`.
_STEP_ERRORS: dict[str, type[RuntimeError]] = {
    "convergence": ContactConvergenceError,
    "divergence": ContactDivergenceError,
    "input": ContactSolverError,
}


class ContinuumProblem:
    """What the step drivers ask of a problem, for a :class:`ContinuumIncrementSolver`.

    The steps drive a :class:`~dolfinx_ntf.ContactProblem`: they pair at the start of each
    increment and commit the friction state at its end. A UFL contact residual has no pairing and
    no state, so those calls only move the obstacles to the increment's time. The spring count
    of the progress line is the number of nodes with a contact force.

    Args:
        newton: The solver whose displacement, Dirichlet conditions and Jacobian these are.
        obstacles: Obstacles that the steps move to the relative step time at the start of each
            increment (their ``motion``).
    """

    def __init__(self, newton: ContinuumNewton, obstacles: typing.Sequence[RigidObstacle]) -> None:
        self._newton = newton
        self.obstacles = list(obstacles)
        for obstacle in self.obstacles:
            validation.check_type(obstacle, RigidObstacle, "ContinuumIncrementSolver: obstacles")
        #: The contact pairs, none (so run_steps' contact changes cannot name one).
        self.states: list = []

    @property
    def u(self) -> dolfinx.fem.Function:
        """The displacement."""
        return self._newton.u

    @property
    def bcs(self) -> list[compat.DirichletBC]:
        """The Dirichlet conditions."""
        return self._newton.bcs

    def set_bcs(self, bcs: typing.Sequence[compat.DirichletBC]) -> None:
        """Replace the Dirichlet conditions (``AnalysisStep.bcs`` of a run_steps).

        Args:
            bcs: The new conditions, on ``u``'s space.
        """
        self._newton.bcs = list(bcs)

    def begin_step(self) -> None:
        """A step starts (nothing to do)."""

    def begin_increment(self, time_fraction: float, *, static: bool = True) -> None:
        """Move the obstacles to the end of the increment.

        Args:
            time_fraction: Relative step time at the end of the increment.
            static: Unused (the springs' initial overlap ramp has no counterpart here).
        """
        for obstacle in self.obstacles:
            obstacle.update(time_fraction)

    def end_increment(self) -> None:
        """The increment converged (no state to commit)."""

    def reject_increment(self) -> None:
        """An attempt failed and ``u`` is back at the increment start (no state to roll back)."""

    def pair(self, **_: object) -> int:
        """No pairing (the gap is part of the residual); returns 0."""
        return 0

    def ensure_matrix(self) -> PETSc.Mat:
        """The Jacobian matrix (its pattern never changes)."""
        return self._newton.A

    def unpaired_contacts(self) -> int:
        """No node can lack a pairing; returns 0."""
        return 0

    @property
    def total_springs(self) -> int:
        """Nodes with a non-zero contact force after the last converged solve, all processes.

        For Nitsche with ``theta != 0`` also nodes where only its stress term acts.
        """
        return self._newton.contact_nodes

    @property
    def total_face_changes(self) -> int:
        """No master faces to change; 0."""
        return 0


class ContinuumIncrementSolver:
    """A :class:`~dolfinx_ntf.fem.continuum.ContinuumNewton` as the solver of the step drivers.

    ``StaticStep(set_load, initial_increment=0.25).run(ContinuumIncrementSolver(newton), u)``
    solves by increments: a failed solve raises :class:`~dolfinx_ntf.ContactConvergenceError`
    (or :class:`~dolfinx_ntf.ContactDivergenceError`) and the step cuts back; a failure no smaller
    increment can fix (non-finite input) raises :class:`~dolfinx_ntf.ContactSolverError`.

    Args:
        newton: The continuum solver; its ``u`` is the Function to pass to ``run``.
        obstacles: The obstacles of its contact form that move (a ``motion``): the steps move
            them to each increment's time.
    """

    def __init__(
        self, newton: ContinuumNewton, obstacles: typing.Sequence[RigidObstacle] = ()
    ) -> None:
        validation.check_type(newton, ContinuumNewton, "ContinuumIncrementSolver: newton")
        self.newton = newton
        #: The steps' view of the problem.
        self.problem = ContinuumProblem(newton, obstacles)
        #: Residual norms of the last solve, the first one first.
        self.residual_norms: list[float] = []
        #: Displacement at the start of the increment (set by the steps; unused).
        self.increment_start = None

    def begin_step(self) -> None:
        """A step starts (the test is relative to each solve's first residual: nothing to reset)."""

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """Solve one increment attempt into ``u``.

        Args:
            u: The solver's displacement (``newton.u``).

        Returns:
            The number of Newton updates and True.

        Raises:
            ContactConvergenceError: No convergence in ``max_it`` updates (the step cuts back).
            ContactDivergenceError: A non-finite residual or failed linear solve after an update.
            ContactSolverError: A non-finite residual before any update, or a failed first linear
                solve (the setup's fault).
        """
        if u is not self.newton.u:
            raise ValueError(
                "ContinuumIncrementSolver.solve: u must be the Function the ContinuumNewton was "
                "made with"
            )
        try:
            record = self.newton.solve()
        except ContinuumNewtonError as error:
            raise _STEP_ERRORS[error.kind](str(error)) from error
        finally:
            self.residual_norms = self.newton.residual_norms
        return record.iterations, True
