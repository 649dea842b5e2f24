"""Step cards: procedures, controls and changes between steps.

``*STEP``, ``*STATIC``, ``*DYNAMIC``, ``*COUPLED TEMPERATURE-DISPLACEMENT``, ``*HEAT TRANSFER``,
``*CONTROLS``, ``*CHANGE FRICTION``, ``*MODEL CHANGE``,
``*END STEP`` (with the checks of a ``*MODAL DYNAMIC`` step's cards).
"""

from __future__ import annotations

from .data import Coupled, Dynamic, ModelChange, Static, Step
from .errors import DeckError
from .lexer import Card
from .state import ReaderState, StepBuilder


class StepCards(ReaderState):
    """Handlers of the step, procedure and step-change cards."""

    def _k_STEP(self, card: Card) -> None:
        if self.step is not None:
            raise DeckError(f"*STEP inside the step started at {self.step.location}", card.location)
        self._check_params(card, allowed={"NLGEOM", "INC", "INCF"})
        self._no_data(card)
        nlgeom = card.params.get("NLGEOM", "NO" if not self.nlgeom else "YES")
        if nlgeom not in (None, "YES", "NO"):
            raise DeckError(f"NLGEOM={nlgeom}: use NLGEOM or NLGEOM=YES/NO", card.location)
        self.nlgeom = nlgeom != "NO"
        inc = 100
        if "INC" in card.params:
            inc = self._int(card.params["INC"] or "", "INC", card.location)
            if inc <= 0:
                raise DeckError(f"INC must be > 0, got {inc}", card.location)
        self.step = StepBuilder(len(self.steps) + 1, self.nlgeom, inc, card.location)
        self.context = None

    def _k_STATIC(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"DIRECT", "SOLVER", "TIMERESET", "TOTALTIMEATSTART",
                                          "EXPLICIT"})  # fmt: skip
        self._first_procedure(step, card)
        values = self._procedure_line(
            card, "*STATIC", "initial increment, period, minimum, maximum", 4, 5
        )
        for name, value in zip(("initial increment", "period", "minimum", "maximum"), values):
            if value is not None and value <= 0.0 and name != "minimum":
                raise DeckError(f"*STATIC {name} must be > 0, got {value}", card.location)
        total_at_start = None
        if "TOTALTIMEATSTART" in card.params:
            total_at_start = self._float(
                card.params["TOTALTIMEATSTART"] or "", "TOTAL TIME AT START", card.location
            )
        step.static = Static(
            initial_increment=values[0] if values[0] is not None else 1.0,
            period=values[1] if values[1] is not None else 1.0,
            minimum=values[2],
            maximum=values[3],
            direct="DIRECT" in card.params,
            time_reset="TIMERESET" in card.params,
            total_time_at_start=total_at_start,
        )

    def _k_DYNAMIC(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"DIRECT", "ALPHA", "SOLVER", "EXPLICIT"})
        if "EXPLICIT" in card.params:
            raise DeckError(
                "*DYNAMIC, EXPLICIT is not supported yet (implicit only)", card.location
            )
        self._first_procedure(step, card)
        alpha = self._alpha(card, "*DYNAMIC ")
        self._need_data(card)
        loc = card.lines[0][2]
        usage = "initial increment, period, minimum, maximum[, CFD increment]"
        values = self._procedure_line(card, "*DYNAMIC", usage, 4, 5)
        for name, value in zip(("initial increment", "period"), values[:2]):
            if value is None or value <= 0.0:
                raise DeckError(f"*DYNAMIC {name} must be given and > 0, got {value}", loc)
        step.static = Static(
            initial_increment=values[0],
            period=values[1],
            minimum=values[2],
            maximum=values[3],
            direct="DIRECT" in card.params,
        )
        step.dynamic = Dynamic(alpha=alpha)

    def _alpha(self, card: Card, prefix: str = "") -> float:
        """The alpha method's ``ALPHA`` (ccx's default -0.05), in [-1/3, 0].

        ``prefix`` starts the error message (``"*DYNAMIC "``).
        """
        if "ALPHA" not in card.params:
            return -0.05
        alpha = self._float(card.params["ALPHA"] or "", "ALPHA", card.location)
        if not -1.0 / 3.0 <= alpha <= 0.0:
            raise DeckError(f"{prefix}ALPHA must be in [-1/3, 0], got {alpha}", card.location)
        return alpha

    def _k_COUPLEDTEMPERATURE_DISPLACEMENT(self, card: Card) -> None:
        """Initial increment, period, minimum, maximum, DELTMX; ``STEADY STATE`` or transient."""
        self._check_params(card, allowed={"STEADYSTATE", "SOLVER", "DIRECT", "ALPHA"})
        self._thermal_procedure(card, "*COUPLED TEMPERATURE-DISPLACEMENT", heat=False)

    def _k_HEATTRANSFER(self, card: Card) -> None:
        """As the coupled step, the mechanics not solved (docs/method.md §20.9)."""
        self._check_params(card, allowed={"STEADYSTATE", "SOLVER", "DIRECT"})
        self._thermal_procedure(card, "*HEAT TRANSFER", heat=True)

    def _thermal_procedure(self, card: Card, name: str, *, heat: bool) -> None:
        """The data line and parameters shared by the two thermal procedures."""
        step = self._in_step(card)
        self._first_procedure(step, card)
        alpha = self._alpha(card)
        usage = "initial increment, period, minimum, maximum, DELTMX"
        values = self._procedure_line(card, name, usage, 5, 5)
        for what, value in zip(("initial increment", "period", "maximum", "DELTMX"),
                               (values[0], values[1], values[3], values[4])):  # fmt: skip
            if value is not None and value <= 0.0:
                raise DeckError(
                    f"{name} {what} must be > 0, got {value}",
                    card.location,
                )
        step.static = Static(
            initial_increment=values[0] if values[0] is not None else 1.0,
            period=values[1] if values[1] is not None else 1.0,
            minimum=values[2],
            maximum=values[3],
            direct="DIRECT" in card.params,
        )
        step.coupled = Coupled(
            "STEADYSTATE" in card.params, values[4], card.location, alpha, heat=heat
        )

    def _k_CONTROLS(self, card: Card) -> None:
        self._in_step(card)
        self._check_params(card, allowed={"PARAMETERS", "RESET"})
        if "RESET" in card.params:
            self._no_data(card)
            self.controls = {}
            return
        if "PARAMETERS" not in card.params or not card.params["PARAMETERS"]:
            raise DeckError("*CONTROLS needs PARAMETERS=... or RESET", card.location)
        self._need_data(card)
        self.controls[card.params["PARAMETERS"]] = tuple(
            self._floats_line(fields, "*CONTROLS", loc) for fields, _, loc in card.lines
        )

    def _k_CHANGEFRICTION(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"INTERACTION"}, required={"INTERACTION"})
        self._no_data(card)
        name = card.params["INTERACTION"] or ""
        if name not in self.interactions:
            raise DeckError(f"surface interaction {name} is not defined", card.location)
        step.pending_friction = (name, card.location)

    def _k_MODELCHANGE(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"TYPE", "ADD", "REMOVE"}, required={"TYPE"})
        if card.params["TYPE"] != "CONTACTPAIR":
            raise DeckError(
                f"*MODEL CHANGE, TYPE={card.params['TYPE']} is not supported yet "
                "(only TYPE=CONTACT PAIR)",
                card.location,
            )
        if ("ADD" in card.params) == ("REMOVE" in card.params):
            raise DeckError("*MODEL CHANGE needs exactly one of ADD and REMOVE", card.location)
        action = "ADD" if "ADD" in card.params else "REMOVE"
        self._need_data(card)
        for fields, _, loc in card.lines:
            if len(fields) != 2:
                raise DeckError("*MODEL CHANGE data line: slave surface, master surface", loc)
            step.model_changes.append(ModelChange(action, fields[0], fields[1], loc))

    def _k_ENDSTEP(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed=set())
        self._no_data(card)
        if step.static is None and step.frequency is None:
            raise DeckError(
                "the step has no *STATIC, *DYNAMIC, *FREQUENCY, *MODAL DYNAMIC, *COUPLED "
                "TEMPERATURE-DISPLACEMENT or *HEAT TRANSFER procedure (the only ones supported)",
                step.location,
            )
        self._check_modal_step(step)
        if step.pending_friction is not None:
            raise DeckError("*CHANGE FRICTION without a following *FRICTION",
                            step.pending_friction[1])  # fmt: skip
        self.steps.append(
            Step(
                number=step.number,
                nlgeom=step.nlgeom,
                max_increments=step.max_increments,
                static=step.static if step.static is not None else Static(),
                boundaries=tuple(step.boundaries),
                cloads=tuple(step.cloads),
                dloads=tuple(step.dloads),
                prints=tuple(self.prints),
                file_requests=tuple(self.files),
                output_frequency=self.frequency,
                controls=dict(self.controls),
                friction_changes=tuple(step.friction_changes),
                model_changes=tuple(step.model_changes),
                location=step.location,
                dynamic=step.dynamic,
                frequency=step.frequency,
                coupled=step.coupled,
                temperatures=tuple(step.temperatures),
                modal_dynamic=step.modal_dynamic,
                modal_damping=self.modal_damping,
                temperature_fields=tuple(step.temperature_fields),
                gravity=tuple(step.gravity),
                cfluxes=tuple(step.cfluxes),
                dfluxes=tuple(step.dfluxes),
                films=tuple(step.films),
            )
        )
        self.step = None

    def _check_modal_step(self, step: StepBuilder) -> None:
        """What a ``*MODAL DYNAMIC`` step cannot hold yet, refused at ``*END STEP``."""
        if step.modal_dynamic is None:
            return
        if step.boundaries:
            raise DeckError(
                "*BOUNDARY in a *MODAL DYNAMIC step (base motion) is not supported yet",
                step.boundaries[0].location,
            )
        if step.dloads or step.temperatures:
            raise DeckError(
                "*DLOAD and temperatures in a *MODAL DYNAMIC step are not supported yet "
                "(concentrated loads only)",
                step.location,
            )
        for cload in step.cloads:
            if cload.amplitude is not None:
                raise DeckError(
                    f"*CLOAD with AMPLITUDE={cload.amplitude} in a *MODAL DYNAMIC step is not "
                    "supported yet (loads constant over the step, as ccx applies them without "
                    "an amplitude)",
                    cload.location,
                )
