"""C3D15 wedges: what the deck runner needs of them and what it refuses (docs/method.md §34).

A C3D15 deck becomes an 18-node prism mesh with a degree-2 space whose quadrilateral face
centres are constrained to the serendipity wedge (``fem/serendipity_wedge.py``), integrated at
ccx's 9 points. dolfinx holds one cell type per mesh and runs degree-2 spaces on prisms from 0.11
on only (0.5.2's FFCx refuses prisms, 0.9 aborts the process while assembling P2 on prisms,
§32.5): older releases refuse the deck, naming the element's line. A prism mesh has no ``ds``
in dolfinx 0.11, so ``*DLOAD`` pressures become nodal forces with ccx's face rules (§34.4), and
element-face ``*SURFACE``s become :class:`~dolfinx_ntf.FaceNodesSurface`s of the deck's faces
for contact (§38).
"""

from __future__ import annotations

import typing
from dataclasses import dataclass

from petsc4py import PETSc

import numpy as np

import basix
import dolfinx.fem

from dolfinx_ntf.fem.discrete_springs import GlobalBlocks
from dolfinx_ntf.fem.serendipity_wedge import (
    QUADRATIC_PRISMS_MIN_DOLFINX,
    add_wedge_centres,
    require_quadratic_prisms,
)
from dolfinx_ntf.fem.surfaces import FaceNodesSurface
from dolfinx_ntf.fem.wedge_faces import c3d15_face_surface
from dolfinx_ntf.kernels.faces import (
    QUAD8,
    TRI6,
    film_matrices,
    flux_flows,
    pressure_forces,
)

from ..deck import Deck, ElementBlock, Surface, not_supported
from ..elements import ELEMENT_TYPES
from .mesh import MeshMaps

__all__ = [
    "C3D15_MIN_DOLFINX",
    "C3D15Films",
    "C3D15Pressures",
    "c3d15_exterior",
    "c3d15_face_flows",
    "c3d15_films",
    "c3d15_metadata",
    "c3d15_rule",
    "c3d15_surface",
    "check_c3d15_deck",
]

#: The first dolfinx release that assembles degree-2 spaces on prisms (docs/method.md §32.5).
C3D15_MIN_DOLFINX = QUADRATIC_PRISMS_MIN_DOLFINX

_G2 = 1.0 / np.sqrt(3.0)
#: ccx's rule for pressures on C3D15's quadrilaterals: 2 x 2 Gauss points (measured, §34.3).
_QUAD_RULE = (np.array([[x, y] for y in (-_G2, _G2) for x in (-_G2, _G2)]), np.ones(4))


def c3d15_rule() -> tuple[np.ndarray, np.ndarray]:
    """ccx's 9 points of C3D15 on dolfinx's reference prism and their weights (sum 1/2).

    The 3-point triangle rule (weights 1/6) times 3 Gauss points along the axis (5/18, 8/18,
    5/18 on ``[0, 1]``), triangle points fastest: ccx's ``*EL PRINT`` order.
    """
    points = ELEMENT_TYPES["C3D15"].integration_points
    axis = np.repeat([5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0], 3)
    return np.array(points), axis / 6.0


def c3d15_metadata() -> dict:
    """UFL integral metadata of :func:`c3d15_rule` (FFCx's custom rule)."""
    points, weights = c3d15_rule()
    return {
        "quadrature_rule": "custom",
        "quadrature_degree": 2,
        "quadrature_points": tuple(map(tuple, points.tolist())),
        "quadrature_weights": tuple(weights.tolist()),
    }


