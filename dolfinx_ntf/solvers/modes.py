"""Natural frequencies and modes of a structure stiffened by its closed contact springs.

:func:`contact_modes` solves ``K phi = omega^2 M phi`` with SLEPc (shift-invert about a target)
for the lowest modes, ``K`` being the tangent of a :class:`~dolfinx_ntf.ContactProblem` at its
converged state: the bulk tangent plus every spring's tangent stiffness (closed springs stiffen,
open ones add nothing), as CalculiX's ``*FREQUENCY`` step after a static contact step
(docs/method.md §16). It is built of :func:`tangent_stiffness`, :func:`mass_matrix` and
:func:`solve_modes`.

Dirichlet dofs carry 1 on ``K``'s diagonal and 0 on ``M``'s (the dofs of dolfinx's modal demos):
their eigenvalues are infinite and shift-invert never returns them. Constraints (``*EQUATION``,
C3D20's face centres) reduce both matrices by the same elimination ``T`` as the Newton solve,
with zero mass on the dependent rows. All functions are collective on the mesh's communicator.
"""

from __future__ import annotations

import dataclasses
import math

from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.solvers.errors import ContactSolverError

__all__ = [
    "Modes",
    "bulk_stiffness",
    "contact_modes",
    "mass_matrix",
    "solve_modes",
    "tangent_stiffness",
]


@dataclasses.dataclass
class Modes:
    """Eigenpairs of ``K phi = lambda M phi``, lowest first.

    Attributes:
        eigenvalues: ``lambda = omega^2`` [rad^2/time^2], ascending.
        modes: Mode shapes, normalized to unit generalized mass ``phi^T M phi = 1``.
        mass: The mass matrix ``M`` of the eigenproblem (zero rows and columns at Dirichlet and
            dependent dofs: the products below are over the free dofs, as CalculiX's), kept for
            :meth:`participation_factors`; :meth:`destroy` frees it.
    """

    eigenvalues: np.ndarray
    modes: list[dolfinx.fem.Function]
    mass: PETSc.Mat | None = None

    @property
    def angular_frequencies(self) -> np.ndarray:
        """``omega = sqrt(lambda)`` [rad/time] (negative eigenvalues give ``-sqrt(-lambda)``)."""
        return np.sign(self.eigenvalues) * np.sqrt(np.abs(self.eigenvalues))

    @property
    def frequencies(self) -> np.ndarray:
        """``omega / (2 pi)`` [cycles/time]."""
        return self.angular_frequencies / (2.0 * math.pi)

    def participation_factors(self) -> np.ndarray:
        """``phi_i^T M r_k`` for the six rigid motions ``r_k`` about the origin, shape (n, 6).

        ``r`` are the unit translations along x, y, z and the unit rotations about the x, y, z
        axes through the origin (CalculiX's ``P A R T I C I P A T I O N   F A C T O R S``); the
        effective modal masses are their squares.
        """
        return self._rigid_products()[0]

    def total_effective_mass(self) -> np.ndarray:
        """``r_k^T M r_k`` of the six rigid motions: the sums of all modes' effective masses.

        CalculiX's ``T O T A L   E F F E C T I V E   M A S S`` (free dofs only).
        """
        return self._rigid_products()[1]

    def _rigid_products(self) -> tuple[np.ndarray, np.ndarray]:
        """``phi_i^T M r_k`` (modes, 6) and ``r_k^T M r_k`` (6). Collective."""
        if self.mass is None or not self.modes:
            raise ValueError("Modes: no mass matrix or no modes kept")
        V = self.modes[0].function_space
        work = self.mass.createVecLeft()
        factors, totals = np.zeros((len(self.modes), 6)), np.zeros(6)
        r = dolfinx.fem.Function(V)
        for k in range(6):
            r.interpolate(_rigid_motion(k))
            self.mass.mult(compat.petsc_vector(r), work)
            totals[k] = compat.petsc_vector(r).dot(work)
            for i, mode in enumerate(self.modes):
                factors[i, k] = compat.petsc_vector(mode).dot(work)
        work.destroy()
        return factors, totals

    def destroy(self) -> None:
        """Free the kept mass matrix. Collective."""
        if self.mass is not None:
            self.mass.destroy()
            self.mass = None


def _rigid_motion(k: int):
    """Unit translation (k < 3) or rotation about axis ``k - 3`` through the origin, at ``x``."""

    def motion(x: np.ndarray) -> np.ndarray:
        values = np.zeros((3, x.shape[1]))
        if k < 3:
            values[k] = 1.0
        else:
            axis = np.zeros(3)
            axis[k - 3] = 1.0
            values[:] = np.cross(axis, x.T).T
        return values

    return motion


