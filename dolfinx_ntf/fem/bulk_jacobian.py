"""The bulk Jacobian kept while nothing it depends on changes (docs/method.md §7.5).

With a linear material at small strain the bulk tangent does not depend on ``u``: assembling it at
every Newton iteration repeats the same numbers (0.3 s per iteration at 80k dofs). The bulk part of
the Jacobian is therefore assembled once and copied into the matrix at the next iterations, as long
as its form does not contain ``u`` and its other inputs (coefficients, constants, mesh geometry),
the matrix's pattern and the Dirichlet conditions are those of the saved copy. The copy is the
assembled matrix itself, so the Jacobian is the same to the last bit.
"""

from __future__ import annotations

import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem.petsc
import ufl
import ufl.algorithms
from ufl.algorithms.analysis import extract_coefficients, extract_constants

__all__ = ["BulkJacobian"]


class BulkJacobian:
    """Assembles the bulk Jacobian, or copies the last one when its inputs are unchanged.

    Args:
        J: The bulk Jacobian form (UFL), e.g. ``ufl.derivative(F, u)``.
        u: The unknown: a form containing it is assembled at every call.
        enabled: False assembles at every call (no saved copy, no extra memory).
    """

    def __init__(self, J: ufl.Form, u: dolfinx.fem.Function, enabled: bool = True) -> None:
        form = ufl.algorithms.expand_derivatives(J)
        coefficients = extract_coefficients(form)
        self._mesh = u.function_space.mesh
        self._coefficients = [c for c in coefficients if c is not u]
        self._constants = extract_constants(form)
        #: Whether the saved copy is used: the form does not contain ``u`` and reuse is enabled.
        self.enabled = bool(enabled) and all(c is not u for c in coefficients)
        self._saved: PETSc.Mat | None = None
        self._key: tuple | None = None
        self._inputs: list[np.ndarray] | None = None
        #: Assemblies and copies so far.
        self.assemblies = 0
        self.copies = 0

    def _snapshot(self) -> list[np.ndarray]:
        return [
            *(c.x.array.copy() for c in self._coefficients),
            *(np.array(c.value, copy=True) for c in self._constants),
            self._mesh.geometry.x.copy(),
        ]

    def _unchanged(self, key: tuple, inputs: list[np.ndarray]) -> bool:
        same = (
            self._saved is not None
            and key == self._key
            and all(np.array_equal(a, b) for a, b in zip(inputs, self._inputs, strict=True))
        )
        return bool(self._mesh.comm.allreduce(same, op=MPI.LAND))

    def assemble(
        self,
        A: PETSc.Mat,
        a: dolfinx.fem.Form,
        bcs: typing.Sequence,
        pattern: typing.Hashable,
    ) -> None:
        """Set ``A`` (assembled) to the bulk Jacobian of form ``a`` with Dirichlet rows ``bcs``.

        ``pattern`` identifies ``A`` and its nonzero pattern (it changes when the pattern grows).
        Collective.
        """
        key = (A.handle, pattern, tuple(id(bc) for bc in bcs))
        if self.enabled:
            inputs = self._snapshot()
            if self._unchanged(key, inputs):
                self._saved.copy(A, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
                self.copies += 1
                return
        A.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(A, a, bcs)
        A.assemble()
        self.assemblies += 1
        if self.enabled:
            self.release()
            self._saved = A.copy()
            self._key, self._inputs = key, inputs

    def release(self) -> None:
        """Free the saved copy (the next call assembles). Collective."""
        if self._saved is not None:
            self._saved.destroy()
            self._saved = None
            self._key = self._inputs = None
