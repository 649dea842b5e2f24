"""Faces of deck surfaces in ccx's outward node order: element-face and nodal surfaces.

See docs/method.md §2.1 and §8.5.
"""

from __future__ import annotations

import numpy as np

from .data import Deck, Surface
from .lexer import normalized_name


def _surface(deck: Deck, surface: Surface | str) -> Surface:
    if isinstance(surface, Surface):
        return surface
    name = normalized_name(surface)
    if name not in deck.surfaces:
        raise ValueError(f"surface {name} is not defined in {deck.path}")
    return deck.surfaces[name]


def face_nodes(deck: Deck, surface: Surface | str) -> np.ndarray:
    """Node numbers ``(F, n)`` of the faces of an element-face surface, in CalculiX face order.

    ``surface`` is one of ``deck``'s surfaces or its name.

    Faces follow the surface definition order; node order is ccx's outward order (corners
    counter-clockwise seen from outside the element, then midside nodes).

    Raises:
        ValueError: nodal surface, or faces of different sizes (e.g. tets and hexes mixed).
    """
    surf = _surface(deck, surface)
    if surf.type != "ELEMENT":
        raise ValueError(
            f"surface {surf.name} ({surf.location}) is a nodal surface (TYPE=NODE): it has no "
            "faces; use node_surface_faces() for the faces ccx assigns to it"
        )
    if surf.elements.size == 0:
        return np.zeros((0, 0), dtype=np.int64)
    type_index, row = deck.element_location(surf.elements)
    blocks = list(deck.elements.values())
    # C3D15's 6-node triangles pad the element's face table with -1 (ElementType.face_sizes)
    sizes = {
        int(size)
        for k in np.unique(type_index)
        for size in blocks[k].type.face_sizes[surf.faces[type_index == k] - 1]
    }
    if len(sizes) > 1:
        raise ValueError(
            f"surface {surf.name} ({surf.location}) mixes faces with {sorted(sizes)} nodes; "
            "split it by element type (or C3D15 triangles and quadrilaterals)"
        )
    width = sizes.pop()
    result = np.empty((surf.elements.size, width), dtype=np.int64)
    for k in np.unique(type_index):
        block = blocks[k]
        mask = type_index == k
        local = block.type.faces[surf.faces[mask] - 1, :width]  # (m, n) element-local indices
        result[mask] = block.connectivity[row[mask][:, None], local]
    return result


def surface_nodes(deck: Deck, surface: Surface | str) -> np.ndarray:
    """Sorted unique node numbers of a surface (its listed nodes, or all nodes of its faces).

    ``surface`` is one of ``deck``'s surfaces or its name.
    """
    surf = _surface(deck, surface)
    if surf.type == "NODE":
        return np.unique(surf.nodes)
    if surf.elements.size == 0:
        return np.zeros(0, dtype=np.int64)
    type_index, row = deck.element_location(surf.elements)
    blocks = list(deck.elements.values())
    nodes = []
    for k in np.unique(type_index):  # faces of any sizes (C3D15's triangles beside quadrilaterals)
        mask = type_index == k
        local = blocks[k].type.faces[surf.faces[mask] - 1]  # -1 pads C3D15's triangles
        picked = blocks[k].connectivity[row[mask][:, None], np.maximum(local, 0)]
        nodes.append(picked[local >= 0])
    return np.unique(np.concatenate(nodes))


def external_faces(deck: Deck) -> np.ndarray:
    """Node numbers ``(F, n)`` of every face that belongs to exactly one element of ``deck``.

    See docs/method.md §2.1.

    Faces are in ccx outward order, grouped by element block then element then face number.

    Raises:
        ValueError: the mesh mixes face sizes (e.g. C3D4 and C3D8).
    """
    faces = []
    for block in deck.elements.values():
        if block.ids.size:
            n = block.type.faces.shape[1]
            faces.append(block.connectivity[:, block.type.faces].reshape(-1, n))
    if not faces:
        return np.zeros((0, 0), dtype=np.int64)
    if len({f.shape[1] for f in faces}) > 1:
        raise ValueError(f"{deck.path}: the mesh mixes face sizes; external faces need one type")
    all_faces = np.concatenate(faces)
    corners = 3 if all_faces.shape[1] in (3, 6) else 4
    key = np.sort(all_faces[:, :corners], axis=1)
    # collapsed wedges (docs/method.md §30): a triangle face repeats a corner, in a different
    # slot in each of its two wedges, so a repeat is keyed as -1; the collapsed face (two
    # distinct corners) is no face at all
    repeat = np.zeros(key.shape, dtype=bool)
    repeat[:, 1:] = key[:, 1:] == key[:, :-1]
    all_faces = all_faces[np.sum(~repeat, axis=1) >= 3]
    key = np.sort(np.where(repeat, -1, key)[np.sum(~repeat, axis=1) >= 3], axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return all_faces[counts[inverse.ravel()] == 1]


def node_surface_faces(deck: Deck, surface: Surface | str) -> np.ndarray:
    """Faces ``(F, n)`` that ccx uses as slave faces of a surface (docs/method.md §2.1).

    ``surface`` is one of ``deck``'s surfaces or its name.

    Element-face surface: its faces. Nodal surface (``TYPE=NODE``): every external face of the
    whole mesh with at least one *corner* node in the surface.
    """
    surf = _surface(deck, surface)
    if surf.type == "ELEMENT":
        return face_nodes(deck, surf)
    faces = external_faces(deck)
    if faces.size == 0:
        return faces
    corners = 3 if faces.shape[1] in (3, 6) else 4
    return faces[np.isin(faces[:, :corners], surf.nodes).any(axis=1)]
