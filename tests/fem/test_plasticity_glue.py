"""J2 plasticity at quadrature points (fem/plasticity): the glue, its forms and its history.

The quadrature stresses of an elastic displacement give the same residual as Hooke's law in UFL
(the points and their order are dolfinx's), the assembled Jacobian is the finite-difference
derivative of the assembled residual, and a bar pulled past yield follows the closed form of the
uniaxial stress-strain curve (linear hardening and a ``*PLASTIC`` table) through a
ContactProblem stepped by a StaticStep, serial and on several processes.
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest
from helpers import box_grid
from helpers.blocks import hexes_to_tets

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import hooke_stress

E, NU = 200e3, 0.3
SIGMA_Y0, H = 250.0, 20e3
TABLE = ntf.IsotropicHardening((250.0, 300.0, 320.0), (0.0, 0.002, 0.01))
LENGTH = 2.0


def _mesh(cell: str = "hexahedron", comm=MPI.COMM_WORLD) -> dolfinx.mesh.Mesh:
    points, hexes = box_grid((0, 0, 0), (LENGTH, 1, 1), (4, 2, 2))
    cells = hexes_to_tets(hexes) if cell == "tetrahedron" else hexes
    if comm.rank != 0:
        points, cells = np.empty((0, 3)), np.empty((0, cells.shape[1]), dtype=np.int64)
    return compat.create_mesh(comm, cells.astype(np.int64), points, compat.coordinate_element(cell))


def _smooth_field(x: np.ndarray, scale: float) -> np.ndarray:
    """A displacement whose strain varies inside the cells (and past yield for scale ~ 1e-2)."""
    return scale * np.vstack(
        [x[0] * x[1] + 0.3 * x[2] ** 2, 0.5 * x[0] ** 2 - x[1] * x[2], x[0] * x[2] + 0.2 * x[1]]
    )


def _vector(form: ufl.Form) -> np.ndarray:
    vector = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(form))
    vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    values = vector.array.copy()
    vector.destroy()
    return values


@pytest.mark.mpi
@pytest.mark.parametrize(("cell", "degree"), [("hexahedron", 1), ("tetrahedron", 2)])
def test_elastic_stresses_are_hookes_law(cell: str, degree: int) -> None:
    """Below yield the quadrature stresses integrate to the residual of Hooke's law in UFL: the
    strain is evaluated at the rule's points in the stress space's order."""
    mesh = _mesh(cell)
    V = compat.vector_space(mesh, "Lagrange", degree)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    u.interpolate(lambda x: _smooth_field(x, 1e-5))
    material = ntf.J2Plasticity(u, E, NU, TABLE)
    assert material.quadrature_degree == 2 * degree
    assert not mesh.comm.allreduce(material.yielding.any(), op=MPI.LOR)
    plastic = _vector(material.residual(v))
    elastic = _vector(
        ufl.inner(hooke_stress(ufl.sym(ufl.grad(u)), E, NU), ufl.grad(v)) * material.dx
    )
    scale = mesh.comm.allreduce(np.abs(elastic).max(initial=0.0), op=MPI.MAX)
    assert scale > 0
    np.testing.assert_allclose(plastic, elastic, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("dim", [2, 3])
def test_jacobian_against_finite_differences(dim: int) -> None:
    """The assembled consistent Jacobian times a direction is the central difference of the
    assembled residual, at a state with committed plastic strain and yielding points (3D and
    plane strain)."""
    if dim == 3:
        mesh = _mesh()
    else:
        mesh = dolfinx.mesh.create_rectangle(
            MPI.COMM_WORLD,
            [np.zeros(2), np.array([LENGTH, 1.0])],
            [4, 2],
            dolfinx.mesh.CellType.quadrilateral,
        )
    V = compat.vector_space(mesh)
    u, v, du = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    field = lambda x, s: _smooth_field(x, s)[:dim]  # noqa: E731
    material = ntf.J2Plasticity(u, E, NU, TABLE)
    u.interpolate(lambda x: field(x, 2e-3))
    material.evaluate()
    material.increment_converged()  # a committed plastic history
    assert material.equivalent_plastic_strain.max() > 0
    u.interpolate(lambda x: field(x, 3e-3) + 1e-4 * np.sin(3 * x[:dim]))
    material.evaluate()
    yielding = material.yielding
    assert 0 < yielding.sum() < yielding.size
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(material.jacobian(du, v)))
    A.assemble()
    rng = np.random.default_rng(3)
    direction = dolfinx.fem.Function(V)
    direction.x.array[:] = rng.normal(size=direction.x.array.size) * 1e-3
    direction.x.scatter_forward()
    product = A.createVecLeft()
    A.mult(compat.petsc_vector(direction), product)
    start = u.x.array.copy()
    h = 1e-6
    values = []
    for sign in (1.0, -1.0):
        u.x.array[:] = start + sign * h * direction.x.array
        material.evaluate()
        values.append(_vector(material.residual(v)))
    fd = (values[0] - values[1]) / (2 * h)
    exact = product.array
    assert np.abs(fd - exact).max() < 1e-6 * np.abs(exact).max()
    A.destroy()
    product.destroy()


def _uniaxial_stress(strain: float, hardening: ntf.IsotropicHardening) -> float:
    """The closed form of the uniaxial curve: elastic up to sigma_y0 / E, then
    ``strain = sigma / E + alpha`` with ``sigma = sigma_y(alpha)``, linear on each piece."""
    starts, values, slopes = hardening.segments()
    strains = values / E + starts  # the strains at the table points
    if strain <= strains[0]:
        return E * strain
    j = np.searchsorted(strains, strain, side="right") - 1
    # sigma = s_j + h_j (alpha - a_j) and strain = sigma / E + alpha
    alpha = (strain - values[j] / E + slopes[j] * starts[j] / E) / (1 + slopes[j] / E)
    return float(values[j] + slopes[j] * (alpha - starts[j]))


@pytest.mark.mpi
@pytest.mark.parametrize("hardening", [ntf.IsotropicHardening.linear(SIGMA_Y0, H), TABLE])
def test_uniaxial_bar_closed_form(hardening: ntf.IsotropicHardening) -> None:
    """A bar on symmetry rollers pulled past yield by a prescribed end displacement: the axial
    stress at every quadrature point and the end reaction follow the uniaxial curve, increment by
    increment, each plastic increment in two Newton iterations (the elastic predictor's, then the
    consistent tangent's exact one: the curve is linear within a piece)."""
    mesh = _mesh()
    V = compat.vector_space(mesh)
    u, v, du = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    material = ntf.J2Plasticity(u, E, NU, hardening)

    def plane(axis, where):
        return dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[axis], where))

    bcs = [ntf.component_bc(V, axis, plane(axis, 0.0)) for axis in range(3)]
    Vx, _ = compat.component_space(V, 0)
    end = dolfinx.fem.Function(Vx)
    dofs = dolfinx.fem.locate_dofs_topological((V.sub(0), Vx), 2, plane(0, LENGTH))
    bcs.append(dolfinx.fem.dirichletbc(end, dofs, V.sub(0)))
    problem = ntf.ContactProblem(
        material.residual(v), u, [], bcs, J=material.jacobian(du, v), history=[material]
    )
    solver = ntf.ContactNewtonSolver(mesh.comm, problem)
    largest = 6 * SIGMA_Y0 / E  # about 0.0075, past the table's second point
    checked = []

    def check(result: ntf.IncrementResult) -> None:
        strain = result.time * largest
        expected = _uniaxial_stress(strain, hardening)
        stress = material.stress.x.array.reshape(-1, 6)
        np.testing.assert_allclose(stress[:, 0], expected, rtol=1e-10)
        np.testing.assert_allclose(stress[:, 1:], 0.0, atol=1e-9 * expected)
        # the committed history: uniform, alpha = strain - sigma / E past yield
        np.testing.assert_allclose(
            material.equivalent_plastic_strain, max(strain - expected / E, 0.0), atol=1e-12
        )
        checked.append((strain > SIGMA_Y0 / E * (1 + 1e-9), result.iterations))

    step = ntf.StaticStep(
        lambda t: end.x.array.__setitem__(slice(None), t * largest * LENGTH),
        initial_increment=0.1,
        fixed=True,
        on_increment=check,
    )
    step.run(solver, u)
    solver.destroy()
    problem.destroy()
    assert len(checked) == 10 and sum(plastic for plastic, _ in checked) == 9
    assert all(iterations == 2 for _, iterations in checked)


