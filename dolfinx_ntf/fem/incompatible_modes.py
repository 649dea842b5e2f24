"""Incompatible-mode hexahedra (C3D8I) on a trilinear hexahedral mesh: :class:`IncompatibleModes`.

The dolfinx glue of ``kernels/incompatible_modes.py`` (docs/method.md §22). The bulk form stays
the trilinear hexahedron's small-strain elasticity (2x2x2 Gauss points, CalculiX's C3D8); this
element term adds, cell by cell, the condensed internal modes' correction ``-Kua Kaa^-1 Kau``
(a constant 24x24 matrix per cell, computed once) to the residual and the Jacobian through
:attr:`~dolfinx_ntf.ContactProblem.element_terms`. Each process evaluates its owned cells, in
global dofs; the couplings are the bulk form's own, so the matrix pattern needs nothing more.
Linear elasticity only (the correction is the small-strain one).
"""

from __future__ import annotations

import typing

from petsc4py import PETSc

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.fem.discrete_springs import GlobalBlocks
from dolfinx_ntf.kernels.incompatible_modes import Condensation, condensation, gauss_point_strains

__all__ = ["IncompatibleModes"]


class IncompatibleModes:
    """The incompatible modes of the cells of a trilinear hexahedral mesh, condensed per cell.

    Args:
        V: The displacement space: 3D vector Lagrange of degree 1 on hexahedra.
        mu: Shear modulus: one value or a DG0 Function (one value per cell).
        lmbda: Lamé's first parameter: one value or a DG0 Function.
        taylor: Taylor's ``det J0 / det J`` scaling of the modes (passes the patch test on any
            hexahedron, default); False reproduces CalculiX 2.20's C3D8I (docs/method.md §22).
        cells: Local cells that get the modes (default: all owned cells).

    Append it to ``problem.element_terms`` of a :class:`~dolfinx_ntf.ContactProblem` whose
    residual is the small-strain elasticity of the same ``mu`` and ``lmbda`` with the 2x2x2 Gauss
    rule (``quadrature_degree=2``). Collective construction (none of its methods communicate).
    """

    def __init__(
        self,
        V: dolfinx.fem.FunctionSpace,
        mu: float | dolfinx.fem.Function,
        lmbda: float | dolfinx.fem.Function,
        *,
        taylor: bool = True,
        cells: np.ndarray | None = None,
    ) -> None:
        mesh = V.mesh
        cell = mesh.topology.cell_type.name
        if cell != "hexahedron" or V.dofmap.index_map_bs != 3 or compat.space_degree(V) != 1:
            raise ValueError(
                "IncompatibleModes: needs a 3D vector Lagrange space of degree 1 on hexahedra, "
                f"got {cell} cells, block size {V.dofmap.index_map_bs}, "
                f"degree {compat.space_degree(V)}"
            )
        num_owned = mesh.topology.index_map(mesh.topology.dim).size_local
        if cells is None:
            cells = np.arange(num_owned, dtype=np.int32)
        cells = np.asarray(cells, dtype=np.int32)
        if np.any((cells < 0) | (cells >= num_owned)):
            raise ValueError("IncompatibleModes: cells must be owned local cells")
        #: Local cells with modes.
        self.cells = cells
        nodes = compat.cell_dofs(V)[cells]  # (C, 8) local block dofs, tensor order
        coordinates = V.tabulate_dof_coordinates()[nodes]
        self._local = (3 * nodes[:, :, None] + np.arange(3)).reshape(-1, 24)
        global_nodes = V.dofmap.index_map.local_to_global(nodes.ravel().astype(np.int32))
        self._global = (3 * global_nodes.reshape(-1, 8)[:, :, None] + np.arange(3)).reshape(-1, 24)
        #: The cells' condensation (correction, recovery of the modes, gradients).
        self.condensed: Condensation = condensation(
            coordinates, _cell_values(mu, cells), _cell_values(lmbda, cells), taylor=taylor
        )
        self._forces = np.zeros((0, 24))

    def node_couplings(self) -> np.ndarray:
        """No couplings beyond the bulk form's (the cells' own nodes): an empty (0, 2) array."""
        return np.zeros((0, 2), dtype=np.int64)

    def cell_displacements(self, x: PETSc.Vec) -> np.ndarray:
        """(C, 24) nodal displacements of the cells in ``x`` (ghost values must be current)."""
        with x.localForm() as local:
            return local.array_r[self._local]

    def evaluate(
        self, x: PETSc.Vec, bcs: typing.Sequence[compat.DirichletBC], *, tangent: bool = True
    ) -> GlobalBlocks:
        """The correction's forces (and matrix) of the cells at ``x``, in global dofs.

        Args:
            x: The displacement vector with current ghost values.
            bcs: Dirichlet conditions: their dofs get index -1 (rows and columns skipped).
            tangent: Return the matrices too.
        """
        forces = self.cell_forces(x)
        self._forces = forces
        dofs = self._global.copy()
        for bc in bcs:
            constrained, _ = bc.dof_indices()
            dofs[np.isin(self._local, constrained)] = -1
        return GlobalBlocks(dofs, self.condensed.correction if tangent else None, forces)

    def cell_forces(self, x: PETSc.Vec) -> np.ndarray:
        """(C, 24) the correction's internal forces of each cell at ``x`` (node-major)."""
        return np.einsum("cij,cj->ci", self.condensed.correction, self.cell_displacements(x))

    def strains(self, x: PETSc.Vec) -> np.ndarray:
        """(C, 8, 3, 3) small strains at the 2x2x2 Gauss points with the modes (``xi`` fastest).

        Args:
            x: The displacement vector (ghost values must be current).
        """
        return gauss_point_strains(self.condensed, self.cell_displacements(x))

    def force_sum(self) -> tuple[float, int]:
        """Sum of the absolute correction forces at the last evaluation and their count."""
        return float(np.abs(self._forces).sum()), int(self._forces.size)


def _cell_values(value: float | dolfinx.fem.Function, cells: np.ndarray) -> np.ndarray:
    """(C,) a constant or a DG0 Function's values on ``cells``."""
    if isinstance(value, dolfinx.fem.Function):
        return value.x.array[compat.cell_dofs(value.function_space)[cells, 0]]
    return np.full(cells.size, float(value))
