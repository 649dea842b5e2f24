"""Decks that mix C3D8 with C3D20 or C3D20R elements: one mesh of 20-node elements.

dolfinx puts one element type in one space, so the C3D8 elements become 20-node elements of
the deck's quadratic type (:func:`mixed_hexahedra`): a midside node is added on every edge of a
C3D8 element, at its midpoint, and the model fixes it to the mean of the edge's end nodes
(``serendipity.trilinear_constraints``), so the field on those cells is C3D8's trilinear one.
Their integration points stay C3D8's (2x2x2 Gauss): with C3D20R that is the quadratic cells'
rule too, with C3D20 the volume integrals are split by cell (:class:`CellMeasures`).
See docs/method.md §27.
"""

from __future__ import annotations

import dataclasses

import numpy as np

import dolfinx.mesh
import ufl

from dolfinx_ntf import compat

from ..deck import Deck, ElementBlock
from ..elements import ELEMENT_TYPES

__all__ = ["CellMeasures", "MixedHexahedra", "check_mixed_deck", "mixed_hexahedra"]

#: ccx C3D20 midside nodes 9..20 as edges between its corners (0-based, ccx order).
_C3D20_EDGES = np.array(
    [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4], [0, 4], [1, 5], [2, 6],
     [3, 7]]
)  # fmt: skip


@dataclasses.dataclass(frozen=True, eq=False)
class MixedHexahedra:
    """What :func:`mixed_hexahedra` changed.

    Attributes:
        linear: ``(E,)`` flags of the merged block's rows that were C3D8 elements.
        added_nodes: ``(A,)`` numbers of the added midside nodes (after the deck's largest).
    """

    linear: np.ndarray
    added_nodes: np.ndarray


def mixed_hexahedra(deck: Deck) -> tuple[Deck, MixedHexahedra | None]:
    """The deck with its C3D8 elements as 20-node elements of its C3D20/C3D20R type.

    Decks of one element type, or other mixes, are returned unchanged (None). A C3D8 edge that
    is also the edge of a quadratic element is refused (the two fields would not match there).
    """
    blocks = {name: b for name, b in deck.elements.items() if b.ids.size}
    quadratic = sorted(set(blocks) & {"C3D20", "C3D20R"})
    if set(blocks) - {"C3D8", "C3D20", "C3D20R"} or "C3D8" not in blocks or len(quadratic) != 1:
        return deck, None
    linear_block, quad_block = blocks["C3D8"], blocks[quadratic[0]]
    corners = linear_block.connectivity  # (L, 8) node numbers
    edges = np.sort(corners[:, _C3D20_EDGES], axis=2).reshape(-1, 2)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    quad_edges = np.sort(quad_block.connectivity[:, _C3D20_EDGES], axis=2).reshape(-1, 2)
    shared = np.isin(
        unique.view([("a", np.int64), ("b", np.int64)]).ravel(),
        np.ascontiguousarray(quad_edges).view([("a", np.int64), ("b", np.int64)]).ravel(),
    )
    if np.any(shared):
        a, b = unique[np.argmax(shared)]
        raise NotImplementedError(
            f"{deck.path}: the edge between nodes {a} and {b} belongs to a C3D8 and a "
            f"{quadratic[0]} element: C3D8 and quadratic elements may not share edges"
        )
    added = int(deck.node_ids.max()) + 1 + np.arange(unique.shape[0], dtype=np.int64)
    x = deck.node_coords[deck.node_index(unique)].mean(axis=1)
    midsides = added[inverse.ravel()].reshape(-1, 12)
    connectivity = np.vstack([np.hstack([corners, midsides]), quad_block.connectivity])
    merged = ElementBlock(
        ELEMENT_TYPES[quadratic[0]],
        np.concatenate([linear_block.ids, quad_block.ids]),
        connectivity,
        tuple(linear_block.locations) + tuple(quad_block.locations),
    )
    elements = {name: b for name, b in deck.elements.items() if name not in ("C3D8", *quadratic)}
    elements[quadratic[0]] = merged
    new = dataclasses.replace(
        deck,
        node_ids=np.concatenate([deck.node_ids, added]),
        node_coords=np.vstack([deck.node_coords, x]),
        elements=elements,
    )
    linear = np.zeros(merged.ids.size, dtype=bool)
    linear[: linear_block.ids.size] = True
    return new, MixedHexahedra(linear, added)


class CellMeasures:
    """Volume measures with their own quadrature on tagged cells; ``f * measures`` sums them.

    The integrand times each measure, added up: the forms of a mesh whose cells take different
    integration rules (C3D8's 2x2x2 beside C3D20's 3x3x3).
    """

    def __init__(
        self,
        mesh: dolfinx.mesh.Mesh,
        tags: compat.MeshTags,
        degrees: dict[int, int | dict | None],
    ) -> None:
        """Measures ``dx(tag)`` of quadrature degree ``degrees[tag]`` (None: UFL's estimate).

        A dict instead of a degree is the integral's metadata itself (e.g. a custom rule).
        """
        self.measures = [
            ufl.Measure(
                "dx",
                domain=mesh,
                subdomain_data=tags,
                metadata=rule
                if isinstance(rule, dict)
                else {}
                if rule is None
                else {"quadrature_degree": rule},
            )(tag)
            for tag, rule in degrees.items()
        ]

    def __rmul__(self, integrand: ufl.core.expr.Expr) -> ufl.Form:
        """``integrand * dx`` over every tagged cell, each with its rule."""
        forms = [integrand * m for m in self.measures]
        return sum(forms[1:], forms[0])


def check_mixed_deck(deck: Deck) -> None:
    """Refuse what a mixed C3D8/C3D20 deck cannot do yet (naming the card).

    Element output (``*EL PRINT``, ``.frd`` files: the element types and stresses of both
    kinds), ``*DLOAD`` pressures (the face rules differ), coupled temperature steps and
    ``*FREQUENCY`` steps were not measured against ccx.
    """
    for step in deck.steps:
        what = None
        if step.el_prints:
            what, where = "*EL PRINT", step.el_prints[0].location
        elif step.file_requests:
            what, where = step.file_requests[0].keyword, step.file_requests[0].location
        elif step.dloads:
            what, where = "*DLOAD pressures", step.dloads[0].location
        elif step.coupled is not None or step.frequency is not None:
            what, where = "coupled and frequency steps", step.location
        if what is not None:
            raise NotImplementedError(
                f"{where}: {what} in a deck that mixes C3D8 and C3D20/C3D20R elements is not "
                "supported yet (docs/method.md §27)"
            )
