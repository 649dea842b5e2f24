"""Hertz contact: an elastic sphere pressed onto an elastic block, compared with Hertz's solution.

A steel hemisphere of radius R = 25 mm touches a steel block at one point; its flat top is pushed
down by a prescribed displacement. Hertz's theory (two elastic half-spaces, frictionless, small
strain) relates the total force F to the contact radius, the peak pressure and the pressure
distribution::

    1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2,   a = (3 F R / (4 E*))^(1/3),
    p0 = 3 F / (2 pi a^2),                   p(r) = p0 sqrt(1 - r^2/a^2)  for r < a.

Only a quarter of the model is meshed (``dolfinx_ntf.meshes.hertz``): the planes x = 0 and y = 0 are
symmetry planes of both bodies, so the total force is 4 times the quarter's. The sphere's curved
surface is the slave (its nodes get the springs), the block top the master. The displacement (0.55
mm) makes a/R = 0.155, so the contact radius spans about eleven elements of the default mesh (four
of the coarse one), and the block (13a wide, 10a deep) stands in for a half-space.

The demo takes the total force from the contact springs (checked against the reaction at the
sphere's top), evaluates Hertz's a and p0 for it, and compares them with the computed contact radius
and peak pressure (a least-squares fit of Hertz's profile to the nodal pressures, the nodal maximum,
and the last closed / first open node); it also compares the force carried by the fitted profile,
2/3 pi a^2 p0, with F. It saves ``output/hertz_deformed.png`` (the deformed mesh in the symmetry
plane y = 0 and the sphere's deformed contact surface, coloured by the recovered contact pressure),
``output/hertz_pressure.png`` (nodal pressure against radius beside the analytical curve) and
``output/hertz_sphere.xdmf``.

What limits the accuracy:

* the mesh: linear tetrahedra and nodal pressures F_N/A_p from lumped spring areas scatter by about
  +-10 % around the profile (the nodal maximum is the least reliable figure), and the pressure edge
  at r = a falls between two nodes, so nodes bracket a only to one element; the fit does better;
* the penalty: the springs let the bodies overlap by p/K, a compliance of relative size
  p0/(K a^2/R), about 1 % with K = 10 E; it widens the contact and lowers the peak a little;
* the finite bodies (Hertz assumes half-spaces and a << R; here a/R = 0.155), the faceted master,
  and contact evaluated in the current configuration while the bulk is small-strain (p0/E* = 0.1).

Run it with::

    .venv/bin/python demos/hertz_sphere.py            # ~26k dofs, ~1 min on 2 cores
    .venv/bin/python demos/hertz_sphere.py --coarse   # ~3k dofs (tests)
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
import dolfinx.fem.petsc
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import measures
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.fem.surfaces import boundary_faces, reference_coordinates
from dolfinx_ntf.kernels.spring_areas import spring_areas
from dolfinx_ntf.kernels.springs import evaluate_springs
from dolfinx_ntf.meshes import hertz as geometry
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

__all__ = ["hertz", "main"]

# %%
# Parameters and Hertz's solution
# -------------------------------
# Steel on steel; the penalty slope is 10 E per mm, a fifth of CalculiX's default, which keeps the
# overlap ``p/K`` small against the contact radius while Newton still converges in a few
# iterations.

# Units: mm, N, MPa.
RADIUS = 25.0
E_SPHERE, NU_SPHERE = 210_000.0, 0.3
E_BLOCK, NU_BLOCK = 210_000.0, 0.3
#: Downward displacement of the sphere's top [mm]: gives a/R = 0.155.
DISPLACEMENT = 0.55
#: Penalty slope of the LINEAR law in units of E [1/mm] (CalculiX recommends 5-50, defaults to 50).
PENALTY = 10.0
#: Relative tolerance of the equilibrium check (contact force against the reaction at the top).
TOLERANCE = 1e-8


def hertz(force: float, radius: float = RADIUS) -> tuple[float, float, float]:
    """Hertz's contact radius, peak pressure and effective modulus E* for a sphere on a half-space.

    Args:
        force: Total normal force F (the whole sphere, not the quarter).
        radius: Sphere radius R.

    Returns:
        ``(a, p0, E*)``.
    """
    e_star = 1.0 / ((1 - NU_SPHERE**2) / E_SPHERE + (1 - NU_BLOCK**2) / E_BLOCK)
    a = (3 * force * radius / (4 * e_star)) ** (1 / 3)
    return a, 3 * force / (2 * math.pi * a**2), e_star


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh (tests)")
    parser.add_argument(
        "--output", type=Path, default=Path("output"), help="output folder (default: output/)"
    )
    parser.add_argument("--cell-type", choices=("tetrahedron", "hexahedron"), default="tetrahedron")
    parser.add_argument(
        "--displacement",
        type=float,
        default=DISPLACEMENT,
        help=f"downward displacement of the sphere top [mm] (default {DISPLACEMENT})",
    )
    parser.add_argument(
        "--penalty",
        type=float,
        default=PENALTY,
        help=f"penalty slope K of the LINEAR law in units of E per mm "
        f"(default {PENALTY:g}; CalculiX's default is 50)",
    )
    parser.add_argument(
        "--increments", type=int, default=8, help="number of increments (default 8)"
    )
    parser.add_argument(
        "--ccx-pairing",
        action="store_true",
        help="start the face search at the nearest centroid like CalculiX",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser.parse_args(argv)


# %%
# The analysis
# ------------
# The quarter model of :mod:`dolfinx_ntf.meshes.hertz` with symmetry conditions, the sphere's
# top pushed down by a prescribed displacement growing as ``t^2`` in equal increments; the
# sphere's curved surface is the slave, the block top the master.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (Hertz values, computed values, relative errors, timings)."""
    args = _parse(argv)
    if args.increments < 1 or not args.penalty > 0:
        raise ValueError(
            f"need --increments >= 1 and --penalty > 0, got {args.increments} and {args.penalty}"
        )
    comm = MPI.COMM_WORLD
    start = time.perf_counter()

    # --- Mesh ------------------------------------------------------------------------------------
    # Quarter hemisphere on a quarter block, refined around the contact point; sizes are multiples
    # of R (dolfinx_ntf.meshes.hertz).
    sizes = {key: value * RADIUS for key, value in geometry.COARSE.items()} if args.coarse else {}
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        geometry.build_hertz, comm, radius=RADIUS, cell_type=args.cell_type, **sizes
    )

    # --- Bulk problem ----------------------------------------------------------------------------
    # Small-strain elasticity (Hertz's theory is linear too), one material per body.
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    F = ufl.inner(small_strain_stress(u, E_BLOCK, NU_BLOCK), ufl.grad(v)) * dx(
        geometry.BLOCK
    ) + ufl.inner(small_strain_stress(u, E_SPHERE, NU_SPHERE), ufl.grad(v)) * dx(geometry.SPHERE)

    # Block bottom clamped, symmetry planes of both bodies: u_x = 0 on x = 0, u_y = 0 on y = 0. The
    # sphere's flat top moves down (u_x, u_y free). A prescribed displacement rather than a force:
    # under a force the sphere would be held by contact springs alone, and a Newton iterate that
    # opens them leaves it floating.
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, facet_tags.find(geometry.BLOCK_BOTTOM))
    Vz, _ = compat.component_space(V, 2)
    top_uz = dolfinx.fem.Function(Vz)
    top = dolfinx.fem.locate_dofs_topological(
        (V.sub(2), Vz), 2, facet_tags.find(geometry.SPHERE_TOP)
    )
    top_bc = dolfinx.fem.dirichletbc(top_uz, top, V.sub(2))
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), bottom, V),
        component_bc(V, 0, facet_tags.find(geometry.SYMMETRY_X)),
        component_bc(V, 1, facet_tags.find(geometry.SYMMETRY_Y)),
        top_bc,
    ]

    # --- Contact ----------------------------------------------------------------------------------
    # LINEAR law with K = 10 E instead of CalculiX's default 50 E (both within CalculiX's advice of
    # 5-50 E). Nodes entering the contact during an increment are paired only after they penetrate;
    # with K = 50 E their first spring forces are large enough to distort the faces under them and
    # Newton diverges (cutbacks on the default mesh, failures on the coarse one; try --penalty 50).
    # The search starts at each node's current face (beyond CalculiX): nodes pressed into the
    # corners of the faceted master do not hop between faces at every re-pairing.
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E_BLOCK, slope=args.penalty * E_BLOCK)
    pair = ntf.ContactPair(
        slave=ntf.FacetSurface(facet_tags, geometry.SPHERE_CONTACT),
        master=ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP),
        interaction=ntf.SurfaceInteraction(law),
        name="hertz",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs, walk_from_previous_face=not args.ccx_pairing)
    solver = ntf.ContactNewtonSolver(comm, problem)
    if not args.quiet:
        ntf.log_progress()

    # --- Static step ------------------------------------------------------------------------------
    # The displacement follows t^2: the contact radius (a ~ sqrt(displacement)) then grows by about
    # the same amount in each of the equal increments, so that few new nodes enter per increment.
    args.output.mkdir(parents=True, exist_ok=True)
    xdmf = args.output / "hertz_sphere.xdmf"
    iterations: list[int] = []
    with ntf.ContactWriter(problem, xdmf) as writer:
        writer.write(0.0)

        def record(result: ntf.IncrementResult) -> None:
            iterations.append(result.iterations)
            writer.write(result.time)

        def set_load(t: float) -> None:
            top_uz.x.array[:] = -(t**2) * args.displacement

        step = ntf.StaticStep(
            set_load,
            initial_increment=1.0 / args.increments,
            max_increment=1.0 / args.increments,
            on_increment=record,
        )
        solve_start = time.perf_counter()
        step.run(solver, u)
        solve_time = time.perf_counter() - solve_start

    # --- Compare with Hertz -----------------------------------------------------------------------
    # Every slave node takes part, with zero pressure where it has no spring; radii are measured in
    # the reference configuration, like Hertz's (linear) theory does.
    # The total force is the contact force of the quarter times 4; it must equal the reaction at
    # the sphere's top (the support pushes the sphere down: a negative z reaction) to the solver
    # tolerance. Hertz's radius and pressure follow from it.
    force = 4 * float(ntf.contact_force(problem)[2])
    reaction = -4 * float(ntf.reaction(problem, dofs=top_bc)[2])
    a_hertz, p0_hertz, _ = hertz(force)
    slave_nodes = problem.states[0].slave.nodes
    reference = V.tabulate_dof_coordinates()[slave_nodes]
    fields = ntf.ContactFields(problem)
    pressure, _, status = fields.at_nodes(slave_nodes)
    deformed = _deformed_faces(problem, fields, facet_tags)
    closed = status > 0
    r_all = np.concatenate(comm.allgather(np.hypot(reference[:, 0], reference[:, 1])))
    p_all = np.concatenate(comm.allgather(pressure))
    closed = np.concatenate(comm.allgather(closed))
    a_fit, p0_fit = measures.fit_hertz_profile(r_all, p_all, a_hertz, p0_hertz)
    r_closed, r_open = r_all[closed].max(), _first_open_radius(r_all, closed)
    p_max = float(p_all.max())
    # CalculiX freezes the pairing after Newton iteration 8, so an increment can converge with
    # slave nodes that penetrate the master without a spring; count them (there should be none).
    unpaired, unpaired_depth = _unpaired_penetrations(problem)
    summary = {
        "dofs": V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
        "increments": len(iterations),
        "iterations": iterations,
        "springs": problem.total_springs,
        "displacement": args.displacement,
        "penalty": args.penalty,
        "force": force,
        "reaction": reaction,
        "equilibrium_error": abs(reaction / force - 1),
        "fit_force": 2 / 3 * math.pi * a_fit**2 * p0_fit,
        "a_hertz": a_hertz,
        "a_fit": a_fit,
        "a_last_closed": r_closed,
        "a_first_open": r_open,
        "p0_hertz": p0_hertz,
        "p0_fit": p0_fit,
        "p_max": p_max,
        "unpaired_penetrations": unpaired,
        "unpaired_depth": unpaired_depth,
        "solve_time": solve_time,
        "xdmf": str(xdmf),
    }
    summary["fit_force_error"] = summary["fit_force"] / force - 1
    summary["a_error"] = a_fit / a_hertz - 1
    summary["p0_error"] = p0_fit / p0_hertz - 1
    summary["p_max_error"] = p_max / p0_hertz - 1
    summary["passed"] = summary["equilibrium_error"] <= TOLERANCE and unpaired == 0
    if comm.rank == 0:
        summary["png"] = str(_plot(args.output / "hertz_pressure.png", r_all, p_all, summary))
        summary["deformed_png"] = str(
            _plot_deformed(args.output / "hertz_deformed.png", deformed, summary)
        )
    summary["time"] = time.perf_counter() - start
    if comm.rank == 0:
        _print_report(summary)
    return summary


