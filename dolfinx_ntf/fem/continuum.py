"""UFL frictionless contact against rigid surfaces: penalty and Nitsche (docs/method.md §15.2).

The same rigid surfaces as the node-to-face rigid masters (``dolfinx_ntf.kernels.rigid``)
become UFL expressions of the current position ``x = X + u``: the gap ``g = phi(x - c)`` and the
normal ``n = grad phi``. With ``[a]_+ = (a + |a|)/2`` and ``[a]_- = (a - |a|)/2``:

- penalty: ``F_c(u; v) = -∫ K [-g]_+ n·v ds``, pressure ``K [-g]_+``;
- Nitsche (theta in {1, 0, -1}, ``gamma = gamma0 E / h``, ``sigma_n(w) = n·sigma(w) n``)::

      F_c = -theta/gamma ∫ sigma_n(u) sigma_n(v) ds
            + 1/gamma ∫ [sigma_n(u) + gamma g]_- (theta sigma_n(v) + gamma n·v) ds,

  pressure ``-[sigma_n(u) + gamma g]_-``.

Both are added to the bulk residual; :class:`ContinuumNewton` solves with a tolerance relative to
the first residual and records iterations and the time split (bulk assembly, contact assembly,
linear solve).
"""

from __future__ import annotations

import time
import typing
from dataclasses import dataclass, field

from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.kernels.rigid import (
    RigidCylinder,
    RigidPlane,
    RigidSphere,
    RigidSurface,
    SignedDistanceSurface,
)

__all__ = [
    "ContinuumNewton",
    "RigidObstacle",
    "contact_measure",
    "macaulay",
    "nitsche_gamma",
    "nitsche_pressure",
    "nitsche_residual",
    "penalty_pressure",
    "penalty_residual",
]

#: Quadrature degree of the contact integrals (P1 displacements). The Macaulay bracket has a kink
#: inside the facets at the contact edge, which low degrees integrate poorly: on the coarse Hertz
#: mesh the reaction differs from the accurately integrated pressure by 1.5e-2 (degree 2), 8.5e-3
#: (4) and 5e-4 (8) for the penalty, 6e-3, 4.7e-3 and 4e-4 for Nitsche (docs/method.md §15.2).
DEFAULT_QUADRATURE_DEGREE = 8


