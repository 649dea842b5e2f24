"""A flat punch pressed onto a block with friction: a sticking centre and a slipping rim.

The steel punch (40 x 40 x 30 mm) of ``demos/punch.py`` is pressed onto an aluminium block
(100 x 100 x 50 mm, clamped at its bottom) by a pressure on its top, now with Coulomb friction
(``mu = 0.2``, stick slope ``lambda = K/100``). Under load the softer block's surface spreads out
more than the punch bottom: near the punch edges, where the pressure peaks but the tangential
mismatch is largest, the contact slips; in the centre it sticks. The demo plots the stick and slip
zones on the punch bottom with the shear tractions, and the pressure, shear traction and ``mu p``
along the centre line (``output/frictional_punch.png``).

Checks: every spring satisfies its return map (stick ``|tau| < mu p``, slip ``|tau| = mu p`` to
1e-10), both zones exist and the slip zone lies outside the stick zone, and the block bottom carries
the load to 1e-8. Results go to ``output/frictional_punch.xdmf`` (``contact_shear`` and
``contact_slip`` beside the pressure).

Run it with::

    .venv/bin/python demos/frictional_punch.py           # 18k dofs, ~40 s (45 stick, 76 slip)
    .venv/bin/python demos/frictional_punch.py --coarse  # small mesh (tests)
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
# The punch, block and materials of the frictionless punch demo; ``mu = 0.2``.

# Units: mm, N, MPa (the geometry and materials of demos/punch.py).
BLOCK_SIZE, PUNCH_SIZE = (100.0, 100.0, 50.0), (40.0, 40.0, 30.0)
E_PUNCH, NU_PUNCH = 210_000.0, 0.3
E_BLOCK, NU_BLOCK = 70_000.0, 0.33
PRESSURE, MU = 100.0, 0.2
CENTRE = np.array([50.0, 50.0])
TOLERANCE = 1e-10


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh (tests)")
    parser.add_argument("--output", type=Path, default=Path("output"))
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser.parse_args(argv)


# %%
# The analysis
# ------------
# The pair's :class:`~dolfinx_ntf.SurfaceInteraction` holds a :class:`~dolfinx_ntf.Friction`; the
# load is one static step. The stick and slip zones are read from the ``sliding`` column of
# :func:`~dolfinx_ntf.contact_results`.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns a summary (zones, checks, files)."""
    args = _parse(argv)
    comm = MPI.COMM_WORLD
    start = time.perf_counter()
    sizes = (
        dict(geometry.COARSE) if args.coarse else {"mesh_size_block": 0.05, "mesh_size_punch": 0.04}
    )
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        geometry.build_punch,
        comm,
        block_size=BLOCK_SIZE,
        punch_size=PUNCH_SIZE,
        **{key: 100.0 * value for key, value in sizes.items()},
    )
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
    bottom = facet_tags.find(geometry.BLOCK_BOTTOM)
    top = facet_tags.find(geometry.PUNCH_TOP)
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(3), dolfinx.fem.locate_dofs_topological(V, 2, bottom), V),
        component_bc(V, 0, top),
        component_bc(V, 1, top),
    ]
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E_BLOCK)
    pair = ntf.ContactPair(
        ntf.FacetSurface(facet_tags, geometry.PUNCH_BOTTOM),
        ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP),
        ntf.SurfaceInteraction(law, ntf.Friction(MU, law.slope / 100)),
        name="punch",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    # the residual bottoms out near 1e-12 of the load with K = 3.5e6 N/mm^3 in mm
    controls = {**TIGHT_FIELD_CONTROLS, "R_n": 1e-8, "R_p": 1e-8}
    solver = ntf.ContactNewtonSolver(comm, problem, controls=controls)
    if not args.quiet:
        ntf.log_progress()
    args.output.mkdir(parents=True, exist_ok=True)
    xdmf = args.output / "frictional_punch.xdmf"
    with ntf.ContactWriter(problem, str(xdmf)) as writer:
        writer.write(0.0)
        step = ntf.StaticStep(
            lambda t: setattr(pressure, "value", PRESSURE * t),
            initial_increment=0.25,
            on_increment=lambda result: writer.write(result.time),
        )
        results = step.run(solver, u)

    # --- Zones and checks -------------------------------------------------------------------------
    (res,) = ntf.contact_results(problem)
    x = problem.reference_coordinates[res.node][:, :2] - CENTRE
    radius = np.linalg.norm(x, axis=1)  # distance from the centre
    shear = np.linalg.norm(res.shear, axis=1)
    limit = MU * np.maximum(res.pressure, 0.0)
    scale = limit.max()
    slip, stick = res.sliding, ~res.sliding
    load = PRESSURE * PUNCH_SIZE[0] * PUNCH_SIZE[1]
    reaction = ntf.reaction(problem, bottom)
    summary = {
        "dofs": 3 * V.dofmap.index_map.size_global,
        "springs": int(res.node.size),
        "increments": len(results),
        "iterations": [r.iterations for r in results],
        "stick_nodes": int(stick.sum()),
        "slip_nodes": int(slip.sum()),
        "stick_margin": float(np.max((shear - limit)[stick], initial=-scale) / scale),
        "slip_error": float(np.max(np.abs(shear - limit)[slip], initial=0.0) / scale),
        "stick_radius": float(radius[stick].max(initial=0.0)),
        "slip_radius": float(radius[slip].min(initial=np.inf)),
        "equilibrium_error": float(abs(reaction[2] - load) / load),
        "max_shear_over_pressure": float((shear / np.maximum(res.pressure, 1e-300)).max()),
        "xdmf": str(xdmf),
        "time": time.perf_counter() - start,
    }
    summary["passed"] = bool(
        summary["stick_nodes"] > 0
        and summary["slip_nodes"] > 0
        and summary["stick_margin"] < 0
        and summary["slip_error"] < TOLERANCE
        and np.mean(radius[slip]) > np.mean(radius[stick])
        and summary["equilibrium_error"] < 1e-8
    )
    if comm.rank == 0:
        summary["png"] = str(
            _plot(args.output / "frictional_punch.png", x, res, limit, slip, summary)
        )
        print(
            f"\nFrictional punch: {summary['dofs']} dofs, {summary['springs']} springs, "
            f"{summary['increments']} increments {summary['iterations']}, "
            f"{summary['time']:.1f} s\n"
            f"stick {summary['stick_nodes']} nodes (out to {summary['stick_radius']:.3g} mm from "
            f"the centre), slip {summary['slip_nodes']} nodes (from {summary['slip_radius']:.3g} "
            f"mm on); slip: | |tau| - mu p | / max(mu p) = {summary['slip_error']:.1e}; "
            f"equilibrium {summary['equilibrium_error']:.1e}: "
            f"{'PASSED' if summary['passed'] else 'FAILED'}"
        )
    return summary


