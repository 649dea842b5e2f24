"""Load, constraint and initial condition cards.

``*AMPLITUDE``, ``*TIME POINTS``, ``*BOUNDARY``, ``*EQUATION``, ``*INITIAL CONDITIONS``,
``*CLOAD``, ``*CFLUX``, ``*DLOAD`` (face pressures and ``GRAV``), ``*DFLUX`` (face fluxes),
``*FILM``.
"""

from __future__ import annotations

import re

import numpy as np

from ..elements import frozen_array
from .data import (
    Amplitude,
    Boundary,
    CLoad,
    DLoad,
    Equation,
    Film,
    Gravity,
    InitialTemperature,
    InitialVelocity,
    TimePoints,
)
from .errors import DeckError, Location
from .lexer import Card
from .state import ReaderState


class LoadCards(ReaderState):
    """Handlers of the load, constraint and initial condition cards."""

    def _k_AMPLITUDE(self, card: Card) -> None:
        self._check_params(card, allowed={"NAME", "TIME"}, required={"NAME"})
        time = card.params.get("TIME")
        if time not in (None, "TOTALTIME", "STEPTIME"):
            raise DeckError(f"*AMPLITUDE, TIME={time}: use TIME=TOTAL TIME", card.location)
        self._need_data(card)
        values: list[float] = []
        for fields, _, loc in card.lines:
            values.extend(self._float(t, "amplitude data", loc) for t in fields if t != "")
        if len(values) % 2:
            raise DeckError(
                "*AMPLITUDE needs time, value pairs (odd number of entries)", card.location
            )
        pairs = np.array(values, dtype=np.float64).reshape(-1, 2)
        if np.any(np.diff(pairs[:, 0]) < 0.0):
            raise DeckError("*AMPLITUDE times must not decrease", card.location)
        name = card.params["NAME"] or ""
        self.amplitudes[name] = Amplitude(
            name,
            frozen_array(pairs[:, 0], np.float64),
            frozen_array(pairs[:, 1], np.float64),
            time == "TOTALTIME",
            card.location,
        )

    def _k_TIMEPOINTS(self, card: Card) -> None:
        """Step times, listed or ``GENERATE`` (start, end, increment lines); step time only."""
        self._check_params(card, allowed={"NAME", "GENERATE", "TIME"}, required={"NAME"})
        if card.params.get("TIME") not in (None, "STEPTIME"):
            raise DeckError(
                f"*TIME POINTS, TIME={card.raw_params['TIME']} is not supported yet (step time "
                "only)",
                card.location,
            )
        self._need_data(card)
        times: list[float] = []
        for fields, _, loc in card.lines:
            values = [self._float(t, "time point", loc) for t in fields if t != ""]
            if "GENERATE" not in card.params:
                times.extend(values)
                continue
            if len(values) != 3 or values[2] <= 0.0 or values[1] < values[0]:
                raise DeckError(
                    "*TIME POINTS, GENERATE data line: start, end >= start, increment > 0", loc
                )
            start, end, step = values
            count = int(np.floor((end - start) / step * (1.0 + 1e-12) + 1e-9))
            times.extend(start + step * np.arange(count + 1))
        points = np.array(times, dtype=np.float64)
        if np.any(np.diff(points) <= 0.0):
            raise DeckError("*TIME POINTS must increase", card.location)
        name = card.params["NAME"] or ""
        self.time_points[name] = TimePoints(name, frozen_array(points, np.float64), card.location)

    def _amplitude_param(self, card: Card) -> str | None:
        name = card.params.get("AMPLITUDE")
        if name is not None and name not in self.amplitudes:
            raise DeckError(f"amplitude {name} is not defined (before this line)", card.location)
        return name

    def _k_BOUNDARY(self, card: Card) -> None:
        self._check_params(card, allowed={"OP", "AMPLITUDE"})
        op = self._op(card)
        amplitude = self._amplitude_param(card)
        target_list = self.step.boundaries if self.step is not None else self.boundaries
        temperatures = (
            self.step.temperatures if self.step is not None else self.temperature_boundaries
        )
        for fields, _, loc in card.lines:
            if not 2 <= len(fields) <= 4:
                raise DeckError(
                    "*BOUNDARY data line: node or node set, first dof[, last dof[, value]]", loc
                )
            nodes = self._nodes_of(fields[0], card, loc)
            if self._int(fields[1], "degree of freedom", loc) == 11:  # the temperature
                last_token = fields[2] if len(fields) > 2 and fields[2] else "11"
                if self._int(last_token, "degree of freedom", loc) != 11:
                    raise DeckError("*BOUNDARY: dof 11 (temperature) cannot start a range", loc)
                value = self._optional_float(fields, 3, "prescribed temperature", loc) or 0.0
                temperatures.append(Boundary(frozen_array(nodes, np.int64), 11, 11, value,
                                             amplitude, op, fields[0], loc))  # fmt: skip
                continue
            first = self._boundary_dof(fields[1], loc)
            last = self._boundary_dof(fields[2], loc) if len(fields) > 2 and fields[2] else first
            if last < first:
                raise DeckError(f"*BOUNDARY: last dof {last} < first dof {first}", loc)
            value = self._optional_float(fields, 3, "prescribed value", loc) or 0.0
            target_list.append(
                Boundary(
                    frozen_array(nodes, np.int64),
                    first,
                    last,
                    value,
                    amplitude,
                    op,
                    fields[0],
                    loc,
                )
            )

    def _k_EQUATION(self, card: Card) -> None:
        """Blocks of a term count line, then that many (node, dof, coefficient) triples."""
        self._check_params(card, allowed=set())
        self._need_data(card)
        lines = iter(card.lines)
        for fields, _, loc in lines:
            fields = [f for f in fields if f != ""]
            if len(fields) != 1:
                raise DeckError("*EQUATION: a line with the number of terms is expected", loc)
            count = self._int(fields[0], "number of terms", loc)
            if count < 1:
                raise DeckError(f"*EQUATION: number of terms must be >= 1, got {count}", loc)
            tokens: list[str] = []
            for more, _, more_loc in lines:
                more = [f for f in more if f != ""]
                if len(more) % 3 or len(tokens) + len(more) > 3 * count:
                    raise DeckError(
                        f"*EQUATION: {count} terms (node, dof, coefficient) expected; this line "
                        f"has {len(more)} fields after {len(tokens) // 3} terms",
                        more_loc,
                    )
                tokens += more
                if len(tokens) == 3 * count:
                    break
            if len(tokens) != 3 * count:
                raise DeckError(f"*EQUATION: {count} terms expected, the card ends before", loc)
            nodes = []
            for token in tokens[0::3]:
                ids = self._nodes_of(token, card, loc)
                if ids.size != 1:
                    raise DeckError(
                        f"*EQUATION: node set {token} has {ids.size} nodes, one is needed", loc
                    )
                nodes.append(int(ids[0]))
            dofs = [self._dof(t, loc) for t in tokens[1::3]]
            coefficients = [self._float(t, "coefficient", loc) for t in tokens[2::3]]
            if coefficients[0] == 0.0:
                raise DeckError("*EQUATION: the first (dependent) coefficient is zero", loc)
            self.equations.append(Equation(
                frozen_array(nodes, np.int64), frozen_array(dofs, np.int64),
                frozen_array(coefficients, np.float64), loc,
            ))  # fmt: skip

    def _k_INITIALCONDITIONS(self, card: Card) -> None:
        self._check_params(card, allowed={"TYPE"}, required={"TYPE"})
        if card.params["TYPE"] == "TEMPERATURE":
            self._initial_temperatures(card)
            return
        if card.params["TYPE"] != "VELOCITY":
            raise DeckError(
                "*INITIAL CONDITIONS is not supported yet for "
                f"TYPE={card.raw_params['TYPE']} (only TYPE=VELOCITY and TYPE=TEMPERATURE)",
                card.location,
            )
        self._need_data(card)
        for fields, _, loc in card.lines:
            if len(fields) != 3:
                raise DeckError(
                    "*INITIAL CONDITIONS, TYPE=VELOCITY data line: node or node set, dof, value",
                    loc,
                )
            nodes = self._nodes_of(fields[0], card, loc)
            value = self._floats_line(fields[2:3], "*INITIAL CONDITIONS", loc)[0]
            self.initial_velocities.append(
                InitialVelocity(frozen_array(nodes, np.int64), self._dof(fields[1], loc),
                                float(value or 0.0), loc)
            )  # fmt: skip

    def _initial_temperatures(self, card: Card) -> None:
        """``*INITIAL CONDITIONS, TYPE=TEMPERATURE``: lines of node or node set, temperature."""
        self.initial_temperatures.extend(
            self._node_temperatures(
                card,
                "initial temperature",
                "*INITIAL CONDITIONS, TYPE=TEMPERATURE data line: node or node set, "
                "temperature (temperature gradients are not supported)",
            )
        )

    def _k_TEMPERATURE(self, card: Card) -> None:
        """``*TEMPERATURE`` (a step's temperature field): lines of node or node set, temperature."""
        step = self._in_step(card)
        self._check_params(card, allowed=set())
        step.temperature_fields.extend(
            self._node_temperatures(
                card,
                "temperature",
                "*TEMPERATURE data line: node or node set, temperature (gradients are not "
                "supported)",
            )
        )

    def _node_temperatures(
        self, card: Card, what: str, line_error: str
    ) -> list[InitialTemperature]:
        """The node or node set, temperature lines of ``*INITIAL CONDITIONS`` and ``*TEMPERATURE``.

        ``what`` names the value in a number error, ``line_error`` is a malformed line's error.
        """
        self._need_data(card)
        temperatures = []
        for fields, _, loc in card.lines:
            if len(fields) != 2:
                raise DeckError(line_error, loc)
            nodes = self._nodes_of(fields[0], card, loc)
            value = self._float(fields[1], what, loc)
            temperatures.append(InitialTemperature(frozen_array(nodes, np.int64), value, loc))
        return temperatures

    def _k_CLOAD(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"OP", "AMPLITUDE"})
        op, amplitude = self._op(card), self._amplitude_param(card)
        for fields, _, loc in card.lines:
            if len(fields) != 3:
                raise DeckError("*CLOAD data line: node or node set, dof, value", loc)
            nodes = self._nodes_of(fields[0], card, loc)
            dof = self._dof(fields[1], loc)
            value = self._float(fields[2], "load", loc)
            step.cloads.append(CLoad(frozen_array(nodes, np.int64), dof, value, amplitude, op,
                                     fields[0], loc))  # fmt: skip

    def _k_CFLUX(self, card: Card) -> None:
        """Concentrated heat flows into nodes (dof 11; docs/method.md §39)."""
        step = self._in_step(card)
        self._check_params(card, allowed={"OP", "AMPLITUDE"})
        op, amplitude = self._op(card), self._amplitude_param(card)
        for fields, _, loc in card.lines:
            if len(fields) != 3:
                raise DeckError("*CFLUX data line: node or node set, 11, heat flow", loc)
            nodes = self._nodes_of(fields[0], card, loc)
            dof = self._int(fields[1], "*CFLUX degree of freedom", loc)
            if dof != 11:
                raise DeckError(f"*CFLUX degree of freedom must be 11, got {dof}", loc)
            value = self._float(fields[2], "heat flow", loc)
            step.cfluxes.append(CLoad(frozen_array(nodes, np.int64), dof, value, amplitude, op,
                                      fields[0], loc))  # fmt: skip

    def _k_DFLUX(self, card: Card) -> None:
        """Uniform heat fluxes into element faces S1..S6 (docs/method.md §39)."""
        step = self._in_step(card)
        self._check_params(card, allowed={"OP", "AMPLITUDE"})
        op, amplitude = self._op(card), self._amplitude_param(card)
        for fields, _, loc in card.lines:
            label = fields[1] if len(fields) > 1 else ""
            if not re.fullmatch(r"S[1-6]", label):
                raise DeckError(
                    f"*DFLUX, {label or '(no label)'} is not supported yet (load types: uniform "
                    "face fluxes S1..S6)",
                    loc,
                )
            if len(fields) != 3:
                raise DeckError("*DFLUX data line: element or element set, S1..S6, flux", loc)
            elements = self._elements_of(fields[0], card, loc)
            self.element_refs.append((f"{card.name} face {label}", elements, loc))
            value = self._float(fields[2], "heat flux", loc)
            step.dfluxes.append(DLoad(frozen_array(elements, np.int64), int(label[1]), value,
                                      amplitude, op, fields[0], loc))  # fmt: skip

    def _k_FILM(self, card: Card) -> None:
        """Film conditions on element faces F1..F6 (docs/method.md §39)."""
        step = self._in_step(card)
        self._check_params(card, allowed={"OP"})
        op = self._op(card)
        for fields, _, loc in card.lines:
            label = fields[1] if len(fields) > 1 else ""
            if not re.fullmatch(r"F[1-6]", label):
                raise DeckError(
                    f"*FILM, {label or '(no label)'} is not supported yet (load types: uniform "
                    "film conditions F1..F6)",
                    loc,
                )
            if len(fields) != 4:
                raise DeckError(
                    "*FILM data line: element or element set, F1..F6, sink temperature, film "
                    "coefficient",
                    loc,
                )
            elements = self._elements_of(fields[0], card, loc)
            self.element_refs.append((f"{card.name} face {label}", elements, loc))
            sink = self._float(fields[2], "sink temperature", loc)
            coefficient = self._float(fields[3], "film coefficient", loc)
            step.films.append(Film(frozen_array(elements, np.int64), int(label[1]), sink,
                                   coefficient, op, loc))  # fmt: skip

    def _k_DLOAD(self, card: Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"OP", "AMPLITUDE"})
        op, amplitude = self._op(card), self._amplitude_param(card)
        for fields, _, loc in card.lines:
            label = fields[1] if len(fields) > 1 else ""
            if label == "GRAV":
                step.gravity.append(self._gravity(card, fields, loc, op, amplitude))
                continue
            if label and not re.fullmatch(r"P[1-6]", label):
                raise DeckError(
                    f"*DLOAD, {label} is not supported yet (load types: uniform pressure P1..P6, "
                    "GRAV)",
                    loc,
                )
            if len(fields) != 3:
                raise DeckError("*DLOAD data line: element or element set, P1..P6, pressure", loc)
            elements = self._elements_of(fields[0], card, loc)
            self.element_refs.append((f"{card.name} face {label}", elements, loc))
            value = self._float(fields[2], "pressure", loc)
            step.dloads.append(DLoad(frozen_array(elements, np.int64), int(label[1]), value,
                                     amplitude, op, fields[0], loc))  # fmt: skip

    def _gravity(
        self, card: Card, fields: list[str], loc: Location, op: str, amplitude: str | None
    ) -> Gravity:
        """A ``GRAV`` data line: element set, GRAV, magnitude, direction (normed by ccx)."""
        if len(fields) != 6:
            raise DeckError(
                "*DLOAD, GRAV data line: element or element set, GRAV, magnitude, x, y, z", loc
            )
        elements = self._elements_of(fields[0], card, loc)
        self.element_refs.append((f"{card.name} GRAV", elements, loc))
        value = self._float(fields[2], "gravity magnitude", loc)
        direction = np.array([self._float(t, "gravity direction", loc) for t in fields[3:6]])
        length = float(np.linalg.norm(direction))
        if length == 0.0:
            raise DeckError("*DLOAD, GRAV: the direction is the zero vector", loc)
        return Gravity(frozen_array(elements, np.int64), value,
                       frozen_array(direction / length, np.float64), amplitude, op, fields[0],
                       loc)  # fmt: skip
