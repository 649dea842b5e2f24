"""The staggered (isothermal split) solution of thermal contact: :func:`solve_staggered`.

docs/method.md §20.4. Each pass solves the mechanics at the current temperature (the thermal strain
of the mechanical form reads ``T``), then the heat problem at the new displacement (the springs'
areas, pressures and projection points held, its temperature tangent exact), until neither field
changes. The coupled problem's fixed point is the monolithic one's; the split converges when the
coupling is weak enough (linear rate, the contraction of the two solves).
"""

from __future__ import annotations

import logging
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from dolfinx_ntf import compat
from dolfinx_ntf.contact.thermal import ThermalContactProblem
from dolfinx_ntf.solvers.errors import ContactConvergenceError
from dolfinx_ntf.solvers.newton_loop import NewtonSolver

__all__ = ["solve_staggered", "thermal_solver"]

logger = logging.getLogger("dolfinx_ntf")


def thermal_solver(problem: ThermalContactProblem) -> NewtonSolver:
    """A Newton solver for ``problem`` on its Jacobian matrix (the springs' couplings included).

    With constraints it solves with the reduced Jacobian (``problem.reduced_matrix``).

    Args:
        problem: The heat problem.
    """
    solver = NewtonSolver(problem.T.function_space.mesh.comm, problem)

    def jacobian(x: PETSc.Vec, A: PETSc.Mat) -> None:
        # A grown pattern starts the factorization afresh: PETSc 3.22 does not see the pattern
        # change of MatAXPY(..., DIFFERENT_NONZERO_PATTERN) (solvers/linear_solver.py).
        merges = problem.assembler.pattern_merges
        problem.J(x, A)
        if problem.reduced_matrix is not None:  # constraints: the reduced system (§13.1)
            solver.krylov_solver.setOperators(problem.reduced_matrix, problem.reduced_matrix)
        elif problem.assembler.pattern_merges != merges:
            solver.krylov_solver.getPC().reset()
            solver.krylov_solver.setOperators(A, A)

    solver.setJ(jacobian, problem.ensure_matrix())
    solver.report = False
    return solver


def solve_staggered(
    solve_mechanics: typing.Callable[[], object],
    thermal: ThermalContactProblem,
    *,
    solver: NewtonSolver | None = None,
    rtol: float = 1e-8,
    max_passes: int = 50,
) -> int:
    """Alternate the mechanical and the thermal solves until both fields are stationary.

    Args:
        solve_mechanics: Solves the mechanical problem at the current temperature (e.g. a
            :class:`~dolfinx_ntf.StaticStep` run of ``thermal.contact``).
        thermal: The heat problem on the springs of the mechanical problem.
        solver: The thermal Newton solver (default :func:`thermal_solver`).
        rtol: Stop when the changes of ``u`` and ``T`` in a pass are below ``rtol`` times their
            norms (max norms over all processes).
        max_passes: Raise after this many passes.

    Returns:
        The number of passes. Collective.

    Raises:
        ContactConvergenceError: No convergence within ``max_passes``.
    """
    own = solver is None
    solver = thermal_solver(thermal) if own else solver
    u, T = thermal.contact.u, thermal.T
    try:
        for passes in range(1, max_passes + 1):
            u_old, T_old = u.x.array.copy(), T.x.array.copy()
            solve_mechanics()
            solver.solve(T)
            changes = [
                _relative_change(compat.petsc_vector(f), old) for f, old in ((u, u_old), (T, T_old))
            ]
            logger.info("staggered pass %d: changes u %.3e, T %.3e", passes, *changes)
            if max(changes) <= rtol:
                return passes
    finally:
        if own:
            solver.destroy()
    raise ContactConvergenceError(
        f"solve_staggered: u and T still changed by {changes[0]:.3e} and {changes[1]:.3e} "
        f"(relative) after {max_passes} passes; the coupling may be too strong for the split"
    )


def _relative_change(vector: PETSc.Vec, old: np.ndarray) -> float:
    """max |x - old| / max |x| over the owned entries of all processes. Collective."""
    n = vector.getLocalSize()
    with vector.localForm() as local:
        new = local.array_r[:n]
        diff = float(np.abs(new - old[:n]).max(initial=0.0))
        size = float(np.abs(new).max(initial=0.0))
    comm = vector.getComm().tompi4py()
    diff, size = comm.allreduce(diff, op=MPI.MAX), comm.allreduce(size, op=MPI.MAX)
    return diff / max(size, 1e-300)
