"""Natural frequencies with contact (solvers/modes.py) against closed forms, serial and 2 ranks."""

from mpi4py import MPI

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
from helpers import axial_bar, block_on_springs, drag_problem

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.solvers.modes import _is_symmetric, contact_modes, mass_matrix, tangent_stiffness


@pytest.mark.mpi
def test_axial_bar_frequencies_and_participation_match_the_closed_form():
    """A clamped-free bar held to axial motion (nu = 0): omega_n = (2n - 1) pi c / (2 L)."""
    length, E, rho, area = 1.0, 1000.0, 2.0, 0.01
    problem, _ = axial_bar(length, E)
    bcs = problem.bcs
    V = problem.u.function_space
    v, w = ufl.TestFunction(V), ufl.TrialFunction(V)
    modes = contact_modes(problem, rho * ufl.inner(w, v) * ufl.dx, 3)
    exact = (2 * np.arange(1, 4) - 1) * np.pi / (2 * length) * np.sqrt(E / rho)
    # P2 along 16 elements: measured 6e-8, 5e-6, 4e-5
    assert modes.angular_frequencies == pytest.approx(exact, rel=1e-4)
    assert modes.frequencies == pytest.approx(exact / (2 * np.pi), rel=1e-4)
    # Zero at the clamped end (Dirichlet rows: no spurious modes there) and in the held
    # directions (up to round-off at the free cell-centre dofs of Q2).
    values = modes.modes[0].x.array
    assert np.all(values[bcs[0].dof_indices()[0]] == 0.0)
    assert np.abs(values.reshape(-1, 3)[:, 1:]).max() < 1e-12 * np.abs(values).max()
    # phi_1 = sqrt(2 / (rho A L)) sin(pi x / 2L): Gamma_x = rho A int phi = sqrt(2 rho A L) 2/pi
    factors = modes.participation_factors()
    gamma = np.sqrt(2 * rho * area * length) * 2 / np.pi
    assert abs(factors[0, 0]) == pytest.approx(gamma, rel=1e-4)
    assert np.abs(factors[:, 1:4]).max() < 1e-12
    # The total effective mass along x: the bar's mass on the free dofs (less than rho A L).
    assert 0.9 * rho * area * length < modes.total_effective_mass()[0] < rho * area * length
    modes.destroy()
    problem.destroy()


@pytest.mark.mpi
def test_constraints_are_eliminated_from_both_matrices_and_expanded_in_the_modes():
    length, E, rho = 1.0, 1000.0, 2.0
    plain, _ = axial_bar(length, E)
    tied, end = axial_bar(length, E, tie_end=True)
    assert MPI.COMM_WORLD.allreduce(len(tied.constraints)) == 8  # 9 end nodes, one corner

    def mass(problem):
        V = problem.u.function_space
        return rho * ufl.inner(ufl.TrialFunction(V), ufl.TestFunction(V)) * ufl.dx

    with pytest.raises(ValueError, match="arguments must be on the problem's space"):
        contact_modes(plain, mass(tied))
    expected = contact_modes(plain, mass(plain), 3)
    modes = contact_modes(tied, mass(tied), 3)
    assert modes.eigenvalues == pytest.approx(expected.eigenvalues, rel=1e-9)
    for mode in modes.modes:  # the dependent dofs carry the corner's value
        values = mode.x.array.reshape(-1, 3)[end, 0]
        if values.size:  # the process of the end cell
            assert np.abs(values - values[0]).max() <= 1e-12 * np.abs(mode.x.array).max()
            assert abs(values[0]) > 0.0
    for obj in (expected, modes, plain, tied):
        obj.destroy()


