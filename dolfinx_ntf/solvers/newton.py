"""Newton solver with CalculiX's contact convergence rules.

:class:`ContactNewtonSolver` runs the Newton loop of
:class:`~dolfinx_ntf.solvers.newton_loop.NewtonSolver` (dolfinx's, without ``dolfinx.nls``). It
decides convergence in the residual callback (:meth:`ContactNewtonSolver.is_converged` plus
CalculiX's rules: at least two Newton updates, none right after a re-pairing that changed the number
of springs); the loop's convergence check returns that decision. The pieces it wires live in modules
of their own: the choice of linear solver (:mod:`~dolfinx_ntf.solvers.linear_solver`), the
force-scaled test and the divergence rule (:mod:`~dolfinx_ntf.solvers.convergence`), the line search
(:mod:`~dolfinx_ntf.solvers.line_search`) and the errors (:mod:`~dolfinx_ntf.solvers.errors`).
"""

from __future__ import annotations

import contextlib
import logging
import numbers
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem

from dolfinx_ntf import validation
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.logs import newton_logger, quiet_dolfinx
from dolfinx_ntf.solvers import convergence, errors, factor_reuse
from dolfinx_ntf.solvers import linear_solver as linear
from dolfinx_ntf.solvers.convergence import (
    DIVERGENCE_RULES,
    TIGHT_FIELD_CONTROLS,
    DivergenceRule,
    ExtraPairings,
    ForceScaledTest,
    RoundoffFloor,
)
from dolfinx_ntf.solvers.errors import ContactConvergenceError, ContactSolverError
from dolfinx_ntf.solvers.line_search import LineSearch
from dolfinx_ntf.solvers.newton_loop import NewtonSolver

__all__ = ["ContactNewtonSolver"]

logger = logging.getLogger("dolfinx_ntf")


