"""Hertz sphere on a rigid plane: node-to-face springs against UFL penalty and Nitsche contact.

A steel hemisphere of radius R = 25 mm (the quarter model of ``dolfinx_ntf.meshes.hertz``) is pushed
by its flat top onto a rigid plane ``z = 0``; every method uses the same sphere cells:

- ``ntf-rigid``: node-to-face springs against the analytical plane (``RigidPlane``), CalculiX's
  pairing schedule and convergence test;
- ``ntf-active``: the same springs with the active-set Newton (re-pair every iteration, stop when
  the spring set is stable and the residual small; docs/method.md §15.5);
- ``ntf-meshed``: node-to-face springs against the meshed block of the two-body model, clamped as a
  whole (a stand-in for the rigid plane: the block's dofs are extra unknowns);
- ``penalty``: UFL penalty ``K [-g]_+`` (docs/method.md §15.2);
- ``nitsche``: Nitsche's method, ``gamma = gamma0 E / h``, theta = 1, 0 or -1.

All methods run at the same applied displacement (t^2 in equal increments) and are compared with
Hertz's solution at their own force (the reaction at the sphere top, from the assembled residual):
``a = (3 F R / (4 E*))^(1/3)``, ``p0 = 3 F / (2 pi a^2)``, ``E* = E / (1 - nu^2)`` (rigid plane).
Every measure is taken the same way for all methods (``dolfinx_ntf.fem.measures``) from the pressure
recovered on the contact boundary (``BoundaryPressure``: spring forces, or the continuum pressure,
turned into a traction field). Contact acts on the potential contact zone ``ZONE`` only. Run it
with::

    .venv/bin/python demos/compare_continuum.py            # size_fine = 0.02 R
    .venv/bin/python demos/compare_continuum.py --coarse   # the coarse Hertz mesh (tests)
"""

from __future__ import annotations

import argparse
import math
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import continuum, measures
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.fem.pressure_recovery import BoundaryPressure
from dolfinx_ntf.meshes import hertz as geometry
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh
from dolfinx_ntf.solvers.active_set import ActiveSetNewtonSolver

__all__ = ["METHODS", "hertz", "main", "make_meshes", "run"]

# %%
# Parameters
# ----------
# The Hertz sphere of radius 25 mm on the plane ``z = 0``; ``ZONE`` is the potential contact zone
# (the facets below ``0.2 R``), the only boundary where contact acts in every method.

# Units: mm, N, MPa.
RADIUS = 25.0
E, NU = 210_000.0, 0.3
#: Downward displacement of the sphere top [mm].
DISPLACEMENT = 0.3
#: Tag of the potential contact zone: the facets of the sphere's curved surface below ZONE_HEIGHT.
ZONE = 15
ZONE_HEIGHT = 0.2 * RADIUS
METHODS = ("ntf-rigid", "ntf-active", "ntf-meshed", "penalty", "nitsche")
PLANE = ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0))


def hertz(force: float) -> tuple[float, float]:
    """Hertz's contact radius and peak pressure of the elastic sphere on a rigid plane."""
    e_star = E / (1 - NU**2)
    a = (3 * force * RADIUS / (4 * e_star)) ** (1 / 3)
    return a, 3 * force / (2 * math.pi * a**2)


def make_meshes(size_fine: float, comm: MPI.Comm = MPI.COMM_WORLD) -> dict:
    """The two-body Hertz mesh and the same sphere alone, at ``size_fine`` (relative to R)."""
    sizes = {"size_fine": size_fine * RADIUS}
    if size_fine >= geometry.COARSE["size_fine"]:
        sizes = {key: value * RADIUS for key, value in geometry.COARSE.items()}
    return {
        "two-body": _with_zone(mesh_from_gmsh(geometry.build_hertz, comm, radius=RADIUS, **sizes)),
        "sphere": _with_zone(
            mesh_from_gmsh(geometry.build_hertz_sphere, comm, radius=RADIUS, **sizes)
        ),
    }


