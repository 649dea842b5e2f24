r"""The deck's ``*SURFACE`` cards as dolfinx surfaces.

Element-face surfaces become facet tags (one ``MeshTags`` per ccx surface, value 1) wrapped in
:class:`~dolfinx_ntf.FacetSurface`, with the ccx node numbers of each face for the contact-element
output; ``TYPE=NODE`` surfaces become :class:`~dolfinx_ntf.NodeSurface` (corner vertices, and the
midside nodes of C3D20 elements; on 2D elements all of them faceless, as in ccx). On C3D15's prism
meshes, which have no facet numbering in dolfinx 0.11, element-face surfaces are
:class:`~dolfinx_ntf.FaceNodesSurface`\ s of the deck's faces, without tags (docs/method.md §38).
"""

from __future__ import annotations

import numpy as np

import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.fem.surfaces import FaceNodesSurface, FacetSurface, NodeSurface

from ..deck import Deck, not_supported
from .c3d15 import c3d15_exterior, c3d15_surface
from .mesh import MeshMaps, element_faces_to_facets, exterior

__all__ = ["deck_surfaces"]


def deck_surfaces(
    deck: Deck, mesh: dolfinx.mesh.Mesh, maps: MeshMaps
) -> tuple[
    dict[str, FacetSurface | NodeSurface | FaceNodesSurface],
    dict[str, compat.MeshTags],
    dict[str, tuple[np.ndarray, np.ndarray]],
]:
    """Every ``*SURFACE`` of the deck: the dolfinx surfaces, facet tags and ccx face nodes.

    Returns ``(surfaces, surface_tags, surface_faces)`` as :class:`CalculixModel` holds them
    (C3D15's element-face surfaces have no tags and no facets). Local work: a bad face is a
    ``ValueError`` on the processes that see it.
    """
    surfaces: dict[str, FacetSurface | NodeSurface | FaceNodesSurface] = {}
    tags: dict[str, compat.MeshTags] = {}
    faces: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    node_vertex, corner = maps.node_vertex, maps.corner
    for name, surface in deck.surfaces.items():
        if surface.type == "NODE":
            rows = deck.node_index(surface.nodes)
            if not np.all(maps.meshed[rows]):
                node = int(surface.nodes[np.argmax(~maps.meshed[rows])])
                raise ValueError(
                    f"{surface.location}: *SURFACE {name}, TYPE=NODE: node {node} belongs to no "
                    "element"
                )
            vertices, dofs = node_vertex[rows], maps.node_dof[rows]
            # midside nodes of quadratic elements, and nodes in no element (on carrier cells,
            # §29.6): no face area, ccx's fallback
            carried = maps.carried[rows] if maps.carried is not None else np.zeros(rows.size, bool)
            midside = np.unique(dofs[~corner[rows] & (dofs >= 0)]).astype(np.int32)
            vertices = np.where(carried, -1, vertices)
            # ccx's node sets of 2D elements: the 2D nodes are in none of its expanded
            # elements, every spring gets the fallback area (docs/method.md §26.3)
            faceless = maps.block.type.tdim == 2
            known = corner[rows] | carried
            if not np.all(known) and maps.block.type.num_nodes not in (15, 20) and not faceless:
                node = int(surface.nodes[np.argmax(~known)])
                raise not_supported(
                    f"*SURFACE {name}, TYPE=NODE with node {node}, which is not an element "
                    f"corner, on {maps.block.type.name} elements (midside nodes of "
                    "node-based surfaces: C3D20 and C3D15 only)",
                    surface.location,
                )
            vertices = np.unique(vertices[vertices >= 0]).astype(np.int32)  # this process's
            # C3D15: the exterior faces by their nodes, a prism mesh has no facets (§38)
            wedges = maps.block.type.name == "C3D15"
            outer = c3d15_exterior(deck, maps, name) if wedges else None
            surfaces[name] = NodeSurface(
                vertices, name, midside_nodes=midside, faceless=faceless, exterior=outer
            )
            continue
        if maps.block.type.name == "C3D15":  # no facets on prism meshes (docs/method.md §38)
            surfaces[name] = c3d15_surface(deck, maps, name, surface)
            continue
        facets, nodes = element_faces_to_facets(
            deck, maps, surface.elements, surface.faces, f"*SURFACE {name}", surface.location
        )
        facets, first = np.unique(facets, return_index=True)
        if facets.size and facets[0] < 0:  # faces of other processes' elements
            facets, first = facets[1:], first[1:]
        inner = ~exterior(mesh, facets)
        if np.any(inner):
            k = int(np.argmax(inner))
            raise ValueError(
                f"{surface.location}: *SURFACE {name}: face S{surface.faces[first[k]]} of element "
                f"{surface.elements[first[k]]} lies between two elements, not on the boundary"
            )
        tag = dolfinx.mesh.meshtags(
            mesh,
            mesh.topology.dim - 1,
            facets.astype(np.int32),
            np.ones(facets.size, dtype=np.int32),
        )
        tag.name = name
        tags[name] = tag
        faces[name] = (facets, nodes[first])
        surfaces[name] = FacetSurface(tag, 1)
    return surfaces, tags, faces
