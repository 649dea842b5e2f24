"""Wedges meshed as collapsed hexahedra, integrated with ccx's two-point C3D6 rule.

docs/method.md §30.5. :func:`wedge_cells` finds the local cells of a hexahedral mesh that repeat
a node along one face (the wedges) and their collapse class; :func:`wedge_metadata` is the
integral metadata of a class (FFCx's custom rule, the points and weights of
:func:`~dolfinx_ntf.kernels.wedge_rule.wedge_rule`), for ``dx(tag, metadata=...)`` over
the cells of that class.
"""

from __future__ import annotations

import typing

from mpi4py import MPI

import numpy as np

import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.kernels.collapsed_wedges import unmatched_neighbours
from dolfinx_ntf.kernels.wedge_rule import collapse_classes, wedge_rule

__all__ = ["check_vertices_joined", "create_collapsed_mesh", "wedge_cells", "wedge_metadata"]


def wedge_cells(mesh: dolfinx.mesh.Mesh) -> np.ndarray:
    """The collapse class of every local cell (owned and ghost), -1 for a cell that is no wedge.

    Read from the geometry: a wedge's cell lists a node twice along two parallel edges of one
    face. Meshes of other cells than linear hexahedra have no wedges (all -1).

    Args:
        mesh: The mesh.
    """
    nodes = compat.geometry_dofs(mesh)
    if mesh.topology.dim != 3 or nodes.shape[1] != 8:  # 8 nodes in 3D: linear hexahedra
        return np.full(nodes.shape[0], -1, dtype=np.int64)
    return collapse_classes(nodes)


def wedge_metadata(rule_class: int) -> dict:
    """Integral metadata of ccx's C3D6 rule on the cells of one collapse class.

    Points and weights as tuples (UFL compares metadata; FFCx reads any sequence).

    Args:
        rule_class: The collapse class (:func:`wedge_cells`), ``0..11``.
    """
    points, weights = wedge_rule(rule_class)
    return {
        "quadrature_rule": "custom",
        "quadrature_degree": 2,
        "quadrature_points": tuple(map(tuple, points.tolist())),
        "quadrature_weights": tuple(weights.tolist()),
    }


def create_collapsed_mesh(
    comm: MPI.Comm, cells: np.ndarray, points: np.ndarray, element: typing.Any, root: int = 0
) -> dolfinx.mesh.Mesh:
    """A distributed mesh of hexahedra, some collapsed (wedges), with the cut's vertices joined.

    dolfinx 0.5.2 joins the vertices of a partition's cut through the ghost cells of the facets
    it matches, and it does not match a wedge's triangle with the hexahedron's quadrilateral (or
    another wedge's triangle repeating another corner) lying on it: the cells of those faces are
    made ghosts of each other's processes (docs/method.md §37; 0.9 and later join them by
    themselves, and the faces are not looked for). Then
    :func:`check_vertices_joined` checks the result. Collective.

    Args:
        comm: The communicator.
        cells: ``(n, 8)`` hexahedra in dolfinx's vertex order on ``root`` (``(0, 8)`` elsewhere).
        points: The vertices' coordinates on ``root`` (none elsewhere).
        element: The coordinate element (``compat.coordinate_element``).
        root: The process holding the cells.
    """
    pairs = np.zeros((0, 2), dtype=np.int64)
    if comm.size > 1 and comm.rank == root and not compat.JOINS_UNMATCHED_FACETS:
        pairs = unmatched_neighbours(cells)
    mesh = compat.create_mesh(comm, cells, points, element, unmatched=pairs)
    check_vertices_joined(mesh, cells, root)
    return mesh


def check_vertices_joined(mesh: dolfinx.mesh.Mesh, cells: np.ndarray, root: int = 0) -> None:
    """Refuse a distributed mesh of collapsed cells whose processes did not join their vertices.

    dolfinx matches the vertices of a partition's cut through the cells' facets; a collapsed
    face (a wedge's triangle as a quadrilateral with a repeated node) can fail that match, and
    the cut's vertices are then duplicated, leaving the parts unconnected: a silent wrong answer
    (a mixed wedge and hexahedron block on 2 processes: 36 vertices for 27 nodes, its
    displacements 63 % off, before :func:`create_collapsed_mesh`). The safety net of
    :func:`create_collapsed_mesh`. Collective.

    Args:
        mesh: The mesh created from ``cells``.
        cells: ``(n, 8)`` input cells (on ``root``; any array elsewhere), vertex numbers.
        root: The process holding ``cells``.

    Raises:
        NotImplementedError: The mesh has more vertices than the cells' distinct nodes.
    """
    comm = mesh.comm
    if comm.size == 1:
        return
    expected = comm.bcast(int(np.unique(cells).size) if comm.rank == root else None, root=root)
    found = mesh.topology.index_map(0).size_global
    if found != expected:
        raise NotImplementedError(
            f"a mesh of collapsed hexahedra (wedges) on {comm.size} processes: dolfinx did not "
            f"join the processes' vertices ({found} vertices for {expected} nodes), so the parts "
            "would not be connected; run it on one process"
        )