# %%
# Checks, fit and figures
# -----------------------
# Slave nodes inside the master without a spring are counted (CalculiX's pairing schedule can leave
# some after Newton iteration 8); Hertz's profile is fitted to the nodal pressures. The first
# figure shows the deformed mesh at true scale: the faces of the symmetry plane y = 0 (a section
# through the contact centre) with the slave nodes coloured by the recovered contact pressure, and
# the sphere's deformed contact surface in plan view, coloured the same way. The second one
# shows the nodal pressures against the radius beside Hertz's curve.


def _unpaired_penetrations(problem: ntf.ContactProblem) -> tuple[int, float]:
    """Slave nodes below the master surface that have no spring: their number and largest depth.

    Searched like a pairing but with a generous walk tolerance (5 % of sqrt(A_p) instead of 0.1 %),
    so that nodes just outside the search prisms of the master's boundary edges are caught too.
    """
    state = problem.states[0]
    coords = problem.current_coordinates()
    slave = state.slave
    areas = spring_areas(slave.faces.face_type, slave.faces.faces, coords, slave.nodes)
    points = coords[slave.nodes]
    state.master.update(coords)
    face = state.master.locate(points, 0.05 * np.sqrt(areas))
    found = np.flatnonzero(face >= 0)
    faces = state.master_faces.faces[face[found]]
    gap = evaluate_springs(
        state.master_faces.face_type,
        coords[faces],
        points[found],
        areas[found],
        state.pair.interaction.law,
        tangent=False,
    ).gap
    paired = np.zeros(slave.nodes.size, dtype=bool)
    paired[state.spring_slave] = True
    depth = -gap[~paired[found] & (gap < -1e-8 * RADIUS)]
    comm = problem.u.function_space.mesh.comm
    count = comm.allreduce(int(depth.size), op=MPI.SUM)
    return count, comm.allreduce(float(depth.max(initial=0.0)), op=MPI.MAX)