def bulk_stiffness(problem: ContactProblem) -> PETSc.Mat:
    """The tangent of ``problem``'s bulk form alone at the current displacement. Collective.

    No contact springs (CalculiX 2.20's ``*FREQUENCY`` step has no contact elements, docs/method.md
    §16); Dirichlet and dependent dofs as in :func:`tangent_stiffness`. The caller destroys it.

    Args:
        problem: The problem whose Jacobian form, conditions and constraints apply.
    """
    validation.check_type(problem, ContactProblem, "bulk_stiffness: problem")
    A = dolfinx.fem.petsc.assemble_matrix(problem.a, problem.bcs)
    A.assemble()
    if problem.elimination is None:
        return A
    K = problem.elimination.project(A, diagonal=1.0)
    A.destroy()
    return K


def tangent_stiffness(problem: ContactProblem) -> PETSc.Mat:
    """The tangent ``K`` of ``problem`` at its current (converged) displacement. Collective.

    The bulk tangent of its Jacobian form plus the tangent of every spring of the current pairing;
    Dirichlet rows and columns are identity rows and columns, constrained dofs are eliminated
    (identity rows at the dependent dofs). The caller destroys the returned matrix.

    Args:
        problem: A problem solved to convergence (its springs are those of the last pairing).
    """
    validation.check_type(problem, ContactProblem, "tangent_stiffness: problem")
    if problem.states and problem.pairings == 0:
        raise ValueError(
            "tangent_stiffness: the problem has contact pairs but was never paired; solve it "
            "(StaticStep.run) before asking for its modes"
        )
    x = compat.petsc_vector(problem.u)
    A = problem.ensure_matrix()
    problem.form(x)
    problem.assemble_jacobian(x, A)
    return (A if problem.elimination is None else problem.reduced_matrix).copy()


def mass_matrix(problem: ContactProblem, mass: ufl.Form) -> PETSc.Mat:
    """The mass matrix of the bilinear form ``mass``, zero at Dirichlet and dependent dofs.

    Reduced like the problem's Jacobian (``T'^T M T'``) when there are constraints; zero rows and
    columns (diagonal too) at the removed dofs. The caller destroys it. Collective.

    Args:
        problem: The problem whose space, Dirichlet conditions and constraints apply.
        mass: A bilinear form on the displacement space, e.g. ``rho * inner(u, v) * dx``.
    """
    owner = "mass_matrix"
    if not isinstance(mass, ufl.Form) or len(mass.arguments()) != 2:
        raise TypeError(
            f"{owner}: mass must be a bilinear UFL form such as rho * inner(u, v) * dx, got "
            f"{validation.describe(mass)}"
        )
    V = problem.u.function_space
    for argument in mass.arguments():
        if argument.ufl_function_space() != V:
            raise ValueError(f"{owner}: the mass form's arguments must be on the problem's space")
    full = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(mass), problem.bcs, 0.0)
    full.assemble()
    if problem.elimination is None:
        return full
    M = problem.elimination.project(full, diagonal=0.0)
    full.destroy()
    return M


def solve_modes(
    K: PETSc.Mat,
    M: PETSc.Mat,
    V: dolfinx.fem.FunctionSpace,
    num_modes: int,
    *,
    shift: float = 0.0,
    tolerance: float = 1e-10,
    symmetric: bool = True,
    options_prefix: str = "ntf_modes_",
) -> tuple[np.ndarray, list[dolfinx.fem.Function]]:
    """The ``num_modes`` eigenpairs of ``K phi = lambda M phi`` nearest ``shift``, ascending.

    SLEPc's Krylov-Schur with shift-invert (MUMPS LU of ``K - shift M``). PETSc options under
    ``options_prefix`` override the choices (e.g. ``-ntf_modes_eps_tol``). Collective.

    Args:
        K: Stiffness, identity rows at removed dofs.
        M: Mass, zero rows at removed dofs.
        V: The space of the modes.
        num_modes: How many eigenpairs (>= 1).
        shift: Target ``lambda`` of the spectral transform (below the lowest wanted eigenvalue;
            a free body needs a negative one).
        tolerance: SLEPc's relative residual tolerance.
        symmetric: Solve as a generalized Hermitian problem (else non-Hermitian, e.g. with
            friction or the consistent unsymmetric spring tangent).
        options_prefix: PETSc options prefix of the solver.

    Returns:
        The eigenvalues and the modes (the vectors, unit ``phi^T M phi``).

    Raises:
        ContactSolverError: When fewer than ``num_modes`` pairs converge or one of them is
            complex (an unsymmetric ``K``).
    """
    from slepc4py import SLEPc  # imported here: only the modal analysis needs SLEPc

    if int(num_modes) < 1:
        raise ValueError(f"solve_modes: num_modes must be >= 1, got {num_modes!r}")
    comm = V.mesh.comm
    eps = SLEPc.EPS().create(comm)
    eps.setOptionsPrefix(options_prefix)
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP if symmetric else SLEPc.EPS.ProblemType.GNHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(int(num_modes))
    eps.setTolerances(tolerance, 500)
    eps.setTarget(shift)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_REAL)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(shift)
    ksp = st.getKSP()
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    eps.setFromOptions()
    eps.solve()
    converged = eps.getConverged()
    if converged < num_modes:
        eps.destroy()
        raise ContactSolverError(
            f"solve_modes: {converged} of {num_modes} eigenpairs converged (is K - shift M "
            "singular, e.g. a free body with shift 0?)"
        )
    eigenvalues = np.array([complex(eps.getEigenvalue(i)) for i in range(converged)])
    values = eigenvalues.real
    order = np.argsort(values)[:num_modes]
    complex_pairs = np.abs(eigenvalues.imag[order]) > 1e-8 * np.abs(values[order]).max()
    if np.any(complex_pairs):
        eps.destroy()
        raise ContactSolverError(
            f"solve_modes: eigenvalue {eigenvalues[order][complex_pairs][0]} of the lowest "
            f"{num_modes} is complex (an unsymmetric tangent, e.g. sliding friction, has no real "
            "modes there)"
        )
    modes = []
    for i in order:
        phi = dolfinx.fem.Function(V)
        vector = compat.petsc_vector(phi)
        eps.getEigenvector(int(i), vector)
        scale = _generalized_mass(M, vector)
        if scale <= 0.0:
            eps.destroy()
            raise ContactSolverError(f"solve_modes: mode {len(modes) + 1} has no mass")
        vector.scale(1.0 / math.sqrt(scale))
        modes.append(phi)
    eps.destroy()
    return values[order], modes


