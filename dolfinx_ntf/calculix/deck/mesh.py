"""Mesh cards: ``*NODE``, ``*ELEMENT``, ``*NSET``, ``*ELSET``, ``*SURFACE``."""

from __future__ import annotations

import itertools
import math
import re

import numpy as np

from ..elements import ELEMENT_TYPES, REFUSED_ELEMENTS, frozen_array
from .data import NODE_TWIN, Surface
from .errors import DeckError, Location
from .lexer import INT_RE, Card
from .shells import SHELL_FACES, SHELL_TYPES
from .springs import SPRING_TYPES
from .state import ReaderState
from .wedges import C3D6_NODES


def _plain_ints(tokens: list[str]) -> list[int] | None:
    """The tokens as integers if all are plain ASCII digit strings (the common case), else None."""
    if all(map(str.isdigit, tokens)) and "".join(tokens).isascii():
        return list(map(int, tokens))
    return None


def _node_line(fields: list[str]) -> tuple[int, float, float, float] | None:
    """A plain ``n,x,y,z`` line (digits, finite floats without ccx's D exponent), else None."""
    if len(fields) != 4 or not (fields[0].isdigit() and fields[0].isascii()):
        return None
    try:
        x, y, z = float(fields[1]), float(fields[2]), float(fields[3])
    except ValueError:
        return None
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        return None
    return int(fields[0]), x, y, z


def _plain_nodes(
    lines: list[tuple[list[str], str, Location]],
) -> tuple[list[int], list[tuple[float, float, float]]] | None:
    """Numbers and coordinates of a ``*NODE`` card whose lines are all plain, or None.

    Plain as :func:`_node_line` takes a line (``n,x,y,z``, digits, finite floats), converted
    card-wide rather than line by line; otherwise the line-by-line reading checks each line.
    """
    fields = [f for f, _, _ in lines]
    if not all(len(f) == 4 for f in fields):
        return None
    numbers = [f[0] for f in fields]
    if not ("".join(numbers).isascii() and all(map(str.isdigit, numbers))):
        return None
    try:
        values = list(map(float, itertools.chain.from_iterable(f[1:] for f in fields)))
    except ValueError:
        return None
    if not np.isfinite(values).all():
        return None
    return list(map(int, numbers)), list(zip(values[0::3], values[1::3], values[2::3]))


def _plain_elements(
    lines: list[tuple[list[str], str, Location]], needed: int
) -> tuple[list[list[int]], list[Location]] | None:
    """Rows (element number, then nodes) of a plain ``*ELEMENT`` card, and each row's first line.

    Plain: digit strings only, every element ending where a line ends, as the line-by-line
    reading takes them; None otherwise (that reading then finds what is wrong).
    """
    starts: list[Location] = []
    count = 0
    for fields, _, location in lines:
        if not fields:
            return None
        if count == 0:
            starts.append(location)
        count += len(fields)
        if count == needed:
            count = 0
        elif count > needed:
            return None
    if count:
        return None
    tokens = list(itertools.chain.from_iterable(f for f, _, _ in lines))
    if not ("".join(tokens).isascii() and all(map(str.isdigit, tokens))):
        return None
    numbers = list(map(int, tokens))
    return [numbers[k : k + needed] for k in range(0, len(numbers), needed)], starts


