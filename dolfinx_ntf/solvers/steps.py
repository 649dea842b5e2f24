"""Steps: CalculiX's automatic incrementation of a step, and the static step (``*STATIC``).

:class:`Step` is what every step shares: the configuration is checked once, when the step is
made, and :meth:`Step.run` drives CalculiX's attempts and cutbacks over the step time
(docs/method.md §7.2), calling the step's own start of an increment and its own update after a
converged one. :class:`StaticStep` adds the predictor; :class:`~dolfinx_ntf.DynamicStep` the
time integration.
"""

from __future__ import annotations

import inspect
import logging
import numbers
import time
import typing
from dataclasses import dataclass

import numpy as np

import dolfinx.fem

from dolfinx_ntf import validation
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.logs import details_logger
from dolfinx_ntf.solvers.errors import ContactConvergenceError, ContactDivergenceError

__all__ = ["IncrementResult", "IncrementSolver", "LoadControl", "StaticStep", "Step"]


@typing.runtime_checkable
class IncrementSolver(typing.Protocol):
    """What a step needs of its solver: one Newton solve per increment attempt.

    :class:`~dolfinx_ntf.ContactNewtonSolver` and :class:`~dolfinx_ntf.ContactSNESSolver` play
    this role.
    """

    #: The problem the solver drives.
    problem: ContactProblem
    #: Residual norms of the last solve, the first one first.
    residual_norms: list[float]
    #: Displacement at the start of the increment (set by the step before each attempt).
    increment_start: np.ndarray | None

    def begin_step(self) -> None:
        """A new step starts."""

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """Solve one increment attempt into ``u``; raise ``ContactConvergenceError`` on failure."""


logger = logging.getLogger("dolfinx_ntf")

LoadControl = typing.Callable[[float], None]


def no_load(t: float) -> None:
    """No time-dependent load: the increments only advance the step time ``t``."""


#: The step's own start of an attempt, ``start(t_new, dt, u_start)``, after its loads are set.
IncrementStart = typing.Callable[[float, float, np.ndarray], None]
#: The step's own update after a converged increment, ``converged(dt, u_start)``.
IncrementEnd = typing.Callable[[float, np.ndarray], None]


def check_solver(solver: object, what: str) -> None:
    """Raise ``TypeError`` naming ``what`` unless ``solver`` plays :class:`IncrementSolver`."""
    if not isinstance(solver, IncrementSolver):
        raise TypeError(
            f"{what} must be a ContactNewtonSolver or ContactSNESSolver (an IncrementSolver), "
            f"got {validation.describe(solver)}"
        )


@dataclass
class IncrementResult:
    """Summary of a converged increment.

    Attributes:
        increment: Increment number in the step, from 1.
        attempt: Attempt that converged, from 1 (more after cutbacks).
        time: Step time at the end of the increment.
        time_fraction: ``time`` over the step's period.
        iterations: Newton iterations of the converged attempt.
        springs: Contact springs over all processes at the end.
        residual: Norm of the last residual.
        total_time: Time since the start of the analysis: ``time`` for a step run alone, plus
            the periods of the steps before it in :func:`~dolfinx_ntf.run_steps`.
    """

    increment: int
    attempt: int
    time: float
    time_fraction: float
    iterations: int
    springs: int
    residual: float
    total_time: float = 0.0


def _takes_one_argument(function: typing.Callable) -> bool:
    """Whether ``function(t)`` binds (True when Python cannot tell, e.g. for some builtins)."""
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return True
    try:
        signature.bind(0.0)
    except TypeError:
        return False
    return True


