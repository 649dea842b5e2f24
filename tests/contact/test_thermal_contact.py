"""Thermal contact (contact/thermal.py, solvers/coupled.py, solvers/staggered.py): closed forms.

The coupled (monolithic) Jacobian is also checked against finite differences of its residual.

Two bars stacked along z on rollers (x = 0, y = 0 planes, the lower bottom), meshes matching at
the interface (node-to-face contact passes the patch test only there), the lower block's top the
master surface: with temperatures prescribed on the far ends and the
sides insulated, temperature and stress are uniform across the bars' sections and the hexahedra
are exact, so the finite element answers equal the closed forms to the solver tolerance.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
import scipy.optimize
from helpers import (
    LOWER_BOTTOM,
    LOWER_TOP,
    PUNCH,
    UPPER,
    UPPER_BOTTOM,
    UPPER_TOP,
    YOUNGS_MODULUS,
    solve_increments,
    two_blocks,
)

import dolfinx.fem
import dolfinx.io
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.contact.thermal import ThermalContactProblem
from dolfinx_ntf.fem.constraints import LinearConstraintBlock
from dolfinx_ntf.fem.elasticity import component_bc
from dolfinx_ntf.fem.thermal import thermoelastic_stress
from dolfinx_ntf.kernels.gap_conductance import GapConductance
from dolfinx_ntf.solvers.coupled import ThermoMechanicalContact
from dolfinx_ntf.solvers.staggered import solve_staggered

#: No lateral strain from the axial stress: the spring areas stay the reference ones.
POISSON_RATIO = 0.0
CONDUCTIVITY = 2.0
T_BOTTOM, T_TOP = 400.0, 300.0  # the lower (master) bar is the hotter
#: h(p): 20 at p = 0 rising to 220 at p = 100, constant beyond.
TABLE = GapConductance.from_rows([(20.0, 0.0, 0.0), (220.0, 100.0, 0.0)])
LAW = ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)


def _bars(gap: float = 0.0):
    """Mesh, tags, displacement space, thermal space, temperature and its Dirichlet conditions."""
    mesh, _, ft = two_blocks(
        upper=((0, 0, 0), (1, 1, 1), (3, 3, 2)), lower=((0, 0, -1), (1, 1, 1), (3, 3, 4)), gap=gap
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    Q = compat.scalar_space(mesh, "Lagrange", 1)
    T = dolfinx.fem.Function(Q)
    bcs_T = [
        dolfinx.fem.dirichletbc(
            dolfinx.fem.Constant(mesh, value),
            dolfinx.fem.locate_dofs_topological(Q, 2, ft.find(tag)),
            Q,
        )
        for tag, value in ((LOWER_BOTTOM, T_BOTTOM), (UPPER_TOP, T_TOP))
    ]
    return mesh, ft, V, Q, T, bcs_T


def _rollers(V, ft, *, constrained: bool):
    """Rollers on x = 0, y = 0 and the lower bottom; ``constrained``: also on x = 1, y = 1 (no
    lateral strain: the thermal strain of a gradient along z then bends nothing) and the upper
    top held in z."""
    mesh = V.mesh
    planes = [(0, 0.0), (1, 0.0)] + ([(0, 1.0), (1, 1.0)] if constrained else [])
    bcs = [
        component_bc(V, axis, dolfinx.mesh.locate_entities_boundary(
            mesh, 2, lambda x, a=axis, c=coordinate: np.isclose(x[a], c)
        ))
        for axis, coordinate in planes
    ]  # fmt: skip
    bcs.append(component_bc(V, 2, ft.find(LOWER_BOTTOM)))
    if constrained:
        bcs.append(component_bc(V, 2, ft.find(UPPER_TOP)))
    return bcs


def _pair(ft):
    return ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(LAW),
    )


def _heat_residual(T, Q):
    return CONDUCTIVITY * ufl.inner(ufl.grad(T), ufl.grad(ufl.TestFunction(Q))) * ufl.dx


def _interface_temperatures(T, mesh):
    """(min, max) of T over the nodes at z = 0 (both bodies' interface nodes), all processes."""
    z = T.function_space.tabulate_dof_coordinates()[:, 2]
    values = T.x.array[np.isclose(z, 0.0)]
    low = mesh.comm.allreduce(values.min(initial=np.inf), op=MPI.MIN)
    high = mesh.comm.allreduce(values.max(initial=-np.inf), op=MPI.MAX)
    return low, high


def _total_flow(thermal):
    local = sum(float(q.sum()) for q in thermal.heat_flows)
    return thermal.T.function_space.mesh.comm.allreduce(local, op=MPI.SUM)


@pytest.mark.mpi
def test_heat_flow_through_pressure_dependent_conductance(tmp_path_factory) -> None:
    """Jump T_m - T_s = q/h(p) with the pressure p of the load; flow q through the series."""
    load = 40.0
    mesh, ft, V, Q, T, bcs_T = _bars()
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    sigma = ntf.small_strain_stress(u, YOUNGS_MODULUS, POISSON_RATIO)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx + pressure * ufl.inner(
        ufl.FacetNormal(mesh), v
    ) * ds(UPPER_TOP)
    problem = ntf.ContactProblem(F, u, [_pair(ft)], _rollers(V, ft, constrained=False))
    thermal = ThermalContactProblem(_heat_residual(T, Q), T, problem, TABLE, bcs_T)
    passes = solve_staggered(lambda: solve_increments(problem, pressure, load, 1), thermal)
    assert passes <= 3  # one-way coupling: the second pass changes nothing

    h = 20.0 + 200.0 * load / 100.0
    flux = (T_BOTTOM - T_TOP) / (1.0 / CONDUCTIVITY + 1.0 / h + 1.0 / CONDUCTIVITY)
    slave, master = T_TOP + flux / CONDUCTIVITY, T_BOTTOM - flux / CONDUCTIVITY
    np.testing.assert_allclose(_interface_temperatures(T, mesh), (slave, master), rtol=1e-10)
    np.testing.assert_allclose(_total_flow(thermal), flux, rtol=1e-10)
    np.testing.assert_allclose(master - slave, flux / h, rtol=1e-12)  # the jump q/h
    # Outputs: per spring (every slave node has one) and the flux density as a field.
    (res,) = ntf.thermal_results(thermal)
    assert mesh.comm.allreduce(res.flow.size) == 16
    np.testing.assert_allclose(res.flux, flux, rtol=1e-10)
    np.testing.assert_allclose(res.conductance, h, rtol=1e-12)
    np.testing.assert_allclose(res.master_temperature - res.temperature, flux / h, rtol=1e-9)
    field = ntf.heat_flux_field(thermal)
    z = Q.tabulate_dof_coordinates()[:, 2]
    values = field.x.array[np.isclose(z, 0.0)]
    assert np.all(np.isclose(values, flux, rtol=1e-10) | (values == 0.0))
    owned = field.x.array[: Q.dofmap.index_map.size_local]
    assert mesh.comm.allreduce(int(np.count_nonzero(owned))) == 16
    path = mesh.comm.bcast(str(tmp_path_factory.mktemp("xdmf") / "thermal.xdmf"), root=0)
    T.name = "temperature"
    with dolfinx.io.XDMFFile(mesh.comm, path, "w") as f:
        f.write_mesh(mesh)
        f.write_function(T, 0.0)
        f.write_function(field, 0.0)
    thermal.destroy()
    problem.destroy()


@pytest.mark.mpi
@pytest.mark.parametrize("gap", [5e-5, 1e-2])
def test_heat_flows_only_across_generated_springs(gap: float) -> None:
    """An open spring (clearance 5e-5, below the cutoff 1e-3 sqrt(A) >= 8e-5 of every slave node)
    conducts with h(p) at its (tension) pressure, the table's first value; beyond the cutoff there
    is no spring and no heat flow (CalculiX: heat flows only across generated springs)."""
    mesh, ft, V, Q, T, bcs_T = _bars(gap)
    u = dolfinx.fem.Function(V)
    F = (
        ufl.inner(
            ntf.small_strain_stress(u, YOUNGS_MODULUS, POISSON_RATIO), ufl.grad(ufl.TestFunction(V))
        )
        * ufl.dx
    )
    problem = ntf.ContactProblem(F, u, [_pair(ft)], _rollers(V, ft, constrained=True))
    thermal = ThermalContactProblem(_heat_residual(T, Q), T, problem, TABLE, bcs_T)
    solve_staggered(
        lambda: solve_increments(problem, dolfinx.fem.Constant(mesh, 0.0), 1.0, 1), thermal
    )
    springs = mesh.comm.allreduce(problem.num_springs)
    if gap < 1e-3:
        assert springs == 16
        assert float(LAW.pressure(-gap)) < 0.0  # the law's tension: below the table, h = 20
        h = 20.0
        flux = (T_BOTTOM - T_TOP) / (2.0 / CONDUCTIVITY + 1.0 / h)
        np.testing.assert_allclose(_total_flow(thermal), flux, rtol=1e-10)
    else:
        assert springs == 0
        assert _total_flow(thermal) == 0.0
        z = Q.tabulate_dof_coordinates()[:, 2]
        upper = dolfinx.fem.locate_dofs_topological(Q, 3, _cells(mesh, upper=True))
        np.testing.assert_allclose(T.x.array[upper], T_TOP, rtol=1e-12)
        assert z.size
    thermal.destroy()
    problem.destroy()


def test_refuses_a_rigid_master() -> None:
    _mesh, ft, V, Q, T, _ = _bars()
    u = dolfinx.fem.Function(V)
    F = ufl.inner(ntf.small_strain_stress(u, 1.0, 0.3), ufl.grad(ufl.TestFunction(V))) * ufl.dx
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
        ntf.SurfaceInteraction(LAW),
        name="floor",
    )
    problem = ntf.ContactProblem(F, u, [pair], _rollers(V, ft, constrained=True))
    with pytest.raises(NotImplementedError, match=r"\['floor'\] have a rigid master"):
        ThermalContactProblem(_heat_residual(T, Q), T, problem, TABLE)
    problem.destroy()


