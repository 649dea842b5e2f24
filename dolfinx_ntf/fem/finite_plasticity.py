"""Finite-strain J2 plasticity at quadrature points: the dolfinx glue of its kernel.

The kernel is :mod:`dolfinx_ntf.kernels.finite_plasticity`.
docs/method.md §21.7. :class:`FiniteStrainJ2Plasticity` evaluates the deformation gradient of the
displacement at the quadrature points, runs Simo's multiplicative return (CalculiX's ``*PLASTIC``
under NLGEOM) on all of them at once and keeps the first Piola-Kirchhoff stress (9 components,
row-major) and its derivative ``dP/dF`` (9x9) in quadrature-space Functions. The residual is
``inner(P, grad v) dx`` and the Jacobian ``inner(A grad du, grad v) dx``, total Lagrangian; the
history (``Cp^-1`` and the equivalent plastic strain) is committed as
:class:`~dolfinx_ntf.J2Plasticity`'s, through the problem's ``history`` (the
:class:`~dolfinx_ntf.contact.problem.MaterialHistory` role). 3D only.
"""

from __future__ import annotations

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.kernels.finite_plasticity import finite_return_map
from dolfinx_ntf.kernels.plasticity import IsotropicHardening
from dolfinx_ntf.kernels.strain_energy import green_lagrange_pair

from .plasticity import QuadratureLaw, _cell_rows

__all__ = ["FiniteStrainJ2Plasticity"]


