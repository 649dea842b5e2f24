"""Plane-strain Hertz contact: an elastic cylinder pressed onto an elastic block, in 2D.

A steel cylinder of radius R = 25 mm lies on a steel block along a line; a line load F' (force per
unit length along the axis) presses it down. Hertz's plane-strain solution (two elastic bodies,
frictionless, small strain) gives the half-width of the contact strip and the pressure across it::

    1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2,   b = sqrt(4 F' R / (pi E*)),
    p0 = 2 F' / (pi b),                      p(x) = p0 sqrt(1 - x^2/b^2)  for |x| < b.

The model is the cross-section, meshed in 2D with triangles (``dolfinx_ntf.meshes.cylinder``):
plane strain per unit thickness, half of it (x >= 0, the line x = 0 a symmetry line of both
bodies), so the springs carry F'/2. The cylinder's arc is the slave (node-to-segment springs on
the block's top edges), the load a uniform traction on the cylinder's flat top y = R, the block's
bottom is clamped. F' is chosen for b = R/20: the half-width spans ten elements of the default
mesh (five of the coarse one), and the block (4R wide and deep) stands in for a half-space.

The demo checks equilibrium (the contact force equals half the line load and the reaction of the
block's bottom), fits Hertz's profile to the nodal pressures ``F_N/A_p`` (A_p: the node's share
of the slave edge lengths), and compares the fitted b and p0 and the nodal maximum with Hertz's.
It saves ``output/hertz_cylinder_2d.png`` (the nodal pressures against x beside Hertz's profile)
and ``output/hertz_cylinder_2d.xdmf`` (the displacement and the contact fields).

What limits the accuracy: the mesh (the pressure edge at x = b falls between two nodes), the
penalty (the overlap p/K, 1e4 E / R here, widens the strip by a fraction of a percent), the finite
block, and the contact evaluated in the current configuration while the bulk is small-strain.

Run it with::

    .venv/bin/python demos/hertz_cylinder_2d.py            # ~4k dofs, a few seconds
    .venv/bin/python demos/hertz_cylinder_2d.py --coarse   # ~2k dofs (tests)
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import typing
from pathlib import Path

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import measures
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes import cylinder as geometry
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

__all__ = ["hertz_line", "main"]

# %%
# Parameters and Hertz's solution
# -------------------------------
# Steel on steel, units mm, N, MPa; the line load F' is in N per mm of cylinder length.

RADIUS = 25.0
E_CYLINDER, NU_CYLINDER = 210_000.0, 0.3
E_BLOCK, NU_BLOCK = 210_000.0, 0.3
#: Hertz's half-width the line load is chosen for, in radii.
HALF_WIDTH = 0.05
#: Penalty slope of the LINEAR law in units of E per mm (1e4 E / R).
PENALTY = 1e4 / RADIUS
#: Relative tolerance of the equilibrium checks (contact force against load and reaction).
TOLERANCE = 1e-8


def e_star() -> float:
    """The effective modulus ``E*`` of the two bodies (plane strain)."""
    return 1.0 / ((1 - NU_CYLINDER**2) / E_CYLINDER + (1 - NU_BLOCK**2) / E_BLOCK)


def hertz_line(line_load: float, radius: float = RADIUS) -> tuple[float, float]:
    """Hertz's half-width and peak pressure of a cylinder on a half-space (plane strain).

    Args:
        line_load: The force per unit length F' (the whole cylinder, not the half model).
        radius: The cylinder's radius R.

    Returns:
        ``(b, p0)``.
    """
    b = math.sqrt(4 * line_load * radius / (math.pi * e_star()))
    return b, 2 * line_load / (math.pi * b)


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh (tests)")
    parser.add_argument(
        "--output", type=Path, default=Path("output"), help="output folder (default: output/)"
    )
    parser.add_argument(
        "--increments", type=int, default=4, help="number of increments (default 4)"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser.parse_args(argv)


# %%
# The analysis
# ------------
# The half model of :mod:`dolfinx_ntf.meshes.cylinder`, refined to b/10 (coarse: b/5) around the
# contact point; the line load grows linearly over equal increments.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (Hertz values, computed values, relative errors, timings)."""
    args = _parse(argv)
    if args.increments < 1:
        raise ValueError(f"need --increments >= 1, got {args.increments}")
    comm = MPI.COMM_WORLD
    start = time.perf_counter()
    b_target = HALF_WIDTH * RADIUS
    line_load = math.pi * e_star() * b_target**2 / (4 * RADIUS)  # F' for b = b_target

    # --- Mesh ------------------------------------------------------------------------------------
    size = b_target / (5 if args.coarse else 10)
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        geometry.build_cylinder_on_block,
        comm,
        gdim=2,
        radius=RADIUS,
        size_fine=size,
        size_coarse=0.3 * RADIUS,
        refine_distance=2.5 * b_target,
    )

    # --- Bulk problem ----------------------------------------------------------------------------
    # Plane-strain small-strain elasticity per unit thickness (the 2D stress of
    # small_strain_stress), one material per body; half the line load spread over the top (width
    # R) as a downward traction.
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    load = dolfinx.fem.Constant(mesh, 0.0)
    F = (
        ufl.inner(small_strain_stress(u, E_BLOCK, NU_BLOCK), ufl.grad(v)) * dx(geometry.BLOCK)
        + ufl.inner(small_strain_stress(u, E_CYLINDER, NU_CYLINDER), ufl.grad(v))
        * dx(geometry.CYLINDER)
        + load / (2 * RADIUS) * v[1] * ds(geometry.CYLINDER_TOP)
    )
    bottom = facet_tags.find(geometry.BLOCK_BOTTOM)
    bcs = [
        component_bc(V, 0, facet_tags.find(geometry.SYMMETRY)),
        component_bc(V, 0, bottom),
        component_bc(V, 1, bottom),
    ]

    # --- Contact ----------------------------------------------------------------------------------
    # The LINEAR law with K = 1e4 E / R: stiff against the strip's compliance (b^2/R), and its small
    # tension holds the cylinder, which touches the block at one node at the start, before the
    # load closes the strip. thickness=1: plane strain per unit length, like the residual form.
    law = ntf.LinearLaw(slope=PENALTY * E_BLOCK, tension=E_BLOCK / 70000)
    pair = ntf.ContactPair(
        slave=ntf.FacetSurface(facet_tags, geometry.CYLINDER_CONTACT),
        master=ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP),
        interaction=ntf.SurfaceInteraction(law),
        name="cylinder",
        thickness=1.0,
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    solver = ntf.ContactNewtonSolver(comm, problem)
    if not args.quiet:
        ntf.log_progress()

    # --- Static step ------------------------------------------------------------------------------
    args.output.mkdir(parents=True, exist_ok=True)
    xdmf = args.output / "hertz_cylinder_2d.xdmf"
    iterations: list[int] = []
    with ntf.ContactWriter(problem, xdmf) as writer:
        writer.write(0.0)

        def record(result: ntf.IncrementResult) -> None:
            iterations.append(result.iterations)
            writer.write(result.time)

        step = ntf.StaticStep(
            lambda t: setattr(load, "value", line_load * t),
            initial_increment=1.0 / args.increments,
            max_increment=1.0 / args.increments,
            on_increment=record,
        )
        solve_start = time.perf_counter()
        step.run(solver, u)
        solve_time = time.perf_counter() - solve_start

    # --- Compare with Hertz -----------------------------------------------------------------------
    # The half model's springs carry F'/2 upwards; the clamped bottom reacts with the same force.
    # Every slave node takes part, with zero pressure where it has no spring; x is measured in the
    # reference configuration, like Hertz's (linear) theory does.
    force = float(ntf.contact_force(problem)[1])
    reaction = float(ntf.reaction(problem, bottom)[1])
    b_hertz, p0_hertz = hertz_line(line_load)
    slave_nodes = problem.states[0].slave.nodes
    x = V.tabulate_dof_coordinates()[slave_nodes, 0]
    pressure, _, status = ntf.ContactFields(problem).at_nodes(slave_nodes)
    x_all = np.concatenate(comm.allgather(x))
    p_all = np.concatenate(comm.allgather(pressure))
    closed = np.concatenate(comm.allgather(status > 0))
    b_fit, p0_fit = measures.fit_hertz_profile(x_all, p_all, b_hertz, p0_hertz)
    last_closed, first_open = measures.bracketing_radius(x_all, np.where(closed, p_all, 0.0))
    summary = {
        "dofs": V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
        "increments": len(iterations),
        "iterations": iterations,
        "springs": problem.total_springs,
        "line_load": line_load,
        "force": force,
        "reaction": reaction,
        "load_error": abs(2 * force / line_load - 1),
        "equilibrium_error": abs(reaction / force - 1),
        "b_hertz": b_hertz,
        "b_fit": b_fit,
        "b_last_closed": last_closed,
        "b_first_open": first_open,
        "p0_hertz": p0_hertz,
        "p0_fit": p0_fit,
        "p_max": float(p_all.max()),
        "solve_time": solve_time,
        "xdmf": str(xdmf),
    }
    summary["b_error"] = b_fit / b_hertz - 1
    summary["p0_error"] = p0_fit / p0_hertz - 1
    summary["p_max_error"] = summary["p_max"] / p0_hertz - 1
    summary["passed"] = max(summary["load_error"], summary["equilibrium_error"]) <= TOLERANCE
    if comm.rank == 0:
        summary["png"] = str(_plot(args.output / "hertz_cylinder_2d.png", x_all, p_all, summary))
    summary["time"] = time.perf_counter() - start
    if comm.rank == 0:
        _print_report(summary)
    return summary


