"""Dynamic steps (docs/method.md §12).

The HHT alpha method against a plain numpy integration of the same assembled matrices, cutbacks,
the tension-free LINEAR law, and the energy of a contact impact.
"""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_BOTTOM, LOWER_TOP, UPPER_BOTTOM, two_blocks

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.solvers.dynamics import newmark_parameters

E, NU, RHO = 1000.0, 0.3, 1.0


def _cantilever(comm=MPI.COMM_WORLD):
    """A 2 x 1 x 1 hexahedral bar clamped at x = 0, no contact."""
    mesh = dolfinx.mesh.create_box(
        comm, [[0.0, 0.0, 0.0], [2.0, 1.0, 1.0]], [2, 1, 1], dolfinx.mesh.CellType.hexahedron
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v, w = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    F = ufl.inner(ntf.small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    clamped = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[0], 0.0))
    dofs = dolfinx.fem.locate_dofs_topological(V, 2, clamped)
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), dofs, V)]
    mass = RHO * ufl.inner(w, v) * ufl.dx
    return u, F, bcs, mass, dofs


def _moving_cantilever(comm):
    """The cantilever as a problem and its initial velocity (u_z' = 1 off the clamped dofs).

    Returns the problem, the velocity, the residual and mass forms and the clamped dofs.
    """
    u, F, bcs, mass, clamped = _cantilever(comm)
    problem = ntf.ContactProblem(F, u, [], bcs)
    velocity = dolfinx.fem.Function(u.function_space)
    velocity.x.array.reshape(-1, 3)[:, 2] = 1.0
    velocity.x.array.reshape(-1, 3)[clamped] = 0.0
    return problem, velocity, F, mass, clamped


def _matrix(form, bcs=()):
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(form), list(bcs))
    A.assemble()
    return A.convert("dense").getDenseArray().copy()


@pytest.mark.serial
@pytest.mark.parametrize("alpha", [-0.05, 0.0, -1.0 / 3.0])
def test_hht_matches_numpy_reference(alpha):
    """Displacement, velocity, acceleration histories equal a numpy HHT on the same M and K."""
    problem, velocity, F, mass, clamped = _moving_cantilever(MPI.COMM_SELF)
    u = problem.u
    v0 = velocity.x.array.copy()
    dt, steps = 0.01, 6
    history = []
    with ntf.ContactNewtonSolver(MPI.COMM_SELF, problem) as solver:
        step = ntf.DynamicStep(
            mass,
            period=dt * steps,
            initial_increment=dt,
            fixed=True,
            alpha=alpha,
            velocity=velocity,
            on_increment=lambda r: history.append((u.x.array.copy(), velocity.x.array.copy())),
        )
        results = step.run(solver, u)
    assert len(results) == steps
    # reference: M a + (1 + alpha) K u_{n+1} - alpha K u_n = 0 on the free dofs
    K = _matrix(ufl.derivative(F, u))
    M = _matrix(mass)
    free = np.setdiff1d(np.arange(K.shape[0]), (clamped[:, None] * 3 + np.arange(3)).ravel())
    K, M = K[np.ix_(free, free)], M[np.ix_(free, free)]
    beta, gamma = newmark_parameters(alpha)
    x, vel, acc = np.zeros(free.size), v0[free], np.zeros(free.size)
    lhs = M / (beta * dt * dt) + (1 + alpha) * K
    for n in range(steps):
        pred = x + dt * vel + dt * dt * (0.5 - beta) * acc
        x_new = np.linalg.solve(lhs, M @ pred / (beta * dt * dt) + alpha * K @ x)
        acc_new = (x_new - pred) / (beta * dt * dt)
        vel = vel + dt * ((1 - gamma) * acc + gamma * acc_new)
        x, acc = x_new, acc_new
        scale = np.abs(x).max()
        assert np.abs(history[n][0][free] - x).max() <= 1e-9 * scale
        assert np.abs(history[n][1][free] - vel).max() <= 1e-8 * np.abs(vel).max()
    assert np.abs(x).max() > 1e-3  # the bar moved