def _first_open_radius(r: np.ndarray, closed: np.ndarray) -> float:
    """Smallest radius of an open slave node beyond the closed region (nan if none)."""
    outside = ~closed & (r > r[closed].max())
    return float(r[outside].min()) if outside.any() else math.nan


def _plot(path: Path, r: np.ndarray, p: np.ndarray, summary: dict) -> Path:
    """Nodal contact pressure against radius beside Hertz's profile and the fitted one."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    a, p0 = summary["a_hertz"], summary["p0_hertz"]
    rr = np.linspace(0, 1.5 * a, 400)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    near = r < 1.5 * a
    ax.plot(r[near], p[near], "o", ms=3, label="dolfinx_ntf nodal pressure F_N/A")
    ax.plot(rr, p0 * np.sqrt(np.clip(1 - (rr / a) ** 2, 0, None)), "k-", label="Hertz")
    ax.plot(
        rr,
        summary["p0_fit"] * np.sqrt(np.clip(1 - (rr / summary["a_fit"]) ** 2, 0, None)),
        "r--",
        label=f"fit: a {summary['a_error']:+.1%}, p0 {summary['p0_error']:+.1%}",
    )
    ax.set_xlabel("radius r [mm]")
    ax.set_ylabel("contact pressure [MPa]")
    ax.set_title(
        f"Hertz: sphere R = {RADIUS:g} mm on a block, "
        f"F = {summary['force'] / 1e3:.1f} kN, {summary['dofs']} dofs"
    )
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _deformed_faces(
    problem: ntf.ContactProblem, fields: ntf.ContactFields, facet_tags: typing.Any
) -> dict[str, np.ndarray]:
    """Deformed faces of the section y = 0 and of the slave surface, gathered on rank 0.

    Returns (rank 0; empty arrays elsewhere) ``section_sphere`` and ``section_block``, the corner
    coordinates X + u of the symmetry-plane faces of each body, ``slave`` those of the slave faces
    with ``slave_reference`` (X) and ``slave_pressure`` (the recovered pressure p_h at the corners).
    """
    V = problem.u.function_space
    X = reference_coordinates(V)
    x = X + problem.u.x.array.reshape(-1, 3)
    section = boundary_faces(V, facet_tags.find(geometry.SYMMETRY_Y), what="section y = 0").faces
    sphere = X[section].mean(axis=1)[:, 2] > 0  # the sphere is above z = 0, the block below
    slave_faces = problem.states[0].slave.faces
    slave = slave_faces.faces[slave_faces.facets >= 0]  # -1: a face of another process
    local = {
        "section_sphere": x[section[sphere]],
        "section_block": x[section[~sphere]],
        "slave": x[slave],
        "slave_reference": X[slave],
        "slave_pressure": fields.recovery.at_nodes(slave.ravel()).reshape(slave.shape),
    }
    comm = V.mesh.comm
    gathered = {}
    for key, value in local.items():
        parts = comm.gather(value, root=0)
        gathered[key] = np.concatenate(parts) if comm.rank == 0 else value[:0]
    return gathered


def _plot_deformed(path: Path, faces: dict[str, np.ndarray], summary: dict) -> Path:
    """The deformed section y = 0 and the deformed contact surface, coloured by p_h (true scale)."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    a = summary["a_hertz"]
    p_max = max(float(faces["slave_pressure"].max()), summary["p0_hertz"])
    norm = mpl.colors.Normalize(0.0, p_max)
    cmap = plt.get_cmap("viridis")
    fig = plt.figure(figsize=(10, 4.4))

    # Section y = 0 (x, z): the mesh of both bodies, the slave nodes coloured by p_h.
    ax = fig.add_subplot(1, 2, 1)
    for key, colour in (("section_block", "0.85"), ("section_sphere", "#c6dbef")):
        ax.add_collection(
            PolyCollection(
                faces[key][:, :, [0, 2]], facecolors=colour, edgecolors="0.35", linewidths=0.4
            )
        )
    ref, pts = faces["slave_reference"].reshape(-1, 3), faces["slave"].reshape(-1, 3)
    on_section = np.abs(ref[:, 1]) < 1e-9 * RADIUS
    p = faces["slave_pressure"].ravel()[on_section]
    dots = ax.scatter(
        pts[on_section, 0], pts[on_section, 2], c=p, cmap=cmap, norm=norm, s=18, zorder=3
    )
    ax.axvline(a, color="k", ls="--", lw=0.8)
    ax.annotate(f"Hertz a = {a:.2f} mm", (a, 1.25 * a), xytext=(4, 0), textcoords="offset points")
    ax.set_xlim(0.0, 3.0 * a)
    ax.set_ylim(-1.5 * a, 1.5 * a)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_title("deformed mesh, section y = 0 (true scale)", fontsize=10)

    # The sphere's deformed contact surface in plan view (its x, y), faces coloured by the mean
    # p_h of their corners, with Hertz's contact circle.
    ax2 = fig.add_subplot(1, 2, 2)
    ref = faces["slave_reference"]
    near = (np.hypot(ref[..., 0], ref[..., 1]) < 3.0 * a).all(axis=1)
    ax2.add_collection(
        PolyCollection(
            faces["slave"][near][:, :, :2],
            facecolors=cmap(norm(faces["slave_pressure"][near].mean(axis=1))),
            edgecolors="0.3",
            linewidths=0.4,
        )
    )
    angle = np.linspace(0.0, 0.5 * np.pi, 100)
    ax2.plot(a * np.cos(angle), a * np.sin(angle), "w--", lw=1.2, label="Hertz r = a")
    ax2.set_xlim(0.0, 2.0 * a)
    ax2.set_ylim(0.0, 2.0 * a)
    ax2.set_aspect("equal")
    ax2.set_xlabel("x [mm]")
    ax2.set_ylabel("y [mm]")
    ax2.legend(loc="upper right")
    ax2.set_title("deformed contact surface of the sphere (x, y)", fontsize=10)

    fig.colorbar(
        dots, ax=[ax, ax2], shrink=0.9, pad=0.02, label="recovered contact pressure p_h [MPa]"
    )
    fig.suptitle(
        f"Hertz sphere: F = {summary['force'] / 1e3:.1f} kN, displacement "
        f"{summary['displacement']:g} mm, {summary['dofs']} dofs"
    )
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def _print_report(s: dict) -> None:
    """Final report: computed values against Hertz's, then the checks."""
    print()
    print(
        f"Hertz sphere: {s['dofs']} dofs, {s['increments']} increments (Newton iterations "
        f"{s['iterations']}), {s['springs']} springs, solve {s['solve_time']:.1f} s, "
        f"total {s['time']:.1f} s"
    )
    print(
        f"Total contact force F = 4 sum F_z = {s['force']:.6g} N at a displacement of "
        f"{s['displacement']:g} mm; reaction at the sphere top {s['reaction']:.6g} N "
        f"(relative difference {s['equilibrium_error']:.1e})"
    )
    print(f"{'quantity':<34} {'computed':>12} {'Hertz':>12} {'error':>9}")
    rows = [
        ("force of the fitted profile [N]", s["fit_force"], s["force"], s["fit_force_error"]),
        ("contact radius, fit [mm]", s["a_fit"], s["a_hertz"], s["a_error"]),
        ("peak pressure, fit [MPa]", s["p0_fit"], s["p0_hertz"], s["p0_error"]),
        ("peak nodal pressure [MPa]", s["p_max"], s["p0_hertz"], s["p_max_error"]),
    ]
    for name, computed, exact, error in rows:
        print(f"{name:<34} {computed:>12.6g} {exact:>12.6g} {error:>+9.2%}")
    print(
        f"last closed node at r = {s['a_last_closed']:.4g} mm, first open one at r = "
        f"{s['a_first_open']:.4g} mm (Hertz a = {s['a_hertz']:.4g} mm)"
    )
    if s["unpaired_penetrations"]:
        print(
            f"WARNING: {s['unpaired_penetrations']} slave node(s) penetrate the master without a "
            f"spring (deepest {s['unpaired_depth']:.3e} mm)"
        )
    verdict = "PASSED" if s["passed"] else "FAILED"
    print(
        f"Checks (equilibrium to {TOLERANCE:.0e}, no unpaired penetration): {verdict}. "
        f"Results: {s['xdmf']}, {s.get('deformed_png')}, {s.get('png')}"
    )


# %%
# Run
# ---
# The build of this page ran ``demos/hertz_sphere.py --coarse`` (about four elements across the
# contact radius): the Hertz values for the computed force, the computed ones and their relative
# errors, then the figures: the deformed mesh coloured by the contact pressure, and the pressure
# against the radius beside Hertz's profile.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
