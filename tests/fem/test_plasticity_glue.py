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


def _pulled_bar(mesh, hardening: ntf.IsotropicHardening):
    """J2 plasticity on ``mesh`` with rollers on the planes x, y (, z) = 0 and the end x = LENGTH
    pulled by a prescribed displacement: ``(problem, material, end)``, ``end`` the displacement."""
    fdim = mesh.topology.dim - 1
    V = compat.vector_space(mesh)
    u, v, du = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    material = ntf.J2Plasticity(u, E, NU, hardening)

    def side(axis, where):
        return dolfinx.mesh.locate_entities_boundary(
            mesh, fdim, lambda x: np.isclose(x[axis], where)
        )

    bcs = [ntf.component_bc(V, axis, side(axis, 0.0)) for axis in range(mesh.geometry.dim)]
    Vx, _ = compat.component_space(V, 0)
    end = dolfinx.fem.Function(Vx)
    dofs = dolfinx.fem.locate_dofs_topological((V.sub(0), Vx), fdim, side(0, LENGTH))
    bcs.append(dolfinx.fem.dirichletbc(end, dofs, V.sub(0)))
    problem = ntf.ContactProblem(
        material.residual(v), u, [], bcs, J=material.jacobian(du, v), history=[material]
    )
    return problem, material, end


@pytest.mark.mpi
@pytest.mark.parametrize("hardening", [ntf.IsotropicHardening.linear(SIGMA_Y0, H), TABLE])
@pytest.mark.parametrize("driver", [ntf.ContactNewtonSolver, ntf.ContactSNESSolver])
def test_uniaxial_bar_closed_form(hardening: ntf.IsotropicHardening, driver: type) -> None:
    """A bar on symmetry rollers pulled past yield by a prescribed end displacement: the axial
    stress at every quadrature point and the end reaction follow the uniaxial curve, increment by
    increment, each plastic increment in two Newton iterations (the elastic predictor's, then the
    consistent tangent's exact one: the curve is linear within a piece), with the package's Newton
    and with PETSc's SNES as the driver."""
    problem, material, end = _pulled_bar(_mesh(), hardening)
    u = problem.u
    mesh = u.function_space.mesh
    solver = driver(mesh.comm, problem)
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


def _plane_strain_reference(strains: np.ndarray) -> list[np.ndarray]:
    """The kernel driven along ``eps_xx`` with ``eps_zz = 0`` and ``eps_yy`` such that
    ``sigma_yy = 0`` (Newton on the algorithmic tangent): the stresses of a plane-strain bar."""
    from dolfinx_ntf.kernels.plasticity import return_map

    plastic, alpha, strain = np.zeros((1, 6)), np.zeros(1), np.zeros((1, 6))
    out = []
    for eps_x in strains:
        strain[0, 0] = eps_x
        for _ in range(30):
            result = return_map(strain, plastic, alpha, E, NU, TABLE)
            if abs(result.stress[0, 1]) < 1e-12 * SIGMA_Y0:
                break
            strain[0, 1] -= result.stress[0, 1] / result.tangent[0, 1, 1]
        plastic, alpha = result.plastic_strain, result.equivalent_plastic_strain
        out.append(result.stress[0].copy())
    return out


@pytest.mark.mpi
def test_plane_strain_bar() -> None:
    """A plane-strain bar (2D ``u``, rollers on x = 0 and y = 0) pulled past yield: every point's
    stress, the out-of-plane ``sigma_zz`` included, is the kernel's along the same homogeneous
    path (``eps_zz = 0``, ``sigma_yy = 0``), increment by increment."""
    mesh = dolfinx.mesh.create_rectangle(
        MPI.COMM_WORLD,
        [np.zeros(2), np.array([LENGTH, 1.0])],
        [4, 2],
        dolfinx.mesh.CellType.quadrilateral,
    )
    problem, material, end = _pulled_bar(mesh, TABLE)
    u = problem.u
    solver = ntf.ContactNewtonSolver(mesh.comm, problem)
    largest = 8 * SIGMA_Y0 / E
    times = np.arange(1, 11) / 10
    reference = _plane_strain_reference(times * largest)
    checked = []

    def check(result: ntf.IncrementResult) -> None:
        expected = reference[len(checked)]
        stress = material.stress.x.array.reshape(-1, 6)
        np.testing.assert_allclose(
            stress, np.broadcast_to(expected, stress.shape), atol=1e-8 * E * largest
        )
        checked.append(result.time)

    ntf.StaticStep(
        lambda t: end.x.array.__setitem__(slice(None), t * largest * LENGTH),
        initial_increment=0.1,
        fixed=True,
        on_increment=check,
    ).run(solver, u)
    solver.destroy()
    problem.destroy()
    assert checked == pytest.approx(times)
    assert reference[-1][2] > 0.4 * reference[-1][0]  # sigma_zz carries the constraint
    assert _largest_alpha(material) > TABLE.plastic_strain[1]


