"""Set-up time of C3D20's space on a large hexahedral mesh (docs/method.md §13.5).

Prints the time to build the serendipity constraints of a degree-2 hexahedral space and their
elimination (``u = T w + g``) for a box of about ``--cells`` cells (default 10 000).

Run: ``python benchmarks/serendipity_setup.py [--cells N]``.
"""

from __future__ import annotations

import argparse
import time

from mpi4py import MPI

import numpy as np

import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.fem.constraints import ConstraintElimination, num_equations
from dolfinx_ntf.fem.serendipity import serendipity_constraints


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=10_000)
    args = parser.parse_args()
    n = max(1, round(args.cells ** (1 / 3)))
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_SELF, [[0, 0, 0], [1, 1, 1]], [n, n, n], dolfinx.mesh.CellType.hexahedron
    )
    V = compat.vector_space(mesh, "Lagrange", 2)
    start = time.perf_counter()
    constraints = serendipity_constraints(V)
    built = time.perf_counter()
    elimination = ConstraintElimination(
        V.dofmap.index_map.size_local * 3, constraints, np.zeros(0, np.int64), MPI.COMM_SELF
    )
    done = time.perf_counter()
    print(
        f"{n**3} cells, {V.dofmap.index_map.size_local * 3} dofs, {num_equations(constraints)} "
        f"constraints: built in {built - start:.3f} s, eliminated in {done - built:.3f} s "
        f"({elimination.num_constraints} dependent dofs)"
    )
    elimination.destroy()


if __name__ == "__main__":
    main()
