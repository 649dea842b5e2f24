"""Newton solver with CalculiX's contact convergence rules.

dolfinx 0.5.2's C++ Newton loop has no convergence hook: it compares the residual norm with ``atol``
right after calling the residual callback. :class:`ContactNewtonSolver` decides convergence in that
callback (:meth:`ContactNewtonSolver.is_converged` plus CalculiX's rules: at least two Newton
updates, none right after a re-pairing that changed the number of springs) and sets ``atol`` just
above or below the norm accordingly. The pieces it wires live in modules of their own: the choice
of linear solver (:mod:`~dolfinx_ntf.solvers.linear_solver`), the force-scaled test and the
divergence rule (:mod:`~dolfinx_ntf.solvers.convergence`), the line search
(:mod:`~dolfinx_ntf.solvers.line_search`) and the errors (:mod:`~dolfinx_ntf.solvers.errors`).
"""

from __future__ import annotations

import logging
import numbers
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.nls.petsc

from dolfinx_ntf import validation
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.logs import newton_logger, quiet_dolfinx
from dolfinx_ntf.solvers import linear_solver as linear
from dolfinx_ntf.solvers.convergence import TIGHT_FIELD_CONTROLS, DivergenceRule, ForceScaledTest
from dolfinx_ntf.solvers.errors import (
    ContactConvergenceError,
    ContactDivergenceError,
    ContactSolverError,
    no_support_hint,
    non_finite_input,
)
from dolfinx_ntf.solvers.line_search import LineSearch

__all__ = ["ITERATIONS_PER_EXTRA_PAIRING", "MAX_EXTRA_PAIRINGS", "ContactNewtonSolver"]

logger = logging.getLogger("dolfinx_ntf")

#: Pairings a solve may add to CalculiX's schedule for slave nodes that penetrate without a spring.
MAX_EXTRA_PAIRINGS = 3
#: Newton iterations each extra pairing adds to ``max_it`` (the set changes: Newton starts over).
ITERATIONS_PER_EXTRA_PAIRING = 10


