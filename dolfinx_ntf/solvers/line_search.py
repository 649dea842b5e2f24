"""Backtracking along a Newton correction until the residual of the current pairing decreases.

Beyond CalculiX, which always takes the full step: it breaks the cycles of Newton iterates around
projections clamped to a face edge, and stops runaway iterates after a re-pairing.
"""

from __future__ import annotations

from petsc4py import PETSc

import numpy as np

from dolfinx_ntf.contact.problem import ContactProblem

__all__ = ["LineSearch"]


class LineSearch:
    """Armijo backtracking (steps 1, 1/2, ...) with the work vectors it needs.

    Steps 1, 1/2, ... down to ``2**-max_halvings`` until the residual of the current pairing
    decreases (Armijo), else the best step tried.

    Args:
        template: A residual vector to copy the layout of.
        max_halvings: The smallest step is 2 to the minus this.
    """

    def __init__(self, template: PETSc.Vec, max_halvings: int) -> None:
        self.max_halvings = max_halvings
        #: Residual at the last trial point.
        self.trial_residual = template.duplicate()
        self._start = template.duplicate()
        #: The last trial is the new iterate: its springs and :attr:`trial_residual` are reusable.
        self.trial_is_current = False

    def search(
        self,
        problem: ContactProblem,
        dx: PETSc.Vec,
        x: PETSc.Vec,
        start: float,
        relaxation: float,
    ) -> float:
        """Step length along ``-relaxation dx`` that decreases the residual norm ``start``.

        The Armijo step if one of the trials is, else the best step tried; ``x`` is left as it
        was. Each trial forms the springs and assembles the residual at ``x - step dx``.
        """
        best_step, best_norm = 1.0, np.inf
        step = 1.0
        x.copy(self._start)
        # The caller repeats the same axpy, so the last trial is the new iterate bit for bit (not
        # with constraints: form() back-substitutes the eliminated values into x)
        reusable = problem.elimination is None
        for _ in range(self.max_halvings + 1):
            x.axpy(-step * relaxation, dx)
            problem.form(x)
            problem.assemble_residual(x, self.trial_residual)
            norm = self.trial_residual.norm()
            self._start.copy(x)
            if norm < best_norm:
                best_step, best_norm = step, norm
            if norm <= (1.0 - 1e-4 * step) * start:
                self.trial_is_current = reusable
                return step
            last, step = step, 0.5 * step
        self.trial_is_current = reusable and best_step == last
        return best_step

    def destroy(self) -> None:
        """Destroy the work vectors."""
        self.trial_residual.destroy()
        self._start.destroy()
