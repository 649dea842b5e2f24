"""Per-cell 2D formulations in one mesh: axisymmetric cells beside plane cells with a thickness.

CalculiX's quasi-axisymmetric models (its manual, "disk with holes") mix axisymmetric elements
with plane-stress elements in one meridian plane: the plane-stress cells stand for a part that is
not a full ring (a row of bolts, the web between holes) and carry the width of that part over
the whole circumference as their thickness. :class:`PlaneSections` says which cells are which
and gives the UFL pieces of one residual over the whole mesh (docs/method.md §26):

- the volume weight: ``2 pi r`` on axisymmetric cells, the thickness ``t`` on plane cells
  (:meth:`PlaneSections.weight`), so that every force is the whole ring's;
- the 3x3 displacement gradient (:meth:`PlaneSections.grad`): the hoop entry ``w_r / r`` on
  axisymmetric cells, 0 on plane-strain cells, and on plane-stress cells the strain that makes
  ``sigma_zz = 0``;
- the deformation gradient of finite strain (:meth:`PlaneSections.deformation_gradient`), with the
  stretch ``sqrt(1 + 2 E_zz)`` of the plane-stress condition ``S_zz = 0`` for St.Venant-Kirchhoff.

Small strain: ``inner(sigma(H), sections.grad(v)) * sections.weight() * dx`` with
``H = sections.grad(u, mu, lmbda)``. The choice is a DG0 indicator per cell, so one form and one
mesh serve all cells (no mixed meshes, no subdomain integrals).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat

__all__ = ["PlaneSections"]


@dataclass(frozen=True, eq=False)
class PlaneSections:
    """Which cells of a 2D mesh are axisymmetric, plane stress or plane strain, and their thickness.

    Build it with :meth:`from_cells`. Attributes are DG0 functions (one value per cell):

    Attributes:
        axisymmetric: 1 on axisymmetric cells (``x[0] = r``, ``x[1]`` the axis), else 0.
        plane_stress: 1 on plane-stress cells, else 0 (plane cells with 0 are plane strain).
        thickness: The out-of-plane thickness of plane cells (the whole circumference's width in
            a quasi-axisymmetric model); 1 on axisymmetric cells (not used there).
    """

    axisymmetric: dolfinx.fem.Function
    plane_stress: dolfinx.fem.Function
    thickness: dolfinx.fem.Function

    @classmethod
    def from_cells(
        cls,
        mesh: dolfinx.mesh.Mesh,
        *,
        axisymmetric: Sequence[int] | np.ndarray = (),
        plane_stress: Sequence[int] | np.ndarray = (),
        thickness: float | np.ndarray = 1.0,
    ) -> PlaneSections:
        """The sections of ``mesh`` from local cell indices (owned and ghost cells).

        Args:
            mesh: A 2D mesh (geometric dimension 2).
            axisymmetric: Local cells that are axisymmetric (``x[0] = r >= 0``).
            plane_stress: Local cells that are plane stress; every other cell that is not
                axisymmetric is plane strain.
            thickness: The plane cells' thickness, one value or one per local cell (``> 0``).

        Raises:
            ValueError: a 3D mesh, a cell in both lists or out of range, a thickness that is
                not positive and finite or of the wrong length.
        """
        if mesh.geometry.dim != 2:
            raise ValueError(
                f"PlaneSections needs a 2D mesh, got geometric dimension {mesh.geometry.dim}"
            )
        index_map = mesh.topology.index_map(mesh.topology.dim)
        num_cells = index_map.size_local + index_map.num_ghosts
        axi = _cells(axisymmetric, num_cells, "axisymmetric")
        stress = _cells(plane_stress, num_cells, "plane_stress")
        both = np.intersect1d(axi, stress)
        if both.size:
            raise ValueError(
                f"PlaneSections: cell {int(both[0])} is both axisymmetric and plane stress"
            )
        t = np.broadcast_to(np.asarray(thickness, dtype=np.float64), (num_cells,)).copy()
        if t.size and not np.all(np.isfinite(t) & (t > 0.0)):
            bad = int(np.argmax(~(np.isfinite(t) & (t > 0.0))))
            raise ValueError(f"PlaneSections: thickness of cell {bad} is {t[bad]}; must be > 0")
        Q = compat.scalar_space(mesh, "DG", 0)
        dofs = compat.cell_dofs(Q)[:num_cells, 0]
        flags = []
        for name, cells in (("axisymmetric", axi), ("plane_stress", stress)):
            f = dolfinx.fem.Function(Q, name=name)
            f.x.array[dofs[cells]] = 1.0
            flags.append(f)
        t[axi] = 1.0
        t_function = dolfinx.fem.Function(Q, name="thickness")
        t_function.x.array[dofs] = t
        return cls(flags[0], flags[1], t_function)

    def weight(self) -> ufl.core.expr.Expr:
        """``2 pi r`` on axisymmetric cells, the thickness on plane cells: ``f * weight * dx``."""
        mesh = self.axisymmetric.function_space.mesh
        r = ufl.SpatialCoordinate(mesh)[0]
        a = self.axisymmetric
        return a * 2 * math.pi * r + (1 - a) * self.thickness

    def grad(
        self,
        w: ufl.core.expr.Expr,
        mu: ufl.core.expr.Expr | None = None,
        lmbda: ufl.core.expr.Expr | None = None,
    ) -> ufl.core.expr.Expr:
        """The 3x3 small-strain gradient of a 2D field ``w`` on every cell.

        zz entry: ``w_r / r`` (axisymmetric), 0 (plane strain), and on plane-stress cells, given
        the Lamé parameters, ``-lambda/(lambda + 2 mu) (w_x,x + w_y,y)`` (``sigma_zz = 0``);
        without them 0 there (the test function: ``sigma_zz`` is 0 so its zz entry does no work).

        Args:
            w: A 2D vector field (displacement or test function).
            mu: Lamé's shear modulus (a number or DG0 function), with ``lmbda``.
            lmbda: Lamé's first parameter.
        """
        g = ufl.grad(w)
        r = ufl.SpatialCoordinate(self.axisymmetric.function_space.mesh)[0]
        zz = self.axisymmetric * w[0] / r
        if mu is not None and lmbda is not None:
            zz = zz + self.plane_stress * (-lmbda / (lmbda + 2 * mu)) * (g[0, 0] + g[1, 1])
        return ufl.as_tensor([[g[0, 0], g[0, 1], 0], [g[1, 0], g[1, 1], 0], [0, 0, zz]])

    def deformation_gradient(
        self, u: ufl.core.expr.Expr, mu: ufl.core.expr.Expr, lmbda: ufl.core.expr.Expr
    ) -> ufl.core.expr.Expr:
        """The 3x3 ``F`` of finite strain: hoop stretch ``1 + u_r/r``, 1 or the plane-stress one.

        On plane-stress cells ``F_zz = sqrt(1 + 2 E_zz)`` with ``E_zz = -lambda/(lambda + 2 mu)
        (E_xx + E_yy)`` of the in-plane Green-Lagrange strain: St.Venant-Kirchhoff's ``S_zz = 0``.

        Args:
            u: The 2D displacement.
            mu: Lamé's shear modulus.
            lmbda: Lamé's first parameter.
        """
        g = ufl.grad(u)
        F2 = ufl.Identity(2) + g
        E2 = 0.5 * (F2.T * F2 - ufl.Identity(2))
        e_zz = -lmbda / (lmbda + 2 * mu) * (E2[0, 0] + E2[1, 1])
        r = ufl.SpatialCoordinate(self.axisymmetric.function_space.mesh)[0]
        a, s = self.axisymmetric, self.plane_stress
        zz = 1 + a * u[0] / r + s * (ufl.sqrt(1 + 2 * e_zz) - 1)
        return ufl.as_tensor([[F2[0, 0], F2[0, 1], 0], [F2[1, 0], F2[1, 1], 0], [0, 0, zz]])


def _cells(cells: Sequence[int] | np.ndarray, num_cells: int, what: str) -> np.ndarray:
    """Unique int32 cell indices in ``0..num_cells-1`` (a ``ValueError`` naming ``what``)."""
    array = np.asarray(cells).ravel()
    if array.size and not np.issubdtype(array.dtype, np.integer):
        raise ValueError(f"PlaneSections: {what} must be integer cell indices")
    array = np.unique(array.astype(np.int64))
    if array.size and (array[0] < 0 or array[-1] >= num_cells):
        bad = int(array[0] if array[0] < 0 else array[-1])
        raise ValueError(
            f"PlaneSections: {what} cell {bad} is outside 0..{num_cells - 1} (the local cells)"
        )
    return array.astype(np.int32)
