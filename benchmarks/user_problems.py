"""Problems a FEniCSx user brings, run with the defaults: iterations, cutbacks, time, a check.

Each problem is written as a user would from the docs (gmsh mesh, UFL residual, a contact pair or a
rigid master, ``StaticStep`` with its defaults) and prints one row: dofs, Newton iterations per
increment, cutbacks, wall time (set-up and solve) and a check against a closed form or an
equilibrium that can fail:

- ``cylinder-force``: a half-cylinder pressed onto a block by a pressure on its flat top (held by
  contact alone in the load direction, u_x = 0 in its plane of symmetry); Hertz's line contact
  half-width.
- ``cylinder-displacement``: the same pressed by a prescribed displacement of its top.
- ``press-friction``: a punch pressed by a prescribed displacement with Coulomb friction (mu 0.3),
  then dragged; the tangential force over the normal one is mu once it slides.
- ``sphere-p2``: a quadratic (P2, curved 10-node tetrahedra) hemisphere on a block; Hertz's radius.
- ``sphere-nlgeom``: the P1 hemisphere with a St.Venant-Kirchhoff bulk; Hertz's radius.
- ``sphere-rigid``: the hemisphere on a rigid plane (``RigidPlane``); Hertz's radius.
- ``free-punch``: a punch with no Dirichlet condition above a gap, under a pressure: the solve must
  stop with a ``ContactSolverError`` that names the body.

A cutback on a problem that converges without one at half the increment is a defect (issue 21).
Run: ``.venv/bin/python benchmarks/user_problems.py [--only NAME ...] [--linear-solver direct]
[--size 0.5]`` (serial or under mpirun); ``--linear-solver`` and ``--size`` measure the direct and
iterative solvers on these problem types at other sizes (LU fallbacks: iterative solves that
failed and were done again by MUMPS LU).
"""

from __future__ import annotations

import argparse
import logging
import math
import time
import typing

from mpi4py import MPI

import gmsh
import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import measures
from dolfinx_ntf.meshes import hertz, punch
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

E, NU = 210e3, 0.3  # MPa, steel
COMM = MPI.COMM_WORLD
#: Set by the command line: the solvers' ``linear_solver`` and a factor on every mesh size.
SETTINGS = {"linear_solver": "auto", "size": 1.0}


