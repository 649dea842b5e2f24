"""The deck's ``*EQUATION`` cards as linear constraints on ccx node numbers (docs/method.md §13.1).

Terms on nodes in no element (reference nodes) are either prescribed (a ``*BOUNDARY`` somewhere:
their values move to the right-hand side) or free (eliminated through one equation,
:class:`FreeReference`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dolfinx_ntf.fem.constraints import LinearConstraint

from ..deck import Deck

__all__ = ["FreeReference", "equation_constraints"]


@dataclass(frozen=True, eq=False)
class FreeReference:
    """A component of a node in no element, unknown and eliminated by one ``*EQUATION``.

    ``u_ref = sum(mesh_weights * u[mesh_dofs]) + sum(reference_weights * prescribed values of
    reference_keys)``; a force on it acts on ``mesh_dofs`` with ``mesh_weights`` (virtual work).

    Attributes:
        key: ``3 node row + component`` of the reference component.
        mesh_keys, mesh_weights: Keys ``3 node row + component`` of the mesh terms (nodes of
            elements, on any process) and their weights.
        reference_keys, reference_weights: Prescribed reference components and their weights.
    """

    key: int
    mesh_keys: np.ndarray
    mesh_weights: np.ndarray
    reference_keys: np.ndarray
    reference_weights: np.ndarray


def equation_constraints(
    deck: Deck, meshed: np.ndarray
) -> tuple[list[LinearConstraint], list[tuple[int, np.ndarray, np.ndarray]], list[FreeReference]]:
    """``*EQUATION`` cards as constraints on ccx node numbers (docs/method.md §13.1).

    ``meshed[row]``: the deck node belongs to an element (on any process). Terms are keyed
    ``3 node row + component``. Components of nodes in no element (reference
    nodes) with a ``*BOUNDARY`` somewhere are *prescribed*: returned apart as ``(constraint, keys,
    coefficients)``, their values become right-hand sides. The others are *free*: the first
    equation holding one expresses it by the equation's other terms (a :class:`FreeReference`)
    and is used up; the others get it substituted.
    """
    prescribed = {
        int(k)
        for card in (*deck.boundaries, *(b for step in deck.steps for b in step.boundaries))
        for k in (
            3 * deck.node_index(card.nodes)[:, None] + np.arange(card.first_dof - 1, card.last_dof)
        ).ravel()
    }
    equations = []  # (location, {key: coefficient} in term order)
    for equation in deck.equations:
        keys = 3 * deck.node_index(equation.nodes) + equation.dofs - 1
        terms: dict[int, float] = {}
        for key, a in zip(keys.tolist(), equation.coefficients.tolist()):
            terms[key] = terms.get(key, 0.0) + a
        equations.append((equation.location, terms))

    def free(key: int) -> bool:
        return not meshed[key // 3] and key not in prescribed

    loaded = {
        int(k)
        for step in deck.steps
        for card in step.cloads
        for k in 3 * deck.node_index(card.nodes) + card.dof - 1
    }
    references: list[FreeReference] = []
    used: set[int] = set()
    for key in dict.fromkeys(k for _, terms in equations for k in terms if free(k)):
        holders = [i for i, (_, terms) in enumerate(equations) if key in terms and i not in used]
        location, terms = equations[holders[0]]
        if [k for k in terms if free(k)] != [key]:
            raise ValueError(
                f"{location}: *EQUATION: more than one component of nodes in no element without "
                "a *BOUNDARY in one equation is not supported"
            )
        a = terms[key]
        weights = {k: -c / a for k, c in terms.items() if k != key}
        used.add(holders[0])
        for i in holders[1:]:
            _, other = equations[i]
            factor = other.pop(key)
            for k, w in weights.items():
                other[k] = other.get(k, 0.0) + factor * w
        mesh = [k for k in weights if meshed[k // 3]]
        refs = [k for k in weights if not meshed[k // 3]]
        references.append(
            FreeReference(
                key,
                np.array(mesh, dtype=np.int64),
                np.array([weights[k] for k in mesh]),
                np.array(refs, dtype=np.int64),
                np.array([weights[k] for k in refs]),
            )
        )
    constraints, reference_terms = [], []
    for i, (location, terms) in enumerate(equations):
        if i in used:
            continue
        keys = np.array(list(terms), dtype=np.int64)
        coefficients = np.array(list(terms.values()))
        mesh = meshed[keys // 3]
        if not np.any(mesh):
            raise ValueError(f"{location}: *EQUATION: no node of it belongs to an element")
        for key in keys[~mesh]:
            if int(key) in loaded:
                node = int(deck.node_ids[key // 3])
                raise ValueError(
                    f"{location}: *EQUATION node {node} belongs to no element and carries a "
                    "*CLOAD in a direction with a *BOUNDARY: not supported"
                )
        if not np.all(mesh):
            reference_terms.append((len(constraints), keys[~mesh], coefficients[~mesh]))
        constraints.append(
            LinearConstraint(
                deck.node_ids[keys[mesh] // 3], keys[mesh] % 3, coefficients[mesh],
                name=f"*EQUATION at {location}",
            )
        )  # fmt: skip
    return constraints, reference_terms, references
