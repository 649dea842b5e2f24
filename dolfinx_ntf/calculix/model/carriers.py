"""Dofs for deck nodes in no element: one massless, stiffless carrier cell per node (§29.6).

ccx gives every node three dofs; a dolfinx space has dofs only at the nodes of its cells. Spring
ends and node-based slave nodes that belong to no element (ccx's contdamp1 and contdamp2: the
end of a SPRINGA that is also the contact's slave node) get a *carrier cell*: a small cell of the
deck's cell type with the node at one corner and new nodes at the others. The carrier cells have
no material (zero Lamé parameters and density, as every cell outside a ``*SOLID SECTION``), their
new nodes are held by Dirichlet conditions, and their faces give no contact area (the carried
slave nodes take ccx's fallback area, as nodes without faces). So the carried node has three free
dofs that only the springs, the contact springs, ``*EQUATION`` and loads act on, as in ccx.
"""

from __future__ import annotations

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat

from ..deck import Deck, ElementBlock

__all__ = ["carried_nodes", "carrier_cells", "carrier_dofs"]

#: Unit cells in dolfinx vertex order, by number of cell nodes (hexahedron, tetrahedron).
_UNIT_CELLS = {
    8: np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]],
        dtype=np.float64,
    ),
    4: np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64),
}


def carried_nodes(deck: Deck, block: ElementBlock) -> np.ndarray:
    """Deck rows of the nodes in no element that need dofs: spring ends, node-based slaves.

    Raises:
        NotImplementedError: such nodes in a deck whose cells are not C3D8-like hexahedra or
            C3D4 tetrahedra (linear 3D cells), naming the first node.
    """
    meshed = np.zeros(deck.node_ids.size, dtype=bool)
    meshed[deck.node_index(block.connectivity)] = True
    needed = [deck.node_index(group.connectivity).ravel() for group in deck.springs]
    slaves = {pair.slave for pair in deck.contact_pairs}
    for name in sorted(slaves):
        surface = deck.surfaces.get(name)
        if surface is not None and surface.type == "NODE":
            needed.append(deck.node_index(surface.nodes))
    if not needed:
        return np.zeros(0, dtype=np.int64)
    rows = np.unique(np.concatenate(needed))
    rows = rows[~meshed[rows]]
    etype = block.type
    if rows.size and (etype.tdim != 3 or etype.degree != 1 or etype.num_nodes not in _UNIT_CELLS):
        raise NotImplementedError(
            f"{deck.path}: node {int(deck.node_ids[rows[0]])} belongs to no element; springs and "
            f"node-based slave surfaces on such nodes are supported with linear 3D elements "
            f"(C3D8, C3D4), not {etype.name}"
        )
    return rows.astype(np.int64)


def carrier_cells(
    deck: Deck, block: ElementBlock, rows: np.ndarray, first_point: int
) -> tuple[np.ndarray, np.ndarray]:
    """New points and cells (dolfinx vertex order, point indices) carrying deck nodes ``rows``.

    Each cell has the carried node at its first corner and new points numbered from
    ``first_point`` at the others, a cube (or corner tetrahedron) of edge 1e-3 of the model's size.
    """
    unit = _UNIT_CELLS[block.type.num_nodes]
    x = np.asarray(deck.node_coords, dtype=np.float64)
    size = float(np.ptp(x, axis=0).max()) if x.shape[0] > 1 else 1.0
    edge = 1e-3 * (size if size > 0 else 1.0)
    others = unit[1:]
    points = (x[rows][:, None, :] + edge * others[None, :, :]).reshape(-1, 3)
    new = first_point + np.arange(points.shape[0], dtype=np.int64).reshape(rows.size, -1)
    cells = np.column_stack([rows, new])
    return points, cells


def carrier_dofs(
    mesh: dolfinx.mesh.Mesh, V: dolfinx.fem.FunctionSpace, deck: Deck, carried: np.ndarray
) -> np.ndarray:
    """Local block dofs (owned and ghost) of the carrier cells' new points: held at zero."""
    if carried.size == 0:
        return np.zeros(0, dtype=np.int64)
    tdim = mesh.topology.dim
    num_cells = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
    geometry = compat.geometry_dofs(mesh)[:num_cells].ravel()
    dofs = compat.cell_dofs(V)[:num_cells].ravel()
    input_index = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    new = input_index[geometry] >= deck.node_ids.size
    return np.unique(dofs[new]).astype(np.int64)
