"""A block pressed onto a base and dragged back and forth: stick, slip and a friction change.

A steel block (40 x 40 x 10 mm) lies on an aluminium base (100 x 100 x 50 mm, clamped at its
bottom). A pressure on the block top presses it onto the base; then the block top is dragged
sideways by a prescribed displacement, back, and forth again after the friction coefficient has
been raised. Coulomb friction with a tangential penalty (CalculiX ``*FRICTION``: ``mu``, stick
slope ``lambda = K/100``) acts between the block bottom (slave) and the base top (master).

The analysis is a list of steps (``dolfinx_ntf.run_steps``): press; a small drag (the central node
sticks: ``tau = lambda t``); drag to +d (mu = 0.2); drag to -d; ``ChangeFriction`` to mu = 0.4 and
drag to +d. In every increment each spring either sticks (``|tau| < mu p``) or slips
(``|tau| = mu p``, checked to 1e-10 over all springs); at the end of each drag all springs slip. The
demo checks the equilibrium of the block (the support of its top takes the friction force) and
plots the shear traction and ``mu p`` of the central node and the mean shear
against time (``output/sliding_block.png``). Results go to ``output/sliding_block.xdmf``.

Run it with::

    .venv/bin/python demos/sliding_block.py           # 8.9k dofs, 52 increments, ~200 s
    .venv/bin/python demos/sliding_block.py --coarse  # small mesh, fewer increments (tests)
"""

from __future__ import annotations

import argparse
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
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes import punch as geometry
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh
from dolfinx_ntf.solvers.convergence import TIGHT_FIELD_CONTROLS

__all__ = ["main"]

# %%
# Parameters
# ----------
# The pressure on the block, the amplitude of the drag and a first drag small enough that nothing
# slips.

# Units: mm, N, MPa.
BASE_SIZE, BLOCK_SIZE = (100.0, 100.0, 50.0), (40.0, 40.0, 10.0)
E_BLOCK, NU_BLOCK = 210_000.0, 0.3  # steel
E_BASE, NU_BASE = 70_000.0, 0.33  # aluminium
PRESSURE = 50.0  # MPa on the block top
MU, MU_LATER = 0.2, 0.4
DRAG = 0.03  # mm, amplitude of the prescribed top displacement
STICK_DRAG = 5e-4  # mm, a first drag too small to make anything slip
#: Relative tolerance of the stick/slip and equilibrium checks.
TOLERANCE = 1e-10


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh, fewer increments")
    parser.add_argument("--output", type=Path, default=Path("output"))
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser.parse_args(argv)


