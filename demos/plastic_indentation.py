"""Plastic indentation: a rigid ball pressed into a metal block and withdrawn leaves a dent.

A rigid sphere of radius R = 10 mm is pressed 0.3 mm into an aluminium block (J2 plasticity with
linear isotropic hardening, ``J2Plasticity``: sigma_y = 150 + 700 alpha MPa), then withdrawn to its
start. The block's top is the slave surface, the sphere a rigid master (``RigidSphere``) moved by
the step's load callback; frictionless node-to-face springs with CalculiX's LINEAR law. A quarter of
the block is modelled (8 x 8 x 8 mm, symmetry planes x = 0 and y = 0, bottom clamped) on hexahedra
graded towards the contact. The same indentation of an elastic block (the yield stress out of
reach) is the control.

The demo checks, and prints:

- every increment, the contact force equals the clamped bottom's reaction (to 1e-8 of the peak);
- the block yields under the ball;
- after the withdrawal the springs are open, the contact force is zero, and a dent remains: the
  top centre stays below its start, by less than the indentation depth (the elastic part springs
  back);
- the elastic control comes back to its start (dent below 1e-8 of the depth) and follows Hertz's
  ``F = 4/3 E* sqrt(R) d^(3/2)`` to within 10 % at the first depth, departing from it (stiffer)
  as the contact grows against the clamped block's thickness;
- the plastic block needs less force than the elastic one at every depth, and the work of the
  force over the cycle (loading minus unloading) is positive: energy dissipated in the dent.

It saves ``output/plastic_indentation.png`` (force against depth for the plastic block and the
elastic control beside Hertz's curve, and the surface profile at the peak and after unloading) and
``output/plastic_indentation.xdmf`` (displacement and contact fields, per increment).

Not checked, reported: the unloading is not purely elastic. While the ball withdraws, a few
hundred of the quadrature points under the dent yield again (reverse plasticity: the residual
stresses of a deep indentation exceed the yield stress in the other direction); the largest
equivalent plastic strain does not change, the plastic strains change by less than 1 % of it.

Run it with::

    .venv/bin/python demos/plastic_indentation.py            # ~28k dofs, about 5 minutes
    .venv/bin/python demos/plastic_indentation.py --coarse   # ~4k dofs (tests), about 15 s
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
import time
import typing
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc

__all__ = ["hertz_force", "main"]

# %%
# Parameters
# ----------
# Units mm, N, MPa. The sphere touches the block's top at the origin at the start.

RADIUS = 10.0
DEPTH = 0.2
#: The first part of the withdrawal, in as many increments as the loading (the ball leaves the
#: dent within it: the elastic spring-back is about a tenth of the depth); the rest in two.
SPRING_BACK = 0.2
E, NU = 70_000.0, 0.3
YIELD_STRESS, HARDENING_MODULUS = 150.0, 700.0
#: Quarter block [0, L] x [0, L] x [-L, 0].
SIZE = 8.0
#: Grading of the mesh: node coordinates L (b s + (1 - b) s^3) for s uniform in [0, 1], elements
#: b L / n at the axis and the top, 4 - 3b times larger at the far faces.
GRADING = 0.25
#: Facet tags.
TOP, BOTTOM, SYMMETRY_X, SYMMETRY_Y = 1, 2, 3, 4
#: Relative tolerance of the equilibrium checks and of the elastic control's return.
TOLERANCE = 1e-8
#: Hertz's force against the elastic control's at the first depth.
HERTZ_TOLERANCE = 0.10


def hertz_force(depth: float | np.ndarray) -> float | np.ndarray:
    """Hertz's force of a rigid sphere pressed ``depth`` into an elastic half-space.

    Args:
        depth: The indentation depth d (the approach of the sphere and the far field).
    """
    e_star = E / (1 - NU**2)
    return 4.0 / 3.0 * e_star * math.sqrt(RADIUS) * np.asarray(depth) ** 1.5


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
# Mesh and problem
# ----------------
# A box of hexahedra on the unit cube, its coordinates mapped to ``L (b s + (1 - b) s^3)`` (finer
# towards the axis and the top), its boundary facets tagged.


def _block(comm: MPI.Comm, divisions: int) -> tuple[dolfinx.mesh.Mesh, typing.Any]:
    """The graded quarter block and its facet tags (TOP, BOTTOM, SYMMETRY_X, SYMMETRY_Y)."""
    mesh = dolfinx.mesh.create_box(
        comm,
        [np.zeros(3), np.ones(3)],
        [divisions, divisions, divisions],
        dolfinx.mesh.CellType.hexahedron,
    )
    x = mesh.geometry.x

    def graded(s: np.ndarray) -> np.ndarray:
        return SIZE * (GRADING * s + (1 - GRADING) * s**3)

    x[:, :2] = graded(x[:, :2])
    x[:, 2] = -graded(1.0 - x[:, 2])
    planes = {
        TOP: lambda p: np.isclose(p[2], 0.0),
        BOTTOM: lambda p: np.isclose(p[2], -SIZE),
        SYMMETRY_X: lambda p: np.isclose(p[0], 0.0),
        SYMMETRY_Y: lambda p: np.isclose(p[1], 0.0),
    }
    mesh.topology.create_connectivity(2, 3)
    found = [(tag, dolfinx.mesh.locate_entities_boundary(mesh, 2, f)) for tag, f in planes.items()]
    entities = np.concatenate([facets for _, facets in found]).astype(np.int32)
    values = np.concatenate([np.full(f.size, tag, dtype=np.int32) for tag, f in found])
    order = np.argsort(entities)
    return mesh, dolfinx.mesh.meshtags(mesh, 2, entities[order], values[order])


def _indent(
    comm: MPI.Comm,
    divisions: int,
    increments: int,
    hardening: ntf.IsotropicHardening,
    xdmf: Path | None,
    quiet: bool,
) -> dict:
    """Press the ball DEPTH into the block and withdraw it; per increment the forces and state."""
    mesh, facet_tags = _block(comm, divisions)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    material = ntf.J2Plasticity(u, E, NU, hardening)
    bottom = facet_tags.find(BOTTOM)
    bcs = [
        dolfinx.fem.dirichletbc(
            np.zeros(3, dtype=PETSc.ScalarType),
            dolfinx.fem.locate_dofs_topological(V, 2, bottom),
            V,
        ),
        component_bc(V, 0, facet_tags.find(SYMMETRY_X)),
        component_bc(V, 1, facet_tags.find(SYMMETRY_Y)),
    ]
    ball = ntf.RigidSphere((0.0, 0.0, RADIUS), RADIUS)
    pair = ntf.ContactPair(
        slave=ntf.FacetSurface(facet_tags, TOP),
        master=ball,
        interaction=ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E)),
        name="ball",
    )
    problem = ntf.ContactProblem(
        material.residual(v),
        u,
        [pair],
        bcs,
        J=material.jacobian(ufl.TrialFunction(V), v),
        history=[material],
    )
    solver = ntf.ContactNewtonSolver(comm, problem)
    if not quiet:
        ntf.log_progress()

    # The top centre (the origin) and the top nodes along y = 0 (the surface profile).
    x = V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local]
    centre = np.flatnonzero(np.linalg.norm(x, axis=1) < 1e-9)
    line = np.flatnonzero(np.isclose(x[:, 2], 0.0) & np.isclose(x[:, 1], 0.0))

    def dent() -> float:
        values = u.x.array.reshape(-1, 3)[centre, 2]
        return -comm.allreduce(float(values.sum()), op=MPI.SUM)  # one owner has the node

    def profile() -> tuple[np.ndarray, np.ndarray]:
        r = np.concatenate(comm.allgather(x[line, 0]))
        w = np.concatenate(comm.allgather(u.x.array.reshape(-1, 3)[line, 2]))
        order = np.argsort(r)
        return r[order], w[order]

    rows: list[dict] = []
    writer = ntf.ContactWriter(problem, xdmf) if xdmf is not None else None

    def record(phase: str) -> typing.Callable[[ntf.IncrementResult], None]:
        def on_increment(result: ntf.IncrementResult) -> None:
            rows.append(
                {
                    "phase": phase,
                    "depth": -float(ball.translation(result.time)[2]),
                    "force": -4 * float(ntf.contact_force(problem)[2]),  # whole ball, pressing
                    "reaction": 4 * float(ntf.reaction(problem, bottom)[2]),
                    "springs": comm.allreduce(int(problem.num_springs), op=MPI.SUM),
                    "yielding": comm.allreduce(int(material.yielding.sum()), op=MPI.SUM),
                    "alpha_max": comm.allreduce(
                        float(material.equivalent_plastic_strain.max(initial=0.0)), op=MPI.MAX
                    ),
                    "dent": dent(),
                    "iterations": result.iterations,
                }
            )
            if writer is not None:
                writer.write(len(rows))

        return on_increment

    start = time.perf_counter()
    # A first increment with the ball at rest, touching the block at the origin: the analysis's
    # first pairing records penetrations as an initial overlap, which CalculiX's rule ramps away
    # in that increment (docs/method.md §11.6); with the ball at rest there is none to record.
    ntf.StaticStep(lambda t: None, initial_increment=1.0, fixed=True).run(solver, u)
    phases = (
        ("load", lambda t: DEPTH * t, increments),
        ("unload", lambda t: DEPTH * (1 - SPRING_BACK * t), increments),
        ("unload", lambda t: DEPTH * (1 - SPRING_BACK) * (1 - t), 2),
    )
    for phase, depth_at, count in phases:
        # The ball's motion c(t) of this step: the pairing at an increment's start sees the ball
        # where the increment takes it (a load callback moving ``offset`` would come after it).
        ball.motion = lambda t, f=depth_at: (0.0, 0.0, -f(t))
        step = ntf.StaticStep(
            lambda t: None,
            initial_increment=1.0 / count,
            max_increment=1.0 / count,
            on_increment=record(phase),
        )
        step.run(solver, u)
        if phase == "load":
            peak_profile = profile()
            alpha_peak = material.equivalent_plastic_strain.copy()
    solve_time = time.perf_counter() - start
    if writer is not None:
        writer.close()
    alpha_changed = comm.allreduce(
        float(np.max(np.abs(material.equivalent_plastic_strain - alpha_peak), initial=0.0)),
        op=MPI.MAX,
    )
    result = {
        "dofs": V.dofmap.index_map.size_global * 3,
        "rows": rows,
        "peak_profile": peak_profile,
        "final_profile": profile(),
        "alpha_changed_unloading": alpha_changed,
        "solve_time": solve_time,
    }
    solver.destroy()
    problem.destroy()
    return result


# %%
# The analysis
# ------------
# The plastic block and the elastic control, each loaded and unloaded in equal increments.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (forces, dents, plastic strains, checks, timings)."""
    args = _parse(argv)
    comm = MPI.COMM_WORLD
    start = time.perf_counter()
    divisions, increments = (10, 4) if args.coarse else (20, 8)
    args.output.mkdir(parents=True, exist_ok=True)
    xdmf = args.output / "plastic_indentation.xdmf"
    plastic = _indent(
        comm,
        divisions,
        increments,
        ntf.IsotropicHardening.linear(YIELD_STRESS, HARDENING_MODULUS),
        xdmf,
        args.quiet,
    )
    elastic = _indent(
        comm, divisions, increments, ntf.IsotropicHardening.linear(1e12, 0.0), None, True
    )
    rows, rows_el = plastic["rows"], elastic["rows"]
    peak = max(r["force"] for r in rows)
    loading = [r for r in rows if r["phase"] == "load"]
    unloading = [r for r in rows if r["phase"] == "unload"]
    loading_el = [r for r in rows_el if r["phase"] == "load"]
    summary = {
        "dofs": plastic["dofs"],
        "increments": len(rows),
        "iterations": [r["iterations"] for r in rows],
        "depth": [r["depth"] for r in rows],
        "force": [r["force"] for r in rows],
        "force_elastic": [r["force"] for r in rows_el],
        "peak_force": peak,
        "peak_force_elastic": loading_el[-1]["force"],
        "hertz_peak": float(hertz_force(DEPTH)),
        "hertz_errors": [r["force"] / float(hertz_force(r["depth"])) - 1 for r in loading_el],
        "equilibrium_error": max(abs(r["force"] - r["reaction"]) for r in rows + rows_el) / peak,
        "alpha_max": loading[-1]["alpha_max"],
        "yielding_at_peak": loading[-1]["yielding"],
        "yielding_unloading": max(r["yielding"] for r in unloading),
        "alpha_changed_unloading": plastic["alpha_changed_unloading"],
        "final_springs": unloading[-1]["springs"],
        "final_force": unloading[-1]["force"],
        "dent_at_peak": loading[-1]["dent"],
        "residual_dent": unloading[-1]["dent"],
        "elastic_residual_dent": rows_el[-1]["dent"],
        "elastic_final_force": rows_el[-1]["force"],
        "solve_time": plastic["solve_time"] + elastic["solve_time"],
        "xdmf": str(xdmf),
    }
    summary["hertz_error"] = summary["hertz_errors"][0]
    summary["softer_than_elastic"] = all(
        p["force"] < e["force"] for p, e in zip(loading, loading_el)
    )
    # Work of the ball's force over the cycle (trapezoidal rule, from 0 to the peak and back).
    path = [(0.0, 0.0)] + [(r["depth"], r["force"]) for r in rows]
    summary["cycle_work"] = sum(
        0.5 * (f0 + f1) * (d1 - d0) for (d0, f0), (d1, f1) in itertools.pairwise(path)
    )
    summary["passed"] = bool(
        summary["equilibrium_error"] <= TOLERANCE
        and summary["alpha_max"] > 0
        and summary["final_springs"] == 0
        and summary["final_force"] == 0.0
        and 0 < summary["residual_dent"] < summary["dent_at_peak"]
        and abs(summary["elastic_residual_dent"]) <= TOLERANCE * DEPTH
        and abs(summary["hertz_error"]) <= HERTZ_TOLERANCE
        and all(a < b for a, b in itertools.pairwise(summary["hertz_errors"]))
        and summary["softer_than_elastic"]
        and summary["cycle_work"] > 0
    )
    if comm.rank == 0:
        summary["png"] = str(
            _plot(args.output / "plastic_indentation.png", summary, plastic, elastic)
        )
    summary["time"] = time.perf_counter() - start
    if comm.rank == 0:
        _print_report(summary, rows)
    return summary


