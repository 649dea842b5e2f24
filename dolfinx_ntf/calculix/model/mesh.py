"""The mesh of a deck and the maps between ccx node/element numbers and dolfinx dofs/cells.

The deck's one element type becomes dolfinx cells (C3D4 -> P1 tetrahedra, C3D8 -> Q1 hexahedra,
C3D10 -> P2 tetrahedra with P2 geometry, C3D20/C3D20R -> Q2 hexahedra constrained to the
serendipity space, docs/method.md §13.5). The maps always go through per-cell tables, never by
assuming equal numbers; on several processes they hold this process's nodes and cells only (-1
elsewhere), while the node flags of :class:`MeshMaps` cover the whole deck.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.fem.collapsed_wedges import create_collapsed_mesh
from dolfinx_ntf.fem.serendipity import add_centres
from dolfinx_ntf.fem.serendipity_quad import add_quad_centres
from dolfinx_ntf.fem.serendipity_wedge import add_wedge_centres

from ..deck import Deck, ElementBlock, Location
from ..elements import ELEMENT_TYPES
from .carriers import carrier_cells

__all__ = [
    "CELL_PERMUTATIONS",
    "INTEGRATION_POINTS",
    "FacetFinder",
    "MeshMaps",
    "create_mesh",
    "element_block",
    "element_faces_to_facets",
    "element_models",
    "exterior",
    "facet_finder",
    "mesh_maps",
    "numbering",
]

#: dolfinx cell node order as 0-based indices into the ccx element's nodes, by ccx element type.
CELL_PERMUTATIONS: dict[str, np.ndarray] = {n: t.to_dolfinx for n, t in ELEMENT_TYPES.items()}

#: ccx integration points of each element type in ccx order (``*EL PRINT`` rows), as dolfinx
#: reference coordinates.
INTEGRATION_POINTS: dict[str, np.ndarray] = {
    n: t.integration_points for n, t in ELEMENT_TYPES.items()
}

FacetFinder = Callable[[np.ndarray], np.ndarray]
"""Maps ``(F, k)`` facet corner vertices to local facet indices (-1 if none)."""


@dataclass(frozen=True, eq=False)
class MeshMaps:
    """The deck's element block and the maps the model's builders share.

    Attributes:
        block: The deck's element block (one element type).
        node_vertex: ``(N,)`` local mesh vertex of each deck node, -1 for midside or unused nodes.
        node_dof: ``(N,)`` local block dof of each deck node, -1 for nodes in no local element.
        element_cell: ``(E,)`` local cell of each element of ``block``, -1 for other processes'.
        find: Local facet of facet corner vertices (:func:`facet_finder`).
        meshed: ``(N,)`` the deck node belongs to an element (on any process).
        corner: ``(N,)`` the deck node is an element corner (on any process).
        carried: ``(N,)`` the deck node is in no element but on a carrier cell (§29.6).
    """

    block: ElementBlock
    node_vertex: np.ndarray
    node_dof: np.ndarray
    element_cell: np.ndarray
    find: FacetFinder
    meshed: np.ndarray
    corner: np.ndarray
    carried: np.ndarray | None = None


def mesh_maps(
    deck: Deck,
    block: ElementBlock,
    mesh: dolfinx.mesh.Mesh,
    node_vertex: np.ndarray,
    node_dof: np.ndarray,
    element_cell: np.ndarray,
    carried: np.ndarray | None = None,
) -> MeshMaps:
    """The :class:`MeshMaps` of a deck's mesh: adds the node flags and the facet finder.

    ``carried`` nodes (deck rows, on carrier cells) count as meshed, not as corners.
    """
    # over all processes (from the deck): nodes of an element, element corners
    meshed = np.zeros(deck.node_ids.size, dtype=bool)
    meshed[deck.node_index(block.connectivity)] = True
    flags = np.zeros(deck.node_ids.size, dtype=bool)
    if carried is not None:
        flags[carried] = True
        meshed |= flags
    corner = np.zeros(deck.node_ids.size, dtype=bool)
    corner[deck.node_index(block.connectivity[:, : block.type.num_corners])] = True
    return MeshMaps(
        block=block,
        node_vertex=node_vertex,
        node_dof=node_dof,
        element_cell=element_cell,
        find=facet_finder(mesh),
        meshed=meshed,
        corner=corner,
        carried=flags,
    )


def element_block(deck: Deck) -> ElementBlock:
    """The deck's element block (an error for none or mixed element types).

    ccx's quasi-axisymmetric models mix plane-stress and axisymmetric elements of one layout
    (CPS8R with CAX8R, CPS4 with CAX4, ...): their blocks are merged into one block of the first
    type, whose cells the model gives per-cell formulations (:func:`element_models`,
    docs/method.md §26). Other mixes are refused.
    """
    blocks = [b for b in deck.elements.values() if b.ids.size]
    if not blocks:
        raise ValueError(f"{deck.path}: the deck has no elements")
    if len(blocks) > 1:
        names = ", ".join(f"{b.type.name} (first at {b.locations[0]})" for b in blocks)
        if any(b.type.name == "C3D15" for b in blocks):
            raise ValueError(
                f"{deck.path}: the mesh mixes element types {names}: C3D15 wedges run in meshes "
                "of C3D15 only (a dolfinx mesh holds one cell type, and an 18-node prism mesh "
                "cannot take other cells; docs/method.md §34)"
            )
        if not _quasi_axisymmetric(blocks):
            raise ValueError(
                f"{deck.path}: the mesh mixes element types {names}; use one element type per "
                "deck (or plane-stress and axisymmetric elements of one layout, e.g. CPS8R with "
                "CAX8R)"
            )
        return ElementBlock(
            blocks[0].type,
            np.concatenate([b.ids for b in blocks]),
            np.concatenate([b.connectivity for b in blocks]),
            tuple(loc for b in blocks for loc in b.locations),
        )
    return blocks[0]


def _quasi_axisymmetric(blocks: list[ElementBlock]) -> bool:
    """The blocks are CPS and CAX elements of one layout (cell, nodes, integration, rows)."""
    first = blocks[0].type
    if {b.type.model for b in blocks} != {"plane stress", "axisymmetric"}:
        return False

    def same(a: np.ndarray | None, b: np.ndarray | None) -> bool:
        return (a is None) == (b is None) and (a is None or np.array_equal(a, b))

    return all(
        b.type.name[3:] == first.name[3:]
        and b.type.cell == first.cell
        and b.type.num_nodes == first.num_nodes
        and b.type.quadrature_degree == first.quadrature_degree
        and same(b.type.to_dolfinx, first.to_dolfinx)
        and same(b.type.integration_points, first.integration_points)
        and same(b.type.print_rows, first.print_rows)
        for b in blocks
    )


def element_models(deck: Deck, block: ElementBlock) -> np.ndarray:
    """The 2D model of each element of ``block`` (rows of ``block.ids``) from the deck's types."""
    models = np.full(block.ids.size, block.type.model, dtype=object)
    for other in deck.elements.values():
        models[np.isin(block.ids, other.ids)] = other.type.model
    return models