# %%
# The analysis
# ------------
# The steps are :class:`~dolfinx_ntf.AnalysisStep` objects run by :func:`~dolfinx_ntf.run_steps`:
# each has its :class:`~dolfinx_ntf.Load` (pressure, prescribed displacement of the top) and,
# for the last drag, a :class:`~dolfinx_ntf.ChangeFriction`. After every increment the shear,
# slip and stick/slip state of every spring are read from :func:`~dolfinx_ntf.contact_results`.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (histories, checks, files)."""
    args = _parse(argv)
    comm = MPI.COMM_WORLD
    start = time.perf_counter()
    sizes = {"mesh_size_block": 12.5, "mesh_size_punch": 10.0} if args.coarse else {
        "mesh_size_block": 6.25, "mesh_size_punch": 4.0}  # fmt: skip
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        geometry.build_punch, comm, block_size=BASE_SIZE, punch_size=BLOCK_SIZE, **sizes
    )

    # --- Bulk: small-strain elasticity, pressure on the block top --------------------------------
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    F = (
        ufl.inner(small_strain_stress(u, E_BASE, NU_BASE), ufl.grad(v)) * dx(geometry.BLOCK)
        + ufl.inner(small_strain_stress(u, E_BLOCK, NU_BLOCK), ufl.grad(v)) * dx(geometry.PUNCH)
        + pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(geometry.PUNCH_TOP)
    )
    # Base bottom clamped; the block top: prescribed x (the drag), y = 0, z free (pressure).
    base = dolfinx.fem.locate_dofs_topological(V, 2, facet_tags.find(geometry.BLOCK_BOTTOM))
    top = facet_tags.find(geometry.PUNCH_TOP)
    Vx, _ = compat.component_space(V, 0)
    drag = dolfinx.fem.Function(Vx)
    top_x = dolfinx.fem.locate_dofs_topological((V.sub(0), Vx), 2, top)
    drag_bc = dolfinx.fem.dirichletbc(drag, top_x, V.sub(0))
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), base, V), drag_bc, component_bc(V, 1, top)]

    # --- Contact with friction -------------------------------------------------------------------
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E_BASE)
    stick_slope = law.slope / 100  # CalculiX's advice: lambda about K/100
    pair = ntf.ContactPair(
        ntf.FacetSurface(facet_tags, geometry.PUNCH_BOTTOM),
        ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP),
        ntf.SurfaceInteraction(law, ntf.Friction(MU, stick_slope)),
        name="block",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    # The residual bottoms out at about 5e-13 of the load (penalty K = 3.5e6 N/mm^3 in mm): the
    # tight controls of 1e-10 of the mean element force sit at that floor, 1e-8 is safely above.
    controls = {**TIGHT_FIELD_CONTROLS, "R_n": 1e-8, "R_p": 1e-8}
    solver = ntf.ContactNewtonSolver(comm, problem, controls=controls)
    if not args.quiet:
        ntf.log_progress()

    # --- Steps -----------------------------------------------------------------------------------
    args.output.mkdir(parents=True, exist_ok=True)
    xdmf = args.output / "sliding_block.xdmf"
    writer = ntf.ContactWriter(problem, str(xdmf))
    coords = problem.reference_coordinates
    history: dict[str, list] = {k: [] for k in ("time", "tau", "mu_p", "mean_tau", "mean_mu_p")}
    history["stick_error"], history["slip_error"], history["sliding"] = [], [], []
    history["centre_sliding"], history["centre_law"] = [], []
    clock = {"total": 0.0, "period": 1.0}
    mu_now = {"value": MU}

    def record(result: ntf.IncrementResult) -> None:
        t = clock["total"] + result.time
        writer.write(t)
        (res,) = ntf.contact_results(problem)
        x = coords[res.node]
        centre = int(np.argmin(np.linalg.norm(x[:, :2] - 50.0, axis=1)))
        p, tau = res.pressure, res.shear[:, 0]
        mu = mu_now["value"]
        shear = np.linalg.norm(res.shear, axis=1)
        limit = mu * np.maximum(p, 0.0)
        stick = ~res.sliding
        scale = max(limit.max(), 1e-300)
        # stick: tau = lambda (t - t_p); t_p is not in the results, but |tau| < mu p must hold
        history["stick_error"].append(float(np.max((shear - limit)[stick], initial=-scale)) / scale)
        history["slip_error"].append(
            float(np.max(np.abs(shear - limit)[res.sliding], initial=0.0)) / scale
        )
        history["sliding"].append(int(res.sliding.sum()))
        history["centre_sliding"].append(bool(res.sliding[centre]))
        # a node that never slipped: tau = lambda t exactly (t_p = 0)
        law_error = np.linalg.norm(res.shear[centre] - stick_slope * res.slip[centre])
        history["centre_law"].append(float(law_error / max(shear[centre], 1e-300)))
        history["time"].append(t)
        history["tau"].append(float(tau[centre]))
        history["mu_p"].append(float(limit[centre]))
        area = res.area
        history["mean_tau"].append(float((tau * area).sum() / area.sum()))
        history["mean_mu_p"].append(float((limit * area).sum() / area.sum()))

    increments = (3, 6) if args.coarse else (10, 20)

    def step(n: int, loads, changes=()) -> ntf.AnalysisStep:
        procedure = ntf.StaticStep(initial_increment=1 / n, fixed=True, on_increment=record)
        return ntf.AnalysisStep(procedure, loads, changes=changes)

    plan = [
        ("press", step(1, [ntf.Load(pressure, PRESSURE)]), MU),
        ("stick", step(1, [ntf.Load(drag, STICK_DRAG)]), MU),
        ("drag", step(increments[0], [ntf.Load(drag, DRAG)]), MU),
        ("back", step(increments[1], [ntf.Load(drag, -DRAG)]), MU),
        (
            "mu",
            step(
                increments[1],
                [ntf.Load(drag, DRAG)],
                [ntf.ChangeFriction(pair, ntf.Friction(MU_LATER, stick_slope))],
            ),
            MU_LATER,
        ),
    ]
    ends = []
    for _, analysis_step, mu in plan:
        mu_now["value"] = mu
        ntf.run_steps(solver, [analysis_step])
        clock["total"] += 1.0
        ends.append(len(history["time"]))
    writer.close()

    # --- Checks ----------------------------------------------------------------------------------
    force = ntf.contact_force(problem)
    reaction = ntf.reaction(problem, dofs=drag_bc)
    equilibrium = abs(reaction[0] + force[0]) / abs(force[2])
    sliding = np.array(history["sliding"])
    (res,) = ntf.contact_results(problem)
    summary = {
        "dofs": 3 * V.dofmap.index_map.size_global,
        "springs": int(res.node.size),
        "increments": len(history["time"]),
        "stick_error": max(history["stick_error"]),
        "slip_error": max(history["slip_error"]),
        "equilibrium_error": equilibrium,
        # press and small drag: the central node sticks with tau = lambda t; the end of each
        # drag: every node slips
        "centre_sticks": not any(history["centre_sliding"][: ends[1]]),
        "stick_law_error": max(history["centre_law"][: ends[1]]),
        "stick_sliding": int(sliding[ends[1] - 1]),
        "end_sliding": [int(sliding[e - 1]) for e in ends[2:]],
        "mean_ratio_drag": history["mean_tau"][ends[2] - 1] / history["mean_mu_p"][ends[2] - 1],
        "mean_ratio_back": history["mean_tau"][ends[3] - 1] / history["mean_mu_p"][ends[3] - 1],
        "mean_ratio_mu": history["mean_tau"][ends[4] - 1] / history["mean_mu_p"][ends[4] - 1],
        "history": history,
        "xdmf": str(xdmf),
        "time": time.perf_counter() - start,
    }
    summary["passed"] = bool(
        summary["stick_error"] < 0
        and summary["slip_error"] < TOLERANCE
        and equilibrium < 1e-8
        and summary["centre_sticks"]
        and summary["stick_law_error"] < TOLERANCE
        and summary["end_sliding"] == [summary["springs"]] * 3
    )
    if comm.rank == 0:
        summary["png"] = str(_plot(args.output / "sliding_block.png", history, ends))
        print(
            f"\nSliding block: {summary['dofs']} dofs, {summary['increments']} increments, "
            f"{summary['springs']} springs, {summary['time']:.1f} s\n"
            f"mean shear / (mu p) at the end of drag, back, drag with mu = {MU_LATER}: "
            f"{summary['mean_ratio_drag']:+.4f}, {summary['mean_ratio_back']:+.4f}, "
            f"{summary['mean_ratio_mu']:+.4f}\n"
            f"stick (central node, small drag): |tau - lambda t| / |tau| = "
            f"{summary['stick_law_error']:.1e}; slip: max | |tau| - mu p | / (mu p) = "
            f"{summary['slip_error']:.1e}; equilibrium of the block {equilibrium:.1e}: "
            f"{'PASSED' if summary['passed'] else 'FAILED'}"
        )
    return summary


