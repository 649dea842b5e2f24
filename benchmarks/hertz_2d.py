"""Plane-strain Hertz line contact in native 2D: a convergence table against the closed form.

Three half models (x >= 0, ``dolfinx_ntf.meshes.cylinder``), steel (E = 210000 MPa, nu = 0.3),
plane strain per unit thickness, P1 triangles, frictionless, the LINEAR law of
``demos/hertz_cylinder_2d.py`` (K = 1e4 E / R1):

- ``rigid-line``: an elastic cylinder (R1 = 25 mm) on the rigid line y = 0 (``RigidPlane``),
  ``E* = E / (1 - nu^2)``, ``R = R1``;
- ``block``: the cylinder on an elastic block 4 R1 wide and deep, ``E* = E / (2 (1 - nu^2))``,
  ``R = R1``;
- ``two-cylinders``: the cylinder on a second elastic cylinder (R2 = 50 mm), the same ``E*``
  and ``1/R = 1/R1 + 1/R2``.

Hertz: ``b = sqrt(4 F' R / (pi E*))``, ``p0 = 2 F' / (pi b)``. The line load ``F'`` is chosen for
``b = R1/20``; the mesh has the size ``b/n`` within ``2.5 b`` of the contact point for each
refinement ``n``. Each row gives the dofs, Hertz's profile fitted to the nodal pressures ``F_N/A_p``
(``measures.fit_hertz_profile``; relative errors of ``b`` and ``p0``), the contact force against
``F'/2`` and the Newton iterations and solve time. Run::

    .venv/bin/python benchmarks/hertz_2d.py                    # refinements 5 10 20 40
    .venv/bin/python benchmarks/hertz_2d.py --only two-cylinders --refinements 10
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import typing

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import measures
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes import cylinder
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

__all__ = ["MODELS", "hertz", "main", "run"]

E, NU = 210_000.0, 0.3
R1, R2 = 25.0, 50.0
HALF_WIDTH = 0.05 * R1
MODELS = ("rigid-line", "block", "two-cylinders")
#: The lower cylinder's element size at the contact over the upper one's (non-matching arcs).
MASTER_RATIO = 0.75


def hertz(model: str) -> tuple[float, float, float]:
    """``(F', b, p0)`` of Hertz's line contact for ``model``, with F' chosen for b = R1/20."""
    if model not in MODELS:
        raise ValueError(f"model {model!r}: expected one of {MODELS}")
    e_star = E / (1 - NU**2) / (1 if model == "rigid-line" else 2)
    radius = R1 * R2 / (R1 + R2) if model == "two-cylinders" else R1
    line_load = math.pi * e_star * HALF_WIDTH**2 / (4 * radius)
    return line_load, HALF_WIDTH, 2 * line_load / (math.pi * HALF_WIDTH)


def _mesh(
    model: str, size: float, master_ratio: float, comm: MPI.Comm
) -> tuple[typing.Any, typing.Any]:
    """The half model's mesh and facet tags, ``size`` near the contact point."""
    grading = {"size_fine": size, "size_coarse": 0.3 * R1, "refine_distance": 2.5 * HALF_WIDTH}
    if model == "two-cylinders":
        builder = cylinder.build_two_cylinders
        options = {"lower_radius": R2, "lower_size_fine": master_ratio * size}
    else:
        builder = cylinder.build_cylinder_on_block
        options = {"bodies": "cylinder" if model == "rigid-line" else "both"}
    mesh, _, facet_tags = mesh_from_gmsh(builder, comm, gdim=2, radius=R1, **grading, **options)
    return mesh, facet_tags


def run(
    model: str,
    refinement: int,
    *,
    master_ratio: float = MASTER_RATIO,
    increment: float = 0.25,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> dict[str, typing.Any]:
    """Solve ``model`` with the mesh size ``b/refinement`` at the contact; the row's figures.

    Args:
        model: One of :data:`MODELS`.
        refinement: Elements across Hertz's half-width.
        master_ratio: The lower cylinder's element size over the upper one's at the contact
            (``two-cylinders`` only; 1 puts every slave node over a vertex of the master arc).
        increment: The fixed increment of the load (cutbacks are counted).
        comm: Communicator.
    """
    if refinement < 1:
        raise ValueError(f"refinement {refinement}: need at least 1")
    line_load, b, p0 = hertz(model)
    start = time.perf_counter()
    mesh, ft = _mesh(model, HALF_WIDTH / refinement, master_ratio, comm)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    load = dolfinx.fem.Constant(mesh, 0.0)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    F += load / (2 * R1) * v[1] * ds(cylinder.CYLINDER_TOP)  # F'/2 over the flat top (width R1)
    bcs = [component_bc(V, 0, ft.find(cylinder.SYMMETRY))]
    if model == "rigid-line":
        master: typing.Any = ntf.RigidPlane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))
    else:
        master = ntf.FacetSurface(ft, cylinder.BLOCK_TOP)
        bottom = ft.find(cylinder.BLOCK_BOTTOM)
        bcs += [component_bc(V, 0, bottom), component_bc(V, 1, bottom)]
    law = ntf.LinearLaw(slope=1e4 / R1 * E, tension=E / 70000)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, cylinder.CYLINDER_CONTACT), master, ntf.SurfaceInteraction(law)
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    solver = ntf.ContactNewtonSolver(comm, problem)
    iterations: list[int] = []
    cutbacks = [0]

    def record(result: ntf.IncrementResult) -> None:
        iterations.append(result.iterations)
        cutbacks[0] += result.attempt - 1

    step = ntf.StaticStep(
        lambda t: setattr(load, "value", line_load * t),
        initial_increment=increment,
        max_increment=increment,
        on_increment=record,
    )
    solve_start = time.perf_counter()
    step.run(solver, u)
    solve_time = time.perf_counter() - solve_start

    nodes = problem.states[0].slave.nodes
    x = V.tabulate_dof_coordinates()[nodes, 0]
    pressure = ntf.ContactFields(problem).at_nodes(nodes)[0]
    x_all = np.concatenate(comm.allgather(x))
    p_all = np.concatenate(comm.allgather(pressure))
    b_fit, p0_fit = measures.fit_hertz_profile(x_all, p_all, b, p0)
    force = float(ntf.contact_force(problem)[1])
    return {
        "model": model,
        "refinement": refinement,
        "dofs": V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
        "b_error": b_fit / b - 1,
        "p0_error": p0_fit / p0 - 1,
        "load_error": abs(2 * force / line_load - 1),
        "iterations": iterations,
        "cutbacks": cutbacks[0],
        "solve_time": solve_time,
        "time": time.perf_counter() - start,
    }