def _closed_form(gap: float, alpha: float, t_ref: float) -> tuple[float, float]:
    """Contact force and heat flow of the bars heated closed: the fixed point in the flow q.

    Per unit section (the bars keep their section): q = k dT/dz in each bar (length 1) and
    q = h(p) (T_m - T_s) across the springs; the pressure p = p(d) compresses both bars and fills
    the closure of their free expansions beyond the gap with the penetration d.
    """

    def state(q: float) -> tuple[float, float]:
        t_slave, t_master = T_TOP + q / CONDUCTIVITY, T_BOTTOM - q / CONDUCTIVITY
        means = (0.5 * (T_BOTTOM + t_master), 0.5 * (T_TOP + t_slave))
        closure = alpha * sum(m - t_ref for m in means) - gap
        d = scipy.optimize.brentq(
            lambda d: float(LAW.pressure(d)) * 2.0 / YOUNGS_MODULUS + d - closure,
            -1e-3, 1.0, xtol=1e-15, rtol=1e-15,
        )  # fmt: skip
        return float(LAW.pressure(d)), t_master - t_slave

    def balance(q: float) -> float:
        p, jump = state(q)
        return q - TABLE.evaluate([p], [0.0])[0][0] * jump

    q = scipy.optimize.brentq(balance, 0.0, (T_BOTTOM - T_TOP) * CONDUCTIVITY / 2, xtol=1e-14)
    return state(q)[0], q


