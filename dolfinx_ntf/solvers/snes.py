"""PETSc's SNES as a second driver of a :class:`~dolfinx_ntf.ContactProblem`.

:class:`ContactSNESSolver` hands the problem's residual and Jacobian to a petsc4py ``SNES`` (the
same plain SNES on every dolfinx version): PETSc's line searches, monitors, ``-snes_test_jacobian``
and option database then apply, and the solver composes with other PETSc-based code. The contact
schedule is the problem's own: its Jacobian callback starts each Newton iteration, re-pairs on
CalculiX's schedule (iterations 2 to 8, docs/method.md §3.1) or when asked, and re-assembles the
SNES's residual vector, which is the right-hand side of the coming linear solve. Frozen pairings
(small sliding) stay frozen. By default the SNES stops on CalculiX's force-scaled test, like
:class:`~dolfinx_ntf.ContactNewtonSolver`; ``convergence="petsc"`` uses PETSc's own tolerances.

With the ``basic`` line search (the default: full Newton steps) the iterates are those of
``ContactNewtonSolver(problem, line_search=False)``. PETSc's backtracking line searches need PETSc
3.21 or later (Debian 13, sid) when pairs re-pair inside increments: older SNES keep the residual
norm from before the update hook's re-pairing.
"""

from __future__ import annotations

import logging
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.logs import newton_logger
from dolfinx_ntf.solvers import convergence, errors
from dolfinx_ntf.solvers import linear_solver as linear
from dolfinx_ntf.solvers.convergence import TIGHT_FIELD_CONTROLS, ForceScaledTest, RoundoffFloor
from dolfinx_ntf.solvers.errors import ContactConvergenceError
from dolfinx_ntf.solvers.newton import check_arguments

__all__ = ["ContactSNESSolver"]

logger = logging.getLogger("dolfinx_ntf")

#: Values of ``ContactSNESSolver(convergence=...)``.
CONVERGENCE_TESTS = ("calculix", "petsc")

#: Option names that choose the linear solver: with any of them in ``petsc_options`` the
#: ``linear_solver`` defaults are not set.
LINEAR_SOLVER_KEYS = ("ksp_", "pc_", "mat_")

#: SNES options set unless given: Newton with full steps, no SNES-side stopping before the test.
DEFAULT_SNES_OPTIONS: dict[str, typing.Any] = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "basic",
}