def _generalized_mass(M: PETSc.Mat, x: PETSc.Vec) -> float:
    """``x^T M x``."""
    work = M.createVecLeft()
    M.mult(x, work)
    value = x.dot(work)
    work.destroy()
    return float(np.real(value))


def contact_modes(
    problem: ContactProblem,
    mass: ufl.Form,
    num_modes: int = 10,
    *,
    shift: float | None = None,
    tolerance: float = 1e-10,
    symmetric: bool | None = None,
    options_prefix: str = "ntf_modes_",
    springs: bool = True,
) -> Modes:
    """The lowest natural frequencies and modes of ``problem``'s structure at its converged state.

    The stiffness is the problem's tangent at the current displacement
    (:func:`~dolfinx_ntf.solvers.modes.tangent_stiffness`: bulk tangent, stress stiffening of a
    large-strain form included, plus the closed springs' tangent); the mass is the form ``mass``
    (:func:`~dolfinx_ntf.solvers.modes.mass_matrix`). Collective.

    Args:
        problem: A :class:`~dolfinx_ntf.ContactProblem` solved to convergence (e.g. after
            :meth:`~dolfinx_ntf.solvers.steps.Step.run`).
        mass: Bilinear mass form on the displacement space, e.g. ``rho * inner(u, v) * dx``.
        num_modes: How many modes, lowest first.
        shift: Target of the shift-invert transform (below the lowest eigenvalue); by default
            just below zero, ``-1e-8 |K| / |M|`` (infinity norms), so that a free body (a zero
            eigenvalue) still factors.
        tolerance: SLEPc's relative residual tolerance.
        symmetric: Solve as a symmetric problem; by default when ``K`` is symmetric to round-off.
        options_prefix: PETSc options prefix of the eigensolver.
        springs: Include the contact springs' tangent (False: the bulk alone,
            :func:`~dolfinx_ntf.solvers.modes.bulk_stiffness`, as CalculiX 2.20's
            ``*FREQUENCY`` step).

    Returns:
        The :class:`Modes`; their mode Functions are mass-normalized and zero at Dirichlet dofs.
    """
    validation.check_type(problem, ContactProblem, "contact_modes: problem")
    K = tangent_stiffness(problem) if springs else bulk_stiffness(problem)
    M = mass_matrix(problem, mass)
    if symmetric is None:
        symmetric = _is_symmetric(K)
    if shift is None:
        shift = (
            -1e-8
            * K.norm(PETSc.NormType.NORM_INFINITY)
            / max(M.norm(PETSc.NormType.NORM_INFINITY), 1e-300)
        )
    V = problem.u.function_space
    try:
        values, modes = solve_modes(
            K,
            M,
            V,
            num_modes,
            shift=shift,
            tolerance=tolerance,
            symmetric=symmetric,
            options_prefix=options_prefix,
        )
    except Exception:
        M.destroy()
        raise
    finally:
        K.destroy()
    if problem.elimination is not None:
        for phi in modes:  # dependent dofs from the independent ones: phi = T phi
            problem.elimination.expand(compat.petsc_vector(phi))
    for phi in modes:
        phi.x.scatter_forward()
    return Modes(values, modes, M)


def _is_symmetric(K: PETSc.Mat) -> bool:
    """Whether ``K`` equals its transpose to round-off (relative to its largest row sum)."""
    transposed = K.transpose(PETSc.Mat())
    transposed.axpy(-1.0, K)
    difference = transposed.norm(PETSc.NormType.NORM_INFINITY)
    transposed.destroy()
    return difference <= 1e-10 * K.norm(PETSc.NormType.NORM_INFINITY)
