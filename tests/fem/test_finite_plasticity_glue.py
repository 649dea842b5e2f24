"""Finite-strain J2 plasticity at quadrature points (fem/finite_plasticity): forms and history.

The assembled Jacobian times a direction is the central difference of the assembled residual at a
yielding state with committed history, the law on two halves of the cells (one set of tags) gives
the law on all of them, a homogeneous stretch gives the kernel's stress at every point, and a
rejected increment leaves the committed history alone; serial and on 2 processes.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from test_plasticity_glue import LENGTH, _mesh, _smooth_field, _vector

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.finite_plasticity import FiniteStrainJ2Plasticity
from dolfinx_ntf.kernels.finite_plasticity import finite_return_map
from dolfinx_ntf.kernels.plasticity import IsotropicHardening

E, NU = 5000.0, 0.3
TABLE = IsotropicHardening((50.0, 80.0, 90.0), (0.0, 0.01, 0.05))


def _product(form: ufl.Form, direction: dolfinx.fem.Function) -> np.ndarray:
    """The assembled matrix of ``form`` times ``direction`` (owned rows)."""
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(form))
    A.assemble()
    y = A.createVecLeft()
    A.mult(compat.petsc_vector(direction), y)
    values = y.array.copy()
    A.destroy()
    y.destroy()
    return values


def _owned(values: np.ndarray, V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    return values[: V.dofmap.index_map.size_local * V.dofmap.index_map_bs]


@pytest.mark.mpi
def test_jacobian_against_finite_differences() -> None:
    mesh = _mesh()
    V = compat.vector_space(mesh)
    u, v, du = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    law = FiniteStrainJ2Plasticity(u, E, NU, TABLE)
    u.interpolate(lambda x: _smooth_field(x, 5e-3))
    law.increment_converged()  # committed plastic history
    u.interpolate(lambda x: _smooth_field(x, 1.2e-2))
    law.evaluate()
    assert mesh.comm.allreduce(int(law.yielding.sum()), op=MPI.SUM) > 0
    assert mesh.comm.allreduce(float(law.equivalent_plastic_strain.max(initial=0)), op=MPI.MAX) > 0
    direction = dolfinx.fem.Function(V)
    direction.interpolate(lambda x: _smooth_field(x, 1.0))
    product = _product(law.jacobian(du, v), direction)
    start, h = u.x.array.copy(), 1e-7
    residuals = []
    for sign in (1.0, -1.0):
        u.x.array[:] = start + sign * h * direction.x.array
        law.evaluate()
        residuals.append(_owned(_vector(law.residual(v)), V))
    difference = (residuals[0] - residuals[1]) / (2 * h)
    scale = mesh.comm.allreduce(np.abs(difference).max(initial=0.0), op=MPI.MAX)
    error = mesh.comm.allreduce(np.abs(difference - product).max(initial=0.0), op=MPI.MAX)
    assert scale > 0 and error < 1e-6 * scale, (error, scale)


@pytest.mark.mpi
def test_cell_tags_split_the_law() -> None:
    mesh = _mesh()
    V = compat.vector_space(mesh)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    u.interpolate(lambda x: _smooth_field(x, 1e-2))
    tdim = mesh.topology.dim
    cell_map = mesh.topology.index_map(tdim)
    cells = np.arange(cell_map.size_local + cell_map.num_ghosts, dtype=np.int32)
    midpoints = dolfinx.mesh.compute_midpoints(mesh, tdim, cells)
    tags = dolfinx.mesh.meshtags(
        mesh, tdim, cells, np.where(midpoints[:, 0] < 0.5 * LENGTH, 1, 2).astype(np.int32)
    )
    whole = FiniteStrainJ2Plasticity(u, E, NU, TABLE)
    halves = [FiniteStrainJ2Plasticity(u, E, NU, TABLE, cell_tags=tags, tag=t) for t in (1, 2)]
    expected = _vector(whole.residual(v))
    split = _vector(halves[0].residual(v) + halves[1].residual(v))
    scale = mesh.comm.allreduce(np.abs(expected).max(initial=0.0), op=MPI.MAX)
    assert scale > 0
    np.testing.assert_allclose(split, expected, rtol=0, atol=1e-12 * scale)
    # the Cauchy stresses per cell are the whole law's, and only the law's cells have them
    for half in halves:
        if half.cells.size:
            np.testing.assert_allclose(
                half.cell_stresses(half.cells), whole.cell_stresses(half.cells), rtol=1e-12
            )
    if halves[1].cells.size:
        with pytest.raises(ValueError, match="not one of the law's cells"):
            halves[0].cell_stresses(halves[1].cells[:1])


@pytest.mark.mpi
def test_homogeneous_stretch_is_the_kernel() -> None:
    """u = (F - I) X: every point's P is the kernel's at F; a rejected increment keeps the
    committed history and the stress goes back."""
    mesh = _mesh()
    V = compat.vector_space(mesh)
    u = dolfinx.fem.Function(V)
    law = FiniteStrainJ2Plasticity(u, E, NU, TABLE)
    F = np.array([[1.03, 0.01, 0.0], [0.0, 0.985, 0.004], [0.002, 0.0, 0.99]])
    u.interpolate(lambda x: (F - np.eye(3)) @ x)
    law.increment_converged()
    n = law.equivalent_plastic_strain.size
    expected = finite_return_map(np.tile(F, (n, 1, 1)), np.tile(np.eye(3), (n, 1, 1)),
                                 np.zeros(n), E, NU, TABLE)  # fmt: skip
    assert expected.plastic.all()
    values = law.first_piola.x.array.reshape(-1, 9)[
        compat.cell_dofs(law.first_piola.function_space)[law.cells].reshape(-1)
    ]
    np.testing.assert_allclose(values, expected.first_piola.reshape(-1, 9), rtol=1e-10, atol=1e-9)
    committed = law.equivalent_plastic_strain.copy()
    stress = law.first_piola.x.array.copy()
    start = u.x.array.copy()
    u.x.array[:] *= 1.5  # an attempt that yields further, then rejected
    law.evaluate()
    u.x.array[:] = start
    law.increment_rejected()
    np.testing.assert_array_equal(law.equivalent_plastic_strain, committed)
    np.testing.assert_allclose(law.first_piola.x.array, stress, rtol=1e-12, atol=1e-9)


def test_bad_arguments() -> None:
    mesh = _mesh()
    V = compat.vector_space(mesh)
    u = dolfinx.fem.Function(V)
    with pytest.raises(ValueError, match=r"nu < 0\.5"):
        FiniteStrainJ2Plasticity(u, E, 0.5, TABLE)
    with pytest.raises(TypeError, match="hardening"):
        FiniteStrainJ2Plasticity(u, E, NU, (50.0, 0.0))
    with pytest.raises(ValueError, match="quadrature_degree"):
        FiniteStrainJ2Plasticity(u, E, NU, TABLE, quadrature_degree=-1)
    facets = dolfinx.mesh.meshtags(mesh, 2, np.zeros(0, np.int32), np.zeros(0, np.int32))
    with pytest.raises(ValueError, match="cell_tags"):
        FiniteStrainJ2Plasticity(u, E, NU, TABLE, cell_tags=facets)
