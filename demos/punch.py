"""Flat punch pressed onto a block: frictionless node-to-face contact with dolfinx_ntf.

A steel punch (40 x 40 x 30 mm) stands in the middle of an aluminium block (100 x 100 x 50 mm). A
uniform pressure on the punch top pushes it into the block; the block bottom is clamped. The punch
bottom is the *slave* surface (its nodes get spring elements), the block top the *master* surface
(its faces receive them). The contact law is CalculiX's ``PRESSURE-OVERCLOSURE=LINEAR`` with the
defaults CalculiX derives from Young's modulus. The meshes do not match (5 mm elements on the block,
4 mm on the punch): most punch nodes land inside block faces, which is what node-to-face contact is
for.

The load is applied in increments with automatic incrementation (CalculiX ``*STATIC``); the solver
prints CalculiX-like progress lines. At the end the demo checks global equilibrium: the vertical
contact force on the punch (``dolfinx_ntf.contact_force``) and the reaction of the clamped block
bottom (``dolfinx_ntf.reaction``) equal the applied load to 1e-8 (relative), and so does the sum
of pressure x area once each spring's normal is taken into account (sum p A n_z); sum p A itself
exceeds the load by about 1e-6 because the master normals tilt as the block deforms (checked to
1e-5). Results (displacement, contact pressure, clearance and status, from the initial state on)
go to ``output/punch.xdmf`` for ParaView.

Run it with::

    .venv/bin/python demos/punch.py              # ~18k dofs, hexahedra
    .venv/bin/python demos/punch.py --coarse     # small mesh (tests)
"""

from __future__ import annotations

import argparse
import sys
import time
import typing
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes import punch as geometry
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

__all__ = ["main"]

# %%
# Parameters
# ----------
# The geometry is the default of :mod:`dolfinx_ntf.meshes.punch` scaled to millimetres, the
# materials steel on aluminium, and the load a pressure of 100 MPa on the punch top.

# Units: mm, N, MPa. The geometry is the default of ``dolfinx_ntf.meshes.punch`` scaled by 100 (mm).
SCALE = 100.0
BLOCK_SIZE = (1.0 * SCALE, 1.0 * SCALE, 0.5 * SCALE)
PUNCH_SIZE = (0.4 * SCALE, 0.4 * SCALE, 0.3 * SCALE)
E_PUNCH, NU_PUNCH = 210_000.0, 0.3  # steel
E_BLOCK, NU_BLOCK = 70_000.0, 0.33  # aluminium
PRESSURE = 100.0  # MPa on the punch top: 160 kN in all

