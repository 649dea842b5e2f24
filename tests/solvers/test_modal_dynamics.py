"""Modal superposition (solvers/modal_dynamics.py) against closed forms, serial and 2 ranks."""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import axial_bar, block_on_springs

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

LENGTH, E, RHO, AREA = 1.0, 1000.0, 2.0, 0.01


def _tip_force(V, total: float) -> dolfinx.fem.Function:
    """``total`` along x spread evenly over the owned x dofs of the free end's nodes."""
    force = dolfinx.fem.Function(V)
    owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:owned]
    end = np.flatnonzero(np.isclose(x[:, 0], LENGTH))
    count = V.mesh.comm.allreduce(end.size, op=MPI.SUM)
    force.x.array[3 * end] = total / count
    force.x.scatter_forward()
    return force


@pytest.mark.mpi
@pytest.mark.parametrize("zeta1", [0.0, 0.05])
def test_step_load_on_a_bar_matches_the_modal_series(zeta1):
    """Tip step load ``P`` on a clamped-free bar, 3 modes, Rayleigh damping (alpha only).

    Closed form per mode: ``phi_n(L)^2 = 2 / (rho A L)``, ``f_n = P phi_n(L)`` and
    ``u(L, t) = sum_n (2 P / (rho A L omega_n^2)) [1 - e^(-zeta_n omega_n t) (cos omega_dn t +
    zeta_n omega_n / omega_dn sin omega_dn t)]`` with the exact ``omega_n = (2n - 1) pi c / 2L``.
    """
    problem, _ = axial_bar(LENGTH, E)
    V = problem.u.function_space
    v, w = ufl.TestFunction(V), ufl.TrialFunction(V)
    modes = ntf.contact_modes(problem, RHO * ufl.inner(w, v) * ufl.dx, 3)
    exact_omega = (2 * np.arange(1, 4) - 1) * np.pi / (2 * LENGTH) * np.sqrt(E / RHO)
    alpha = 2.0 * zeta1 * exact_omega[0]
    load = 0.3
    forces = ntf.modal_forces(modes, _tip_force(V, load))
    # |f_n| = P |phi_n(L)| (measured to the frequency accuracy of the mesh)
    np.testing.assert_allclose(np.abs(forces), load * np.sqrt(2 / (RHO * AREA * LENGTH)), rtol=1e-4)
    dynamics = ntf.ModalDynamics(modes, ntf.RayleighDamping(alpha=alpha))
    u = dolfinx.fem.Function(V)
    owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:owned]
    tip = np.flatnonzero(np.isclose(x[:, 0], LENGTH))
    for t_end, dt in ((0.013, 0.013), (0.05, 0.0037), (0.2, 0.04)):
        while dynamics.time < t_end - 1e-12:
            dynamics.advance(min(dt, t_end - dynamics.time), forces, forces)
        dynamics.displacement(u)
        zeta = alpha / (2 * exact_omega)
        wd = exact_omega * np.sqrt(1 - zeta**2)
        t = dynamics.time
        shape = 1 - np.exp(-zeta * exact_omega * t) * (
            np.cos(wd * t) + zeta * exact_omega / wd * np.sin(wd * t)
        )
        expected = np.sum(2 * load / (RHO * AREA * LENGTH * exact_omega**2) * shape)
        local = u.x.array[3 * tip]
        values = np.concatenate(V.mesh.comm.allgather(local))
        assert values.size > 0
        # the mesh's frequencies are within 4e-5 of the exact ones (test_modes.py)
        print("REL", t, np.abs(values / expected - 1).max())
        np.testing.assert_allclose(values, expected, rtol=2e-3, atol=1e-4 * abs(expected))
    # the physical state projects back on the modal coordinates: phi_i^T M u = q_i
    mass = modes.mass
    work = mass.createVecLeft()
    mass.mult(compat.petsc_vector(u), work)
    projected = np.array([compat.petsc_vector(m).dot(work) for m in modes.modes])
    np.testing.assert_allclose(
        projected, dynamics.q, rtol=1e-10, atol=1e-14 * np.abs(dynamics.q).max()
    )
    dynamics.velocity(u)
    mass.mult(compat.petsc_vector(u), work)
    projected = np.array([compat.petsc_vector(m).dot(work) for m in modes.modes])
    np.testing.assert_allclose(
        projected, dynamics.v, rtol=1e-10, atol=1e-14 * np.abs(dynamics.v).max()
    )
    work.destroy()
    modes.destroy()


def test_bad_input_is_refused():
    problem, _ = axial_bar(LENGTH, E)
    V = problem.u.function_space
    v, w = ufl.TestFunction(V), ufl.TrialFunction(V)
    modes = ntf.contact_modes(problem, RHO * ufl.inner(w, v) * ufl.dx, 2)
    with pytest.raises(ValueError, match="3 damping values for 2 modes"):
        ntf.ModalDynamics(modes, [0.1, 0.2, 0.3])
    dynamics = ntf.ModalDynamics(modes)
    with pytest.raises(ValueError, match="modal forces need shape"):
        dynamics.advance(0.1, np.zeros(3))
    with pytest.raises(ValueError, match="non-finite modal force"):
        dynamics.advance(0.1, np.array([np.nan, 0.0]))
    with pytest.raises(ValueError, match="increment must be finite and > 0"):
        dynamics.advance(-0.1, np.zeros(2))
    modes.destroy()


