"""Collapsed hexahedra beside hexahedra on several processes: the cut joined (docs/method.md §37).

Builds an ``n x n x layers`` checkerboard of unit-grid cells, every other one split into two
wedges (collapsed hexahedra whose triangles lie on the neighbouring hexahedra's quadrilaterals:
faces dolfinx does not match), and prints the unmatched pairs and the time of
``unmatched_neighbours``, then the global vertex count and time of plain ``create_mesh`` and of
``create_collapsed_mesh`` against the distinct nodes.

Run: ``mpirun -n 2 python benchmarks/collapsed_join.py [--n 30] [--layers 30]``.
"""

from __future__ import annotations

import argparse
import time

from mpi4py import MPI

import numpy as np

from dolfinx_ntf import compat
from dolfinx_ntf.fem.collapsed_wedges import create_collapsed_mesh
from dolfinx_ntf.kernels.collapsed_wedges import unmatched_neighbours

# dolfinx's tensor order of a hexahedron's corners as (i, j, k) offsets
_TENSOR = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)])


def checkerboard(n: int, layers: int) -> tuple[np.ndarray, np.ndarray]:
    """``(cells, points)``: hexahedra, and two collapsed wedges in every other cell."""
    k, j, i = (a.ravel() for a in np.meshgrid(*map(np.arange, (layers, n, n)), indexing="ij"))

    def vertex(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        return a + (n + 1) * (b + (n + 1) * c)

    hexahedra = np.stack([vertex(i + a, j + b, k + c) for a, b, c in _TENSOR], axis=1)
    split = (i + j + k) % 2 == 1
    v = hexahedra[split]  # the square 0 1 3 2 cut along 0-3; the wedges collapse 3-7 and 0-4
    cells = np.vstack(
        [hexahedra[~split], v[:, [0, 1, 3, 3, 4, 5, 7, 7]], v[:, [3, 2, 0, 0, 7, 6, 4, 4]]]
    )
    kk, jj, ii = (a.ravel() for a in np.meshgrid(*map(np.arange, (layers + 1, n + 1, n + 1)),
                                                   indexing="ij"))  # fmt: skip
    points = np.zeros((ii.size, 3))
    points[vertex(ii, jj, kk)] = np.column_stack([ii, jj, kk]) / n
    return cells.astype(np.int64), points


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=30, help="cells along x and y")
    parser.add_argument("--layers", type=int, default=30, help="cells along z")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    cells, points = checkerboard(args.n, args.layers)
    nodes = np.unique(cells).size
    if comm.rank == 0:
        start = time.perf_counter()
        pairs = unmatched_neighbours(cells)
        print(
            f"{cells.shape[0]} cells, {nodes} nodes, {len(pairs)} unmatched pairs: "
            f"unmatched_neighbours {time.perf_counter() - start:.3f} s"
        )
    else:
        cells, points = np.zeros((0, 8), np.int64), np.zeros((0, 3))
    element = compat.coordinate_element("hexahedron")
    for name, build in (("create_mesh", compat.create_mesh), ("create_collapsed_mesh", None)):
        comm.barrier()
        start = time.perf_counter()
        try:
            if build is None:
                mesh = create_collapsed_mesh(comm, cells, points, element)
            else:
                mesh = build(comm, cells, points, element)
            found = str(mesh.topology.index_map(0).size_global)
        except NotImplementedError:
            found = "refused"
        elapsed = comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
        if comm.rank == 0:
            print(f"{comm.size} processes, {name}: {found} vertices, {elapsed:.2f} s")


if __name__ == "__main__":
    main()
