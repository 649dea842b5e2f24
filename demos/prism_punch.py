"""A round punch of prisms pressed on a block of hexahedra: gmsh extrusions and contact.

A steel punch (a cylinder of radius 20 mm and height 30 mm) stands in the middle of an aluminium
block (100 x 100 x 50 mm, clamped at its bottom); a pressure on its top pushes it into the block.
Both bodies are gmsh extrusions: the punch's disk is triangulated and extruded with
``recombine=True``, which gives *prisms* (6-node wedges); the block's square is meshed with
quadrilaterals and extruded into hexahedra. dolfinx holds one cell type per mesh, so
:func:`~dolfinx_ntf.meshes.gmsh_io.mesh_from_gmsh` reads each prism as a hexahedron with one
collapsed edge, as the deck runner reads CalculiX's C3D6 (docs/method.md §30, §32): one mesh of
hexahedra, on every dolfinx release. The punch bottom, made of the prisms' triangles, is the
*slave* surface; the block top (quadrilaterals) the *master*.

The demo checks the equilibrium: the reaction of the clamped bottom equals the load (pressure x
the meshed top area) to 1e-8 and the vertical contact force on the punch to 1e-7 (the converged
Newton iteration leaves about 1e-3 N), and it plots
the contact pressure of the springs against their distance from the axis (the flat punch's
pressure rises towards its edge, as Boussinesq's rigid punch ``p0 / sqrt(1 - (r/a)^2) / 2``).

Run it with::

    .venv/bin/python demos/prism_punch.py           # 17k dofs, about 25 s
    .venv/bin/python demos/prism_punch.py --coarse  # small mesh (tests)
"""

from __future__ import annotations

import argparse
import sys
import time
import typing
from pathlib import Path

from mpi4py import MPI

import gmsh
import numpy as np

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh
from dolfinx_ntf.solvers.convergence import TIGHT_FIELD_CONTROLS

__all__ = ["build_prism_punch", "main"]

# %%
# Parameters
# ----------
# Units: mm, N, MPa.

BLOCK_SIZE = (100.0, 100.0, 50.0)
RADIUS, HEIGHT = 20.0, 30.0
E_PUNCH, NU_PUNCH = 210_000.0, 0.3  # steel
E_BLOCK, NU_BLOCK = 70_000.0, 0.33  # aluminium
PRESSURE = 100.0  # MPa on the punch top
#: Physical groups: cells, then facets.
BLOCK, PUNCH = 1, 2
BLOCK_BOTTOM, BLOCK_TOP, PUNCH_BOTTOM, PUNCH_TOP = 11, 12, 13, 14
#: Relative tolerance of the equilibrium checks: the reaction of the clamped bottom is the load to
#: round-off; the punch's contact force to the last Newton residual (measured 1.9e-8 on the
#: coarse mesh, 8e-4 N left by the converged iteration).
TOLERANCE = 1e-8
FORCE_TOLERANCE = 1e-7


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh (tests)")
    parser.add_argument("--output", type=Path, default=Path("output"))
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser.parse_args(argv)


# %%
# The gmsh model
# --------------
# Two OpenCASCADE extrusions that touch at z = 0 but keep their own nodes (no fragment): the
# block's square meshed by a transfinite, recombined grid, the punch's disk by triangles.