# %%
# Figure
# ------
# Left: the punch bottom's nodes, sticking or slipping, with their shear tractions. Right: the
# pressure, the shear traction and the limit ``mu p`` along the centre line.


def _plot(path: Path, x: np.ndarray, res, limit: np.ndarray, slip: np.ndarray, summary) -> Path:
    """Stick/slip map with shear arrows, and pressure, shear and mu p along the centre line."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.8))
    left.scatter(*x[~slip].T, c="tab:blue", s=18, label=f"stick ({summary['stick_nodes']})")
    left.scatter(*x[slip].T, c="tab:red", s=18, label=f"slip ({summary['slip_nodes']})")
    left.quiver(*x.T, *res.shear[:, :2].T, color="0.3", width=0.003)
    left.set_aspect("equal")
    left.set_xlabel("x - 50 [mm]")
    left.set_ylabel("y - 50 [mm]")
    left.set_title("punch bottom: stick and slip zones, shear traction")
    left.legend(fontsize=8, loc="upper right")
    line = np.abs(x[:, 1]) <= np.abs(x[:, 1]).min() + 1e-9
    order = np.argsort(x[line, 0])
    xs = x[line, 0][order]
    right.plot(xs, res.pressure[line][order], "o-", ms=3, label="pressure p")
    right.plot(xs, limit[line][order], "k--", label="mu p")
    right.plot(xs, np.linalg.norm(res.shear, axis=1)[line][order], "s-", ms=3, label="|tau|")
    right.set_xlabel("x - 50 [mm] (centre line)")
    right.set_ylabel("stress [MPa]")
    right.set_title(f"pressure {PRESSURE:g} MPa, mu = {MU}")
    right.grid(True, alpha=0.3)
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# %%
# Run
# ---
# The build of this page ran ``demos/frictional_punch.py --coarse``.

if __name__ == "__main__":
    sys.exit(0 if main()["passed"] else 1)