def check_c3d15_deck(deck: Deck, block: ElementBlock) -> None:
    """Refuse a C3D15 deck this dolfinx or the runner cannot reproduce (naming the deck line).

    Raises:
        ValueError: an element whose Jacobian is not positive at one of ccx's 9 points.
        NotImplementedError: dolfinx older than 0.11, pressures in decks mixing NLGEOM
            and small-strain steps, cyclic symmetry ties, ADJUST node sets of contact pairs,
            contact pairs and ties in thermal steps, transient coupled temperature-displacement
            steps, ADJUST and the ``.cel`` file with a master surface of triangles and
            quadrilaterals.
    """
    where = f"{block.locations[0]}: C3D15 (element {int(block.ids[0])})"
    require_quadratic_prisms(f"{where}: 15-node wedges", "§32.5, §34")
    for step in deck.steps:
        if step.dloads and any(other.nlgeom != step.nlgeom for other in deck.steps):
            raise NotImplementedError(
                f"{step.dloads[0].location}: *DLOAD pressures on C3D15 faces in a deck that mixes "
                "NLGEOM and small-strain steps are not supported yet (they are nodal forces on "
                f"the reference faces in the one, on the current faces in the other; {where})"
            )
    _check_jacobians(deck, block)
    for tie in deck.ties:
        if tie.cyclic:
            raise NotImplementedError(
                f"{tie.location}: *TIE {tie.name}, CYCLIC SYMMETRY on C3D15 elements is not "
                f"supported yet (not checked against ccx; {where}; docs/method.md §38)"
            )
    for pair in deck.contact_pairs:
        master = deck.surfaces[pair.master]
        kinds = np.unique(np.minimum(master.faces, 3)) if master.type == "ELEMENT" else []
        requests = [r for step in deck.steps for r in step.file_requests if r.contact_elements]
        if len(kinds) > 1 and pair.adjust is not None:
            raise NotImplementedError(
                f"{pair.location}: ADJUST with the master surface {pair.master} of both 6-node "
                f"triangles and 8-node quadrilaterals of C3D15 elements is not supported yet "
                f"({where}; docs/method.md §38.8)"
            )
        if len(kinds) > 1 and requests:
            raise not_supported(
                f"CONTACT ELEMENTS (the .cel file) with the master surface {pair.master} of both "
                f"6-node triangles and 8-node quadrilaterals of C3D15 elements (the pair at "
                f"{pair.location}; {where}; docs/method.md §38.8)",
                requests[0].location,
            )
    thermal = next((step for step in deck.steps if step.coupled), None)
    coupled = next((step for step in deck.steps if step.coupled and not step.coupled.heat), None)
    if thermal is not None and deck.ties:
        raise NotImplementedError(
            f"{deck.ties[0].location}: ties on C3D15 elements in a deck with thermal steps "
            f"({thermal.location}) are not supported yet (not checked against ccx; {where}; "
            "docs/method.md §38, §39)"
        )
    if coupled is not None and deck.contact_pairs:  # *HEAT TRANSFER steps are (§38.7)
        raise NotImplementedError(
            f"{deck.contact_pairs[0].location}: contact pairs on C3D15 elements in a deck with "
            f"*COUPLED TEMPERATURE-DISPLACEMENT steps ({coupled.location}) are not supported yet "
            f"(*HEAT TRANSFER steps are; not reproduced to ccx's digits; {where}; "
            "docs/method.md §38.7)"
        )
    for step in deck.steps:
        if step.coupled and not step.coupled.heat and not step.coupled.steady:
            raise NotImplementedError(
                f"{step.location}: transient *COUPLED TEMPERATURE-DISPLACEMENT steps with C3D15 "
                "elements are not supported yet (STEADY STATE ones and *HEAT TRANSFER are, "
                f"docs/method.md §39; {where})"
            )


@dataclass(frozen=True)
class C3D15Pressures:
    """The pressure-loaded faces of a C3D15 deck (``*DLOAD`` without ``ds``, §34.4).

    Attributes:
        keys: ``6 row + face - 1`` of each face (element row of the block, ccx face 1..5).
        group: ``(F,)`` the pressure group of each face (one history per group).
        num_groups: Number of groups.
    """

    keys: np.ndarray
    group: np.ndarray
    num_groups: int

    def faces(
        self, deck: Deck, block: ElementBlock
    ) -> list[tuple[typing.Any, np.ndarray, np.ndarray, typing.Any]]:
        """``(face type, deck node rows (F, n), group (F,), ccx's face rule)`` per face type."""
        rows, faces = self.keys // 6, self.keys % 6
        out = []
        for face_type, which in ((TRI6, faces < 2), (QUAD8, faces >= 2)):
            if np.any(which):
                local = block.type.faces[faces[which], : face_type.num_nodes]
                nodes = deck.node_index(block.connectivity[rows[which, None], local])
                rule = _QUAD_RULE if face_type is QUAD8 else None
                out.append((face_type, nodes, self.group[which], rule))
        return out

    def unit_forces(self, deck: Deck, block: ElementBlock) -> np.ndarray:
        """Nodal forces of a unit pressure on each group, on the reference faces.

        ``(groups, 3 nodes)`` over the deck's nodes, the same on every process.
        """
        out = np.zeros((self.num_groups, 3 * deck.node_ids.size))
        for face_type, nodes, group, rule in self.faces(deck, block):
            ones = np.ones(nodes.shape[0])
            forces = pressure_forces(face_type, deck.node_coords[nodes], ones, rule)
            columns = (3 * nodes[:, :, None] + np.arange(3)).reshape(nodes.shape[0], -1)
            rows = np.repeat(group, columns.shape[1])
            np.add.at(out, (rows, columns.ravel()), forces.ravel())
        return out