def _flat(tensor: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """A 3x3 UFL tensor as a 9-vector, row-major."""
    return ufl.as_vector([tensor[i, j] for i in range(3) for j in range(3)])


class FiniteStrainJ2Plasticity(QuadratureLaw):
    """Simo's finite-strain J2 plasticity with isotropic hardening at the quadrature points.

    Args:
        u: The 3D displacement (``F = I + grad u``).
        youngs_modulus: E > 0.
        poisson_ratio: -1 < nu < 0.5.
        hardening: The yield stress table (true stress against equivalent plastic strain).
        quadrature_degree: Degree of the default rule the stresses live at; default
            ``2 * degree(u)`` (2x2x2 Gauss points on linear hexahedra, as CalculiX's C3D8).
        cell_tags: Cell tags and ``tag``: the law covers the cells tagged ``tag`` (default every
            cell), as :class:`~dolfinx_ntf.J2Plasticity`'s.
        tag: The value of this material's cells in ``cell_tags``.
        quadrature_rule: Custom ``(points, weights)`` on the reference cell, as
            :class:`~dolfinx_ntf.J2Plasticity`'s.

    Attributes:
        first_piola: P at the last evaluation, 9 components row-major (a quadrature Function).
        tangent: ``dP/dF`` at the last evaluation, 9x9 (a quadrature Function).
        dx: The measure of that rule over the law's cells.
    """

    def __init__(
        self,
        u: dolfinx.fem.Function,
        youngs_modulus: float,
        poisson_ratio: float,
        hardening: IsotropicHardening,
        *,
        quadrature_degree: int | None = None,
        cell_tags: compat.MeshTags | None = None,
        tag: int = 1,
        quadrature_rule: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> None:
        owner = "FiniteStrainJ2Plasticity"
        if ufl.shape(u) != (3,):
            raise ValueError(f"{owner}: u must be a 3D displacement, got shape {ufl.shape(u)}")
        self._set_up(
            owner,
            u,
            youngs_modulus,
            poisson_ratio,
            hardening,
            quadrature_degree,
            cell_tags,
            tag,
            quadrature_rule,
        )
        self.first_piola = dolfinx.fem.Function(self._space((9,)))
        self.tangent = dolfinx.fem.Function(self._space((9, 9)))
        self.first_piola.name = "first_piola"
        self._gradient = dolfinx.fem.Expression(ufl.Identity(3) + ufl.grad(u), self._points)
        n = self._num_points
        #: Committed inverse plastic right Cauchy-Green tensors ``Cp^-1``, (n, 3, 3).
        self.inverse_plastic_metric = np.tile(np.eye(3), (n, 1, 1))
        #: Committed equivalent plastic strain (CalculiX's PEEQ), (n,).
        self.equivalent_plastic_strain = np.zeros(n)
        self._trial = None
        self._trial_gradient = np.tile(np.eye(3), (n, 1, 1))
        self.evaluate()
        self._start_energy()

    # -- the forms -----------------------------------------------------------------------------

    def residual(self, v: ufl.Argument) -> ufl.Form:
        """The internal virtual work ``inner(P, grad v) dx`` at the quadrature points.

        Args:
            v: The test function of ``u``'s space.
        """
        return ufl.inner(self.first_piola, _flat(ufl.grad(v))) * self.dx

    def jacobian(self, du: ufl.Argument, v: ufl.Argument) -> ufl.Form:
        """The consistent Jacobian ``inner(dP/dF grad du, grad v) dx`` of :meth:`residual`.

        Args:
            du: The trial function of ``u``'s space.
            v: The test function.
        """
        return ufl.inner(ufl.dot(self.tangent, _flat(ufl.grad(du))), _flat(ufl.grad(v))) * self.dx

    # -- the history (the MaterialHistory role) -------------------------------------------------

    def deformation_gradient(self) -> np.ndarray:
        """``F`` of ``u`` at every local quadrature point of the law, (n, 3, 3)."""
        if self._cells.size == 0:
            return np.zeros((0, 3, 3))
        values = compat.evaluate_expression(self._gradient, self.u.function_space.mesh, self._cells)
        return np.asarray(values).reshape(-1, 3, 3)

    def evaluate(self) -> None:
        """Return-map the current ``u`` from the committed history into P and ``dP/dF``."""
        self._trial_gradient = self.deformation_gradient()
        result = finite_return_map(
            self._trial_gradient,
            self.inverse_plastic_metric,
            self.equivalent_plastic_strain,
            self.youngs_modulus,
            self.poisson_ratio,
            self.hardening,
        )
        self._store(self.first_piola, result.first_piola.reshape(-1, 9))
        self._store(self.tangent, result.tangent.reshape(-1, 81))
        self._trial = result

    def increment_converged(self) -> None:
        """Commit the history of the converged increment."""
        self.evaluate()
        self.inverse_plastic_metric = self._trial.inverse_plastic_metric.copy()
        self.equivalent_plastic_strain = self._trial.equivalent_plastic_strain.copy()
        self._commit_energy()

    def _work_pair(self) -> tuple[np.ndarray, np.ndarray]:
        """The second Piola-Kirchhoff stress and Green-Lagrange strain of the last evaluation."""
        return green_lagrange_pair(self._trial_gradient, self._trial.first_piola)

    def state_variables(self) -> np.ndarray:
        """Committed ``[alpha, (I - Cp^-1) xx, yy, zz, xy, xz, yz / 2]`` of every point, ``(n, 7)``.

        The equivalent plastic strain and ``(I - Cp^-1) / 2`` (tensor components): CalculiX's
        first seven internal state variables (``SDV``) of its finite-strain isotropic law
        (measured, docs/method.md §36).
        """
        strain = 0.5 * (np.eye(3) - self.inverse_plastic_metric)
        rows, cols = (0, 1, 2, 0, 0, 1), (0, 1, 2, 1, 2, 2)
        return np.column_stack([self.equivalent_plastic_strain, strain[:, rows, cols]])

    def cell_stresses(self, cells: np.ndarray) -> np.ndarray:
        """Cauchy stresses ``(n, q, 3, 3)`` of the last evaluation at the points of ``cells``.

        Args:
            cells: Local cells of the law (``ValueError`` for others).
        """
        return _cell_rows(self._cells, self._trial.cauchy, cells, "FiniteStrainJ2Plasticity")
