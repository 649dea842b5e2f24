"""UFL helpers for axisymmetric solids: ``x[0] = r``, ``x[1] = z``, the body of revolution about z.

A 2D mesh of the meridian half-plane (``r >= 0``) and a 2D displacement ``u = (u_r, u_z)``. The
displacement gradient of the body of revolution is the 3x3 tensor::

    [[u_r,r  u_r,z  0      ],
     [u_z,r  u_z,z  0      ],
     [0      0      u_r / r]]

(:func:`axisymmetric_grad`; its last entry is the hoop strain), and a volume integral over the
body is ``∫ f 2 pi r dx`` over the mesh (:func:`axisymmetric_weight`), for the full 360 degrees:
forces, reactions and contact forces are those of the whole ring, like the spring areas of
``ContactPair(..., axisymmetric=True)``. The hoop term is evaluated at quadrature points, all at
``r > 0``: a mesh touching the axis needs no special treatment, only ``u_r = 0`` on the axis
(the symmetry condition, e.g. :func:`~dolfinx_ntf.fem.elasticity.component_bc` with component 0).

Small strain: ``inner(axisymmetric_stress(u, E, nu), axisymmetric_grad(v)) * w * dx``; finite
strain: ``inner(neo_hookean_stress(axisymmetric_deformation_gradient(u), E, nu),
axisymmetric_grad(v)) * w * dx`` with ``w = axisymmetric_weight(mesh)``.
"""

from __future__ import annotations

import math

import dolfinx.mesh
import ufl

from dolfinx_ntf.fem.elasticity import hooke_stress

__all__ = [
    "axisymmetric_deformation_gradient",
    "axisymmetric_grad",
    "axisymmetric_strain",
    "axisymmetric_stress",
    "axisymmetric_weight",
]


def axisymmetric_weight(mesh: dolfinx.mesh.Mesh) -> ufl.core.expr.Expr:
    """The weight ``2 pi r`` (``r = x[0]``) of volume integrals over the ring: ``f * w * dx``.

    Args:
        mesh: The 2D mesh of the meridian half-plane ``x[0] = r >= 0``.
    """
    if mesh.geometry.dim != 2:
        raise ValueError(
            f"an axisymmetric model needs a 2D mesh (x[0] = r, x[1] = z), got geometric "
            f"dimension {mesh.geometry.dim}"
        )
    return 2 * math.pi * ufl.SpatialCoordinate(mesh)[0]


def axisymmetric_grad(w: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """The 3x3 gradient of an axisymmetric vector field ``w = (w_r, w_z)`` (hoop entry ``w_r/r``).

    Args:
        w: A 2D vector field (displacement or test function) on the meridian mesh.
    """
    if ufl.shape(w) != (2,):
        raise ValueError(f"an axisymmetric field has 2 components (r, z), got shape {ufl.shape(w)}")
    r = ufl.SpatialCoordinate(ufl.domain.extract_unique_domain(w))[0]
    g = ufl.grad(w)
    return ufl.as_tensor([[g[0, 0], g[0, 1], 0], [g[1, 0], g[1, 1], 0], [0, 0, w[0] / r]])


def axisymmetric_strain(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Small strain (3x3: eps_rr, eps_zz, eps_rz and the hoop strain ``u_r / r``).

    Args:
        u: The displacement ``(u_r, u_z)``.
    """
    return ufl.sym(axisymmetric_grad(u))


def axisymmetric_stress(
    u: ufl.core.expr.Expr, youngs_modulus: float, poisson_ratio: float
) -> ufl.core.expr.Expr:
    """Small-strain isotropic stress (3x3, the hoop stress at [2, 2]) of the displacement ``u``.

    Args:
        u: The displacement ``(u_r, u_z)``.
        youngs_modulus: Young's modulus E > 0.
        poisson_ratio: Poisson's ratio, -1 < nu < 0.5.
    """
    return hooke_stress(axisymmetric_strain(u), youngs_modulus, poisson_ratio)


def axisymmetric_deformation_gradient(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """``F = I + axisymmetric_grad(u)`` (3x3; the hoop stretch ``1 + u_r/r``), for finite strain.

    Args:
        u: The displacement ``(u_r, u_z)``.
    """
    return ufl.Identity(3) + axisymmetric_grad(u)
