"""Natural frequencies of a punch clamped onto a block by contact: the preload stiffens the joint.

A steel punch (40 x 40 x 30 mm) is pressed onto an aluminium block (100 x 100 x 50 mm, bottom
clamped) by a pressure on its top; its top face is held in its plane, so vertically the punch rests
on the contact springs alone. The interface is soft: CalculiX's EXPONENTIAL law
``p = p0 exp(beta d)`` with ``c0 = 0.5 mm`` (a rough, compliant joint). Its stiffness
``p'(d) = beta p`` grows with the pressure, so the springs' total stiffness is ``k = beta F`` at a
contact force ``F``: the joint stiffens in proportion to its preload.

After each load increment the demo computes the lowest modes of the preloaded structure with
``contact_modes`` (the converged tangent: bulk plus closed springs; consistent mass). The punch's
bounce, the mode with the largest effective mass along z, should be close to a rigid punch on the
springs, ``omega^2 = beta F / m_punch`` (the bodies are about a hundred times stiffer than the
joint), below it by the bodies' compliance, and rise as the square root of the preload. Without
the springs (``springs=False``) the punch floats: a zero frequency.

Run it with::

    .venv/bin/python demos/preloaded_modes.py            # 5 mm / 4 mm elements
    .venv/bin/python demos/preloaded_modes.py --coarse   # small mesh (tests)
"""

from __future__ import annotations

import argparse
import math
import typing

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
# Units: mm, N, tonne, s (stress in MPa, density in t/mm^3, frequency in Hz).
SCALE = 100.0
BLOCK_SIZE = (1.0 * SCALE, 1.0 * SCALE, 0.5 * SCALE)
PUNCH_SIZE = (0.4 * SCALE, 0.4 * SCALE, 0.3 * SCALE)
E_PUNCH, NU_PUNCH, RHO_PUNCH = 210_000.0, 0.3, 7.85e-9  # steel
E_BLOCK, NU_BLOCK, RHO_BLOCK = 70_000.0, 0.33, 2.70e-9  # aluminium
LAW = ntf.ExponentialLaw(c0=0.5, p0=0.5)  # beta = ln(100)/c0 = 9.2 per mm
PRESSURE = 1.0  # MPa on the punch top at the end: 1600 N
MODES = 6


def _parse(argv: typing.Sequence[str] | None) -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh (tests)")
    parser.add_argument("--increments", type=int, default=4, help="load increments (default 4)")
    parser.add_argument("--quiet", action="store_true", help="no table")
    return parser.parse_args(argv)


# %%
# The analysis
# ------------
# The punch problem of ``demos/punch.py`` with two materials and densities; after every converged
# increment, ``contact_modes`` at that preload.


def main(argv: typing.Sequence[str] | None = None) -> dict:
    """Run the demo; returns the load, bounce frequency and its rigid estimate per increment."""
    args = _parse(argv)
    comm = MPI.COMM_WORLD
    sizes = (
        dict(geometry.COARSE) if args.coarse else {"mesh_size_block": 0.05, "mesh_size_punch": 0.04}
    )
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        geometry.build_punch,
        comm,
        block_size=BLOCK_SIZE,
        punch_size=PUNCH_SIZE,
        **{key: value * SCALE for key, value in sizes.items()},
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v, w = dolfinx.fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    F = (
        ufl.inner(small_strain_stress(u, E_BLOCK, NU_BLOCK), ufl.grad(v)) * dx(geometry.BLOCK)
        + ufl.inner(small_strain_stress(u, E_PUNCH, NU_PUNCH), ufl.grad(v)) * dx(geometry.PUNCH)
        + pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(geometry.PUNCH_TOP)
    )
    mass = RHO_BLOCK * ufl.inner(w, v) * dx(geometry.BLOCK) + RHO_PUNCH * ufl.inner(w, v) * dx(
        geometry.PUNCH
    )
    bcs = [
        dolfinx.fem.dirichletbc(
            np.zeros(3, dtype=PETSc.ScalarType),
            dolfinx.fem.locate_dofs_topological(V, 2, facet_tags.find(geometry.BLOCK_BOTTOM)),
            V,
        ),
        component_bc(V, 0, facet_tags.find(geometry.PUNCH_TOP)),
        component_bc(V, 1, facet_tags.find(geometry.PUNCH_TOP)),
    ]
    pair = ntf.ContactPair(
        slave=ntf.FacetSurface(facet_tags, geometry.PUNCH_BOTTOM),
        master=ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP),
        interaction=ntf.SurfaceInteraction(LAW),
        name="punch",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    punch_mass = RHO_PUNCH * math.prod(PUNCH_SIZE)
    rows: list[dict] = []

    # %%
    # The modes at each preload: the bounce is the mode that moves the most mass along z.
    def modes_at(result: ntf.IncrementResult) -> None:
        modes = ntf.contact_modes(problem, mass, MODES)
        effective_z = modes.participation_factors()[:, 2] ** 2
        bounce = int(np.argmax(effective_z))
        force = float(ntf.contact_force(problem, "punch")[2])
        rows.append(
            {
                "load": PRESSURE * result.time * PUNCH_SIZE[0] * PUNCH_SIZE[1],
                "time": result.time,
                "iterations": result.iterations,
                "contact_force": force,
                "frequencies": modes.frequencies.tolist(),
                "bounce": float(modes.frequencies[bounce]),
                "bounce_mass": float(effective_z[bounce]),
                "rigid_estimate": math.sqrt(LAW.beta * force / punch_mass) / (2 * math.pi),
            }
        )
        modes.destroy()

    solver = ntf.ContactNewtonSolver(comm, problem)
    step = ntf.StaticStep(
        lambda t: setattr(pressure, "value", PRESSURE * t),
        initial_increment=1.0 / args.increments,
        max_increment=1.0 / args.increments,
        on_increment=modes_at,
    )
    step.run(solver, u)
    floating = ntf.contact_modes(problem, mass, 1, springs=False)
    summary = {
        "dofs": V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
        "punch_mass": punch_mass,
        "rows": rows,
        "floating": float(floating.frequencies[0]),
    }
    floating.destroy()
    solver.destroy()
    problem.destroy()
    if comm.rank == 0 and not args.quiet:
        _print_table(summary)
    return summary


def _print_table(summary: dict) -> None:
    """One row per preload: bounce frequency, its rigid estimate, the lowest frequencies."""
    print(f"\nPreloaded punch: {summary['dofs']} dofs, punch mass {summary['punch_mass']:.3e} t")
    print(f"{'load [N]':>9} {'bounce [Hz]':>12} {'sqrt(bF/m)/2pi':>15} {'ratio':>7}  lowest [Hz]")
    for row in summary["rows"]:
        ratio = row["bounce"] / row["rigid_estimate"]
        lowest = " ".join(f"{f:8.1f}" for f in row["frequencies"][:4])
        print(
            f"{row['load']:9.1f} {row['bounce']:12.1f} {row['rigid_estimate']:15.1f} "
            f"{ratio:7.4f}  {lowest}"
        )
    print(f"without the springs the lowest frequency is {summary['floating']:.3g} Hz (floating)")


if __name__ == "__main__":
    main()