class ContactSNESSolver:
    """PETSc SNES driving a :class:`ContactProblem` (an alternative to ContactNewtonSolver).

    Args:
        comm: MPI communicator of the mesh.
        problem: The contact problem (without linear constraints: their reduced system needs
            :class:`~dolfinx_ntf.ContactNewtonSolver`).
        petsc_options: Options of the SNES, its line search and its Krylov solver, set under
            ``options_prefix`` (e.g. ``{"snes_linesearch_type": "bt", "snes_monitor": None}``).
            ``DEFAULT_SNES_OPTIONS`` fill the SNES options not given, and ``linear_solver``'s
            Krylov options apply unless an option starts with ``ksp_``, ``pc_`` or ``mat_``.
            Options already in PETSc's database under the prefix take precedence.
        linear_solver: ``"direct"``, ``"iterative"`` or ``"auto"``, as for
            :class:`~dolfinx_ntf.ContactNewtonSolver`.
        options_prefix: Prefix of the SNES's options (its KSP and line search share it).
        convergence: ``"calculix"``: CalculiX's force-scaled test (``controls``) after at least
            ``min_iterations`` updates, none right after a re-pairing that changed the number of
            springs; ``"petsc"``: SNES's own tests (``snes_rtol``, ``snes_atol``, ``snes_stol``).
        controls: The force-scaled test's values (default ``TIGHT_FIELD_CONTROLS``).
        relaxation_iteration: CalculiX's I_P (after this many updates ``R_p`` replaces ``R_n``).
        max_it: Maximum Newton iterations per increment (``snes_max_it``).
        min_iterations: Newton updates needed before the force-scaled test may pass.
        check_unpaired: Before accepting convergence, pair again if slave nodes penetrate without
            a spring (as ContactNewtonSolver does).
        roundoff_floor: A largest residual force below the round-off of the forces counts as
            zero, as for ContactNewtonSolver.
    """

    def __init__(
        self,
        comm: MPI.Comm,
        problem: ContactProblem,
        *,
        petsc_options: dict[str, typing.Any] | None = None,
        linear_solver: str = "auto",
        options_prefix: str = "ntf_snes_",
        convergence: str = "calculix",
        controls: typing.Mapping[str, float] | None = None,
        relaxation_iteration: int = 9,
        max_it: int = 30,
        min_iterations: int = 2,
        check_unpaired: bool = True,
        roundoff_floor: bool = True,
    ) -> None:
        owner = "ContactSNESSolver"
        controls = dict(TIGHT_FIELD_CONTROLS if controls is None else controls)
        given = check_arguments(
            comm,
            problem,
            petsc_options or {},
            options_prefix,
            controls=controls,
            max_it=max_it,
            min_iterations=min_iterations,
            owner=owner,
        )
        if convergence not in CONVERGENCE_TESTS:
            raise ValueError(
                f"{owner}: convergence must be one of {CONVERGENCE_TESTS}, got {convergence!r}"
            )
        if problem.constraints:
            raise ValueError(
                f"{owner}: the problem has linear constraints (*EQUATION): their reduced "
                "Jacobian is solved by ContactNewtonSolver only"
            )
        own_linear_solver = any(key.startswith(LINEAR_SOLVER_KEYS) for key in given)
        symmetric = linear.expects_symmetric(problem, given if own_linear_solver else None)
        options = dict(DEFAULT_SNES_OPTIONS)
        options["snes_max_it"] = max_it
        if convergence == "calculix":  # the force-scaled test alone decides
            options.update(snes_rtol=0.0, snes_atol=0.0, snes_stol=0.0)
        if not own_linear_solver:
            options.update(linear.default_options(problem, linear_solver, symmetric))
        options.update(given)
        validation.check_linear_solver(comm, options, owner)
        self.problem = problem
        self.convergence = convergence
        self.min_iterations = min_iterations
        self.check_unpaired = check_unpaired
        self.roundoff_floor = roundoff_floor
        self._roundoff = RoundoffFloor(0.0, 0.0)
        problem.measure_bulk_norm = roundoff_floor
        #: CalculiX's force-scaled test (``convergence="calculix"``).
        self.test = ForceScaledTest(controls, relaxation_iteration, bounded=True)
        #: Displacement at the start of the increment; set by the step driver.
        self.increment_start: np.ndarray | None = None
        #: Residual norms of the current solve, one per residual the SNES tested.
        self.residual_norms: list[float] = []
        self.snes = PETSc.SNES().create(comm)
        self.snes.setOptionsPrefix(options_prefix)
        self._A: PETSc.Mat | None = None
        self._u_vector = compat.petsc_vector(problem.u)
        self._x = self._u_vector.duplicate()
        self._b = self._u_vector.duplicate()
        self._previous = self._u_vector.duplicate()
        self._step = self._u_vector.duplicate()
        self.snes.setFunction(self._residual, self._b)
        self.snes.setMonitor(self._record)
        self.snes.setUpdate(self._start_iteration)
        if convergence == "calculix":
            self.snes.setConvergenceTest(self._converged)
        _check_line_search(options, options_prefix, problem, owner)
        linear.set_options(self.snes, options, options_prefix)
        #: The SNES's Krylov solver, kept in step with the Jacobian (Cholesky to LU with friction).
        self.linear = linear.LinearSolver(
            self.snes.getKSP(), {}, options_prefix, problem.u.function_space, symmetric
        )

    @property
    def iterations(self) -> int:
        """Newton iterations of the last solve."""
        return self.snes.getIterationNumber()

    def begin_step(self) -> None:
        """Start a step (the test's time average restarts)."""
        self.test.step_forces = []

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """Solve one increment from the current ``u`` into ``u``. Collective.

        Returns:
            The number of Newton iterations and True.

        Raises:
            ContactConvergenceError: The SNES did not converge (its reason in the message).
        """
        if u is not self.problem.u:
            raise ValueError(
                "ContactSNESSolver.solve: u must be the Function the ContactProblem was built on"
            )
        self.residual_norms = []
        self._solve_start = u.x.array.copy()
        self.test.begin_solve(0.0)
        A = self.problem.ensure_matrix()
        if A is not self._A:
            self._A = A
            self.snes.setJacobian(self._jacobian, A)
            self.linear.attach(A)
        self._u_vector.copy(self._x)
        self.snes.solve(None, self._x)
        self._load(self._x)
        reason = self.snes.getConvergedReason()
        iterations = self.snes.getIterationNumber()
        if reason <= 0:
            last = f"residual {self.residual_norms[-1]:.3e}, " if self.residual_norms else ""
            raise ContactConvergenceError(
                f"SNES did not converge in {iterations} iterations ({last}"
                f"reason {_snes_reason(reason)}){errors.no_support_hint(self.problem)}"
            )
        self.test.end_solve()
        return iterations, True

    def destroy(self) -> None:
        """Destroy the SNES and its vectors (the Jacobian is the problem's). Collective."""
        self.linear.destroy()
        for vector in (self._x, self._b, self._previous, self._step):
            vector.destroy()
        self.snes.destroy()

    def __enter__(self) -> ContactSNESSolver:
        return self

    def __exit__(self, *args: object) -> None:
        self.destroy()

    def _load(self, x: PETSc.Vec) -> None:
        """Put ``x`` into the problem's displacement and evaluate the springs there."""
        if x.handle != self._u_vector.handle:
            x.copy(self._u_vector)
        self.problem.form(self._u_vector)

    def _residual(self, snes: PETSc.SNES, x: PETSc.Vec, b: PETSc.Vec) -> None:
        self._load(x)
        self.problem.F(self._u_vector, b)
        norm = b.norm()
        if not np.isfinite(norm):
            raise errors.non_finite_residual(norm, snes.getIterationNumber(), self.problem)

    def _start_iteration(self, snes: PETSc.SNES, iteration: int) -> None:
        """SNES's update hook: re-pair on schedule (re-assembling the SNES's residual)."""
        x = snes.getSolution()
        if not np.array_equal(x.array_r, self._u_vector.array_r):
            self._load(x)
        x.copy(self._previous)
        self.problem.residual_vector = snes.getFunction()[0]
        self.problem.start_iteration(self._u_vector)

    def _jacobian(self, snes: PETSc.SNES, x: PETSc.Vec, A: PETSc.Mat, P: PETSc.Mat) -> None:
        """The Jacobian with the springs of this iteration's pairing."""
        merges = self.problem.assembler.pattern_merges
        self.problem.assemble_jacobian(self._u_vector, A)
        if self.roundoff_floor:
            self._roundoff = convergence.roundoff_floor(self.problem, A, self._u_vector)
        self.linear.update(
            A,
            friction=self.problem.has_friction,
            pattern_grew=self.problem.assembler.pattern_merges != merges,
            reduced=None,
        )

    def _record(self, snes: PETSc.SNES, iteration: int, norm: float) -> None:
        self.residual_norms.append(norm)

    def _converged(
        self, snes: PETSc.SNES, iteration: int, norms: tuple[float, float, float]
    ) -> int:
        """CalculiX's test after Newton update ``iteration`` (a SNES convergence test)."""
        x, b = snes.getSolution(), snes.getFunction()[0]
        if iteration == 0:
            if self.test.bounded:  # the forces the bounded test starts from
                self.test.begin_iterations(
                    self.problem.average_element_force(), b.norm(PETSc.NormType.NORM_INFINITY)
                )
            return PETSc.SNES.ConvergedReason.ITERATING
        self._step.waxpy(-1.0, self._previous, x)
        start = self.increment_start if self.increment_start is not None else self._solve_start
        average, largest, correction, change = convergence.measure_iterate(
            self.problem, x, b, self._step, 1.0, start
        )
        if self.roundoff_floor:
            largest = convergence.largest_beyond_roundoff(self.problem, b, self._roundoff)
        converged = self.test.converged(iteration, average, largest, correction, change)
        converged = (
            converged and iteration >= self.min_iterations and not self.problem.count_changed
        )
        if converged and self.check_unpaired and self.problem.unpaired_contacts():
            self.problem.repair_next_iteration = True
            converged = False
        newton_logger.info(
            " SNES iteration %d: residual %.3e, %d contact elements%s",
            iteration,
            norms[2],
            self.problem.total_springs,
            ", converged" if converged else "",
        )
        if converged:
            return PETSc.SNES.ConvergedReason.CONVERGED_FNORM_ABS
        if iteration >= snes.getTolerances()[3]:
            return PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
        return PETSc.SNES.ConvergedReason.ITERATING


