"""UFL penalty and Nitsche contact against rigid surfaces, and the recovered boundary pressure."""

import inspect

import numpy as np
import pytest
from helpers import BLOCK_CONTACT, BLOCK_TOP, rigid_block

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import continuum, measures, pressure_recovery
from dolfinx_ntf.fem.elasticity import small_strain_stress
from dolfinx_ntf.fem.pressure_recovery import BoundaryPressure
from dolfinx_ntf.solvers import continuum as continuum_steps
from dolfinx_ntf.solvers.continuum import ContinuumIncrementSolver

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


# Load stepping through the step drivers (ContinuumIncrementSolver)


def _stress(w):
    return small_strain_stress(w, E, NU)


def _penalty_block(surface, penalty, divisions=(3, 4, 2), **options):
    """The block on ``surface`` with the penalty residual: (newton, u, bulk, tags, top values)."""
    V, tags, bcs = rigid_block("tetrahedron", HEIGHT, divisions)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    bulk = ufl.inner(_stress(u), ufl.grad(v)) * ufl.dx
    obstacle = continuum.RigidObstacle(surface, V.mesh)
    ds = continuum.contact_measure(V.mesh, tags, BLOCK_CONTACT)
    contact = continuum.penalty_residual(u, v, obstacle, ds, penalty)
    Vz, _ = compat.component_space(V, 2)
    top = dolfinx.fem.Function(Vz)  # a Python Function: a Load can drive it
    dofs = dolfinx.fem.locate_dofs_topological((V.sub(2), Vz), 2, tags.find(BLOCK_TOP))
    bcs = [*bcs[:-1], dolfinx.fem.dirichletbc(top, dofs, V.sub(2))]
    newton = continuum.ContinuumNewton(bulk, contact, u, bcs, **options)
    return newton, obstacle, bulk, tags, top


def _bottom_uz_all(u, tags):
    V = u.function_space
    dofs = dolfinx.fem.locate_dofs_topological(V, 2, tags.find(BLOCK_CONTACT))
    return u.x.array.reshape(-1, 3)[dofs, 2]


def test_static_step_loads_the_penalty_block_by_increments(progress_lines):
    ntf.log_progress(iterations=True)
    K = 10 * E
    plane = ntf.RigidPlane((0, 0, 0), (0, 0, 1))
    newton, _, bulk, tags, top = _penalty_block(plane, K)
    step = ntf.StaticStep(lambda t: top.x.array.fill(-t * DEPTH), initial_increment=0.25)
    results = step.run(ContinuumIncrementSolver(newton), newton.u)
    step_lines = list(progress_lines)
    # The first increment finds the contact (one update without it, one with it), then the
    # problem is linear: one update each.
    assert [r.iterations for r in results] == [2] + [1] * (len(results) - 1)
    assert len(results) >= 3 and results[-1].time == pytest.approx(1.0)
    assert all(r.attempt == 1 for r in results)
    nodes = 4 * 5  # the bottom's nodes, all in contact
    assert all(r.springs == nodes for r in results)
    # Uniaxial stress: E (DEPTH - d)/H = K d.
    d = E * DEPTH / HEIGHT / (K + E / HEIGHT)
    assert np.abs(_bottom_uz_all(newton.u, tags) / -d - 1).max() < 1e-8
    assert measures.facet_reaction(bulk, newton.u, tags, BLOCK_TOP)[2] == pytest.approx(-K * d)
    # The same as one solve of the whole load, from rest on the same mesh (two meshes built
    # alike need not be partitioned alike on several ranks).
    stepped = newton.u.x.array.copy()
    newton.u.x.array[:] = 0.0
    top.x.array[:] = -DEPTH
    newton.solve()
    assert np.abs(newton.u.x.array - stepped).max() < 1e-10 * DEPTH
    newton.destroy()
    # One progress line per increment, per-iteration lines on the newton logger.
    lines = [line for line in step_lines if "converged: time" in line]
    assert len(lines) == len(results)
    assert lines[-1].startswith(f" increment {len(results)} converged: time 1, 1 iterations")
    assert f"{nodes} contact elements" in lines[-1]
    assert sum(line.endswith(", converged") for line in step_lines) == len(results)
    assert " iteration 1: residual" in "\n".join(step_lines)