# %%
# Figure
# ------
# The shear traction and ``mu p`` of the central node, and the mean shear over all springs, against
# the analysis time.


def _plot(path: Path, history: dict, ends: list[int]) -> Path:
    """Shear traction and mu p of the central node, and the means, against time."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    t = np.array(history["time"])
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(t, history["tau"], "o-", ms=3, label="shear traction tau_x, central node")
    ax.plot(t, history["mu_p"], "k--", label="+mu p, central node")
    ax.plot(t, -np.array(history["mu_p"]), "k--", label="-mu p")
    ax.plot(t, history["mean_tau"], "-", color="tab:orange", label="mean tau_x")
    ax.plot(t, history["mean_mu_p"], ":", color="tab:orange", label="mean mu p")
    for end in ends[:-1]:
        ax.axvline(t[end - 1], color="0.8", lw=0.8)
    ax.text(1.05, 0.0, "stick", fontsize=8)
    ax.text(4.05, history["mu_p"][-1] * 1.05, f"mu {MU} -> {MU_LATER}", fontsize=8)
    ax.set_xlabel("time (1 press, 2 small drag: stick, 3 drag +d, 4 to -d, 5 mu raised, to +d)")
    ax.set_ylabel("stress [MPa]")
    ax.set_title("Block dragged on a base: stick, then slip at |tau| = mu p")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# %%
# Run
# ---
# The build of this page ran ``demos/sliding_block.py --coarse``.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
