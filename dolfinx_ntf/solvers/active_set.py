"""Node-to-face Newton without CalculiX's rules: an active-set iteration (docs/method.md §15.5).

CalculiX re-pairs in Newton iterations 2..8 only and judges convergence by its force-scaled
criterion with extra rules (at least two updates, none right after the spring count changed).
:class:`ActiveSetNewtonSolver` instead re-pairs at the start of *every* Newton iteration and stops
when the last pairing left the spring set (slave node and master face of every spring) unchanged
and the residual has dropped below ``rtol`` times the first residual of the increment: the springs
then play the role of a semismooth Newton's active set. Penetrating nodes without a spring are
still caught before convergence (``check_unpaired``).
"""

from __future__ import annotations

from petsc4py import PETSc

import numpy as np

from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.solvers.newton import ContactNewtonSolver

__all__ = ["ActiveSetNewtonSolver"]


def _spring_set(problem: ContactProblem) -> list[np.ndarray]:
    return [np.column_stack([s.spring_slave, s.spring_face]) for s in problem.states]


class ActiveSetNewtonSolver(ContactNewtonSolver):
    """Re-pair every iteration; converge when the spring set is stable and the residual small.

    Args:
        comm: MPI communicator.
        problem: The contact problem.
        rtol: Residual tolerance relative to the first residual of each increment.
        atol: Absolute residual tolerance.
        **options: Other :class:`~dolfinx_ntf.ContactNewtonSolver` options (``min_iterations``
            defaults to 1 here).
    """

    def __init__(
        self,
        comm,
        problem: ContactProblem,
        *,
        rtol: float = 1e-10,
        atol: float = 1e-12,
        **options: object,
    ) -> None:
        options.setdefault("min_iterations", 1)
        super().__init__(comm, problem, **options)
        if not (rtol > 0 and atol >= 0):
            raise ValueError(
                f"ActiveSetNewtonSolver: need rtol > 0 and atol >= 0, got {rtol}, {atol}"
            )
        self.active_rtol, self.active_atol = rtol, atol
        self.set_changed = True

    def _jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """Re-pair (every iteration), note whether the spring set changed, assemble."""
        before = _spring_set(self.problem)
        self.problem.repair_next_iteration = True
        super()._jacobian(x, A)
        after = _spring_set(self.problem)
        changed = any(b.shape != a.shape or not np.array_equal(b, a) for b, a in zip(before, after))
        comm = self.problem.u.function_space.mesh.comm
        self.set_changed = bool(comm.allreduce(changed))

    def is_converged(self, x: PETSc.Vec, b: PETSc.Vec, norm: float) -> bool:
        """Spring set unchanged by the last pairing and ``||R|| <= max(rtol ||R_0||, atol)``.

        dolfinx's hook: ``x`` is the iterate, ``b`` its residual and ``norm`` the norm ``||R||``.
        """
        if self.updates == 0:
            self.set_changed = True
            return False
        first = self.residual_norms[0]
        return not self.set_changed and norm <= max(self.active_rtol * first, self.active_atol)
