"""Spring cards: ``*ELEMENT, TYPE=SPRINGA|SPRING1|SPRING2`` and ``*SPRING`` (docs/method.md §18.3).

Spring elements are no mesh cells: the reader keeps them apart from the solid element blocks and
``_finish_springs`` joins each set of them to its ``*SPRING`` behaviour (one
:class:`~dolfinx_ntf.calculix.deck.SpringElements` per ``*SPRING`` card). As in ccx, the first
data line of ``*SPRING`` holds degrees of freedom when its numbers are integers (SPRING1,
SPRING2), else it is the first behaviour line (SPRINGA: ccx drops the blank line).
"""

from __future__ import annotations

import numpy as np

from ..elements import frozen_array
from .data import SpringElements
from .errors import DeckError, Location
from .lexer import INT_RE, Card
from .state import ReaderState

#: Spring element types and their number of nodes.
SPRING_TYPES = {"SPRINGA": 2, "SPRING1": 1, "SPRING2": 2}


class SpringCards(ReaderState):
    """Handlers of the spring element and ``*SPRING`` cards."""

    def _spring_elements(self, card: Card, type_name: str) -> None:
        """The data lines of ``*ELEMENT, TYPE=SPRING...``: element number, then its nodes."""
        needed = SPRING_TYPES[type_name] + 1
        rows = self.spring_rows.setdefault(type_name, [])
        ids: list[int] = []
        for fields, _, loc in card.lines:
            fields = [f for f in fields if f != ""]
            if len(fields) != needed:
                raise DeckError(
                    f"{type_name} element line: element number and {needed - 1} node(s), got "
                    f"{len(fields)} fields",
                    loc,
                )
            numbers = [self._int(t, "element or node number", loc) for t in fields]
            rows.append((numbers[0], numbers[1:], loc))
            self.node_refs.append((f"{type_name} element {numbers[0]}",
                                   np.array(numbers[1:], dtype=np.int64), loc))  # fmt: skip
            ids.append(numbers[0])
        if card.params.get("ELSET"):
            self._add_set(self.elsets, "element", card.params["ELSET"], ids, card.location)

    def _k_SPRING(self, card: Card) -> None:
        self._check_params(card, allowed={"ELSET", "NONLINEAR"}, required={"ELSET"})
        self._need_data(card)
        lines = [([f for f in fields if f != ""], loc) for fields, _, loc in card.lines]
        dofs: tuple[int, ...] = ()
        if lines[0][0] and all(INT_RE.match(f) for f in lines[0][0]):
            dofs = tuple(self._dof(f, lines[0][1]) for f in lines[0][0])
            lines = lines[1:]
        if not lines:
            raise DeckError(
                "*SPRING needs a spring constant or a force-elongation table", card.location
            )
        values = [self._floats_line(fields, "*SPRING", loc) for fields, loc in lines]
        if "NONLINEAR" in card.params:
            self._spring_behaviors.append((card, dofs, None, self._spring_table(values, lines)))
            return
        if len(values) > 1 or (len(values[0]) > 1 and any(v is not None for v in values[0][1:])):
            raise DeckError(
                "*SPRING: temperature-dependent spring constants are not supported (one line "
                "with the constant)",
                lines[0][1],
            )
        if values[0][0] is None:
            raise DeckError("*SPRING: the spring constant is missing", lines[0][1])
        self._spring_behaviors.append((card, dofs, float(values[0][0]), None))

    @staticmethod
    def _spring_table(
        values: list[tuple[float | None, ...]], lines: list[tuple[list[str], Location]]
    ) -> np.ndarray:
        """(k, 2) rows ``(elongation, force)`` of a ``NONLINEAR`` behaviour (one temperature)."""
        rows = []
        for row, (_, loc) in zip(values, lines):
            if len(row) < 2 or row[0] is None or row[1] is None:
                raise DeckError(
                    "*SPRING, NONLINEAR data line: force, elongation[, temperature]", loc
                )
            if len(row) > 2 and row[2] is not None and row[2] != (values[0][2:3] or (None,))[0]:
                raise DeckError(
                    "*SPRING, NONLINEAR: temperature-dependent curves are not supported", loc
                )
            rows.append((row[1], row[0]))
        table = np.array(rows, dtype=float)
        if table.shape[0] < 2 or np.any(np.diff(table[:, 0]) <= 0):
            raise DeckError(
                "*SPRING, NONLINEAR: at least two points with increasing elongations are needed",
                lines[0][1],
            )
        return table

    def _finish_springs(self, solid_ids: np.ndarray) -> tuple[SpringElements, ...]:
        """Every spring element with its behaviour, one group per ``*SPRING`` card and type."""
        elements = {
            number: (type_name, nodes, loc)
            for type_name, rows in self.spring_rows.items()
            for number, nodes, loc in rows
        }
        seen: dict[int, Location] = {}
        for rows in self.spring_rows.values():
            for number, _, loc in rows:
                if number <= 0:
                    raise DeckError(f"element {number} must be > 0", loc)
                if number in seen:
                    raise DeckError(
                        f"element {number} is defined twice (first at {seen[number]})", loc
                    )
                seen[number] = loc
        twice = np.intersect1d(np.fromiter(elements, np.int64, len(elements)), solid_ids)
        if twice.size:
            raise DeckError(
                f"element {int(twice[0])} is defined twice (a spring and a solid element)",
                elements[int(twice[0])][2],
            )
        groups: list[SpringElements] = []
        covered: set[int] = set()
        for card, dofs, stiffness, table in self._spring_behaviors:
            name = card.params["ELSET"] or ""
            if name not in self.elsets:
                raise DeckError(f"element set {name} is not defined", card.location)
            members = [e for e in dict.fromkeys(self.elsets[name]) if e in elements]
            if not members:
                raise DeckError(
                    f"*SPRING: element set {name} holds no spring element", card.location
                )
            kinds = {elements[e][0] for e in members}
            if len(kinds) > 1:
                raise DeckError(
                    f"*SPRING: element set {name} mixes spring types {sorted(kinds)}", card.location
                )
            (kind,) = kinds
            expected = {"SPRINGA": 0, "SPRING1": 1, "SPRING2": 2}[kind]
            if len(dofs) != expected:
                raise DeckError(
                    f"*SPRING, ELSET={name}: {kind} needs {expected} degree(s) of freedom on the "
                    f"line under the card, got {len(dofs)} (write real numbers with a decimal "
                    "point)",
                    card.location,
                )
            covered.update(members)
            groups.append(
                SpringElements(
                    type=kind,
                    ids=frozen_array(members, np.int64),
                    connectivity=frozen_array([elements[e][1] for e in members], np.int64),
                    dofs=dofs,
                    stiffness=stiffness,
                    table=None if table is None else frozen_array(table, np.float64),
                    location=card.location,
                )
            )
        without = [e for e in elements if e not in covered]
        if without:
            raise DeckError(f"spring element {without[0]} has no *SPRING", elements[without[0]][2])
        return tuple(groups)