# %%
# Figure and report
# -----------------
# The nodal pressures across the strip beside Hertz's profile and the fitted one.


def _plot(path: Path, x: np.ndarray, p: np.ndarray, summary: dict) -> Path:
    """Nodal contact pressure against x beside Hertz's profile and the fitted one."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    b, p0 = summary["b_hertz"], summary["p0_hertz"]
    xx = np.linspace(0, 1.5 * b, 400)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    near = x < 1.5 * b
    ax.plot(x[near], p[near], "o", ms=3, label="dolfinx_ntf nodal pressure F_N/A")
    ax.plot(xx, p0 * np.sqrt(np.clip(1 - (xx / b) ** 2, 0, None)), "k-", label="Hertz")
    ax.plot(
        xx,
        summary["p0_fit"] * np.sqrt(np.clip(1 - (xx / summary["b_fit"]) ** 2, 0, None)),
        "r--",
        label=f"fit: b {summary['b_error']:+.1%}, p0 {summary['p0_error']:+.1%}",
    )
    ax.set_xlabel("distance from the contact line x [mm]")
    ax.set_ylabel("contact pressure [MPa]")
    ax.set_title(
        f"Plane-strain Hertz: cylinder R = {RADIUS:g} mm on a block\n"
        f"F' = {summary['line_load']:.0f} N/mm, {summary['dofs']} dofs"
    )
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _print_report(s: dict) -> None:
    """Final report: computed values against Hertz's, then the checks."""
    print()
    print(
        f"Hertz cylinder (plane strain): {s['dofs']} dofs, {s['increments']} increments (Newton "
        f"iterations {s['iterations']}), {s['springs']} springs, solve {s['solve_time']:.1f} s, "
        f"total {s['time']:.1f} s"
    )
    print(
        f"Line load F' = {s['line_load']:.6g} N/mm; contact force of the half model "
        f"{s['force']:.6g} N/mm (F'/2 to {s['load_error']:.1e}), reaction of the block bottom "
        f"{s['reaction']:.6g} N/mm (relative difference {s['equilibrium_error']:.1e})"
    )
    print(f"{'quantity':<34} {'computed':>12} {'Hertz':>12} {'error':>9}")
    rows = [
        ("half-width, fit [mm]", s["b_fit"], s["b_hertz"], s["b_error"]),
        ("peak pressure, fit [MPa]", s["p0_fit"], s["p0_hertz"], s["p0_error"]),
        ("peak nodal pressure [MPa]", s["p_max"], s["p0_hertz"], s["p_max_error"]),
    ]
    for name, computed, exact, error in rows:
        print(f"{name:<34} {computed:>12.6g} {exact:>12.6g} {error:>+9.2%}")
    print(
        f"last closed node at x = {s['b_last_closed']:.4g} mm, first open one at x = "
        f"{s['b_first_open']:.4g} mm (Hertz b = {s['b_hertz']:.4g} mm)"
    )
    verdict = "PASSED" if s["passed"] else "FAILED"
    print(
        f"Checks (contact force = F'/2 = reaction to {TOLERANCE:.0e}): {verdict}. "
        f"Results: {s['xdmf']}, {s.get('png')}"
    )


# %%
# Run
# ---
# The build of this page ran ``demos/hertz_cylinder_2d.py --coarse`` (five elements across the
# half-width): the Hertz values for the line load, the computed ones and their relative
# errors, then the figure of the pressure across the strip beside Hertz's profile.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