@pytest.mark.mpi
def test_thermal_expansion_closes_gap() -> None:
    """The heated bars, held at both ends, close the gap: force and flux from the closed form."""
    gap, alpha, t_ref = 0.02, 2e-4, 250.0
    mesh, ft, V, Q, T, bcs_T = _bars(gap)
    T.x.array[:] = t_ref
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    ramp = dolfinx.fem.Constant(mesh, 0.0)  # the expansion grows with the step time
    sigma = thermoelastic_stress(u, T, YOUNGS_MODULUS, POISSON_RATIO, ramp * alpha, t_ref)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx
    problem = ntf.ContactProblem(F, u, [_pair(ft)], _rollers(V, ft, constrained=True))
    thermal = ThermalContactProblem(_heat_residual(T, Q), T, problem, [TABLE], bcs_T)
    passes = solve_staggered(
        lambda: solve_increments(problem, ramp, 1.0, 2), thermal, rtol=1e-10, max_passes=60
    )
    total, flux = _closed_form(gap, alpha, t_ref)
    assert total > 1.0 and passes > 2  # two-way coupling
    force = ntf.contact_force(problem)
    np.testing.assert_allclose(force[2], total, rtol=1e-9)
    np.testing.assert_allclose(force[:2], 0.0, atol=1e-8 * total)
    np.testing.assert_allclose(_total_flow(thermal), flux, rtol=1e-9)
    thermal.destroy()
    problem.destroy()


