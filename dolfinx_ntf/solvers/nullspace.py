"""Rigid-body near-nullspace per body, for algebraic multigrid on contact problems.

Smoothed-aggregation AMG (PETSc's GAMG) needs the near-nullspace of the operator: for elasticity
the six rigid-body modes. Bodies that touch only through contact springs are separate bodies: each
gets its own six modes, zero outside it (docs/method.md §14.7). Bodies are the connected components
of the mesh (cells sharing a node), found across processes.

:func:`connected_components` and :func:`rigid_body_modes` are numpy/scipy (the latter takes a
communicator for its sums); :func:`body_numbers` and :func:`near_nullspace` are the dolfinx glue.
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph

import dolfinx.fem

from dolfinx_ntf import compat

__all__ = ["body_numbers", "connected_components", "near_nullspace", "rigid_body_modes"]

#: Rigid-body modes in 3D: three translations and three rotations.
MODES_PER_BODY = 6


def connected_components(
    cell_nodes: np.ndarray, num_nodes: int, links: np.ndarray | None = None
) -> tuple[int, np.ndarray]:
    """Connected components of ``num_nodes`` nodes joined by cells (and by extra ``links``).

    Args:
        cell_nodes: Node numbers of each cell, shape (cells, nodes per cell).
        num_nodes: Number of nodes (nodes in no cell are components of their own).
        links: Extra pairs of joined nodes, shape (pairs, 2).

    Returns:
        The number of components and the component of every node (numbered from 0).
    """
    cell_nodes = np.asarray(cell_nodes, dtype=np.int64)
    if cell_nodes.size == 0:
        cell_nodes = np.zeros((0, 1), dtype=np.int64)
    elif cell_nodes.ndim != 2:
        cell_nodes = cell_nodes.reshape(cell_nodes.shape[0], -1)
    first = np.repeat(cell_nodes[:, 0], cell_nodes.shape[1])  # a star per cell is enough
    rows, cols = [first], [cell_nodes.ravel()]
    if links is not None and len(links):
        links = np.asarray(links, dtype=np.int64).reshape(-1, 2)
        rows.append(links[:, 0])
        cols.append(links[:, 1])
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    graph = scipy.sparse.coo_matrix(
        (np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(num_nodes, num_nodes)
    )
    count, labels = scipy.sparse.csgraph.connected_components(graph, directed=False)
    return int(count), labels.astype(np.int64)


def rigid_body_modes(
    points: np.ndarray, bodies: np.ndarray, num_bodies: int, comm: MPI.Comm = MPI.COMM_SELF
) -> np.ndarray:
    """Orthonormal rigid-body modes of every body at the given nodes (3 dofs each).

    Args:
        points: Coordinates of this process's nodes, shape (n, 3).
        bodies: Body number of each node, in ``[0, num_bodies)``.
        num_bodies: Number of bodies over all processes.
        comm: Communicator over which the nodes are distributed (sums are global).

    Returns:
        Shape (3 n, 6 num_bodies), node-major (x, y, z of a node together): columns
        ``6 b ... 6 b + 5`` are body ``b``'s translations and rotations, zero at the nodes of the
        other bodies, orthonormal over all processes.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    bodies = np.asarray(bodies, dtype=np.int64)
    n = points.shape[0]
    sums = np.zeros((num_bodies, 4))  # coordinate sums and node counts per body
    for k in range(3):
        sums[:, k] = np.bincount(bodies, weights=points[:, k], minlength=num_bodies)
    sums[:, 3] = np.bincount(bodies, minlength=num_bodies)
    sums = comm.allreduce(sums, op=MPI.SUM)
    centroids = sums[:, :3] / np.maximum(sums[:, 3:], 1.0)
    r = points - centroids[bodies]  # about each body's centroid: better conditioned
    modes = np.zeros((n, 3, MODES_PER_BODY))  # (node, component, mode)
    modes[:, 0, 0] = modes[:, 1, 1] = modes[:, 2, 2] = 1.0
    # rotations about x, y, z: omega x r
    modes[:, 1, 3], modes[:, 2, 3] = -r[:, 2], r[:, 1]
    modes[:, 0, 4], modes[:, 2, 4] = r[:, 2], -r[:, 0]
    modes[:, 0, 5], modes[:, 1, 5] = -r[:, 1], r[:, 0]
    for _ in range(2):  # Cholesky QR per body, twice for orthonormality to round-off
        gram = np.zeros((num_bodies, MODES_PER_BODY, MODES_PER_BODY))
        np.add.at(gram, bodies, np.einsum("nci,ncj->nij", modes, modes))
        gram = comm.allreduce(gram, op=MPI.SUM)
        empty = sums[:, 3] == 0
        gram[empty] = np.eye(MODES_PER_BODY)
        factor = np.linalg.cholesky(gram)  # gram = L L^T; modes L^-T are orthonormal
        inverse = np.linalg.inv(factor).transpose(0, 2, 1)
        modes = np.einsum("nci,nij->ncj", modes, inverse[bodies])
    out = np.zeros((n, 3, num_bodies, MODES_PER_BODY))
    out[np.arange(n), :, bodies, :] = modes
    return out.reshape(3 * n, num_bodies * MODES_PER_BODY)


