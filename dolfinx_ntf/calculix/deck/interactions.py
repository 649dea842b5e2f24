"""Contact cards: interactions and contact pairs.

``*SURFACE INTERACTION``, ``*SURFACE BEHAVIOR``, ``*FRICTION``, ``*CONTACT PAIR``.
"""

from __future__ import annotations

import re

import numpy as np

from ..elements import frozen_array
from .data import ContactDamping, ContactPair, Friction, FrictionChange, SurfaceBehavior
from .errors import DeckError
from .lexer import Card
from .state import InteractionBuilder, ReaderState


class InteractionCards(ReaderState):
    """Handlers of the surface interaction and contact pair cards."""

    def _k_SURFACEINTERACTION(self, card: Card) -> None:
        self._check_params(card, allowed={"NAME"}, required={"NAME"})
        self._no_data(card)
        name = self._new_name(card, self.interactions, "surface interaction")
        self.context = self.interactions[name] = InteractionBuilder(name, card.location)

    def _interaction(self, card: Card) -> InteractionBuilder:
        if not isinstance(self.context, InteractionBuilder):
            raise DeckError(f"{card.name} must follow a *SURFACE INTERACTION card", card.location)
        return self.context

    def _k_SURFACEBEHAVIOR(self, card: Card) -> None:
        interaction = self._interaction(card)
        key = "PRESSURE-OVERCLOSURE"
        self._check_params(card, allowed={key}, required={key})
        law = card.params["PRESSURE-OVERCLOSURE"] or ""
        what = f"*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE={law}"
        values: tuple[float | None, ...] = ()
        table = None
        if law == "EXPONENTIAL":
            self._need_data(card)
            fields, _, loc = card.lines[0]
            if len(card.lines) != 1 or len(fields) != 2:
                raise DeckError(f"{what}: one data line c0, p0", loc)
            c0, p0 = (self._float(t, "c0/p0", loc) for t in fields)
            if c0 <= 0.0 or p0 < 0.0:
                raise DeckError(f"{what} needs c0 > 0 and p0 >= 0, got {c0}, {p0}", loc)
            values = (c0, p0)
        elif law in ("LINEAR", "HARD"):
            if len(card.lines) > 1:
                raise DeckError(f"{what}: at most one data line K, sigma_inf, c0", card.lines[1][2])
            if card.lines:
                fields, _, loc = card.lines[0]
                if len(fields) > 3:
                    raise DeckError(f"{what}: data line K, sigma_inf, c0", loc)
                values = self._floats_line(fields, "K/sigma_inf/c0", loc)
        elif law == "TABULAR":
            self._need_data(card)
            rows = []
            for fields, _, loc in card.lines:
                if len(fields) not in (2, 3):
                    raise DeckError(f"{what}: data lines pressure, overclosure[, temperature]", loc)
                rows.append([self._float(t, "pressure/overclosure", loc) for t in fields])
            if len({len(r) for r in rows}) > 1:
                raise DeckError(f"{what}: give temperatures on all lines or none", card.location)
            table = frozen_array(rows, np.float64)
        elif law == "TIED":
            raise DeckError(f"{what} is for face-to-face contact: not supported", card.location)
        else:
            raise DeckError(f"{what}: use EXPONENTIAL, LINEAR, TABULAR or HARD", card.location)
        if interaction.behavior is not None:
            raise DeckError(
                f"surface interaction {interaction.name} has two *SURFACE BEHAVIOR cards",
                card.location,
            )
        interaction.behavior = SurfaceBehavior(law, values, table, card.location)

    def _friction_data(self, card: Card) -> Friction:
        self._check_params(card, allowed=set())
        self._need_data(card)
        fields, _, loc = card.lines[-1]  # several lines: the last one counts (as in ccx)
        if not 1 <= len(fields) <= 2:
            raise DeckError("*FRICTION data line: mu[, stick slope]", loc)
        mu = self._float(fields[0], "friction coefficient", loc)
        if mu <= 0.0:
            raise DeckError(f"*FRICTION needs a friction coefficient > 0, got {mu}", loc)
        return Friction(mu, self._optional_float(fields, 1, "stick slope", loc), card.location)

    def _k_FRICTION(self, card: Card) -> None:
        if self.step is not None:
            if self.step.pending_friction is None:
                raise DeckError("*FRICTION in a step must follow *CHANGE FRICTION", card.location)
            name, loc = self.step.pending_friction
            self.step.friction_changes.append(FrictionChange(name, self._friction_data(card), loc))
            self.step.pending_friction = None
            return
        interaction = self._interaction(card)
        interaction.friction = self._friction_data(card)

    def _k_CONTACTDAMPING(self, card: Card) -> None:
        """``*CONTACT DAMPING[, TANGENT FRACTION=f]`` with the damping constant (§29)."""
        interaction = self._interaction(card)
        self._check_params(card, allowed={"TANGENTFRACTION"})
        self._need_data(card)
        fields, _, loc = card.lines[0]
        if len(card.lines) != 1 or len(fields) != 1:
            raise DeckError("*CONTACT DAMPING: one data line with the damping constant", loc)
        coefficient = self._float(fields[0], "damping constant", loc)
        if not coefficient > 0.0:
            raise DeckError(
                f"*CONTACT DAMPING needs a damping constant > 0, got {coefficient}", loc
            )
        fraction = 0.0
        if "TANGENTFRACTION" in card.params:
            token = card.params["TANGENTFRACTION"] or ""
            fraction = self._float(token, "TANGENT FRACTION", card.location)
            if not fraction >= 0.0:
                raise DeckError(f"TANGENT FRACTION must be >= 0, got {fraction}", card.location)
        if interaction.damping is not None:
            raise DeckError(
                f"surface interaction {interaction.name} has two *CONTACT DAMPING cards",
                card.location,
            )
        interaction.damping = ContactDamping(coefficient, fraction, card.location)

    def _unused_interaction(self, card: Card) -> None:
        interaction = self._interaction(card)
        interaction.extra[card.name] = tuple(
            self._floats_line(f, card.name, loc) for f, _, loc in card.lines
        )

    def _k_CONTACTPAIR(self, card: Card) -> None:
        self._check_params(card, allowed={"INTERACTION", "TYPE", "SMALLSLIDING", "ADJUST"},
                           required={"INTERACTION", "TYPE"})  # fmt: skip
        ctype = card.params["TYPE"] or ""
        if ctype != "NODETOSURFACE":
            raise DeckError(
                f"*CONTACT PAIR, TYPE={card.raw_params['TYPE']} is not supported yet "
                "(only TYPE=NODE TO SURFACE)",
                card.location,
            )
        if card.params.get("SMALLSLIDING") is not None:
            raise DeckError("SMALL SLIDING takes no value", card.location)
        adjust: float | str | None = None
        if "ADJUST" in card.params:
            token = card.params["ADJUST"] or ""
            if not token:
                raise DeckError(
                    "ADJUST needs a value: a clearance >= 0 or a node set", card.location
                )
            if token in self.nsets:
                adjust = token
            else:
                try:
                    adjust = float(re.sub(r"[dD]", "e", token))
                except ValueError:
                    raise DeckError(
                        f"ADJUST={token}: neither a number nor a defined node set", card.location
                    ) from None
                if not adjust >= 0.0:
                    raise DeckError(f"ADJUST={token} must be >= 0", card.location)
        self._need_data(card)
        for fields, _, loc in card.lines:
            if len(fields) != 2 or "" in fields:
                raise DeckError("*CONTACT PAIR data line: slave surface, master surface", loc)
            self.contact_pairs.append(
                ContactPair(
                    slave=fields[0],
                    master=fields[1],
                    interaction=card.params["INTERACTION"] or "",
                    type="NODE TO SURFACE",
                    small_sliding="SMALLSLIDING" in card.params,
                    adjust=adjust,
                    location=loc,
                )
            )