class ContactNewtonSolver(dolfinx.nls.petsc.NewtonSolver):
    """dolfinx Newton solver driving a :class:`ContactProblem`.

    Args:
        comm: MPI communicator.
        problem: The contact problem.
        petsc_options: PETSc options of the linear solver, set under ``options_prefix``
            (default: chosen by ``linear_solver``).
        linear_solver: Without ``petsc_options``: ``"direct"`` (MUMPS LU, see
            :data:`DEFAULT_PETSC_OPTIONS`; MUMPS Cholesky, :data:`CHOLESKY_PETSC_OPTIONS`, when
            the problem is ``symmetric`` and its first Jacobian is symmetric), ``"iterative"``
            (GMRES, or CG when symmetric, with GAMG and the rigid-body modes of every body,
            :data:`ITERATIVE_PETSC_OPTIONS`), or ``"auto"``: direct up to
            :data:`DIRECT_MAX_DOFS` dofs (:data:`CHOLESKY_MAX_DOFS` when symmetric), iterative
            above (docs/method.md §14.7). Whatever the
            choice, a GAMG preconditioner gets the per-body near-nullspace.
        options_prefix: Prefix of the Krylov solver's options. ``petsc_options`` are set under
            it, read once, and removed from PETSc's global options database again; options
            already in the database under the prefix (command-line options such as
            ``-ntf_ksp_view`` or ``-ntf_pc_type gamg``) take precedence over them. Unknown
            solver names are a ``ValueError`` naming the option.
        controls: CalculiX's ``*CONTROLS, PARAMETERS=FIELD`` values of the force-scaled
            convergence test (:meth:`is_converged`): ``R_n``, ``C_n``, ``R_p``, ``R_l``,
            ``epsilon``, ``C_epsilon``; default :data:`TIGHT_FIELD_CONTROLS` (round-off level,
            never below it), :data:`CCX_FIELD_CONTROLS` are ccx's defaults.
        relaxation_iteration: CalculiX's I_P: after this many updates ``R_p`` replaces ``R_n``.
        max_it: Maximum Newton iterations per increment.
        min_iterations: Newton updates needed before convergence can be declared (ccx: 2).
        divergence_iteration: CalculiX's I_0: from this Newton update on, a residual larger than
            the two before it means divergence, and the increment is given up at once. Each
            re-pairing that changes the number of springs defers the check to 4 updates later,
            as in CalculiX.
        line_search: Backtrack along each Newton correction (steps 1, 1/2, ... down to
            ``2**-max_line_search_halvings``) until the residual of the current pairing decreases
            (Armijo), else take the best step tried. Beyond CalculiX, which always takes the
            full step; it breaks the cycles of Newton iterates around projections clamped to a
            face edge, and stops runaway iterates after a re-pairing.
        max_line_search_halvings: Smallest step of the line search is 2 to the minus this.
        check_unpaired: Before declaring convergence, search for slave nodes that penetrate
            without a spring (CalculiX freezes the pairing after iteration 8, so such nodes can
            remain): if any, pair again and iterate on, at most ``MAX_EXTRA_PAIRINGS`` times per
            increment, then give the increment up (beyond CalculiX; the deck runner reports
            their number instead).
        line_search_from: First Newton update that is line-searched. The first correction of an
            increment is taken in full: from an unloaded contact it overshoots the residual of
            the LINEAR law (slope K/2 at zero overclosure, K beyond) and is corrected in one
            more iteration, which damping would only delay.
        residual_floor: A largest residual force below this absolute value counts as zero in
            :meth:`is_converged` (then the ``R_l`` test holds). CalculiX 2.20 does this with
            1e-6 in the deck's force unit (docs/method.md §7.1), which the deck runner
            reproduces; 0 (the default) keeps the test scale-free.
        average_over_step: ``q~`` of :meth:`is_converged` is the mean over the increments of
            the step so far (each by its last ``q``, the current one by its ``q`` now),
            CalculiX's time-averaged force, which the deck runner reproduces; default: the mean
            over the iterations of the current increment.
        change_over_iterations: The displacement change ``du`` of :meth:`is_converged` is the
            largest over the iterations of the increment so far (CalculiX's; the deck runner
            reproduces it); default: the change now.
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
        line_search: bool = True,
        max_line_search_halvings: int = 4,
        line_search_from: int = 2,
        check_unpaired: bool = True,
        residual_floor: float = 0.0,
        average_over_step: bool = False,
        change_over_iterations: bool = False,
    ) -> None:
        symmetric = (
            petsc_options is None
            and getattr(problem, "symmetric", False)
            and not getattr(problem, "has_friction", False)  # friction: never Cholesky
        )
        controls = dict(TIGHT_FIELD_CONTROLS if controls is None else controls)
        options = _check_arguments(
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
        self.convergence_criterion = "residual"
        #: CalculiX's force-scaled test (:meth:`is_converged`) and the forces it remembers.
        self.test = ForceScaledTest(
            controls,
            relaxation_iteration,
            residual_floor,
            average_over_step,
            change_over_iterations,
        )
        #: Displacement at the start of the increment (before the predictor); set by the step
        #: driver, else the displacement when :meth:`solve` starts.
        self.increment_start: np.ndarray | None = None
        self.min_iterations = min_iterations
        self.divergence = DivergenceRule(divergence_iteration)
        self.first_solve = True
        self.line_search = line_search
        self.line_search_from = line_search_from
        self.check_unpaired = check_unpaired
        self.extra_pairings = 0
        self.step_lengths: list[float] = []
        self.backtracking = LineSearch(self._b, max_line_search_halvings)
        self.rtol = 0.0
        self.max_it = max_it
        self.error_on_nonconvergence = False
        self.report = False
        self.updates = 0
        self.residual_norms: list[float] = []
        #: Per Newton update of the current solve: (update, springs (all processes), largest
        #: residual force, mean average force, largest correction, largest displacement change in
        #: the increment).
        self.history: list[tuple[int, int, float, float, float, float]] = []
        self._check_symmetry = symmetric
        #: Rigid-body modes of every body, the near-nullspace of a GAMG preconditioner.
        self.near_nullspace = linear.configure(
            self.krylov_solver, options, options_prefix, problem.u.function_space
        )
        if self.near_nullspace is not None:
            self._A.setNearNullSpace(self.near_nullspace)

    @property
    def controls(self) -> dict[str, float]:
        """CalculiX's ``*CONTROLS, PARAMETERS=FIELD`` values of :meth:`is_converged`."""
        return self.test.controls

    @controls.setter
    def controls(self, value: dict[str, float]) -> None:
        self.test.controls = value

    @property
    def relaxation_iteration(self) -> int:
        """CalculiX's I_P: after this many updates ``R_p`` replaces ``R_n``."""
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
        """Destroy the PETSc vectors the solver owns (the residual, the line search's). Collective.

        The Jacobian belongs to the problem (:meth:`ContactProblem.destroy`).
        """
        self._b.destroy()
        self.backtracking.destroy()
        self._destroy_placeholder()
        if self.near_nullspace is not None:  # the matrix keeps its own reference
            self.near_nullspace.destroy()
            self.near_nullspace = None

    def __del__(self) -> None:
        # dolfinx 0.9's NewtonSolver.__del__ destroys its matrix, which here is the problem's.
        b = getattr(self, "_b", None)
        if b is not None:
            b.destroy()
        placeholder = getattr(self, "_placeholder", None)
        if placeholder is not None:
            placeholder.destroy()

    def __enter__(self) -> ContactNewtonSolver:
        return self

    def __exit__(self, *args: object) -> None:
        self.destroy()

    def _jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """The problem's Jacobian; a factorization is started afresh when the pattern grew.

        PETSc 3.22 does not see the pattern change of ``MatAXPY(..., DIFFERENT_NONZERO_PATTERN)``
        and would reuse the old symbolic factorization (MUMPS then reports a zero pivot).
        """
        merges = self.problem.assembler.pattern_merges
        self.problem.J(x, A)
        ksp = self.krylov_solver
        if self.problem.has_friction:
            linear.unsymmetric(ksp, "friction makes the Jacobian unsymmetric")
        if self._check_symmetry:  # Cholesky and CG need a symmetric bulk Jacobian too
            self._check_symmetry = False
            if not A.isSymmetric(1e-10 * A.norm(PETSc.NormType.NORM_INFINITY)):
                linear.unsymmetric(ksp, "the Jacobian is not symmetric")
        if self.problem.assembler.pattern_merges != merges:
            ksp.getPC().reset()
            if self.near_nullspace is not None:
                A.setNearNullSpace(self.near_nullspace)
            ksp.setOperators(A, A)
        reduced = self.problem.reduced_matrix  # constraints: solve the reduced system
        if reduced is not None:
            if reduced.handle != ksp.getOperators()[0].handle:
                ksp.getPC().reset()
            ksp.setOperators(reduced, reduced)

    def _update(self, solver, dx: PETSc.Vec, x: PETSc.Vec) -> None:
        """Dolfinx's update ``x -= relaxation dx``, counted; a failed linear solve stops here."""
        reason = self.krylov_solver.getConvergedReason()
        if reason < 0 or not np.isfinite(dx.norm()):
            self._linear_solve_failed(f"the linear solver failed ({linear.ksp_reason(reason)})")
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

        With ``r`` the largest residual force, ``c`` the largest correction, ``du`` the largest
        displacement change in the increment, ``q`` the average absolute element nodal force
        (:meth:`ContactProblem.average_element_force`) and ``q~`` its mean over the updates so
        far: converged when ``r <= c1 q~`` and at least one of ``c <= c2 du``,
        ``r c / min(r_{i-1}, r_{i-2}) < c2 du``, ``r <= R_l q~``, ``q <= epsilon q~``,
        ``c < 1e-8``; ``(c1, c2)`` is ``(R_n, C_n)`` up to ``relaxation_iteration`` updates,
        ``(R_p, C_n)`` beyond, and ``(epsilon, C_epsilon)`` under zero flux. Scaled by forces,
        the test never asks for less than round-off. The caller adds CalculiX's other rules (at
        least ``min_iterations`` updates, none right after a re-pairing that changed the number
        of springs). Override for other criteria.
        """
        if self.updates == 0:
            return False
        comm = self.problem.u.function_space.mesh.comm
        average = self.problem.average_element_force()
        largest = b.norm(PETSc.NormType.NORM_INFINITY)
        correction = self.relaxation_parameter * self.last_correction.norm(
            PETSc.NormType.NORM_INFINITY
        )
        correction *= self.step_lengths[-1]
        start = self.increment_start if self.increment_start is not None else self._solve_start
        change = float(np.abs(x.array - start[: x.array.size]).max(initial=0.0))
        change = comm.allreduce(change, op=MPI.MAX)
        converged = self.test.converged(self.updates, average, largest, correction, change)
        springs = comm.allreduce(self.problem.num_springs)
        self.history.append((self.updates, springs, *self.test.last))
        return converged

    def _linear_solve_failed(self, what: str) -> None:
        """Non-retryable at the very first Newton iteration of a solver, divergence later."""
        if self.first_solve and self.updates == 0:
            options = self.krylov_solver.getOptionsPrefix()
            hint = (
                f"check the PETSc options under the prefix '{options}' (petsc_options) and that "
                "the residual form is built on the unknown Function u"
            )
            raise ContactSolverError(
                f"{what} at the first Newton iteration: {hint}{no_support_hint(self.problem)}"
            )
        raise ContactDivergenceError(
            f"{what} at Newton iteration {self.updates + 1}{no_support_hint(self.problem)}"
        )

    def _residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        if self.backtracking.trial_is_current:  # the accepted trial: same springs, same x
            self.backtracking.trial_residual.copy(b)
            self.backtracking.trial_is_current = False
        else:
            self.problem.F(x, b)
        norm = b.norm()
        if not np.isfinite(norm):
            if self.updates == 0:
                raise ContactSolverError(non_finite_input(self.problem, x))
            raise ContactDivergenceError(
                f"residual is not finite (norm {norm}) after {self.updates} Newton updates"
            )
        if self.problem.count_changed:
            self.divergence.defer(self.updates, 4)
        self.divergence.check(
            self.updates, self.residual_norms, norm, lambda: no_support_hint(self.problem)
        )
        self.residual_norms.append(norm)
        converged = self.is_converged(x, b, norm)  # always called: criteria may keep a history
        converged = (
            converged and self.updates >= self.min_iterations and not self.problem.count_changed
        )
        if converged and self.check_unpaired:
            converged = self._all_contacts_paired()
        self.atol = 2.0 * norm + 1e-300 if converged else (1.0 - 1e-9) * norm
        if newton_logger.isEnabledFor(logging.INFO):
            correction = (
                self.relaxation_parameter * self.last_correction.norm() if self.updates else 0.0
            )
            newton_logger.info(
                _iteration_line(
                    self.updates,
                    norm,
                    self.residual_norms[0],
                    correction,
                    self.problem.total_springs,
                    converged,
                )
            )

    def _all_contacts_paired(self) -> bool:
        """False (and a re-pairing next iteration) when slave nodes penetrate without a spring."""
        unpaired = self.problem.unpaired_contacts()
        if unpaired == 0:
            return True
        if self.extra_pairings >= MAX_EXTRA_PAIRINGS:
            raise ContactConvergenceError(
                f"{unpaired} slave node(s) still penetrate the master without a spring after "
                f"{MAX_EXTRA_PAIRINGS} extra pairings"
            )
        self.extra_pairings += 1
        self.problem.repair_next_iteration = True
        self.divergence.defer(self.updates, 5)  # as after a count change
        self.max_it += ITERATIONS_PER_EXTRA_PAIRING
        logger.info(" %d slave node(s) penetrate without a spring: pairing again", unpaired)
        return False

    def _bind_matrix(self) -> None:
        """Solve with the problem's current matrix (a new one after a rebuild)."""
        A = self.problem.ensure_matrix()
        if A is not self._A:
            self._destroy_placeholder()
            self._A = A
            self.setJ(self._jacobian, A)
            if getattr(self, "near_nullspace", None) is not None:
                A.setNearNullSpace(self.near_nullspace)

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
        self.extra_pairings = 0
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
            with quiet_dolfinx(), linear.galerkin_products(self.krylov_solver):
                iterations, converged = super().solve(u)
        except (ContactConvergenceError, ContactSolverError):
            raise
        except PETSc.Error as error:
            self._linear_solve_failed(
                f"the Newton iteration failed ({validation.describe_petsc_error(error)})"
            )
        except (RuntimeError, ValueError) as error:  # degenerate iterates
            self._linear_solve_failed(f"the Newton iteration failed ({error})")
        finally:
            self.first_solve = False
            self.max_it = max_it
        if not converged:
            raise ContactConvergenceError(
                f"Newton did not converge in {iterations} iterations "
                f"(residual {self.residual_norms[-1]:.3e}, "
                f"first {self.residual_norms[0]:.3e}){no_support_hint(self.problem)}"
            )
        self.test.end_solve()
        return iterations, True


def _iteration_line(
    updates: int, norm: float, first: float, correction: float, springs: int, converged: bool
) -> str:
    """One progress line: residual and correction norms, spring count."""
    line = f" iteration {updates}: residual {norm:.3e}"
    if updates:
        ratio = norm / first if first > 0 else 0.0
        line += f" ({ratio:.1e} of the first), correction {correction:.3e}"
    line += f", {springs} contact elements"
    return line + (", converged" if converged else "")


def _check_arguments(
    comm: object,
    problem: object,
    petsc_options: object,
    options_prefix: object,
    *,
    controls: object,
    max_it: object,
    min_iterations: object,
) -> dict[str, typing.Any]:
    """The arguments of :class:`ContactNewtonSolver`; returns the PETSc options."""
    owner = "ContactNewtonSolver"
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
