"""Newton corrections solved with an earlier Jacobian's factorization (docs/method.md §31).

From about 10k dofs on, MUMPS's numeric factorization is most of a deck's run (0.65 s of the
0.78 s per Newton iteration of ``punch_20``, 29k dofs), while its triangular solves cost about
1/25 of it. Between Newton iterations the Jacobian changes little: the contact springs and their
faces change, a low-rank part. So a Newton correction after the first is solved by GMRES
(right-preconditioned: the true residual is tested) preconditioned by the factorization of an
earlier Jacobian, to ``rtol`` of the right-hand side; when GMRES would need more than
``max_iterations`` iterations, the current Jacobian is factored afresh and solved directly, as
without reuse. Only a direct solver (``preonly`` with an LU or Cholesky factorization) is reused;
the iterates differ from fresh factorizations by the Krylov tolerance only.
"""

from __future__ import annotations

import math

from petsc4py import PETSc

__all__ = [
    "FACTORIZATIONS",
    "REUSE_MAX_ITERATIONS",
    "REUSE_MIN_DOFS",
    "REUSE_RTOL",
    "FactorReuse",
    "reuses_factorization",
]

#: Values of ``ContactNewtonSolver(factorization=...)``: ``"fresh"`` factors every Jacobian,
#: ``"reuse"`` solves with an earlier factorization when GMRES converges fast enough, ``"auto"``
#: reuses from ``REUSE_MIN_DOFS`` dofs on.
FACTORIZATIONS = ("auto", "fresh", "reuse")

#: ``factorization="auto"`` reuses factorizations from this many dofs on: below, a factorization
#: costs little more than the triangular solves GMRES needs (docs/performance.md, "Reusing the
#: factorization").
REUSE_MIN_DOFS = 10_000

#: GMRES with the stale factorization stops when the true residual is below this fraction of the
#: right-hand side (a direct solve leaves about 1e-14).
REUSE_RTOL = 1e-11

#: ... and gives up, for a fresh factorization, when it would need more iterations than this
#: (a factorization of ``punch_20`` costs about 25 GMRES iterations).
REUSE_MAX_ITERATIONS = 12

#: GMRES iterations after which the rate of convergence so far predicts whether ``rtol`` is
#: reached within ``max_iterations``; a solve predicted to miss gives up then.
PREDICT_AFTER = 2


def reuses_factorization(factorization: object, dofs: int, owner: str = "factor_reuse") -> bool:
    """Whether ``factorization`` (one of ``FACTORIZATIONS``) reuses factorizations at ``dofs``.

    Args:
        factorization: ``"fresh"``, ``"reuse"`` or ``"auto"`` (``ValueError`` otherwise).
        dofs: Global number of dofs of the problem.
        owner: Who asks, for the error message.
    """
    if not isinstance(factorization, str) or factorization not in FACTORIZATIONS:
        raise ValueError(
            f"{owner}: factorization must be one of {FACTORIZATIONS}, got {factorization!r}"
        )
    return factorization == "reuse" or (factorization == "auto" and dofs >= REUSE_MIN_DOFS)


