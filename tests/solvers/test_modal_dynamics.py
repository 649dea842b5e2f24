"""Modal superposition (solvers/modal_dynamics.py) against closed forms, serial and 2 ranks."""

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress

LENGTH, E, RHO, AREA = 1.0, 1000.0, 2.0, 0.01


def _axial_bar():
    """A clamped-free bar (Q2, nu = 0, 16 cells) held to axial motion: a 1D wave guide."""
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD,
        [[0, 0, 0], [LENGTH, 0.1, 0.1]],
        [16, 1, 1],
        dolfinx.mesh.CellType.hexahedron,
    )
    V = compat.vector_space(mesh, "Lagrange", 2)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(small_strain_stress(u, E, 0.0), ufl.grad(v)) * ufl.dx
    every = dolfinx.mesh.locate_entities(mesh, 2, lambda x: np.full(x.shape[1], True))
    clamped = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[0], 0.0))
    bcs = [component_bc(V, 0, clamped), component_bc(V, 1, every), component_bc(V, 2, every)]
    return ntf.ContactProblem(F, u, [], bcs)


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
    problem = _axial_bar()
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
    problem = _axial_bar()
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