class Step:
    """A step of ``period`` with CalculiX's automatic incrementation; the base of the steps.

    Subclasses are dataclasses with the fields below (see :class:`StaticStep`) and implement
    ``_run``; they check their own fields in ``_check_own``.
    """

    set_load: LoadControl
    period: float
    initial_increment: float
    min_increment: float | None
    max_increment: float | None
    fixed: bool
    cutback_factor: float
    divergence_cutback_factor: float
    growth_factor: float
    growth_iterations: int
    on_increment: typing.Callable[[IncrementResult], None] | None
    time_points: typing.Sequence[float] | None

    def __post_init__(self) -> None:
        """Check the configuration (``TypeError``/``ValueError`` naming the field)."""
        self.check()

    def check(self) -> None:
        """Raise ``TypeError``/``ValueError`` naming the first wrong field.

        Run when the step is made (and by ``dataclasses.replace``).
        """
        owner = type(self).__name__
        self._check_own(owner)
        if not callable(self.set_load) or not _takes_one_argument(self.set_load):
            raise TypeError(
                f"{owner}: set_load must be a function of the step time t (one argument), got "
                f"{validation.describe(self.set_load)}"
            )
        if self.on_increment is not None and not callable(self.on_increment):
            raise TypeError(
                f"{owner}: on_increment must be a function or None, got "
                f"{validation.describe(self.on_increment)}"
            )
        for name in ("period", "initial_increment"):
            validation.check_positive(getattr(self, name), f"{owner}: {name}")
        minimum = self.minimum_increment()
        validation.check_positive(minimum, f"{owner}: min_increment")
        for name in ("cutback_factor", "growth_factor"):
            validation.check_positive(getattr(self, name), f"{owner}: {name}")
        validation.check_positive(self.max_increment, f"{owner}: max_increment", allow_none=True)
        max_inc = self.period if self.max_increment is None else self.max_increment
        if not (minimum <= self.initial_increment <= max_inc):
            raise ValueError(
                f"{owner}: need 0 < min_increment ({minimum}) <= initial_increment "
                f"({self.initial_increment}) <= max_increment ({max_inc})"
            )
        factors = (self.cutback_factor, self.divergence_cutback_factor)
        if not (all(0 < f < 1 for f in factors) and self.growth_factor >= 1):
            raise ValueError(
                f"{owner}: need 0 < cutback_factor ({self.cutback_factor}), "
                f"divergence_cutback_factor ({self.divergence_cutback_factor}) < 1 <= "
                f"growth_factor ({self.growth_factor})"
            )
        if self.time_points is not None:
            points = np.asarray(self.time_points, dtype=np.float64)
            if points.ndim != 1 or not np.all(np.isfinite(points)) or np.any(np.diff(points) <= 0):
                raise ValueError(
                    f"{owner}: time_points must be increasing finite step times, got "
                    f"{validation.describe(self.time_points)}"
                )
        if isinstance(self.growth_iterations, bool) or not isinstance(
            self.growth_iterations, numbers.Integral
        ):
            raise TypeError(
                f"{owner}: growth_iterations must be an integer, got "
                f"{validation.describe(self.growth_iterations)}"
            )

    def _check_own(self, owner: str) -> None:
        """Check the fields of the subclass (before the shared ones)."""

    def minimum_increment(self) -> float | None:
        """The smallest increment a cutback may reach."""
        return self.min_increment

    def _time_point_limit(self, t: float, dt: float) -> float:
        """``dt`` shortened to end on the first time point after ``t`` that it would pass.

        CalculiX's ``*TIME POINTS`` (measured with ccx 2.20: "the increment size exceeds a time
        point and is decreased"); the increment size kept for the next increment is not changed,
        except after the step's first increment (docs/method.md §27.2).
        """
        if self.time_points is None:
            return dt
        points = np.asarray(self.time_points, dtype=np.float64)
        tolerance = 1e-9 * self.period
        ahead = points[points > t + tolerance]
        if ahead.size and t + dt > ahead[0] + tolerance:
            return float(ahead[0] - t)
        return dt

    def run(
        self, solver: IncrementSolver, u: dolfinx.fem.Function, *, start_time: float = 0.0
    ) -> list[IncrementResult]:
        """Run the step from the current ``u``.

        Args:
            solver: The solver of the problem.
            u: The problem's displacement (the Function the problem was built on).
            start_time: Total time at the start of the step (``IncrementResult.total_time`` is
                this plus the step time; :func:`~dolfinx_ntf.run_steps` passes it).

        Returns:
            The result of every converged increment of this run.

        Raises:
            ContactConvergenceError: When an increment fails and cutbacks are exhausted.
        """
        owner = type(self).__name__
        check_solver(solver, f"{owner}.run: solver")
        if u is not solver.problem.u:
            raise ValueError(
                f"{owner}.run: u must be the Function the ContactProblem was built on "
                f"(got {validation.describe(u)})"
            )
        return self._run(solver, u, float(start_time))

    def _run(
        self, solver: IncrementSolver, u: dolfinx.fem.Function, start_time: float
    ) -> list[IncrementResult]:
        """The step's own run, with checked arguments: set up, then :meth:`_increments`."""
        raise NotImplementedError

    def _cut_back(
        self,
        error: ContactConvergenceError,
        first_failure: ContactConvergenceError,
        dt: float,
        minimum: float,
        failed: str,
    ) -> float:
        """The increment size after a failed attempt (CalculiX's D_F or D_C); raise if none.

        Args:
            error: Why the attempt failed.
            first_failure: Why the increment's first attempt failed.
            dt: The failed increment size.
            minimum: The smallest increment size.
            failed: What failed, the start of the message when the step gives up.
        """
        factor = (
            self.divergence_cutback_factor
            if isinstance(error, ContactDivergenceError)
            else self.cutback_factor
        )
        if self.fixed or dt * factor < minimum:
            why = (
                "fixed increments"
                if self.fixed
                else f"increment size {dt:.3e} cannot be cut back below the minimum {minimum:.3e}"
            )
            first = "" if first_failure is error else f"; first attempt: {first_failure}"
            raise ContactConvergenceError(f"{failed} ({why}): {error}{first}") from error
        return dt * factor

    def _increments(
        self,
        solver: IncrementSolver,
        u: dolfinx.fem.Function,
        start: IncrementStart,
        converged: IncrementEnd,
        start_time: float,
    ) -> list[IncrementResult]:
        """CalculiX's increment control over the step time (docs/method.md §7.2).

        Each attempt sets the loads at the new time (``set_load``), calls ``start(t_new, dt,
        u_start)`` and solves; a failed attempt restores ``u`` and is cut back; a converged one
        commits the problem's increment state, calls ``converged(dt, u_start)`` and may let the
        next increment grow.
        """
        problem = solver.problem
        minimum = self.minimum_increment()
        solver.begin_step()
        max_inc = self.period if self.max_increment is None else self.max_increment
        results: list[IncrementResult] = []
        t, dt = 0.0, self.initial_increment
        increment, fast_in_a_row = 0, 0
        while t < self.period * (1 - 1e-12):
            increment += 1
            attempt = 0
            u_start = u.x.array.copy()
            solver.increment_start = u_start
            first_failure: ContactConvergenceError | None = None
            while True:
                attempt += 1
                dt = min(dt, self.period - t)
                desired, dt = dt, self._time_point_limit(t, dt)
                if increment == 1 and attempt == 1:  # ccx: the step starts with the shorter size
                    desired = dt
                t_new = t + dt
                details_logger.info(
                    " increment %d attempt %d\n increment size= %.6e\n actual step time= %.6e",
                    increment,
                    attempt,
                    dt,
                    t_new,
                )
                self.set_load(t_new)
                clock = time.perf_counter()
                try:
                    start(t_new, dt, u_start)
                    iterations, _ = solver.solve(u)
                    problem.end_increment()  # commits the friction state
                    break
                except ContactConvergenceError as error:
                    u.x.array[:] = u_start
                    u.x.scatter_forward()
                    problem.reject_increment()  # the material history back to the start
                    first_failure = first_failure or error
                    failed = (
                        f"increment {increment} (step time {t:.6g} -> {t_new:.6g}) "
                        f"failed after {attempt} attempt(s)"
                    )
                    dt = self._cut_back(error, first_failure, dt, minimum, failed)
                    desired = dt
                    fast_in_a_row = 0
                    logger.info(" %s; cutting back to %.6e", error, dt)
            converged(dt, u_start)
            t, dt = t_new, desired
            result = IncrementResult(
                increment,
                attempt,
                t,
                t / self.period,
                iterations,
                problem.total_springs,
                solver.residual_norms[-1],
                start_time + t,
            )
            results.append(result)
            changes = problem.total_face_changes
            logger.info(
                " increment %d converged: time %.6g, %d iterations, %d contact elements%s, "
                "residual %.3e (%.2f s)",
                increment,
                t,
                iterations,
                result.springs,
                f" ({changes} changed face)" if changes else "",
                result.residual,
                time.perf_counter() - clock,
            )
            if self.on_increment is not None:
                self.on_increment(result)
            fast_in_a_row = fast_in_a_row + 1 if iterations <= self.growth_iterations else 0
            if not self.fixed and fast_in_a_row >= 2:
                dt = min(self.growth_factor * dt, max_inc)
        return results