def body_numbers(V: dolfinx.fem.FunctionSpace) -> tuple[int, np.ndarray]:
    """Body (connected component of the mesh) of every local node of V, numbered globally.

    Collective. Components are found on each process, then joined through the nodes that
    processes share (a ghost and its owner are one node). Returns the number of bodies and the
    body of each owned and ghost node of V (block dofs).
    """
    comm = V.mesh.comm
    index_map = V.dofmap.index_map
    num_nodes = index_map.size_local + index_map.num_ghosts
    count, local = connected_components(compat.cell_dofs(V), num_nodes)
    offset = comm.exscan(count) or 0
    total = comm.allreduce(count)
    labels = local + offset
    carrier = dolfinx.fem.Function(V)  # the owners' labels at the ghosts (exact as floats)
    carrier.x.array.reshape(-1, V.dofmap.index_map_bs)[:, 0] = labels
    carrier.x.scatter_forward()
    owners = carrier.x.array.reshape(-1, V.dofmap.index_map_bs)[:, 0].astype(np.int64)
    joined = np.unique(np.column_stack([labels, owners])[labels != owners], axis=0)
    links = np.vstack([np.empty((0, 2), dtype=np.int64), *comm.allgather(joined)])
    num_bodies, body = connected_components(np.zeros((0, 1)), total, links)
    return num_bodies, body[labels]


def near_nullspace(V: dolfinx.fem.FunctionSpace) -> PETSc.NullSpace:
    """The rigid-body modes of every body of V as a PETSc near-nullspace (``MatSetNearNullSpace``).

    Collective. V is a 3D vector Lagrange space (any degree); the vectors have the layout of the
    owned dofs of V (the rows of its matrices).
    """
    if V.dofmap.index_map_bs != 3 or V.mesh.geometry.dim != 3:
        raise ValueError(
            "near_nullspace: needs a 3D vector space with 3 components per node, got block "
            f"size {V.dofmap.index_map_bs} in {V.mesh.geometry.dim}D"
        )
    comm = V.mesh.comm
    owned = V.dofmap.index_map.size_local
    num_bodies, body = body_numbers(V)
    points = V.tabulate_dof_coordinates()[:owned]
    modes = rigid_body_modes(points, body[:owned], num_bodies, comm)
    size = (3 * owned, 3 * V.dofmap.index_map.size_global)
    vectors = []
    for column in modes.T:
        vector = PETSc.Vec().createMPI(size, bsize=3, comm=comm)
        vector.array[:] = column
        vectors.append(vector)
    nullspace = PETSc.NullSpace().create(vectors=vectors, comm=comm)
    for vector in vectors:  # the null space holds its own references
        vector.destroy()
    return nullspace