def create_mesh(
    deck: Deck, block: ElementBlock, comm: MPI.Comm, carried: np.ndarray | None = None
) -> dolfinx.mesh.Mesh:
    """The dolfinx mesh of ``block``, distributed from rank 0's cells (collective).

    ``carried``: deck rows of nodes in no element that get a carrier cell each (``carriers.py``,
    docs/method.md §29.6), appended after the element cells; their new points follow the deck's.
    """
    gdim = block.type.tdim  # ccx's 2D elements: a 2D mesh of the plane z = 0 (§23)
    domain = compat.coordinate_element(block.type.cell, block.type.degree, gdim)
    serendipity = block.type.num_nodes == 20  # C3D20(R): 27-node cells (docs/method.md §13.5)
    quad8 = gdim == 2 and block.type.num_nodes == 8  # CPE8 ...: 9-node cells (§23)
    wedge15 = block.type.name == "C3D15"  # 18-node prisms (docs/method.md §34)
    width = 27 if serendipity else (9 if quad8 else (18 if wedge15 else block.type.num_nodes))
    if comm.rank == 0:
        cells = deck.node_index(block.connectivity)[:, block.type.to_dolfinx]
        x = np.asarray(deck.node_coords, dtype=np.float64)[:, :gdim].copy()
        if serendipity:
            cells, x = add_centres(cells, x)
        if quad8:
            cells, x = add_quad_centres(cells, x)
        if wedge15:
            cells, x = add_wedge_centres(cells, x)
        if carried is not None and carried.size:
            points, extra = carrier_cells(deck, block, carried, x.shape[0])
            cells, x = np.vstack([cells, extra]), np.vstack([x, points])
    else:
        cells = np.zeros((0, width), dtype=np.int64)
        x = np.zeros((0, gdim))
    if width == 8 and gdim == 3:  # C3D6 wedges are collapsed C3D8 cells
        return create_collapsed_mesh(comm, cells.astype(np.int64), x, domain)
    return compat.create_mesh(comm, cells.astype(np.int64), x, domain)


