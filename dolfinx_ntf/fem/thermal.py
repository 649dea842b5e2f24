"""Thermal expansion in the mechanical form: the UFL helpers of thermo-elasticity.

docs/method.md §20.3. The small-strain thermal strain is ``eps_th = alpha (T - T0) I`` (CalculiX's
``*EXPANSION`` with the reference temperature ``ZERO``); the stress is the elastic stress of the
mechanical strain ``eps - eps_th``. ``T`` is any UFL expression: a temperature Function (the field
of a :class:`~dolfinx_ntf.ThermalContactProblem`), a Constant or a number.
"""

from __future__ import annotations

from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import lame_parameters

__all__ = ["CellTemperature", "thermal_strain", "thermoelastic_stress"]


class CellTemperature:
    """The mean of each cell's nodal temperatures (DG0), a linear map ``T_c = P T``.

    CalculiX's C3D8 takes the thermal strain from one temperature per element, the mean of its
    eight nodal temperatures (its value at the element centre; measured against ccx 2.20,
    docs/method.md §20.8). A mechanical residual written with ``T_c`` instead of ``T`` has
    that thermal strain; :class:`~dolfinx_ntf.ThermoMechanicalContact` updates ``T_c`` before
    each evaluation and chains ``∂F_u/∂T_c`` with :attr:`P` in the coupling block.

    Args:
        T: The temperature (a scalar Lagrange function).
    """

    def __init__(self, T: dolfinx.fem.Function) -> None:
        mesh = T.function_space.mesh
        Q, Q0 = T.function_space, compat.scalar_space(mesh, "DG", 0)
        #: The temperature; ``T_c`` holds its cell means.
        self.T = T
        self.T_c = dolfinx.fem.Function(Q0, name="cell_temperature")
        cell_map, node_map = Q0.dofmap.index_map, Q.dofmap.index_map
        num_owned = cell_map.size_local
        cells = compat.cell_dofs(Q)[:num_owned]
        rows = compat.cell_dofs(Q0)[:num_owned, 0]
        columns = node_map.local_to_global(cells.ravel().astype(np.int32)).reshape(cells.shape)
        order = np.argsort(rows)  # the owned cells' DG0 dofs are 0..num_owned-1
        width = cells.shape[1]
        #: ``P`` (owned cells x temperature dofs): ``1/n`` at each cell's ``n`` nodes.
        self.P = PETSc.Mat().createAIJ(
            ((num_owned, cell_map.size_global), (node_map.size_local, node_map.size_global)),
            nnz=(width, width),
            comm=mesh.comm,
        )
        self.P.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        indptr = np.arange(num_owned + 1, dtype=PETSc.IntType) * width
        self.P.setValuesCSR(
            indptr,
            columns[order].ravel().astype(PETSc.IntType),
            np.full(num_owned * width, 1.0 / width),
        )
        self.P.assemble()
        self.update()

    def update(self) -> None:
        """``T_c = P T`` from the current ``T``. Collective."""
        x = compat.petsc_vector(self.T)
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        y = compat.petsc_vector(self.T_c)
        self.P.mult(x, y)
        y.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def destroy(self) -> None:
        """Destroy the PETSc matrix. Collective."""
        self.P.destroy()


def thermal_strain(
    T: ufl.core.expr.Expr | float,
    alpha: ufl.core.expr.Expr | float,
    reference_temperature: ufl.core.expr.Expr | float,
    dim: int = 3,
) -> ufl.core.expr.Expr:
    """Isotropic thermal strain ``alpha (T - T0) I`` (dim x dim).

    Args:
        T: The temperature.
        alpha: Coefficient of thermal expansion.
        reference_temperature: T0, where the thermal strain vanishes.
        dim: Dimension of the identity (the displacement's).
    """
    return alpha * (T - reference_temperature) * ufl.Identity(dim)


def thermoelastic_stress(
    u: ufl.core.expr.Expr,
    T: ufl.core.expr.Expr | float,
    youngs_modulus: float,
    poisson_ratio: float,
    alpha: ufl.core.expr.Expr | float,
    reference_temperature: ufl.core.expr.Expr | float,
) -> ufl.core.expr.Expr:
    """Small-strain isotropic stress of the mechanical strain ``sym(grad u) - eps_th``.

    Args:
        u: The displacement (3D; 2D is plane strain as in
            :func:`~dolfinx_ntf.fem.elasticity.small_strain_stress`).
        T: The temperature.
        youngs_modulus: E.
        poisson_ratio: nu.
        alpha: Coefficient of thermal expansion.
        reference_temperature: T0.
    """
    dim = ufl.shape(u)[0]
    mu, lmbda = lame_parameters(youngs_modulus, poisson_ratio)
    eps = ufl.sym(ufl.grad(u)) - thermal_strain(T, alpha, reference_temperature, dim)
    return 2 * mu * eps + lmbda * ufl.tr(eps) * ufl.Identity(dim)
