"""Time the contact phases against the number of slave nodes (issue 2, §11).

Geometry: two thin flat plates of hexahedra stacked along z, touching at z = 0. The upper plate is
the slave body; its bottom face (the slave surface) is finer than the lower plate's top face (the
master surface), so the meshes do not match. Each plate has ``--layers`` layers of near-cubic
cells, so the number of dofs grows linearly with the number of slave nodes and 1e5 slave nodes fit
in memory and minutes. The lower plate's bottom is clamped; the upper plate's top is held in x and
y and loaded by a pressure, and the upper plate is given a small uniform penetration so that every
slave node carries a compressed spring.

With ``--dim 2`` the plates are two strips of triangles meeting along the line y = 0 (plane strain,
node-to-segment springs, docs/guide/two_d.md): the slave line has about ``--sizes`` nodes and the
strips ``--layers`` rows of near-square cells (split into two triangles each), so 1e5 slave nodes
with 2 layers make about 1e6 dofs, solved by MUMPS (a strip's fill is small; 2D problems switch
to GAMG only above ``--direct-max-dofs``, default 2e6 in 2D).

Every phase calls the library's own code path, timed with ``time.perf_counter`` over ``--repeat``
runs after one untimed warm-up run; the tables give the median:

- search: ``ContactProblem.pair`` (spring areas, master update, triangle walk, and the projection
  that gives the clearance for the creation cutoff);
- spring evaluation: ``ContactProblem.evaluate(tangent=True)`` (residual and tangent);
- insertion: ``ContactAssembler.add_to_matrix`` (with the final ``A.assemble()``) plus
  ``ContactAssembler.add_to_vector``;
- pattern build: ``ContactAssembler.create_matrix`` (bulk pattern plus contact couplings, new AIJ);
- Newton iteration: ``problem.form`` (no re-pairing: the search has its own column), ``problem.F``,
  ``problem.J`` and the linear solve by the ``ContactNewtonSolver``'s Krylov solver. The median
  leaves out the first solve, which also runs MUMPS's analysis (or GAMG's set-up).

The linear solver is MUMPS LU, the library default, up to ``--direct-max-dofs`` (400k); larger
problems (the 1e5 case, 892k dofs) use CG + GAMG with the rigid-body near-nullspace, and the table
says so. Measured there with MUMPS on 2 shared cores: 66 s per solve, 111 s with the analysis,
12 GB.

Under ``mpirun`` (docs/method.md §14) every phase is timed between barriers and the slowest
process's time is reported; the extra parallel phases are the gather of the surfaces (in the
set-up, ``ContactProblem`` construction: "gather") and the halo exchange of displacements
(``current_coordinates``: "exchange"); insertion then includes the off-process rows. A further
table compares the allgather of the master surface with its exchange by bounding boxes
(docs/method.md §14.8) at the same size: their set-up, and one pairing's update and walk on the
whole surface and on the patch. GAMG's
near-nullspace (one set of 6 rigid modes per plate, ``solvers.nullspace``) works on any number
of processes. Run::

    .venv/bin/python benchmarks/contact_phases.py                     # 1e3, 1e4, 1e5 slave nodes
    .venv/bin/python benchmarks/contact_phases.py --sizes 1e3 1e4 --repeat 5 --solver gamg
    mpirun -n 2 .venv/bin/python benchmarks/contact_phases.py --sizes 1e3 1e4
    .venv/bin/python benchmarks/contact_phases.py --dim 2 --layers 2   # 2D, up to about 1e6 dofs

The main table's last column is the contact share of a Newton iteration: the spring evaluation
and its insertion into the matrix and the vector, over the whole iteration.
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import statistics
import sys
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.contact.assembly import SpringBlocks
from dolfinx_ntf.contact.pairing import SEARCH_TOLERANCE, slave_areas
from dolfinx_ntf.contact.problem import LAST_REPAIRING_ITERATION
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.fem.surfaces import resolve_master
from dolfinx_ntf.kernels.search import NOT_HELD, MasterSurface
from dolfinx_ntf.parallel import master_exchange, surface_distribution
from dolfinx_ntf.parallel.halo import NodeHalo
from dolfinx_ntf.solvers.linear_solver import ITERATIVE_PETSC_OPTIONS, galerkin_products

__all__ = ["SOLVERS", "PlateMesh", "build_plates", "build_problem", "main", "report", "run_size"]

LOWER_BOTTOM, MASTER, SLAVE, UPPER_TOP = 11, 12, 13, 14
E, NU = 1000.0, 0.3
#: PETSc options: MUMPS LU (the library default), CG or GMRES with smoothed-aggregation AMG (with
#: the rigid-body modes of each plate as near-nullspace, which ContactNewtonSolver attaches).
SOLVERS: dict[str, dict[str, typing.Any]] = {
    "mumps": {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"},
    "gamg": {
        "ksp_type": "cg",
        "pc_type": "gamg",
        "ksp_rtol": 1e-8,
        "ksp_max_it": 1000,
        "mg_levels_ksp_type": "chebyshev",
        "mg_levels_pc_type": "jacobi",
    },
    "iterative": dict(ITERATIVE_PETSC_OPTIONS),  # the library's: GMRES + GAMG, rtol 1e-10
}
#: Timings of the two ways of distributing the master surface (parallel runs only).
_DISTRIBUTION = (
    "master_gather",
    "master_exchange",
    "update_whole",
    "update_patch",
    "locate_whole",
    "locate_patch",
)
#: Result keys that depend on the linear solver (no scaling exponent across solvers).
_SOLVER_KEYS = ("newton", "newton_solve")


class PlateMesh(typing.NamedTuple):
    """The two-plate mesh: facet tags and the local cells of the upper (slave) plate."""

    mesh: dolfinx.mesh.Mesh
    facet_tags: compat.MeshTags
    upper_cells: np.ndarray


def _box(
    origin: typing.Sequence[float], size: typing.Sequence[float], divisions: typing.Sequence[int]
) -> tuple[np.ndarray, np.ndarray]:
    """Points and hexahedra (dolfinx tensor vertex order) of a structured box."""
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, divisions)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    nx, ny, nz = divisions
    grid = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    i, j, k = (a.ravel() for a in grid)

    def node(di: int, dj: int, dk: int) -> np.ndarray:
        return ((k + dk) * (ny + 1) + j + dj) * (nx + 1) + i + di

    corners = [
        (0, 0, 0),
        (1, 0, 0),
        (0, 1, 0),
        (1, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (0, 1, 1),
        (1, 1, 1),
    ]
    return points, np.column_stack([node(*c) for c in corners])


def _strip(
    origin: typing.Sequence[float], size: typing.Sequence[float], divisions: typing.Sequence[int]
) -> tuple[np.ndarray, np.ndarray]:
    """Points and triangles (each rectangle of a structured grid cut along a diagonal)."""
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, divisions)]
    y, x = np.meshgrid(axes[1], axes[0], indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel()])
    nx, ny = divisions
    j, i = (a.ravel() for a in np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij"))
    corner = j * (nx + 1) + i
    a, b, c, d = corner, corner + 1, corner + nx + 1, corner + nx + 2
    return points, np.vstack([np.column_stack([a, b, d]), np.column_stack([a, d, c])])


def build_plates(
    slave_nodes: int,
    *,
    layers: int = 1,
    master_ratio: float = 0.7,
    dim: int = 3,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> PlateMesh:
    """Two touching plates; the upper plate's bottom face has about ``slave_nodes`` nodes.

    Args:
        slave_nodes: Target number of slave nodes: (n+1)^2 with n slave divisions per side in 3D,
            n+1 along the slave line in 2D.
        layers: Cell layers through the thickness of each plate (cells are near-cubic).
        master_ratio: Master divisions per side relative to the slave's (< 1: coarser master).
        dim: 3 (hexahedra) or 2 (triangles, two strips meeting along y = 0).
        comm: Communicator (the mesh is built on rank 0).
    """
    if dim not in (2, 3):
        raise ValueError(f"dim = {dim}: expected 2 or 3")
    if slave_nodes < 4:
        raise ValueError(f"slave_nodes = {slave_nodes}: need at least 4")
    if layers < 1:
        raise ValueError(f"layers = {layers}: need at least 1")
    if not master_ratio > 0.0:
        raise ValueError(f"master_ratio = {master_ratio}: must be positive")
    n = max(1, (round(math.sqrt(slave_nodes)) if dim == 3 else slave_nodes) - 1)
    m = max(1, round(master_ratio * n))
    inset = 0.01  # the slave plate lies inside the master's edges
    hs, hm = (1.0 - 2 * inset) / n, 1.0 / m
    if dim == 3:
        p1, c1 = _box((0.0, 0.0, -layers * hm), (1.0, 1.0, layers * hm), (m, m, layers))
        p2, c2 = _box(
            (inset, inset, 0.0), (1.0 - 2 * inset, 1.0 - 2 * inset, layers * hs), (n, n, layers)
        )
    else:
        p1, c1 = _strip((0.0, -layers * hm), (1.0, layers * hm), (m, layers))
        p2, c2 = _strip((inset, 0.0), (1.0 - 2 * inset, layers * hs), (n, layers))
    points, cells = np.vstack([p1, p2]), np.vstack([c1, c2 + p1.shape[0]])
    if comm.rank != 0:
        points, cells = np.empty((0, dim)), np.empty((0, cells.shape[1]), dtype=np.int64)
    domain = compat.coordinate_element("hexahedron" if dim == 3 else "triangle", 1, gdim=dim)
    mesh = compat.create_mesh(comm, cells.astype(np.int64), points, domain)

    tdim = dim
    num_cells = mesh.topology.index_map(tdim).size_local
    cells_local = np.arange(num_cells, dtype=np.int32)
    upper = dolfinx.mesh.compute_midpoints(mesh, tdim, cells_local)[:, dim - 1] > 0.0
    mesh.topology.create_connectivity(tdim - 1, tdim)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    f_to_c = mesh.topology.connectivity(tdim - 1, tdim)
    z = dolfinx.mesh.compute_midpoints(mesh, tdim - 1, exterior)[:, dim - 1]
    in_upper = upper[f_to_c.array[f_to_c.offsets[exterior]]]
    tol = 1e-3 * min(hs, hm)
    values = np.zeros(exterior.size, dtype=np.int32)
    values[~in_upper & np.isclose(z, -layers * hm, atol=tol)] = LOWER_BOTTOM
    values[~in_upper & np.isclose(z, 0.0, atol=tol)] = MASTER
    values[in_upper & np.isclose(z, 0.0, atol=tol)] = SLAVE
    values[in_upper & np.isclose(z, layers * hs, atol=tol)] = UPPER_TOP
    keep = values > 0
    order = np.argsort(exterior[keep])
    tags = dolfinx.mesh.meshtags(mesh, tdim - 1, exterior[keep][order], values[keep][order])
    return PlateMesh(mesh, tags, np.flatnonzero(upper).astype(np.int32))


def build_problem(
    plates: PlateMesh, solver: str, *, options_prefix: str = "bench_", penetration: float = 1e-4
) -> tuple[ntf.ContactProblem, ntf.ContactNewtonSolver]:
    """The contact problem on the plates, paired at a uniform penetration, and its Newton solver.

    Args:
        plates: Mesh and tags from :func:`build_plates`.
        solver: Key of :data:`SOLVERS`.
        options_prefix: PETSc prefix of the Krylov solver.
        penetration: Downward displacement of the upper plate, relative to the slave cell size.
    """
    if solver not in SOLVERS:
        raise ValueError(f"solver = {solver!r}: expected one of {sorted(SOLVERS)}")
    mesh, ft = plates.mesh, plates.facet_tags
    dim = mesh.topology.dim
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    sigma = small_strain_stress(u, E, NU)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    pressure = dolfinx.fem.Constant(mesh, 1.0)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx + pressure * ufl.inner(
        ufl.FacetNormal(mesh), v
    ) * ds(UPPER_TOP)
    clamp = dolfinx.fem.locate_dofs_topological(V, dim - 1, ft.find(LOWER_BOTTOM))
    top = ft.find(UPPER_TOP)
    bcs = [dolfinx.fem.dirichletbc(np.zeros(dim), clamp, V)]
    bcs += [component_bc(V, i, top) for i in range(dim - 1)]  # the top slides along the normal
    interaction = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E))
    pair = ntf.ContactPair(ntf.FacetSurface(ft, SLAVE), ntf.FacetSurface(ft, MASTER), interaction)
    problem = ntf.ContactProblem(F, u, [pair], bcs)

    # Press the upper plate down uniformly so that every slave node is in compression.
    slave_faces = problem.states[0].slave.faces.faces
    x = problem.current_coordinates()
    edges = np.linalg.norm(x[slave_faces[:, 1]] - x[slave_faces[:, 0]], axis=1)
    h = mesh.comm.allreduce(edges.sum()) / mesh.comm.allreduce(edges.size)  # any process count
    mesh.topology.create_connectivity(dim, dim)  # dolfinx 0.9 needs it to locate dofs by cell
    upper = dolfinx.fem.locate_dofs_topological(V, dim, plates.upper_cells)
    u.x.array.reshape(-1, dim)[upper, dim - 1] = -penetration * h
    u.x.scatter_forward()
    problem.begin_increment(1.0)

    newton = ntf.ContactNewtonSolver(
        mesh.comm, problem, petsc_options=SOLVERS[solver], options_prefix=options_prefix
    )
    return problem, newton  # a GAMG preconditioner gets the per-body rigid modes (nullspace.py)


def timed(fn: typing.Callable[[], typing.Any], repeat: int) -> float:
    """Median wall time of ``repeat`` calls of ``fn``, after one untimed warm-up call.

    In parallel: between barriers, the slowest process's time.
    """
    comm = MPI.COMM_WORLD
    fn()
    times = []
    for _ in range(repeat):
        comm.barrier()
        start = time.perf_counter()
        fn()
        times.append(comm.allreduce(time.perf_counter() - start, op=MPI.MAX))
    return statistics.median(times)


def _print(*args: typing.Any, **kwargs: typing.Any) -> None:
    """``print`` on rank 0 only."""
    if MPI.COMM_WORLD.rank == 0:
        print(*args, **kwargs)


def _time_search(problem: ntf.ContactProblem, repeat: int, out: dict[str, typing.Any]) -> None:
    """The whole pairing, then its parts (the calls ``ContactProblem.pair`` makes)."""
    state = problem.states[0]
    out["search"] = timed(problem.pair, repeat)
    out["springs"] = problem.total_springs
    coords = problem.current_coordinates()
    nodes = state.slave.nodes
    out["areas"] = timed(lambda: slave_areas(state.slave, coords), repeat)
    areas = slave_areas(state.slave, coords)
    out["update"] = timed(lambda: state.master.update(coords), repeat)
    points = coords[nodes]
    tolerances = np.where(areas > 0, SEARCH_TOLERANCE * np.sqrt(areas), 0.0)
    out["locate"] = timed(lambda: state.master.locate(points, tolerances), repeat)
    out["gap"] = max(out["search"] - out["areas"] - out["update"] - out["locate"], 0.0)


def _time_master_distribution(
    problem: ntf.ContactProblem, repeat: int, out: dict[str, typing.Any]
) -> None:
    """Both ways of giving each process its master surface (docs/method.md §14.1, §14.8).

    The allgather of the whole surface with the build of its search surface, against the
    exchange by bounding boxes with the build of the patch; then one pairing's update and walk on
    each (what ``pair`` runs), and the faces each process holds (largest over the processes).
    """
    comm = MPI.COMM_WORLD
    halo, state = problem.halo, problem.states[0]
    if halo is None or isinstance(state.master, master_exchange.MasterPatch):
        return  # serial, or the problem's own halo lacks the whole surface
    if problem.u.function_space.mesh.topology.dim == 2:
        return  # a 2D master is always gathered whole (docs/method.md §14.11)
    own = resolve_master(problem.u.function_space, state.pair.master, what="master")
    coords = problem.current_coordinates()
    nodes = state.slave.nodes

    def gathered() -> MasterSurface:
        g, x, _ = surface_distribution._gather_faces(halo, own, "master")
        faces = halo.local(g, x).astype(np.int32)
        return MasterSurface(own.face_type, faces, coords=halo.reference)

    def exchanged() -> master_exchange.MasterPatch:
        return master_exchange.MasterPatch(halo, own, nodes, coords, "master")

    out["master_gather"] = timed(gathered, repeat)
    out["master_exchange"] = timed(exchanged, repeat)
    whole, patch = gathered(), exchanged()
    areas = slave_areas(state.slave, coords)
    points = coords[nodes]
    tolerances = np.where(areas > 0, SEARCH_TOLERANCE * np.sqrt(areas), 0.0)
    for key, surface in (("whole", whole), ("patch", patch)):
        out[f"update_{key}"] = timed(lambda s=surface: s.update(coords), repeat)
        out[f"locate_{key}"] = timed(lambda s=surface: s.locate(points, tolerances), repeat)
    faces, found = whole.locate(points, tolerances), patch.locate(points, tolerances)
    unresolved = found == NOT_HELD
    same = np.all(
        _global_faces(whole.faces, faces, halo) == _global_faces(patch.faces.faces, found, halo),
        axis=1,
    )
    out["patch_unresolved"] = comm.allreduce(int(np.count_nonzero(unresolved)))
    out["patch_differs"] = comm.allreduce(int(np.count_nonzero(~unresolved & ~same)))
    out["faces_whole"] = whole.num_faces
    searched = 0 if patch.surface is None else patch.surface.num_faces  # core and ring
    out["faces_patch"] = comm.allreduce(searched, op=MPI.MAX)


def _global_faces(table: np.ndarray, faces: np.ndarray, halo: NodeHalo) -> np.ndarray:
    """Sorted global nodes of each found face (rows of -1 where none)."""
    g = np.sort(halo.global_nodes[table[np.maximum(faces, 0)]], axis=1)
    return np.where(faces[:, None] >= 0, g, -1)


def _time_newton(
    problem: ntf.ContactProblem,
    newton: ntf.ContactNewtonSolver,
    b: PETSc.Vec,
    repeat: int,
    out: dict[str, typing.Any],
) -> None:
    """One Newton iteration without re-pairing: form, F, J, linear solve (u is not updated)."""
    x, A = compat.petsc_vector(problem.u), problem.matrix
    ksp = newton.krylov_solver
    dx = A.createVecRight()
    parts: dict[str, list[float]] = {"form": [], "F": [], "J": [], "solve": []}
    for _ in range(repeat + 1):  # the first solve includes MUMPS's analysis / GAMG's set-up
        problem.iteration = LAST_REPAIRING_ITERATION  # past the re-pairing schedule
        t0 = time.perf_counter()
        problem.form(x)
        t1 = time.perf_counter()
        problem.F(x, b)
        t2 = time.perf_counter()
        problem.J(x, A)
        t3 = time.perf_counter()
        ksp.setOperators(A)
        with galerkin_products(ksp):  # as ContactNewtonSolver.solve does
            ksp.solve(b, dx)
        t4 = time.perf_counter()
        if ksp.getConvergedReason() <= 0:
            raise RuntimeError(f"linear solve failed: KSP reason {ksp.getConvergedReason()}")
        for key, t in zip(parts, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            parts[key].append(t)
    totals = [sum(p[i] for p in parts.values()) for i in range(repeat + 1)]
    comm = MPI.COMM_WORLD  # the slowest process's times
    out["newton"] = comm.allreduce(statistics.median(totals[1:]), op=MPI.MAX)
    out["first_solve"] = comm.allreduce(parts["solve"][0], op=MPI.MAX)
    for key, values in parts.items():
        out[f"newton_{key}"] = comm.allreduce(statistics.median(values[1:]), op=MPI.MAX)
    out["ksp_iterations"] = ksp.getIterationNumber()


def run_size(
    slave_nodes: int,
    *,
    repeat: int,
    solver: str,
    layers: int = 1,
    master_ratio: float = 0.7,
    dim: int = 3,
    log: typing.Callable[[str], None] = _print,
) -> dict[str, typing.Any]:
    """Build the plates for one size and time every phase; returns median times (s) and counts."""
    comm = MPI.COMM_WORLD
    t0 = time.perf_counter()
    plates = build_plates(slave_nodes, layers=layers, master_ratio=master_ratio, dim=dim)
    comm.barrier()
    t1 = time.perf_counter()
    problem, newton = build_problem(plates, solver, options_prefix=f"bench{slave_nodes}_")
    setup = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
    state = problem.states[0]
    dofs = dim * problem.u.function_space.dofmap.index_map.size_global
    out: dict[str, typing.Any] = {
        "slave_nodes": comm.allreduce(int(state.slave.nodes.size)),
        "dofs": dofs,
        "solver": solver,
        "setup": setup,
        "problem_setup": comm.allreduce(time.perf_counter() - t1, op=MPI.MAX),
    }
    log(
        f"  {out['slave_nodes']} slave nodes, {state.master_faces.faces.shape[0]} master faces, "
        f"{dofs} dofs, {problem.total_springs} springs; set-up {setup:.1f} s"
    )
    out["exchange"] = timed(problem.current_coordinates, repeat)

    _time_search(problem, repeat, out)
    out["evaluate"] = timed(lambda: problem.evaluate(tangent=True), repeat)

    # Insertion into an assembled Jacobian (as left by problem.J) and into a residual vector.
    blocks = problem.evaluate(tangent=True)
    x, A = compat.petsc_vector(problem.u), problem.matrix
    problem.iteration = LAST_REPAIRING_ITERATION
    problem.form(x)
    problem.J(x, A)
    b = compat.create_vector(problem.L)
    assembler = problem.assembler

    def insert_matrix() -> None:
        assembler.add_to_matrix(A, blocks)
        A.assemble()

    out["insert_mat"] = timed(insert_matrix, repeat)
    out["insert_vec"] = timed(lambda: assembler.add_to_vector(b, blocks), repeat)
    out["insert"] = out["insert_mat"] + out["insert_vec"]
    out["has_pattern"] = timed(lambda: assembler.has_pattern(blocks), repeat)

    # Pattern build as ensure_matrix does it on a rebuild; dolfinx's bulk-only matrix for scale.
    pattern_blocks = [SpringBlocks(s.element_nodes, s.element_nodes) for s in problem.states]
    out["pattern"] = timed(lambda: assembler.create_matrix(pattern_blocks).destroy(), repeat)
    out["pattern_bulk"] = timed(
        lambda: dolfinx.fem.petsc.create_matrix(problem.a).destroy(), repeat
    )

    _time_master_distribution(problem, repeat, out)
    _time_newton(problem, newton, b, repeat, out)
    return out


def _format_table(header: typing.Sequence[str], rows: typing.Sequence[typing.Sequence[str]]) -> str:
    """A Markdown table with right-aligned columns."""
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    lines = [
        "| " + " | ".join(h.rjust(w) for h, w in zip(header, widths)) + " |",
        "|" + "|".join("-" * (w + 2) for w in widths) + "|",
    ]
    lines += ["| " + " | ".join(c.rjust(w) for c, w in zip(r, widths)) + " |" for r in rows]
    return "\n".join(lines)


def _s(t: float) -> str:
    """Seconds with three significant digits."""
    return f"{t:.3g}" if t >= 1e-3 else f"{t:.2e}"


def _exponents(results: typing.Sequence[dict], keys: typing.Sequence[str]) -> list[list[str]]:
    """Local scaling exponents log(t2/t1)/log(n2/n1) between successive sizes (1 = linear)."""
    rows = []
    for r1, r2 in itertools.pairwise(results):
        ratio = math.log(r2["slave_nodes"] / r1["slave_nodes"])
        same_solver = r1["solver"] == r2["solver"]
        row = [f"{r1['slave_nodes']} -> {r2['slave_nodes']}"]
        for k in keys:
            ok = r1[k] > 0 and r2[k] > 0 and (same_solver or k not in _SOLVER_KEYS)
            row.append(f"{math.log(r2[k] / r1[k]) / ratio:.2f}" if ok else "-")
        rows.append(row)
    return rows


def contact_share(result: dict[str, typing.Any]) -> float:
    """The springs' part of a Newton iteration: their evaluation and insertion, over the whole."""
    return (result["evaluate"] + result["insert"]) / result["newton"]


