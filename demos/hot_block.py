"""Hot block pressed on a cold one: coupled temperature-displacement contact in 3D.

A steel block (20 x 20 x 20 mm) at 373 K is pressed with 10 MPa onto a larger steel block
(40 x 40 x 20 mm) at 293 K. Heat flows across the contact springs through a gap conductance that
grows with the contact pressure (CalculiX's ``*GAP CONDUCTANCE`` table, ``GapConductance``), the
blocks expand with their temperature (``thermoelastic_stress``), and one Newton solves both fields
per increment (``ThermoMechanicalContact``): three backward-Euler increments of transient heat
conduction (``rho c (T - T_old)/dt``), then the steady state (the capacity term switched off). The
hot block's top is held at 373 K and the cold block's bottom at 293 K; every other face is
insulated. The hot block's bottom is the slave surface, the cold block's top the master; their
meshes do not match (5 mm and 6.7 mm hexahedra on the coarse mesh).

The demo checks, and prints:

- the vertical contact force equals the applied load (to 1e-8, every increment);
- at steady state the heat flow through the contact (the sum of the springs' flows) equals the heat
  entering the hot block's top and the heat leaving the cold block's bottom (the Dirichlet
  boundaries' thermal reactions), to the solver's tolerance: the difference is the sum of the
  converged thermal residual over the free nodes, at most ``sqrt(n)`` times its 2-norm;
- in each transient increment, the heat stored (``int rho c (T - T_old) dx``) equals the net inflow
  times ``dt`` (to the same bound);
- spring by spring, the temperature jump ``T_m - T_s`` equals ``q/(h A)`` with ``T_m`` interpolated
  here from the master face's nodal temperatures, ``h`` looked up here in the table at the
  spring's contact pressure and ``A`` the mechanical spring's area;
- every temperature lies between the two boundary temperatures (at steady state and in each
  transient increment).

It saves ``output/hot_block.png`` (the temperature along the blocks' axis at each increment, with
the jump at the interface), ``output/hot_block_interface.png`` (the contact pressure and the heat
flux over the interface) and ``output/hot_block.xdmf`` (temperature, displacement and the flux
density at the slave nodes, per increment).

Run it with::

    .venv/bin/python demos/hot_block.py            # ~10k dofs (u and T), about 25 s
    .venv/bin/python demos/hot_block.py --coarse   # ~2k dofs (tests), a few seconds
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import typing
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.io
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc
from dolfinx_ntf.meshes import punch as geometry
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

__all__ = ["CONDUCTANCE_TABLE", "main"]

# %%
# Parameters
# ----------
# Steel on steel in mm, N, MPa, s, W and K. The hot block is the "punch" of
# :mod:`dolfinx_ntf.meshes.punch`, centred on the cold block's top.

COLD_SIZE = (40.0, 40.0, 20.0)
HOT_SIZE = (20.0, 20.0, 20.0)
E, NU = 210_000.0, 0.3
#: Thermal expansion coefficient [1/K] and the stress-free temperature [K].
ALPHA, T_REF = 1.2e-5, 293.0
T_HOT, T_COLD = 373.0, 293.0
#: Conductivity [W/(mm K)] and volumetric heat capacity rho c [J/(mm^3 K)].
CONDUCTIVITY, RHO_C = 0.05, 3.6e-3
#: Pressure on the hot block's top [MPa].
PRESSURE = 10.0
#: ``*GAP CONDUCTANCE`` lines (conductance [W/(mm^2 K)], pressure [MPa], temperature): h grows
#: linearly from 0.002 at p = 0 to 0.02 at 20 MPa and stays there beyond.
CONDUCTANCE_TABLE = ((0.002, 0.0, 0.0), (0.02, 20.0, 0.0))
#: Transient increments (backward Euler) before the steady state, and their length [s].
TRANSIENT_INCREMENTS, DT = 3, 5.0
#: Absolute tolerance of the coupled Newton's combined residual 2-norm (N and W).
ATOL = 1e-9
#: Relative tolerance of the force check and of the spring-by-spring jump check.
TOLERANCE = 1e-8


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh (tests)")
    parser.add_argument(
        "--output", type=Path, default=Path("output"), help="output folder (default: output/)"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser.parse_args(argv)


# %%
# The coupled problem
# -------------------
# Displacement and temperature are P1 on one mesh of both blocks (the temperature numbered like
# the displacement's nodes, as :class:`~dolfinx_ntf.ThermalContactProblem` needs). The mechanical
# residual has the thermal strain ``alpha (T - T_ref) I``; the heat residual the conduction and
# the backward-Euler capacity term, whose ``1/dt`` is a Constant set to 0 for the steady state.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (checks, heat flows, forces, iterations, timings)."""
    args = _parse(argv)
    comm = MPI.COMM_WORLD
    start = time.perf_counter()

    # --- Mesh ------------------------------------------------------------------------------------
    # Even divisions put nodes on the axis x = y = 20 mm of both blocks (the temperature plot).
    sizes = (20.0 / 3, 5.0) if args.coarse else (10.0 / 3, 2.0)
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        geometry.build_punch,
        comm,
        block_size=COLD_SIZE,
        punch_size=HOT_SIZE,
        mesh_size_block=sizes[0],
        mesh_size_punch=sizes[1],
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    Q = compat.scalar_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    T, w = dolfinx.fem.Function(Q, name="temperature"), ufl.TestFunction(Q)
    T_old = dolfinx.fem.Function(Q)

    # Initial temperatures: each block uniform at its boundary temperature.
    mesh.topology.create_connectivity(3, 3)  # dolfinx >= 0.9 locates cell dofs with it
    hot_nodes = dolfinx.fem.locate_dofs_topological(Q, 3, cell_tags.find(geometry.PUNCH))
    T.x.array[:] = T_COLD
    T.x.array[hot_nodes] = T_HOT
    T.x.scatter_forward()

    # --- Mechanics: thermoelasticity, the load, supports ---------------------------------------
    load = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    sigma = ntf.thermoelastic_stress(u, T, E, NU, ALPHA, T_REF)
    n = ufl.FacetNormal(mesh)
    F_u = ufl.inner(sigma, ufl.grad(v)) * ufl.dx + load * ufl.inner(n, v) * ds(geometry.PUNCH_TOP)
    # Cold block's bottom clamped; the hot block's top held in its plane (its in-plane rigid
    # motions), free to move down and to expand upwards.
    bcs_u = [
        dolfinx.fem.dirichletbc(
            np.zeros(3, dtype=PETSc.ScalarType),
            dolfinx.fem.locate_dofs_topological(V, 2, facet_tags.find(geometry.BLOCK_BOTTOM)),
            V,
        ),
        component_bc(V, 0, facet_tags.find(geometry.PUNCH_TOP)),
        component_bc(V, 1, facet_tags.find(geometry.PUNCH_TOP)),
    ]
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E)
    pair = ntf.ContactPair(
        slave=ntf.FacetSurface(facet_tags, geometry.PUNCH_BOTTOM),
        master=ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP),
        interaction=ntf.SurfaceInteraction(law),
        name="interface",
    )
    # The centre node sits above a master vertex: start its face search at its current face
    # (beyond CalculiX, as in the punch demo) so that it does not hop between the four faces.
    problem = ntf.ContactProblem(F_u, u, [pair], bcs_u, walk_from_previous_face=True)

    # --- Heat: conduction, capacity, gap conductance, boundary temperatures -------------------
    inv_dt = dolfinx.fem.Constant(mesh, 1.0 / DT)
    conduction = CONDUCTIVITY * ufl.inner(ufl.grad(T), ufl.grad(w)) * ufl.dx
    capacity = RHO_C * inv_dt * (T - T_old) * w * ufl.dx
    top = facet_tags.find(geometry.PUNCH_TOP)
    bottom = facet_tags.find(geometry.BLOCK_BOTTOM)
    top_nodes = dolfinx.fem.locate_dofs_topological(Q, 2, top)
    bottom_nodes = dolfinx.fem.locate_dofs_topological(Q, 2, bottom)
    bcs_T = [
        dolfinx.fem.dirichletbc(dolfinx.fem.Constant(mesh, value), nodes, Q)
        for value, nodes in ((T_HOT, top_nodes), (T_COLD, bottom_nodes))
    ]
    conductance = ntf.GapConductance.from_rows(CONDUCTANCE_TABLE)
    thermal = ntf.ThermalContactProblem(conduction + capacity, T, problem, conductance, bcs_T)
    coupled = ntf.ThermoMechanicalContact(F_u, thermal)
    # The combined residual mixes N and W: forces of 4e3 N leave a round-off floor near 1e-10, so
    # the absolute tolerance stops there (1e-13 of the load; the heat checks use the residual).
    coupled.atol = ATOL
    if not args.quiet:
        ntf.log_progress()

    # Thermal reactions: the residual (conduction + capacity) summed over a Dirichlet boundary's
    # nodes is the heat flowing in there (an indicator of those nodes as the test function).
    flows_in = {}
    for name, nodes in (("top", top_nodes), ("bottom", bottom_nodes)):
        indicator = dolfinx.fem.Function(Q)
        indicator.x.array[nodes] = 1.0
        flows_in[name] = dolfinx.fem.form(ufl.replace(conduction + capacity, {w: indicator}))
    stored = dolfinx.fem.form(RHO_C * (T - T_old) * ufl.dx)
    free = np.ones(Q.dofmap.index_map.size_local, dtype=bool)
    for nodes in (top_nodes, bottom_nodes):
        free[nodes[nodes < free.size]] = False
    n_free = comm.allreduce(int(free.sum()), op=MPI.SUM)

    # %%
    # Increments
    # ----------
    # The load is applied in the first increment, together with the first dt of heat
    # conduction; then two more transient increments and the steady state (1/dt = 0). Each is one
    # monolithic Newton on (u, T) that pairs at its start.

    args.output.mkdir(parents=True, exist_ok=True)
    xdmf_path = args.output / "hot_block.xdmf"
    axis = _axis_profile(Q, T)
    profiles = [("initial", *axis())]
    rows: list[dict] = []
    flux_field = dolfinx.fem.Function(Q, name="heat_flux")
    top_area = HOT_SIZE[0] * HOT_SIZE[1]
    solve_start = time.perf_counter()
    with dolfinx.io.XDMFFile(comm, str(xdmf_path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        for increment in range(TRANSIENT_INCREMENTS + 1):
            steady = increment == TRANSIENT_INCREMENTS
            load.value = PRESSURE
            inv_dt.value = 0.0 if steady else 1.0 / DT
            T_old.x.array[:] = T.x.array
            iterations = coupled.solve_increment()
            label = "steady state" if steady else f"t = {(increment + 1) * DT:g} s"
            time_value = (increment + 1) * DT  # in the XDMF file (the steady state one dt on)
            row = {
                "label": label,
                "iterations": iterations,
                "contact_force": float(ntf.contact_force(problem)[2]),
                "load": PRESSURE * top_area,
                **_heat_balance(comm, coupled, flows_in, stored, free, n_free, thermal),
                **_bounds(comm, T),
            }
            row["force_error"] = abs(row["contact_force"] / row["load"] - 1)
            row["stored_rate"] = 0.0 if steady else row["stored"] / DT
            rows.append(row)
            profiles.append((label, *axis()))
            ntf.heat_flux_field(thermal, out=flux_field)
            for f in (T, u, flux_field):
                xdmf.write_function(f, time_value)
    solve_time = time.perf_counter() - solve_start

    # %%
    # Checks at the steady state
    # --------------------------
    # The springs' heat flows (into the slave nodes of the hot block: negative) against the
    # boundaries' thermal reactions; spring by spring, the jump against q/(h A).
    springs = _springs(comm, problem, thermal)
    final = rows[-1]
    summary = {
        "dofs": V.dofmap.index_map.size_global * 3 + Q.dofmap.index_map.size_global,
        "increments": len(rows),
        "iterations": [r["iterations"] for r in rows],
        "springs": springs["count"],
        "load": final["load"],
        "contact_force": [r["contact_force"] for r in rows],
        "force_error": max(r["force_error"] for r in rows),
        "heat_in_top": final["top"],
        "heat_in_bottom": final["bottom"],
        "heat_through_contact": final["contact"],
        "balance_top": abs(final["top"] + final["contact"]),
        "balance_bottom": abs(final["bottom"] - final["contact"]),
        "balance_bound": final["bound"],
        "storage_error": max(
            (abs(r["stored_rate"] - r["top"] - r["bottom"]) for r in rows[:-1]), default=0.0
        ),
        "storage_bound": max((r["bound"] for r in rows[:-1]), default=0.0),
        "jump_error": springs["jump_error"],
        "jump_range": springs["jump_range"],
        "conductance_range": springs["conductance_range"],
        "pressure_range": springs["pressure_range"],
        "t_min": [r["t_min"] for r in rows],
        "t_max": [r["t_max"] for r in rows],
        "solve_time": solve_time,
        "xdmf": str(xdmf_path),
    }
    # Series estimate of the steady flow with the mean conductance over the hot block's footprint
    # (the cold block is wider: its spreading resistance is less than L/(k A)).
    mean_h = springs["mean_conductance"]
    summary["series_estimate"] = (T_HOT - T_COLD) / (
        HOT_SIZE[2] / (CONDUCTIVITY * top_area)
        + 1 / (mean_h * top_area)
        + COLD_SIZE[2] / (CONDUCTIVITY * top_area)
    )
    span = T_HOT - T_COLD
    summary["passed"] = bool(
        summary["force_error"] <= TOLERANCE
        and summary["balance_top"] <= summary["balance_bound"]
        and summary["balance_bottom"] <= summary["balance_bound"]
        and summary["storage_error"] <= summary["storage_bound"]
        and summary["jump_error"] <= TOLERANCE * span
        and min(summary["t_min"]) >= T_COLD - TOLERANCE * span
        and max(summary["t_max"]) <= T_HOT + TOLERANCE * span
        and final["contact"] < 0
    )
    if comm.rank == 0:
        summary["png"] = str(_plot_axis(args.output / "hot_block.png", profiles, summary))
        summary["interface_png"] = str(
            _plot_interface(args.output / "hot_block_interface.png", springs)
        )
    summary["time"] = time.perf_counter() - start
    if comm.rank == 0:
        _print_report(summary, rows)
    coupled.destroy()
    thermal.destroy()
    problem.destroy()
    return summary


# %%
# Heat balances
# -------------
# At a converged state the thermal residual vanishes at the free nodes to the solver's tolerance;
# summed over the free nodes of one block it is at most ``sqrt(n)`` times its 2-norm, and that sum
# is what separates a boundary's heat flow from the contact's (the springs conserve heat).


def _heat_balance(
    comm: MPI.Comm,
    coupled: ntf.ThermoMechanicalContact,
    flows_in: dict,
    stored: compat.Form,
    free: np.ndarray,
    n_free: int,
    thermal: ntf.ThermalContactProblem,
) -> dict:
    """Heat flowing in at the top and the bottom, through the contact, stored; the bound."""
    coupled.evaluate()  # the springs and residuals at the converged state
    residual = coupled.residual()[-free.size :]  # the owned temperature rows
    norm = math.sqrt(comm.allreduce(float(residual[free] @ residual[free]), op=MPI.SUM))
    result = {
        name: comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)
        for name, form in flows_in.items()
    }
    result["stored"] = comm.allreduce(dolfinx.fem.assemble_scalar(stored), op=MPI.SUM)
    result["contact"] = comm.allreduce(float(np.sum(np.concatenate(thermal.heat_flows))))
    result["bound"] = math.sqrt(n_free) * norm
    return result


def _bounds(comm: MPI.Comm, T: dolfinx.fem.Function) -> dict:
    """The lowest and highest nodal temperature over all processes."""
    owned = T.x.array[: T.function_space.dofmap.index_map.size_local]
    return {
        "t_min": comm.allreduce(float(owned.min(initial=np.inf)), op=MPI.MIN),
        "t_max": comm.allreduce(float(owned.max(initial=-np.inf)), op=MPI.MAX),
    }


def _springs(
    comm: MPI.Comm, problem: ntf.ContactProblem, thermal: ntf.ThermalContactProblem
) -> dict:
    """Per spring: position, pressure, conductance, flux; the jump check, gathered everywhere.

    ``T_m`` is interpolated from the master face's nodal temperatures with the projection
    point's shape functions, ``h`` looked up in :data:`CONDUCTANCE_TABLE` at the pressure of
    :func:`~dolfinx_ntf.contact_results`: neither comes from :func:`~dolfinx_ntf.thermal_results`,
    whose flows they check.
    """
    temperatures = thermal.temperatures()  # collective
    (mech,) = ntf.contact_results(problem)
    (heat,) = ntf.thermal_results(thermal)
    state = problem.states[0]
    if not np.array_equal(mech.node, heat.node):
        raise RuntimeError("hot_block: mechanical and thermal springs differ")
    if heat.node.size:
        nodes = state.element_nodes
        master_t = np.sum(state.evaluation.phi * temperatures[nodes[:, :-1]], axis=1)
        slave_t = temperatures[nodes[:, -1]]
        table = np.array(CONDUCTANCE_TABLE)
        h = np.interp(mech.pressure, table[:, 1], table[:, 0])
        jump_error = float(np.max(np.abs((master_t - slave_t) - heat.flow / (h * mech.area))))
        jump = master_t - slave_t
    else:
        h = jump = np.zeros(0)
        jump_error = 0.0

    def gather(a: np.ndarray) -> np.ndarray:
        return np.concatenate(comm.allgather(np.asarray(a)))

    out = {
        "count": comm.allreduce(int(heat.node.size), op=MPI.SUM),
        "x": gather(mech.position[:, 0]) if heat.node.size else gather(np.zeros(0)),
        "y": gather(mech.position[:, 1]) if heat.node.size else gather(np.zeros(0)),
        "pressure": gather(mech.pressure),
        "flux": gather(-heat.flux),  # from the hot block into the cold one
        "conductance": gather(h),
        "jump": gather(jump),
        "jump_error": comm.allreduce(jump_error, op=MPI.MAX),
    }
    out["jump_range"] = (float(out["jump"].min()), float(out["jump"].max()))
    out["conductance_range"] = (float(out["conductance"].min()), float(out["conductance"].max()))
    out["pressure_range"] = (float(out["pressure"].min()), float(out["pressure"].max()))
    area = gather(mech.area)
    out["mean_conductance"] = float(np.sum(out["conductance"] * area) / np.sum(area))
    return out


def _axis_profile(Q: dolfinx.fem.FunctionSpace, T: dolfinx.fem.Function) -> typing.Callable:
    """A function giving ``(z, T)`` of the nodes on the axis x = y = 20 mm (sorted, gathered)."""
    x = Q.tabulate_dof_coordinates()[: Q.dofmap.index_map.size_local]
    centre = 0.5 * COLD_SIZE[0], 0.5 * COLD_SIZE[1]
    on_axis = np.flatnonzero(np.hypot(x[:, 0] - centre[0], x[:, 1] - centre[1]) < 1e-6)
    comm = Q.mesh.comm

    def profile() -> tuple[np.ndarray, np.ndarray]:
        z = np.concatenate(comm.allgather(x[on_axis, 2]))
        t = np.concatenate(comm.allgather(T.x.array[on_axis]))
        order = np.argsort(z, kind="stable")
        return z[order], t[order]

    return profile


# %%
# Figures and report
# ------------------
# The temperature along the axis (both blocks' nodes at the interface z = 0: the jump), and the
# contact pressure and heat flux at the slave nodes over the interface.


def _plot_axis(path: Path, profiles: list, summary: dict) -> Path:
    """Temperature against height on the blocks' axis, one line per increment."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for label, z, t in profiles:
        ax.plot(z, t, "o-", ms=3, label=label)
    ax.axvline(0.0, color="k", lw=0.8, ls=":")
    ax.set_xlabel("height z on the axis [mm] (cold block below 0, hot block above)")
    ax.set_ylabel("temperature [K]")
    ax.set_title(
        f"Hot block on a cold one: {PRESSURE:g} MPa, steady heat flow "
        f"{-summary['heat_through_contact']:.3g} W"
    )
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _plot_interface(path: Path, springs: dict) -> Path:
    """Contact pressure and heat flux density at the slave nodes over the interface."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.5))
    for ax, key, label in (
        (axes[0], "pressure", "contact pressure [MPa]"),
        (axes[1], "flux", "heat flux into the cold block [W/mm$^2$]"),
    ):
        shown = ax.scatter(springs["x"], springs["y"], c=springs[key], s=60, cmap="inferno")
        fig.colorbar(shown, ax=ax, label=label)
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.set_title(label.split(" [")[0])
    fig.suptitle("Steady state at the interface (slave nodes of the hot block)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _print_report(s: dict, rows: list[dict]) -> None:
    """Per increment the forces and heat flows, then the steady state's checks."""
    print()
    print(
        f"Hot block on a cold one: {s['dofs']} dofs (u and T), {s['springs']} springs, "
        f"solve {s['solve_time']:.1f} s, total {s['time']:.1f} s"
    )
    print(
        f"{'increment':<14} {'Newton':>6} {'contact force [N]':>18} {'in at top [W]':>14} "
        f"{'contact [W]':>12} {'in at bottom [W]':>17} {'stored/dt [W]':>14} {'T range [K]':>17}"
    )
    for r in rows:
        print(
            f"{r['label']:<14} {r['iterations']:>6} {r['contact_force']:>18.6f} {r['top']:>14.6f} "
            f"{-r['contact']:>12.6f} {r['bottom']:>17.6f} {r['stored_rate']:>14.6f} "
            f"{r['t_min']:>8.3f}-{r['t_max']:.3f}"
        )
    print(
        f"Load {s['load']:g} N; contact force off by {s['force_error']:.1e} at most. Steady heat "
        f"flow {-s['heat_through_contact']:.6f} W through the contact; top and bottom differ by "
        f"{s['balance_top']:.1e} and {s['balance_bottom']:.1e} W (bound from the residual "
        f"{s['balance_bound']:.1e} W); series estimate with the mean h: "
        f"{s['series_estimate']:.3f} W"
    )
    print(
        f"Transient increments: stored heat/dt against the net inflow off by "
        f"{s['storage_error']:.1e} W (bound {s['storage_bound']:.1e} W)"
    )
    print(
        f"Interface: pressure {s['pressure_range'][0]:.3f} to {s['pressure_range'][1]:.3f} MPa, "
        f"conductance {s['conductance_range'][0]:.5f} to {s['conductance_range'][1]:.5f} "
        f"W/(mm^2 K), jump T_m - T_s {s['jump_range'][0]:.3f} to {s['jump_range'][1]:.3f} K, "
        f"equal to q/(h A) to {s['jump_error']:.1e} K"
    )
    verdict = "PASSED" if s["passed"] else "FAILED"
    print(
        f"Checks (force = load, heat balances, jump = q/(h A), {T_COLD:g} K <= T <= {T_HOT:g} K): "
        f"{verdict}. Results: {s['xdmf']}, {s.get('png')}, {s.get('interface_png')}"
    )


# %%
# Run
# ---
# The build of this page ran ``demos/hot_block.py --coarse``: per increment the Newton
# iterations, the contact force and the heat flows, then the steady state's checks and the
# figures.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