def _largest_alpha(material: ntf.J2Plasticity) -> float:
    comm = material.u.function_space.mesh.comm
    return comm.allreduce(float(material.equivalent_plastic_strain.max(initial=0.0)), op=MPI.MAX)


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


@pytest.mark.mpi
def test_cell_tags_split_the_material() -> None:
    """Two laws on the two halves of the cells (one set of tags) give the residual, the Jacobian
    and the history of one law on every cell, at a yielding state; tags of another dimension are
    refused."""
    mesh = _mesh()
    V = compat.vector_space(mesh)
    u, v, du = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    u.interpolate(lambda x: _smooth_field(x, 5e-3))
    tdim = mesh.topology.dim
    cell_map = mesh.topology.index_map(tdim)
    cells = np.arange(cell_map.size_local + cell_map.num_ghosts, dtype=np.int32)
    midpoints = dolfinx.mesh.compute_midpoints(mesh, tdim, cells)
    values = np.where(midpoints[:, 0] < 0.5 * LENGTH, 1, 2).astype(np.int32)
    tags = dolfinx.mesh.meshtags(mesh, tdim, cells, values)
    whole = ntf.J2Plasticity(u, E, NU, TABLE)
    left = ntf.J2Plasticity(u, E, NU, TABLE, cell_tags=tags, tag=1)
    right = ntf.J2Plasticity(u, E, NU, TABLE, cell_tags=tags, tag=2)
    assert mesh.comm.allreduce(int(whole.yielding.sum()), op=MPI.SUM) > 0
    assert left.yielding.size + right.yielding.size == whole.yielding.size
    expected = _vector(whole.residual(v))
    split = _vector(left.residual(v) + right.residual(v))
    scale = mesh.comm.allreduce(np.abs(expected).max(initial=0.0), op=MPI.MAX)
    np.testing.assert_allclose(split, expected, rtol=0, atol=1e-12 * scale)
    direction = dolfinx.fem.Function(V)
    direction.interpolate(lambda x: _smooth_field(x, 1.0))
    jacobians = []
    for form in (whole.jacobian(du, v), left.jacobian(du, v) + right.jacobian(du, v)):
        A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(form))
        A.assemble()
        y = A.createVecLeft()
        A.mult(compat.petsc_vector(direction), y)
        jacobians.append(y.array.copy())
        A.destroy()
        y.destroy()
    np.testing.assert_allclose(
        jacobians[1], jacobians[0], rtol=0, atol=1e-10 * np.abs(jacobians[0]).max(initial=1.0)
    )
    left.increment_converged()
    right.increment_converged()
    whole.increment_converged()
    total = mesh.comm.allreduce(whole.equivalent_plastic_strain.sum(), op=MPI.SUM)
    halves = left.equivalent_plastic_strain.sum() + right.equivalent_plastic_strain.sum()
    assert mesh.comm.allreduce(halves, op=MPI.SUM) == pytest.approx(total, rel=1e-12)
    facets = dolfinx.mesh.meshtags(mesh, tdim - 1, np.zeros(0, np.int32), np.zeros(0, np.int32))
    with pytest.raises(ValueError, match="cell_tags"):
        ntf.J2Plasticity(u, E, NU, TABLE, cell_tags=facets)


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


_CCX_NODES = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float
)
#: A non-proportional strain path: tension with shear, a turn with partial elastic unloading,
#: then tension past the table's last line.
_PATH = (
    np.array([[0.004, 0.002, 0.0], [0.002, -0.001, 0.0], [0.0, 0.0, -0.001]]),
    np.array([[0.002, 0.002, 0.003], [0.002, 0.002, 0.0], [0.003, 0.0, -0.001]]),
    np.array([[0.016, 0.002, 0.003], [0.002, -0.006, 0.0], [0.003, 0.0, -0.007]]),
)


def _ccx_path_deck() -> str:
    """One C3D8 of the table's steel, every node prescribed to ``u = eps X`` in steps of ten
    fixed increments (ccx ramps the boundary values linearly over each step)."""
    nodes = "\n".join(f"{i + 1}, {x[0]}, {x[1]}, {x[2]}" for i, x in enumerate(_CCX_NODES))
    table = "\n".join(f"{s}, {a}" for s, a in zip(TABLE.yield_stress, TABLE.plastic_strain))
    steps = []
    for eps in _PATH:
        u = _CCX_NODES @ eps.T
        values = "\n".join(
            f"{n + 1}, {d + 1}, {d + 1}, {float(u[n, d])!r}" for n in range(8) for d in range(3)
        )
        steps.append(
            f"*STEP, INC=1000\n*STATIC, DIRECT\n0.1, 1.\n*BOUNDARY\n{values}\n"
            "*EL PRINT, ELSET=EALL\nS, PEEQ\n*END STEP"
        )
    return (
        f"*NODE, NSET=NALL\n{nodes}\n*ELEMENT, TYPE=C3D8, ELSET=EALL\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"
        f"*MATERIAL, NAME=STEEL\n*ELASTIC\n{E}, {NU}\n*PLASTIC\n{table}\n"
        "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n" + "\n".join(steps) + "\n"
    )