class MeshCards(ReaderState):
    """Handlers of the mesh, set and surface cards."""

    def _k_NODE(self, card: Card) -> None:
        self._check_params(card, allowed={"NSET"})
        plain = _plain_nodes(card.lines)
        if plain is not None:  # the common case, read card-wide
            ids, coords = plain
            self.node_coords.extend(coords)
            self.node_locs.extend(loc for _, _, loc in card.lines)
            self.node_ids.extend(ids)
            if card.params.get("NSET"):
                self._add_set(self.nsets, "node", card.params["NSET"], ids, card.location)
            return
        ids: list[int] = []
        for fields, _, loc in card.lines:
            line = _node_line(fields)
            if line is None:  # not the plain "n,x,y,z": checked field by field
                if not 1 <= len(fields) <= 4:
                    raise DeckError("*NODE data line: node number, x, y, z", loc)
                xyz = [
                    self._optional_float(fields, i, "a coordinate", loc) or 0.0 for i in (1, 2, 3)
                ]
                line = (self._int(fields[0], "node number", loc), xyz[0], xyz[1], xyz[2])
            ids.append(line[0])
            self.node_coords.append(line[1:])
            self.node_locs.append(loc)
        self.node_ids.extend(ids)
        if card.params.get("NSET"):
            self._add_set(self.nsets, "node", card.params["NSET"], ids, card.location)

    def _k_ELEMENT(self, card: Card) -> None:
        self._check_params(card, allowed={"TYPE", "ELSET"}, required={"TYPE"})
        type_name = card.params["TYPE"] or ""
        if type_name in SPRING_TYPES:  # no mesh cells: springs.py
            self._spring_elements(card, type_name)
            return
        if type_name in SHELL_TYPES:  # expanded into bricks once read: shells.py
            self._shell_elements(card, type_name)
            return
        wedge = type_name == "C3D6"  # read as collapsed C3D8 (wedges.py)
        if type_name not in ELEMENT_TYPES and not wedge:
            supported = ", ".join([*ELEMENT_TYPES, "C3D6", *SHELL_TYPES, *SPRING_TYPES])
            why = REFUSED_ELEMENTS.get(type_name, "")
            raise DeckError(
                f"element type {type_name} is not supported{why} (supported: {supported})",
                card.location,
            )
        num_nodes = C3D6_NODES if wedge else ELEMENT_TYPES[type_name].num_nodes
        block = "C3D8" if wedge else type_name
        needed = num_nodes + 1
        ids: list[int] = []
        plain = _plain_elements(card.lines, needed)
        if plain is not None:  # the common case, read card-wide
            rows, starts = plain
            ids = [row[0] for row in rows]
            self._element_rows(block, [row[1:] for row in rows], wedge, ids, starts)
            card_lines: list = []
        else:
            card_lines = card.lines
        tokens: list[str] = []
        start: Location | None = None
        for fields, _, loc in card_lines:
            if not tokens:
                start = loc
            tokens.extend(fields)
            if len(tokens) < needed:
                continue
            if len(tokens) > needed:
                raise DeckError(
                    f"element {tokens[0]} has {len(tokens) - 1} nodes, {type_name} has {num_nodes}",
                    start,
                )
            numbers = _plain_ints(tokens) or [
                self._int(t, "element or node number", start) for t in tokens
            ]
            ids.append(numbers[0])
            self._element_rows(block, [numbers[1:]], wedge, [numbers[0]], [start])
            tokens = []
        if tokens:
            raise DeckError(
                f"element {tokens[0]} has {len(tokens) - 1} nodes, {type_name} has {num_nodes}",
                start,
            )
        if card.params.get("ELSET"):
            self._add_set(self.elsets, "element", card.params["ELSET"], ids, card.location)

    def _element_rows(self, block: str, rows: list[list[int]], wedge: bool, ids: list[int],
                      locations: list[Location]) -> None:  # fmt: skip
        """Append elements ``ids`` (node rows ``rows``) to ``block``, or to the wedges (C3D6)."""
        if wedge:
            for number, row, loc in zip(ids, rows, locations):
                if len(set(row)) != C3D6_NODES:
                    raise DeckError(f"element {number} repeats a node", loc)
            self.wedge_ids.extend(ids)
            self.wedge_rows.extend(rows)
            self.wedge_locs.extend(locations)
            return
        self.element_ids[block].extend(ids)
        self.element_rows[block].extend(rows)
        self.element_locs[block].extend(locations)

    def _add_set(self, sets: dict, kind: str, name: str, ids: list[int], loc: Location) -> None:
        sets.setdefault(name, []).extend(ids)
        self.set_locations.setdefault((kind, name), loc)

    def _k_NSET(self, card: Card) -> None:
        self._set_card(card, "NSET", self.nsets, "node")

    def _k_ELSET(self, card: Card) -> None:
        self._set_card(card, "ELSET", self.elsets, "element")

    def _set_card(self, card: Card, param: str, sets: dict, kind: str) -> None:
        self._check_params(card, allowed={param, "GENERATE"}, required={param})
        name = card.params[param] or ""
        members: list[int] = []
        for fields, _, loc in card.lines:
            if "GENERATE" in card.params:
                if len(fields) not in (2, 3):
                    raise DeckError(
                        f"{card.name}, GENERATE data line: first, last[, increment]", loc
                    )
                first, last = (self._int(t, f"{kind} number", loc) for t in fields[:2])
                inc = self._int(fields[2], "increment", loc) if len(fields) == 3 else 1
                if inc <= 0 or last < first:
                    raise DeckError(
                        f"{card.name}, GENERATE: need first <= last and increment > 0, got "
                        f"{first}, {last}, {inc}",
                        loc,
                    )
                ids = list(range(first, last + 1, inc))
                self._ref(kind, card, np.array(ids, dtype=np.int64), loc)
                members.extend(ids)
                continue
            for token in fields:
                if token == "":
                    continue
                if INT_RE.match(token):
                    self._ref(kind, card, np.array([int(token)], dtype=np.int64), loc)
                    members.append(int(token))
                elif token in sets:
                    members.extend(sets[token])
                else:
                    raise DeckError(f"{kind} set {token} is not defined (before this line)", loc)
        self._add_set(sets, kind, name, members, card.location)

    def _ref(self, kind: str, card: Card, ids: np.ndarray, loc: Location) -> None:
        (self.node_refs if kind == "node" else self.element_refs).append((card.name, ids, loc))

    def _k_SURFACE(self, card: Card) -> None:
        self._check_params(card, allowed={"NAME", "TYPE"}, required={"NAME"})
        stype = card.params.get("TYPE") or "ELEMENT"
        if stype not in ("ELEMENT", "NODE"):
            raise DeckError(f"*SURFACE TYPE={stype}: use TYPE=ELEMENT or TYPE=NODE", card.location)
        name = card.params["NAME"] or ""
        twin = self.surfaces.get(name)
        if twin is not None and twin.type != stype and name + NODE_TWIN not in self.surfaces:
            # a node and an element surface of one name: the element one keeps the name, the
            # node one (the slave of a contact pair, as in ccx) is NAME#NODES (docs/method.md §30)
            if stype == "ELEMENT":
                self.surfaces[name + NODE_TWIN] = self.surfaces.pop(name)
            key = name if stype == "ELEMENT" else name + NODE_TWIN
        else:
            key = self._new_name(card, self.surfaces, "surface")
        elements: list[np.ndarray] = []
        faces: list[np.ndarray] = []
        nodes: list[np.ndarray] = []
        for fields, _, loc in card.lines:
            fields = [f for f in fields if f != ""]
            if stype == "NODE":
                for token in fields:
                    nodes.append(self._nodes_of(token, card, loc))
                continue
            if len(fields) != 2:
                raise DeckError(
                    "*SURFACE data line: element or element set, face label S1..S6", loc
                )
            label = fields[1]
            if not (re.fullmatch(r"S[1-6]", label) or label in SHELL_FACES):
                raise DeckError(f"bad face label {label!r}: use S1..S6 (SPOS, SNEG on shells)", loc)
            ids = self._elements_of(fields[0], card, loc)
            self.element_refs.append((f"{card.name} face {label}", ids, loc))
            elements.append(ids)
            if label in SHELL_FACES:  # the expanded brick's bottom or top face
                self.shell_face_refs.append((ids, loc))
            face = SHELL_FACES.get(label) or int(label[1])
            faces.append(np.full(ids.size, face, dtype=np.int64))
        self.surfaces[key] = Surface(
            name=name,
            type=stype,
            elements=frozen_array(np.concatenate(elements) if elements else [], np.int64),
            faces=frozen_array(np.concatenate(faces) if faces else [], np.int64),
            nodes=frozen_array(np.concatenate(nodes) if nodes else [], np.int64),
            location=card.location,
        )