# %%
# Figure and report
# -----------------
# Force against depth (the plastic block's loop, the elastic control, Hertz) and the top surface
# along y = 0 at the peak and after unloading.


def _plot(path: Path, s: dict, plastic: dict, elastic: dict) -> Path:
    """Force-depth curves and the surface profiles."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.5))
    depth = [0.0] + s["depth"]
    ax.plot(depth, [0.0] + s["force"], "o-", ms=4, label="plastic block: load and unload")
    ax.plot(depth, [0.0] + s["force_elastic"], "s--", ms=4, label="elastic control")
    d = np.linspace(0, DEPTH, 100)
    ax.plot(d, hertz_force(d), "k:", label="Hertz (elastic half-space)")
    ax.set_xlabel("ball displacement d [mm]")
    ax.set_ylabel("force F [N]")
    ax.set_title(f"Rigid ball R = {RADIUS:g} mm into a block, {s['dofs']} dofs (quarter)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    for label, (r, w), style in (
        ("plastic, at the peak", plastic["peak_profile"], "C0-"),
        ("plastic, unloaded", plastic["final_profile"], "C0--"),
        ("elastic, at the peak", elastic["peak_profile"], "C1-"),
        ("elastic, unloaded", elastic["final_profile"], "C1--"),
    ):
        bx.plot(r, w, style, marker=".", label=label)
    bx.set_xlim(0, 0.5 * SIZE)
    bx.set_xlabel("distance from the axis x [mm] (y = 0)")
    bx.set_ylabel("top surface displacement u_z [mm]")
    bx.set_title(f"residual dent {s['residual_dent']:.4f} mm of {DEPTH:g} mm")
    bx.grid(True, alpha=0.3)
    bx.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _print_report(s: dict, rows: list[dict]) -> None:
    """Per increment depth, force, springs, yielding points; then the checks."""
    print()
    print(
        f"Plastic indentation: {s['dofs']} dofs, {s['increments']} increments per block, solve "
        f"{s['solve_time']:.1f} s, total {s['time']:.1f} s"
    )
    print(
        f"{'phase':<7} {'d [mm]':>7} {'F [N]':>12} {'elastic F [N]':>14} {'springs':>8} "
        f"{'yielding':>9} {'max alpha':>10} {'dent [mm]':>10} {'Newton':>7}"
    )
    for r, f_el in zip(rows, s["force_elastic"]):
        print(
            f"{r['phase']:<7} {r['depth']:>7.4f} {r['force']:>12.3f} {f_el:>14.3f} "
            f"{r['springs']:>8} {r['yielding']:>9} {r['alpha_max']:>10.4g} {r['dent']:>10.5f} "
            f"{r['iterations']:>7}"
        )
    print(
        f"Equilibrium (contact force = bottom reaction) to {s['equilibrium_error']:.1e} of the "
        f"peak; unloading: {s['yielding_unloading']} yielding points, plastic strains changed by "
        f"{s['alpha_changed_unloading']:.1e}"
    )
    print(
        f"Residual dent {s['residual_dent']:.5f} mm (at the peak {s['dent_at_peak']:.5f} mm); "
        f"elastic control {s['elastic_residual_dent']:.1e} mm; work over the cycle "
        f"{s['cycle_work']:.3f} N mm"
    )
    print(
        f"Elastic control at the peak {s['peak_force_elastic']:.1f} N, Hertz "
        f"{s['hertz_peak']:.1f} N; elastic over Hertz per depth "
        + ", ".join(f"{e:+.1%}" for e in s["hertz_errors"])
        + f"; plastic peak {s['peak_force']:.1f} N"
    )
    verdict = "PASSED" if s["passed"] else "FAILED"
    print(f"Checks: {verdict}. Results: {s['xdmf']}, {s.get('png')}")


# %%
# Run
# ---
# The build of this page ran ``demos/plastic_indentation.py --coarse``: the table of the
# increments of the plastic block (with the elastic control's force), the checks, the figure.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
