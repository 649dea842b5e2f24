"""Newton solver with CalculiX's contact convergence rules, and a static step driver with cutbacks.

dolfinx 0.5.2's C++ Newton loop has no convergence hook: it compares the residual norm with ``atol``
right after calling the residual callback. :class:`ContactNewtonSolver` decides convergence in that
callback (:meth:`ContactNewtonSolver.is_converged` plus CalculiX's rules: at least two Newton
updates, none right after a re-pairing that changed the number of springs) and sets ``atol`` just
above or below the norm accordingly.
"""

from __future__ import annotations

import contextlib
import logging
import time
import typing
from dataclasses import dataclass

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.nls.petsc

from dolfinx_ntf import validation
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.logs import log_progress, newton_logger, quiet_dolfinx
from dolfinx_ntf.solvers import nullspace

__all__ = [
    "CCX_FIELD_CONTROLS",
    "CHOLESKY_MAX_DOFS",
    "DIVERGENCE_GROWTH",
    "TIGHT_FIELD_CONTROLS",
    "ContactConvergenceError",
    "ContactDivergenceError",
    "ContactNewtonSolver",
    "ContactSolverError",
    "IncrementResult",
    "LoadControl",
    "StaticStep",
    "log_progress",
]

logger = logging.getLogger("dolfinx_ntf")

#: CalculiX's defaults of ``*CONTROLS, PARAMETERS=FIELD`` (mechanical field).
CCX_FIELD_CONTROLS: dict[str, float] = {
    "R_n": 0.005,
    "C_n": 0.01,
    "R_p": 0.02,
    "R_l": 1e-8,
    "epsilon": 1e-5,
    "C_epsilon": 1e-3,
}
#: Field controls that converge to round-off level: the default of :class:`ContactNewtonSolver`
#: and of ``dolfinx-ntf run --tight``.
TIGHT_FIELD_CONTROLS: dict[str, float] = {
    "R_n": 1e-10,
    "C_n": 1e-8,
    "R_p": 1e-10,
    "R_l": 1e-12,
    "epsilon": 1e-5,
    "C_epsilon": 1e-8,
}

#: Pairings a solve may add to CalculiX's schedule for slave nodes that penetrate without a spring.
MAX_EXTRA_PAIRINGS = 3
#: Newton iterations each extra pairing adds to ``max_it`` (the set changes: Newton starts over).
ITERATIONS_PER_EXTRA_PAIRING = 10

#: Default linear solver of symmetric Jacobians (``ContactProblem(symmetric=True)`` with a
#: symmetric bulk form): sparse direct Cholesky (LDL^T) by MUMPS, about half the work of LU.
CHOLESKY_PETSC_OPTIONS = {
    "ksp_type": "preonly",
    "pc_type": "cholesky",
    "pc_factor_mat_solver_type": "mumps",
}

#: Default linear solver: sparse direct LU by MUMPS.
DEFAULT_PETSC_OPTIONS = {
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}

#: Iterative linear solver of large problems (docs/method.md §14.7): GMRES (CG when the Jacobian is
#: symmetric) preconditioned by smoothed-aggregation AMG with the rigid-body modes of every body
#: as near-nullspace; the true residual is reduced by ``ksp_rtol`` (tight enough to leave Newton's
#: iteration counts unchanged).
ITERATIVE_PETSC_OPTIONS = {
    "ksp_type": "gmres",
    "ksp_pc_side": "right",
    "ksp_gmres_restart": 100,
    "ksp_rtol": 1e-10,
    "ksp_max_it": 1000,
    "pc_type": "gamg",
    "mg_levels_ksp_type": "chebyshev",
    "mg_levels_pc_type": "jacobi",
}

#: PETSc's algorithm for GAMG's Galerkin products ``P^T A P`` on one process (``-matptap_via``):
#: "rap" (``A P`` first) took 3.9 s where the default took 8.8 s on the plates of
#: ``benchmarks/scaling.py`` at 70k dofs, the same on PETSc 3.18 and 3.22 (docs/method.md §14.7).
#: Distributed matrices have no such algorithm and keep PETSc's default.
SEQUENTIAL_PTAP = "rap"