def _with_zone(mesh_and_tags: tuple) -> tuple:
    """Add the tag ZONE: the sphere-contact facets below ZONE_HEIGHT (the potential contact zone).

    Nitsche's terms act on the whole contact boundary, also where it is open: with the whole curved
    surface the force of the coarse mesh changed by 2.5 % between theta = 1 and -1 (0.9 % with this
    zone), so every method gets this smaller zone (the springs never reach beyond it anyway).
    """
    mesh, cell_tags, facet_tags = mesh_and_tags
    curved = facet_tags.find(geometry.SPHERE_CONTACT)
    low = curved[dolfinx.mesh.compute_midpoints(mesh, 2, curved)[:, 2] < ZONE_HEIGHT]
    keep = ~np.isin(facet_tags.indices, low)
    entities = np.concatenate([facet_tags.indices[keep], low])
    values = np.concatenate([facet_tags.values[keep], np.full(low.size, ZONE, dtype=np.int32)])
    order = np.argsort(entities)
    tags = dolfinx.mesh.meshtags(mesh, 2, entities[order], values[order])
    return mesh, cell_tags, tags


class _Timer:
    """Time spent in a problem's contact and bulk callbacks, and in PETSc's KSPSolve."""

    def __init__(self, problem: ntf.ContactProblem) -> None:
        self.contact = 0.0
        self.total = 0.0
        for owner, name, kind in (
            (problem, "evaluate", "contact"),
            (problem, "pair", "contact"),
            (problem.assembler, "add_to_matrix", "contact"),
            (problem.assembler, "add_to_vector", "contact"),
            (problem, "begin_increment", "total"),
            (problem, "form", "total"),
            (problem, "assemble_residual", "total"),
            (problem, "J", "total"),
        ):
            setattr(owner, name, self._wrap(getattr(owner, name), kind))

    def _wrap(self, method: typing.Callable, kind: str) -> typing.Callable:
        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return method(*args, **kwargs)
            finally:
                setattr(self, kind, getattr(self, kind) + time.perf_counter() - start)

        return timed


def _ksp_time() -> float:
    return PETSc.Log.Event("KSPSolve").getPerfInfo()["time"]


# %%
# One method
# ----------
# ``run`` solves the same sphere with one method: node-to-face springs against the rigid plane
# (:class:`~dolfinx_ntf.RigidPlane`) or against a clamped meshed block, the active-set Newton
# (:class:`~dolfinx_ntf.ActiveSetNewtonSolver`), or the UFL penalty and Nitsche residuals of
# :mod:`dolfinx_ntf.fem.continuum` solved by
# :class:`~dolfinx_ntf.fem.continuum.ContinuumNewton`. Every method's pressure is recovered on the
# contact boundary by :class:`~dolfinx_ntf.BoundaryPressure` and measured alike
# (:mod:`dolfinx_ntf.fem.measures`).


