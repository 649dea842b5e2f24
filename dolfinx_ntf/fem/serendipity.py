"""The 20-node serendipity hexahedron (CalculiX C3D20/C3D20R) as a constrained Q2 space.

See docs/method.md §13.5. The classical 20-node serendipity space on a hexahedron lies inside the
27-node triquadratic (Q2) space: it is the Q2 functions whose values at the 6 face centres and the
cell centre are fixed by the 20 others,

    u(face centre) = -1/4 sum(4 face corners) + 1/2 sum(4 face midside nodes),
    u(cell centre) = -1/4 sum(8 corners) + 1/4 sum(12 midside nodes),

the values the serendipity shape functions take there. :func:`serendipity_constraints` returns
these 7 constraints per cell (each face once) for a degree-2 vector Lagrange space on hexahedra;
with them, :class:`~dolfinx_ntf.ContactProblem` solves in the serendipity space by elimination
(docs/method.md §13.1) while every ccx node keeps a point-value dof (basix's own serendipity element
has edge moments as dofs instead, which node-to-face springs cannot use).

C3D8 cells in the same mesh (a deck mixing C3D8 with C3D20/C3D20R, docs/method.md §27) are cells
of the same space whose midside nodes are also fixed, each to the mean of its edge's end nodes
(:func:`trilinear_constraints`): the field on them is then exactly trilinear (the face and cell
centre rows above then give the bilinear and trilinear centre values).
"""

from __future__ import annotations

import typing

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.fem.constraints import LinearConstraintBlock
from dolfinx_ntf.fem.surfaces import SurfaceFaces
from dolfinx_ntf.kernels.faces import QUAD4, QUAD8, QUAD9

__all__ = [
    "add_centres",
    "as_quad8",
    "face_centres",
    "linear_midsides",
    "serendipity_centres",
    "serendipity_constraints",
    "trilinear_constraints",
]

# basix reference hexahedron: vertices in tensor order, edges and faces by their vertices.
_EDGES = [
    (0, 1),
    (0, 2),
    (0, 4),
    (1, 3),
    (1, 5),
    (2, 3),
    (2, 6),
    (3, 7),
    (4, 5),
    (4, 6),
    (5, 7),
    (6, 7),
]
_FACES = [(0, 1, 2, 3), (0, 1, 4, 5), (0, 2, 4, 6), (1, 3, 5, 7), (2, 3, 6, 7), (4, 5, 6, 7)]


def _local_rows() -> list[tuple[int, np.ndarray, np.ndarray]]:
    """(dependent local dof, independent local dofs, weights) of the 7 constraints of a cell.

    Local dofs of a Q2 hexahedron: 0..7 vertices, 8..19 edges, 20..25 faces, 26 the interior.
    """
    rows = []
    for f, face in enumerate(_FACES):
        edges = [8 + e for e, (a, b) in enumerate(_EDGES) if a in face and b in face]
        rows.append((20 + f, np.array([*face, *edges]), np.array([-0.25] * 4 + [0.5] * 4)))
    rows.append((26, np.arange(20), np.array([-0.25] * 8 + [0.25] * 12)))
    return rows


def serendipity_constraints(V: dolfinx.fem.FunctionSpace) -> list[LinearConstraintBlock]:
    """Constraints that turn a degree-2 vector Lagrange space on hexahedra into C3D20's space.

    Args:
        V: Vector Lagrange space of degree 2 on a hexahedral mesh. On several processes the
            rows of this process's cells, ghosts included (a face between two processes'
            cells on both: ``ContactProblem`` counts it once, docs/method.md §14.10).

    Returns:
        Two blocks (all arrays, no Python loop over cells): the face centres (each face once,
        9 terms) and the cell centres (21 terms), three components each; the centre dof is the
        first term, the dependent one. Dirichlet conditions must leave face- and cell-centre dofs
        free (their values follow from the 20 nodes).
    """
    if V.mesh.topology.cell_type != dolfinx.mesh.CellType.hexahedron:
        raise ValueError("serendipity_constraints: a hexahedral mesh is needed")
    if compat.space_degree(V) != 2 or V.dofmap.index_map_bs != 3:
        raise ValueError("serendipity_constraints: a degree-2 vector Lagrange space is needed")
    dofs = compat.cell_dofs(V).astype(np.int64)
    if dofs.shape[1] != 27:
        raise ValueError(f"serendipity_constraints: 27 dofs per cell expected, got {dofs.shape[1]}")
    rows = _local_rows()
    face_local = np.array([[dependent, *independent] for dependent, independent, _ in rows[:6]])
    face_nodes = dofs[:, face_local].reshape(-1, 9)  # (cells * 6, 9)
    _, first = np.unique(face_nodes[:, 0], return_index=True)  # a shared face once
    face_nodes = face_nodes[np.sort(first)]
    cell_nodes = dofs[:, [rows[6][0], *rows[6][1]]]
    blocks = []
    for nodes, weights, what in (
        (face_nodes, rows[0][2], "face centres"),
        (cell_nodes, rows[6][2], "cell centres"),
    ):
        coefficients = np.concatenate([[1.0], -weights])
        blocks.append(
            LinearConstraintBlock(
                np.repeat(nodes, 3, axis=0),
                np.tile(np.arange(3), nodes.shape[0])[:, None],
                coefficients,
                name=f"C3D20 {what}",
                geometric=True,
            )
        )
    return blocks