@dataclass
class StaticStep(Step):
    """A static step of ``period`` with automatic incrementation (CalculiX ``*STATIC``).

    The step holds configuration only: :meth:`~dolfinx_ntf.solvers.steps.Step.run` returns the
    results of that run, and the same step can run again (e.g. another load case on a fresh
    problem).

    Args:
        set_load: Called with the step time at the end of each increment (before the pairing);
            scales loads and prescribed displacements, e.g.
            ``lambda t: setattr(traction, "value", t * p)``. Default: no load (the increments
            advance the time only, e.g. for loads that :func:`~dolfinx_ntf.run_steps` sets).
        period: Step time.
        initial_increment, min_increment, max_increment: Increment sizes.
        fixed: Use ``initial_increment`` throughout (CalculiX DIRECT).
        predictor: Start each increment from ``u_n + dt v_prev`` like CalculiX (after the
            pairing). Off by default: on contact zones that grow, the extrapolated displacement
            pushes open slave nodes deep into the master and the iterates run away (measured on a
            quarter sphere pressed by fixed increments: diverges with it, converges without).
        pair_after_predictor: Pair again at the predicted displacement (beyond CalculiX, which
            pairs at ``u_n`` only): slave nodes the predictor pushes into the master start with a
            spring instead of penetrating freely in the first iteration, which otherwise makes
            the iterates run away on growing contact zones (measured on a quarter sphere pressed
            by fixed increments, where ccx's order diverges and this converges).
        cutback_factor: Increment size factor after an attempt that did not converge in
            ``max_it`` iterations (CalculiX's D_C = 0.5).
        divergence_cutback_factor: Increment size factor after an attempt that diverged
            (CalculiX's D_F = 0.25).
        growth_factor, growth_iterations: Like CalculiX (D_D = 1.5, I_G = 4), the increment grows by
            ``growth_factor`` after two consecutive increments that each converged in at most
            ``growth_iterations`` iterations.
        on_increment: Called with the :class:`IncrementResult` of each converged increment.
        time_points: Step times the increments end on (CalculiX ``*TIME POINTS``): an increment
            that would pass one is shortened to end there, and a shortened first increment is
            the size kept for the next ones, as in CalculiX (docs/method.md §27.2); None: none.
        guard_predictor: With ``predictor`` and without ``pair_after_predictor``: start from
            ``u_n`` instead when the predicted displacement brings slave nodes into contact that
            the increment-start pairing gave no spring (the growing contact zones on which the
            predictor makes the iterates run away); the deck runner's default (docs/method.md
            §7.2).
        elastic_start: CalculiX's elastic first iteration: in the first increment of the step
            (every attempt), the first iterate evaluates the material history (plasticity)
            elastically when the prescribed displacements change there by more than 1e-5
            (docs/method.md §33); the deck runner's default.
        elastic_contact: The springs in that first iterate when the prescribed displacements
            change there by more than 1e-5 (docs/method.md §33.4): ``"iterate"`` (default) at
            the iterate; ``"start"`` at the increment start, as CalculiX 2.20's static steps (the
            deck runner's default with ``elastic_start``); ``"stick"`` at the iterate, every
            friction spring's force stuck.
    """

    set_load: LoadControl = no_load
    period: float = 1.0
    initial_increment: float = 1.0
    min_increment: float = 1e-5
    max_increment: float | None = None
    fixed: bool = False
    predictor: bool = False
    cutback_factor: float = 0.5
    divergence_cutback_factor: float = 0.25
    pair_after_predictor: bool = True
    growth_factor: float = 1.5
    growth_iterations: int = 4
    on_increment: typing.Callable[[IncrementResult], None] | None = None
    guard_predictor: bool = False
    time_points: typing.Sequence[float] | None = None
    elastic_start: bool = False
    elastic_contact: str = "iterate"

    def _run(
        self, solver: IncrementSolver, u: dolfinx.fem.Function, start_time: float
    ) -> list[IncrementResult]:
        """Start each increment from the last one's, or from the predictor."""
        problem = solver.problem
        problem.begin_step()
        velocity: np.ndarray | None = None

        def start(t_new: float, dt: float, u_start: np.ndarray) -> None:
            first = self.elastic_start or self.elastic_contact != "iterate"
            if velocity is None and first:  # the step's first increment
                problem.begin_increment(
                    t_new / self.period,
                    elastic_start=self.elastic_start,
                    elastic_contact=self.elastic_contact,
                )
            else:
                problem.begin_increment(t_new / self.period)
            if self.predictor and velocity is not None:
                u.x.array[:] = u_start + dt * velocity
                u.x.scatter_forward()
                if self.pair_after_predictor:
                    problem.pair()
                    problem.ensure_matrix()
                elif self.guard_predictor and (unpaired := problem.unpaired_contacts()):
                    u.x.array[:] = u_start
                    u.x.scatter_forward()
                    logger.info(
                        " predictor dropped: it brings %d unpaired slave node(s) into contact",
                        unpaired,
                    )

        def converged(dt: float, u_start: np.ndarray) -> None:
            nonlocal velocity
            velocity = (u.x.array - u_start) / dt

        return self._increments(solver, u, start, converged, start_time)
