"""The linear solver of the Newton corrections: which one, with which PETSc options.

Direct (MUMPS LU, or Cholesky when the Jacobian is symmetric) up to a size, GMRES or CG with
smoothed-aggregation AMG above (docs/method.md §14.7); a GAMG preconditioner gets the rigid-body
modes of every body as near-nullspace. Options are set under the solver's prefix, read once and
removed from PETSc's global database again, so that command-line options under the same prefix
win.
"""

from __future__ import annotations

import contextlib
import logging
import typing

from petsc4py import PETSc

import numpy as np

import dolfinx.fem

from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.logs import details_logger
from dolfinx_ntf.solvers import nullspace
from dolfinx_ntf.solvers.factor_reuse import FactorReuse

__all__ = [
    "CHOLESKY_MAX_DOFS",
    "CHOLESKY_PETSC_OPTIONS",
    "DEFAULT_PETSC_OPTIONS",
    "DIRECT_MAX_DOFS",
    "ITERATIVE_PETSC_OPTIONS",
    "LINEAR_SOLVERS",
    "SEQUENTIAL_PTAP",
    "LinearSolver",
    "configure",
    "default_options",
    "expects_symmetric",
    "galerkin_products",
    "ksp_reason",
    "unsymmetric",
]

logger = logging.getLogger("dolfinx_ntf")

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

#: ``linear_solver="auto"`` chooses the direct solver up to this many dofs, the iterative one above
#: (about twice the measured crossover on 2 cores, docs/performance.md "Linear solvers").
DIRECT_MAX_DOFS = 20_000

#: ... and up to this many dofs when the Jacobian is symmetric: MUMPS Cholesky does about half
#: the work of LU and beats CG + GAMG at 81k dofs (docs/method.md §7.4).
CHOLESKY_MAX_DOFS = 100_000

#: Values of ``ContactNewtonSolver(linear_solver=...)``.
LINEAR_SOLVERS = ("auto", "direct", "iterative")