def c3d15_face_flows(
    deck: Deck, block: ElementBlock, rows: np.ndarray, faces: np.ndarray, flux: np.ndarray
) -> np.ndarray:
    """``(nodes,)`` nodal heat flows of uniform fluxes into C3D15 faces (``*DFLUX``, §39).

    Without ``ds`` on prism meshes (§34.4), as the pressures: the consistent flows of each face
    from its deck nodes with ccx's face rules (6-node triangles 3 points, 8-node quadrilaterals
    2 x 2), summed at the deck's nodes (the same on every process).

    Args:
        deck: The deck.
        block: Its C3D15 block.
        rows: ``(F,)`` element rows of the faces in the block.
        faces: ``(F,)`` ccx face numbers 1..5.
        flux: ``(F,)`` flux into each face.
    """
    out = np.zeros(deck.node_ids.size)
    for face_type, which in ((TRI6, faces <= 2), (QUAD8, faces > 2)):
        if np.any(which):
            local = block.type.faces[faces[which] - 1, : face_type.num_nodes]
            nodes = deck.node_index(block.connectivity[rows[which, None], local])
            rule = _QUAD_RULE if face_type is QUAD8 else None
            flows = flux_flows(face_type, deck.node_coords[nodes], flux[which], rule)
            np.add.at(out, nodes.ravel(), flows.ravel())
    return out


class C3D15Films:
    """``*FILM`` conditions on C3D15 faces of one face type, as element blocks of ``T`` (§39).

    No ``ds`` on prism meshes (§34.4): each face of an owned cell is a block of its nodes with
    the matrix ``h M`` (``M`` from ``kernels.faces.film_matrices`` with ccx's
    face rule) and the residual ``h M (T - T_sink)``: the heat flow out of the face. The
    :class:`~dolfinx_ntf.contact.thermal.HeatElementTerm` role.

    Args:
        T: The temperature.
        dofs: ``(F, n)`` local dofs of the faces' nodes.
        matrices: ``(F, n, n)`` face mass matrices.
        prescribed: Local dofs with a prescribed temperature (skipped in the blocks).
    """

    def __init__(
        self,
        T: dolfinx.fem.Function,
        dofs: np.ndarray,
        matrices: np.ndarray,
        prescribed: np.ndarray,
    ) -> None:
        index_map = T.function_space.dofmap.index_map
        glob = index_map.local_to_global(dofs.ravel().astype(np.int32)).astype(np.int64)
        glob = glob.reshape(dofs.shape)
        self._local = dofs
        self._dofs = np.where(np.isin(dofs, prescribed), -1, glob)
        self._matrices = matrices
        #: ``(F,)`` film coefficient and sink temperature of each face (0: no film).
        self.coefficient = np.zeros(dofs.shape[0])
        self.sink = np.zeros(dofs.shape[0])

    def evaluate(self, x: PETSc.Vec) -> GlobalBlocks:
        """The faces' blocks at the temperature ``x`` (local values, ghosts updated)."""
        with x.localForm() as local:
            T = local.array_r[self._local]
        K = self.coefficient[:, None, None] * self._matrices
        vector = np.einsum("fij,fj->fi", K, T - self.sink[:, None])
        return GlobalBlocks(self._dofs, K, vector)


def c3d15_films(
    deck: Deck,
    block: ElementBlock,
    T: dolfinx.fem.Function,
    node_dof: np.ndarray,
    element_cell: np.ndarray,
    keys: np.ndarray,
    prescribed: np.ndarray,
) -> list[tuple[C3D15Films, np.ndarray]]:
    """The film terms of the faces ``keys`` per face type (docs/method.md §39).

    Each with the positions in ``keys`` of its faces: those of cells this process owns.

    Args:
        deck: The deck.
        block: Its C3D15 block.
        T: The temperature.
        node_dof: Local dof of each deck node (-1 where this process has none).
        element_cell: Local cell of each element row (-1 elsewhere).
        keys: ``(F, 2)`` element row and ccx face (1..5) of each face with a film.
        prescribed: Local dofs with a prescribed temperature.
    """
    num_owned = T.function_space.mesh.topology.index_map(3).size_local
    cell = element_cell[keys[:, 0]]
    owned = (cell >= 0) & (cell < num_owned)
    out = []
    for face_type, which in ((TRI6, keys[:, 1] <= 2), (QUAD8, keys[:, 1] > 2)):
        positions = np.flatnonzero(which & owned)
        local = block.type.faces[keys[positions, 1] - 1, : face_type.num_nodes]
        nodes = deck.node_index(block.connectivity[keys[positions, 0, None], local])
        rule = _QUAD_RULE if face_type is QUAD8 else None
        matrices = film_matrices(face_type, deck.node_coords[nodes], rule)
        out.append((C3D15Films(T, node_dof[nodes], matrices, prescribed), positions))
    return out


