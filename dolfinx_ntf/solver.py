"""Newton solver with CalculiX's contact convergence rules, and a static step driver with cutbacks.

dolfinx 0.5.2's C++ Newton loop has no convergence hook: it compares the residual norm with ``atol``
right after calling the residual callback. :class:`ContactNewtonSolver` decides convergence in that
callback (:meth:`ContactNewtonSolver.is_converged` plus CalculiX's rules: at least two Newton
updates, none right after a re-pairing that changed the number of springs) and sets ``atol`` just
above or below the norm accordingly.
"""

from __future__ import annotations

import logging
import time
import typing
from dataclasses import dataclass

from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.nls.petsc

from dolfinx_ntf import validation
from dolfinx_ntf.logs import log_progress, newton_logger, quiet_dolfinx
from dolfinx_ntf.problem import ContactProblem

__all__ = [
    "ContactConvergenceError",
    "ContactNewtonSolver",
    "IncrementResult",
    "LoadControl",
    "StaticStep",
    "log_progress",
]

logger = logging.getLogger("dolfinx_ntf")

#: Default linear solver: sparse direct LU by MUMPS.
DEFAULT_PETSC_OPTIONS = {
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}


class ContactConvergenceError(RuntimeError):
    """A Newton solve or a whole step failed to converge."""