@pytest.mark.mpi
def test_block_on_contact_springs_bounces_at_the_springs_frequency():
    """The closed springs (stiffness p'(d) A) carry a block: a rod on an end spring.

    Exact (nu = 0, free top): E beta tan(beta H) = k / A with omega = beta sqrt(E / rho); nearly
    the rigid block's sqrt(k / m) for a stiff block. Without the springs the block would be free
    (no finite lowest frequency).
    """
    K, height, E, rho, load = 1e3, 0.2, 1e5, 3.0, 5.0
    problem, pressure, law = block_on_springs(height, E, K, (2, 2, 4))
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", load * t)).run(solver, problem.u)
    (result,) = ntf.contact_results(problem)
    comm = MPI.COMM_WORLD
    overclosure = -comm.allreduce(float(result.clearance.sum())) / comm.allreduce(
        result.clearance.size
    )
    assert overclosure == pytest.approx(load / K, rel=1e-3)  # the block sits on the springs
    k = float(law.pressure_derivative(overclosure))  # times the unit area
    v, w = ufl.TestFunction(problem.u.function_space), ufl.TrialFunction(problem.u.function_space)
    modes = contact_modes(problem, rho * ufl.inner(w, v) * ufl.dx, 2)
    beta = scipy.optimize.brentq(
        lambda b: E * b * np.tan(b * height) - k, 1e-9, np.pi / (2 * height) - 1e-9
    )
    bounce = beta * np.sqrt(E / rho)
    # 4 linear elements over the height: measured 5.2e-6 above the rod's value
    assert modes.angular_frequencies[0] == pytest.approx(bounce, rel=1e-4)
    assert modes.angular_frequencies[0] != pytest.approx(np.sqrt(k / (rho * height)), rel=1e-4)
    assert modes.angular_frequencies[1] > 2 * bounce  # the rollers hold the other motions
    # The bounce carries (nearly) the whole mass along z: Gamma_z^2 ~ m.
    factors = modes.participation_factors()
    assert factors[0, 2] ** 2 == pytest.approx(rho * height, rel=1e-3)
    modes.destroy()
    solver.destroy()
    problem.destroy()


@pytest.mark.mpi
def test_the_tangent_includes_the_springs_and_asks_for_a_solved_problem():
    problem, pressure, _ = block_on_springs(0.2, 1e5, 1e3, (2, 2, 4))
    with pytest.raises(ValueError, match="never paired"):
        tangent_stiffness(problem)
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", 5.0 * t)).run(solver, problem.u)
    K = tangent_stiffness(problem)
    # Rigid motion along z: only the springs resist it, sum of all entries = k = K * A (= 1e3).
    ones = K.createVecRight()
    V = problem.u.function_space
    rigid = dolfinx.fem.Function(V)
    rigid.interpolate(lambda x: np.vstack([0 * x[0], 0 * x[0], 1 + 0 * x[0]]))
    rigid.x.array[np.concatenate([bc.dof_indices()[0] for bc in problem.bcs])] = 0.0
    K.mult(compat.petsc_vector(rigid), ones)
    assert compat.petsc_vector(rigid).dot(ones) == pytest.approx(1e3, rel=1e-6)
    for obj in (K, ones):
        obj.destroy()
    with pytest.raises(TypeError, match="bilinear"):
        contact_modes(problem, ufl.inner(rigid, ufl.TestFunction(V)) * ufl.dx)
    solver.destroy()
    problem.destroy()


@pytest.mark.serial
def test_unsymmetric_tangent_with_friction_matches_a_dense_eigensolver():
    """Sliding friction makes K unsymmetric: SLEPc's non-Hermitian path against scipy's eig."""
    problem, pressure, set_drag, _ = drag_problem()
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)

    def load(t):
        pressure.value = 10.0 * t
        set_drag(0.02 * t)

    ntf.StaticStep(load).run(solver, problem.u)
    assert problem.has_friction
    K = tangent_stiffness(problem)
    assert not _is_symmetric(K)
    V = problem.u.function_space
    mass = ufl.inner(ufl.TrialFunction(V), ufl.TestFunction(V)) * ufl.dx
    M = mass_matrix(problem, mass)
    dense_k, dense_m = (A.convert("dense").getDenseArray() for A in (K, M))
    free = np.flatnonzero(np.diag(dense_m) != 0.0)
    values = scipy.linalg.eigvals(dense_k[np.ix_(free, free)], dense_m[np.ix_(free, free)])
    lowest = values[np.argsort(values.real)[:4]]
    assert np.abs(lowest.imag).max() <= 1e-8 * lowest.real.max()  # (higher pairs may be complex)
    modes = contact_modes(problem, mass, 4)
    # measured: equal to the last digits
    assert modes.eigenvalues == pytest.approx(lowest.real, rel=1e-8)
    # Asked for modes up to the first complex pair, it refuses (no real modes there).
    ordered = values[np.argsort(values.real)]
    first_complex = int(np.flatnonzero(np.abs(ordered.imag) > 1e-8 * np.abs(ordered.real))[0])
    with pytest.raises(ntf.ContactSolverError, match="is complex"):
        contact_modes(problem, mass, first_complex + 1)
    for obj in (K, M, modes, solver, problem):
        obj.destroy()
