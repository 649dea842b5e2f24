"""Incompatible-mode hexahedra in the Python API (``IncompatibleModes``, docs/method.md §22).

A cantilever of 8 x 1 x 2 hexahedra (its inner nodes moved off the grid) under an end traction,
solved by a ``ContactProblem`` without pairs whose element terms hold the condensed modes, is
compared node by node with a serial numpy solution of the same mesh assembled from the kernel's
element matrices (each process looks its owned nodes up by their coordinates), on 1 and 2
processes. The trilinear cells alone lock: the tip moves much less.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.kernels.incompatible_modes import condensed_stiffness

pytestmark = pytest.mark.mpi

E, NU, LENGTH, HEIGHT, DIVISIONS = 1000.0, 0.3, 10.0, 1.0, (8, 1, 2)
MU, LMBDA = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))


def _grid() -> tuple[np.ndarray, np.ndarray]:
    """Points (P, 3) and hexahedra (C, 8) in dolfinx's vertex order; inner x nodes moved."""
    nx, ny, nz = DIVISIONS
    x, y, z = np.meshgrid(
        np.linspace(0, LENGTH, nx + 1), np.linspace(0, 1, ny + 1), np.linspace(0, 1, nz + 1),
        indexing="ij",
    )  # fmt: skip
    points = np.stack([x, y, z], axis=-1)
    shift = np.random.default_rng(3).uniform(-0.15, 0.15, points.shape)
    points[1:-1] += shift[1:-1] * [LENGTH / nx, 1.0 / ny, 1.0 / nz]
    ids = np.arange(points[..., 0].size).reshape(nx + 1, ny + 1, nz + 1)
    cells = [
        [ids[i + a, j + b, k + c] for c in (0, 1) for b in (0, 1) for a in (0, 1)]
        for i in range(nx)
        for j in range(ny)
        for k in range(nz)
    ]
    return points.reshape(-1, 3), np.array(cells, dtype=np.int64)


def _reference(points: np.ndarray, cells: np.ndarray, taylor: bool) -> np.ndarray:
    """(P, 3) numpy solution: the kernel's matrices assembled, clamped at x = 0, end traction."""
    K = condensed_stiffness(points[cells], MU, LMBDA, taylor=taylor)
    dofs = (3 * cells[:, :, None] + np.arange(3)).reshape(-1, 24)
    A = np.zeros((points.size, points.size))
    np.add.at(A, (dofs[:, :, None], dofs[:, None, :]), K)
    f = np.zeros(points.size)
    tip = np.isclose(points[:, 0], LENGTH)
    # traction 1/HEIGHT in z on the unit-width end face: each of its quads gives a quarter of its
    # force to each corner (the end face is a regular 1 x 2 grid)
    counts = np.zeros(points.shape[0])
    for cell in cells:
        face = cell[[1, 3, 5, 7]]  # dolfinx vertices with a = 1: the cell's x = max face
        if np.all(tip[face]):
            counts[face] += 1.0
    area = 1.0 / (DIVISIONS[1] * DIVISIONS[2])
    f[2::3] = counts * area / 4 / HEIGHT
    free = np.flatnonzero(~np.repeat(np.isclose(points[:, 0], 0.0), 3))
    u = np.zeros(points.size)
    u[free] = np.linalg.solve(A[np.ix_(free, free)], f[free])
    return u.reshape(-1, 3)