@pytest.mark.mpi
def test_contact_forces_as_modal_loads_match_the_modes_with_springs():
    """A preloaded block on LINEAR springs, struck from above: two complete modal bases.

    (a) the modes with the springs' stiffness, no contact force; (b) the bulk modes (the block
    floats: a rigid mode) with the springs' forces as nonlinear modal loads, iterated per
    increment. All 24 free dofs' modes: the two agree up to the springs' force taken linear
    within an increment, a second-order error (measured 7.3e-5, 1.9e-5, 5.0e-6 of the largest
    displacement with 50, 100, 200 increments per period of the bounce).
    """
    problem, pressure, _ = block_on_springs(0.2, 1e5, 1e3)
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", 5.0 * t)).run(solver, problem.u)
    V = problem.u.function_space
    v, w = ufl.TestFunction(V), ufl.TrialFunction(V)
    mass = 3.0 * ufl.inner(w, v) * ufl.dx
    free = 36 - 12  # 12 nodes, 3 dofs, rollers on x = 0 and y = 0 (6 nodes each)
    springs = ntf.contact_modes(problem, mass, free)
    bulk = ntf.contact_modes(problem, mass, free, springs=False)
    assert abs(bulk.eigenvalues[0]) < 1e-6 * springs.eigenvalues[0]  # floats without springs
    force = dolfinx.fem.Function(V)
    owned = V.dofmap.index_map.size_local
    top = np.flatnonzero(np.isclose(V.tabulate_dof_coordinates()[:owned, 2], 0.2))
    force.x.array[3 * top + 2] = -0.5
    force.x.scatter_forward()
    f_springs, f_bulk = ntf.modal_forces(springs, force), ntf.modal_forces(bulk, force)
    period = 2 * np.pi / np.sqrt(springs.eigenvalues[0])
    ua, ub = dolfinx.fem.Function(V), dolfinx.fem.Function(V)
    errors = []
    for n in (50, 100, 200):
        a = ntf.ModalDynamics(springs, ntf.RayleighDamping(alpha=20.0))
        b = ntf.ModalDynamics(bulk, ntf.RayleighDamping(alpha=20.0))
        contact = ntf.ModalContactForces(problem, bulk)
        assert np.abs(contact(np.zeros(free))).max() == 0.0  # relative to the preload
        iterations = []
        for _ in range(n):
            a.advance(period / n, f_springs, f_springs)
            step = b.advance_with_contact(period / n, f_bulk, contact, force_start=f_bulk)
            iterations.append(step)
        assert max(iterations) <= 5
        a.displacement(ua)
        b.displacement(ub)
        scale = V.mesh.comm.allreduce(np.abs(ua.x.array).max(), op=MPI.MAX)
        diff = V.mesh.comm.allreduce(np.abs(ua.x.array - ub.x.array).max(), op=MPI.MAX)
        errors.append(diff / scale)
    assert errors[-1] < 1e-5
    assert 3.5 < errors[0] / errors[1] < 4.5 and 3.5 < errors[1] / errors[2] < 4.5
    # without the springs' forces the floating block falls away: the forces matter
    free_fall = ntf.ModalDynamics(bulk, ntf.RayleighDamping(alpha=20.0))
    for _ in range(200):
        free_fall.advance(period / 200, f_bulk, f_bulk)
    free_fall.displacement(ub)
    diff = V.mesh.comm.allreduce(np.abs(ua.x.array - ub.x.array).max(), op=MPI.MAX)
    assert diff > 0.5 * scale
    for obj in (springs, bulk, solver, problem):
        obj.destroy()


@pytest.mark.mpi
def test_modal_contact_tangent_matches_finite_differences():
    """``-Phi^T K_c Phi`` of ModalContactForces.evaluate against central differences.

    Each evaluation re-pairs, so the spring areas follow the displacement: the tangent is exact
    with ``linearize_area=True`` (without it the area terms are missing, docs/method.md §6.3).
    """
    problem, pressure, _ = block_on_springs(0.2, 1e5, 1e3, linearize_area=True)
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", 5.0 * t)).run(solver, problem.u)
    V = problem.u.function_space
    v, w = ufl.TestFunction(V), ufl.TrialFunction(V)
    bulk = ntf.contact_modes(problem, 3.0 * ufl.inner(w, v) * ufl.dx, 6, springs=False)
    contact = ntf.ModalContactForces(problem, bulk)
    q = np.linspace(-1.0, 1.0, 6) * 1e-4  # the springs stay closed (overclosure 5e-3)
    forces, stiffness = contact.evaluate(q)
    assert np.abs(stiffness).max() > 0.0
    np.testing.assert_allclose(forces, contact(q), rtol=1e-14, atol=1e-14 * np.abs(forces).max())
    h = 1e-7
    for j in range(6):
        step = np.zeros(6)
        step[j] = h
        column = (contact(q + step) - contact(q - step)) / (2 * h)
        np.testing.assert_allclose(
            column, stiffness[:, j], rtol=1e-5, atol=1e-6 * np.abs(stiffness).max()
        )
    for obj in (bulk, solver, problem):
        obj.destroy()