@pytest.mark.mpi
def test_refuses_a_temperature_of_another_space() -> None:
    mesh, ft, V, Q, T, _ = _bars()
    u, v, q = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TestFunction(Q)
    F = ufl.inner(ntf.small_strain_stress(u, 1.0, 0.3), ufl.grad(v)) * ufl.dx
    problem = ntf.ContactProblem(F, u, [_pair(ft)], _rollers(V, ft, constrained=False))
    P2 = dolfinx.fem.Function(compat.scalar_space(mesh, "Lagrange", 2))
    with pytest.raises(ValueError, match="number its nodes like the displacement"):
        ThermalContactProblem(_heat_residual(P2, P2.function_space), P2, problem, TABLE)
    with pytest.raises(ValueError, match="2 conductances for 1 contact pairs"):
        ThermalContactProblem(_heat_residual(T, Q), T, problem, [TABLE, TABLE])
    with pytest.raises(ValueError, match="conductance_pressure must be 'contact' or 'ccx'"):
        ThermalContactProblem(_heat_residual(T, Q), T, problem, TABLE, conductance_pressure="p")
    heat = CONDUCTIVITY * ufl.inner(ufl.grad(T), ufl.grad(q)) * ufl.dx
    thermal = ThermalContactProblem(heat, T, problem, TABLE)
    with pytest.raises(ValueError, match="F does not depend on the temperature"):
        ThermoMechanicalContact(F, thermal)
    thermal2 = ThermalContactProblem(heat + ufl.div(u) * q * ufl.dx, T, problem, TABLE)
    F_T = F + ufl.inner(T * ufl.Identity(3), ufl.grad(v)) * ufl.dx
    with pytest.raises(NotImplementedError, match="heat residual depends on the displacement"):
        ThermoMechanicalContact(F_T, thermal2)
    problem.destroy()


def _punch(alpha: float = 1e-3, t_ref: float = 300.0, cell_mean: bool = False):
    """A punch on a block (slave nodes inside master faces), thermal expansion and heat flow.

    ``cell_mean``: the thermal strain of the cells' mean temperatures (``CellTemperature``).
    """
    mesh, cells, ft = two_blocks(MPI.COMM_SELF, upper=PUNCH)
    V = compat.vector_space(mesh, "Lagrange", 1)
    Q = compat.scalar_space(mesh, "Lagrange", 1)
    u, T = dolfinx.fem.Function(V), dolfinx.fem.Function(Q)
    cell = ntf.CellTemperature(T) if cell_mean else None
    T_strain = cell.T_c if cell_mean else T
    sigma = ntf.thermoelastic_stress(u, T_strain, YOUNGS_MODULUS, 0.3, alpha, t_ref)
    F = ufl.inner(sigma, ufl.grad(ufl.TestFunction(V))) * ufl.dx
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_BOTTOM))
    top = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(UPPER_TOP))
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(3), bottom, V),
        dolfinx.fem.dirichletbc(np.zeros(3), top, V),
    ]
    problem = ntf.ContactProblem(F, u, [_pair(ft)], bcs, contact_start_slope=False)
    bcs_T = [
        dolfinx.fem.dirichletbc(
            dolfinx.fem.Constant(mesh, 350.0),
            dolfinx.fem.locate_dofs_topological(Q, 2, ft.find(LOWER_BOTTOM)),
            Q,
        )
    ]
    thermal = ThermalContactProblem(_heat_residual(T, Q), T, problem, TABLE, bcs_T)
    mesh.topology.create_connectivity(3, 3)  # dolfinx >= 0.9 locates cell dofs with it
    punch = dolfinx.fem.locate_dofs_topological(V, 3, cells.find(UPPER))
    if cell_mean:
        with pytest.raises(ValueError, match="F does not depend on the temperature"):
            ThermoMechanicalContact(F, thermal)  # F holds T_c, not T
        other = ntf.CellTemperature(dolfinx.fem.Function(Q))
        with pytest.raises(ValueError, match=r"cell_temperature is not made from thermal\.T"):
            ThermoMechanicalContact(F, thermal, cell_temperature=other)
        other.destroy()
    coupled = ThermoMechanicalContact(F, thermal, cell_temperature=cell)
    return coupled, punch, [bottom, top], bcs_T[0].dof_indices()[0]


