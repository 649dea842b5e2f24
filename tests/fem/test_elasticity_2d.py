"""UFL helpers for 2D elasticity against closed forms: plane stress and plane strain bars, the
axisymmetric thick-walled cylinder (Lamé) and neo-Hookean stretches (axisymmetric, plane strain).

The fields are compared at each process's own nodes with the closed form evaluated there, so the
tests run alike in serial and on several processes.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.axisymmetric import (
    axisymmetric_deformation_gradient,
    axisymmetric_grad,
    axisymmetric_stress,
    axisymmetric_weight,
)
from dolfinx_ntf.fem.elasticity import (
    component_bc,
    lame_parameters,
    neo_hookean_stress,
    plane_stress_stress,
    small_strain_stress,
)

pytestmark = pytest.mark.mpi

E, NU = 200.0, 0.3


def _rectangle(x0: float, y0: float, x1: float, y1: float, nx: int, ny: int) -> dolfinx.mesh.Mesh:
    return dolfinx.mesh.create_rectangle(
        MPI.COMM_WORLD,
        [np.array([x0, y0]), np.array([x1, y1])],
        [nx, ny],
        dolfinx.mesh.CellType.triangle,
    )


def _facets(mesh: dolfinx.mesh.Mesh, where) -> np.ndarray:
    return dolfinx.mesh.locate_entities_boundary(mesh, 1, where)


def _tagged_ds(mesh: dolfinx.mesh.Mesh, facets: np.ndarray) -> ufl.Measure:
    """``ds(1)`` over the given facets."""
    facets = np.sort(facets).astype(np.int32)
    tags = dolfinx.mesh.meshtags(mesh, 1, facets, np.ones(facets.size, dtype=np.int32))
    return ufl.Measure("ds", domain=mesh, subdomain_data=tags)


def _owned_nodes(V: dolfinx.fem.FunctionSpace) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates (x, y) and indices of the nodes this process owns."""
    owned = V.dofmap.index_map.size_local
    return V.tabulate_dof_coordinates()[:owned, :2], np.arange(owned)


def _solve_linear(F: ufl.Form, u: dolfinx.fem.Function, bcs: list) -> None:
    """Solve the linear residual ``F(u) = 0`` (``u`` appears linearly) into ``u``."""
    V = u.function_space
    w = ufl.TrialFunction(V)
    a = ufl.derivative(F, u, w)
    L = -ufl.replace(F, {u: ufl.as_vector([0.0, 0.0])})
    problem = compat.linear_problem(
        a, L, bcs=bcs, petsc_options={"ksp_type": "preonly", "pc_type": "lu"}
    )
    u.x.array[:] = problem.solve().x.array


@pytest.mark.parametrize(
    ("stress", "compliance"),
    [(plane_stress_stress, 1.0), (small_strain_stress, 1.0 - NU**2)],
    ids=["plane_stress", "plane_strain"],
)
def test_uniaxial_bar_2d(stress, compliance: float) -> None:
    """A bar pulled by sigma0: u_x = c sigma0 x / E, u_y = -nu' c sigma0 y / E exactly (P1)."""
    length, height, sigma0 = 4.0, 1.0, 3.0
    mesh = _rectangle(0.0, 0.0, length, height, 8, 3)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    ds = _tagged_ds(mesh, _facets(mesh, lambda x: np.isclose(x[0], length)))
    F = ufl.inner(stress(u, E, NU), ufl.grad(v)) * ufl.dx - sigma0 * v[0] * ds(1)
    bcs = [
        component_bc(V, 0, _facets(mesh, lambda x: np.isclose(x[0], 0.0))),
        component_bc(V, 1, _facets(mesh, lambda x: np.isclose(x[1], 0.0))),
    ]
    _solve_linear(F, u, bcs)
    x, nodes = _owned_nodes(V)
    values = u.x.array.reshape(-1, 2)[nodes]
    lateral = NU if compliance == 1.0 else NU / (1 - NU)  # plane strain: nu' = nu / (1 - nu)
    expected_x = compliance * sigma0 * x[:, 0] / E
    expected_y = -lateral * compliance * sigma0 * x[:, 1] / E
    scale = sigma0 * length / E
    np.testing.assert_allclose(values[:, 0], expected_x, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(values[:, 1], expected_y, rtol=0, atol=1e-10 * scale)


def test_thick_walled_cylinder_axisymmetric() -> None:
    """Lamé: a tube a <= r <= b under internal pressure p, eps_z = 0, P2.

    u_r = (1 + nu)/E ((1 - 2 nu) A r + B / r), A = p a²/(b² - a²), B = p a² b²/(b² - a²); the
    radial displacement within 1e-4 of its largest value (the plane-strain form without the hoop
    term is off by tens of percent), and the reaction on the end planes equal to the ring's.
    """
    a, b, height, p = 1.0, 2.0, 0.5, 1.5
    mesh = _rectangle(a, 0.0, b, height, 16, 2)
    V = compat.vector_space(mesh, "Lagrange", 2)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    w = axisymmetric_weight(mesh)
    ds = _tagged_ds(mesh, _facets(mesh, lambda x: np.isclose(x[0], a)))
    # The pressure pushes the inner wall outwards: traction p e_r on r = a.
    bulk = ufl.inner(axisymmetric_stress(u, E, NU), axisymmetric_grad(v)) * w * ufl.dx
    F = bulk - p * v[0] * w * ds(1)
    ends = _facets(mesh, lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], height))
    _solve_linear(F, u, [component_bc(V, 1, ends)])
    x, nodes = _owned_nodes(V)
    c_a, c_b = p * a**2 / (b**2 - a**2), p * a**2 * b**2 / (b**2 - a**2)
    r = x[:, 0]
    expected = (1 + NU) / E * ((1 - 2 * NU) * c_a * r + c_b / r)
    values = u.x.array.reshape(-1, 2)[nodes]
    scale = (1 + NU) / E * ((1 - 2 * NU) * c_a * a + c_b / a)
    np.testing.assert_allclose(values[:, 0], expected, rtol=0, atol=1e-4 * scale)
    np.testing.assert_allclose(values[:, 1], 0.0, atol=1e-4 * scale)
    # Total pressure force on the inner wall of the full ring: 2 pi a h p.
    ring = dolfinx.fem.assemble_scalar(dolfinx.fem.form(p * w * ds(1)))
    assert mesh.comm.allreduce(ring, op=MPI.SUM) == pytest.approx(
        2 * np.pi * a * height * p, rel=1e-12
    )