def _check_line_search(
    options: dict[str, typing.Any], prefix: str, problem: ContactProblem, owner: str
) -> None:
    """Refuse a backtracking line search that PETSc < 3.21 would feed a stale residual norm.

    Before 3.21, SNES does not take the residual norm again after the update hook, so a line
    search other than ``basic`` compares its trial residuals with the norm before a re-pairing
    and can fail where Newton converges.
    """
    database = PETSc.Options()
    key = "snes_linesearch_type"
    kind = database.getString(f"{prefix}{key}", str(options.get(key, "bt")))
    if kind == "basic" or problem.small_sliding or PETSc.Sys.getVersion() >= (3, 21, 0):
        return
    version = ".".join(str(v) for v in PETSc.Sys.getVersion())
    raise ValueError(
        f"{owner}: snes_linesearch_type {kind!r} needs PETSc >= 3.21 when pairs re-pair inside "
        f"increments (PETSc {version} keeps the residual norm from before the re-pairing); use "
        "'basic', small sliding pairs, or ContactNewtonSolver(line_search=True)"
    )


def _snes_reason(reason: int) -> str:
    """Name of a PETSc SNES converged/diverged reason."""
    names = {
        value: name
        for name, value in vars(PETSc.SNES.ConvergedReason).items()
        if isinstance(value, int) and not name.startswith("_")
    }
    return names.get(reason, str(reason))