@pytest.mark.parametrize("cell_mean", [False, True], ids=["T", "cell-mean-T"])
def test_coupled_jacobian_matches_finite_differences(cell_mean: bool) -> None:
    """All four blocks, springs included, at a penetrated state with a varying temperature.

    ``cell-mean-T``: the thermal strain of each cell's mean temperature (CalculiX's C3D8,
    ``CellTemperature``): the block ∂F_u/∂T is ∂F_u/∂T_c P. Also: without the coupling blocks
    (``coupling_blocks=False``, ccx's iteration) the diagonal blocks are the same and the
    off-diagonal ones vanish.
    """
    coupled, punch, fixed_u, fixed_T = _punch(cell_mean=cell_mean)
    contact, thermal = coupled.contact, coupled.thermal
    u, T = contact.u, thermal.T
    x = u.function_space.tabulate_dof_coordinates()
    rng = np.random.default_rng(7)
    values = u.x.array.reshape(-1, 3)
    values[punch, 2] = -0.01 * (1.2 - x[punch, 2])  # the punch pressed 0.006..0.012 into the block
    values += 1e-3 * rng.uniform(-1, 1, values.shape)
    for dofs in fixed_u:
        values[dofs] = 0.0
    T.x.array[:] = (
        300.0 + 40.0 * x[:, 2] + 20.0 * x[:, 0] * x[:, 1] + rng.uniform(-2, 2, x.shape[0])
    )
    T.x.array[fixed_T] = 350.0
    contact.begin_increment(1.0)
    assert contact.num_springs == 16
    coupled.evaluate()
    r0 = coupled.residual()
    A = coupled.jacobian()
    dense = A.convert("dense").getDenseArray().copy()
    A.destroy()
    n_u = u.x.array.size
    free = np.ones(dense.shape[0], dtype=bool)
    free[np.concatenate([3 * d[:, None] + np.arange(3) for d in fixed_u]).ravel()] = False
    free[n_u + fixed_T] = False
    columns = np.flatnonzero(free)
    fd = np.zeros((dense.shape[0], columns.size))
    step = 1e-6
    for j, col in enumerate(columns):
        field, index = (u, col) if col < n_u else (T, col - n_u)
        results = []
        for sign in (1.0, -1.0):
            field.x.array[index] += sign * step
            coupled.evaluate()
            results.append(coupled.residual())
            field.x.array[index] -= sign * step
        fd[:, j] = (results[0] - results[1]) / (2 * step)
    coupled.evaluate()
    np.testing.assert_allclose(coupled.residual(), r0, rtol=0, atol=1e-12 * np.abs(r0).max())
    exact = dense[np.ix_(free, columns)]
    fd = fd[free]
    error = np.abs(exact - fd).max() / np.abs(fd).max()
    assert error <= 1e-6, error
    # The cross blocks are there and right: heat flows by displacement, expansion by temperature.
    rows_T, columns_u = free[:n_u].sum(), columns < n_u
    block = fd[rows_T:][:, columns_u]
    assert np.abs(block).max() > 1e-3 * np.abs(fd).max()
    assert np.abs(exact[rows_T:][:, columns_u] - block).max() <= 1e-6 * np.abs(block).max()
    assert np.abs(fd[:rows_T][:, ~columns_u]).max() > 0
    if cell_mean:  # T_c is the mean of each cell's nodal temperatures
        cell = coupled.cell_temperature
        Q0 = cell.T_c.function_space
        means = T.x.array[compat.cell_dofs(T.function_space)].mean(axis=1)
        np.testing.assert_allclose(cell.T_c.x.array[compat.cell_dofs(Q0)[:, 0]], means, rtol=1e-14)
    coupled.coupling_blocks = False
    coupled.evaluate()
    A = coupled.jacobian()
    split = A.convert("dense").getDenseArray()[np.ix_(free, columns)]
    A.destroy()
    rows_u = np.arange(split.shape[0]) < rows_T
    diagonal = rows_u[:, None] == columns_u[None, :]
    np.testing.assert_array_equal(split[~diagonal], 0.0)
    np.testing.assert_allclose(
        split[diagonal], exact[diagonal], rtol=0, atol=1e-12 * np.abs(exact).max()
    )
    coupled.destroy()
    if cell_mean:
        coupled.cell_temperature.destroy()


