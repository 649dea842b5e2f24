"""Thermal expansion in the mechanical form: the UFL helpers of thermo-elasticity.

docs/method.md §20.3. The small-strain thermal strain is ``eps_th = alpha (T - T0) I`` (CalculiX's
``*EXPANSION`` with the reference temperature ``ZERO``); the stress is the elastic stress of the
mechanical strain ``eps - eps_th``. ``T`` is any UFL expression: a temperature Function (the field
of a :class:`~dolfinx_ntf.ThermalContactProblem`), a Constant or a number.
"""

from __future__ import annotations

import ufl

from dolfinx_ntf.fem.elasticity import lame_parameters

__all__ = ["thermal_strain", "thermoelastic_stress"]


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