def report(results: typing.Sequence[dict], repeat: int) -> str:
    """The main table, the breakdown and the scaling exponents as text."""
    main_keys = ["search", "evaluate", "insert", "pattern", "newton"]
    header = [
        "slave nodes",
        "springs",
        "search (s)",
        "spring eval (s)",
        "insertion (s)",
        "pattern build (s)",
        "Newton iteration (s)",
        "dofs",
        "solver",
        "contact share",
    ]
    rows = []
    for r in results:
        its = f" ({r['ksp_iterations']} its)" if r["solver"] != "mumps" else ""
        solver = r["solver"] + its
        rows.append(
            [str(r["slave_nodes"]), str(r["springs"])]
            + [_s(r[k]) for k in main_keys]
            + [str(r["dofs"]), solver, f"{contact_share(r):.1%}"]
        )
    text = [f"Median of {repeat} runs (s).", _format_table(header, rows), ""]

    parts = [
        "problem_setup",
        "exchange",
        "areas",
        "update",
        "locate",
        "gap",
        "insert_mat",
        "has_pattern",
        "insert_vec",
        "pattern_bulk",
        "newton_form",
        "newton_F",
        "newton_J",
        "newton_solve",
        "first_solve",
    ]
    header = [
        "slave nodes",
        "ContactProblem set-up (gather)",
        "exchange",
        "areas",
        "master update",
        "locate",
        "gap+cutoff",
        "add_to_matrix+assemble",
        "(has_pattern)",
        "add_to_vector",
        "dolfinx bulk create_matrix",
        "form",
        "F",
        "J",
        "solve",
        "first solve",
    ]
    rows = [[str(r["slave_nodes"])] + [_s(r[k]) for k in parts] for r in results]
    text += [
        "Breakdown (s): search = areas + master update + locate + gap+cutoff (the projection "
        "in pair);",
        "Newton iteration = form + F + J + solve; J includes add_to_matrix; 'first solve' "
        "includes MUMPS's analysis or GAMG's set-up.",
        _format_table(header, rows),
        "",
    ]
    rows = [
        [str(r["slave_nodes"]), str(r["faces_whole"]), str(r["faces_patch"])]
        + [_s(r[k]) for k in _DISTRIBUTION]
        + [f"{r['patch_unresolved']} / {r['patch_differs']}"]
        for r in results
        if "master_gather" in r
    ]
    if rows:
        text += [
            "Master surface per process (docs/method.md §14.1, §14.8): the whole surface "
            "allgathered, or the patch exchanged by bounding boxes (faces: the most any process "
            "searches, core and ring); set-up of each (with its search surface), then one "
            "pairing's master update and walk on each; slave nodes the patch could not tell / "
            "told differently.",
            _format_table(
                [
                    "slave nodes",
                    "faces (whole)",
                    "faces (patch)",
                    "allgather",
                    "exchange",
                    "update (whole)",
                    "update (patch)",
                    "locate (whole)",
                    "locate (patch)",
                    "unresolved / differ",
                ],
                rows,
            ),
            "",
        ]
    if len(results) > 1:
        keys = [
            *main_keys,
            "locate",
            "insert_mat",
            "has_pattern",
            "newton_F",
            "newton_J",
            "newton_solve",
        ]
        text += [
            "Scaling exponents between sizes (time ~ slave_nodes^k; 1 = linear; '-' where "
            "the solver differs):",
            _format_table(["sizes", *keys], _exponents(results, keys)),
        ]
    return "\n".join(text)