@pytest.mark.mpi
@pytest.mark.parametrize("increments", [0, 2], ids=["one-solve", "static-step"])
def test_heated_bars_closing_gap_monolithic(increments: int) -> None:
    """The heated bars closing the gap, in one Newton on (u, T): the same closed form.

    Alone (``solve_increment``) or as the solver of a StaticStep ramping the expansion.
    """
    gap, alpha, t_ref = 0.02, 2e-4, 250.0
    _, ft, V, Q, T, bcs_T = _bars(gap)
    T.x.array[:] = t_ref
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    ramp = dolfinx.fem.Constant(V.mesh, 1.0)
    sigma = ntf.thermoelastic_stress(u, T, YOUNGS_MODULUS, POISSON_RATIO, ramp * alpha, t_ref)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx
    problem = ntf.ContactProblem(F, u, [_pair(ft)], _rollers(V, ft, constrained=True))
    thermal = ThermalContactProblem(_heat_residual(T, Q), T, problem, TABLE, bcs_T)
    coupled = ThermoMechanicalContact(F, thermal)
    coupled.rtol = 1e-12
    if increments:
        step = ntf.StaticStep(
            lambda t: setattr(ramp, "value", t), initial_increment=1 / increments, fixed=True
        )
        results = step.run(coupled, u)
        assert [r.increment for r in results] == list(range(1, increments + 1))
        iterations = results[-1].iterations
    else:
        iterations = coupled.solve_increment()
    total, flux = _closed_form(gap, alpha, t_ref)
    np.testing.assert_allclose(ntf.contact_force(problem)[2], total, rtol=1e-10)
    np.testing.assert_allclose(_total_flow(thermal), flux, rtol=1e-10)
    assert iterations <= 15
    norms = coupled.residual_norms
    assert norms[-1] <= 1e-12 * norms[0]
    coupled.destroy()
    thermal.destroy()
    problem.destroy()


@pytest.mark.mpi
@pytest.mark.parametrize("conductivity", [1.0, 1e6])
def test_transient_exchange_between_bars(conductivity: float) -> None:
    """Backward Euler: two insulated bars exchange heat through the springs only.

    The heat content is conserved (to the Newton tolerance). With a nearly infinite conductivity
    (Biot number hL/k = 1e-6) the bars are lumped and the jump decays by
    1/(1 + dt h A (1/C_1 + 1/C_2)) per step.
    """
    mesh, ft, V, Q, T, _ = _bars()
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    load = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    sigma = ntf.small_strain_stress(u, YOUNGS_MODULUS, POISSON_RATIO)
    n = ufl.FacetNormal(mesh)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx + load * ufl.inner(n, v) * ds(UPPER_TOP)
    problem = ntf.ContactProblem(F, u, [_pair(ft)], _rollers(V, ft, constrained=False))
    solve_increments(problem, load, 10.0, 1)
    lower = dolfinx.fem.locate_dofs_topological(Q, 3, _cells(mesh, upper=False))
    T.x.array[:] = T_TOP
    T.x.array[lower] = T_BOTTOM
    T_old = dolfinx.fem.Function(Q)
    dt, h, capacity = 0.25, 1.0, 1.0
    q = ufl.TestFunction(Q)
    F_T = capacity * (T - T_old) / dt * q * ufl.dx
    F_T += conductivity * ufl.inner(ufl.grad(T), ufl.grad(q)) * ufl.dx
    thermal = ThermalContactProblem(F_T, T, problem, GapConductance.constant(h))
    solver = ntf.thermal_solver(thermal)
    # Linear in T: one update reaches the round-off floor, about k T eps per row.
    solver.rtol, solver.atol = 1e-13, 1e-13 * conductivity * T_BOTTOM
    heat = dolfinx.fem.form(capacity * T * ufl.dx)
    content = mesh.comm.allreduce(dolfinx.fem.assemble_scalar(heat), op=MPI.SUM)
    jump, jumps = T_BOTTOM - T_TOP, []
    for _ in range(4):
        T_old.x.array[:] = T.x.array
        solver.solve(T)
        jump /= 1.0 + dt * h * (1.0 / capacity + 1.0 / capacity)  # C = capacity x volume 1
        low, high = _interface_temperatures(T, mesh)
        jumps.append(high - low)
        total = mesh.comm.allreduce(dolfinx.fem.assemble_scalar(heat), op=MPI.SUM)
        np.testing.assert_allclose(total, content, rtol=1e-12 * conductivity)
        if conductivity > 1e5:
            np.testing.assert_allclose(high - low, jump, rtol=1e-5)
    assert np.all(np.diff(jumps) < 0) and 0 < jumps[-1] < 0.5 * (T_BOTTOM - T_TOP)
    solver.destroy()
    thermal.destroy()
    problem.destroy()