@contextlib.contextmanager
def galerkin_products(ksp: PETSc.KSP) -> typing.Iterator[None]:
    """Use :data:`SEQUENTIAL_PTAP` for GAMG's Galerkin products inside the context.

    Only if ``ksp`` is GAMG on one process and the user has not chosen ``-matptap_via``; PETSc
    reads the option, without prefix, at each set-up of the hierarchy.
    """
    options = PETSc.Options()
    use = (
        ksp.getComm().getSize() == 1
        and ksp.getPC().getType() == "gamg"
        and not options.hasName("matptap_via")
    )
    if use:
        options["matptap_via"] = SEQUENTIAL_PTAP
    try:
        yield
    finally:
        if use:
            options.delValue("matptap_via")


#: ``linear_solver="auto"`` chooses the direct solver up to this many dofs, the iterative one above
#: (about twice the measured crossover on 2 cores, docs/performance.md "Linear solvers").
DIRECT_MAX_DOFS = 20_000

#: ... and up to this many dofs when the Jacobian is symmetric: MUMPS Cholesky does about half
#: the work of LU and beats CG + GAMG at 81k dofs (docs/method.md §7.4).
CHOLESKY_MAX_DOFS = 100_000

#: Values of ``ContactNewtonSolver(linear_solver=...)``.
LINEAR_SOLVERS = ("auto", "direct", "iterative")


#: A residual counts as larger than an earlier one when it exceeds it by this factor: CalculiX's
#: strict comparison, with a margin for iterations that stagnate at round-off level.
DIVERGENCE_GROWTH = 1.01


class ContactConvergenceError(RuntimeError):
    """A Newton solve or a whole step failed to converge; a smaller increment may succeed."""


class ContactDivergenceError(ContactConvergenceError):
    """The Newton iterates diverge (growing or non-finite residual, failed linear solve)."""