def main(argv: typing.Sequence[str] | None = None) -> int:
    """Command line entry point."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--sizes",
        type=float,
        nargs="+",
        default=[1e3, 1e4, 1e5],
        help="target numbers of slave nodes (default: 1e3 1e4 1e5)",
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="timed repetitions per phase; the median is reported (default 3)",
    )
    parser.add_argument(
        "--solver",
        choices=sorted(SOLVERS),
        default="mumps",
        help="linear solver of the Newton iteration (default: mumps)",
    )
    parser.add_argument(
        "--direct-max-dofs",
        type=int,
        default=None,
        help="with --solver mumps, sizes with more dofs use cg+gamg instead "
        "(default 400000 in 3D, 2000000 in 2D; 0 = never switch)",
    )
    parser.add_argument(
        "--dim", type=int, choices=(2, 3), default=3, help="3D plates or 2D strips (default 3)"
    )
    parser.add_argument(
        "--layers", type=int, default=1, help="cell layers through each plate (default 1)"
    )
    parser.add_argument(
        "--master-ratio",
        type=float,
        default=0.7,
        help="master divisions relative to the slave's (default 0.7)",
    )
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error(f"--repeat {args.repeat}: need at least 1")
    if args.direct_max_dofs is None:
        args.direct_max_dofs = 400_000 if args.dim == 3 else 2_000_000
    if any(size < 4 for size in args.sizes):
        parser.error(f"--sizes {args.sizes}: every size must be at least 4 slave nodes")

    results = []
    start = time.perf_counter()
    load = os.getloadavg()[0]
    for size in args.sizes:
        target = round(size)
        master_share = args.master_ratio ** (args.dim - 1)
        dofs = int(args.dim * (args.layers + 1) * target * (1 + master_share))  # both plates
        solver = args.solver
        if solver == "mumps" and args.direct_max_dofs and dofs > args.direct_max_dofs:
            solver = "gamg"
            _print(
                f"{target} slave nodes: about {dofs} dofs > --direct-max-dofs "
                f"{args.direct_max_dofs}: the Newton iteration uses cg+gamg instead of MUMPS"
            )
        _print(f"{target} slave nodes ({solver}) ...", flush=True)
        results.append(
            run_size(
                target,
                repeat=args.repeat,
                solver=solver,
                layers=args.layers,
                master_ratio=args.master_ratio,
                dim=args.dim,
            )
        )
    _print()
    _print(report(results, args.repeat))
    version = ".".join(map(str, PETSc.Sys.getVersion()))
    _print(
        f"\nTotal {time.perf_counter() - start:.0f} s; {args.dim}D, layers {args.layers}, "
        f"master ratio {args.master_ratio}, PETSc {version}, {MPI.COMM_WORLD.size} process(es); "
        f"1-min load "
        f"average {load:.1f} at start, "
        f"{os.getloadavg()[0]:.1f} at end (other processes on the machine inflate the times)."
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