def _cells(mesh, *, upper: bool) -> np.ndarray:
    """Local cells of the upper (or lower) bar, by their midpoints."""
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim, tdim)  # dolfinx >= 0.9 locates cell dofs with it
    cells = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
    midpoints = dolfinx.mesh.compute_midpoints(mesh, tdim, cells)
    return cells[(midpoints[:, 2] > 0.0) == upper]


_CCX_DECK = """*NODE, NSET=NALL
1, 0., 0., -1.
2, 1., 0., -1.
3, 1., 1., -1.
4, 0., 1., -1.
5, 0., 0., 0.
6, 1., 0., 0.
7, 1., 1., 0.
8, 0., 1., 0.
11, 0., 0., 0.
12, 1., 0., 0.
13, 1., 1., 0.
14, 0., 1., 0.
15, 0., 0., 1.
16, 1., 0., 1.
17, 1., 1., 1.
18, 0., 1., 1.
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
2, 11, 12, 13, 14, 15, 16, 17, 18
*NSET, NSET=BOTTOM
1, 2, 3, 4
*NSET, NSET=TOP
15, 16, 17, 18
*NSET, NSET=X0
1, 4, 5, 8, 11, 14, 15, 18
*NSET, NSET=Y0
1, 2, 5, 6, 11, 12, 15, 16
*SURFACE, NAME=SLAVE
2, S1
*SURFACE, NAME=MASTER
1, S2
*MATERIAL, NAME=M
*ELASTIC
{E}, 0.
*CONDUCTIVITY
{k}
*EXPANSION
0.
*DENSITY
1.
*SPECIFIC HEAT
1.
*SOLID SECTION, ELSET=EALL, MATERIAL=M
*SURFACE INTERACTION, NAME=SI
*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR
{slope}, {tension}, 1.e-3
*GAP CONDUCTANCE
{table}
*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE
SLAVE, MASTER
*INITIAL CONDITIONS, TYPE=TEMPERATURE
NALL, 350.
*BOUNDARY
BOTTOM, 3, 3
X0, 1, 1
Y0, 2, 2
BOTTOM, 11, 11, {t_bottom}
TOP, 11, 11, {t_top}
*STEP
*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE
1., 1.
*DLOAD
2, P2, {load}
*NODE PRINT, NSET=NALL
NT
*END STEP
"""