def _check_jacobians(deck: Deck, block: ElementBlock) -> None:
    """Refuse elements whose map has a Jacobian ``<= 0`` at one of ccx's 9 points.

    The 18-node geometry the mesh gets (face centres by the quad8 map), differentiated with
    basix's degree-2 prism at the points: a wedge numbered against ccx's order (triangle 1-2-3
    counter-clockwise seen from 4-5-6) or folded would otherwise give a silent wrong answer.
    """
    etype = block.type
    cells = deck.node_index(block.connectivity)[:, etype.to_dolfinx]
    cells, x = add_wedge_centres(cells, np.asarray(deck.node_coords, dtype=np.float64))
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.prism, 2, basix.LagrangeVariant.equispaced
    )
    dphi = element.tabulate(1, etype.integration_points)[1:4, :, :, 0]  # (3, q, 18)
    jacobian = np.einsum("aqn,cnd->cqda", dphi, x[cells])
    det = np.linalg.det(jacobian)
    bad = np.flatnonzero(np.any(det <= 0.0, axis=1))
    if bad.size:
        k = int(bad[0])
        raise ValueError(
            f"{block.locations[k]}: C3D15 element {int(block.ids[k])} has a Jacobian <= 0 "
            f"({det[k].min():.3g}) at an integration point: its nodes are not in ccx's order "
            "(triangle 1-2-3 counter-clockwise seen from the triangle 4-5-6, midside nodes 7..15 "
            f"on 1-2, 2-3, 3-1, 4-5, 5-6, 6-4, 1-4, 2-5, 3-6) or it is folded "
            f"({bad.size} such element(s))"
        )


def c3d15_surface(deck: Deck, maps: MeshMaps, name: str, surface: Surface) -> FaceNodesSurface:
    """An element-face ``*SURFACE`` of a C3D15 deck as the faces' nodes (docs/method.md §38).

    ccx's faces S1, S2 are 6-node triangles, S3..S5 8-node quadrilaterals, in ccx's outward
    order (``ELEMENT_TYPES["C3D15"].faces``); a surface of both kinds gives the triangles as
    ``more`` faces (a master of both is searched as one surface, docs/method.md §38.8). The
    quadrilaterals' spring areas take ccx's 2 x 2 points (``QUAD8_GAUSS2``, 3 x 3 differ by up
    to 3e-6 of the contact stress on faces with curved edges, measured). On
    several processes each gives the faces of the elements it holds (owned and ghost cells).

    Raises:
        ValueError: a face that lies between two elements.
    """
    block = maps.block
    order = np.argsort(block.ids)
    rows = order[np.searchsorted(block.ids, surface.elements, sorter=order)]
    faces = surface.faces - 1
    inner = ~_exterior_faces(block)[rows, faces]
    if np.any(inner):
        k = int(np.argmax(inner))
        raise ValueError(
            f"{surface.location}: *SURFACE {name}: face S{surface.faces[k]} of element "
            f"{surface.elements[k]} lies between two elements, not on the boundary"
        )
    return _face_nodes_surface(deck, maps, rows, faces, name)


def c3d15_exterior(deck: Deck, maps: MeshMaps, name: str) -> FaceNodesSurface:
    """Every exterior face of a C3D15 deck by its nodes: a node-based surface's faces (§38).

    ccx's slave faces of a ``TYPE=NODE`` surface are the exterior faces with a corner in it
    (docs/method.md §2.1); the model's ``NodeSurface`` picks them from these.
    """
    rows, faces = np.nonzero(_exterior_faces(maps.block))
    return _face_nodes_surface(deck, maps, rows, faces, f"{name} (exterior faces)")


def _face_nodes_surface(
    deck: Deck, maps: MeshMaps, rows: np.ndarray, faces: np.ndarray, name: str
) -> FaceNodesSurface:
    """Faces (element rows, 0-based ccx faces) of the elements this process holds, per type."""
    block = maps.block
    held = maps.element_cell[rows] >= 0
    kinds = []  # quadrilaterals (ccx's 2 x 2 area rule, §38.2), triangles
    for size, which in ((8, faces >= 2), (6, faces < 2)):
        dofs = None
        if np.any(which):  # decided on the deck: the same kinds on every process
            take = which & held
            local = block.type.faces[faces[take], :size]
            nodes = block.connectivity[rows[take, None], local]
            dofs = maps.node_dof[deck.node_index(nodes)].astype(np.int32)
        kinds.append(dofs)
    return c3d15_face_surface(name, quadrilaterals=kinds[0], triangles=kinds[1])


def _exterior_faces(block: ElementBlock) -> np.ndarray:
    """``(E, 5)``: face ``f`` of element row ``e`` belongs to that element only."""
    etype = block.type
    corners = etype.faces[:, :4].copy()
    corners[etype.face_corner_counts == 3, 3] = -1
    keys = np.where(corners >= 0, block.connectivity[:, np.maximum(corners, 0)], -1)
    keys = np.sort(keys.reshape(-1, 4), axis=1)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    return (counts[inverse.ravel()] == 1).reshape(block.ids.size, etype.num_faces)
