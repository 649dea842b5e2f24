"""The bulk Jacobian is copied, not re-assembled, only while nothing it depends on changes, and the
copy is the matrix a fresh assembly gives (docs/method.md §7.5)."""

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest
from helpers import (
    LOWER_TOP,
    POISSON_RATIO,
    UPPER_BOTTOM,
    YOUNGS_MODULUS,
    elastic_residual,
    punch_problem,
)

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import lame_parameters

COMM = MPI.COMM_WORLD


def _problem(form, **options):
    """The helpers' punch with the bulk residual ``form(u, v, facet_tags, pressure)``, loaded and
    displaced a little so that springs and stresses are not zero."""
    punch, pressure, ft = punch_problem(comm=COMM)
    u = punch.u
    F = form(u, ufl.TestFunction(u.function_space), ft, pressure)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)),
    )
    problem = ntf.ContactProblem(F, u, [pair], punch.bcs, **options)
    punch.destroy()
    pressure.value = 10.0
    u.x.array[:] = -1e-3 * np.abs(np.sin(np.arange(u.x.array.size)))
    u.x.scatter_forward()
    problem.begin_increment(1.0)
    return problem


def _scaled(u, v, ft, pressure):
    """Small-strain elasticity whose stiffness is a Constant (named ``stiffness``)."""
    scale = dolfinx.fem.Constant(u.function_space.mesh, 1.0)
    scale.name = "stiffness"
    return (
        elastic_residual(u, v, ft, pressure)
        + (scale - 1.0) * ufl.inner(ufl.sym(ufl.grad(u)), ufl.grad(v)) * ufl.dx
    )


def _kirchhoff(u, v, ft, pressure):
    """St.Venant-Kirchhoff: its tangent depends on u."""
    mu, lmbda = lame_parameters(YOUNGS_MODULUS, POISSON_RATIO)
    F = ufl.Identity(3) + ufl.grad(u)
    E = 0.5 * (F.T * F - ufl.Identity(3))
    S = lmbda * ufl.tr(E) * ufl.Identity(3) + 2 * mu * E
    return ufl.inner(F * S, ufl.grad(v)) * ufl.dx


def _jacobian(problem):
    """The problem's Jacobian at the current ``u`` (springs evaluated first), as a new matrix."""
    x = compat.petsc_vector(problem.u)
    A = problem.ensure_matrix()
    problem.form(x)
    problem.J(x, A)
    return A.copy()


def _difference(A, B):
    C = A.copy()
    C.axpy(-1.0, B, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
    norm = C.norm(PETSc.NormType.FROBENIUS)
    C.destroy()
    return norm


@pytest.mark.mpi
def test_linear_bulk_is_copied_and_equals_a_fresh_assembly():
    """Small strain: the second Jacobian copies the first's bulk part; it is bit-identical to the
    Jacobian of a problem that assembles every time."""
    problem = _problem(elastic_residual)
    reference = _problem(elastic_residual, reuse_bulk_jacobian=False)
    assert problem.bulk_jacobian.enabled and not reference.bulk_jacobian.enabled
    matrices = [_jacobian(p) for p in (problem, reference) for _ in range(2)]
    assert (problem.bulk_jacobian.assemblies, problem.bulk_jacobian.copies) == (1, 1)
    assert reference.bulk_jacobian.copies == 0
    assert matrices[0].norm() > 0.0
    # Newton iterations 1 and 2 (the second re-pairs) of both problems
    assert _difference(matrices[0], matrices[2]) == 0.0
    assert _difference(matrices[1], matrices[3]) == 0.0
    for matrix in matrices:
        matrix.destroy()
    problem.destroy()
    reference.destroy()


@pytest.mark.mpi
def test_changed_inputs_are_assembled_again():
    """A changed stiffness Constant, moved mesh nodes and new Dirichlet conditions each make the
    next Jacobian a fresh assembly, equal to that of a problem that never copies."""
    problem = _problem(_scaled)
    reference = _problem(_scaled, reuse_bulk_jacobian=False)
    for target in (problem, reference):  # the same Newton iterations on both
        _jacobian(target).destroy()
    for change in ("constant", "geometry", "bcs"):
        for target in (problem, reference):
            if change == "constant":
                (scale,) = [
                    c
                    for c in target.bulk_jacobian._constants
                    if getattr(c, "name", None) == "stiffness"
                ]
                scale.value = 2.0
            elif change == "geometry":
                target.u.function_space.mesh.geometry.x[:, 2] *= 1.001
            else:
                target.set_bcs(target.bcs[:1])
        assemblies = problem.bulk_jacobian.assemblies
        A, B = _jacobian(problem), _jacobian(reference)
        assert problem.bulk_jacobian.assemblies == assemblies + 1, change
        assert _difference(A, B) == 0.0, change
        A.destroy()
        B.destroy()
    problem.destroy()
    reference.destroy()


def test_form_with_u_is_assembled_every_time():
    """A St.Venant-Kirchhoff bulk form contains u: nothing is saved, every Jacobian is assembled."""
    problem = _problem(_kirchhoff)
    assert not problem.bulk_jacobian.enabled
    for _ in range(2):
        _jacobian(problem).destroy()
    assert (problem.bulk_jacobian.assemblies, problem.bulk_jacobian.copies) == (2, 0)
    problem.destroy()