#: Relative tolerance of the equilibrium check.
TOLERANCE = 1e-8
#: Bound on the relative excess of sum p A over the load (tilted normals: about 1e-6 measured).
PRESSURE_AREA_TOLERANCE = 1e-5


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh (tests)")
    parser.add_argument(
        "--output", type=Path, default=Path("output"), help="output folder (default: output/)"
    )
    parser.add_argument("--cell-type", choices=("hexahedron", "tetrahedron"), default="hexahedron")
    parser.add_argument(
        "--increments",
        type=int,
        default=4,
        help="initial (and largest) number of increments of the step (default 4)",
    )
    parser.add_argument(
        "--ccx-pairing",
        action="store_true",
        help="start the face search at the nearest centroid like CalculiX (slower Newton)",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser.parse_args(argv)


# %%
# The analysis
# ------------
# ``main`` builds the two-body mesh with gmsh (:func:`~dolfinx_ntf.meshes.gmsh_io.mesh_from_gmsh`),
# the small-strain residual of both bodies, the contact pair (punch bottom slave, block top master,
# :meth:`LinearLaw.with_ccx_defaults <dolfinx_ntf.LinearLaw.with_ccx_defaults>`), then solves with
# :class:`~dolfinx_ntf.ContactNewtonSolver` and :class:`~dolfinx_ntf.StaticStep`, writing every
# increment with :class:`~dolfinx_ntf.ContactWriter`.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (iterations per increment, forces, timings, check result)."""
    args = _parse(argv)
    if args.increments < 1:
        raise ValueError(f"--increments must be at least 1, got {args.increments}")
    comm = MPI.COMM_WORLD
    rank0 = comm.rank == 0
    start = time.perf_counter()

    # --- Mesh ------------------------------------------------------------------------------------
    # The gmsh builder of dolfinx_ntf.meshes.punch makes two separate bodies with physical groups;
    # the facet tags name the block bottom (clamped), the block top (master), the punch bottom
    # (slave) and the punch top (loaded). Hexahedra give 4-node master faces and 5-node springs.
    sizes = (
        dict(geometry.COARSE) if args.coarse else {"mesh_size_block": 0.05, "mesh_size_punch": 0.04}
    )
    sizes = {key: value * SCALE for key, value in sizes.items()}
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        geometry.build_punch,
        comm,
        block_size=BLOCK_SIZE,
        punch_size=PUNCH_SIZE,
        cell_type=args.cell_type,
        **sizes,
    )

    # --- Bulk problem in UFL ---------------------------------------------------------------------
    # Small-strain elasticity with one material per body. The pressure on the punch top is a
    # Constant that the step scales with the step time; ``n`` is the outward normal, so ``p n·v``
    # in the residual R = f_int - f_ext is a pressure pushing into the punch.
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    F = (
        ufl.inner(small_strain_stress(u, E_BLOCK, NU_BLOCK), ufl.grad(v)) * dx(geometry.BLOCK)
        + ufl.inner(small_strain_stress(u, E_PUNCH, NU_PUNCH), ufl.grad(v)) * dx(geometry.PUNCH)
        + pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(geometry.PUNCH_TOP)
    )

    # Block bottom clamped. The punch is held vertically by the contact only; its in-plane rigid
    # motions (two translations, rotation about z) are removed by u_x = u_y = 0 on its top face.
    bcs = [
        dolfinx.fem.dirichletbc(
            np.zeros(3, dtype=PETSc.ScalarType),
            dolfinx.fem.locate_dofs_topological(V, 2, facet_tags.find(geometry.BLOCK_BOTTOM)),
            V,
        ),
        component_bc(V, 0, facet_tags.find(geometry.PUNCH_TOP)),
        component_bc(V, 1, facet_tags.find(geometry.PUNCH_TOP)),
    ]

    # --- Contact ----------------------------------------------------------------------------------
    # LINEAR law with CalculiX's defaults from the block's Young's modulus: slope K = 50 E, tension
    # E/70000, pairing cutoff 1e-3 sqrt(A). In mm, K h is ~250 E for 5 mm elements: the penetration
    # p/K is ~1e-5 mm, a thousandth of the punch's displacement.
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E_BLOCK)
    pair = ntf.ContactPair(
        slave=ntf.FacetSurface(facet_tags, geometry.PUNCH_BOTTOM),
        master=ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP),
        interaction=ntf.SurfaceInteraction(law),
        name="punch",
    )
    # CalculiX starts each node's face search at the nearest face centroid. The punch centre node
    # sits right above a block vertex, at the bottom of the dish the punch presses into the block:
    # all four faces around the vertex hold its projection, rounding decides, and the node hops
    # between two of them at every re-pairing, each hop tilting its force a little. With the strict
    # tolerance used here (residual 1e-10 of the first one) Newton then waits for the pairing to
    # freeze at iteration 9. Starting the search at the node's current face (beyond CalculiX) keeps
    # it put: 2-4 iterations. ``--ccx-pairing`` shows CalculiX's behaviour.
    problem = ntf.ContactProblem(F, u, [pair], bcs, walk_from_previous_face=not args.ccx_pairing)
    solver = ntf.ContactNewtonSolver(comm, problem)
    if not args.quiet:
        ntf.log_progress()

    # --- Static step ------------------------------------------------------------------------------
    # Automatic incrementation: start with 1/increments of the load, never more (max_increment),
    # halve on divergence. The XDMF file gets the initial state, then after each converged
    # increment the forces are recorded and the state written.
    top_area = PUNCH_SIZE[0] * PUNCH_SIZE[1]
    args.output.mkdir(parents=True, exist_ok=True)
    xdmf = args.output / "punch.xdmf"
    rows: list[dict] = []
    with ntf.ContactWriter(problem, xdmf) as writer:
        writer.write(0.0)

        def record(result: ntf.IncrementResult) -> None:
            rows.append(
                {
                    "increment": result.increment,
                    "time": result.time,
                    "iterations": result.iterations,
                    "springs": result.springs,
                    **_forces(problem, facet_tags, PRESSURE * result.time * top_area),
                }
            )
            writer.write(result.time)

        step = ntf.StaticStep(
            lambda t: setattr(pressure, "value", PRESSURE * t),
            initial_increment=1.0 / args.increments,
            max_increment=1.0 / args.increments,
            on_increment=record,
        )
        solve_start = time.perf_counter()
        step.run(solver, u)
        solve_time = time.perf_counter() - solve_start

    # --- Check and report -------------------------------------------------------------------------
    final = rows[-1]
    passed = all(
        r["vertical_error"] <= TOLERANCE
        and r["normal_error"] <= TOLERANCE
        and r["reaction_error"] <= TOLERANCE
        and abs(r["pressure_area"] / r["load"] - 1) <= PRESSURE_AREA_TOLERANCE
        for r in rows
    )
    summary = {
        "dofs": V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
        "increments": len(rows),
        "iterations": [r["iterations"] for r in rows],
        "springs": [r["springs"] for r in rows],
        "load": [r["load"] for r in rows],
        "contact_force": [r["vertical"] for r in rows],
        "pressure_area": [r["pressure_area"] for r in rows],
        "vertical_error": max(r["vertical_error"] for r in rows),
        "normal_error": max(r["normal_error"] for r in rows),
        "reaction_error": max(r["reaction_error"] for r in rows),
        "pressure_area_deviation": final["pressure_area"] / final["load"] - 1.0,
        "max_pressure": final["max_pressure"],
        "mean_pressure": final["load"] / top_area,
        "contact_area": final["contact_area"],
        "solve_time": solve_time,
        "time": time.perf_counter() - start,
        "xdmf": str(xdmf),
        "passed": passed,
    }
    if rank0:
        _print_table(rows, summary)
    return summary