def macaulay(a: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """``[a]_+ = max(a, 0)`` as ``(a + |a|)/2`` (differentiable by UFL almost everywhere)."""
    return 0.5 * (a + abs(a))


def _negative_part(a: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    return 0.5 * (a - abs(a))


class RigidObstacle:
    """A :class:`~dolfinx_ntf.kernels.rigid.RigidSurface` as UFL gap and normal of ``u``.

    The surface's translation is a dolfinx Constant: call :meth:`update` with the step time when
    the surface moves (``motion``/``offset``).

    Args:
        surface: Plane, sphere, cylinder, or a :class:`~dolfinx_ntf.SignedDistanceSurface` with a
            ``ufl_distance`` (its normal is the UFL derivative of it).
        mesh: The mesh of ``u``.
    """

    def __init__(self, surface: RigidSurface, mesh: dolfinx.mesh.Mesh) -> None:
        if not isinstance(surface, RigidSurface):
            raise TypeError(f"RigidObstacle: surface must be a RigidSurface, got {surface!r}")
        if isinstance(surface, SignedDistanceSurface) and surface.ufl_distance is None:
            raise ValueError(
                "RigidObstacle: this SignedDistanceSurface has no ufl_distance (numpy callables "
                "cannot enter a UFL form)"
            )
        self.surface = surface
        self.mesh = mesh
        self.translation = dolfinx.fem.Constant(mesh, np.zeros(3, dtype=PETSc.ScalarType))
        self.update(0.0)

    def update(self, time: float) -> None:
        """Move the surface to its position at relative step time ``time``."""
        self.translation.value[:] = self.surface.translation(time)

    def _local(self, u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        return ufl.SpatialCoordinate(self.mesh) + u - self.translation

    def gap_and_normal(
        self, u: ufl.core.expr.Expr
    ) -> tuple[ufl.core.expr.Expr, ufl.core.expr.Expr]:
        """UFL ``(g, n)`` at the current position ``X + u``."""
        y = self._local(u)
        s = self.surface
        if isinstance(s, RigidPlane):
            n = ufl.as_vector([float(c) for c in s.unit_normal])
            return ufl.dot(y - ufl.as_vector([float(c) for c in s.point]), n), n
        if isinstance(s, RigidSphere):
            r = y - ufl.as_vector([float(c) for c in s.center])
            length = ufl.sqrt(ufl.dot(r, r))
            return s.sign * (length - s.radius), s.sign * r / length
        if isinstance(s, RigidCylinder):
            a = ufl.as_vector([float(c) for c in s.axis])
            r = y - ufl.as_vector([float(c) for c in s.point])
            radial = r - ufl.dot(r, a) * a
            length = ufl.sqrt(ufl.dot(radial, radial))
            return s.sign * (length - s.radius), s.sign * radial / length
        if isinstance(s, SignedDistanceSurface):
            yv = ufl.variable(y)
            phi = s.ufl_distance(yv)
            return phi, ufl.diff(phi, yv)
        raise TypeError(f"RigidObstacle: no UFL form of {type(s).__name__}")


def contact_measure(
    mesh: dolfinx.mesh.Mesh,
    facet_tags: compat.MeshTags,
    tag: int,
    degree: int = DEFAULT_QUADRATURE_DEGREE,
) -> ufl.Measure:
    """``ds(tag)`` with the contact quadrature degree (docs/method.md §15.2)."""
    ds = ufl.Measure(
        "ds", domain=mesh, subdomain_data=facet_tags, metadata={"quadrature_degree": degree}
    )
    return ds(tag)


def penalty_pressure(
    u: ufl.core.expr.Expr, obstacle: RigidObstacle, penalty: float
) -> ufl.core.expr.Expr:
    """Penalty contact pressure ``K [-g(u)]_+``."""
    g, _ = obstacle.gap_and_normal(u)
    return penalty * macaulay(-g)


def penalty_residual(
    u: ufl.core.expr.Expr,
    v: ufl.core.expr.Expr,
    obstacle: RigidObstacle,
    ds: ufl.Measure,
    penalty: float,
) -> ufl.Form:
    """Penalty contact residual ``-∫ K [-g]_+ n·v ds`` (add it to the bulk residual)."""
    _, n = obstacle.gap_and_normal(u)
    return -penalty_pressure(u, obstacle, penalty) * ufl.dot(n, v) * ds


def nitsche_gamma(
    gamma0: float, youngs_modulus: float, mesh: dolfinx.mesh.Mesh
) -> ufl.core.expr.Expr:
    """Nitsche's parameter ``gamma0 E / h`` with ``h`` the diameter of the facet's cell."""
    if not (gamma0 > 0 and youngs_modulus > 0):
        raise ValueError(f"need gamma0 > 0 and E > 0, got {gamma0} and {youngs_modulus}")
    return gamma0 * youngs_modulus / ufl.CellDiameter(mesh)


def _sigma_n(sigma: ufl.core.expr.Expr, n: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    return ufl.dot(ufl.dot(sigma, n), n)


def nitsche_pressure(
    u: ufl.core.expr.Expr,
    obstacle: RigidObstacle,
    stress: typing.Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr],
    gamma: ufl.core.expr.Expr,
) -> ufl.core.expr.Expr:
    """Nitsche's contact pressure ``-[sigma_n(u) + gamma g]_-`` (the multiplier it enforces)."""
    g, n = obstacle.gap_and_normal(u)
    return -_negative_part(_sigma_n(stress(u), n) + gamma * g)


def nitsche_residual(
    u: ufl.core.expr.Expr,
    v: ufl.core.expr.Expr,
    obstacle: RigidObstacle,
    ds: ufl.Measure,
    stress: typing.Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr],
    gamma: ufl.core.expr.Expr,
    theta: int = 1,
) -> ufl.Form:
    """Nitsche's frictionless contact residual (docs/method.md §15.2); add it to the bulk residual.

    Args:
        u: The displacement.
        v: The test function.
        obstacle: The rigid surface.
        ds: Measure of the contact boundary (:func:`contact_measure`).
        stress: ``stress(w)``, the (linear) stress of a displacement, used for ``u`` and ``v``.
        gamma: Nitsche parameter (:func:`nitsche_gamma`).
        theta: 1 (symmetric), 0 (incomplete), -1 (skew-symmetric).
    """
    if theta not in (1, 0, -1):
        raise ValueError(f"nitsche_residual: theta must be 1, 0 or -1, got {theta!r}")
    g, n = obstacle.gap_and_normal(u)
    sn_u, sn_v = _sigma_n(stress(u), n), _sigma_n(stress(v), n)
    active = _negative_part(sn_u + gamma * g)
    form = active * (theta / gamma * sn_v + ufl.dot(n, v)) * ds
    if theta:
        form += -theta / gamma * sn_u * sn_v * ds
    return form


@dataclass
class NewtonRecord:
    """Iterations and time split of one solve."""

    iterations: int = 0
    residual_norms: list[float] = field(default_factory=list)
    bulk_assembly: float = 0.0
    contact_assembly: float = 0.0
    linear_solve: float = 0.0


class ContinuumNewton:
    """Newton's method for ``F_bulk(u) + F_contact(u) = 0`` with a relative residual tolerance.

    Converged when ``||R_k|| <= rtol ||R_0||`` (``R_0``: the residual at the start of the solve,
    Dirichlet values included) or ``||R_k|| <= atol``. Bulk and contact forms are assembled
    separately (the contact form's couplings lie inside the bulk pattern) so that their times can
    be told apart; the linear solver is MUMPS LU by default.

    Args:
        bulk: Bulk residual (UFL, linear in the test function).
        contact: Contact residual (UFL), e.g. :func:`penalty_residual`.
        u: The displacement.
        bcs: Dirichlet conditions.
        rtol, atol, max_it: Convergence controls.
        petsc_options: Linear solver options (prefix ``ntf_continuum_``).
    """

    def __init__(
        self,
        bulk: ufl.Form,
        contact: ufl.Form,
        u: dolfinx.fem.Function,
        bcs: typing.Sequence[compat.DirichletBC] = (),
        *,
        rtol: float = 1e-10,
        atol: float = 1e-12,
        max_it: int = 30,
        petsc_options: dict | None = None,
        form_compiler_options: dict | None = None,
        jit_options: dict | None = None,
    ) -> None:
        if not (rtol > 0 and atol >= 0 and max_it >= 1):
            raise ValueError(f"need rtol > 0, atol >= 0, max_it >= 1; got {rtol}, {atol}, {max_it}")
        options = compat.jit_keywords(form_compiler_options, jit_options)
        du = ufl.TrialFunction(u.function_space)
        self.u, self.bcs = u, list(bcs)
        self.rtol, self.atol, self.max_it = rtol, atol, max_it
        self.L = [dolfinx.fem.form(f, **options) for f in (bulk, contact)]
        self.a = [dolfinx.fem.form(ufl.derivative(f, u, du), **options) for f in (bulk, contact)]
        self.A = dolfinx.fem.petsc.create_matrix(self.a[0])
        self.b = compat.create_vector(self.L[0])
        self.dx = self.A.createVecRight()
        self.ksp = PETSc.KSP().create(u.function_space.mesh.comm)
        self.ksp.setOptionsPrefix("ntf_continuum_")
        opts = PETSc.Options()
        settings = petsc_options or {
            "ksp_type": "preonly",
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "mumps",
        }
        for key, value in settings.items():
            opts[f"ntf_continuum_{key}"] = value
        self.ksp.setFromOptions()
        for key in settings:
            opts.delValue(f"ntf_continuum_{key}")
        self.ksp.setOperators(self.A)
        self.records: list[NewtonRecord] = []

    def _assemble(self, record: NewtonRecord) -> None:
        x = compat.petsc_vector(self.u)
        b, A = self.b, self.A
        start = time.perf_counter()
        with b.localForm() as local:
            local.set(0.0)
        A.zeroEntries()
        dolfinx.fem.petsc.assemble_vector(b, self.L[0])
        dolfinx.fem.petsc.apply_lifting(b, [self.a[0]], [self.bcs], [x], -1.0)
        dolfinx.fem.petsc.assemble_matrix(A, self.a[0], self.bcs)
        A.assemblyBegin(PETSc.Mat.AssemblyType.FLUSH)
        A.assemblyEnd(PETSc.Mat.AssemblyType.FLUSH)
        middle = time.perf_counter()
        dolfinx.fem.petsc.assemble_vector(b, self.L[1])
        dolfinx.fem.petsc.apply_lifting(b, [self.a[1]], [self.bcs], [x], -1.0)
        dolfinx.fem.petsc.assemble_matrix(A, self.a[1], self.bcs)
        A.assemble()
        end = time.perf_counter()
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(b, self.bcs, x, -1.0)
        record.bulk_assembly += middle - start
        record.contact_assembly += end - middle

    def solve(self) -> NewtonRecord:
        """Solve from the current ``u``; a failure raises ``RuntimeError`` with the residuals."""
        record = NewtonRecord()
        x = compat.petsc_vector(self.u)
        for _ in range(self.max_it + 1):
            self._assemble(record)
            norm = self.b.norm()
            record.residual_norms.append(norm)
            if not np.isfinite(norm):
                raise RuntimeError(
                    f"ContinuumNewton: residual not finite after {record.iterations} iterations"
                )
            if norm <= max(self.rtol * record.residual_norms[0], self.atol):
                self.records.append(record)
                return record
            if record.iterations == self.max_it:
                break
            start = time.perf_counter()
            self.ksp.solve(self.b, self.dx)
            record.linear_solve += time.perf_counter() - start
            if self.ksp.getConvergedReason() < 0:
                raise RuntimeError(
                    f"ContinuumNewton: linear solve failed (reason {self.ksp.getConvergedReason()})"
                )
            x.axpy(-1.0, self.dx)
            x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            record.iterations += 1
        raise RuntimeError(
            f"ContinuumNewton: no convergence in {self.max_it} iterations (residuals "
            f"{', '.join(f'{r:.3e}' for r in record.residual_norms[-4:])}; first "
            f"{record.residual_norms[0]:.3e})"
        )

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.A, self.b, self.dx, self.ksp):
            obj.destroy()
