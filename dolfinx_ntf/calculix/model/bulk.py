"""The bulk material of a deck: Lamé parameters per cell and the stresses of its kinematics.

Small-strain isotropic elasticity, or total-Lagrangian St.Venant-Kirchhoff with ``NLGEOM``
(switched by a Constant when a deck has both kinds of steps).
"""

from __future__ import annotations

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat

from ..deck import Deck, ElementBlock

__all__ = ["density", "lame", "plane_stress_factor", "stresses"]


def lame(
    deck: Deck, block: ElementBlock, mesh: dolfinx.mesh.Mesh, element_cell: np.ndarray
) -> tuple[dolfinx.fem.Function, dolfinx.fem.Function]:
    """Lamé parameters ``mu, lambda`` per cell (DG0) from each section's ``*ELASTIC`` material."""
    Q = compat.scalar_space(mesh, "DG", 0)
    mu, lmbda = dolfinx.fem.Function(Q, name="mu"), dolfinx.fem.Function(Q, name="lambda")
    for section in deck.sections:
        young, nu = deck.materials[section.material].elastic
        members = np.unique(deck.elsets[section.elset])
        members = members[np.isin(members, block.ids)]
        order = np.argsort(block.ids)
        rows = order[np.searchsorted(block.ids, members, sorter=order)]
        cells = element_cell[rows]
        dofs = compat.cell_dofs(Q)[cells[cells >= 0], 0]
        mu.x.array[dofs] = young / (2 * (1 + nu))
        lmbda.x.array[dofs] = young * nu / ((1 + nu) * (1 - 2 * nu))
    return mu, lmbda


def density(
    deck: Deck, block: ElementBlock, mesh: dolfinx.mesh.Mesh, element_cell: np.ndarray
) -> tuple[dolfinx.fem.Function, np.ndarray]:
    """Density per cell (DG0) from each section's ``*DENSITY``, and which elements have one.

    Returns the density (0 where a material has none) and a flag per element of ``block``;
    a temperature-dependent or non-positive ``*DENSITY`` is a ``ValueError`` naming its section.
    """
    Q = compat.scalar_space(mesh, "DG", 0)
    rho = dolfinx.fem.Function(Q, name="density")
    given = np.zeros(block.ids.size, dtype=bool)
    order = np.argsort(block.ids)
    for section in deck.sections:
        data = deck.materials[section.material].extra.get("*DENSITY")
        if not data:
            continue
        if len(data) != 1 or data[0][0] is None or data[0][0] <= 0.0:
            raise ValueError(
                f"{section.location}: material {section.material} needs one positive *DENSITY "
                "(temperature-dependent densities are not supported)"
            )
        members = np.unique(deck.elsets[section.elset])
        members = members[np.isin(members, block.ids)]
        rows = order[np.searchsorted(block.ids, members, sorter=order)]
        given[rows] = True
        cells = element_cell[rows]
        rho.x.array[compat.cell_dofs(Q)[cells[cells >= 0], 0]] = data[0][0]
    return rho, given


def stresses(
    u: dolfinx.fem.Function,
    mu: dolfinx.fem.Function,
    lmbda: dolfinx.fem.Function,
    nlgeom: dolfinx.fem.Constant | float,
    thermal_strain: ufl.core.expr.Expr | None = None,
) -> tuple[ufl.core.expr.Expr, ufl.core.expr.Expr, ufl.core.expr.Expr]:
    """Deformation gradient, first Piola-Kirchhoff and Cauchy stress.

    ``nlgeom`` 0 gives small-strain elasticity, 1 St.Venant-Kirchhoff. A ``thermal_strain``
    ``eps_th`` is subtracted from the displacement gradient before the strain is formed: the
    strain is that of ``H - eps_th`` (with ``nlgeom`` its Green-Lagrange strain, as ccx 2.20's
    measured: docs/method.md §20.8), the deformation gradient that of ``H``.
    """
    H = ufl.grad(u)
    Id = ufl.Identity(3)
    F = Id + nlgeom * H
    Hm = H if thermal_strain is None else H - thermal_strain
    E = ufl.sym(Hm) + 0.5 * nlgeom * Hm.T * Hm
    S = 2 * mu * E + lmbda * ufl.tr(E) * Id
    P = F * S
    return F, P, P * F.T / ufl.det(F)


def plane_stress_factor(
    mu: dolfinx.fem.Function, lmbda: dolfinx.fem.Function
) -> ufl.core.expr.Expr:
    """``-lambda / (lambda + 2 mu)``: the plane-stress strain ``e_zz`` per ``e_xx + e_yy``."""
    return -lmbda / (lmbda + 2 * mu)
