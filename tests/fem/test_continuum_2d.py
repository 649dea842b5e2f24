"""UFL penalty and Nitsche contact on 2D meshes (docs/method.md §17.5), beside the springs.

A block pressed by its top into the rigid line y = 0 (plane strain) or a disc pressed onto the
plane z = 0 (axisymmetric, the ring weight ``2 pi r`` in the bulk and the contact integrals):
uniform pressure, exact for Nitsche (no penetration), ``E' (DEPTH - d)/H = K d`` for the penalty.
A half cylinder pressed onto the rigid line: the penalty, Nitsche and the node-to-segment springs
on the same mesh follow Hertz's line contact (b within 1 %, p0 within 2 %) and agree with each
other; the same mesh as an axisymmetric hemisphere follows Hertz's sphere. A rigid surface that
leaves the plane is refused; a circle's UFL gap and normal are the numpy surface's.
"""

from __future__ import annotations

import functools

from mpi4py import MPI

import numpy as np
import pytest
from helpers.blocks_2d import tagged_block

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import continuum, measures
from dolfinx_ntf.fem.axisymmetric import (
    axisymmetric_grad,
    axisymmetric_stress,
    axisymmetric_weight,
)
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.fem.pressure_recovery import BoundaryPressure
from dolfinx_ntf.meshes import cylinder
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

E, NU, HEIGHT, DEPTH = 1000.0, 0.3, 0.4, 0.01
BOTTOM, TOP, LEFT = 1, 2, 3
LINE = ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 1.0, 0.0))


def _press_block(method: str, *, axisymmetric: bool = False, theta: int = 1, penalty=10 * E):
    """The block's top moved DEPTH down in two solves: (u, recovered pressure, top reaction)."""
    mesh, tags = tagged_block(HEIGHT, tags=(BOTTOM, TOP, LEFT))
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    if axisymmetric:
        weight = axisymmetric_weight(mesh)

        def stress(w):
            return axisymmetric_stress(w, E, NU)

        grad_v = axisymmetric_grad(v)
    else:
        weight = 1.0

        def stress(w):
            return small_strain_stress(w, E, NU)

        grad_v = ufl.grad(v)
    bulk = ufl.inner(stress(u), grad_v) * weight * ufl.dx
    obstacle = continuum.RigidObstacle(LINE, mesh)
    ds = continuum.contact_measure(mesh, tags, BOTTOM)
    if method == "penalty":
        contact = continuum.penalty_residual(u, v, obstacle, ds, penalty, weight)
        pressure = continuum.penalty_pressure(u, obstacle, penalty)
    else:
        gamma = continuum.nitsche_gamma(10.0, E, mesh)
        contact = continuum.nitsche_residual(u, v, obstacle, ds, stress, gamma, theta, weight)
        pressure = continuum.nitsche_pressure(u, obstacle, stress, gamma)
    Vy, _ = compat.component_space(V, 1)
    top_uy = dolfinx.fem.Function(Vy)
    top = dolfinx.fem.locate_dofs_topological((V.sub(1), Vy), 1, tags.find(TOP))
    bcs = [component_bc(V, 0, tags.find(LEFT)), dolfinx.fem.dirichletbc(top_uy, top, V.sub(1))]
    newton = continuum.ContinuumNewton(bulk, contact, u, bcs)
    for t in (0.5, 1.0):
        top_uy.x.array[:] = -t * DEPTH
        newton.solve()
    newton.destroy()
    recovery = BoundaryPressure(V, tags.find(BOTTOM))
    recovery.from_expression(pressure)
    reaction = measures.facet_reaction(bulk, u, tags, TOP)
    return u, recovery, reaction


def _modulus(axisymmetric: bool) -> float:
    """The stiffness of the compressed block: uniaxial stress in a ring (no hoop or radial
    stress), uniaxial strain in plane strain (``E / (1 - nu^2)``)."""
    return E if axisymmetric else E / (1 - NU**2)


#: The bottom's width: 1 per unit thickness, the disc's area pi as a ring.
def _area(axisymmetric: bool) -> float:
    return np.pi if axisymmetric else 1.0