@pytest.mark.serial
@pytest.mark.parametrize("alpha", [-0.05, 0.0])
@pytest.mark.parametrize("start_increment", [None, 0.02])
def test_load_from_the_start_matches_numpy_reference(alpha, start_increment):
    """A body force from the step start: the start ``(M + beta (1 + alpha) h^2 K) a_0 = f``.

    ``initial_acceleration_increment=h`` (ccx takes a tenth of the initial increment,
    docs/method.md §12.7; here h = dt, to make the effect large); None: the exact ``M a_0 = f``.
    The histories equal a numpy HHT with that start to 1e-9, and the two starts differ by more
    than 1e-3 of max |u| (measured 3.9e-3 to 4.3e-3).
    """
    u, F, bcs, mass, clamped = _cantilever(MPI.COMM_SELF)
    V = u.function_space
    v = ufl.TestFunction(V)
    load = ufl.as_vector([0.0, 0.0, -3.0])
    problem = ntf.ContactProblem(F - ufl.inner(load, v) * ufl.dx, u, [], bcs)
    dt, steps = 0.02, 5
    history = []
    with ntf.ContactNewtonSolver(MPI.COMM_SELF, problem) as solver:
        ntf.DynamicStep(
            mass,
            period=dt * steps,
            initial_increment=dt,
            fixed=True,
            alpha=alpha,
            initial_acceleration_increment=start_increment,
            on_increment=lambda r: history.append(u.x.array.copy()),
        ).run(solver, u)
    K = _matrix(ufl.derivative(F, u))
    M = _matrix(mass)
    f = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(ufl.inner(load, v) * ufl.dx))
    free = np.setdiff1d(np.arange(K.shape[0]), (clamped[:, None] * 3 + np.arange(3)).ravel())
    K, M, f = K[np.ix_(free, free)], M[np.ix_(free, free)], f.array[free]
    beta, gamma = newmark_parameters(alpha)
    lhs = M / (beta * dt * dt) + (1 + alpha) * K

    def reference(h: float | None) -> list[np.ndarray]:
        c = 0.0 if h is None else beta * (1 + alpha) * h * h
        x, vel, acc = np.zeros(free.size), np.zeros(free.size), np.linalg.solve(M + c * K, f)
        out = []
        for _ in range(steps):
            pred = x + dt * vel + dt * dt * (0.5 - beta) * acc
            x_new = np.linalg.solve(lhs, M @ pred / (beta * dt * dt) + f + alpha * K @ x)
            acc_new = (x_new - pred) / (beta * dt * dt)
            vel = vel + dt * ((1 - gamma) * acc + gamma * acc_new)
            x, acc = x_new, acc_new
            out.append(x)
        return out

    ours = reference(start_increment)
    other = reference(0.02 if start_increment is None else None)
    scale = max(np.abs(x).max() for x in ours)
    assert scale > 1e-3  # the bar moved
    assert max(np.abs(h[free] - x).max() for h, x in zip(history, ours)) <= 1e-9 * scale
    assert max(np.abs(y - x).max() for y, x in zip(other, ours)) > 1e-3 * scale


@pytest.mark.serial
def test_cutback_restores_the_state():
    """A failed first attempt leaves no trace: the end state of a run with the smaller increment."""
    runs = []
    for fail in (True, False):
        problem, velocity, _, mass, _ = _moving_cantilever(MPI.COMM_SELF)
        u = problem.u
        acceleration = dolfinx.fem.Function(u.function_space)
        with ntf.ContactNewtonSolver(MPI.COMM_SELF, problem) as solver:
            if fail:
                original = solver.solve
                calls = []

                def failing(w, original=original, calls=calls):
                    calls.append(1)
                    original(w)  # moves u, then fails
                    if len(calls) == 1:
                        raise ntf.ContactConvergenceError("injected failure")
                    return original(w)

                solver.solve = failing
            step = ntf.DynamicStep(
                mass,
                period=0.04,
                initial_increment=0.02 if fail else 0.01,
                growth_factor=1.0,
                velocity=velocity,
                acceleration=acceleration,
            )
            results = step.run(solver, u)
        runs.append((results, u.x.array.copy(), velocity.x.array.copy(), acceleration.x.array))
    (failed, *state_a), (plain, *state_b) = runs
    assert failed[0].attempt == 2 and [r.time for r in failed] == pytest.approx(
        [r.time for r in plain], abs=1e-14
    )
    for a, b in zip(state_a, state_b):
        assert np.abs(a - b).max() <= 1e-12 * max(np.abs(b).max(), 1.0)