def _solve(
    points: np.ndarray, cells: np.ndarray, taylor: bool | None
) -> tuple[dolfinx.fem.Function, np.ndarray]:
    """The dolfinx solution and the clamp's reaction; ``taylor`` None: no modes (trilinear)."""
    comm = MPI.COMM_WORLD
    if comm.rank != 0:
        points, cells = np.zeros((0, 3)), np.zeros((0, 8), np.int64)
    mesh = compat.create_mesh(comm, cells, points, compat.coordinate_element("hexahedron"))
    V = compat.vector_space(mesh)
    u = dolfinx.fem.Function(V)
    fixed = dolfinx.fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 0.0))
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), fixed, V)]
    facets = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[0], LENGTH))
    tags = dolfinx.mesh.meshtags(mesh, 2, facets, np.full(facets.size, 1, np.int32))
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 2})
    eps = ufl.sym(ufl.grad(u))
    sigma = 2 * MU * eps + LMBDA * ufl.tr(eps) * ufl.Identity(3)
    v = ufl.TestFunction(V)
    F = ufl.inner(sigma, ufl.grad(v)) * dx - v[2] / HEIGHT * ds(1)
    problem = ntf.ContactProblem(F, u, [], bcs)
    if taylor is not None:
        problem.element_terms.append(ntf.IncompatibleModes(V, MU, LMBDA, taylor=taylor))
    solver = ntf.ContactNewtonSolver(comm, problem)
    ntf.StaticStep(fixed=True, initial_increment=1.0).run(solver, u)
    support = ntf.reaction(problem, dofs=bcs)
    problem.destroy()
    return u, support


def _at_owned_nodes(u: dolfinx.fem.Function, points: np.ndarray, values: np.ndarray):
    """This process's owned node values of ``u`` and ``values`` at the same coordinates."""
    V = u.function_space
    owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:owned]
    distance = np.linalg.norm(x[:, None, :] - points[None, :, :], axis=2)
    nearest = distance.argmin(axis=1)
    assert np.all(distance[np.arange(owned), nearest] < 1e-12)
    return u.x.array[: 3 * owned].reshape(-1, 3), values[nearest]


@pytest.mark.parametrize("taylor", [True, False], ids=["taylor", "ccx"])
def test_cantilever_node_by_node(taylor: bool) -> None:
    """The dolfinx solution equals the numpy one at every node, on any number of processes."""
    points, cells = _grid()
    reference = _reference(points, cells, taylor)
    u, support = _solve(points, cells, taylor)
    # the clamp carries the load only with the modes' forces at its (Dirichlet) rows
    np.testing.assert_allclose(support, [0.0, 0.0, -1.0], atol=1e-9)
    ours, theirs = _at_owned_nodes(u, points, reference)
    scale = np.abs(reference).max()
    assert MPI.COMM_WORLD.allreduce(np.abs(ours - theirs).max(initial=0.0), MPI.MAX) < 1e-9 * scale
    # the tip near beam theory, 4 P L^3 / (E b h^3) + 1.2 P L / (G A) = 4.03 with P = 1, b = h = 1
    # (measured 3.66 with Taylor's modes, 3.67 with ccx's, 3.91 on the regular grid: the coarse
    # distorted cells and the clamp's Poisson constraint stiffen)
    assert scale == pytest.approx(4 * LENGTH**3 / E + 1.2 * LENGTH * 2 * (1 + NU) / E, rel=0.1)


def test_trilinear_cells_lock() -> None:
    """Without the modes the same beam is far stiffer (shear locking)."""
    points, cells = _grid()
    plain, _ = _solve(points, cells, None)
    tip = MPI.COMM_WORLD.allreduce(np.abs(plain.x.array).max(initial=0.0), MPI.MAX)
    assert tip < 0.75 * np.abs(_reference(points, cells, True)).max()


def test_wrong_spaces_are_refused() -> None:
    """Tetrahedra or a degree-2 space raise a ValueError naming what was found."""
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    with pytest.raises(ValueError, match="hexahedra, got tetrahedron cells"):
        ntf.IncompatibleModes(compat.vector_space(mesh), MU, LMBDA)
    hexes = dolfinx.mesh.create_unit_cube(
        MPI.COMM_WORLD, 1, 1, 1, cell_type=dolfinx.mesh.CellType.hexahedron
    )
    with pytest.raises(ValueError, match="degree 2"):
        ntf.IncompatibleModes(compat.vector_space(hexes, "Lagrange", 2), MU, LMBDA)