class ContactNewtonSolver(NewtonSolver):
    """Newton solver driving a :class:`ContactProblem`.

    Args:
        comm: MPI communicator.
        problem: The contact problem.
        petsc_options: PETSc options of the linear solver, set under ``options_prefix``
            (default: chosen by ``linear_solver``).
        linear_solver: Without ``petsc_options``: ``"direct"`` (MUMPS LU or Cholesky),
            ``"iterative"`` (GMRES or CG with GAMG) or ``"auto"`` (by size), see
            ``default_options`` in ``solvers/linear_solver.py``. Whatever the choice, a
            GAMG preconditioner gets the rigid-body modes of every body as near-nullspace.
        options_prefix: Prefix of the Krylov solver's options; options already in PETSc's
            database under it (``-ntf_ksp_view``, ``-ntf_pc_type gamg``) take precedence over
            ``petsc_options``, which are removed again once read. Unknown solver names are a
            ``ValueError`` naming the option.
        controls: CalculiX's ``*CONTROLS, PARAMETERS=FIELD`` values of the force-scaled test
            (:meth:`is_converged`); default ``TIGHT_FIELD_CONTROLS`` (round-off level, never
            below it), ``CCX_FIELD_CONTROLS`` are ccx's defaults (``solvers/convergence.py``).
        relaxation_iteration: CalculiX's I_P: after this many updates ``R_p`` replaces ``R_n``.
        max_it: Maximum Newton iterations per increment.
        min_iterations: Newton updates needed before convergence can be declared (ccx: 2).
        divergence_iteration: CalculiX's I_0: from this Newton update on, a growing residual
            gives the increment up at once
            (:class:`~dolfinx_ntf.solvers.convergence.DivergenceRule`; a re-pairing that changes
            the number of springs defers it by 4 updates, as in ccx).
        divergence_rule: ``"growth"``: a residual 2-norm larger than each of the two before it;
            ``"ccx"``: CalculiX 2.20's check on the largest residual force (the last two larger
            than the one before them and the last above the force-scaled test's tolerance; the
            deck runner's). docs/method.md §42 measures both.
        line_search: Backtrack along each Newton correction until the residual of the current
            pairing decreases (:class:`~dolfinx_ntf.solvers.line_search.LineSearch`, beyond
            CalculiX).
        max_line_search_halvings: Smallest step of the line search is 2 to the minus this.
        line_search_from: First Newton update that is line-searched. The first correction of an
            increment is taken in full: from an unloaded contact it overshoots the residual of
            the LINEAR law (slope K/2 at zero overclosure, K beyond) and is corrected in one
            more iteration, which damping would only delay.
        check_unpaired: Before declaring convergence, search for slave nodes that penetrate
            without a spring and pair again if any
            (:class:`~dolfinx_ntf.solvers.convergence.ExtraPairings`, beyond CalculiX; the deck
            runner reports their number instead).
        roundoff_floor: Leave residual forces below their round-off out of the test, beyond
            CalculiX (``solvers.convergence.roundoff_floor``: at spring nodes 10 eps times the
            Jacobian's largest row sum and the largest coordinate, elsewhere 10 eps times the
            bulk Jacobian's largest row sum and the largest displacement): a stiff penalty's
            spring forces, or the large element forces under a contact, carry that much
            round-off, which the force-scaled test can otherwise ask to go below (the deck
            runner keeps CalculiX's test).
        bounded_scale: A force-scaled test that runaway iterates cannot pass, beyond CalculiX
            (``bounded`` of :class:`~dolfinx_ntf.solvers.convergence.ForceScaledTest`; the deck
            runner keeps CalculiX's test).
        residual_floor, average_over_step, change_over_iterations: CalculiX's variants of the
            force-scaled test that the deck runner reproduces
            (:class:`~dolfinx_ntf.solvers.convergence.ForceScaledTest`);
            the defaults keep the test scale-free and within the increment.
        factorization: With a direct linear solver: ``"fresh"`` factors every Jacobian,
            ``"reuse"`` solves the corrections after the first by GMRES preconditioned by an
            earlier factorization and factors afresh only when GMRES would need more than a
            few iterations (:mod:`~dolfinx_ntf.solvers.factor_reuse`; the iterates differ at
            the Krylov tolerance, 1e-11 of the residual), ``"auto"`` reuses from
            ``REUSE_MIN_DOFS`` dofs on.
    """

    def __init__(
        self,
        comm: MPI.Comm,
        problem: ContactProblem,
        *,
        petsc_options: dict[str, typing.Any] | None = None,
        linear_solver: str = "auto",
        options_prefix: str = "ntf_",
        controls: typing.Mapping[str, float] | None = None,
        relaxation_iteration: int = 9,
        max_it: int = 30,
        min_iterations: int = 2,
        divergence_iteration: int = 4,
        divergence_rule: str = "growth",
        line_search: bool = True,
        max_line_search_halvings: int = 4,
        line_search_from: int = 2,
        check_unpaired: bool = True,
        roundoff_floor: bool = True,
        bounded_scale: bool = True,
        residual_floor: float = 0.0,
        average_over_step: bool = False,
        change_over_iterations: bool = False,
        factorization: str = "auto",
    ) -> None:
        dofs = (
            problem.u.function_space.dofmap.index_map.size_global
            * problem.u.function_space.dofmap.index_map_bs
            if isinstance(problem, ContactProblem)
            else 0
        )
        if divergence_rule not in DIVERGENCE_RULES:
            raise ValueError(
                f"ContactNewtonSolver: divergence_rule must be one of {DIVERGENCE_RULES}, "
                f"got {divergence_rule!r}"
            )
        reuse = factor_reuse.reuses_factorization(factorization, dofs, "ContactNewtonSolver")
        symmetric = linear.expects_symmetric(problem, petsc_options)
        controls = dict(TIGHT_FIELD_CONTROLS if controls is None else controls)
        options = check_arguments(
            comm,
            problem,
            linear.default_options(problem, linear_solver, symmetric)
            if petsc_options is None
            else petsc_options,
            options_prefix,
            controls=controls,
            max_it=max_it,
            min_iterations=min_iterations,
        )
        validation.check_linear_solver(comm, options, "ContactNewtonSolver")
        super().__init__(comm, problem)
        self.problem = problem
        # Before the first pairing the problem's matrix would lack the springs' couplings and be
        # built twice (0.3 s at 80k dofs): dolfinx's bulk matrix stands in until solve binds it.
        self._placeholder: PETSc.Mat | None = self._A
        if problem.matrix is not None:
            self._bind_matrix()
        self.setJ(self._jacobian, self._A)
        self.setF(self._residual, self._b)
        self.set_form(self._form)
        self.set_update(self._update)
        self.set_convergence_check(self._decision)
        self._converged_now = False
        self.convergence_criterion = "residual"
        #: CalculiX's force-scaled test (:meth:`is_converged`) and the forces it remembers.
        self.test = ForceScaledTest(
            controls,
            relaxation_iteration,
            residual_floor,
            average_over_step,
            change_over_iterations,
            bounded_scale,
        )
        #: Displacement at the start of the increment (before the predictor); set by the step
        #: driver, else the displacement when :meth:`solve` starts.
        self.increment_start: np.ndarray | None = None
        self.min_iterations = min_iterations
        self.roundoff_floor = roundoff_floor
        self._roundoff = RoundoffFloor(0.0, 0.0)
        problem.measure_bulk_norm = roundoff_floor
        self.divergence = DivergenceRule(divergence_iteration, divergence_rule)
        self.first_solve = True
        self.line_search = line_search
        self.line_search_from = line_search_from
        self.check_unpaired = check_unpaired
        self.extra_pairings = ExtraPairings()
        self.step_lengths: list[float] = []
        self.backtracking = LineSearch(self._b, max_line_search_halvings)
        self.max_it = max_it
        self.error_on_nonconvergence = False
        self.report = False
        self.updates = 0
        self.residual_norms: list[float] = []
        #: One row per Newton update of the current solve, (update, springs (all processes), largest
        #: residual force, mean average force, largest correction, largest displacement change in
        #: the increment).
        self.history: list[tuple[int, int, float, float, float, float]] = []
        self.linear = linear.LinearSolver(
            self.krylov_solver,
            options,
            options_prefix,
            problem.u.function_space,
            symmetric,
            reuse_factorization=reuse,
        )
        self.linear.attach(self._A)

    @property
    def near_nullspace(self) -> PETSc.NullSpace | None:
        """Rigid-body modes of every body, the near-nullspace of a GAMG preconditioner."""
        return self.linear.near_nullspace

    @property
    def controls(self) -> dict[str, float]:
        """CalculiX's ``*CONTROLS, PARAMETERS=FIELD`` values of :meth:`is_converged`."""
        return self.test.controls

    @controls.setter
    def controls(self, value: dict[str, float]) -> None:
        self.test.controls = value

    @property
    def relaxation_iteration(self) -> int:
        """CalculiX's I_P, the number of updates after which ``R_p`` replaces ``R_n``."""
        return self.test.relaxation_iteration

    @relaxation_iteration.setter
    def relaxation_iteration(self, value: int) -> None:
        self.test.relaxation_iteration = value

    @property
    def largest_residual(self) -> float:
        """Largest residual force of the last iterate (before ``residual_floor``), all processes."""
        return self.test.largest_residual

    def begin_step(self) -> None:
        """Start a step: CalculiX's time average of the forces restarts."""
        self.test.step_forces = []

    def destroy(self) -> None:
        """Destroy the PETSc objects the solver owns (residual, line search, Krylov solver).

        Collective. The Jacobian belongs to the problem (:meth:`ContactProblem.destroy`).
        """
        self._b.destroy()
        self.backtracking.destroy()
        self._destroy_placeholder()
        self.linear.destroy()
        super().destroy()

    def __enter__(self) -> ContactNewtonSolver:
        return self

    def __exit__(self, *args: object) -> None:
        self.destroy()

    def _jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """The problem's Jacobian, with the linear solver kept in step with it."""
        merges = self.problem.assembler.pattern_merges
        self.problem.J(x, A)
        if self.roundoff_floor:
            self._roundoff = convergence.roundoff_floor(self.problem, A, x)
        self.linear.update(
            A,
            friction=self.problem.has_friction,
            pattern_grew=self.problem.assembler.pattern_merges != merges,
            reduced=self.problem.reduced_matrix,
        )

    def solve_correction(self, b: PETSc.Vec, dx: PETSc.Vec) -> None:
        """Solve ``J dx = b``, with an earlier factorization where it is reused."""
        self.linear.solve(b, dx)

    def _update(self, solver: NewtonSolver, dx: PETSc.Vec, x: PETSc.Vec) -> None:
        """Dolfinx's update ``x -= relaxation dx``, counted; a failed linear solve stops here.

        An iterative solve that failed is done again by MUMPS LU, which the solver keeps for the
        rest of the run (a singular Jacobian is not retried). A zero first right-hand side cannot
        show a singular Jacobian: the rigid-body modes of the bodies nothing holds are tried.
        """
        failure = self.linear.failure(dx, self._b)
        if failure is not None and "singular" not in failure and self.linear.fall_back_to_direct():
            logger.info(" %s: solving again with MUMPS LU, kept for the rest of the run", failure)
            self.krylov_solver.solve(self._b, dx)
            failure = self.linear.failure(dx, self._b)
        if failure is None and self.first_solve and self.updates == 0 and self._b.norm() == 0:
            failure = errors.free_rigid_motion(self.problem, self._A)  # no residual to judge by
        if failure is not None:
            self._linear_solve_failed(failure)
        self.updates += 1
        self.last_correction = dx
        step = 1.0
        if self.line_search and self.updates >= self.line_search_from:
            step = self._line_search(dx, x)
        self.step_lengths.append(step)
        x.axpy(-step * self.relaxation_parameter, dx)

    def _line_search(self, dx: PETSc.Vec, x: PETSc.Vec) -> float:
        """Step length along ``-dx`` that decreases the residual of the current pairing."""
        start = self._b.norm()  # the residual of the pairing this correction was computed with
        return self.backtracking.search(self.problem, dx, x, start, self.relaxation_parameter)

    def _form(self, x: PETSc.Vec) -> None:
        """Springs at the new iterate, unless the line search has just evaluated them there."""
        if not self.backtracking.trial_is_current:
            self.problem.form(x)

    def is_converged(self, x: PETSc.Vec, b: PETSc.Vec, norm: float) -> bool:
        """CalculiX's force-scaled test of the mechanical field, after each Newton update.

        Measures the iterate (largest residual force, correction and displacement change in the
        increment, average element force :meth:`ContactProblem.average_element_force`) for
        :meth:`~dolfinx_ntf.solvers.convergence.ForceScaledTest.converged`, whose docstring states
        the test. The caller adds CalculiX's other rules (at least ``min_iterations`` updates,
        none right after a re-pairing that changed the number of springs). Override for other
        criteria.

        dolfinx's hook: ``x`` is the iterate, ``b`` its residual and ``norm`` the residual's norm
        (unused: the test takes the largest residual force).
        """
        if self.updates == 0:
            if self.test.bounded:  # the forces the bounded test starts from
                self.test.begin_iterations(
                    self.problem.average_element_force(), b.norm(PETSc.NormType.NORM_INFINITY)
                )
            return False
        start = self.increment_start if self.increment_start is not None else self._solve_start
        measures = convergence.measure_iterate(
            self.problem, x, b, self.last_correction, self.relaxation_parameter, start
        )
        average, largest, correction, change = measures
        correction *= self.step_lengths[-1]
        if self.roundoff_floor:
            largest = convergence.largest_beyond_roundoff(self.problem, b, self._roundoff)
        converged = self.test.converged(self.updates, average, largest, correction, change)
        springs = self.problem.u.function_space.mesh.comm.allreduce(self.problem.num_springs)
        self.history.append((self.updates, springs, *self.test.last))
        return converged

    def _linear_solve_failed(self, what: str) -> typing.NoReturn:
        """Non-retryable at the very first Newton iteration of a solver, divergence later."""
        at_start = self.first_solve and self.updates == 0
        prefix = self.krylov_solver.getOptionsPrefix()
        raise errors.linear_solve_failure(what, at_start, self.updates, prefix, self.problem)

    def _residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        if self.backtracking.trial_is_current:  # the accepted trial: same springs, same x
            self.backtracking.trial_residual.copy(b)
            self.backtracking.trial_is_current = False
        else:
            self.problem.F(x, b)
        norm = b.norm()
        if not np.isfinite(norm):
            raise errors.non_finite_residual(norm, self.updates, self.problem)
        if self.problem.count_changed:
            self.divergence.defer(self.updates, 4)
        self.residual_norms.append(norm)
        converged = self.is_converged(x, b, norm)  # always called: criteria may keep a history
        self._check_divergence()  # after the test: the diverging iterate is in the history
        converged = (
            converged and self.updates >= self.min_iterations and not self.problem.count_changed
        )
        if converged and self.check_unpaired:
            converged = self._all_contacts_paired()
        self._converged_now = converged
        if newton_logger.isEnabledFor(logging.INFO):
            correction = self.last_correction if self.updates else None
            springs = self.problem.total_springs
            newton_logger.info(
                _iteration_line(
                    self.updates,
                    self.residual_norms,
                    correction,
                    self.relaxation_parameter,
                    springs,
                )
                + (", converged" if converged else "")
            )

    def _check_divergence(self) -> None:
        """Give the attempt up if the residual grows (:class:`DivergenceRule`)."""
        hint = lambda: errors.no_support_hint(self.problem)  # noqa: E731
        if self.divergence.rule == "ccx":  # the force-scaled test's measures
            self.divergence.check(self.updates, self.test.residuals, hint, self.test.tolerance)
        else:
            self.divergence.check(self.updates, self.residual_norms, hint)

    def _decision(self, solver: NewtonSolver, b: PETSc.Vec) -> tuple[float, bool]:
        """The loop's convergence check: what :meth:`_residual` decided for ``b``."""
        return self.residual_norms[-1], self._converged_now

    def _all_contacts_paired(self) -> bool:
        """False (and a re-pairing next iteration) when slave nodes penetrate without a spring."""
        unpaired = self.problem.unpaired_contacts()
        if unpaired == 0:
            return True
        self.max_it += self.extra_pairings.take(unpaired)
        self.problem.repair_next_iteration = True
        self.divergence.defer(self.updates, 5)  # as after a count change
        logger.info(" %d slave node(s) penetrate without a spring: pairing again", unpaired)
        return False

    def _bind_matrix(self) -> None:
        """Solve with the problem's current matrix (a new one after a rebuild)."""
        A = self.problem.ensure_matrix()
        if A is not self._A:
            self._destroy_placeholder()
            self._A = A
            self.setJ(self._jacobian, A)
            if hasattr(self, "linear"):  # not yet while __init__ binds an existing matrix
                self.linear.attach(A)

    def _destroy_placeholder(self) -> None:
        if self._placeholder is not None:
            self._placeholder.destroy()
            self._placeholder = None

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """Solve one increment from the current ``u`` (after ``begin_increment``).

        Returns:
            The number of Newton iterations and True; a failure raises
            :class:`ContactConvergenceError`.
        """
        if u is not self.problem.u:
            raise ValueError(
                "ContactNewtonSolver.solve: u must be the Function the ContactProblem was built on"
            )
        self.residual_norms = []
        self.step_lengths = []
        self.history = []
        self.extra_pairings = ExtraPairings()
        max_it = self.max_it
        self._solve_start = u.x.array.copy()
        self.updates = 0
        self.backtracking.trial_is_current = False
        change = 0.0  # with a predictor, its own change counts too (as in ccx)
        if self.test.change_over_iterations and self.increment_start is not None:
            moved = np.abs(u.x.array - self.increment_start[: u.x.array.size]).max(initial=0.0)
            change = u.function_space.mesh.comm.allreduce(moved, op=MPI.MAX)
        self.test.begin_solve(change)
        self.divergence.reset()
        self._bind_matrix()
        try:
            # non-convergence is reported below, with the residuals
            with (
                quiet_dolfinx(),
                linear.galerkin_products(self.krylov_solver),
                _as_contact_errors(self._linear_solve_failed),
            ):
                iterations, converged = super().solve(u)
        finally:
            self.first_solve = False
            self.max_it = max_it
        if not converged:
            raise ContactConvergenceError(
                f"Newton did not converge in {iterations} iterations "
                f"(residual {self.residual_norms[-1]:.3e}, "
                f"first {self.residual_norms[0]:.3e}){errors.no_support_hint(self.problem)}"
            )
        self.test.end_solve()
        if self.linear.factor_reuse is not None:
            logger.debug("linear solves so far: %s", self.linear.factor_reuse.summary())
        return iterations, True