class _Fallbacks(logging.Handler):
    """Counts the iterative solves that the Newton solver did again with MUMPS LU."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.count = 0

    def emit(self, record: logging.LogRecord) -> None:
        self.count += "solving again with MUMPS LU" in record.getMessage()


FALLBACKS = _Fallbacks()
logging.getLogger("dolfinx_ntf").addHandler(FALLBACKS)
logging.getLogger("dolfinx_ntf").setLevel(logging.INFO)


def _solver(mesh: dolfinx.mesh.Mesh, problem: ntf.ContactProblem) -> ntf.ContactNewtonSolver:
    return ntf.ContactNewtonSolver(mesh.comm, problem, linear_solver=SETTINGS["linear_solver"])


class Row(typing.NamedTuple):
    name: str
    dofs: int
    iterations: list[int]
    cutbacks: int
    seconds: float
    check: str
    passed: bool


def _results_row(name: str, V, steps, start: float, check: str, passed: bool) -> Row:
    results = [result for step in steps for result in step]
    return Row(
        name,
        V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
        [r.iterations for r in results],
        sum(r.attempt - 1 for r in results),
        time.perf_counter() - start,
        check,
        passed,
    )


# Half-cylinder on a block (plane strain slice) ---
R_CYL, SLICE = 10.0, 1.0
BLOCK, CYLINDER = 1, 2
BLOCK_BOTTOM, BLOCK_TOP, CURVED, CYLINDER_TOP, ENDS = 11, 12, 13, 14, 15


def build_half_cylinder(size_fine: float = 0.2, size_coarse: float = 1.0) -> None:
    """A half-cylinder (axis along y, z from 0 to R) touching a block (z <= 0) along x = z = 0."""
    occ = gmsh.model.occ
    block = occ.addBox(-2 * R_CYL, 0, -2 * R_CYL, 4 * R_CYL, SLICE, 2 * R_CYL)
    cylinder = occ.addCylinder(0, 0, R_CYL, 0, SLICE, 0, R_CYL)
    upper = occ.addBox(-R_CYL, 0, R_CYL, 2 * R_CYL, SLICE, R_CYL)
    (half,), _ = occ.cut([(3, cylinder)], [(3, upper)])
    occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [block], BLOCK)
    gmsh.model.addPhysicalGroup(3, [half[1]], CYLINDER)
    groups: dict[int, list[int]] = {tag: [] for tag in (BLOCK_BOTTOM, BLOCK_TOP, CURVED)}
    groups.update({CYLINDER_TOP: [], ENDS: []})
    for volume, top_height in ((block, 0.0), (half[1], R_CYL)):
        for _, face in gmsh.model.getBoundary([(3, volume)], oriented=False):
            _, y, z = occ.getCenterOfMass(2, face)
            if abs(y) < 1e-9 or abs(y - SLICE) < 1e-9:
                groups[ENDS].append(face)
            elif abs(z - top_height) < 1e-9:
                groups[BLOCK_TOP if volume == block else CYLINDER_TOP].append(face)
            elif abs(z + 2 * R_CYL) < 1e-9:
                groups[BLOCK_BOTTOM].append(face)
            elif volume != block:
                groups[CURVED].append(face)
    for tag, faces in groups.items():
        gmsh.model.addPhysicalGroup(2, faces, tag)
    fields = gmsh.model.mesh.field
    distance = fields.add("MathEval")
    fields.setString(distance, "F", "Sqrt(x*x + z*z)")
    threshold = fields.add("Threshold")
    fields.setNumber(threshold, "InField", distance)
    fields.setNumber(threshold, "SizeMin", size_fine)
    fields.setNumber(threshold, "SizeMax", size_coarse)
    fields.setNumber(threshold, "DistMin", 0.2 * R_CYL)
    fields.setNumber(threshold, "DistMax", 0.6 * R_CYL)
    fields.setAsBackgroundMesh(threshold)
    for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{option}", 0)
    gmsh.model.mesh.generate(3)


def cylinder(by_force: bool) -> Row:
    """The half-cylinder pressed by a pressure (``by_force``) or a displacement of its top."""
    start = time.perf_counter()
    mesh, _, tags = mesh_from_gmsh(
        build_half_cylinder, COMM, size_fine=0.2 * SETTINGS["size"], size_coarse=SETTINGS["size"]
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ntf.small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    base = dolfinx.fem.locate_dofs_topological(V, 2, tags.find(BLOCK_BOTTOM))
    # u_x = 0 in the plane of symmetry x = 0 (else a frictionless cylinder may turn about its own
    # axis, a mechanism), u_y = 0 on the end faces (plane strain), the block bottom clamped.
    Vx, _ = V.sub(0).collapse()
    middle = dolfinx.fem.locate_dofs_geometrical((V.sub(0), Vx), lambda x: np.isclose(x[0], 0.0))
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(3), base, V),
        dolfinx.fem.dirichletbc(dolfinx.fem.Function(Vx), middle, V.sub(0)),
        ntf.component_bc(V, 1, tags.find(ENDS)),
    ]
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    Vz, _ = V.sub(2).collapse()
    top_uz = dolfinx.fem.Function(Vz)
    if by_force:
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
        F += pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(CYLINDER_TOP)
        load = ntf.Load(pressure, 14000.0 / (2 * R_CYL * SLICE))  # 14 kN on the slice
    else:
        top = dolfinx.fem.locate_dofs_topological((V.sub(2), Vz), 2, tags.find(CYLINDER_TOP))
        bcs.append(dolfinx.fem.dirichletbc(top_uz, top, V.sub(2)))
        load = ntf.Load(top_uz, -0.25)
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E, slope=10 * E)
    pair = ntf.ContactPair(
        ntf.FacetSurface(tags, CURVED),
        ntf.FacetSurface(tags, BLOCK_TOP),
        ntf.SurfaceInteraction(law),
        name="line",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    with _solver(mesh, problem) as solver:
        step = ntf.StaticStep(initial_increment=0.25, max_increment=0.25)
        results = ntf.run_steps(solver, [ntf.AnalysisStep(step, loads=[load])])
    force = ntf.contact_force(problem, "line")[2]
    base_force = ntf.reaction(problem, tags.find(BLOCK_BOTTOM))[2]
    e_star = E / (2 * (1 - NU**2))
    b = math.sqrt(4 * (force / SLICE) * R_CYL / (math.pi * e_star))
    nodes = dolfinx.fem.locate_dofs_topological(V, 2, tags.find(CURVED))
    nodes = nodes[nodes < V.dofmap.index_map.size_local]
    pressures, _, _ = ntf.ContactFields(problem).at_nodes(nodes)
    x = np.concatenate(COMM.allgather(np.abs(V.tabulate_dof_coordinates()[nodes, 0])))
    p = np.concatenate(COMM.allgather(pressures))
    b_fit, _ = measures.fit_hertz_profile(x, p, b, 2 * force / (math.pi * b))
    balance = abs(base_force / force - 1)
    check = f"Hertz b {b_fit / b - 1:+.2%}, F base/contact - 1 = {balance:.0e}"
    name = "cylinder-force" if by_force else "cylinder-displacement"
    return _results_row(
        name, V, results, start, check, abs(b_fit / b - 1) < 0.05 and balance < 1e-8
    )


# Frictional press and slide ---
def press_friction() -> Row:
    """A punch pressed 5 um into a block by its top, then its top dragged 20 um along x (mu 0.3)."""
    start = time.perf_counter()
    mesh, _, tags = mesh_from_gmsh(
        punch.build_punch,
        COMM,
        mesh_size_block=0.05 * SETTINGS["size"],
        mesh_size_punch=0.04 * SETTINGS["size"],
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ntf.small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    top_facets = tags.find(punch.PUNCH_TOP)
    bcs, moved = [], []
    for component in range(3):
        Vc, _ = V.sub(component).collapse()
        value = dolfinx.fem.Function(Vc)
        dofs = dolfinx.fem.locate_dofs_topological((V.sub(component), Vc), 2, top_facets)
        bcs.append(dolfinx.fem.dirichletbc(value, dofs, V.sub(component)))
        moved.append(value)
    base = dolfinx.fem.locate_dofs_topological(V, 2, tags.find(punch.BLOCK_BOTTOM))
    bcs.append(dolfinx.fem.dirichletbc(np.zeros(3), base, V))
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E)
    interaction = ntf.SurfaceInteraction(law, ntf.Friction(mu=0.3, stick_slope=law.slope / 100))
    pair = ntf.ContactPair(
        ntf.FacetSurface(tags, punch.PUNCH_BOTTOM),
        ntf.FacetSurface(tags, punch.BLOCK_TOP),
        interaction,
        name="press",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    with _solver(mesh, problem) as solver:
        steps = [
            ntf.AnalysisStep(loads=[ntf.Load(moved[2], -0.005)]),
            ntf.AnalysisStep(
                ntf.StaticStep(initial_increment=0.25, max_increment=0.25),
                loads=[ntf.Load(moved[0], 0.02)],
            ),
        ]
        results = ntf.run_steps(solver, steps)
    force = ntf.contact_force(problem, "press")
    ratio = abs(force[0]) / force[2]
    check = f"tangential/normal force {ratio:.5f} (mu 0.3)"
    passed = 0.99 * 0.3 < ratio <= 0.3 * (1 + 1e-9)  # Coulomb bounds it, sliding reaches it
    return _results_row("press-friction", V, results, start, check, passed)


# Hemisphere on a block or on a rigid plane ---
R_SPHERE, SPHERE_DISPLACEMENT = 25.0, 0.3


def sphere(kind: str) -> Row:
    """The quarter hemisphere pressed by its top: ``p2``, ``nlgeom`` or ``rigid``."""
    start = time.perf_counter()
    sizes = {key: value * R_SPHERE for key, value in hertz.COARSE.items()}
    sizes["size_fine"] *= SETTINGS["size"]
    sizes["size_coarse"] *= SETTINGS["size"]
    builder = hertz.build_hertz_sphere if kind == "rigid" else hertz.build_hertz
    order = 2 if kind == "p2" else 1
    mesh, _, tags = mesh_from_gmsh(builder, COMM, radius=R_SPHERE, order=order, **sizes)
    V = compat.vector_space(mesh, "Lagrange", order)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    if kind == "nlgeom":  # St.Venant-Kirchhoff: S = lambda tr(E) I + 2 mu E, P = F S
        lame, shear = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
        deformation = ufl.Identity(3) + ufl.grad(u)
        strain = 0.5 * (deformation.T * deformation - ufl.Identity(3))
        stress = lame * ufl.tr(strain) * ufl.Identity(3) + 2 * shear * strain
        F = ufl.inner(deformation * stress, ufl.grad(v)) * ufl.dx
    else:
        F = ufl.inner(ntf.small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    Vz, _ = V.sub(2).collapse()
    top_uz = dolfinx.fem.Function(Vz)
    top = dolfinx.fem.locate_dofs_topological((V.sub(2), Vz), 2, tags.find(hertz.SPHERE_TOP))
    bcs = [
        dolfinx.fem.dirichletbc(top_uz, top, V.sub(2)),
        ntf.component_bc(V, 0, tags.find(hertz.SYMMETRY_X)),
        ntf.component_bc(V, 1, tags.find(hertz.SYMMETRY_Y)),
    ]
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E, slope=10 * E)
    if kind == "rigid":
        master = ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
        e_star = E / (1 - NU**2)
    else:
        base = dolfinx.fem.locate_dofs_topological(V, 2, tags.find(hertz.BLOCK_BOTTOM))
        bcs.append(dolfinx.fem.dirichletbc(np.zeros(3), base, V))
        master = ntf.FacetSurface(tags, hertz.BLOCK_TOP)
        e_star = E / (2 * (1 - NU**2))
    pair = ntf.ContactPair(
        ntf.FacetSurface(tags, hertz.SPHERE_CONTACT),
        master,
        ntf.SurfaceInteraction(law),
        name="ball",
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    with _solver(mesh, problem) as solver:
        step = ntf.StaticStep(initial_increment=0.25, max_increment=0.25)
        results = ntf.run_steps(
            solver, [ntf.AnalysisStep(step, loads=[ntf.Load(top_uz, -SPHERE_DISPLACEMENT)])]
        )
    force = 4 * ntf.contact_force(problem, "ball")[2]
    top_force = -4 * ntf.reaction(problem, dofs=bcs[0])[2]
    a = (3 * force * R_SPHERE / (4 * e_star)) ** (1 / 3)
    nodes = dolfinx.fem.locate_dofs_topological(V, 2, tags.find(hertz.SPHERE_CONTACT))
    nodes = nodes[nodes < V.dofmap.index_map.size_local]
    pressures, _, _ = ntf.ContactFields(problem).at_nodes(nodes)
    X = V.tabulate_dof_coordinates()[nodes]
    r = np.concatenate(COMM.allgather(np.hypot(X[:, 0], X[:, 1])))
    p = np.concatenate(COMM.allgather(pressures))
    a_fit, _ = measures.fit_hertz_profile(r, p, a, 3 * force / (2 * math.pi * a**2))
    balance = abs(top_force / force - 1)
    check = f"Hertz a {a_fit / a - 1:+.2%}, F top/contact - 1 = {balance:.0e}"
    passed = abs(a_fit / a - 1) < 0.1 and balance < 1e-6
    return _results_row(f"sphere-{kind}", V, results, start, check, passed)


# A body nothing holds ---
def free_punch() -> Row:
    """The punch 0.05 above the block, no Dirichlet condition on it, a pressure on its top."""
    start = time.perf_counter()
    mesh, _, tags = mesh_from_gmsh(punch.build_punch, COMM, gap=0.05, **punch.COARSE)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    F = ufl.inner(ntf.small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    F += pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(punch.PUNCH_TOP)
    base = dolfinx.fem.locate_dofs_topological(V, 2, tags.find(punch.BLOCK_BOTTOM))
    law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E)
    pair = ntf.ContactPair(
        ntf.FacetSurface(tags, punch.PUNCH_BOTTOM),
        ntf.FacetSurface(tags, punch.BLOCK_TOP),
        ntf.SurfaceInteraction(law),
    )
    problem = ntf.ContactProblem(F, u, [pair], [dolfinx.fem.dirichletbc(np.zeros(3), base, V)])
    message = "no error"
    with _solver(mesh, problem) as solver:
        try:
            ntf.run_steps(solver, [ntf.AnalysisStep(loads=[ntf.Load(pressure, 10.0)])])
        except ntf.ContactSolverError as error:
            message = str(error)
    passed = "has no Dirichlet condition" in message
    check = "ContactSolverError naming the body" if passed else f"wrong outcome: {message}"
    return Row(
        "free-punch",
        V.dofmap.index_map.size_global * 3,
        [],
        0,
        time.perf_counter() - start,
        check,
        passed,
    )


PROBLEMS: dict[str, typing.Callable[[], Row]] = {
    "cylinder-force": lambda: cylinder(by_force=True),
    "cylinder-displacement": lambda: cylinder(by_force=False),
    "press-friction": press_friction,
    "sphere-p2": lambda: sphere("p2"),
    "sphere-nlgeom": lambda: sphere("nlgeom"),
    "sphere-rigid": lambda: sphere("rigid"),
    "free-punch": free_punch,
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=sorted(PROBLEMS), help="problems to run")
    parser.add_argument(
        "--linear-solver",
        default="auto",
        choices=("auto", "direct", "iterative"),
        help="the solvers' linear_solver (default: auto)",
    )
    parser.add_argument(
        "--size", type=float, default=1.0, help="factor on every mesh size (0.5: finer meshes)"
    )
    args = parser.parse_args(argv)
    SETTINGS.update(linear_solver=args.linear_solver, size=args.size)
    rows, fallbacks = [], []
    for name in args.only or PROBLEMS:
        start, before = time.perf_counter(), FALLBACKS.count
        try:
            rows.append(PROBLEMS[name]())
        except ntf.ContactConvergenceError as error:
            rows.append(Row(name, 0, [], 0, time.perf_counter() - start, str(error)[:200], False))
        fallbacks.append(FALLBACKS.count - before)
    if COMM.rank == 0:
        print(
            f"{COMM.size} process(es), linear_solver={args.linear_solver!r}, "
            f"mesh sizes x {args.size:g}"
        )
        print(
            "| problem | dofs | Newton iterations per increment | cutbacks | LU fallbacks "
            "| time [s] | check |"
        )
        print("|---|---|---|---|---|---|---|")
        for row, fallback in zip(rows, fallbacks):
            iterations = ", ".join(map(str, row.iterations)) or "-"
            verdict = "" if row.passed else " FAILED"
            print(
                f"| {row.name} | {row.dofs} | {iterations} | {row.cutbacks} | {fallback} | "
                f"{row.seconds:.1f} | {row.check}{verdict} |"
            )
    return 0 if all(row.passed for row in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
