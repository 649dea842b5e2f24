"""Small UFL and boundary-condition helpers for the bulk elasticity around contact.

Used by the demos, tests and scripts. In 2D, :func:`small_strain_stress` is plane strain and
:func:`plane_stress_stress` plane stress (both per unit thickness: a thickness ``t`` multiplies the
whole residual, and ``ContactPair.thickness`` the spring areas); axisymmetric models have their own
module, :mod:`dolfinx_ntf.fem.axisymmetric`. :func:`neo_hookean_stress` is the finite-strain law
of all three (3D, plane strain, axisymmetric).
"""

from __future__ import annotations

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf import compat

__all__ = [
    "component_bc",
    "hooke_stress",
    "lame_parameters",
    "neo_hookean_stress",
    "plane_stress_stress",
    "small_strain_stress",
]


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
    return hooke_stress(ufl.sym(ufl.grad(u)), youngs_modulus, poisson_ratio)


def hooke_stress(
    strain: ufl.core.expr.Expr, youngs_modulus: float, poisson_ratio: float
) -> ufl.core.expr.Expr:
    """Isotropic Hooke's law ``2 mu eps + lambda tr(eps) I`` of a (2x2 or 3x3) strain tensor.

    Args:
        strain: The small-strain tensor (e.g.
            :func:`~dolfinx_ntf.fem.axisymmetric.axisymmetric_strain`, 3x3 with the hoop strain).
        youngs_modulus: Young's modulus E > 0.
        poisson_ratio: Poisson's ratio, -1 < nu < 0.5.
    """
    mu, lmbda = lame_parameters(youngs_modulus, poisson_ratio)
    return 2 * mu * strain + lmbda * ufl.tr(strain) * ufl.Identity(ufl.shape(strain)[0])


def plane_stress_stress(
    u: ufl.core.expr.Expr, youngs_modulus: float, poisson_ratio: float
) -> ufl.core.expr.Expr:
    """Plane-stress (sigma_zz = 0) small-strain stress of a 2D displacement ``u``.

    ``sigma = E/(1 - nu^2) ((1 - nu) eps + nu tr(eps) I)``: Hooke's law with the reduced Lamé
    parameter ``lambda* = 2 mu lambda / (lambda + 2 mu)``; the out-of-plane strain is
    ``eps_zz = -nu/(1 - nu) tr(eps)``. Per unit thickness: multiply the residual by the thickness
    ``t`` and give the contact pairs ``ContactPair(..., thickness=t)``.

    Args:
        u: The 2D displacement.
        youngs_modulus: Young's modulus E > 0.
        poisson_ratio: Poisson's ratio, -1 < nu < 0.5.
    """
    if ufl.shape(u) != (2,):
        raise ValueError(f"plane stress needs a 2D displacement, got shape {ufl.shape(u)}")
    mu, lmbda = lame_parameters(youngs_modulus, poisson_ratio)
    eps = ufl.sym(ufl.grad(u))
    return 2 * mu * eps + (2 * mu * lmbda / (lmbda + 2 * mu)) * ufl.tr(eps) * ufl.Identity(2)


def neo_hookean_stress(
    deformation_gradient: ufl.core.expr.Expr, youngs_modulus: float, poisson_ratio: float
) -> ufl.core.expr.Expr:
    """First Piola-Kirchhoff stress of a compressible neo-Hookean solid (finite strain).

    ``P = mu (F - F^-T) + lambda ln(J) F^-T`` with ``J = det F`` and the Lamé parameters of
    ``E`` and ``nu`` (the small-strain limit is Hooke's law). ``F`` is 3x3 in 3D and in
    axisymmetry (:func:`~dolfinx_ntf.fem.axisymmetric.axisymmetric_deformation_gradient`, with
    the hoop stretch ``1 + u_r/r``), 2x2 in plane strain (``F_zz = 1``: ``J`` and ``F^-T``
    restricted to the plane are the 3D ones). The residual is ``inner(P, grad(v)) dx`` on the
    reference configuration (axisymmetric: ``inner(P, axisymmetric_grad(v)) 2 pi r dx``).

    Args:
        deformation_gradient: ``F = I + grad(u)`` (2x2 or 3x3).
        youngs_modulus: Young's modulus E > 0 (small-strain limit).
        poisson_ratio: Poisson's ratio, -1 < nu < 0.5 (small-strain limit).
    """
    mu, lmbda = lame_parameters(youngs_modulus, poisson_ratio)
    F = deformation_gradient
    F_inv_T = ufl.inv(F).T
    return mu * (F - F_inv_T) + lmbda * ufl.ln(ufl.det(F)) * F_inv_T


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
