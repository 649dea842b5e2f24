"""A Newton solver of dolfinx's shape that does not depend on ``dolfinx.nls``.

dolfinx deprecated ``dolfinx.nls.petsc.NewtonSolver`` in 0.10 and removed it after 0.11.
:class:`NewtonSolver` keeps its interface (``setF``, ``setJ``, ``set_form``, ``set_update``,
``set_convergence_check``, ``solve(u)``, ``krylov_solver``, ``atol``, ``rtol``, ``max_it``,
``relaxation_parameter``...) and its loop, step for step, so that a solver written for dolfinx's
class runs unchanged and gives the same iterates on every dolfinx version:

1. ``form(x)``, ``F(x, b)``, convergence check of ``b``;
2. while not converged and fewer than ``max_it`` updates: ``J(x, A)``, solve ``A dx = b``
   (:meth:`NewtonSolver.solve_correction`),
   ``update(dx, x)`` (default ``x -= relaxation_parameter * dx``), ``form(x)``, ``F(x, b)``,
   convergence check.
"""

from __future__ import annotations

import logging
import typing

from mpi4py import MPI
from petsc4py import PETSc

import dolfinx.fem
import dolfinx.fem.petsc

from dolfinx_ntf import compat

__all__ = ["NewtonSolver", "NonlinearSystem"]

logger = logging.getLogger("dolfinx_ntf")

#: ``check(solver, r) -> (norm, converged)`` for the residual (or, with the ``"incremental"``
#: criterion, the correction) ``r``.
ConvergenceCheck = typing.Callable[["NewtonSolver", PETSc.Vec], tuple[float, bool]]
#: ``update(solver, dx, x)`` applies the correction ``dx`` to the iterate ``x``.
Update = typing.Callable[["NewtonSolver", PETSc.Vec, PETSc.Vec], None]