#: Coefficients of a trilinear midside row: the midside node, then its edge's two end nodes.
_EDGE_ROW = np.array([1.0, -0.5, -0.5])


def trilinear_constraints(V: dolfinx.fem.FunctionSpace, cells: np.ndarray) -> LinearConstraintBlock:
    """Constraints that make ``V`` trilinear on ``cells``: each midside node the mean of its edge.

    Args:
        V: Vector Lagrange space of degree 2 on a hexahedral mesh (with
            :func:`serendipity_constraints` on every cell, the space of C3D20 there and of C3D8
            on ``cells``).
        cells: Local cells (owned and ghost) to make trilinear.

    Returns:
        One block of 3-term rows (each edge once, three components), the midside dof first (the
        dependent one). A midside node shared with a cell not in ``cells`` is constrained too
        (the neighbour's edge becomes straight and linear): decks refuse that case.
    """
    if V.mesh.topology.cell_type != dolfinx.mesh.CellType.hexahedron:
        raise ValueError("trilinear_constraints: a hexahedral mesh is needed")
    if compat.space_degree(V) != 2 or V.dofmap.index_map_bs != 3:
        raise ValueError("trilinear_constraints: a degree-2 vector Lagrange space is needed")
    dofs = compat.cell_dofs(V).astype(np.int64)[np.asarray(cells, dtype=np.int64)]
    local = np.array([[8 + e, a, b] for e, (a, b) in enumerate(_EDGES)])
    nodes = dofs[:, local].reshape(-1, 3)
    _, first = np.unique(nodes[:, 0], return_index=True)  # a shared edge once
    nodes = nodes[np.sort(first)]
    return LinearConstraintBlock(
        np.repeat(nodes, 3, axis=0),
        np.tile(np.arange(3), nodes.shape[0])[:, None],
        _EDGE_ROW,
        name="C3D8 midside nodes",
        geometric=True,
    )


def linear_midsides(constraints: typing.Sequence) -> np.ndarray:
    """Sorted midside nodes fixed by :func:`trilinear_constraints` rows (maybe none)."""
    found = [
        c.nodes[np.all(np.isclose(c.coefficients, _EDGE_ROW), axis=1), 0]
        for c in constraints
        if isinstance(c, LinearConstraintBlock) and c.nodes.shape[1] == 3 and c.block_size == 3
    ]
    return np.unique(np.concatenate(found)) if found else np.zeros(0, np.int64)