@contextlib.contextmanager
def galerkin_products(ksp: PETSc.KSP) -> typing.Iterator[None]:
    """Use ``SEQUENTIAL_PTAP`` for GAMG's Galerkin products inside the context.

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


def expects_symmetric(problem: object, petsc_options: object) -> bool:
    """Whether the default options may use Cholesky or CG: a ``symmetric`` frictionless problem.

    Contact damping (unsymmetric tangent, docs/method.md §29) rules them out too.
    """
    return (
        petsc_options is None
        and getattr(problem, "symmetric", False)
        and not getattr(problem, "has_friction", False)  # friction: never Cholesky
        and not getattr(problem, "has_damping", False)
    )


def default_options(problem: object, linear_solver: object, symmetric: bool) -> dict:
    """PETSc options of ``linear_solver`` for this problem (docs/method.md §14.7).

    ``"direct"``: MUMPS LU (``DEFAULT_PETSC_OPTIONS``), or MUMPS Cholesky
    (``CHOLESKY_PETSC_OPTIONS``) when ``symmetric`` (the Newton solver swaps it for LU if the
    first Jacobian is not symmetric after all); ``"iterative"``: GMRES, or CG when symmetric, with
    GAMG (``ITERATIVE_PETSC_OPTIONS``); ``"auto"``: direct up to ``DIRECT_MAX_DOFS`` dofs
    (``CHOLESKY_MAX_DOFS`` when symmetric, any size with linear constraints or on a 2D mesh),
    iterative above.

    Args:
        problem: The problem (not checked yet: a :class:`ContactProblem` sizes the "auto" choice).
        linear_solver: One of ``LINEAR_SOLVERS`` (``ValueError`` otherwise).
        symmetric: The Jacobian is expected symmetric: Cholesky or CG.
    """
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
        small |= (
            problem.u.function_space.dofmap.index_map_bs == 2
        )  # 2D: no rigid modes for GAMG yet
        linear_solver = "direct" if small else "iterative"
        details_logger.info(" %d dofs: %s linear solver", dofs, linear_solver)
    if linear_solver == "iterative":
        if not symmetric:
            return dict(ITERATIVE_PETSC_OPTIONS)
        options = {**ITERATIVE_PETSC_OPTIONS, "ksp_type": "cg", "ksp_norm_type": "unpreconditioned"}
        del options["ksp_pc_side"], options["ksp_gmres_restart"]
        return options
    return dict(CHOLESKY_PETSC_OPTIONS if symmetric else DEFAULT_PETSC_OPTIONS)


def configure(
    ksp: PETSc.KSP,
    options: dict[str, typing.Any],
    prefix: str,
    space: dolfinx.fem.FunctionSpace,
) -> PETSc.NullSpace | None:
    """Set ``ksp`` up from ``options`` under ``prefix``; a GAMG gets the rigid-body modes.

    Options already in PETSc's database under the prefix win; the others are set, read once and
    removed again.

    Returns:
        The near-nullspace of a GAMG preconditioner (rigid-body modes of every body of
        ``space``), or None; the caller attaches it to the matrix and destroys it.
    """
    ksp.setOptionsPrefix(prefix)
    set_options(ksp, options, prefix)
    if ksp.getPC().getType() == "gamg":
        return nullspace.near_nullspace(space)
    return None


#: A direct solve that leaves more than this fraction of the right-hand side (2-norm) unsolved
#: found a singular matrix (:meth:`LinearSolver.failure`).
SINGULAR_RESIDUAL = 1e-3


def set_options(
    solver: PETSc.KSP | PETSc.SNES, options: dict[str, typing.Any], prefix: str
) -> None:
    """Set ``options`` on ``solver`` under ``prefix``: those already in PETSc's database win.

    The others are put into the database, read by ``setFromOptions`` and removed again.
    """
    database = PETSc.Options()
    own = {k: v for k, v in options.items() if not database.hasName(f"{prefix}{k}")}
    for key, value in own.items():
        database[f"{prefix}{key}"] = value
    try:
        solver.setFromOptions()
    finally:
        for key in own:
            database.delValue(f"{prefix}{key}")


class LinearSolver:
    """The Krylov solver of the Newton corrections, kept in step with the Jacobian.

    Args:
        ksp: The Newton solver's Krylov solver.
        options: Checked PETSc options, set under ``prefix`` (:func:`configure`).
        prefix: Prefix of the Krylov solver's options.
        space: The displacement space (rigid-body modes of a GAMG preconditioner).
        symmetric: The options chose Cholesky or CG: the first Jacobian's symmetry is checked.
        reuse_factorization: A direct solver solves with an earlier factorization while GMRES
            converges fast enough (:class:`~dolfinx_ntf.solvers.factor_reuse.FactorReuse`).
    """

    def __init__(
        self,
        ksp: PETSc.KSP,
        options: dict[str, typing.Any],
        prefix: str,
        space: dolfinx.fem.FunctionSpace,
        symmetric: bool,
        reuse_factorization: bool = False,
    ) -> None:
        self.ksp = ksp
        self.check_symmetry = symmetric
        #: Rigid-body modes of every body, the near-nullspace of a GAMG preconditioner.
        self.near_nullspace = configure(ksp, options, prefix, space)
        #: The reuse of factorizations, or None (every Jacobian factored afresh).
        self.factor_reuse = FactorReuse(ksp) if reuse_factorization else None

    def solve(self, b: PETSc.Vec, dx: PETSc.Vec) -> None:
        """Solve ``A dx = b``, with an earlier factorization where it is reused. Collective."""
        if self.factor_reuse is None:
            self.ksp.solve(b, dx)
        else:
            self.factor_reuse.solve(b, dx)

    def attach(self, A: PETSc.Mat) -> None:
        """Give a (new) Jacobian the near-nullspace of a GAMG preconditioner."""
        if self.near_nullspace is not None:
            A.setNearNullSpace(self.near_nullspace)

    def update(
        self, A: PETSc.Mat, *, friction: bool, pattern_grew: bool, reduced: PETSc.Mat | None
    ) -> None:
        """After an assembly of ``A``: unsymmetric solvers if needed, a fresh factorization.

        A grown pattern starts the factorization afresh: PETSc 3.22 does not see the pattern
        change of ``MatAXPY(..., DIFFERENT_NONZERO_PATTERN)`` and would reuse the old symbolic
        factorization (MUMPS then reports a zero pivot). With linear constraints the reduced
        matrix is solved.
        """
        ksp = self.ksp
        if friction:
            unsymmetric(ksp, "friction makes the Jacobian unsymmetric")
        if self.check_symmetry:  # Cholesky and CG need a symmetric bulk Jacobian too
            self.check_symmetry = False
            if not A.isSymmetric(1e-10 * A.norm(PETSc.NormType.NORM_INFINITY)):
                unsymmetric(ksp, "the Jacobian is not symmetric")
        if pattern_grew and self.factor_reuse is not None:
            self.factor_reuse.invalidate()
        if pattern_grew:
            ksp.getPC().reset()
            self.attach(A)
            ksp.setOperators(A, A)
        if reduced is not None:
            if reduced.handle != ksp.getOperators()[0].handle:
                ksp.getPC().reset()
            ksp.setOperators(reduced, reduced)

    def failure(self, dx: PETSc.Vec, b: PETSc.Vec | None = None) -> str | None:
        """Why the last solve of ``A dx = b`` failed, or None. Collective.

        Besides PETSc's reason and a non-finite ``dx``: a direct solve that leaves more than
        ``SINGULAR_RESIDUAL`` of ``b`` unsolved, the mark of a singular matrix (a regular one,
        however ill-conditioned, leaves round-off: about 1e-13 on the demos).
        """
        reason = self.ksp.getConvergedReason()
        if reason < 0 or not np.isfinite(dx.norm()):
            return f"the linear solver failed ({ksp_reason(reason)})"
        if b is None or self.ksp.getType() != "preonly":
            return None
        size = b.norm()
        if size == 0:
            return None
        left = b.duplicate()
        self.ksp.getOperators()[0].mult(dx, left)
        left.aypx(-1.0, b)
        ratio = left.norm() / size
        left.destroy()
        if ratio > SINGULAR_RESIDUAL:
            return (
                f"the Jacobian is singular: the direct solve leaves {ratio:.1e} of the "
                "right-hand side unsolved"
            )
        return None

    def fall_back_to_direct(self) -> bool:
        """After a failed iterative solve: MUMPS LU for this and every later solve.

        Returns:
            True, or False when the solver is direct already (nothing to fall back to).
        """
        if self.ksp.getType() == "preonly":
            return False
        A, P = self.ksp.getOperators()
        self.ksp.reset()
        self.ksp.setType("preonly")
        self.ksp.getPC().setType("lu")
        self.ksp.getPC().setFactorSolverType("mumps")
        self.ksp.setOperators(A, P)
        return True

    def destroy(self) -> None:
        """Destroy the near-nullspace (a matrix keeps its own reference)."""
        if self.near_nullspace is not None:
            self.near_nullspace.destroy()
            self.near_nullspace = None


def unsymmetric(ksp: PETSc.KSP, why: str) -> None:
    """Swap the symmetric solvers of ``ksp``: Cholesky for LU, CG for right-preconditioned GMRES."""
    if ksp.getPC().getType() == "cholesky":
        details_logger.info(" %s: LU instead of Cholesky", why)
        ksp.getPC().setType("lu")
    if ksp.getType() == "cg":
        details_logger.info(" %s: GMRES instead of CG", why)
        ksp.setType("gmres")
        ksp.setPCSide(PETSc.PC.Side.RIGHT)


def ksp_reason(reason: int) -> str:
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