@pytest.mark.mpi
@pytest.mark.parametrize("axisymmetric", [False, True], ids=["plane_strain", "axisymmetric"])
def test_penalty_block_gives_the_uniform_pressure(axisymmetric):
    K = 10 * E
    modulus = _modulus(axisymmetric)
    d = modulus * DEPTH / HEIGHT / (K + modulus / HEIGHT)
    u, recovery, reaction = _press_block("penalty", axisymmetric=axisymmetric, penalty=K)
    nodes, p = recovery.nodal()
    assert np.abs(p / (K * d) - 1).max() < 1e-8
    assert reaction[1] == pytest.approx(-K * d * _area(axisymmetric), rel=1e-8)
    np.testing.assert_allclose(u.x.array.reshape(-1, 2)[nodes, 1], -d, rtol=1e-8)


@pytest.mark.mpi
@pytest.mark.parametrize("theta", [1, 0, -1])
@pytest.mark.parametrize("axisymmetric", [False, True], ids=["plane_strain", "axisymmetric"])
def test_nitsche_block_gives_the_exact_pressure(axisymmetric, theta):
    expected = _modulus(axisymmetric) * DEPTH / HEIGHT
    u, recovery, reaction = _press_block("nitsche", axisymmetric=axisymmetric, theta=theta)
    nodes, p = recovery.nodal()
    assert np.abs(p / expected - 1).max() < 1e-8
    assert reaction[1] == pytest.approx(-expected * _area(axisymmetric), rel=1e-8)
    assert np.abs(u.x.array.reshape(-1, 2)[nodes, 1]).max() < 1e-10 * DEPTH


HALF_WIDTH = 0.05
ZONE = 99  # the cylinder's arc below y = 0.2 R: the potential contact zone
PUSH = 0.005  # the top's displacement: b close to HALF_WIDTH
SPHERE_PUSH = 0.0025  # the same for the axisymmetric hemisphere's contact radius a


@functools.cache
def _cylinder():
    """The half cylinder (R = 1) of the Hertz tests, its arc below 0.2 R tagged ZONE."""
    mesh, _, ft = mesh_from_gmsh(
        cylinder.build_cylinder_on_block,
        MPI.COMM_SELF,
        gdim=2,
        bodies="cylinder",
        size_fine=HALF_WIDTH / 15,
        refine_distance=2.5 * HALF_WIDTH,
    )
    arc = ft.find(cylinder.CYLINDER_CONTACT)
    low = arc[dolfinx.mesh.compute_midpoints(mesh, 1, arc)[:, 1] < 0.2]
    values = ft.values.copy()
    values[np.isin(ft.indices, low)] = ZONE
    return mesh, dolfinx.mesh.meshtags(mesh, 1, ft.indices, values)


