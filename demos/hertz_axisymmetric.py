"""Hertz contact in axisymmetry: the sphere of ``hertz_sphere.py`` as a 2D model of revolution.

The same steel hemisphere (R = 25 mm) on the same steel block, its flat top pushed down by the same
0.55 mm, with the same LINEAR law (K = 10 E) and increments, but meshed in the meridian half-plane
(``x = r``, ``y = z``; ``dolfinx_ntf.meshes.hertz.build_hertz_axisymmetric``) and solved with the
axisymmetric UFL helpers (``dolfinx_ntf.fem.axisymmetric``) and ring spring areas
(``ContactPair(..., axisymmetric=True)``, docs/method.md §17). Forces are those of the whole ring.
Hertz's closed forms for the total force F::

    1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2,   a = (3 F R / (4 E*))^(1/3),   p0 = 3 F / (2 pi a^2).

The demo fits Hertz's profile to the nodal pressures F_N/A_p (reference radii) and compares the
fitted a and p0 with those of the computed force; the force is checked against the reaction at the
sphere's top. ``--size-fine`` sets the element size at the contact point (relative to R; the 3D
demo's default is 0.014), ``--order 2`` uses 6-node triangles with curved edges.

Run it with::

    .venv/bin/python demos/hertz_axisymmetric.py                    # same sizes as the 3D demo
    .venv/bin/python demos/hertz_axisymmetric.py --size-fine 0.002  # finer
    .venv/bin/python demos/hertz_axisymmetric.py --coarse           # tests
    .venv/bin/python demos/hertz_axisymmetric.py --output output    # and a pressure plot
"""

from __future__ import annotations

import argparse
import math
import time
import typing
from pathlib import Path

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import measures
from dolfinx_ntf.fem.axisymmetric import axisymmetric_grad, axisymmetric_stress, axisymmetric_weight
from dolfinx_ntf.fem.elasticity import component_bc
from dolfinx_ntf.meshes import hertz as geometry
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

__all__ = ["main"]

# The values of demos/hertz_sphere.py.
RADIUS = 25.0
E_SPHERE, NU_SPHERE = 210_000.0, 0.3
E_BLOCK, NU_BLOCK = 210_000.0, 0.3
DISPLACEMENT = 0.55
PENALTY = 10.0
#: Element size at the contact point relative to R: the 3D demo's default and coarse meshes.
SIZE_FINE, SIZE_COARSE_MESH = 0.014, 0.04