def build_prism_punch(block_divisions: int = 20, punch_size: float = 4.0, layers: int = 6) -> None:
    """A new gmsh model: the punch of prisms on the block of hexahedra, meshed and tagged.

    Args:
        block_divisions: Hexahedra along each side of the block (and half as many in depth).
        punch_size: Element size on the punch's disk.
        layers: Prism layers through the punch's height.
    """
    gmsh.model.add("prism_punch")
    occ = gmsh.model.occ
    lx, ly, lz = BLOCK_SIZE
    square = occ.addRectangle(0, 0, -lz, lx, ly)
    block = occ.extrude([(2, square)], 0, 0, lz, [block_divisions // 2], recombine=True)
    disk = occ.addDisk(lx / 2, ly / 2, 0, RADIUS, RADIUS)
    punch = occ.extrude([(2, disk)], 0, 0, HEIGHT, [layers], recombine=True)
    occ.synchronize()
    for curve in gmsh.model.getBoundary([(2, square)], oriented=False):
        gmsh.model.mesh.setTransfiniteCurve(abs(curve[1]), block_divisions + 1)
    gmsh.model.mesh.setTransfiniteSurface(square)
    gmsh.model.mesh.setRecombine(2, square)
    gmsh.model.mesh.setSize(gmsh.model.getBoundary([(2, disk)], recursive=True), punch_size)
    gmsh.model.mesh.generate(3)
    for dim, entity, tag in (
        (3, block[1][1], BLOCK), (3, punch[1][1], PUNCH), (2, square, BLOCK_BOTTOM),
        (2, block[0][1], BLOCK_TOP), (2, disk, PUNCH_BOTTOM), (2, punch[0][1], PUNCH_TOP),
    ):  # fmt: skip
        gmsh.model.addPhysicalGroup(dim, [entity], tag)


# %%
# The analysis
# ------------
# Elasticity in UFL, the block bottom clamped, the punch held sideways at its top; one contact
# pair with CalculiX's linear pressure-overclosure law; the load in fixed increments.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (equilibrium errors, springs, pressures, files)."""
    args = _parse(argv)
    comm = MPI.COMM_WORLD
    start = time.perf_counter()
    sizes = {"block_divisions": 6, "punch_size": 8.0, "layers": 3} if args.coarse else {}
    mesh, cell_tags, facet_tags = mesh_from_gmsh(build_prism_punch, comm, **sizes)

    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    F = (
        ufl.inner(small_strain_stress(u, E_BLOCK, NU_BLOCK), ufl.grad(v)) * dx(BLOCK)
        + ufl.inner(small_strain_stress(u, E_PUNCH, NU_PUNCH), ufl.grad(v)) * dx(PUNCH)
        + pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(PUNCH_TOP)
    )
    clamped = dolfinx.fem.locate_dofs_topological(V, 2, facet_tags.find(BLOCK_BOTTOM))
    bottom_bc = dolfinx.fem.dirichletbc(np.zeros(3), clamped, V)
    top = facet_tags.find(PUNCH_TOP)
    sideways = [component_bc(V, k, top) for k in (0, 1)]
    bcs = [bottom_bc, *sideways]

    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E_BLOCK)
    pair = ntf.ContactPair(
        ntf.FacetSurface(facet_tags, PUNCH_BOTTOM),
        ntf.FacetSurface(facet_tags, BLOCK_TOP),
        ntf.SurfaceInteraction(law),
        name="punch",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    solver = ntf.ContactNewtonSolver(comm, problem, controls=TIGHT_FIELD_CONTROLS)
    if not args.quiet:
        ntf.log_progress()
    increments = 2 if args.coarse else 4
    step = ntf.StaticStep(
        lambda t: setattr(pressure, "value", PRESSURE * t),
        initial_increment=1.0 / increments,
        fixed=True,
    )
    results = step.run(solver, u)

    # --- Checks ----------------------------------------------------------------------------------
    area = comm.allreduce(
        dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ds(PUNCH_TOP))), op=MPI.SUM
    )
    load = PRESSURE * area  # the meshed disk (a polygon) carries it
    force = ntf.contact_force(problem)
    reaction = ntf.reaction(problem, dofs=bottom_bc)
    (res,) = ntf.contact_results(problem)
    x = problem.reference_coordinates[res.node]
    radius = np.hypot(x[:, 0] - BLOCK_SIZE[0] / 2, x[:, 1] - BLOCK_SIZE[1] / 2)
    closed = res.clearance < 0
    radii = np.concatenate(comm.allgather(radius[closed]))
    pressures = np.concatenate(comm.allgather(res.pressure[closed]))
    summary = {
        "dofs": 3 * V.dofmap.index_map.size_global,
        "cells": mesh.topology.index_map(3).size_global,
        "springs": comm.allreduce(int(res.node.size), op=MPI.SUM),
        "closed": int(radii.size),
        "increments": len(results),
        "load": load,
        "force_error": abs(force[2] - load) / load,
        "reaction_error": abs(reaction[2] - load) / load,
        "mean_pressure": load / area,
        "max_pressure": float(pressures.max()),
        "centre_pressure": float(pressures[np.argmin(radii)]),
        "time": time.perf_counter() - start,
    }
    summary["passed"] = bool(
        summary["force_error"] < FORCE_TOLERANCE and summary["reaction_error"] < TOLERANCE
    )
    if comm.rank == 0:
        args.output.mkdir(parents=True, exist_ok=True)
        summary["png"] = str(_plot(args.output / "prism_punch.png", radii, pressures))
        print(
            f"\nPrism punch: {summary['dofs']} dofs, {summary['cells']} cells, "
            f"{summary['springs']} springs ({summary['closed']} closed), {summary['time']:.1f} s\n"
            f"contact force and reaction against the load {load:.6g} N: "
            f"{summary['force_error']:.1e}, {summary['reaction_error']:.1e}; pressure at the "
            f"centre {summary['centre_pressure']:.1f} MPa, largest {summary['max_pressure']:.1f} "
            f"(mean {summary['mean_pressure']:.1f}): {'PASSED' if summary['passed'] else 'FAILED'}"
        )
    return summary


# %%
# Figure
# ------
# The springs' contact pressure against their distance from the axis, with Boussinesq's rigid
# flat punch of the same mean pressure for comparison (the punch is not rigid, the block not a
# half-space: a guide, not a reference).


def _plot(path: Path, radii: np.ndarray, pressures: np.ndarray) -> Path:
    """Contact pressure against the distance from the axis."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(radii, pressures, "o", ms=3, label="springs (slave nodes on the prisms' triangles)")
    r = np.linspace(0.0, 0.97 * RADIUS, 100)
    ax.plot(r, 0.5 * PRESSURE / np.sqrt(1 - (r / RADIUS) ** 2), "k--", label="rigid flat punch")
    ax.axhline(PRESSURE, color="0.6", lw=0.8, label="mean pressure")
    ax.set_xlabel("distance from the axis [mm]")
    ax.set_ylabel("contact pressure [MPa]")
    ax.set_title("Round punch of prisms on a block of hexahedra")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# %%
# Run
# ---
# The build of this page ran ``demos/prism_punch.py --coarse``.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
