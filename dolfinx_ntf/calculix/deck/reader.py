"""``read_deck``: the cards of a deck dispatched to their handlers.

See docs/method.md §8.5.
"""

from __future__ import annotations

import gc
from collections.abc import Callable
from pathlib import Path

from .checks import Checks
from .data import Deck
from .errors import DeckError, DeckWarning
from .frequency import FrequencyCards
from .interactions import InteractionCards
from .keywords import (
    _CONTEXT_KEYWORDS,
    _MODEL_KEYWORDS,
    _STEP_KEYWORDS,
    _UNSUPPORTED_CONSTRAINTS,
    _UNUSED_INTERACTION,
    _UNUSED_MATERIAL,
)
from .leniency import LENIENCY_RULES
from .lexer import CANONICAL_KEYWORDS, Card, read_cards
from .loads import LoadCards
from .materials import MaterialCards
from .mesh import MeshCards
from .output import OutputCards
from .shells import ShellCards
from .springs import SpringCards
from .steps import StepCards
from .ties import TieCards
from .transforms import TransformCards


class _Reader(
    MeshCards,
    SpringCards,
    MaterialCards,
    InteractionCards,
    LoadCards,
    StepCards,
    FrequencyCards,
    OutputCards,
    TieCards,
    ShellCards,
    TransformCards,
    Checks,
):
    """Keyword-by-keyword deck reader; one method ``_k_<KEYWORD>`` per supported keyword."""

    def read(self) -> Deck:
        for card in read_cards(self.path):
            self._dispatch(card)
        if self.step is not None:
            raise DeckError("*STEP without *END STEP", self.step.location)
        return self._finish()

    def _dispatch(self, card: Card) -> None:
        key = card.keyword
        if key in _STEP_KEYWORDS and key != "ENDSTEP":
            self._in_step(card)
        if key in _MODEL_KEYWORDS and self.step is not None:
            raise DeckError(
                f"{card.name} is a model definition keyword: it must come before the first *STEP",
                card.location,
            )
        if key not in _CONTEXT_KEYWORDS:
            self.context = None
        if self._apply_leniency(card):
            return
        handler: Callable[[Card], None] | None = getattr(self, f"_k_{key.replace('-', '_')}", None)
        if handler is not None:
            handler(card)
        elif key in _UNUSED_MATERIAL:
            self._unused_material(card)
        elif key in _UNUSED_INTERACTION:
            self._unused_interaction(card)
        elif key in _UNSUPPORTED_CONSTRAINTS:
            raise DeckError(f"{card.name} is not supported yet (constraint)", card.location)
        elif key in CANONICAL_KEYWORDS:
            raise DeckError(f"{card.name} is not supported yet", card.location)
        else:
            raise DeckError(f"unknown keyword *{card.text}", card.location)

    def _apply_leniency(self, card: Card) -> bool:
        """Apply ``LENIENCY`` to ``card``: warn or refuse; True if the whole card is skipped."""
        rules = LENIENCY_RULES.get(card.keyword, {})
        for key in list(card.params):
            rule = rules.get(key) or rules.get("*")
            if rule is None:
                continue
            action, reason, spelling = rule
            if action == "refuse":
                raise DeckError(
                    f"{card.name}, {spelling} is not supported yet ({reason})", card.location
                )
            raw = card.raw_params[key]
            written = key if spelling == "*" else spelling
            self.warnings.append(DeckWarning(
                card.name, written if raw is None else f"{written}={raw}", reason, card.location
            ))  # fmt: skip
            del card.params[key], card.raw_params[key]
        if "" not in rules:
            return False
        self._ignore(card, rules[""][1])
        return True

    def _k_HEADING(self, card: Card) -> None:
        self._check_params(card, allowed=set())
        self.heading.extend(raw.strip() for _, raw, _ in card.lines)


def read_deck(path: str | Path) -> Deck:
    """Read a CalculiX ``.inp`` deck (node-to-face contact subset) with its ``*INCLUDE`` files.

    Args:
        path: the deck file.

    Returns:
        The parsed ``Deck``.

    Raises:
        DeckError: (a ``ValueError``) bad, inconsistent or unsupported input; the message starts
            with ``file:line`` and names the keyword, number or set at fault.
    """
    # a deck is many small lists and tuples and no cyclic garbage: the collector's passes over
    # them cost more than the whole parse on large decks (half of 0.3 s at 81k dofs)
    enabled = gc.isenabled()
    gc.disable()
    try:
        return _Reader(Path(path)).read()
    finally:
        if enabled:
            gc.enable()