class FactorReuse:
    """Solves of ``A dx = b`` that reuse the last factorization of a direct Krylov solver.

    Args:
        ksp: The Newton solver's Krylov solver; only when it is ``preonly`` with an LU or
            Cholesky preconditioner at a solve is the factorization reused, else it solves as is.
        rtol: GMRES's tolerance on the true residual, relative to ``b``.
        max_iterations: GMRES iterations after which the current matrix is factored afresh.
    """

    def __init__(
        self,
        ksp: PETSc.KSP,
        rtol: float = REUSE_RTOL,
        max_iterations: int = REUSE_MAX_ITERATIONS,
    ) -> None:
        self.ksp = ksp
        self.rtol = rtol
        self.max_iterations = max_iterations
        #: Numeric factorizations done by :meth:`solve`.
        self.factorizations = 0
        #: Solves done by GMRES with an earlier factorization.
        self.reuses = 0
        #: GMRES solves that gave up (followed by a fresh factorization).
        self.give_ups = 0
        #: GMRES iterations over all solves, those that gave up included.
        self.krylov_iterations = 0
        self._factor: tuple[int, str] | None = None  # (operator handle, PC type) of the factor
        self._first_residual = 0.0
        self._switched = False  # the Krylov solver is GMRES because of a reuse

    def invalidate(self) -> None:
        """Factor afresh at the next solve (the matrix's pattern or the operator changed)."""
        self._factor = None

    def solve(self, b: PETSc.Vec, dx: PETSc.Vec) -> None:
        """Solve ``A dx = b`` for the Krylov solver's operator ``A``. Collective.

        With a factorization of an earlier ``A`` (same operator, same factorization type), GMRES
        preconditioned by it; if GMRES gives up, or without one, a fresh factorization.
        """
        ksp = self.ksp
        pc = ksp.getPC()
        direct = ksp.getType() == "preonly" or (self._switched and ksp.getType() == "gmres")
        if not direct or pc.getType() not in ("lu", "cholesky"):
            self._factor = None
            self._switched = False
            ksp.solve(b, dx)  # an iterative solver, or the user's options: as they are
            return
        key = (ksp.getOperators()[0].handle, pc.getType())
        if self._factor == key and self._gmres(b, dx):
            self.reuses += 1
            return
        self._direct(b, dx)
        self._factor = key

    def _gmres(self, b: PETSc.Vec, dx: PETSc.Vec) -> bool:
        """GMRES with the current factorization; whether it converged."""
        ksp, pc = self.ksp, self.ksp.getPC()
        pc.setReusePreconditioner(True)
        ksp.setType("gmres")
        self._switched = True
        ksp.setPCSide(PETSc.PC.Side.RIGHT)
        ksp.setInitialGuessNonzero(False)
        ksp.setTolerances(rtol=self.rtol, atol=0.0, max_it=self.max_iterations)
        ksp.setConvergenceTest(self._test)
        ksp.solve(b, dx)
        self.krylov_iterations += ksp.getIterationNumber()
        converged = ksp.getConvergedReason() > 0
        if not converged:
            self.give_ups += 1
        return converged

    def _direct(self, b: PETSc.Vec, dx: PETSc.Vec) -> None:
        """A fresh factorization of the current matrix and its direct solve."""
        ksp, pc = self.ksp, self.ksp.getPC()
        pc.setReusePreconditioner(False)
        ksp.setType("preonly")
        self._switched = False
        ksp.solve(b, dx)
        self.factorizations += 1

    def _test(self, ksp: PETSc.KSP, its: int, rnorm: float) -> int:
        """GMRES's convergence test: ``rtol`` reached, or giving up as soon as it is out of reach.

        After ``PREDICT_AFTER`` iterations the mean rate of decrease so far extrapolates the
        iterations needed; more than ``max_iterations`` gives up then, not at the limit.
        """
        if its == 0:
            self._first_residual = rnorm
            return 0 if rnorm > 0 else PETSc.KSP.ConvergedReason.CONVERGED_ATOL
        if not math.isfinite(rnorm):
            return PETSc.KSP.ConvergedReason.DIVERGED_NANORINF
        if rnorm <= self.rtol * self._first_residual:
            return PETSc.KSP.ConvergedReason.CONVERGED_RTOL
        if its >= self.max_iterations:
            return PETSc.KSP.ConvergedReason.DIVERGED_MAX_IT
        if its >= PREDICT_AFTER:
            decrease = rnorm / self._first_residual
            needed = its * math.log(self.rtol) / math.log(decrease) if decrease < 1 else math.inf
            if needed > self.max_iterations:
                return PETSc.KSP.ConvergedReason.DIVERGED_MAX_IT
        return 0

    def summary(self) -> str:
        """The counts, for a log line."""
        return (
            f"{self.factorizations} factorization(s), {self.reuses} solve(s) with an earlier one "
            f"({self.krylov_iterations} GMRES iterations, {self.give_ups} gave up)"
        )