def _hertz(method: str, axisymmetric: bool = False) -> dict:
    """The top pushed down in 4 increments: plane strain, the cylinder by PUSH (Hertz's b and p0
    of the line contact for the reaction); axisymmetric, the quarter disc turned about its
    symmetry line, a hemisphere, by SPHERE_PUSH (Hertz's a and p0 of the sphere). The fit of
    Hertz's profile to the nodal pressures: the springs' law values ``F_N / A_p`` in the ring (the
    recovery's boundary mass has no ``2 pi r``), the recovered pressure otherwise."""
    mesh, tags = _cylinder()
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    if axisymmetric:
        weight, grad_v, push = axisymmetric_weight(mesh), axisymmetric_grad(v), SPHERE_PUSH

        def stress(w):
            return axisymmetric_stress(w, E, NU)

    else:
        weight, grad_v, push = 1.0, ufl.grad(v), PUSH

        def stress(w):
            return small_strain_stress(w, E, NU)

    bulk = ufl.inner(stress(u), grad_v) * weight * ufl.dx
    Vy, _ = compat.component_space(V, 1)
    top_uy = dolfinx.fem.Function(Vy)
    top = dolfinx.fem.locate_dofs_topological((V.sub(1), Vy), 1, tags.find(cylinder.CYLINDER_TOP))
    bcs = [
        component_bc(V, 0, tags.find(cylinder.SYMMETRY)),  # the axis in axisymmetry
        dolfinx.fem.dirichletbc(top_uy, top, V.sub(1)),
    ]
    recovery = BoundaryPressure(V, tags.find(ZONE))
    X = V.tabulate_dof_coordinates()
    if method == "springs":
        law = ntf.LinearLaw.with_ccx_defaults(E, slope=1e4 * E)
        pair = ntf.ContactPair(
            ntf.FacetSurface(tags, ZONE),
            LINE,
            ntf.SurfaceInteraction(law),
            axisymmetric=axisymmetric,
        )
        problem = ntf.ContactProblem(bulk, u, [pair], bcs)
        with ntf.ContactNewtonSolver(MPI.COMM_SELF, problem) as solver:
            ntf.StaticStep(
                lambda t: top_uy.x.array.fill(-t * push), initial_increment=0.25, max_increment=0.25
            ).run(solver, u)
        (res,) = ntf.contact_results(problem)
        recovery.from_forces(res.node, res.normal_force)
        residual = bulk
        nodes, p = (res.node, res.pressure) if axisymmetric else recovery.nodal()
        x = X[nodes, 0]
    else:
        obstacle = continuum.RigidObstacle(LINE, mesh)
        ds = continuum.contact_measure(mesh, tags, ZONE)
        if method == "penalty":
            contact = continuum.penalty_residual(u, v, obstacle, ds, 1e4 * E, weight)
            pressure = continuum.penalty_pressure(u, obstacle, 1e4 * E)
        else:
            gamma = continuum.nitsche_gamma(10.0, E, mesh)
            contact = continuum.nitsche_residual(u, v, obstacle, ds, stress, gamma, weight=weight)
            pressure = continuum.nitsche_pressure(u, obstacle, stress, gamma)
        newton = continuum.ContinuumNewton(bulk, contact, u, bcs)
        for k in range(4):
            top_uy.x.array[:] = -(k + 1) / 4 * push
            newton.solve()
        newton.destroy()
        recovery.from_expression(pressure)
        residual = bulk + contact
        nodes, p = recovery.nodal()
        x = X[nodes, 0]
    reaction = -measures.facet_reaction(residual, u, tags, cylinder.CYLINDER_TOP)[1]
    e_star = E / (1 - NU**2)
    if axisymmetric:  # the whole sphere's force; R = 1
        force = reaction
        b = (3 * force / (4 * e_star)) ** (1 / 3)
        p0 = 3 * force / (2 * np.pi * b**2)
    else:  # the half model carries half the line load
        force = 2 * reaction
        b = np.sqrt(4 * force / (np.pi * e_star))
        p0 = 2 * force / (np.pi * b)
    b_fit, p0_fit = measures.fit_hertz_profile(x, p, b, p0)
    return {
        "force": force,
        "pressure_load": None if axisymmetric else 2 * recovery.total(),
        "b": b,
        "p0": p0,
        "b_fit": b_fit,
        "p0_fit": p0_fit,
    }


@pytest.mark.serial
def test_hertz_cylinder_by_penalty_nitsche_and_springs():
    runs = {m: _hertz(m) for m in ("springs", "penalty", "nitsche")}
    for run in runs.values():
        assert run["b"] == pytest.approx(HALF_WIDTH, rel=0.05)
        assert run["pressure_load"] == pytest.approx(run["force"], rel=1e-10)
        # measured b -0.53 %, -0.56 %, -0.69 %; p0 +0.17 %, +0.19 %, +0.32 %
        assert run["b_fit"] == pytest.approx(run["b"], rel=1e-2)
        assert run["p0_fit"] == pytest.approx(run["p0"], rel=2e-2)
    springs = runs["springs"]
    # the same penalty slope: the penalty is the springs' continuum twin (measured 1e-5);
    # Nitsche has no penetration: a little more force for the same push (measured 4e-4)
    assert runs["penalty"]["force"] == pytest.approx(springs["force"], rel=1e-4)
    assert runs["nitsche"]["force"] == pytest.approx(springs["force"], rel=2e-3)
    for method in ("penalty", "nitsche"):
        assert runs[method]["b_fit"] == pytest.approx(springs["b_fit"], rel=3e-3)
        assert runs[method]["p0_fit"] == pytest.approx(springs["p0_fit"], rel=3e-3)