def test_dynamic_linear_law_has_no_tension_and_exact_energy():
    law = ntf.LinearLaw.with_ccx_defaults(E).dynamic()
    d = np.array([-1e-3, -1e-9, 1e-6, 1e-4, 3e-3])
    assert np.all(law.pressure(d[:2]) == 0.0) and np.all(law.energy(d[:2], 0.5) == 0.0)
    static = ntf.LinearLaw.with_ccx_defaults(E)
    np.testing.assert_allclose(law.pressure(d[2:]), static.pressure(d[2:]), rtol=1e-15)
    h = 1e-9
    derivative = (law.energy(d[2:] + h, 0.5) - law.energy(d[2:] - h, 0.5)) / (2 * h)
    np.testing.assert_allclose(derivative, 0.5 * law.pressure(d[2:]), rtol=1e-5)
    slope = (law.pressure(d[2:] + h) - law.pressure(d[2:] - h)) / (2 * h)
    np.testing.assert_allclose(law.pressure_derivative(d[2:]), slope, rtol=1e-5)


@pytest.mark.mpi
def test_time_points_shorten_increments():
    """Increments that would pass a time point end on it; the next one takes the size before.

    ccx 2.20 on its deck: 0.03 over points 0.05 apart gives 0.03, 0.02, 0.03, 0.02 (method §27).
    Except the first: shortened, it is the size kept (0.02, 0.02, then growth; method §27.2).
    """
    u, F, bcs, mass, _ = _cantilever()
    problem = ntf.ContactProblem(F, u, [], bcs)
    points = [0.0, 0.05, 0.1]
    with ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem) as solver:
        dynamic = ntf.DynamicStep(
            mass, period=0.1, initial_increment=0.03, max_increment=0.03, time_points=points
        )
        times = [r.time for r in dynamic.run(solver, u)]
        static = ntf.StaticStep(
            period=1.0, initial_increment=0.4, max_increment=0.4, time_points=[0.5]
        )
        static_times = [r.time for r in static.run(solver, u)]
        # a first increment shortened by a point is the step's size from then on (ccx 2.20)
        first = ntf.DynamicStep(
            mass, period=0.1, initial_increment=0.03, max_increment=0.03, time_points=[0.02, 0.1]
        )
        first_times = [r.time for r in first.run(solver, u)]
    np.testing.assert_allclose(times, [0.03, 0.05, 0.08, 0.1], rtol=1e-12)
    np.testing.assert_allclose(static_times, [0.4, 0.5, 0.9, 1.0], rtol=1e-12)
    np.testing.assert_allclose(first_times, [0.02, 0.04, 0.07, 0.1], rtol=1e-12)
    with pytest.raises(ValueError, match="time_points must be increasing"):
        ntf.DynamicStep(mass, time_points=[0.5, 0.2])


def test_wrong_configuration_is_named():
    _, F, _, mass, _ = _cantilever(MPI.COMM_SELF)
    with pytest.raises(ValueError, match="alpha"):
        ntf.DynamicStep(mass, alpha=-0.5)
    with pytest.raises(TypeError, match="mass"):
        ntf.DynamicStep(F)
    with pytest.raises(ValueError, match="min_increment"):
        ntf.DynamicStep(mass, initial_increment=1e-9, min_increment=1e-8)
    for h in (0.0, -1.0, float("nan"), True):
        with pytest.raises(ValueError, match="initial_acceleration_increment"):
            ntf.DynamicStep(mass, initial_acceleration_increment=h)


