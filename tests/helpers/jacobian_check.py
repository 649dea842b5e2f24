"""The assembled Jacobian of a contact problem against central differences of its residual.

The pairing is held fixed (``problem.iteration`` past the re-pairing schedule), a random direction
with zero Dirichlet components is taken, and ``J w`` is compared with ``(F(u + h w) - F(u - h w)) /
2 h`` by the caller, relative to the largest entry of ``J w`` on the contact rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dolfinx_ntf import compat


@dataclass
class DirectionalCheck:
    """``J w`` and its central difference, on the process's rows, and the assembled ``J``."""

    matrix: object
    product: np.ndarray
    difference: np.ndarray
    contact_scale: float


def directional_derivative(problem, *, amplitude: float, h: float, seed: int) -> DirectionalCheck:
    """``J w`` and the central difference of the residual along a random ``w`` (size ``amplitude``).

    The iterate is restored afterwards (the pairing, the friction states and the increment start are
    those of the last solve).
    """
    problem.iteration = 100  # past the re-pairing schedule: the pairing stays fixed
    x = compat.petsc_vector(problem.u)
    base = x.copy()
    problem.form(x)
    A = problem.ensure_matrix()
    problem.J(x, A)
    direction = x.copy()
    direction.array[:] = (
        np.random.default_rng(seed).standard_normal(direction.array.size) * amplitude
    )
    bc_dofs = np.concatenate([bc.dof_indices()[0] for bc in problem.bcs])
    direction.array[bc_dofs] = 0.0
    product = A.createVecLeft()
    A.mult(direction, product)

    def residual(scale: float) -> np.ndarray:
        x.array[:] = base.array + scale * direction.array
        problem.u.x.scatter_forward()
        problem.form(x)
        b = x.copy()
        problem.F(x, b)
        return b.array.copy()

    difference = (residual(h) - residual(-h)) / (2 * h)
    x.array[:] = base.array
    problem.u.x.scatter_forward()
    components = problem.u.function_space.dofmap.index_map_bs
    nodes = problem.states[0].element_nodes
    contact_rows = np.unique(components * nodes[:, :, None] + np.arange(components))
    return DirectionalCheck(
        A, product.array.copy(), difference, float(np.abs(product.array[contact_rows]).max())
    )
