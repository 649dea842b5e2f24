"""The ``*FREQUENCY`` step card (natural frequencies; docs/method.md §16).

A ``*FREQUENCY`` step computes the lowest modes of the structure at the state the previous steps
left: the tangent with the closed contact springs, no loads. ``*MODAL DYNAMIC`` (the modal
superposition ccx runs on those modes, with contact forces) is refused with its own message.
"""

from __future__ import annotations

from .data import Frequency
from .errors import DeckError
from .lexer import Card
from .state import ReaderState


class FrequencyCards(ReaderState):
    """Handlers of ``*FREQUENCY`` and the refusal of the modal procedures built on it."""

    def _k_FREQUENCY(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"STORAGE", "SOLVER"})
        if step.static is not None or step.frequency is not None:
            raise DeckError("a step can have only one procedure card", card.location)
        if step.nlgeom:
            raise DeckError(
                "*FREQUENCY with NLGEOM (in this step or an earlier one) is not supported yet "
                "(ccx's base state and stress stiffness there were not measured)",
                card.location,
            )
        storage = (card.params.get("STORAGE") or "NO") == "YES"
        values: tuple[float | None, ...] = ()
        if card.lines:
            fields, _, loc = card.lines[0]
            if len(card.lines) > 1 or len(fields) > 4:
                raise DeckError(
                    "*FREQUENCY data line: number of eigenfrequencies, lower and upper frequency",
                    loc,
                )
            values = self._floats_line(fields[:3], "*FREQUENCY", loc)
        values = values + (None,) * (3 - len(values))
        count = 10 if values[0] is None else values[0]
        if count != int(count) or count < 1:
            raise DeckError(
                f"*FREQUENCY number of eigenfrequencies must be a whole number >= 1, got {count}",
                card.location,
            )
        if any(v is not None and v != 0.0 for v in values[1:]):
            raise DeckError(
                "*FREQUENCY with a frequency range (lower or upper value) is not supported yet "
                "(the lowest modes only)",
                card.location,
            )
        step.frequency = Frequency(num_eigenvalues=int(count), storage=storage)

    def _k_MODALDYNAMIC(self, card: Card) -> None:
        raise DeckError(
            "*MODAL DYNAMIC is not supported yet (modal superposition with contact forces)",
            card.location,
        )
