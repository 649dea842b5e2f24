"""UFL penalty and Nitsche contact against rigid surfaces, and the recovered boundary pressure."""

import numpy as np
import pytest
from helpers import BLOCK_CONTACT, BLOCK_TOP, rigid_block

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import continuum, measures
from dolfinx_ntf.fem.elasticity import small_strain_stress
from dolfinx_ntf.fem.pressure_recovery import BoundaryPressure

pytestmark = pytest.mark.mpi  # also on 2 ranks (make test)

E, NU, HEIGHT, DEPTH = 1000.0, 0.3, 0.5, 0.01


def _solve(method, cell_type="tetrahedron", **parameters):
    """The block pressed DEPTH into the rigid plane z = 0, in two increments."""
    V, tags, bcs = rigid_block(cell_type, HEIGHT)
    mesh = V.mesh
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)

    def stress(w):
        return small_strain_stress(w, E, NU)

    bulk = ufl.inner(stress(u), ufl.grad(v)) * ufl.dx
    obstacle = continuum.RigidObstacle(ntf.RigidPlane((0, 0, 0), (0, 0, 1)), mesh)
    ds = continuum.contact_measure(mesh, tags, BLOCK_CONTACT)
    if method == "penalty":
        K = parameters["penalty"]
        contact = continuum.penalty_residual(u, v, obstacle, ds, K)
        pressure = continuum.penalty_pressure(u, obstacle, K)
    else:
        gamma = continuum.nitsche_gamma(parameters["gamma0"], E, mesh)
        theta = parameters["theta"]
        contact = continuum.nitsche_residual(u, v, obstacle, ds, stress, gamma, theta)
        pressure = continuum.nitsche_pressure(u, obstacle, stress, gamma)
    newton = continuum.ContinuumNewton(bulk, contact, u, bcs)
    top = compat.boundary_values(bcs[-1])
    records = []
    for t in (0.5, 1.0):
        top.x.array[:] = -t * DEPTH
        records.append(newton.solve())
    recovery = BoundaryPressure(V, tags.find(BLOCK_CONTACT))
    recovery.from_expression(pressure)
    reaction = measures.facet_reaction(bulk, u, tags, BLOCK_TOP)
    newton.destroy()
    return u, recovery, reaction, records


def test_penalty_block_gives_the_uniform_pressure():
    K = 10 * E
    _u, recovery, reaction, records = _solve("penalty", penalty=K)
    # Uniaxial stress: E (DEPTH - d)/H = K d (the UFL penalty integrates on the reference area).
    d = E * DEPTH / HEIGHT / (K + E / HEIGHT)
    _nodes, p = recovery.nodal()
    assert np.abs(p / (K * d) - 1).max() < 1e-8
    assert reaction[2] == pytest.approx(-K * d, rel=1e-8)
    assert recovery.total() == pytest.approx(K * d, rel=1e-8)
    # Newton: one iteration for the new contact, one for the kink, at most.
    assert all(1 <= r.iterations <= 3 for r in records)
    assert records[-1].residual_norms[-1] <= 1e-10 * records[-1].residual_norms[0]


@pytest.mark.parametrize("theta", [1, 0, -1])
def test_nitsche_block_gives_the_exact_pressure(theta):
    u, recovery, reaction, _records = _solve("nitsche", gamma0=10.0, theta=theta)
    # Nitsche is consistent: no penetration, sigma = E DEPTH/H.
    expected = E * DEPTH / HEIGHT
    nodes, p = recovery.nodal()
    assert np.abs(p / expected - 1).max() < 1e-8
    assert reaction[2] == pytest.approx(-expected, rel=1e-8)
    bottom = _bottom_uz(u, nodes)
    assert np.abs(bottom).max() < 1e-10 * DEPTH


def _bottom_uz(u, nodes):
    return u.x.array.reshape(-1, 3)[nodes, 2]


def test_bad_arguments_are_named():
    V, tags, _bcs = rigid_block()
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    obstacle = continuum.RigidObstacle(ntf.RigidPlane((0, 0, 0), (0, 0, 1)), V.mesh)
    ds = continuum.contact_measure(V.mesh, tags, BLOCK_CONTACT)
    with pytest.raises(ValueError, match="theta must be 1, 0 or -1"):
        continuum.nitsche_residual(u, v, obstacle, ds, lambda w: w, 1.0, theta=2)
    with pytest.raises(ValueError, match="has no ufl_distance"):
        continuum.RigidObstacle(ntf.SignedDistanceSurface(np.sum, np.sum), V.mesh)
    with pytest.raises(ValueError, match="lumped recovery needs P1"):
        BoundaryPressure(compat.vector_space(V.mesh, "Lagrange", 2), tags.find(1), lumped=True)


def test_signed_distance_surface_in_ufl_matches_the_sphere():
    V, tags, _ = rigid_block()
    u = dolfinx.fem.Function(V)
    u.x.array[:] = 0.01
    center, radius = np.array([0.3, 0.2, 2.0]), 1.9
    sphere = continuum.RigidObstacle(ntf.RigidSphere(center, radius), V.mesh)
    general = continuum.RigidObstacle(
        ntf.SignedDistanceSurface(
            np.sum,
            np.sum,
            ufl_distance=lambda y: (
                ufl.sqrt(ufl.dot(y - ufl.as_vector(center), y - ufl.as_vector(center))) - radius
            ),
        ),
        V.mesh,
    )
    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=tags)(BLOCK_CONTACT)
    values = []
    for obstacle in (sphere, general):
        g, n = obstacle.gap_and_normal(u)
        values.append(
            [dolfinx.fem.assemble_scalar(dolfinx.fem.form(f * ds)) for f in (g, n[0], n[1], n[2])]
        )
    assert np.allclose(values[0], values[1], rtol=1e-12)