def hertz(force: float, radius: float = RADIUS) -> tuple[float, float]:
    """Hertz's contact radius a and peak pressure p0 for the total force ``force``."""
    e_star = 1.0 / ((1 - NU_SPHERE**2) / E_SPHERE + (1 - NU_BLOCK**2) / E_BLOCK)
    a = (3 * force * radius / (4 * e_star)) ** (1 / 3)
    return a, 3 * force / (2 * math.pi * a**2)


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="the 3D demo's coarse sizes (tests)")
    parser.add_argument("--size-fine", type=float, default=None, help="size at the contact / R")
    parser.add_argument("--order", type=int, choices=(1, 2), default=1)
    parser.add_argument("--displacement", type=float, default=DISPLACEMENT)
    parser.add_argument("--penalty", type=float, default=PENALTY, help="K in units of E per mm")
    parser.add_argument("--increments", type=int, default=8)
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    parser.add_argument(
        "--output", type=Path, default=None, help="folder for hertz_axisymmetric_pressure.png"
    )
    return parser.parse_args(argv)


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the axisymmetric Hertz model; returns a summary (sizes, figures, errors, times)."""
    args = _parse(argv)
    if args.increments < 1 or args.penalty <= 0:
        raise SystemExit(
            f"need --increments >= 1 and --penalty > 0, got {args.increments} and {args.penalty}"
        )
    comm = MPI.COMM_WORLD
    start = time.perf_counter()
    size_fine = args.size_fine or (SIZE_COARSE_MESH if args.coarse else SIZE_FINE)
    sizes = {key: value * RADIUS for key, value in geometry.COARSE.items()} if args.coarse else {}
    sizes["size_fine"] = size_fine * RADIUS
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        geometry.build_hertz_axisymmetric, comm, gdim=2, radius=RADIUS, order=args.order, **sizes
    )
    V = compat.vector_space(mesh, "Lagrange", args.order)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    w = axisymmetric_weight(mesh)
    F = ufl.inner(axisymmetric_stress(u, E_BLOCK, NU_BLOCK), axisymmetric_grad(v)) * w * dx(
        geometry.BLOCK
    ) + ufl.inner(axisymmetric_stress(u, E_SPHERE, NU_SPHERE), axisymmetric_grad(v)) * w * dx(
        geometry.SPHERE
    )
    # Block bottom clamped, u_r = 0 on the axis, the sphere's top pushed down.
    Vz, _ = compat.component_space(V, 1)
    top_uz = dolfinx.fem.Function(Vz)
    top = dolfinx.fem.locate_dofs_topological(
        (V.sub(1), Vz), 1, facet_tags.find(geometry.SPHERE_TOP)
    )
    bottom = facet_tags.find(geometry.BLOCK_BOTTOM)
    bcs = [
        component_bc(V, 0, bottom),
        component_bc(V, 1, bottom),
        component_bc(V, 0, facet_tags.find(geometry.SYMMETRY_X)),
        dolfinx.fem.dirichletbc(top_uz, top, V.sub(1)),
    ]
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E_BLOCK, slope=args.penalty * E_BLOCK)
    pair = ntf.ContactPair(
        slave=ntf.FacetSurface(facet_tags, geometry.SPHERE_CONTACT),
        master=ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP),
        interaction=ntf.SurfaceInteraction(law),
        name="hertz",
        axisymmetric=True,
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs, walk_from_previous_face=True)
    solver = ntf.ContactNewtonSolver(comm, problem)
    if not args.quiet:
        ntf.log_progress()
    iterations: list[int] = []

    def set_load(t: float) -> None:
        top_uz.x.array[:] = -(t**2) * args.displacement

    step = ntf.StaticStep(
        set_load,
        initial_increment=1.0 / args.increments,
        max_increment=1.0 / args.increments,
        on_increment=lambda result: iterations.append(result.iterations),
    )
    solve_start = time.perf_counter()
    step.run(solver, u)
    solve_time = time.perf_counter() - solve_start

    # The force of the block on the sphere (whole ring) and the reaction at the sphere's top.
    state = problem.states[0]
    ev = state.evaluation
    force = -float(ev.forces[:, -1, 1].sum())
    residual = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(F))
    top_nodes = dolfinx.fem.locate_dofs_topological(V, 1, facet_tags.find(geometry.SPHERE_TOP))
    reaction = -float(residual.array[2 * top_nodes + 1].sum())
    a_hertz, p0_hertz = hertz(force)
    reference = V.tabulate_dof_coordinates()[state.slave.nodes, 0]
    pressure = np.zeros(state.slave.nodes.size)
    pressure[state.spring_slave] = ev.normal_force / ev.area
    a_fit, p0_fit = measures.fit_hertz_profile(reference, pressure, a_hertz, p0_hertz)
    closed = pressure > 0
    summary = {
        "dofs": V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
        "order": args.order,
        "size_fine": size_fine,
        "increments": len(iterations),
        "iterations": iterations,
        "springs": state.num_springs,
        "force": force,
        "reaction": reaction,
        "equilibrium_error": abs(reaction / force - 1),
        "a_hertz": a_hertz,
        "a_fit": a_fit,
        "a_last_closed": float(reference[closed].max()),
        "a_first_open": float(reference[~closed & (reference > reference[closed].max())].min()),
        "p0_hertz": p0_hertz,
        "p0_fit": p0_fit,
        "p_max": float(pressure.max()),
        "solve_time": solve_time,
    }
    summary["a_error"] = a_fit / a_hertz - 1
    summary["p0_error"] = p0_fit / p0_hertz - 1
    summary["p_max_error"] = summary["p_max"] / p0_hertz - 1
    if args.output is not None:
        args.output.mkdir(parents=True, exist_ok=True)
        summary["png"] = str(_plot(args.output, reference, pressure, summary))
    summary["time"] = time.perf_counter() - start
    if not args.quiet:
        print(
            f"Axisymmetric Hertz: {summary['dofs']} dofs (P{args.order}, h = {size_fine:g} R), "
            f"Newton iterations {iterations}, {state.num_springs} springs, solve "
            f"{solve_time:.2f} s, total {summary['time']:.2f} s\n"
            f"F = {force:.6g} N (reaction {reaction:.6g} N); a = {a_fit:.5g} mm "
            f"({summary['a_error']:+.2%} against Hertz {a_hertz:.5g}), p0 = {p0_fit:.6g} MPa "
            f"({summary['p0_error']:+.2%} against {p0_hertz:.6g}), nodal maximum "
            f"{summary['p_max_error']:+.2%}"
        )
    return summary


def _plot(folder: Path, r: np.ndarray, p: np.ndarray, summary: dict) -> Path:
    """Nodal contact pressure against radius beside Hertz's profile and the fitted one."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    a, p0 = summary["a_hertz"], summary["p0_hertz"]
    rr = np.linspace(0, 1.5 * a, 400)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    near = r < 1.5 * a
    ax.plot(r[near], p[near], "o", ms=3, label="nodal pressure F_N/A (ring areas)")
    ax.plot(rr, p0 * np.sqrt(np.clip(1 - (rr / a) ** 2, 0, None)), "k-", label="Hertz")
    fitted = summary["p0_fit"] * np.sqrt(np.clip(1 - (rr / summary["a_fit"]) ** 2, 0, None))
    label = f"fit: a {summary['a_error']:+.1%}, p0 {summary['p0_error']:+.1%}"
    ax.plot(rr, fitted, "r--", label=label)
    ax.set_xlabel("radius r [mm]")
    ax.set_ylabel("contact pressure [MPa]")
    ax.set_title(
        f"Axisymmetric Hertz: R = {RADIUS:g} mm, F = {summary['force'] / 1e3:.1f} kN, "
        f"{summary['dofs']} dofs"
    )
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = folder / "hertz_axisymmetric_pressure.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


if __name__ == "__main__":
    main()