def serendipity_centres(V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Sorted local block dofs of the face and cell centres of a degree-2 hexahedral space."""
    dofs = compat.cell_dofs(V)
    return np.unique(dofs[:, 20:27])


#: Coefficients of a face-centre row: the centre, its 4 corners, its 4 midside nodes.
_FACE_ROW = np.array([1.0, 0.25, 0.25, 0.25, 0.25, -0.5, -0.5, -0.5, -0.5])


def face_centres(constraints: typing.Sequence) -> np.ndarray:
    """Sorted nodes fixed by serendipity face-centre rows among ``constraints`` (maybe none).

    A row counts when it is a :class:`LinearConstraintBlock` row of 9 terms with the
    coefficients of :func:`serendipity_constraints` (the centre first).
    """
    found = [
        c.nodes[np.all(np.isclose(c.coefficients, _FACE_ROW), axis=1), 0]
        for c in constraints
        if isinstance(c, LinearConstraintBlock) and c.nodes.shape[1] == 9 and c.block_size == 3
    ]
    return np.unique(np.concatenate(found)) if found else np.zeros(0, np.int64)


def as_quad8(
    faces: SurfaceFaces, centres: np.ndarray, midsides: np.ndarray | None = None
) -> SurfaceFaces:
    """quad9 faces whose centre node is a serendipity face centre as ccx's quad8 faces.

    The centre's value is the quad8 interpolation of the other 8 nodes, so the face is the
    quad8 face (docs/method.md §13.5); other faces are returned unchanged. Faces whose four
    midside nodes are among ``midsides`` (:func:`linear_midsides`, C3D8 cells, §27) are
    bilinear: they become quad4 faces of their corners. A surface of both kinds is refused; on
    several processes a process without faces returns quad8 faces.
    """
    if faces.face_type is not QUAD9:
        return faces
    if faces.faces.shape[0] == 0:  # every process the same face type (docs/method.md §14.10)
        return SurfaceFaces(QUAD8, np.zeros((0, 8), faces.faces.dtype), faces.facets)
    constrained = np.isin(faces.faces[:, 8], centres)
    if not np.any(constrained):
        return faces
    if not np.all(constrained):
        raise ValueError(
            "a surface mixes serendipity (C3D20) and triquadratic faces: "
            f"{int(np.sum(~constrained))} of {constrained.size} face centres are free"
        )
    if midsides is not None and midsides.size:
        linear = np.all(np.isin(faces.faces[:, 4:8], midsides), axis=1)
        if np.all(linear):
            return SurfaceFaces(QUAD4, np.ascontiguousarray(faces.faces[:, :4]), faces.facets)
        if np.any(linear):
            raise ValueError(
                "a surface mixes faces of C3D8 and C3D20 elements: "
                f"{int(np.sum(linear))} of {linear.size} faces are C3D8 faces"
            )
    return SurfaceFaces(QUAD8, np.ascontiguousarray(faces.faces[:, :8]), faces.facets)


def add_centres(cells: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """27-node cells from 20-node ones (dolfinx order): face and cell centres appended to ``x``.

    ``cells`` are ``(C, 20)`` rows into ``x`` in dolfinx's order of a 27-node hexahedron
    (vertices, then edges). Centres are placed by the serendipity map of the 20 nodes
    (docs/method.md §13.5); a face shared by two cells gets one node (keyed by its sorted
    corners). Their rows come after those of ``x``.
    """
    rows = _local_rows()
    faces = np.stack([cells[:, independent] for _, independent, _ in rows[:6]], axis=1)
    weights = rows[0][2]
    face_x = np.einsum("cfk,cfkd->cfd", np.broadcast_to(weights, faces.shape), x[faces])
    keys = np.sort(faces[:, :, :4], axis=2).reshape(-1, 4)
    unique, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    num_faces = unique.shape[0]
    face_node = x.shape[0] + inverse.ravel().reshape(cells.shape[0], 6)
    cell_x = x[cells[:, :20]].transpose(0, 2, 1) @ rows[6][2]
    cell_node = x.shape[0] + num_faces + np.arange(cells.shape[0])
    x = np.vstack([x, face_x.reshape(-1, 3)[first], cell_x])
    return np.hstack([cells, face_node, cell_node[:, None]]), x


def element_forces_on_nodes(values: np.ndarray, space: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Element nodal forces of a broken Q2 vector as C3D20's: ``(cells, 20, 3)`` flattened.

    ``values`` is a vector of ``space``, a discontinuous degree-2 vector space on hexahedra
    (every cell's 27 nodal forces; owned entries). Each centre's force moves to the 20 nodes it
    depends on (virtual work), so that CalculiX's average element force (docs/method.md §7.1) is
    taken over the 20 nodes of each element, as ccx does. On several processes: the owned cells.
    """
    num_owned = space.mesh.topology.index_map(space.mesh.topology.dim).size_local
    dofs = compat.cell_dofs(space)[:num_owned]
    forces = np.asarray(values).reshape(-1, 3)[dofs]  # (cells, 27, 3)
    return (forces[:, :20] + np.einsum("kn,ckd->cnd", _CENTRE_WEIGHTS, forces[:, 20:])).ravel()


def _centre_weights() -> np.ndarray:
    """``(7, 20)``: value of face centre ``k`` (then the cell centre) from the 20 local nodes."""
    weights = np.zeros((7, 20))
    for k, (_, independent, w) in enumerate(_local_rows()):
        weights[k, independent] = w
    return weights


_CENTRE_WEIGHTS = _centre_weights()