def numbering(
    deck: Deck, mesh: dolfinx.mesh.Mesh, V: dolfinx.fem.FunctionSpace
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``node_dof``, ``dof_node``, ``node_vertex`` and each local cell's element row.

    Through per-cell tables (see :class:`~dolfinx_ntf.calculix.model.CalculixModel`).
    """
    tdim = mesh.topology.dim
    num_cells = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
    geometry_dofs = compat.geometry_dofs(mesh)[:num_cells]
    space_dofs = compat.cell_dofs(V)[:num_cells]
    if geometry_dofs.shape != space_dofs.shape:
        raise RuntimeError("the displacement space and the geometry have different cell layouts")
    num_geometry = mesh.geometry.x.shape[0]
    dof_of_geometry = np.full(num_geometry, -1, dtype=np.int64)
    dof_of_geometry[geometry_dofs.ravel()] = space_dofs.ravel()
    input_index = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    deck_node = input_index < deck.node_ids.size  # not C3D20's added face and cell centres
    node_dof = np.full(deck.node_ids.size, -1, dtype=np.int64)
    node_dof[input_index[deck_node]] = dof_of_geometry[deck_node]
    num_dofs = V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
    dof_node = np.full(num_dofs, -1, dtype=np.int64)  # -1: an added centre, no ccx node
    dof_node[dof_of_geometry[deck_node]] = deck.node_ids[input_index[deck_node]]

    num_vertices = mesh.topology.index_map(0).size_local + mesh.topology.index_map(0).num_ghosts
    vertices = np.arange(num_vertices, dtype=np.int32)
    vertex_geometry = compat.entities_to_geometry(mesh, 0, vertices).ravel()
    node_vertex = np.full(deck.node_ids.size, -1, dtype=np.int64)
    vertex_input = input_index[vertex_geometry]
    deck_vertex = vertex_input < deck.node_ids.size  # not the points of carrier cells
    node_vertex[vertex_input[deck_vertex]] = vertices[deck_vertex]

    original = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)[:num_cells]
    return node_dof, dof_node, node_vertex, original


def facet_finder(mesh: dolfinx.mesh.Mesh) -> FacetFinder:
    """A function mapping ``(F, k)`` facet corner vertices to local facet indices (-1 if none).

    A prism mesh has two facet types, numbered apart by dolfinx 0.11, whose ``ds`` it does not
    assemble: its finder refuses every query (C3D15 decks refuse faces first, §34).
    """
    tdim = mesh.topology.dim
    if mesh.topology.cell_type == dolfinx.mesh.CellType.prism:

        def refuse(corners: np.ndarray) -> np.ndarray:
            raise NotImplementedError(
                "faces of prism meshes are not supported (docs/method.md §34)"
            )

        return refuse
    mesh.topology.create_connectivity(tdim - 1, 0)
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f_to_v = mesh.topology.connectivity(tdim - 1, 0)
    num_facets = (
        mesh.topology.index_map(tdim - 1).size_local + mesh.topology.index_map(tdim - 1).num_ghosts
    )
    width = f_to_v.offsets[1] - f_to_v.offsets[0] if num_facets else 3
    keys = np.sort(f_to_v.array.reshape(num_facets, width).astype(np.int64), axis=1)
    order = np.lexsort(keys.T[::-1])
    sorted_keys = keys[order]

    def find(corners: np.ndarray) -> np.ndarray:
        query = np.sort(np.asarray(corners, dtype=np.int64), axis=1)
        if query.shape[1] != width:
            raise ValueError(f"faces with {query.shape[1]} corners, mesh facets have {width}")
        lo, hi = (
            np.zeros(query.shape[0], dtype=np.int64),
            np.full(query.shape[0], num_facets, dtype=np.int64),
        )
        # vectorized lexicographic binary search over the sorted facet keys
        for _ in range(int(np.ceil(np.log2(num_facets + 1))) + 1):
            mid = (lo + hi) // 2
            active = lo < hi
            cand = sorted_keys[np.minimum(mid, num_facets - 1)]
            diff = cand - query
            first = np.argmax(diff != 0, axis=1)
            sign = diff[np.arange(query.shape[0]), first]
            less = active & (sign < 0)
            lo = np.where(less, mid + 1, lo)
            hi = np.where(active & ~less, mid, hi)
        pos = np.minimum(lo, num_facets - 1)
        found = np.all(sorted_keys[pos] == query, axis=1) & (query.min(axis=1) >= 0)
        return np.where(found, order[pos], -1)

    return find


def exterior(mesh: dolfinx.mesh.Mesh, facets: np.ndarray) -> np.ndarray:
    """True for the local ``facets`` that belong to one cell only (boundary facets)."""
    tdim = mesh.topology.dim
    f_to_c = mesh.topology.connectivity(tdim - 1, tdim)
    return (f_to_c.offsets[facets + 1] - f_to_c.offsets[facets]) == 1


def element_faces_to_facets(
    deck: Deck,
    maps: MeshMaps,
    element_ids: np.ndarray,
    faces: np.ndarray,
    what: str,
    location: Location | str,
) -> tuple[np.ndarray, np.ndarray]:
    """Local facets and ccx face nodes ``(F, n)`` of element faces (1-based face numbers).

    The facet is -1 for faces of elements this process does not hold.
    """
    block, node_vertex, find = maps.block, maps.node_vertex, maps.find
    etype = block.type
    order = np.argsort(block.ids)
    pos = np.minimum(np.searchsorted(block.ids, element_ids, sorter=order), block.ids.size - 1)
    rows = order[pos]
    nodes = block.connectivity[rows[:, None], etype.faces[faces - 1]]
    corners = node_vertex[deck.node_index(nodes[:, : etype.face_corners])]
    here = maps.element_cell[rows] >= 0
    facets = np.full(here.size, -1, dtype=np.int64)
    if np.any(here):  # a process without cells has no facets to search
        facets[here] = find(corners[here])
    if np.any(here & (facets < 0)):
        bad = int(np.argmax(here & (facets < 0)))
        raise ValueError(
            f"{location}: {what}: face S{faces[bad]} of element {element_ids[bad]} is not a "
            "facet of "
            "the mesh"
        )
    return facets, nodes
