"""A block pressed onto a base and dragged, in plane strain: stick, slip and a friction change.

The 2D counterpart of ``sliding_block.py``: the cross-section of a steel block (40 x 10 mm) on an
aluminium base (100 x 50 mm, clamped at its bottom), plane strain per unit thickness, meshed with
triangles. A pressure on the block top presses it onto the base; then the top is dragged along x
by a prescribed displacement: first a little (the block sticks: ``F_x < mu F_y``; only nodes near
its edges, where the press already made the tractions peak, may slip), then far (every spring
slips, ``|tau| = mu p``), then further after ``ChangeFriction`` raised mu. Coulomb
friction with a tangential penalty (``Friction(mu, lambda)``, ``lambda = K/100``) acts between the
block bottom (slave, node-to-segment springs) and the base top (master edges): one tangent
direction, the edge's.

Checks: in every increment each sticking spring is below its limit and each slipping one on it
(``|F_T| = mu F_N`` to 1e-10); after the small drag ``0 < F_x < mu F_y``; at the end of each drag
every spring slips, so the friction force of the whole block is ``mu`` times its normal force:
``sum |F_T| = mu sum F_N`` to round-off, and the horizontal contact force ``F_x`` equals
``mu F_y`` up to the tilt of the base's deformed top (1e-3); the support of the block top takes
``F_x`` (equilibrium to 1e-8). The figure ``output/sliding_block_2d.png`` shows ``F_x / F_y``
against time beside ``mu``, and the shear traction along the block bottom at the end; the fields
go to ``output/sliding_block_2d.xdmf``.

Run it with::

    .venv/bin/python demos/sliding_block_2d.py           # 1.3k dofs, a few seconds
    .venv/bin/python demos/sliding_block_2d.py --coarse  # 186 dofs (tests)
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
from dolfinx_ntf.fem.elasticity import small_strain_stress
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

__all__ = ["build_block_on_base", "main"]

# %%
# Parameters
# ----------
# Units: mm, N, MPa; forces per mm of thickness (plane strain per unit thickness).

BASE_SIZE, BLOCK_SIZE = (100.0, 50.0), (40.0, 10.0)
E_BLOCK, NU_BLOCK = 210_000.0, 0.3  # steel
E_BASE, NU_BASE = 70_000.0, 0.33  # aluminium
PRESSURE = 50.0  # MPa on the block top
MU, MU_LATER = 0.2, 0.3
STICK_DRAG = 2e-3  # mm: small enough that nothing slips
DRAG = 0.03  # mm: every spring slips
#: Relative tolerance of the slip checks (round-off) and of the equilibrium (Newton).
TOLERANCE, EQUILIBRIUM = 1e-10, 1e-8
# Cell and facet tags.
BASE, BLOCK = 1, 2
BASE_BOTTOM, BASE_TOP, BLOCK_BOTTOM, BLOCK_TOP = 11, 12, 13, 14


def build_block_on_base(divisions: int = 1) -> None:
    """Structured triangles: the base ``[0, 100] x [-50, 0]`` and the block on its middle.

    Args:
        divisions: Mesh refinement factor (1: 10 x 5 base and 8 x 2 block elements).
    """
    gmsh.model.add("block_on_base_2d")
    g = gmsh.model.geo
    surfaces, lines = [], []
    (bw, bh), (w, h) = BASE_SIZE, BLOCK_SIZE
    x0 = 0.5 * (bw - w)
    for (xa, ya, xb, yb), (nx, ny) in (
        ((0.0, -bh, bw, 0.0), (10, 5)),
        ((x0, 0.0, x0 + w, h), (8, 2)),
    ):
        p = [
            g.addPoint(xa, ya, 0),
            g.addPoint(xb, ya, 0),
            g.addPoint(xb, yb, 0),
            g.addPoint(xa, yb, 0),
        ]
        edges = [g.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
        surface = g.addPlaneSurface([g.addCurveLoop(edges)])
        for edge, n in zip(edges, (nx, ny, nx, ny)):
            g.mesh.setTransfiniteCurve(edge, n * divisions + 1)
        g.mesh.setTransfiniteSurface(surface)
        surfaces.append(surface)
        lines.append(edges)
    g.synchronize()
    model = gmsh.model
    model.addPhysicalGroup(2, [surfaces[0]], BASE)
    model.addPhysicalGroup(2, [surfaces[1]], BLOCK)
    model.addPhysicalGroup(1, [lines[0][0]], BASE_BOTTOM)
    model.addPhysicalGroup(1, [lines[0][2]], BASE_TOP)
    model.addPhysicalGroup(1, [lines[1][0]], BLOCK_BOTTOM)
    model.addPhysicalGroup(1, [lines[1][2]], BLOCK_TOP)
    model.mesh.generate(2)


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh, fewer increments")
    parser.add_argument("--output", type=Path, default=Path("output"))
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser.parse_args(argv)


# %%
# The analysis
# ------------
# Four :class:`~dolfinx_ntf.AnalysisStep` objects run by :func:`~dolfinx_ntf.run_steps`: press,
# a small drag (stick), a drag to ``DRAG`` (slip) and, after a
# :class:`~dolfinx_ntf.ChangeFriction`, a drag to ``2 DRAG``. After every increment the springs'
# forces are read from :func:`~dolfinx_ntf.contact_results`.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (histories, checks, files)."""
    args = _parse(argv)
    comm = MPI.COMM_WORLD
    start = time.perf_counter()
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        build_block_on_base, comm, gdim=2, divisions=1 if args.coarse else 3
    )

    # --- Bulk: plane-strain small-strain elasticity, pressure on the block top ------------------
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    F = (
        ufl.inner(small_strain_stress(u, E_BASE, NU_BASE), ufl.grad(v)) * dx(BASE)
        + ufl.inner(small_strain_stress(u, E_BLOCK, NU_BLOCK), ufl.grad(v)) * dx(BLOCK)
        + pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(BLOCK_TOP)
    )
    # Base bottom clamped; the block top: x prescribed (the drag), y free (the pressure).
    base = dolfinx.fem.locate_dofs_topological(V, 1, facet_tags.find(BASE_BOTTOM))
    Vx, _ = compat.component_space(V, 0)
    drag = dolfinx.fem.Function(Vx)
    top_x = dolfinx.fem.locate_dofs_topological((V.sub(0), Vx), 1, facet_tags.find(BLOCK_TOP))
    drag_bc = dolfinx.fem.dirichletbc(drag, top_x, V.sub(0))
    bcs = [dolfinx.fem.dirichletbc(np.zeros(2), base, V), drag_bc]

    # --- Contact with friction -------------------------------------------------------------------
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E_BASE)
    stick_slope = law.slope / 100  # CalculiX's advice: lambda about K/100
    pair = ntf.ContactPair(
        ntf.FacetSurface(facet_tags, BLOCK_BOTTOM),
        ntf.FacetSurface(facet_tags, BASE_TOP),
        ntf.SurfaceInteraction(law, ntf.Friction(MU, stick_slope)),
        name="block",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    solver = ntf.ContactNewtonSolver(comm, problem)
    if not args.quiet:
        ntf.log_progress()

    # --- Steps -----------------------------------------------------------------------------------
    args.output.mkdir(parents=True, exist_ok=True)
    xdmf = args.output / "sliding_block_2d.xdmf"
    writer = ntf.ContactWriter(problem, str(xdmf))
    history: dict[str, list] = {k: [] for k in ("time", "ratio", "mu", "sliding", "springs")}
    history["stick_margin"], history["slip_error"], history["coulomb_error"] = [], [], []
    clock = {"total": 0.0, "mu": MU}

    def record(result: ntf.IncrementResult) -> None:
        t = clock["total"] + result.time
        writer.write(t)
        (res,) = ntf.contact_results(problem)
        mu = clock["mu"]
        shear_force = comm.allgather(np.linalg.norm(res.shear, axis=1) * res.area)
        limit = comm.allgather(mu * np.maximum(res.normal_force, 0.0))
        sliding = comm.allgather(res.sliding)
        shear_force, limit, sliding = (np.concatenate(a) for a in (shear_force, limit, sliding))
        scale = limit.max()
        force = ntf.contact_force(problem)  # on the block
        history["time"].append(t)
        history["ratio"].append(float(-force[0] / force[1]))
        history["mu"].append(mu)
        history["sliding"].append(int(sliding.sum()))
        history["springs"].append(int(sliding.size))
        # stick: below the limit (the margin < 0); slip: on it, spring by spring and in all
        history["stick_margin"].append(float(np.max((shear_force - limit)[~sliding], initial=-1)))
        history["slip_error"].append(
            float(np.max(np.abs(shear_force - limit)[sliding], initial=0.0) / scale)
        )
        history["coulomb_error"].append(float(abs(shear_force.sum() / limit.sum() - 1)))

    increments = 4 if args.coarse else 8

    def step(n: int, loads, changes=()) -> ntf.AnalysisStep:
        procedure = ntf.StaticStep(initial_increment=1 / n, fixed=True, on_increment=record)
        return ntf.AnalysisStep(procedure, loads, changes=changes)

    plan = [
        (step(2, [ntf.Load(pressure, PRESSURE)]), MU),
        (step(1, [ntf.Load(drag, STICK_DRAG)]), MU),
        (step(increments, [ntf.Load(drag, DRAG)]), MU),
        (
            step(
                increments,
                [ntf.Load(drag, 2 * DRAG)],
                [ntf.ChangeFriction(pair, ntf.Friction(MU_LATER, stick_slope))],
            ),
            MU_LATER,
        ),
    ]
    ends = []
    for analysis_step, mu in plan:
        clock["mu"] = mu
        ntf.run_steps(solver, [analysis_step])
        clock["total"] += 1.0
        ends.append(len(history["time"]))
    writer.close()

    # --- Checks ----------------------------------------------------------------------------------
    force = ntf.contact_force(problem)
    reaction = ntf.reaction(problem, dofs=drag_bc)
    equilibrium = abs(reaction[0] + force[0]) / abs(force[1])
    (res,) = ntf.contact_results(problem)
    x = np.concatenate(comm.allgather(problem.reference_coordinates[res.node, 0]))
    shear = np.concatenate(comm.allgather(res.shear[:, 0]))
    mu_p = np.concatenate(comm.allgather(MU_LATER * np.maximum(res.pressure, 0.0)))
    last = [e - 1 for e in ends]
    summary = {
        "dofs": 2 * V.dofmap.index_map.size_global,
        "springs": history["springs"][-1],
        "increments": len(history["time"]),
        "stick_sliding": history["sliding"][last[1]],
        "stick_margin": max(history["stick_margin"]),
        "slip_error": max(history["slip_error"]),
        "end_sliding": [history["sliding"][e] for e in last[2:]],
        "coulomb_error": max(history["coulomb_error"][e] for e in last[2:]),
        "ratio_stick": history["ratio"][last[1]],
        "ratio_drag": history["ratio"][last[2]],
        "ratio_mu": history["ratio"][last[3]],
        "equilibrium_error": equilibrium,
        "history": history,
        "xdmf": str(xdmf),
    }
    summary["tilt_error"] = max(
        abs(summary["ratio_drag"] / MU - 1), abs(summary["ratio_mu"] / MU_LATER - 1)
    )
    summary["passed"] = bool(
        summary["stick_margin"] < 0  # every sticking spring below its limit, every increment
        and summary["slip_error"] < TOLERANCE  # every slipping spring on it
        and summary["stick_sliding"] < summary["springs"]
        and 0 < summary["ratio_stick"] < MU
        and summary["end_sliding"] == [summary["springs"]] * 2
        and summary["coulomb_error"] < TOLERANCE
        and summary["tilt_error"] < 1e-3
        and equilibrium < EQUILIBRIUM
    )
    if comm.rank == 0:
        order = np.argsort(x)
        summary["png"] = str(
            _plot(args.output / "sliding_block_2d.png", history, ends, x[order], shear[order],
                  mu_p[order])
        )  # fmt: skip
    summary["time"] = time.perf_counter() - start
    if comm.rank == 0:
        print(
            f"\nSliding block (plane strain): {summary['dofs']} dofs, {summary['increments']} "
            f"increments, {summary['springs']} springs, {summary['time']:.1f} s\n"
            f"F_x / F_y at the end of the small drag, the drag (mu = {MU}) and the drag with "
            f"mu = {MU_LATER}: {summary['ratio_stick']:.4f}, {summary['ratio_drag']:.6f}, "
            f"{summary['ratio_mu']:.6f}\n"
            f"stick: max |F_T| - mu F_N = {summary['stick_margin']:.2g} N/mm (< 0); "
            f"slip: max | |F_T| - mu F_N | / (mu F_N) = {summary['slip_error']:.1e}, "
            f"sum |F_T| / (mu sum F_N) - 1 = {summary['coulomb_error']:.1e}; equilibrium of the "
            f"block {equilibrium:.1e}: {'PASSED' if summary['passed'] else 'FAILED'}"
        )
    return summary


# %%
# Figure
# ------
# Left: the friction coefficient the block sees, ``F_x / F_y``, against the analysis time beside
# ``mu``. Right: the shear traction along the block bottom at the end beside ``mu p``.


def _plot(
    path: Path, history: dict, ends: list[int], x: np.ndarray, shear: np.ndarray, mu_p: np.ndarray
) -> Path:
    """``F_x / F_y`` against time beside mu, and the final shear traction along the bottom."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    t = np.array(history["time"])
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.2))
    left.plot(t, history["ratio"], "o-", ms=3, label="F_x / F_y (contact force on the block)")
    left.step(t, history["mu"], "k--", where="pre", label="mu")
    for end in ends[:-1]:
        left.axvline(t[end - 1], color="0.8", lw=0.8)
    left.set_xlabel("time (1 press, 2 small drag: stick, 3 drag, 4 mu raised, drag)")
    left.set_ylabel("F_x / F_y")
    left.set_title("Block dragged on a base (plane strain)")
    left.grid(True, alpha=0.3)
    left.legend(fontsize=8, loc="center right")
    right.plot(x, shear, "o-", ms=3, label="shear traction tau_x")
    right.plot(x, mu_p, "k--", label=f"mu p (mu = {MU_LATER})")
    right.set_xlabel("x along the block bottom [mm]")
    right.set_ylabel("stress [MPa]")
    right.set_title("End of the last drag: every node slips")
    right.grid(True, alpha=0.3)
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# %%
# Run
# ---
# The build of this page ran ``demos/sliding_block_2d.py --coarse``.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