def _neo_hookean_lateral_stretch(stretch_z: float, free: int) -> float:
    """Lateral stretch of a neo-Hookean rod stretched axially with ``free`` free directions.

    Axisymmetric: r and hoop (2, J = s² lz); plane strain: one (J = s lz); P_lateral = 0.
    """
    mu, lmbda = lame_parameters(E, NU)
    s = 1.0
    for _ in range(50):  # Newton on s P = mu (s² - 1) + lambda ln(s^free lz) = 0
        f = mu * (s**2 - 1) + lmbda * np.log(s**free * stretch_z)
        step = f / (2 * mu * s + free * lmbda / s)
        s -= step
        if abs(step) < 1e-15:
            break
    return s


@pytest.mark.parametrize("axisymmetric", [True, False], ids=["axisymmetric", "plane_strain"])
def test_neo_hookean_stretch(axisymmetric: bool) -> None:
    """A solid cylinder (or a plane-strain strip) stretched 30 %: the homogeneous neo-Hookean
    solution, exact in P1.

    Its width shrinks by the stretch of P_lateral = 0 (a scalar Newton solve); Newton on the FE
    residual converges quadratically from the axial field alone.
    """
    radius, height, stretch_z = 1.0, 2.0, 1.3
    mesh = _rectangle(0.0, 0.0, radius, height, 4, 6)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 4})
    if axisymmetric:
        P = neo_hookean_stress(axisymmetric_deformation_gradient(u), E, NU)
        F = ufl.inner(P, axisymmetric_grad(v)) * axisymmetric_weight(mesh) * dx
    else:
        P = neo_hookean_stress(ufl.Identity(2) + ufl.grad(u), E, NU)
        F = ufl.inner(P, ufl.grad(v)) * dx
    u.interpolate(lambda x: np.stack([0.0 * x[0], (stretch_z - 1.0) * x[1]]))
    bcs = [
        component_bc(V, 0, _facets(mesh, lambda x: np.isclose(x[0], 0.0))),  # axis, symmetry
        component_bc(
            V, 1, _facets(mesh, lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], height))
        ),
    ]
    du = ufl.TrialFunction(V)
    corrections = []
    for _ in range(10):
        problem = compat.linear_problem(
            ufl.derivative(F, u, du), -F, bcs=bcs,
            petsc_options={"ksp_type": "preonly", "pc_type": "lu"},
        )  # fmt: skip
        step = problem.solve()
        u.x.array[:] += step.x.array
        u.x.scatter_forward()
        norm = mesh.comm.allreduce(float(np.abs(step.x.array).max()), op=MPI.MAX)
        corrections.append(norm)
        if norm < 1e-13:
            break
    assert corrections[-1] < 1e-13 and len(corrections) <= 7
    s = _neo_hookean_lateral_stretch(stretch_z, 2 if axisymmetric else 1)
    assert s < 1.0 - 0.05  # a real contraction
    x, nodes = _owned_nodes(V)
    values = u.x.array.reshape(-1, 2)[nodes]
    np.testing.assert_allclose(values[:, 0], (s - 1.0) * x[:, 0], rtol=0, atol=1e-11)
    np.testing.assert_allclose(values[:, 1], (stretch_z - 1.0) * x[:, 1], rtol=0, atol=1e-11)


def test_axisymmetric_helpers_refuse_wrong_shapes() -> None:
    mesh3 = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    with pytest.raises(ValueError, match="axisymmetric model needs a 2D mesh"):
        axisymmetric_weight(mesh3)
    V3 = compat.vector_space(mesh3, "Lagrange", 1)
    with pytest.raises(ValueError, match="2 components"):
        axisymmetric_grad(dolfinx.fem.Function(V3))
    with pytest.raises(ValueError, match="plane stress needs a 2D displacement"):
        plane_stress_stress(dolfinx.fem.Function(V3), E, NU)
