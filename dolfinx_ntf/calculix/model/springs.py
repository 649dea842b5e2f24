"""The deck's spring elements as :class:`~dolfinx_ntf.DiscreteSprings` (docs/method.md §18.3).

SPRINGA is an :class:`~dolfinx_ntf.AxialSpring` (the current line where ccx iterates, the initial
one in linear steps), SPRING1 and SPRING2 are :class:`~dolfinx_ntf.DirectionalSpring` (SPRING1's
second end grounded) acting in the global directions of their degrees of freedom; a linear
``*SPRING`` is a :class:`~dolfinx_ntf.LinearSpringLaw`, ``NONLINEAR`` a
:class:`~dolfinx_ntf.TabularSpringLaw`.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

import dolfinx.fem

from dolfinx_ntf.fem.discrete_springs import DiscreteSprings
from dolfinx_ntf.kernels.discrete_springs import (
    AxialSpring,
    DirectionalSpring,
    LinearSpringLaw,
    SpringLaw,
    TabularSpringLaw,
)

from ..deck import Deck, SpringElements, Step

__all__ = ["check_springs", "deck_springs"]


def check_springs(deck: Deck, meshed: np.ndarray) -> bool | None:
    """Refuse what springs cannot do; whether SPRINGA follows its current line (None: no springs).

    ccx 2.20 takes SPRINGA's force along the current line and length whenever it iterates (NLGEOM,
    contact pairs, ``*DYNAMIC``), and the initial line only in a linear step, solved at once
    (measured, docs/method.md §18.3). ``meshed[row]``: the deck node belongs to a solid element. The
    same on every process.
    """
    if not deck.springs:
        return None
    for group in deck.springs:
        rows = deck.node_index(group.connectivity)
        loose = np.argwhere(~meshed[rows])
        if loose.size:
            e, k = loose[0]
            raise NotImplementedError(
                f"{group.location}: node {int(group.connectivity[e, k])} of {group.type} element "
                f"{int(group.ids[e])} belongs to no solid element: springs to such nodes are not "
                "supported yet (they need dofs outside the mesh)"
            )
    kinds = {_iterated(deck, step) for step in deck.steps}
    tables = [group for group in deck.springs if group.table is not None]
    if tables and False in kinds:
        raise NotImplementedError(
            f"{tables[0].location}: *SPRING, NONLINEAR in a linear step (no NLGEOM, no contact, "
            "static) is not supported: ccx 2.20 then takes the spring as linear with the table's "
            "slope at zero elongation (measured), which is not reproduced; use NLGEOM"
        )
    if len(kinds) > 1 and any(group.type == "SPRINGA" for group in deck.springs):
        raise NotImplementedError(
            f"{deck.springs[0].location}: SPRINGA elements in a deck with linear steps (one solve) "
            "and iterated ones (NLGEOM, contact, *DYNAMIC) are not supported yet"
        )
    return True in kinds


def _iterated(deck: Deck, step: Step) -> bool:
    """Whether ccx solves ``step`` by Newton iterations rather than one linear solve."""
    return step.nlgeom or bool(deck.contact_pairs) or step.dynamic is not None


def deck_springs(
    deck: Deck, V: dolfinx.fem.FunctionSpace, node_dof: np.ndarray, nlgeom: bool
) -> list[DiscreteSprings]:
    """One :class:`~dolfinx_ntf.DiscreteSprings` per ``*SPRING`` group. Collective.

    ``node_dof``: local block dof of each deck node (-1 where this process holds none); the
    springs get the nodes' global numbers from it (coincident nodes stay apart).
    """
    comm = V.mesh.comm
    held = node_dof >= 0
    global_node = np.full(node_dof.size, -1, dtype=np.int64)
    global_node[held] = V.dofmap.index_map.local_to_global(node_dof[held].astype(np.int32))
    comm.Allreduce(MPI.IN_PLACE, global_node, op=MPI.MAX)  # ghosts give the same number
    springs = []
    for group in deck.springs:
        rows = deck.node_index(group.connectivity)
        coordinates = deck.node_coords[rows]
        nodes = global_node[rows]
        if group.type == "SPRING1":  # the second end grounded at the node
            coordinates = np.concatenate([coordinates, coordinates], axis=1)
            nodes = np.column_stack([nodes[:, 0], np.full(nodes.shape[0], -1)])
        springs.append(
            DiscreteSprings(
                V, _element(group, nlgeom), coordinates[:, 0], coordinates[:, 1], nodes=nodes
            )
        )
    return springs


def _element(group: SpringElements, nlgeom: bool) -> AxialSpring | DirectionalSpring:
    """The spring element of a group with its law."""
    law: SpringLaw
    if group.table is not None:
        law = TabularSpringLaw(group.table[:, 0], group.table[:, 1])
    else:
        law = LinearSpringLaw(float(group.stiffness))
    if group.type == "SPRINGA":
        return AxialSpring(law, nlgeom=nlgeom)
    directions = np.eye(3)[[d - 1 for d in group.dofs]]
    return DirectionalSpring(
        law,
        tuple(directions[0]),
        tuple(directions[1]) if len(group.dofs) == 2 else None,
    )