def run(
    method: str,
    meshes: dict,
    *,
    penalty: float = 10.0,
    gamma0: float = 10.0,
    theta: int = 1,
    degree: int = continuum.DEFAULT_QUADRATURE_DEGREE,
    displacement: float = DISPLACEMENT,
    increments: int = 4,
) -> dict:
    """Solve one method; returns its measures (forces of the whole sphere, 4 quarters)."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    PETSc.Log.begin()
    mesh, cell_tags, facet_tags = meshes["two-body" if method == "ntf-meshed" else "sphere"]
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)

    def stress(w):
        return small_strain_stress(w, E, NU)

    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    bulk = ufl.inner(stress(u), ufl.grad(v)) * dx
    Vz, _ = compat.component_space(V, 2)
    top_uz = dolfinx.fem.Function(Vz)
    top = dolfinx.fem.locate_dofs_topological(
        (V.sub(2), Vz), 2, facet_tags.find(geometry.SPHERE_TOP)
    )
    bcs = [
        component_bc(V, 0, facet_tags.find(geometry.SYMMETRY_X)),
        component_bc(V, 1, facet_tags.find(geometry.SYMMETRY_Y)),
        dolfinx.fem.dirichletbc(top_uz, top, V.sub(2)),
    ]
    if method == "ntf-meshed":  # the whole block clamped: a rigid plane made of elements
        mesh.topology.create_connectivity(3, 3)
        block = dolfinx.fem.locate_dofs_topological(V, 3, cell_tags.find(geometry.BLOCK))
        bcs.append(dolfinx.fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), block, V))
    recovery = BoundaryPressure(V, facet_tags.find(ZONE))
    loads = [((k + 1) / increments) ** 2 * displacement for k in range(increments)]
    iterations: list[int] = []
    split = {"bulk": 0.0, "contact": 0.0, "solve": 0.0}
    ksp_start = _ksp_time()
    start = time.perf_counter()
    if method.startswith("ntf"):
        law = ntf.LinearLaw.with_ccx_defaults(E, slope=penalty * E)
        master = (
            ntf.FacetSurface(facet_tags, geometry.BLOCK_TOP) if method == "ntf-meshed" else PLANE
        )
        pair = ntf.ContactPair(
            ntf.FacetSurface(facet_tags, ZONE),
            master,
            ntf.SurfaceInteraction(law),
        )
        problem = ntf.ContactProblem(bulk, u, [pair], bcs)
        timer = _Timer(problem)
        kind = ActiveSetNewtonSolver if method == "ntf-active" else ntf.ContactNewtonSolver
        solver = kind(mesh.comm, problem)
        step = ntf.StaticStep(
            lambda t: top_uz.x.array.fill(-(t**2) * displacement),
            initial_increment=1.0 / increments,
            max_increment=1.0 / increments,
            on_increment=lambda r: iterations.append(r.iterations),
        )
        step.run(solver, u)
        split["contact"] = timer.contact
        split["bulk"] = timer.total - timer.contact
        (res,) = ntf.contact_results(problem)
        recovery.from_forces(res.node, res.normal_force)
        residual = bulk  # no springs at the top: the bulk residual is all of it there
        law_values = res.pressure
        solver.destroy()
        problem.destroy()
    else:
        obstacle = continuum.RigidObstacle(PLANE, mesh)
        ds = continuum.contact_measure(mesh, facet_tags, ZONE, degree)
        if method == "penalty":
            contact = continuum.penalty_residual(u, v, obstacle, ds, penalty * E)
            pressure = continuum.penalty_pressure(u, obstacle, penalty * E)
        else:
            gamma = continuum.nitsche_gamma(gamma0, E, mesh)
            contact = continuum.nitsche_residual(u, v, obstacle, ds, stress, gamma, theta)
            pressure = continuum.nitsche_pressure(u, obstacle, stress, gamma)
        newton = continuum.ContinuumNewton(bulk, contact, u, bcs)
        for load in loads:
            top_uz.x.array[:] = -load
            record = newton.solve()
            iterations.append(record.iterations)
            split["bulk"] += record.bulk_assembly
            split["contact"] += record.contact_assembly
        recovery.from_expression(pressure)
        law_values = None
        residual = bulk + contact
        newton.destroy()
    total_time = time.perf_counter() - start
    split["solve"] = _ksp_time() - ksp_start
    return _measure(
        method, u, residual, facet_tags, recovery, law_values, iterations, split, total_time
    )


def _measure(method, u, residual, facet_tags, recovery, law_values, iterations, split, total_time):
    """The measures of docs/method.md §15.4, whole sphere (4 quarters)."""
    comm = u.function_space.mesh.comm
    V = u.function_space
    force = -4 * float(measures.facet_reaction(residual, u, facet_tags, geometry.SPHERE_TOP)[2])
    a_hertz, p0_hertz = hertz(force)
    nodes, p = recovery.nodal()
    owned = nodes < V.dofmap.index_map.size_local
    nodes, p = nodes[owned], p[owned]
    X = V.tabulate_dof_coordinates()[nodes]
    r = np.concatenate(comm.allgather(np.hypot(X[:, 0], X[:, 1])))
    p = np.concatenate(comm.allgather(p))
    positions = X + u.x.array.reshape(-1, 3)[nodes]
    a_fit, p0_fit = measures.fit_hertz_profile(r, p, a_hertz, p0_hertz)
    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=facet_tags)(ZONE)
    area = measures.contact_area(recovery.pressure, ds)
    a_area = measures.radius_from_area(area, 0.25)
    last, first = measures.bracketing_radius(r, p)
    penetration = comm.allreduce(measures.largest_penetration(PLANE, positions), op=MPI.MAX)
    summary = {
        "method": method,
        "dofs": V.dofmap.index_map.size_global * 3,
        "force": force,
        "pressure_force": 4 * recovery.total(),
        "a_hertz": a_hertz,
        "p0_hertz": p0_hertz,
        "a_fit": a_fit,
        "a_area": a_area,
        "a_last_closed": last,
        "a_first_open": first,
        "p0_fit": p0_fit,
        "p_max": float(p.max()),
        "penetration": penetration,
        "iterations": iterations,
        "time": total_time,
        "time_bulk": split["bulk"],
        "time_contact": split["contact"],
        "time_solve": split["solve"],
    }
    if law_values is not None:
        summary["p_max_law"] = float(comm.allreduce(law_values.max(initial=0.0), op=MPI.MAX))
    summary["pressure_force_error"] = summary["pressure_force"] / force - 1
    summary["a_error"] = a_fit / a_hertz - 1
    summary["p0_error"] = p0_fit / p0_hertz - 1
    summary["a_area_error"] = a_area / a_hertz - 1
    summary["p_max_error"] = summary["p_max"] / p0_hertz - 1
    recovery.destroy()
    return summary


def print_table(rows: list[dict]) -> None:
    """One line per run."""
    print(
        f"{'method':<12} {'dofs':>6} {'F [N]':>10} {'a fit':>7} {'a area':>7} {'p0 fit':>7} "
        f"{'p max':>7} {'pen. [um]':>9} {'iterations':<16} {'time [s]':>8}"
    )
    for s in rows:
        print(
            f"{s['method']:<12} {s['dofs']:>6} {s['force']:>10.5g} {s['a_error']:>+7.2%} "
            f"{s['a_area_error']:>+7.2%} {s['p0_error']:>+7.2%} {s['p_max_error']:>+7.2%} "
            f"{1e3 * s['penetration']:>9.3f} {s['iterations']!s:<16} {s['time']:>8.2f}"
        )


def main(argv: typing.Sequence[str] | None = None) -> list[dict]:
    """Run every method on one mesh and print the table; returns the summaries."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="coarse Hertz mesh (tests)")
    parser.add_argument("--size-fine", type=float, default=0.02, help="fine size / R")
    parser.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS))
    parser.add_argument("--penalty", type=float, default=10.0, help="K in units of E per mm")
    parser.add_argument("--gamma0", type=float, default=10.0)
    parser.add_argument("--theta", type=int, default=1, choices=(1, 0, -1))
    parser.add_argument("--increments", type=int, default=4)
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    size = geometry.COARSE["size_fine"] if args.coarse else args.size_fine
    meshes = make_meshes(size)
    rows = [
        run(
            m,
            meshes,
            penalty=args.penalty,
            gamma0=args.gamma0,
            theta=args.theta,
            increments=args.increments,
        )
        for m in args.methods
    ]
    if not args.quiet and MPI.COMM_WORLD.rank == 0:
        print_table(rows)
    return rows


# %%
# Run
# ---
# The build of this page ran ``demos/compare_continuum.py --coarse``: one row per method. The
# comparison at three mesh levels, with sweeps over the penalties and Nitsche's parameters, is
# on the :doc:`comparison page <../comparison>` (``benchmarks/continuum.py``).

if __name__ == "__main__":
    main()