# %%
# Equilibrium checks and the report
# ----------------------------------
# The contact force (:func:`~dolfinx_ntf.contact_force`), the reaction of the clamped block bottom
# (:func:`~dolfinx_ntf.reaction`) and ``sum p A n_z`` must equal the load.


def _forces(problem: ntf.ContactProblem, facet_tags: typing.Any, load: float) -> dict:
    """Contact force balance of the current (converged) state.

    ``contact_area`` is Σ A_p over the closed springs (the punch bottom in the current
    configuration); ``vertical`` is Σ F_z over the slave nodes (force of the block on the punch);
    ``reaction`` the vertical reaction of the clamped block bottom; ``pressure_area`` is Σ p A =
    Σ F_N, larger than the vertical force by the tilt of the master normals in the deformed block;
    ``normal_z`` weights each spring by its normal's z component, Σ p A n_z, which must equal the
    load exactly.
    """
    comm = problem.u.function_space.mesh.comm
    vertical = float(ntf.contact_force(problem, "punch")[2])
    area = ntf.contact_area(problem, "punch")
    reaction = float(ntf.reaction(problem, ntf.FacetSurface(facet_tags, geometry.BLOCK_BOTTOM))[2])
    # Σ p A and its weighting by the normals need the per-spring table.
    res = ntf.contact_results(problem)[0]
    pressure_area = comm.allreduce(float(np.sum(res.pressure * res.area)), op=MPI.SUM)
    normal_z = comm.allreduce(float(np.sum(res.pressure * res.area * res.normal[:, 2])), op=MPI.SUM)
    closed = res.clearance < 0
    max_pressure = comm.allreduce(float(res.pressure.max(initial=0.0)), op=MPI.MAX)
    penetration = comm.allreduce(float(-res.clearance[closed].min(initial=0.0)), op=MPI.MAX)
    return {
        "load": load,
        "vertical": vertical,
        "pressure_area": pressure_area,
        "normal_z": normal_z,
        "contact_area": area,
        "reaction": reaction,
        "reaction_error": abs(reaction - load) / load,
        "vertical_error": abs(vertical - load) / load,
        "normal_error": abs(normal_z - load) / load,
        "closed": comm.allreduce(int(closed.sum()), op=MPI.SUM),
        "max_pressure": max_pressure,
        "max_penetration": penetration,
    }


def _print_table(rows: list[dict], summary: dict) -> None:
    """Final table: one row per increment, then the checks."""
    print()
    print(
        f"Flat punch: {summary['dofs']} dofs, {summary['increments']} increments, "
        f"solve {summary['solve_time']:.1f} s, total {summary['time']:.1f} s"
    )
    print(
        f"{'inc':>3} {'time':>6} {'iter':>4} {'springs':>7} {'closed':>6} {'load [N]':>12} "
        f"{'sum F_z [N]':>14} {'rel.err':>8} {'sum p*A [N]':>14} {'max p':>8} "
        f"{'max pen. [mm]':>13}"
    )
    for r in rows:
        print(
            f"{r['increment']:>3} {r['time']:>6.3f} {r['iterations']:>4} {r['springs']:>7} "
            f"{r['closed']:>6} {r['load']:>12.6g} {r['vertical']:>14.8g} "
            f"{r['vertical_error']:>8.1e} {r['pressure_area']:>14.8g} "
            f"{r['max_pressure']:>8.4g} {r['max_penetration']:>13.3e}"
        )
    print(
        f"Contact area {summary['contact_area']:.6g} mm^2 (punch bottom "
        f"{PUNCH_SIZE[0] * PUNCH_SIZE[1]:g} mm^2). "
        f"Mean pressure under the punch {summary['mean_pressure']:.4g} MPa, "
        f"peak {summary['max_pressure']:.4g} MPa (corner singularity). "
        f"Sum p*A exceeds the load by {summary['pressure_area_deviation']:.2e} "
        f"(tilted master normals); sum p*A*n_z matches it to {summary['normal_error']:.1e}, "
        f"the reaction of the block bottom to {summary['reaction_error']:.1e}."
    )
    verdict = "PASSED" if summary["passed"] else "FAILED"
    print(
        f"Equilibrium check (sum F_z, base reaction and sum p*A*n_z to {TOLERANCE:.0e}, sum p*A to "
        f"{PRESSURE_AREA_TOLERANCE:.0e}): {verdict}. "
        f"Results: {summary['xdmf']}"
    )


# %%
# Run
# ---
# The build of this page ran ``demos/punch.py --coarse``: one row per increment, then the
# equilibrium errors.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