@pytest.mark.parametrize(
    ("rows", "conductance_pressure"),
    [
        ([(100.0, 0.0, 0.0)], "contact"),
        ([(50.0, 0.0, 300.0), (150.0, 0.0, 400.0)], "contact"),
        ([(20.0, 0.0, 0.0), (220.0, 1e5, 0.0)], "ccx"),
    ],
    ids=["constant", "temperature-dependent", "pressure-dependent-ccx"],
)
def test_agrees_with_ccx(rows, conductance_pressure, tmp_path) -> None:
    """The bars of the first test in ccx 2.20 (one C3D8 per bar, *COUPLED TEMPERATURE-
    DISPLACEMENT, STEADY STATE): the interface temperatures agree to ccx's 7 printed digits.

    For a LINEAR law ccx 2.20's thermal spring looks the table up at the law's slope K instead of
    the contact pressure (docs/method.md §20.1): a pressure-dependent table agrees with
    ``conductance_pressure="ccx"`` (h(K = 5e4) = 120 here, h(40) = 20.08 with the contact pressure).
    """
    from dolfinx_ntf.calculix.ccx import read_ccx_dat, run_ccx

    load = 40.0
    deck = _CCX_DECK.format(
        E=YOUNGS_MODULUS, k=CONDUCTIVITY, slope=LAW.slope, tension=LAW.tension, load=load,
        table="\n".join(f"{h}, {p}, {t}" for h, p, t in rows), t_bottom=T_BOTTOM, t_top=T_TOP,
    )  # fmt: skip
    (tmp_path / "bars.inp").write_text(deck)
    run_ccx(tmp_path, "bars", timeout=120)
    block = next(b for b in read_ccx_dat(tmp_path, "bars") if b.name == "NT")
    ccx = dict(zip(block.labels.tolist(), block.values[:, 0]))

    mesh, ft, V, Q, T, bcs_T = _bars()
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    sigma = ntf.small_strain_stress(u, YOUNGS_MODULUS, POISSON_RATIO)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx
    F += pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(UPPER_TOP)
    problem = ntf.ContactProblem(F, u, [_pair(ft)], _rollers(V, ft, constrained=False))
    table = GapConductance.from_rows(rows)
    thermal = ThermalContactProblem(
        _heat_residual(T, Q), T, problem, table, bcs_T, conductance_pressure=conductance_pressure
    )
    solve_staggered(lambda: solve_increments(problem, pressure, load, 1), thermal)
    slave, master = _interface_temperatures(T, mesh)
    np.testing.assert_allclose([slave, master], [ccx[11], ccx[5]], rtol=2e-7)  # 7 digits
    assert all(ccx[n] == ccx[11] for n in (12, 13, 14)) and ccx[5] > ccx[11]
    thermal.destroy()
    problem.destroy()


@pytest.mark.mpi
def test_constraints_on_the_temperature_are_eliminated() -> None:
    """Constraint blocks on ``T`` (``block_size=1``) are eliminated (docs/method.md §39): one-term
    rows holding every node of the lower bar at z = -0.5 at 380 act as a prescribed layer, so the
    flow is the series of the half bar, the conductance and the upper bar (closed form, 1e-10);
    a block of another block size is refused."""
    load, held = 40.0, 380.0
    mesh, ft, V, Q, T, bcs_T = _bars()
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    sigma = ntf.small_strain_stress(u, YOUNGS_MODULUS, POISSON_RATIO)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx + pressure * ufl.inner(
        ufl.FacetNormal(mesh), v
    ) * ds(UPPER_TOP)
    problem = ntf.ContactProblem(F, u, [_pair(ft)], _rollers(V, ft, constrained=False))
    layer = np.flatnonzero(np.isclose(Q.tabulate_dof_coordinates()[:, 2], -0.5))
    rows = LinearConstraintBlock(
        layer[:, None], 0, [1.0], np.full(layer.size, held), name="layer", block_size=1
    )
    wrong = LinearConstraintBlock(layer[:, None], 0, [1.0], name="vector")
    with pytest.raises(ValueError, match="'vector' has block size 3"):
        ThermalContactProblem(_heat_residual(T, Q), T, problem, TABLE, bcs_T, constraints=[wrong])
    thermal = ThermalContactProblem(
        _heat_residual(T, Q), T, problem, TABLE, bcs_T, constraints=[rows]
    )
    assert mesh.comm.allreduce(1 if thermal.elimination is not None else 0) == mesh.comm.size
    assert thermal.elimination.num_constraints == 16  # the 4 x 4 nodes of the layer, once
    solve_staggered(lambda: solve_increments(problem, pressure, load, 1), thermal)
    h = 20.0 + 200.0 * load / 100.0
    flux = (held - T_TOP) / (0.5 / CONDUCTIVITY + 1.0 / h + 1.0 / CONDUCTIVITY)
    slave, master = T_TOP + flux / CONDUCTIVITY, held - 0.5 * flux / CONDUCTIVITY
    np.testing.assert_allclose(_interface_temperatures(T, mesh), (slave, master), rtol=1e-10)
    np.testing.assert_allclose(_total_flow(thermal), flux, rtol=1e-10)
    np.testing.assert_allclose(T.x.array[layer], held, rtol=1e-14)
    F_T = F + ufl.inner(T * ufl.Identity(3), ufl.grad(v)) * ufl.dx
    with pytest.raises(NotImplementedError, match="linear constraints are not supported"):
        ThermoMechanicalContact(F_T, thermal)
    thermal.destroy()
    problem.destroy()