class ContactNewtonSolver(dolfinx.nls.petsc.NewtonSolver):
    """dolfinx Newton solver driving a :class:`ContactProblem`.

    Args:
        comm: MPI communicator.
        problem: The contact problem.
        petsc_options: PETSc options of the linear solver (default: MUMPS LU, see
            :data:`DEFAULT_PETSC_OPTIONS`). They are set under ``options_prefix``, read once, and
            removed from PETSc's global options database again; unknown solver names are a
            ``ValueError`` naming the option.
        options_prefix: Prefix of the Krylov solver's options (command-line options such as
            ``-ntf_ksp_view`` still apply).
        relative_tolerance: Converged when the residual norm falls below this fraction of the first
            residual norm of the increment (or below ``atol``).
        atol: Absolute residual tolerance.
        max_it: Maximum Newton iterations per increment.
    """

    def __init__(
        self,
        comm,
        problem: ContactProblem,
        *,
        petsc_options: dict | None = None,
        options_prefix: str = "ntf_",
        relative_tolerance: float = 1e-10,
        atol: float = 1e-12,
        max_it: int = 30,
        min_iterations: int = 2,
    ) -> None:
        options = validation.check_solver(
            comm,
            problem,
            ContactProblem,
            DEFAULT_PETSC_OPTIONS if petsc_options is None else petsc_options,
            options_prefix,
            relative_tolerance=relative_tolerance,
            atol=atol,
            max_it=max_it,
            min_iterations=min_iterations,
        )
        validation.check_linear_solver(comm, options, "ContactNewtonSolver")
        super().__init__(comm, problem)
        self.problem = problem
        self._A.destroy()
        self._A = problem.ensure_matrix()
        self.setJ(self._jacobian, self._A)
        self.setF(self._residual, self._b)
        self.set_update(self._update)
        self.convergence_criterion = "residual"
        self.relative_tolerance = relative_tolerance
        self.absolute_tolerance = atol
        self.min_iterations = min_iterations
        self.rtol = 0.0
        self.max_it = max_it
        self.error_on_nonconvergence = False
        self.report = False
        self.updates = 0
        self.residual_norms: list[float] = []
        ksp = self.krylov_solver
        ksp.setOptionsPrefix(options_prefix)
        opts = PETSc.Options()
        for key, value in options.items():
            opts[f"{options_prefix}{key}"] = value
        try:
            ksp.setFromOptions()
        finally:
            for key in options:
                opts.delValue(f"{options_prefix}{key}")

    def destroy(self) -> None:
        """Destroy the PETSc vector the solver owns (the residual). Collective.

        The Jacobian belongs to the problem (:meth:`ContactProblem.destroy`).
        """
        self._b.destroy()

    def __del__(self) -> None:
        # dolfinx 0.9's NewtonSolver.__del__ destroys its matrix, which here is the problem's.
        b = getattr(self, "_b", None)
        if b is not None:
            b.destroy()

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
        if self.problem.assembler.pattern_merges != merges:
            ksp = self.krylov_solver
            ksp.getPC().reset()
            ksp.setOperators(A, A)

    def _update(self, solver, dx: PETSc.Vec, x: PETSc.Vec) -> None:
        """dolfinx's update ``x -= relaxation dx``, counted."""
        self.updates += 1
        self.last_correction = dx
        x.axpy(-self.relaxation_parameter, dx)

    def is_converged(self, x: PETSc.Vec, b: PETSc.Vec, norm: float) -> bool:
        """Residual test: norm below ``atol`` or ``relative_tolerance`` times the first norm.

        Override for other criteria (the CalculiX job runner uses ccx's force-based test).
        """
        return norm <= max(
            self.absolute_tolerance, self.relative_tolerance * self.residual_norms[0]
        )

    def _residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        self.problem.F(x, b)
        norm = b.norm()
        if not np.isfinite(norm):
            raise ContactConvergenceError(
                f"residual is not finite (norm {norm}) at iteration {self.problem.iteration}"
            )
        self.residual_norms.append(norm)
        converged = self.is_converged(x, b, norm)  # always called: criteria may keep a history
        converged = (
            converged and self.updates >= self.min_iterations and not self.problem.count_changed
        )
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
        line += f", {self.problem.num_springs} contact elements"
        newton_logger.info(line + (", converged" if converged else ""))

    def _bind_matrix(self) -> None:
        A = self.problem.ensure_matrix()
        if A is not self._A:
            self._A = A
            self.setJ(self._jacobian, A)

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
        self.updates = 0
        self._bind_matrix()
        try:
            with quiet_dolfinx():  # non-convergence is reported below, with the residuals
                iterations, converged = super().solve(u)
        except PETSc.Error as error:
            raise ContactConvergenceError(
                f"Newton iteration failed: {validation.describe_petsc_error(error)}"
            ) from error
        except (RuntimeError, ValueError) as error:  # degenerate iterates
            raise ContactConvergenceError(f"Newton iteration failed: {error}") from error
        if not converged:
            hint = ""
            if self.problem.num_springs == 0 and self.problem.states:
                hint = (
                    "; there are no contact springs, so a body held only by contact is unsupported "
                    "(close the initial gap, or start with a prescribed displacement)"
                )
            raise ContactConvergenceError(
                f"Newton did not converge in {iterations} iterations "
                f"(residual {self.residual_norms[-1]:.3e}, "
                f"first {self.residual_norms[0]:.3e}){hint}"
            )
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
        predictor: Start each increment from ``u_n + dt v_prev`` like CalculiX (after the pairing).
        cutback_factor: Increment size factor after a failed attempt.
        growth_factor, growth_iterations: Like CalculiX (D_D = 1.5, I_G = 4), the increment grows by
            ``growth_factor`` after two consecutive increments that each converged in at most
            ``growth_iterations`` iterations.
        on_increment: Called with the :class:`IncrementResult` of each converged increment.
    """

    set_load: LoadControl
    period: float = 1.0
    initial_increment: float = 1.0
    min_increment: float = 1e-5
    max_increment: float | None = None
    fixed: bool = False
    predictor: bool = True
    cutback_factor: float = 0.5
    growth_factor: float = 1.5
    growth_iterations: int = 4
    on_increment: typing.Callable[[IncrementResult], None] | None = None

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
        results: list[IncrementResult] = []
        t, dt = 0.0, self.initial_increment
        increment = 0
        fast_in_a_row = 0
        velocity = None
        while t < self.period * (1 - 1e-12):
            increment += 1
            attempt = 0
            u_start = u.x.array.copy()
            while True:
                attempt += 1
                dt = min(dt, self.period - t)
                t_new = t + dt
                logger.info(
                    " increment %d attempt %d\n increment size= %.6e\n actual step time= %.6e",
                    increment,
                    attempt,
                    dt,
                    t_new,
                )
                self.set_load(t_new)
                start = time.perf_counter()
                try:
                    problem.begin_increment(t_new / self.period)
                    if self.predictor and velocity is not None:
                        u.x.array[:] = u_start + dt * velocity
                        u.x.scatter_forward()
                    iterations, _ = solver.solve(u)
                    break
                except ContactConvergenceError as error:
                    u.x.array[:] = u_start
                    u.x.scatter_forward()
                    if self.fixed or dt * self.cutback_factor < self.min_increment:
                        raise ContactConvergenceError(
                            f"increment {increment} (step time {t:.6g} -> {t_new:.6g}) "
                            f"failed after {attempt} attempt(s); increment size {dt:.3e} "
                            f"cannot be cut back below the minimum "
                            f"{self.min_increment:.3e}: {error}"
                        ) from error
                    dt *= self.cutback_factor
                    fast_in_a_row = 0
                    logger.info(" %s; cutting back to %.6e", error, dt)
            velocity = (u.x.array - u_start) / dt
            t = t_new
            result = IncrementResult(
                increment,
                attempt,
                t,
                t / self.period,
                iterations,
                problem.num_springs,
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
                time.perf_counter() - start,
            )
            if self.on_increment is not None:
                self.on_increment(result)
            fast_in_a_row = fast_in_a_row + 1 if iterations <= self.growth_iterations else 0
            if not self.fixed and fast_in_a_row >= 2:
                dt = min(self.growth_factor * dt, max_inc)
        return results
