"""Contact damping in dynamic steps (docs/method.md §29): a mass on a damped contact spring.

A stiff block rests on a clamped base through node-to-face springs (LINEAR law, slope K) with
``ContactDamping(c)`` and is pressed down by a constant traction from t = 0. It moves as a rigid
body in z: ``m z'' + c A z' + K A z = -F``, a 1-dof oscillator whose closed form (decay, log
decrement, period) the trapezoidal rule (alpha = 0, 100 increments per period) reproduces to
O((omega dt)^2). Serial and on 2 ranks (each block on its own process: the master face's
velocities come through the halo).
"""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_TOP, UPPER, UPPER_BOTTOM, UPPER_TOP, two_blocks

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

E, NU, RHO = 1.0e6, 0.0, 1.0
K = 100.0  # contact slope: k = K A with A = 1
HEIGHT = 0.5  # block 1 x 1 x HEIGHT: m = RHO HEIGHT
TRACTION = 1.0  # F on the top, downwards
ZETA = 0.05


def _mass_on_damped_spring(damping, comm, *, periods=3.0, per_period=100):
    """Mean z displacement of the block at each increment (times, values) and the problem."""
    mesh, cell_tags, ft = two_blocks(
        comm,
        lower=((0, 0, -0.5), (1, 1, 0.5), (1, 1, 1)),
        upper=((0, 0, 0), (1, 1, HEIGHT), (1, 1, 1)),
        partition=None if comm.size == 1 else lambda mid: (mid[:, 2] > 0).astype(np.int32),
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v, w = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    F = ufl.inner(ntf.small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    F += TRACTION * v[2] * ds(UPPER_TOP)
    x = V.tabulate_dof_coordinates()
    lower = np.flatnonzero(x[:, 2] < -1e-9)
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), lower.astype(np.int32), V)]
    for c in (0, 1):  # the block moves in z only
        sub = V.sub(c)
        dofs = dolfinx.fem.locate_dofs_geometrical((sub, sub.collapse()[0]), lambda p: p[2] > -1e-9)
        bcs.append(dolfinx.fem.dirichletbc(dolfinx.fem.Function(sub.collapse()[0]), dofs, sub))
    law = ntf.LinearLaw(slope=K, tension=1e-12).dynamic()
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(law, damping=damping),
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    mass = RHO * ufl.inner(w, v) * ufl.dx
    mean_z = dolfinx.fem.form(u[2] / HEIGHT * dx(UPPER))
    m, k = RHO * HEIGHT, K
    period = 2 * np.pi / np.sqrt(k / m)
    times, values = [0.0], [0.0]

    def record(result):
        times.append(result.time)
        values.append(comm.allreduce(dolfinx.fem.assemble_scalar(mean_z)))

    with ntf.ContactNewtonSolver(comm, problem) as solver:
        step = ntf.DynamicStep(
            mass,
            period=periods * period,
            initial_increment=period / per_period,
            fixed=True,
            alpha=0.0,
            on_increment=record,
        )
        step.run(solver, u)
    return np.array(times), np.array(values), problem


def _closed_form(t, c):
    """Penetration d(t) = -z(t) of the 1-dof oscillator under a step load, from rest."""
    m, k = RHO * HEIGHT, K
    omega = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    omega_d = omega * np.sqrt(1 - zeta**2)
    d_eq = TRACTION / k
    decay = np.exp(-zeta * omega * t)
    return d_eq * (
        1 - decay * (np.cos(omega_d * t) + zeta / np.sqrt(1 - zeta**2) * np.sin(omega_d * t))
    )


def _peaks(t, d):
    """Times and values of the local maxima of d (parabola through the three samples)."""
    i = np.flatnonzero((d[1:-1] > d[:-2]) & (d[1:-1] >= d[2:])) + 1
    a, b, c = d[i - 1], d[i], d[i + 1]
    shift = 0.5 * (a - c) / (a - 2 * b + c)
    dt = t[1] - t[0]
    return t[i] + shift * dt, b - 0.25 * (a - c) * shift


@pytest.mark.mpi
def test_log_decrement_of_a_mass_on_a_damped_contact_spring():
    """Peaks decay with the closed form's log decrement 2 pi zeta / sqrt(1 - zeta^2)."""
    comm = MPI.COMM_WORLD
    c = ZETA * 2 * np.sqrt(K * RHO * HEIGHT)  # per unit area; A = 1
    t, z, problem = _mass_on_damped_spring(ntf.ContactDamping(c), comm)
    assert comm.allreduce(problem.num_springs) == 4
    d = -z
    d_eq = TRACTION / K
    exact = _closed_form(t, c)
    assert np.abs(d - exact).max() <= 5e-3 * d_eq  # measured 2.7e-3 (the rule's O((omega dt)^2))
    peak_t, peak_d = _peaks(t, d)
    assert peak_t.size == 3
    decrement = np.log((peak_d[:-1] - d_eq) / (peak_d[1:] - d_eq))
    expected = 2 * np.pi * ZETA / np.sqrt(1 - ZETA**2)
    np.testing.assert_allclose(decrement, expected, rtol=2e-3)  # measured 8.9e-4
    period = 2 * np.pi / np.sqrt(K / (RHO * HEIGHT) * (1 - ZETA**2))
    np.testing.assert_allclose(np.diff(peak_t), period, rtol=1e-3)  # 3.5e-4: (omega dt)^2/12


@pytest.mark.serial
def test_without_damping_the_peaks_stay():
    """The control: without damping the same oscillator keeps its amplitude (alpha = 0)."""
    t, z, _ = _mass_on_damped_spring(None, MPI.COMM_SELF, periods=2.2)
    _, peak_d = _peaks(t, -z)
    d_eq = TRACTION / K
    np.testing.assert_allclose(peak_d - d_eq, d_eq, rtol=2e-3)


@pytest.mark.serial
def test_tangential_damping_only_acts_with_a_tangent_fraction():
    """Normal motion: the tangent fraction changes nothing (P n = n for every f)."""
    c = ZETA * 2 * np.sqrt(K * RHO * HEIGHT)
    runs = [
        _mass_on_damped_spring(ntf.ContactDamping(c, f), MPI.COMM_SELF, periods=0.6)[1]
        for f in (0.0, 1.0)
    ]
    np.testing.assert_allclose(runs[0], runs[1], rtol=0, atol=1e-12 * np.abs(runs[0]).max())


def test_bad_damping_is_named():
    with pytest.raises(ValueError, match="coefficient must be > 0"):
        ntf.ContactDamping(0.0)
    with pytest.raises(ValueError, match="tangent_fraction must be >= 0"):
        ntf.ContactDamping(1.0, -0.5)
    with pytest.raises(ValueError, match="damping must be a ContactDamping"):
        ntf.SurfaceInteraction(ntf.LinearLaw(slope=1.0, tension=1.0), damping=2.0)