def main(argv: typing.Sequence[str] | None = None) -> int:
    """Print the convergence table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", choices=MODELS, default=list(MODELS))
    parser.add_argument("--refinements", type=int, nargs="+", default=[5, 10, 20, 40])
    parser.add_argument(
        "--master-ratio",
        type=float,
        default=MASTER_RATIO,
        help=f"two-cylinders: lower over upper size at the contact (default {MASTER_RATIO})",
    )
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD
    rows = []
    for model in args.only:
        for refinement in args.refinements:
            r = run(model, refinement, master_ratio=args.master_ratio, comm=comm)
            name = model if model != "two-cylinders" else f"{model} ({args.master_ratio:g})"
            rows.append(
                f"| {name} | b/{refinement} | {r['dofs']} | {r['b_error']:+.2%} | "
                f"{r['p0_error']:+.2%} | {r['load_error']:.1e} | "
                f"{', '.join(map(str, r['iterations']))} | {r['cutbacks']} | "
                f"{r['solve_time']:.2f} | {r['time']:.2f} |"
            )
            if comm.rank == 0:
                print(rows[-1], flush=True)
    if comm.rank == 0:
        print()
        print(
            "| model | mesh at the contact | dofs | b | p0 | contact force - F'/2 "
            "| Newton iterations | cutbacks | solve [s] | total [s] |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|")
        print("\n".join(rows))
        print(
            f"\n{comm.size} process(es); b, p0: relative errors of the fitted Hertz profile; "
            "two-cylinders (r): the lower cylinder's element size is r times the upper one's."
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
