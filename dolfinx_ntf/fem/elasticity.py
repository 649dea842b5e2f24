"""Small UFL and boundary-condition helpers for the bulk elasticity around contact.

Used by the demos, tests and scripts.
"""

from __future__ import annotations

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf import compat

__all__ = ["component_bc", "lame_parameters", "small_strain_stress"]


def lame_parameters(youngs_modulus: float, poisson_ratio: float) -> tuple[float, float]:
    """Lamé parameters (mu, lambda) of an isotropic material."""
    if not (youngs_modulus > 0 and -1 < poisson_ratio < 0.5):
        raise ValueError(
            f"isotropic elasticity needs E > 0 and -1 < nu < 0.5, got E = {youngs_modulus}, "
            f"nu = {poisson_ratio}"
        )
    mu = youngs_modulus / (2 * (1 + poisson_ratio))
    lmbda = youngs_modulus * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio))
    return mu, lmbda


def small_strain_stress(
    u: ufl.core.expr.Expr, youngs_modulus: float, poisson_ratio: float
) -> ufl.core.expr.Expr:
    """Small-strain isotropic linear elastic stress of the displacement ``u``.

    ``youngs_modulus`` and ``poisson_ratio`` give the Lamé parameters; for a 2D ``u`` this is
    plane strain (the in-plane stresses, per unit thickness).
    """
    mu, lmbda = lame_parameters(youngs_modulus, poisson_ratio)
    eps = ufl.sym(ufl.grad(u))
    return 2 * mu * eps + lmbda * ufl.tr(eps) * ufl.Identity(ufl.shape(u)[0])


def component_bc(
    V: dolfinx.fem.FunctionSpace, component: int, facets: np.ndarray
) -> compat.DirichletBC:
    """Zero displacement component ``component`` on the given facets (rollers, symmetry planes).

    ``V`` is the vector displacement space, ``facets`` the (local) facet indices.
    """
    Vc, _ = compat.component_space(V, component)
    dofs = dolfinx.fem.locate_dofs_topological(
        (V.sub(component), Vc), V.mesh.topology.dim - 1, facets
    )
    return dolfinx.fem.dirichletbc(dolfinx.fem.Function(Vc), dofs, V.sub(component))