def test_agrees_with_ccx(tmp_path) -> None:
    """CalculiX's *PLASTIC on one C3D8 along a non-proportional strain path (past the table's
    last line, where ccx keeps the yield stress constant, and through an elastic unloading at
    the turn): the stresses and PEEQ at the 8 Gauss points agree with ccx's 7 printed digits at
    every increment."""
    from dolfinx_ntf.calculix.ccx import read_ccx_dat, run_ccx

    (tmp_path / "path.inp").write_text(_ccx_path_deck())
    run_ccx(tmp_path, "path", timeout=120)
    blocks = read_ccx_dat(tmp_path, "path")
    stresses = [b for b in blocks if b.name == "S"]
    peeq = [b for b in blocks if b.name == "PEEQ"]
    assert len(stresses) == len(peeq) == 10 * len(_PATH)

    points, hexes = box_grid((0, 0, 0), (1, 1, 1), (1, 1, 1))
    comm = MPI.COMM_SELF
    mesh = compat.create_mesh(
        comm, hexes.astype(np.int64), points, compat.coordinate_element("hexahedron")
    )
    u = dolfinx.fem.Function(compat.vector_space(mesh))
    material = ntf.J2Plasticity(u, E, NU, TABLE)
    r = 1 / np.sqrt(2)
    previous = np.zeros((3, 3))
    increment = 0
    for eps in _PATH:
        for t in np.arange(1, 11) / 10:
            strain = previous + (eps - previous) * t
            u.interpolate(lambda x, s=strain: s @ x)
            material.increment_converged()  # the return map at u, committed
            ours = material.stress.x.array.reshape(-1, 6) * [1, 1, 1, r, r, r]  # ccx: tensor
            ccx = stresses[increment].values  # sxx, syy, szz, sxy, sxz, syz
            assert ccx.shape == (8, 6)
            scale = np.abs(ccx).max()
            np.testing.assert_allclose(ours, np.broadcast_to(ccx[0], ours.shape), atol=5e-7 * scale)
            np.testing.assert_allclose(ccx, ccx[0:1].repeat(8, axis=0), atol=1e-12 * scale)
            np.testing.assert_allclose(
                material.equivalent_plastic_strain,
                peeq[increment].values[0, 0],
                rtol=5e-7,
                atol=1e-12,
            )
            increment += 1
        previous = eps
    assert material.equivalent_plastic_strain.min() > TABLE.plastic_strain[-1]  # past the table


@pytest.mark.parametrize("finite", [False, True], ids=["small", "finite"])
def test_elastic_evaluation_is_the_trial_state(finite: bool) -> None:
    """``evaluate_elastic`` (ccx's elastic first iteration, docs/method.md §33): past yield, the
    elastic trial stress and the elastic tangent from the committed history, which it keeps;
    the next ``evaluate`` return-maps again."""
    from dolfinx_ntf.fem.finite_plasticity import FiniteStrainJ2Plasticity

    mesh = _mesh()
    u = dolfinx.fem.Function(compat.vector_space(mesh))
    law = (FiniteStrainJ2Plasticity if finite else ntf.J2Plasticity)(u, E, NU, TABLE)
    u.interpolate(lambda x: _smooth_field(x, 2e-3))
    law.increment_converged()  # a committed plastic state
    committed = law.equivalent_plastic_strain.copy()
    assert committed.max() > 0.0
    u.interpolate(lambda x: _smooth_field(x, 6e-3))
    elastic = ntf.J2Plasticity(u, E, NU, ntf.IsotropicHardening.linear(1e300, 0.0))
    law.evaluate_elastic()
    assert not law.yielding.any()
    np.testing.assert_array_equal(law.equivalent_plastic_strain, committed)
    tangent = law.tangent.x.array.copy()
    law.evaluate()
    assert law.yielding.any() and not np.allclose(law.tangent.x.array, tangent)
    if not finite:  # the small-strain trial: C (eps - eps_p), the elastic tangent
        law.evaluate_elastic()
        strain = law.strain()
        expected = (strain - law.plastic_strain) @ elastic.tangent.x.array.reshape(-1, 6, 6)[0]
        np.testing.assert_allclose(
            law.stress.x.array.reshape(-1, 6), expected, rtol=1e-10, atol=1e-6 * E * 1e-3
        )
        np.testing.assert_allclose(
            law.tangent.x.array.reshape(-1, 36), elastic.tangent.x.array.reshape(-1, 36)
        )