@pytest.mark.serial
def test_axisymmetric_hertz_sphere_by_penalty_nitsche_and_springs():
    """The quarter disc as a hemisphere (R = 1) on the plane: a and p0 of Hertz's sphere."""
    runs = {m: _hertz(m, axisymmetric=True) for m in ("springs", "penalty", "nitsche")}
    for run in runs.values():
        assert run["b"] == pytest.approx(HALF_WIDTH, rel=0.05)
        # measured a -0.29 %, -0.19 %, -0.26 %; p0 +1.2 %, -0.41 %, -0.27 %
        assert run["b_fit"] == pytest.approx(run["b"], rel=1e-2)
        assert run["p0_fit"] == pytest.approx(run["p0"], rel=2e-2)
    springs = runs["springs"]
    # force: the penalty within 4e-5 of the springs, Nitsche 1e-3 above (no penetration)
    assert runs["penalty"]["force"] == pytest.approx(springs["force"], rel=1e-4)
    assert runs["nitsche"]["force"] == pytest.approx(springs["force"], rel=2e-3)
    for method in ("penalty", "nitsche"):
        assert runs[method]["b_fit"] == pytest.approx(springs["b_fit"], rel=3e-3)


@pytest.mark.serial
@pytest.mark.parametrize(
    ("surface", "message"),
    [
        (ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 0.6, 0.8)), "the plane's normal"),
        (ntf.RigidCylinder((0.0, 2.0, 0.0), (1.0, 0.0, 0.0), 1.0), "the cylinder's axis"),
        (ntf.RigidSphere((0.0, 2.0, 0.5), 1.0), "the sphere's centre"),
    ],
)
def test_an_obstacle_out_of_the_plane_is_refused(surface, message):
    mesh, _ = tagged_block(HEIGHT, MPI.COMM_SELF)
    with pytest.raises(ValueError, match=f"RigidObstacle: on a 2D mesh .*{message}"):
        continuum.RigidObstacle(surface, mesh)


@pytest.mark.serial
def test_an_obstacle_moving_out_of_the_plane_is_refused():
    mesh, _ = tagged_block(HEIGHT, MPI.COMM_SELF)
    line = ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), motion=lambda t: (0.0, -t, 0.1 * t))
    obstacle = continuum.RigidObstacle(line, mesh)  # at t = 0 still in the plane
    with pytest.raises(ValueError, match=r"must move in the xy-plane.*step time 0\.5"):
        obstacle.update(0.5)


@pytest.mark.serial
def test_circle_obstacle_gap_and_normal_in_2d():
    """A circle (a cylinder along z) as UFL gap and normal equals the numpy surface's."""
    mesh, _ = tagged_block(HEIGHT, MPI.COMM_SELF)
    circle = ntf.RigidCylinder(
        (0.3, 1.5, 0.0), (0.0, 0.0, 1.0), 1.0, motion=lambda t: (0.1 * t, -0.2 * t, 0.0)
    )
    obstacle = continuum.RigidObstacle(circle, mesh)
    obstacle.update(0.5)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u = dolfinx.fem.Function(V)
    shift = np.array([0.01, -0.02])
    u.x.array.reshape(-1, 2)[:] = shift
    g, n = obstacle.gap_and_normal(u)
    vertices = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])  # the P1 triangle's nodes
    cells = np.arange(mesh.topology.index_map(2).size_local, dtype=np.int32)
    values = compat.evaluate_expression(
        dolfinx.fem.Expression(ufl.as_vector([g, n[0], n[1]]), vertices), mesh, cells
    ).reshape(cells.size, 3, 3)
    x = mesh.geometry.x[compat.geometry_dofs(mesh)[cells]]  # (cells, 3 nodes, 3)
    x[..., :2] += shift
    points = x.reshape(-1, 3)
    np.testing.assert_allclose(values[..., 0].ravel(), circle.distance(points, 0.5), atol=1e-14)
    np.testing.assert_allclose(
        values[..., 1:].reshape(-1, 2), circle.normal(points, 0.5)[:, :2], atol=1e-14
    )
