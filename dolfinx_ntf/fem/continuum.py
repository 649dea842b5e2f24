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
linear solve). :class:`~dolfinx_ntf.solvers.continuum.ContinuumIncrementSolver` lets the step
drivers (``StaticStep(set_load, ...).run(...)``, :func:`~dolfinx_ntf.run_steps`) load it by
increments, cut back after a failed solve and log a line per increment like for the springs.
"""

from __future__ import annotations

import logging
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
    check_in_plane,
)
from dolfinx_ntf.logs import newton_logger

__all__ = [
    "ContinuumNewton",
    "ContinuumNewtonError",
    "NewtonRecord",
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
    """``[a]_+ = max(a, 0)`` as ``(a + |a|)/2`` (differentiable by UFL almost everywhere).

    Args:
        a: A scalar UFL expression, e.g. the negative gap ``-g``.
    """
    return 0.5 * (a + abs(a))


def _negative_part(a: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    return 0.5 * (a - abs(a))


class RigidObstacle:
    """A :class:`~dolfinx_ntf.kernels.rigid.RigidSurface` as UFL gap and normal of ``u``.

    The surface's translation is a dolfinx Constant: call :meth:`update` with the step time when
    the surface moves (``motion``/``offset``), or list the obstacle in
    ``ContinuumIncrementSolver(newton, obstacles)`` and the steps do it
    (:mod:`dolfinx_ntf.solvers.continuum`).

    On a 2D mesh (docs/method.md §17.5) the surface must not depend on z, as for the springs: a
    plane with its normal in the xy-plane (a line), a cylinder along z or a sphere centred in
    z = 0 (a circle); gap and normal are then those of the xy-plane (2 components), a
    ``ufl_distance`` receives a 2-component vector, and a motion must stay in the plane.

    Args:
        surface: Plane, sphere, cylinder, or a :class:`~dolfinx_ntf.SignedDistanceSurface` with a
            ``ufl_distance`` (its normal is the UFL derivative of it).
        mesh: The mesh of ``u``.

    Raises:
        ValueError: On a 2D mesh, a surface or a motion that leaves the xy-plane.
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
        self.dim = mesh.geometry.dim
        if self.dim == 2:
            check_in_plane(surface, "RigidObstacle")
        self.translation = dolfinx.fem.Constant(mesh, np.zeros(self.dim, dtype=PETSc.ScalarType))
        self.update(0.0)

    def update(self, time: float) -> None:
        """Move the surface to its position at relative step time ``time``.

        Args:
            time: Relative step time, 0 to 1 (the steps pass the end of the increment).

        Raises:
            ValueError: On a 2D mesh, a translation with a z component.
        """
        c = self.surface.translation(time)
        if self.dim == 2 and c[2] != 0.0:
            raise ValueError(
                f"RigidObstacle: on a 2D mesh the surface must move in the xy-plane, but its "
                f"translation at step time {time:g} is {tuple(float(v) for v in c)}"
            )
        self.translation.value[:] = c[: self.dim]

    def _vector(self, values: np.ndarray) -> ufl.core.expr.Expr:
        """A constant vector of the mesh's dimension (the z component dropped in 2D)."""
        return ufl.as_vector([float(c) for c in values[: self.dim]])

    def _local(self, u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        return ufl.SpatialCoordinate(self.mesh) + u - self.translation

    def gap_and_normal(
        self, u: ufl.core.expr.Expr
    ) -> tuple[ufl.core.expr.Expr, ufl.core.expr.Expr]:
        """UFL ``(g, n)`` at the current position ``X + u``.

        Args:
            u: The displacement (a Function, or any vector expression of it).

        Returns:
            The signed gap (negative inside the surface) and the outward unit normal.
        """
        y = self._local(u)
        s = self.surface
        if isinstance(s, RigidPlane):
            n = self._vector(s.unit_normal)
            return ufl.dot(y - self._vector(s.point), n), n
        if isinstance(s, RigidSphere):
            r = y - self._vector(s.center)
            length = ufl.sqrt(ufl.dot(r, r))
            return s.sign * (length - s.radius), s.sign * r / length
        if isinstance(s, RigidCylinder):
            r = y - self._vector(s.point)
            if self.dim == 2:  # the axis is along z: the distance is the in-plane one
                radial = r
            else:
                a = self._vector(s.axis)
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
    """``ds(tag)`` with the contact quadrature degree (docs/method.md §15.2).

    Args:
        mesh: The mesh of ``u``.
        facet_tags: Facet tags that mark the potential contact boundary.
        tag: The tag of the contact boundary in ``facet_tags``.
        degree: Quadrature degree (high: the Macaulay bracket has a kink inside the facets at the
            contact edge, docs/method.md §15.2).
    """
    ds = ufl.Measure(
        "ds", domain=mesh, subdomain_data=facet_tags, metadata={"quadrature_degree": degree}
    )
    return ds(tag)


def penalty_pressure(
    u: ufl.core.expr.Expr, obstacle: RigidObstacle, penalty: float
) -> ufl.core.expr.Expr:
    """Penalty contact pressure ``K [-g(u)]_+`` (e.g. for :class:`~dolfinx_ntf.BoundaryPressure`).

    Args:
        u: The displacement.
        obstacle: The rigid surface.
        penalty: The penalty stiffness ``K`` (pressure per penetration).
    """
    g, _ = obstacle.gap_and_normal(u)
    return penalty * macaulay(-g)


def penalty_residual(
    u: ufl.core.expr.Expr,
    v: ufl.core.expr.Expr,
    obstacle: RigidObstacle,
    ds: ufl.Measure,
    penalty: float,
    weight: ufl.core.expr.Expr | float = 1.0,
) -> ufl.Form:
    """Penalty contact residual ``-∫ K [-g]_+ n·v w ds`` (add it to the bulk residual).

    Args:
        u: The displacement.
        v: The test function.
        obstacle: The rigid surface.
        ds: Measure of the contact boundary (:func:`contact_measure`).
        penalty: The penalty stiffness ``K`` (pressure per penetration).
        weight: The weight ``w`` of the boundary integral: 1, or the ring weight ``2 pi r`` of an
            axisymmetric model (:func:`~dolfinx_ntf.fem.axisymmetric.axisymmetric_weight`).
    """
    _, n = obstacle.gap_and_normal(u)
    return -penalty_pressure(u, obstacle, penalty) * ufl.dot(n, v) * weight * ds


def nitsche_gamma(
    gamma0: float, youngs_modulus: float, mesh: dolfinx.mesh.Mesh
) -> ufl.core.expr.Expr:
    """Nitsche's parameter ``gamma0 E / h`` with ``h`` the diameter of the facet's cell.

    Args:
        gamma0: Dimensionless factor (> 0); too small loses stability (no convergence).
        youngs_modulus: Young's modulus ``E`` of the body (> 0).
        mesh: The mesh of ``u`` (for ``h``).

    Raises:
        ValueError: ``gamma0`` or ``youngs_modulus`` not positive.
    """
    if not (gamma0 > 0 and youngs_modulus > 0):
        raise ValueError(f"need gamma0 > 0 and E > 0, got {gamma0} and {youngs_modulus}")
    return gamma0 * youngs_modulus / ufl.CellDiameter(mesh)


def _sigma_n(sigma: ufl.core.expr.Expr, n: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """``n·sigma n``; an axisymmetric 3x3 stress (hoop last) takes the meridian normal padded."""
    if ufl.shape(sigma)[0] == 3 and ufl.shape(n)[0] == 2:
        n = ufl.as_vector([n[0], n[1], 0.0])
    return ufl.dot(ufl.dot(sigma, n), n)


def nitsche_pressure(
    u: ufl.core.expr.Expr,
    obstacle: RigidObstacle,
    stress: typing.Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr],
    gamma: ufl.core.expr.Expr,
) -> ufl.core.expr.Expr:
    """Nitsche's contact pressure ``-[sigma_n(u) + gamma g]_-`` (the multiplier it enforces).

    Args:
        u: The displacement.
        obstacle: The rigid surface.
        stress: ``stress(w)``, the stress of a displacement.
        gamma: Nitsche parameter (:func:`nitsche_gamma`).
    """
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
    weight: ufl.core.expr.Expr | float = 1.0,
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
        weight: The weight of the boundary integrals: 1, or the ring weight ``2 pi r`` of an
            axisymmetric model (:func:`~dolfinx_ntf.fem.axisymmetric.axisymmetric_weight`, with
            ``stress`` the 3x3 axisymmetric one).

    Raises:
        ValueError: ``theta`` not 1, 0 or -1.
    """
    if theta not in (1, 0, -1):
        raise ValueError(f"nitsche_residual: theta must be 1, 0 or -1, got {theta!r}")
    g, n = obstacle.gap_and_normal(u)
    sn_u, sn_v = _sigma_n(stress(u), n), _sigma_n(stress(v), n)
    active = _negative_part(sn_u + gamma * g)
    form = active * (theta / gamma * sn_v + ufl.dot(n, v)) * weight * ds
    if theta:
        form += -theta / gamma * sn_u * sn_v * weight * ds
    return form


@dataclass
class NewtonRecord:
    """Iterations and time split of one :meth:`ContinuumNewton.solve`.

    Attributes:
        iterations: Newton updates until convergence.
        residual_norms: ``||R_k||`` of every iterate, the first one first.
        bulk_assembly: Seconds spent assembling the bulk residual and Jacobian.
        contact_assembly: Seconds spent assembling the contact residual and Jacobian.
        linear_solve: Seconds spent in the linear solver.
    """

    iterations: int = 0
    residual_norms: list[float] = field(default_factory=list)
    bulk_assembly: float = 0.0
    contact_assembly: float = 0.0
    linear_solve: float = 0.0


class ContinuumNewtonError(RuntimeError):
    """A failed :meth:`ContinuumNewton.solve`; ``kind`` says what a step can do about it.

    Args:
        message: What failed, with the residuals.
        kind: ``"convergence"`` (no convergence in ``max_it`` updates: a smaller increment may
            converge), ``"divergence"`` (non-finite residual or failed linear solve after an
            update: cut back further) or ``"input"`` (a non-finite residual before any update,
            or the solver's first linear solve failed: no smaller increment helps).
    """

    def __init__(self, message: str, kind: str) -> None:
        if kind not in ("convergence", "divergence", "input"):
            raise ValueError(f"ContinuumNewtonError: unknown kind {kind!r}")
        super().__init__(message)
        self.kind = kind


class ContinuumNewton:
    """Newton's method for ``F_bulk(u) + F_contact(u) = 0`` with a relative residual tolerance.

    Converged when ``||R_k|| <= rtol ||R_0||`` (``R_0``: the residual at the start of the solve,
    Dirichlet values included) or ``||R_k|| <= atol``. Bulk and contact forms are assembled
    separately (the contact form's couplings lie inside the bulk pattern) so that their times can
    be told apart; the linear solver is MUMPS LU by default.

    The step drivers (:class:`~dolfinx_ntf.StaticStep`, :func:`~dolfinx_ntf.run_steps`) drive it
    by increments with cutbacks through
    :class:`~dolfinx_ntf.solvers.continuum.ContinuumIncrementSolver`. Each iteration logs a line
    on ``"dolfinx_ntf.newton"`` (:func:`~dolfinx_ntf.log_progress` with ``iterations=True``).

    Args:
        bulk: Bulk residual (UFL, linear in the test function).
        contact: Contact residual (UFL), e.g. :func:`penalty_residual`.
        u: The displacement, the unknown of both forms.
        bcs: Dirichlet conditions.
        rtol: Convergence when the residual norm falls to ``rtol`` times the first one.
        atol: Or below ``atol`` (absolute, e.g. for a solve that starts converged).
        max_it: Newton updates before the solve gives up (a step then cuts back).
        petsc_options: Linear solver options (prefix ``ntf_continuum_``); default MUMPS LU.
        form_compiler_options: Options of the form compiler (FFCx), e.g. for the quadrature.
        jit_options: Options of the JIT compilation of the forms.
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
        self._contact_force = compat.create_vector(self.L[1])
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
        #: One record per converged solve.
        self.records: list[NewtonRecord] = []
        #: Residual norms of the last solve (also a failed one), the first one first.
        self.residual_norms: list[float] = []
        #: Nodes with a non-zero contact force after the last converged solve, all processes.
        self.contact_nodes = 0
        self._first_solve = True

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

    def _count_contact_nodes(self) -> int:
        """Owned nodes with a non-zero contact residual, summed over the processes. Collective."""
        f = self._contact_force
        with f.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(f, self.L[1])
        f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        bs = self.u.function_space.dofmap.index_map_bs
        local = int(np.count_nonzero(np.any(f.array.reshape(-1, bs) != 0, axis=1)))
        return self.u.function_space.mesh.comm.allreduce(local)

    def _not_finite(self, norm: float, updates: int) -> ContinuumNewtonError:
        """A non-finite residual: the input's fault before any update, a divergence after."""
        if updates:
            return ContinuumNewtonError(
                f"ContinuumNewton: residual not finite (norm {norm}) after {updates} updates",
                "divergence",
            )
        comm = self.u.function_space.mesh.comm
        bad_u = comm.allreduce(int(np.count_nonzero(~np.isfinite(self.u.x.array))))
        what = (
            f"the displacement has {bad_u} non-finite value(s) at the start of the solve (check "
            "the initial values and the prescribed displacements that set_load writes)"
            if bad_u
            else "the displacement is finite: check the loads, constants and material "
            "parameters of the residual forms and the obstacles' positions"
        )
        return ContinuumNewtonError(
            f"ContinuumNewton: residual not finite at the start; {what}", "input"
        )

    def _linear_solve(self, record: NewtonRecord) -> None:
        """``dx = J^{-1} R``; a failure: the setup's at the very first solve, a divergence later."""
        start = time.perf_counter()
        try:
            self.ksp.solve(self.b, self.dx)
            reason = self.ksp.getConvergedReason()
            what = f"linear solve failed (KSP reason {reason})" if reason < 0 else ""
        except PETSc.Error as error:
            what = f"linear solve failed (PETSc error {getattr(error, 'ierr', error)})"
        record.linear_solve += time.perf_counter() - start
        if not what and not np.isfinite(self.dx.norm()):
            what = "linear solve gave a non-finite correction (a singular Jacobian?)"
        if not what:
            return
        if self._first_solve and record.iterations == 0:
            raise ContinuumNewtonError(
                f"ContinuumNewton: {what} at the first Newton iteration: check the PETSc options "
                "(petsc_options, prefix 'ntf_continuum_'), the Dirichlet conditions (every body "
                "held) and that the forms are built on u",
                "input",
            )
        raise ContinuumNewtonError(
            f"ContinuumNewton: {what} at Newton iteration {record.iterations + 1}", "divergence"
        )

    def solve(self) -> NewtonRecord:
        """Solve from the current ``u``.

        Returns:
            The record of the solve (also appended to ``records``).

        Raises:
            ContinuumNewtonError: No convergence in ``max_it`` updates, a non-finite residual or
                a failed linear solve; its ``kind`` tells whether a smaller increment may help.
        """
        record = NewtonRecord()
        self.residual_norms = record.residual_norms
        x = compat.petsc_vector(self.u)
        verbose = newton_logger.isEnabledFor(logging.INFO)
        try:
            for _ in range(self.max_it + 1):
                self._assemble(record)
                norm = self.b.norm()
                record.residual_norms.append(norm)
                if not np.isfinite(norm):
                    raise self._not_finite(norm, record.iterations)
                converged = norm <= max(self.rtol * record.residual_norms[0], self.atol)
                if verbose:
                    newton_logger.info(_iteration_line(record, self.dx, converged))
                if converged:
                    self.records.append(record)
                    self.contact_nodes = self._count_contact_nodes()
                    return record
                if record.iterations == self.max_it:
                    break
                self._linear_solve(record)
                x.axpy(-1.0, self.dx)
                x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
                record.iterations += 1
        finally:
            self._first_solve = False
        raise ContinuumNewtonError(
            f"ContinuumNewton: no convergence in {self.max_it} iterations (residuals "
            f"{', '.join(f'{r:.3e}' for r in record.residual_norms[-4:])}; first "
            f"{record.residual_norms[0]:.3e})",
            "convergence",
        )

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.A, self.b, self._contact_force, self.dx, self.ksp):
            obj.destroy()


def _iteration_line(record: NewtonRecord, correction: PETSc.Vec, converged: bool) -> str:
    """The springs' per-iteration line: residual, its ratio to the first, correction. Collective."""
    norms = record.residual_norms
    line = f" iteration {record.iterations}: residual {norms[-1]:.3e}"
    if record.iterations:
        ratio = norms[-1] / norms[0] if norms[0] > 0 else 0.0
        line += f" ({ratio:.1e} of the first), correction {correction.norm():.3e}"
    return line + (", converged" if converged else "")