def _gauss_rule() -> tuple[np.ndarray, np.ndarray]:
    """The 2x2x2 Gauss rule on ``[0, 1]^3`` (dolfinx's default of degree 2 on hexahedra)."""
    g = 0.5 + np.array([-1.0, 1.0]) / (2.0 * np.sqrt(3.0))
    points = np.array([[x, y, z] for x in g for y in g for z in g])
    return points, np.full(8, 1.0 / 8.0)


@pytest.mark.mpi
@pytest.mark.parametrize("finite", [False, True], ids=["small", "finite"])
def test_custom_rule_reproduces_the_default_one(finite: bool) -> None:
    """A law with ``quadrature_rule`` (values in a DG1 carrier, docs/method.md §30.5) given the
    2x2x2 Gauss points explicitly assembles the default law's residual and Jacobian."""
    from dolfinx_ntf.fem.finite_plasticity import FiniteStrainJ2Plasticity

    mesh = _mesh()
    V = compat.vector_space(mesh)
    u, v, du = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    law = FiniteStrainJ2Plasticity if finite else ntf.J2Plasticity
    default = law(u, E, NU, TABLE)
    custom = law(u, E, NU, TABLE, quadrature_rule=_gauss_rule())
    u.interpolate(lambda x: _smooth_field(x, 2e-3))
    for material in (default, custom):
        material.increment_converged()
    u.interpolate(lambda x: _smooth_field(x, 3e-3) + 1e-4 * np.sin(3 * x))
    for material in (default, custom):
        material.evaluate()
    assert default.yielding.any()
    np.testing.assert_array_equal(np.sort(default.yielding), np.sort(custom.yielding))
    expected, got = _vector(default.residual(v)), _vector(custom.residual(v))
    assert np.abs(got - expected).max() <= 1e-10 * np.abs(expected).max()
    matrices = []
    for material in (default, custom):
        A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(material.jacobian(du, v)))
        A.assemble()
        matrices.append(A)
    matrices[1].axpy(-1.0, matrices[0])
    assert matrices[1].norm() <= 1e-10 * matrices[0].norm()
    for A in matrices:
        A.destroy()


def test_custom_rule_refused_with_a_clear_error() -> None:
    mesh = _mesh()
    u = dolfinx.fem.Function(compat.vector_space(mesh))
    with pytest.raises(ValueError, match=r"quadrature_rule must be \(points \(q, 3\)"):
        ntf.J2Plasticity(u, E, NU, TABLE, quadrature_rule=(np.zeros((2, 2)), np.ones(2)))
    tets = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    w = dolfinx.fem.Function(compat.vector_space(tets))
    with pytest.raises(ValueError, match="linear quadrilaterals or hexahedra"):
        ntf.J2Plasticity(w, E, NU, TABLE, quadrature_rule=(np.full((1, 3), 0.25), np.ones(1)))


@pytest.mark.parametrize("finite", [False, True], ids=["small", "finite"])
def test_custom_rule_jacobian_against_finite_differences(finite: bool) -> None:
    """With ccx's two-point C3D6 rule (``kernels/wedge_rule.py``) as the custom rule, the
    assembled Jacobian times a direction is the central difference of the assembled residual."""
    from dolfinx_ntf.fem.finite_plasticity import FiniteStrainJ2Plasticity
    from dolfinx_ntf.kernels.wedge_rule import wedge_rule

    mesh = _mesh()
    V = compat.vector_space(mesh)
    u, v, du = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    law = FiniteStrainJ2Plasticity if finite else ntf.J2Plasticity
    material = law(u, E, NU, TABLE, quadrature_rule=wedge_rule(1))
    u.interpolate(lambda x: _smooth_field(x, 2e-3))
    material.increment_converged()
    u.interpolate(lambda x: _smooth_field(x, 3e-3) + 1e-4 * np.sin(3 * x))
    material.evaluate()
    assert material.yielding.any()
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(material.jacobian(du, v)))
    A.assemble()
    direction = dolfinx.fem.Function(V)
    direction.x.array[:] = np.random.default_rng(5).normal(size=direction.x.array.size) * 1e-3
    product = A.createVecLeft()
    A.mult(compat.petsc_vector(direction), product)
    start, h, values = u.x.array.copy(), 1e-6, []
    for sign in (1.0, -1.0):
        u.x.array[:] = start + sign * h * direction.x.array
        material.evaluate()
        values.append(_vector(material.residual(v)))
    fd = (values[0] - values[1]) / (2 * h)
    assert np.abs(fd - product.array).max() < 1e-6 * np.abs(product.array).max()
    A.destroy()
    product.destroy()