def test_a_solve_that_fails_is_cut_back(progress_lines):
    """A sphere pressed into the block: the whole load needs 6 updates, half of it 5."""
    ntf.log_progress()
    R, depth, divisions = 1.0, 0.05, (6, 6, 3)
    sphere = ntf.RigidSphere((0, 0, -R), R)
    reactions, histories = [], []
    for max_it in (30, 5):
        newton, _, bulk, tags, top = _penalty_block(sphere, 100 * E, divisions, max_it=max_it)
        step = ntf.StaticStep(lambda t, top=top: top.x.array.fill(-t * depth))
        results = step.run(ContinuumIncrementSolver(newton), newton.u)
        histories.append([(r.attempt, r.time, r.iterations) for r in results])
        reactions.append(measures.facet_reaction(bulk, newton.u, tags, BLOCK_TOP))
        newton.destroy()
    assert histories[0] == [(1, 1.0, 6)]
    assert histories[1][0][:2] == (2, 0.5)  # cut back once, by the step's cutback factor 0.5
    assert [h[1] for h in histories[1]] == [0.5, 1.0]
    assert all(h[2] <= 5 for h in histories[1])
    assert reactions[1] == pytest.approx(reactions[0], rel=1e-8)
    assert any(
        "no convergence in 5 iterations" in line and "cutting back" in line
        for line in progress_lines
    )


def test_a_newton_failure_raises_and_nonfinite_input_is_not_cut_back():
    sphere = ntf.RigidSphere((0, 0, -1.0), 1.0)
    newton, _, _, _, top = _penalty_block(sphere, 100 * E, max_it=1)
    solver = ContinuumIncrementSolver(newton)
    step = ntf.StaticStep(lambda t: top.x.array.fill(-t * 0.05), fixed=True)
    with pytest.raises(ntf.ContactConvergenceError, match=r"fixed increments.*no convergence in 1"):
        step.run(solver, newton.u)
    with pytest.raises(continuum.ContinuumNewtonError, match="no convergence") as error:
        newton.solve()  # alone it raises too, never returns quietly
    assert error.value.kind == "convergence"
    newton.u.x.array[:] = 0.0
    bad = ntf.StaticStep(lambda t: top.x.array.fill(np.nan), initial_increment=0.5)
    with pytest.raises(ntf.ContactSolverError, match="residual not finite at the start"):
        bad.run(solver, newton.u)
    with pytest.raises(ValueError, match="u must be the Function"):
        step.run(solver, dolfinx.fem.Function(newton.u.function_space))
    newton.destroy()


def test_run_steps_moves_the_obstacle_and_drives_loads():
    """The plane rises DEPTH in step 1 (its motion), the top goes down DEPTH in step 2 (a Load)."""
    K = 10 * E
    plane = ntf.RigidPlane((0, 0, 0), (0, 0, 1), motion=lambda t: (0.0, 0.0, t * DEPTH))
    newton, obstacle, _, tags, top = _penalty_block(plane, K)
    solver = ContinuumIncrementSolver(newton, [obstacle])
    rising = ntf.StaticStep(initial_increment=0.5)
    steps = [
        ntf.AnalysisStep(rising),
        ntf.AnalysisStep(
            ntf.StaticStep(initial_increment=0.5), loads=[ntf.Load(top, -DEPTH)], name="press"
        ),
    ]
    first, second = ntf.run_steps(solver, steps)
    assert [r.total_time for r in first + second] == pytest.approx([0.5, 1.0, 1.5, 2.0])
    # The plane stays at DEPTH (its motion at t = 1 of step 2); the block is squeezed by 2 DEPTH
    # over its height against the penalty: E (2 DEPTH - d)/H = K d, bottom at DEPTH - d.
    d = 2 * E * DEPTH / HEIGHT / (K + E / HEIGHT)
    assert np.abs(_bottom_uz_all(newton.u, tags) - (DEPTH - d)).max() < 1e-8 * DEPTH
    newton.destroy()


@pytest.mark.parametrize("module", [continuum, measures, pressure_recovery, continuum_steps])
def test_every_public_argument_is_documented(module):
    """Each public function, class and method of the module names each argument in its docstring."""
    missing = []
    for name in module.__all__:
        obj = getattr(module, name)
        targets = [(name, obj)]
        if inspect.isclass(obj):
            targets = [(name, obj.__init__)]
            doc = obj.__doc__ or ""
            targets += [
                (f"{name}.{member}", value)
                for member, value in vars(obj).items()
                if inspect.isfunction(value) and not member.startswith("_")
            ]
        for label, function in targets:
            text = doc if function is getattr(obj, "__init__", None) else function.__doc__ or ""
            params = [p for p in inspect.signature(function).parameters if p not in ("self", "_")]
            missing += [f"{label}: {p}" for p in params if f"{p}:" not in text]
    assert not missing