def test_rejected_increment_rolls_back() -> None:
    """A failed attempt leaves the committed history alone; the stress at the restored
    displacement is the committed state's again, and only a converged increment commits."""
    mesh = _mesh()
    V = compat.vector_space(mesh)
    u = dolfinx.fem.Function(V)
    material = ntf.J2Plasticity(u, E, NU, TABLE)
    u.interpolate(lambda x: _smooth_field(x, 2e-3))
    material.increment_converged()
    committed = material.equivalent_plastic_strain.copy()
    stress = material.stress.x.array.copy()
    start = u.x.array.copy()
    u.interpolate(lambda x: _smooth_field(x, 5e-3))  # an attempt that yields further
    material.evaluate()
    assert not np.allclose(material.stress.x.array, stress)
    np.testing.assert_array_equal(material.equivalent_plastic_strain, committed)
    u.x.array[:] = start  # what the step driver does, then the problem's reject_increment
    material.increment_rejected()
    np.testing.assert_allclose(material.stress.x.array, stress, rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(material.equivalent_plastic_strain, committed)


def test_bad_arguments() -> None:
    """A history without its Jacobian, and wrong materials, are refused with the reason."""
    mesh = _mesh()
    V = compat.vector_space(mesh)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    material = ntf.J2Plasticity(u, E, NU, TABLE)
    with pytest.raises(ValueError, match="pass J"):
        ntf.ContactProblem(material.residual(v), u, [], history=[material])
    with pytest.raises(TypeError, match="lacks"):
        ntf.ContactProblem(
            material.residual(v),
            u,
            [],
            J=material.jacobian(ufl.TrialFunction(V), v),
            history=[object()],
        )
    with pytest.raises(ValueError, match=r"nu < 0\.5"):
        ntf.J2Plasticity(u, E, 0.5, TABLE)
    with pytest.raises(TypeError, match="hardening"):
        ntf.J2Plasticity(u, E, NU, (250.0, 0.0))
    with pytest.raises(ValueError, match="quadrature_degree"):
        ntf.J2Plasticity(u, E, NU, TABLE, quadrature_degree=-1)
