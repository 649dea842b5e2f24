"""Time to choose the collapsed edges of extruded prism meshes (docs/method.md §32.4).

Builds gmsh extrusions of a Delaunay-triangulated rectangle (``recombine=True``: prisms) of
growing size and prints, per mesh, the prisms and the time of
``wedge_rotations(rows, shared=True)`` (the gmsh reader's rule), and that the choice obeys it.

Run: ``python benchmarks/prism_collapse.py [--sizes 0.1 0.05 ...] [--layers 1 4]`` (one layer:
as many stacks as triangles, about twice the vertical lines, the tight case).
"""

from __future__ import annotations

import argparse
import time

import gmsh
import numpy as np

from dolfinx_ntf.kernels.collapsed_wedges import collapse_wedges, wedge_rotations


def extruded_prisms(size: float, layers: int) -> np.ndarray:
    """``(e, 6)`` 0-based prisms of a 2 x 1 rectangle meshed at ``size``, ``layers`` high."""
    gmsh.model.add("prisms")
    square = gmsh.model.occ.addRectangle(0.0, 0.0, 0.0, 2.0, 1.0)
    gmsh.model.occ.extrude([(2, square)], 0, 0, 0.5, numElements=[layers], recombine=True)
    gmsh.model.occ.synchronize()
    gmsh.model.mesh.setSize(gmsh.model.getEntities(0), size)
    gmsh.model.mesh.generate(3)
    types, _, nodes = gmsh.model.mesh.getElements(3)
    rows = np.asarray(nodes[list(types).index(6)], dtype=np.int64).reshape(-1, 6) - 1
    gmsh.model.remove()
    return rows


def obeys_shared_rule(rows: np.ndarray, rotation: np.ndarray) -> bool:
    """Every collapsed edge belongs to at most two prisms, and two only if they share no face."""
    hexahedra = collapse_wedges(rows, rotation)
    edges = np.sort(hexahedra[:, [2, 6]], axis=1)
    _, users, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    users = users.ravel()
    if np.any(counts > 2):
        return False
    order = np.argsort(users, kind="stable")
    pairs = order[counts[users[order]] == 2].reshape(-1, 2)  # the two prisms of a shared edge
    common = (rows[pairs[:, 0], :, None] == rows[pairs[:, 1], None, :]).any(axis=2).sum(axis=1)
    return bool(np.all(common <= 2))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[0.1, 0.05, 0.025, 0.0125])
    parser.add_argument("--layers", type=int, nargs="+", default=[1, 4])
    args = parser.parse_args()
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        print(f"{'size':>8} {'layers':>6} {'prisms':>8} {'seconds':>9} {'us/prism':>9}  rule")
        for layers, size in ((layers, size) for layers in args.layers for size in args.sizes):
            rows = extruded_prisms(size, layers)
            start = time.perf_counter()
            rotation = wedge_rotations(rows, shared=True)
            elapsed = time.perf_counter() - start
            ok = obeys_shared_rule(rows, rotation)
            print(
                f"{size:8.4f} {layers:6d} {rows.shape[0]:8d} {elapsed:9.3f} "
                f"{1e6 * elapsed / rows.shape[0]:9.1f}  {'obeyed' if ok else 'BROKEN'}"
            )
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main()