class NonlinearSystem(typing.Protocol):
    """What :class:`NewtonSolver` needs of a problem: dolfinx's ``NonlinearProblem`` shape.

    ``a`` and ``L`` are the compiled Jacobian and residual forms (they size the matrix and the
    vector); ``form`` is called before every residual, ``F`` and ``J`` assemble.
    """

    @property
    def a(self) -> compat.Form:
        """The compiled Jacobian form."""

    @property
    def L(self) -> compat.Form:
        """The compiled residual form."""

    def form(self, x: PETSc.Vec) -> None:
        """Prepare the evaluation at ``x`` (e.g. update its ghost values)."""

    def F(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Assemble the residual at ``x`` into ``b``."""

    def J(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """Assemble the Jacobian at ``x`` into ``A``."""


def residual_test(solver: NewtonSolver, r: PETSc.Vec) -> tuple[float, bool]:
    """dolfinx's default test: ``||r|| < atol`` or ``||r|| / residual0 < rtol``.

    As in dolfinx, ``residual0`` is the norm of the first correction of the solve (of the last
    solve's before the first update: the relative test cannot pass there in a first solve).
    """
    norm = r.norm()
    relative = norm / solver.residual0 if solver.residual0 > 0 else float("inf")
    if solver.report:
        logger.info(
            "Newton iteration %d: r (abs) = %.3e (tol = %.3e), r (rel) = %.3e (tol = %.3e)",
            solver.iteration,
            norm,
            solver.atol,
            relative,
            solver.rtol,
        )
    return norm, relative < solver.rtol or norm < solver.atol


def relaxed_update(solver: NewtonSolver, dx: PETSc.Vec, x: PETSc.Vec) -> None:
    """dolfinx's default update: ``x -= relaxation_parameter * dx``."""
    x.axpy(-solver.relaxation_parameter, dx)


class NewtonSolver:
    """Newton's method for ``F(u) = 0`` with a PETSc Krylov solver, in dolfinx's shape.

    Args:
        comm: The problem's MPI communicator.
        problem: Its residual, Jacobian and pre-evaluation callbacks (:class:`NonlinearSystem`);
            ``setF``, ``setJ`` and ``set_form`` replace them.

    The Krylov solver (``krylov_solver``) defaults to dolfinx's choice, LU (MUMPS when PETSc
    has it), and reads PETSc's options under the prefix ``nls_solve_``.
    """

    def __init__(self, comm: MPI.Comm, problem: NonlinearSystem) -> None:
        self.comm = comm
        #: Stop after this many updates without convergence.
        self.max_it = 50
        #: Relative tolerance of the default test.
        self.rtol = 1e-9
        #: Absolute tolerance of the default test.
        self.atol = 1e-10
        #: ``"residual"`` tests ``b`` after each update (and before the first), ``"incremental"``
        #: tests the correction ``dx`` from the second update on.
        self.convergence_criterion = "residual"
        #: Log each test of the default convergence check (logger ``dolfinx_ntf``, INFO).
        self.report = True
        #: Raise ``RuntimeError`` when ``solve`` ends without convergence (else return False).
        self.error_on_nonconvergence = True
        #: Factor of the correction in the default update.
        self.relaxation_parameter = 1.0
        #: Updates of the current (or last) solve.
        self.iteration = 0
        #: Krylov iterations of the current (or last) solve.
        self.krylov_iterations = 0
        #: Norm of the last tested residual (or correction).
        self.residual = -1.0
        #: Norm the relative test divides by.
        self.residual0 = 0.0
        self._A = dolfinx.fem.petsc.create_matrix(problem.a)
        self._b = compat.create_vector(problem.L)
        self._P: PETSc.Mat | None = None
        self._dx: PETSc.Vec | None = None
        self._fn_F = problem.F
        self._fn_J = problem.J
        self._fn_P: typing.Callable[[PETSc.Vec, PETSc.Mat], None] | None = None
        self._fn_form: typing.Callable[[PETSc.Vec], None] | None = problem.form
        self._converged: ConvergenceCheck = residual_test
        self._update_solution: Update = relaxed_update
        self.krylov_solver = PETSc.KSP().create(comm)
        self.krylov_solver.setOptionsPrefix("nls_solve_")
        self.krylov_solver.setType("preonly")
        self.krylov_solver.getPC().setType("lu")
        if PETSc.Sys.hasExternalPackage("mumps"):
            self.krylov_solver.getPC().setFactorSolverType("mumps")
        self.krylov_solver.setFromOptions()

    @property
    def A(self) -> PETSc.Mat:
        """The Jacobian matrix."""
        return self._A

    @property
    def b(self) -> PETSc.Vec:
        """The residual vector."""
        return self._b

    def setF(self, F: typing.Callable[[PETSc.Vec, PETSc.Vec], None], b: PETSc.Vec) -> None:
        """Assemble the residual with ``F(x, b)`` into the vector ``b``."""
        self._fn_F, self._b = F, b

    def setJ(self, J: typing.Callable[[PETSc.Vec, PETSc.Mat], None], A: PETSc.Mat) -> None:
        """Assemble the Jacobian with ``J(x, A)`` into the matrix ``A``."""
        self._fn_J, self._A = J, A

    def setP(self, P: typing.Callable[[PETSc.Vec, PETSc.Mat], None], Pmat: PETSc.Mat) -> None:
        """Assemble a separate preconditioner matrix with ``P(x, Pmat)``."""
        self._fn_P, self._P = P, Pmat

    def set_form(self, form: typing.Callable[[PETSc.Vec], None]) -> None:
        """Call ``form(x)`` before every residual evaluation."""
        self._fn_form = form

    def set_update(self, update: Update) -> None:
        """Apply corrections with ``update(solver, dx, x)`` instead of ``x -= relaxation dx``."""
        self._update_solution = update

    def set_convergence_check(self, check: ConvergenceCheck) -> None:
        """Decide convergence with ``check(solver, r) -> (norm, converged)``."""
        self._converged = check

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """Solve from the current ``u`` into ``u``; returns (updates, converged). Collective.

        Raises:
            RuntimeError: No convergence within ``max_it`` updates and ``error_on_nonconvergence``.
        """
        x = compat.petsc_vector(u)
        converged = self._iterate(x)
        u.x.scatter_forward()
        if converged:
            logger.debug(
                "Newton solver finished in %d iterations and %d linear solver iterations.",
                self.iteration,
                self.krylov_iterations,
            )
        elif self.error_on_nonconvergence:
            why = " (maximum number of iterations reached)" if self.iteration == self.max_it else ""
            raise RuntimeError(f"Newton solver did not converge{why}")
        return self.iteration, converged

    def _iterate(self, x: PETSc.Vec) -> bool:
        """dolfinx's Newton loop on the PETSc vector ``x``; returns whether it converged."""
        if self.convergence_criterion not in ("residual", "incremental"):
            raise ValueError(
                f"NewtonSolver: convergence_criterion must be 'residual' or 'incremental', "
                f"got {self.convergence_criterion!r}"
            )
        self.iteration, self.krylov_iterations, self.residual = 0, 0, -1.0
        self._evaluate(x)
        converged = False
        if self.convergence_criterion == "residual":
            self.residual, converged = self._converged(self, self._b)
        self.krylov_solver.setOperators(self._A, self._P if self._P is not None else self._A)
        if self._dx is None:
            self._dx = self._A.createVecRight()
        while not converged and self.iteration < self.max_it:
            self._fn_J(x, self._A)
            if self._fn_P is not None:
                self._fn_P(x, self._P)
            self.solve_correction(self._b, self._dx)
            self.krylov_iterations += self.krylov_solver.getIterationNumber()
            self._update_solution(self, self._dx, x)
            self.iteration += 1
            self._evaluate(x)
            if self.iteration == 1:
                self.residual0 = self._dx.norm()
            if self.convergence_criterion == "residual":
                self.residual, converged = self._converged(self, self._b)
            elif self.iteration > 1:
                self.residual, converged = self._converged(self, self._dx)
        return converged

    def solve_correction(self, b: PETSc.Vec, dx: PETSc.Vec) -> None:
        """Solve ``J dx = b`` with the Krylov solver (subclasses may reuse factorizations)."""
        self.krylov_solver.solve(b, dx)

    def _evaluate(self, x: PETSc.Vec) -> None:
        if self._fn_form is not None:
            self._fn_form(x)
        self._fn_F(x, self._b)

    def destroy(self) -> None:
        """Destroy the PETSc objects the solver created. Collective."""
        for obj in (self._dx, self.krylov_solver):
            if obj is not None:
                obj.destroy()
        self._dx = None