@contextlib.contextmanager
def _as_contact_errors(fail: typing.Callable[[str], typing.NoReturn]) -> typing.Iterator[None]:
    """Turn PETSc errors and those of degenerate iterates into a call of ``fail(what)``."""
    try:
        yield
    except (ContactConvergenceError, ContactSolverError):
        raise
    except PETSc.Error as error:
        fail(f"the Newton iteration failed ({validation.describe_petsc_error(error)})")
    except (RuntimeError, ValueError) as error:  # degenerate iterates
        fail(f"the Newton iteration failed ({error})")


def _iteration_line(
    updates: int,
    norms: list[float],
    correction: PETSc.Vec | None,
    relaxation: float,
    springs: int,
) -> str:
    """One progress line: residual (``norms[-1]``) and correction norms, spring count.

    Collective with a ``correction`` (its norm).
    """
    norm = norms[-1]
    line = f" iteration {updates}: residual {norm:.3e}"
    if correction is not None:
        ratio = norm / norms[0] if norms[0] > 0 else 0.0
        line += f" ({ratio:.1e} of the first), correction {relaxation * correction.norm():.3e}"
    return line + f", {springs} contact elements"


def check_arguments(
    comm: object,
    problem: object,
    petsc_options: object,
    options_prefix: object,
    *,
    controls: object,
    max_it: object,
    min_iterations: object,
    owner: str = "ContactNewtonSolver",
) -> dict[str, typing.Any]:
    """The arguments a contact solver shares with :class:`ContactNewtonSolver`.

    Returns:
        The checked PETSc options.
    """
    validation.check_type(comm, MPI.Comm, f"{owner}: comm", "pass mesh.comm")
    validation.check_type(problem, ContactProblem, f"{owner}: problem")
    if MPI.Comm.Compare(comm, problem.u.function_space.mesh.comm) == MPI.UNEQUAL:
        raise ValueError(f"{owner}: comm must be the communicator of the mesh (mesh.comm)")
    if not isinstance(options_prefix, str) or not options_prefix or " " in options_prefix:
        raise ValueError(
            f"{owner}: options_prefix must be a non-empty string without blanks such as 'ntf_', "
            f"got {options_prefix!r}"
        )
    if not isinstance(controls, typing.Mapping):
        raise TypeError(
            f"{owner}: controls must be a mapping of names to numbers, got "
            f"{validation.describe(controls)}"
        )
    missing = sorted(set(TIGHT_FIELD_CONTROLS) - set(controls))
    if missing:
        raise ValueError(f"{owner}: controls lack {missing}")
    for name, value in controls.items():
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not value > 0:
            raise ValueError(f"{owner}: controls[{name!r}] must be a number > 0, got {value}")
    for name, value, least in (("max_it", max_it, 1), ("min_iterations", min_iterations, 0)):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least:
            raise ValueError(f"{owner}: {name} must be an integer >= {least}, got {value}")
    return validation.check_petsc_options(petsc_options, owner)
