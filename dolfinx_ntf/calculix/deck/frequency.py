"""The modal step cards: ``*FREQUENCY``, ``*MODAL DYNAMIC`` and ``*MODAL DAMPING``.

A ``*FREQUENCY`` step computes the lowest modes of the structure at the state the previous steps
left (docs/method.md §16). A ``*MODAL DYNAMIC`` step superposes the modes of the last
``*FREQUENCY, STORAGE=YES`` step under the step's concentrated loads, damped by the effective
``*MODAL DAMPING, RAYLEIGH`` (docs/method.md §25).
"""

from __future__ import annotations

from .data import Frequency, ModalDamping, ModalDynamic, Static
from .errors import DeckError
from .lexer import Card
from .state import ReaderState


class FrequencyCards(ReaderState):
    """Handlers of ``*FREQUENCY`` and the refusal of the modal procedures built on it."""

    def _k_FREQUENCY(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"STORAGE", "SOLVER"})
        self._first_procedure(step, card)
        if step.nlgeom:
            raise DeckError(
                "*FREQUENCY with NLGEOM (in this step or an earlier one) is not supported yet "
                "(ccx's base state and stress stiffness there were not measured)",
                card.location,
            )
        storage = (card.params.get("STORAGE") or "NO") == "YES"
        usage = "number of eigenfrequencies, lower and upper frequency"
        values = self._procedure_line(card, "*FREQUENCY", usage, 3, 4)
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
        """Increments (initial, period, minimum, maximum); DIRECT=NO with DELTMX or fixed."""
        step = self._in_step(card)
        self._check_params(card, allowed={"DIRECT", "DELTMX", "SOLVER", "STEADYSTATE"})
        self._first_procedure(step, card)
        if "STEADYSTATE" in card.params:
            raise DeckError(
                "*MODAL DYNAMIC, STEADY STATE is not supported yet (a fixed period only)",
                card.location,
            )
        stored = [s for s in self.steps if s.frequency is not None and s.frequency.storage]
        if not stored:
            raise DeckError(
                "*MODAL DYNAMIC needs the modes of an earlier *FREQUENCY, STORAGE=YES step in "
                "this deck (modes read from another job's .eig file are not supported)",
                card.location,
            )
        earlier = [s.location for s in self.steps if s.cloads or s.dloads]
        if earlier:
            raise DeckError(
                "*MODAL DYNAMIC after a step with loads is not supported yet (ccx removes the "
                f"earlier loading; loads in the step at {earlier[0]})",
                card.location,
            )
        direct = card.params.get("DIRECT", "")
        # ccx 2.20 does not recognize a bare DIRECT (a warning) and keeps fixed increments
        variable = direct is not None and direct.upper() == "NO"
        deltmx = None
        if "DELTMX" in card.params:
            deltmx = self._float(card.params["DELTMX"] or "", "DELTMX", card.location)
            if deltmx <= 0.0:
                raise DeckError(f"*MODAL DYNAMIC DELTMX must be > 0, got {deltmx}", card.location)
        if variable and deltmx is None:
            raise DeckError("*MODAL DYNAMIC, DIRECT=NO needs DELTMX (ccx manual)", card.location)
        self._need_data(card)
        loc = card.lines[0][2]
        usage = "initial increment, period, minimum, maximum"
        values = self._procedure_line(card, "*MODAL DYNAMIC", usage, 4, 4)
        if values[1] is None or values[1] <= 0.0:
            raise DeckError(f"*MODAL DYNAMIC period must be given and > 0, got {values[1]}", loc)
        for name, value in (("initial increment", values[0]), ("maximum", values[3])):
            if value is not None and value <= 0.0:
                raise DeckError(f"*MODAL DYNAMIC {name} must be > 0, got {value}", loc)
        step.static = Static(
            initial_increment=values[0] if values[0] is not None else values[1],
            period=values[1],
            minimum=values[2],
            maximum=values[3],
            direct=not variable,
        )
        step.modal_dynamic = ModalDynamic(variable, deltmx, card.location)

    def _k_MODALDAMPING(self, card: Card) -> None:
        """``RAYLEIGH``: data line ``, , alpha, beta``; kept for the following steps."""
        self._in_step(card)
        self._check_params(card, allowed={"RAYLEIGH", "MODAL"})
        if "RAYLEIGH" not in card.params:
            raise DeckError(
                "*MODAL DAMPING without RAYLEIGH (direct damping per mode) is not supported yet",
                card.location,
            )
        self._need_data(card)
        fields, _, loc = card.lines[0]
        if len(card.lines) > 1 or len(fields) > 4:
            raise DeckError("*MODAL DAMPING, RAYLEIGH data line: , , alpha, beta", loc)
        values = self._floats_line(fields, "*MODAL DAMPING", loc) + (None,) * 4
        alpha, beta = values[2] or 0.0, values[3] or 0.0
        if alpha < 0.0 or beta < 0.0:
            raise DeckError(
                f"*MODAL DAMPING, RAYLEIGH coefficients must be >= 0, got {alpha}, {beta}", loc
            )
        self.modal_damping = ModalDamping(alpha, beta, card.location)