class ContactSolverError(RuntimeError):
    """A failure that no smaller increment can fix; :class:`StaticStep` raises it at once.

    Non-finite input, or a linear solver that cannot factor the first Jacobian.
    """


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
        comm,
        problem: ContactProblem,
        *,
        petsc_options: dict | None = None,
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
        options = validation.check_solver(
            comm,
            problem,
            ContactProblem,
            _default_options(problem, linear_solver, symmetric)
            if petsc_options is None
            else petsc_options,
            options_prefix,
            controls=controls,
            required_controls=TIGHT_FIELD_CONTROLS,
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
        self.controls = controls
        self.relaxation_iteration = relaxation_iteration
        #: Displacement at the start of the increment (before the predictor); set by the step
        #: driver, else the displacement when :meth:`solve` starts.
        self.increment_start: np.ndarray | None = None
        self._averages: list[float] = []
        self._largest: list[float] = []
        #: Largest residual force of the last iterate (before ``residual_floor``), all processes.
        self.largest_residual = 0.0
        #: Mean element force of every converged increment so far (the scale of an unloaded one).
        self.past_averages: list[float] = []
        self.min_iterations = min_iterations
        self.divergence_iteration = divergence_iteration
        self._first_check = divergence_iteration
        self.first_solve = True
        self.line_search = line_search
        self.max_line_search_halvings = max_line_search_halvings
        self.line_search_from = line_search_from
        self.check_unpaired = check_unpaired
        self.residual_floor = residual_floor
        self.average_over_step = average_over_step
        self.change_over_iterations = change_over_iterations
        self._largest_change = 0.0
        #: Last average force ``q`` of each converged increment of the current step.
        self.step_forces: list[float] = []
        self.extra_pairings = 0
        self.step_lengths: list[float] = []
        self._trial_residual = self._b.duplicate()
        #: The line search's last trial is the new iterate: its springs and residual are reused.
        self._trial_is_current = False
        self._line_search_start = self._b.duplicate()
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
        ksp = self.krylov_solver
        ksp.setOptionsPrefix(options_prefix)
        self._check_symmetry = symmetric
        opts = PETSc.Options()
        options = {k: v for k, v in options.items() if not opts.hasName(f"{options_prefix}{k}")}
        for key, value in options.items():
            opts[f"{options_prefix}{key}"] = value
        try:
            ksp.setFromOptions()
        finally:
            for key in options:
                opts.delValue(f"{options_prefix}{key}")
        #: Rigid-body modes of every body, the near-nullspace of a GAMG preconditioner.
        self.near_nullspace: PETSc.NullSpace | None = None
        if ksp.getPC().getType() == "gamg":
            self.near_nullspace = nullspace.near_nullspace(problem.u.function_space)
            self._A.setNearNullSpace(self.near_nullspace)

    def destroy(self) -> None:
        """Destroy the PETSc vector the solver owns (the residual). Collective.

        The Jacobian belongs to the problem (:meth:`ContactProblem.destroy`).
        """
        self._b.destroy()
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
            _unsymmetric(ksp, "friction makes the Jacobian unsymmetric")
        if self._check_symmetry:  # Cholesky and CG need a symmetric bulk Jacobian too
            self._check_symmetry = False
            if not A.isSymmetric(1e-10 * A.norm(PETSc.NormType.NORM_INFINITY)):
                _unsymmetric(ksp, "the Jacobian is not symmetric")
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
            self._linear_solve_failed(f"the linear solver failed ({_ksp_reason(reason)})")
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
        best_step, best_norm = 1.0, np.inf
        step = 1.0
        x.copy(self._line_search_start)
        # _update repeats the same axpy, so the last trial is the new iterate bit for bit (not
        # with constraints: form() back-substitutes the eliminated values into x)
        reusable = self.problem.elimination is None
        for _ in range(self.max_line_search_halvings + 1):
            x.axpy(-step * self.relaxation_parameter, dx)
            self.problem.form(x)
            self.problem.assemble_residual(x, self._trial_residual)
            norm = self._trial_residual.norm()
            self._line_search_start.copy(x)
            if norm < best_norm:
                best_step, best_norm = step, norm
            if norm <= (1.0 - 1e-4 * step) * start:
                self._trial_is_current = reusable
                return step
            last, step = step, 0.5 * step
        self._trial_is_current = reusable and best_step == last
        return best_step

    def _form(self, x: PETSc.Vec) -> None:
        """Springs at the new iterate, unless the line search has just evaluated them there."""
        if not self._trial_is_current:
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
        controls = self.controls
        average = self.problem.average_element_force()
        self._averages.append(average)
        mean = float(np.mean(self._averages))
        if self.average_over_step:
            mean = (sum(self.step_forces) + average) / (len(self.step_forces) + 1)
        largest = b.norm(PETSc.NormType.NORM_INFINITY)
        self.largest_residual = largest
        if largest < self.residual_floor:
            largest = 0.0
        self._largest.append(largest)
        correction = self.relaxation_parameter * self.last_correction.norm(
            PETSc.NormType.NORM_INFINITY
        )
        correction *= self.step_lengths[-1]
        start = self.increment_start if self.increment_start is not None else self._solve_start
        change = float(np.abs(x.array - start[: x.array.size]).max(initial=0.0))
        change = self.problem.u.function_space.mesh.comm.allreduce(change, op=MPI.MAX)
        if self.change_over_iterations:
            self._largest_change = change = max(self._largest_change, change)
        past = float(np.mean(self.past_averages)) if self.past_averages else 0.0
        if mean <= controls["epsilon"] * past:
            # Unloaded (all forces vanish, e.g. a contact pair removed): CalculiX's zero-flux test
            # against the forces of the earlier increments (docs/method.md §11.6).
            mean = past
        if average <= controls["epsilon"] * mean:
            c1, c2 = controls["epsilon"], controls["C_epsilon"]
        else:
            c1 = controls["R_n"] if self.updates <= self.relaxation_iteration else controls["R_p"]
            c2 = controls["C_n"]
        springs = self.problem.u.function_space.mesh.comm.allreduce(self.problem.num_springs)
        self.history.append((self.updates, springs, largest, mean, correction, change))
        estimate = np.inf
        if self.updates >= 3 and min(self._largest[-3:-1]) > 0:
            estimate = largest * correction / min(self._largest[-3:-1])
        return largest <= c1 * mean and (
            correction <= c2 * change
            or estimate < c2 * change
            or largest <= controls["R_l"] * mean
            or average <= controls["epsilon"] * mean
            or correction < 1e-8
        )

    def _linear_solve_failed(self, what: str) -> None:
        """Non-retryable at the very first Newton iteration of a solver, divergence later."""
        if self.first_solve and self.updates == 0:
            options = self.krylov_solver.getOptionsPrefix()
            hint = (
                f"check the PETSc options under the prefix '{options}' (petsc_options) and that "
                "the residual form is built on the unknown Function u"
            )
            raise ContactSolverError(
                f"{what} at the first Newton iteration: {hint}{_no_support_hint(self.problem)}"
            )
        raise ContactDivergenceError(
            f"{what} at Newton iteration {self.updates + 1}{_no_support_hint(self.problem)}"
        )

    def _residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        if self._trial_is_current:  # the line search's accepted trial: same springs, same x
            self._trial_residual.copy(b)
            self._trial_is_current = False
        else:
            self.problem.F(x, b)
        norm = b.norm()
        if not np.isfinite(norm):
            if self.updates == 0:
                raise ContactSolverError(_non_finite_input(self.problem, x))
            raise ContactDivergenceError(
                f"residual is not finite (norm {norm}) after {self.updates} Newton updates"
            )
        if self.problem.count_changed:
            self._first_check = max(self._first_check, self.updates + 4)
        norms = self.residual_norms
        if (
            self.updates >= self._first_check
            and len(norms) >= 2
            and norm > DIVERGENCE_GROWTH * max(norms[-1], norms[-2])
        ):
            raise ContactDivergenceError(
                f"residual grows: {norms[-2]:.3e}, {norms[-1]:.3e}, {norm:.3e} after "
                f"{self.updates} Newton updates{_no_support_hint(self.problem)}"
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
            self._log_iteration(norm, converged)

    def _log_iteration(self, norm: float, converged: bool) -> None:
        """One progress line: residual and correction norms, spring count."""
        line = f" iteration {self.updates}: residual {norm:.3e}"
        if self.updates:
            first = self.residual_norms[0]
            ratio = norm / first if first > 0 else 0.0
            correction = self.relaxation_parameter * self.last_correction.norm()
            line += f" ({ratio:.1e} of the first), correction {correction:.3e}"
        line += f", {self.problem.total_springs} contact elements"
        newton_logger.info(line + (", converged" if converged else ""))

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
        self._first_check = max(self._first_check, self.updates + 5)  # as after a count change
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
        self._averages, self._largest = [], []
        self.extra_pairings = 0
        max_it = self.max_it
        self._solve_start = u.x.array.copy()
        self.updates = 0
        self._trial_is_current = False
        self._largest_change = 0.0  # with a predictor, its own change counts too (as in ccx)
        if self.change_over_iterations and self.increment_start is not None:
            moved = np.abs(u.x.array - self.increment_start[: u.x.array.size]).max(initial=0.0)
            self._largest_change = u.function_space.mesh.comm.allreduce(moved, op=MPI.MAX)
        self._first_check = self.divergence_iteration
        self._bind_matrix()
        try:
            # non-convergence is reported below, with the residuals
            with quiet_dolfinx(), galerkin_products(self.krylov_solver):
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
                f"first {self.residual_norms[0]:.3e}){_no_support_hint(self.problem)}"
            )
        if self._averages:
            self.past_averages.append(float(np.mean(self._averages)))
            self.step_forces.append(self._averages[-1])
        return iterations, True


LoadControl = typing.Callable[[float], None]


@dataclass
class IncrementResult:
    """Summary of a converged increment."""

    increment: int
    attempt: int
    time: float
    time_fraction: float
    iterations: int
    springs: int
    residual: float


@dataclass
class StaticStep:
    """A static step of ``period`` with automatic incrementation (CalculiX ``*STATIC``).

    The step holds configuration only: :meth:`run` returns the results of that run, and the same
    step can run again (e.g. another load case on a fresh problem).

    Args:
        set_load: Called with the step time at the end of each increment (before the pairing);
            scales loads and prescribed displacements, e.g. ``lambda t: traction.value = t * p``.
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
        guard_predictor: With ``predictor`` and without ``pair_after_predictor``: start from
            ``u_n`` instead when the predicted displacement brings slave nodes into contact that
            the increment-start pairing gave no spring (the growing contact zones on which the
            predictor makes the iterates run away); the deck runner's default (docs/method.md
            §7.2).
    """

    set_load: LoadControl
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

    def __post_init__(self) -> None:
        """Check the configuration (``TypeError``/``ValueError`` naming the field)."""
        validation.check_step(self)

    def run(self, solver: ContactNewtonSolver, u: dolfinx.fem.Function) -> list[IncrementResult]:
        """Run the step from the current ``u``.

        Args:
            solver: The solver of the problem.
            u: The problem's displacement (the Function the problem was built on).

        Returns:
            The result of every converged increment of this run.

        Raises:
            ContactConvergenceError: When an increment fails and cutbacks are exhausted.
        """
        validation.check_step(self)
        validation.check_type(solver, ContactNewtonSolver, "StaticStep.run: solver")
        if u is not solver.problem.u:
            raise ValueError(
                "StaticStep.run: u must be the Function the ContactProblem was built on "
                f"(got {validation.describe(u)})"
            )
        problem = solver.problem
        max_inc = self.period if self.max_increment is None else self.max_increment
        if not (0 < self.min_increment <= self.initial_increment <= max_inc):
            raise ValueError(
                f"StaticStep: need 0 < min_increment ({self.min_increment}) <= initial_increment "
                f"({self.initial_increment}) <= max_increment ({max_inc})"
            )
        factors = (self.cutback_factor, self.divergence_cutback_factor)
        if not (all(0 < f < 1 for f in factors) and self.growth_factor >= 1):
            raise ValueError(
                f"StaticStep: need 0 < cutback_factor ({self.cutback_factor}), "
                f"divergence_cutback_factor ({self.divergence_cutback_factor}) < 1 <= "
                f"growth_factor ({self.growth_factor})"
            )
        problem.begin_step()
        velocity: np.ndarray | None = None

        def start(t_new: float, dt: float, u_start: np.ndarray) -> None:
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

        return run_increments(self, solver, u, self.min_increment, start, converged)


def run_increments(
    step: typing.Any,
    solver: ContactNewtonSolver,
    u: dolfinx.fem.Function,
    min_increment: float,
    start: typing.Callable[[float, float, np.ndarray], None],
    converged: typing.Callable[[float, np.ndarray], None],
) -> list[IncrementResult]:
    """CalculiX's increment control over ``step.period``, shared by the static and dynamic steps.

    Each attempt sets the loads at the new time (``step.set_load``), calls ``start(t_new, dt,
    u_start)`` (the step's own start of an increment) and solves; a failed attempt restores
    ``u`` and is cut back (docs/method.md §7.2); a converged one commits the problem's increment
    state, calls ``converged(dt, u_start)`` and may let the next increment grow.

    Args:
        step: The step's configuration (period, increments, cutback and growth factors, fixed,
            set_load, on_increment) as in :class:`StaticStep`.
        solver: The solver of the problem.
        u: The problem's displacement.
        min_increment: The smallest increment a cutback may reach.
        start: Begins an attempt after its loads are set.
        converged: Updates the step's own state after a converged increment.
    """
    problem = solver.problem
    solver.step_forces = []
    max_inc = step.period if step.max_increment is None else step.max_increment
    results: list[IncrementResult] = []
    t, dt = 0.0, step.initial_increment
    increment, fast_in_a_row = 0, 0
    while t < step.period * (1 - 1e-12):
        increment += 1
        attempt = 0
        u_start = u.x.array.copy()
        solver.increment_start = u_start
        first_failure: ContactConvergenceError | None = None
        while True:
            attempt += 1
            dt = min(dt, step.period - t)
            t_new = t + dt
            logger.info(
                " increment %d attempt %d\n increment size= %.6e\n actual step time= %.6e",
                increment,
                attempt,
                dt,
                t_new,
            )
            step.set_load(t_new)
            clock = time.perf_counter()
            try:
                start(t_new, dt, u_start)
                iterations, _ = solver.solve(u)
                problem.end_increment()  # commits the friction state
                break
            except ContactConvergenceError as error:
                u.x.array[:] = u_start
                u.x.scatter_forward()
                first_failure = first_failure or error
                factor = (
                    step.divergence_cutback_factor
                    if isinstance(error, ContactDivergenceError)
                    else step.cutback_factor
                )
                if step.fixed or dt * factor < min_increment:
                    why = (
                        "fixed increments"
                        if step.fixed
                        else (
                            f"increment size {dt:.3e} cannot be cut back below the minimum "
                            f"{min_increment:.3e}"
                        )
                    )
                    first = "" if first_failure is error else f"; first attempt: {first_failure}"
                    raise ContactConvergenceError(
                        f"increment {increment} (step time {t:.6g} -> {t_new:.6g}) "
                        f"failed after {attempt} attempt(s) ({why}): {error}{first}"
                    ) from error
                dt *= factor
                fast_in_a_row = 0
                logger.info(" %s; cutting back to %.6e", error, dt)
        converged(dt, u_start)
        t = t_new
        result = IncrementResult(
            increment,
            attempt,
            t,
            t / step.period,
            iterations,
            problem.total_springs,
            solver.residual_norms[-1],
        )
        results.append(result)
        logger.info(
            " increment %d converged: time %.6g, %d iterations, %d contact elements, "
            "residual %.3e (%.2f s)",
            increment,
            t,
            iterations,
            result.springs,
            result.residual,
            time.perf_counter() - clock,
        )
        if step.on_increment is not None:
            step.on_increment(result)
        fast_in_a_row = fast_in_a_row + 1 if iterations <= step.growth_iterations else 0
        if not step.fixed and fast_in_a_row >= 2:
            dt = min(step.growth_factor * dt, max_inc)
    return results


def _default_options(problem: object, linear_solver: object, symmetric: bool) -> dict:
    """PETSc options of ``linear_solver`` for this problem (docs/method.md §14.7)."""
    if not isinstance(linear_solver, str) or linear_solver not in LINEAR_SOLVERS:
        raise ValueError(
            f"ContactNewtonSolver: linear_solver must be one of {LINEAR_SOLVERS}, "
            f"got {linear_solver!r}"
        )
    if linear_solver == "auto" and isinstance(problem, ContactProblem):
        index_map = problem.u.function_space.dofmap.index_map
        dofs = index_map.size_global * problem.u.function_space.dofmap.index_map_bs
        # linear constraints: the reduced matrix has no rigid modes for GAMG (§14.7)
        limit = CHOLESKY_MAX_DOFS if symmetric else DIRECT_MAX_DOFS
        small = dofs <= limit or bool(getattr(problem, "constraints", None))
        linear_solver = "direct" if small else "iterative"
        logger.info(" %d dofs: %s linear solver", dofs, linear_solver)
    if linear_solver == "iterative":
        if not symmetric:
            return dict(ITERATIVE_PETSC_OPTIONS)
        options = {**ITERATIVE_PETSC_OPTIONS, "ksp_type": "cg", "ksp_norm_type": "unpreconditioned"}
        del options["ksp_pc_side"], options["ksp_gmres_restart"]
        return options
    return dict(CHOLESKY_PETSC_OPTIONS if symmetric else DEFAULT_PETSC_OPTIONS)


def _unsymmetric(ksp: PETSc.KSP, why: str) -> None:
    """Swap the symmetric solvers of ``ksp``: Cholesky for LU, CG for right-preconditioned GMRES."""
    if ksp.getPC().getType() == "cholesky":
        logger.info(" %s: LU instead of Cholesky", why)
        ksp.getPC().setType("lu")
    if ksp.getType() == "cg":
        logger.info(" %s: GMRES instead of CG", why)
        ksp.setType("gmres")
        ksp.setPCSide(PETSc.PC.Side.RIGHT)


def _ksp_reason(reason: int) -> str:
    """Name of a PETSc KSP converged/diverged reason."""
    names = {
        value: name
        for name, value in vars(PETSc.KSP.ConvergedReason).items()
        if isinstance(value, int) and not name.startswith("_")
    }
    name = names.get(reason, "unknown")
    if reason == -11:  # DIVERGED_PC_FAILED (PETSc >= 3.11; petsc4py 3.18 has no name for it)
        name += ", e.g. a zero pivot: singular Jacobian"
    return f"KSP reason {reason}: {name}"


def _non_finite_input(problem: ContactProblem, x: PETSc.Vec) -> str:
    """Message for a residual that is not finite before any Newton update."""
    values = problem.u.x.array
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        node = bad[0] // 3
        position = problem.reference_coordinates[node]
        return (
            f"the displacement has {bad.size} non-finite value(s) at the start of the increment "
            f"(first at node {node}, reference position ({position[0]:.6g}, {position[1]:.6g}, "
            f"{position[2]:.6g})): check the initial values and prescribed displacements"
        )
    return (
        "the residual is not finite at the start of the increment although the displacement is: "
        "check the loads, constants and material parameters of the residual form"
    )


def _no_support_hint(problem: ContactProblem) -> str:
    """Why a body may float: contact pairs but no springs."""
    if problem.total_springs == 0 and problem.states:
        return (
            "; there are no contact springs, so a body held only by contact has no support "
            "(close the initial gap, or start with a prescribed displacement)"
        )
    return ""
