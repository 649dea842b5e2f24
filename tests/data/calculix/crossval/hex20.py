"""C3D8 decks turned into C3D20 / C3D20R decks: a midside node on every edge (docs/method.md §13.5).

``to_hex20(path, reduced)`` rewrites a deck of ``write_inp``: the ``*NODE`` block gets one node at
the middle of every element edge (numbered after the last node), every ``*ELEMENT, TYPE=C3D8``
block becomes ``C3D20`` (or ``C3D20R``) with ccx's 20-node order, and every ``*NSET`` other than
the ``*NODE`` set and every ``*SURFACE, TYPE=NODE`` gains the midside nodes of the edges whose two
ends it holds (sets of the decks are planes or faces). Element-face surfaces keep their faces
S1..S6, which C3D20 numbers like C3D8. ``move_nodes`` then moves the nodes of an element set.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dolfinx_ntf.calculix.deck import read_deck

__all__ = ["to_hex20"]

#: C3D20 midside nodes 9..20 on these C3D8 corner pairs (0-based), ccx manual.
EDGES = np.array(
    [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4], [0, 4], [1, 5], [2, 6], [3, 7]]
)


def to_hex20(path: Path, reduced: bool = False) -> None:
    """Rewrite the C3D8 deck ``path`` in place as a C3D20 (``reduced``: C3D20R) deck."""
    deck = read_deck(path)
    block = deck.elements["C3D8"]
    ends = np.sort(block.connectivity[:, EDGES], axis=2).reshape(-1, 2)
    unique, inverse = np.unique(ends, axis=0, return_inverse=True)
    first_id = int(deck.node_ids.max()) + 1
    mid_ids = first_id + np.arange(unique.shape[0])
    x = np.asarray(deck.node_coords)
    mid_x = 0.5 * (x[deck.node_index(unique[:, 0])] + x[deck.node_index(unique[:, 1])])
    midside = mid_ids[inverse.ravel()].reshape(-1, 12)
    connectivity = dict(zip(block.ids.tolist(), np.hstack([block.connectivity, midside])))
    name = "C3D20R" if reduced else "C3D20"

    out: list[str] = []
    section = ""
    members: list[int] = []
    for line in path.read_text().splitlines():
        if line.startswith("*"):
            if section == "NSET":
                out.extend(_lines(_with_midsides(members, unique, mid_ids)))
            if section == "NODE SURFACE":
                out.extend(map(str, _with_midsides(members, unique, mid_ids)))
            section = ""
            upper = line.upper().replace(" ", "")
            if upper.startswith("*NODE,") or upper == "*NODE":
                section = "NODE"
                out.append(line)
                for ids, coords in ((deck.node_ids, x), (mid_ids, mid_x)):
                    out.extend(_node_line(i, p) for i, p in zip(ids.tolist(), coords.tolist()))
                continue
            if upper.startswith("*ELEMENT,") and "TYPE=C3D8" in upper:
                section = "ELEMENT"
                out.append(line.replace("C3D8", name))
                continue
            if upper.startswith("*NSET,"):
                section, members = "NSET", []
            if upper.startswith("*SURFACE,") and "TYPE=NODE" in upper:
                section, members = "NODE SURFACE", []
            out.append(line)
            continue
        if section == "NODE":
            continue
        if section == "ELEMENT":
            element = int(line.split(",")[0])
            nodes = [element, *connectivity[element].tolist()]
            out.append(", ".join(map(str, nodes[:11])) + ",")
            out.append(", ".join(map(str, nodes[11:])))
            continue
        if section in ("NSET", "NODE SURFACE"):
            members += [int(t) for t in line.replace(",", " ").split()]
            continue
        out.append(line)
    if section == "NSET":
        out.extend(_lines(_with_midsides(members, unique, mid_ids)))
    if section == "NODE SURFACE":
        out.extend(map(str, _with_midsides(members, unique, mid_ids)))
    path.write_text("\n".join(out) + "\n")


def _node_line(node: int, x: list[float]) -> str:
    return f"{node}, " + ", ".join(repr(float(v)) for v in x)


def _with_midsides(members: list[int], ends: np.ndarray, mid_ids: np.ndarray) -> list[int]:
    inside = np.isin(ends, members).all(axis=1)
    return [*members, *mid_ids[inside].tolist()]


def _lines(ids: list[int]) -> list[str]:
    return [", ".join(map(str, ids[i : i + 16])) for i in range(0, len(ids), 16)]


def move_nodes(path: Path, elset: str, function) -> None:
    """Move every node of the elements of ``elset`` to ``function(x)`` (``(n, 3)`` arrays)."""
    deck = read_deck(path)
    block = next(b for b in deck.elements.values() if b.ids.size)
    members = np.isin(block.ids, deck.elsets[elset])
    ids = np.unique(block.connectivity[members])
    x = np.asarray(deck.node_coords)[deck.node_index(ids)]
    moved = dict(zip(ids.tolist(), function(x)))
    out, section = [], False
    for line in path.read_text().splitlines():
        if line.startswith("*"):
            section = line.upper().replace(" ", "").startswith("*NODE,") or line.upper() == "*NODE"
        elif section and int(line.split(",")[0]) in moved:
            node = int(line.split(",")[0])
            line = f"{node}, " + ", ".join(repr(float(v)) for v in moved[node])
        out.append(line)
    path.write_text("\n".join(out) + "\n")