@pytest.mark.serial
def test_impact_energy():
    """A block dropped onto a base: total energy kept within 1 % with ccx's alpha."""
    from dolfinx_ntf.solvers.dynamics import kinetic_energy

    mesh, _, ft = two_blocks(
        MPI.COMM_SELF,
        lower=((0, 0, -0.5), (1, 1, 0.5), (3, 3, 1)),
        upper=((0.25, 0.25, 0.0), (0.5, 0.5, 0.5), (2, 2, 2)),
        gap=0.005,
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v, w = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    sigma = ntf.small_strain_stress(u, E, NU)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx
    strain = dolfinx.fem.form(0.5 * ufl.inner(sigma, ufl.sym(ufl.grad(u))) * ufl.dx)
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_BOTTOM))
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), bottom, V)]
    law = ntf.LinearLaw.with_ccx_defaults(E, slope=10 * E).dynamic()
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(law),
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    mass = RHO * ufl.inner(w, v) * ufl.dx
    velocity = dolfinx.fem.Function(V)
    x = V.tabulate_dof_coordinates()
    velocity.x.array.reshape(-1, 3)[x[:, 2] > 1e-3, 2] = -0.5
    energies, springs = [], []

    def energy(_=None):
        spring = sum(float(r.energy.sum()) for r in ntf.contact_results(problem))
        total = kinetic_energy(mass, velocity) + dolfinx.fem.assemble_scalar(strain) + spring
        energies.append(total)
        springs.append(problem.num_springs)

    energy()
    with ntf.ContactNewtonSolver(MPI.COMM_SELF, problem) as solver:
        step = ntf.DynamicStep(
            mass, period=0.06, initial_increment=1e-3, fixed=True, velocity=velocity,
            on_increment=energy,
        )  # fmt: skip
        step.run(solver, u)
    energies = np.array(energies)
    assert springs[0] == 0 and max(springs) == 9  # open at the start, all 9 slave nodes in contact
    assert velocity.x.array.reshape(-1, 3)[x[:, 2] > 1e-3, 2].mean() > 0.3  # bounced back
    drift = np.abs(energies - energies[0]).max() / energies[0]
    assert drift < 0.01  # measured 0.21 % (0.57 % with alpha = -1/3, 0.09 % with alpha = 0)


@pytest.mark.mpi
def test_dynamic_step_is_the_same_in_parallel():
    """No contact: the bar's tip motion on any number of ranks equals the single-process one."""
    tips = []
    for comm in (MPI.COMM_SELF, MPI.COMM_WORLD):
        problem, velocity, _, mass, _ = _moving_cantilever(comm)
        u, V = problem.u, problem.u.function_space
        with ntf.ContactNewtonSolver(comm, problem) as solver:
            ntf.DynamicStep(mass, period=0.03, initial_increment=0.01, velocity=velocity).run(
                solver, u
            )
        x = V.tabulate_dof_coordinates()
        owned = V.dofmap.index_map.size_local
        tip = np.isclose(x[:owned, 0], 2.0)
        local = u.x.array.reshape(-1, 3)[:owned][tip, 2]
        values = np.concatenate(comm.allgather(local))
        tips.append((values.min(), values.max(), comm.allreduce(int(tip.sum()))))
    (serial_min, serial_max, n1), (parallel_min, parallel_max, n2) = tips
    assert n1 == n2 == 4 and serial_max > 1e-3
    assert parallel_min == pytest.approx(serial_min, rel=1e-10)
    assert parallel_max == pytest.approx(serial_max, rel=1e-10)


@pytest.mark.serial
def test_dynamic_deck_without_density_is_named(tmp_path):

    from impact_deck import write_impact_deck

    from dolfinx_ntf.calculix.job import run_job

    path = write_impact_deck(tmp_path, "nodensity", period=0.001)
    path.write_text(path.read_text().replace("*DENSITY\n1.0\n", ""))
    with pytest.raises(ValueError, match=r"needs one positive \*DENSITY in material STEEL"):
        run_job("nodensity", tmp_path, comm=MPI.COMM_SELF, progress=False)
