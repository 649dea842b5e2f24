"""Material cards: ``*MATERIAL``, ``*ELASTIC``, ``*PLASTIC``, unused data, ``*SOLID SECTION``."""

from __future__ import annotations

import numpy as np

from .data import SolidSection
from .errors import DeckError
from .lexer import Card
from .orientations import OrientationCards
from .state import MaterialBuilder

#: ``*ELASTIC`` types of anisotropic materials (ccx 2.20 reads the first letters: ORTHOTROPIC is
#: ORTHO, ANISOTROPIC is ANISO, measured; any other value is ISO).
_ANISOTROPIC = ("ORTHO", "ENGINEERING", "ANISO")


def table_at_temperature(
    rows: tuple[tuple[float | None, ...], ...], temperature: float
) -> tuple[float, ...]:
    """The values of a material table at ``temperature``, as ccx 2.20 (measured, method §41.2).

    Args:
        rows: Lines of values with the temperature last, temperatures increasing (``*ELASTIC``:
            ``(E, nu, T)``, ``*DENSITY``: ``(rho, T)``).
        temperature: Where to evaluate: each value linear between lines, the first (last)
            line's values below (above) the table.
    """
    table = np.array([r[-1] for r in rows], dtype=float)
    return tuple(
        float(np.interp(temperature, table, [r[k] for r in rows])) for k in range(len(rows[0]) - 1)
    )


class MaterialCards(OrientationCards):
    """Handlers of the material and section cards."""

    def _k_MATERIAL(self, card: Card) -> None:
        self._check_params(card, allowed={"NAME"}, required={"NAME"})
        self._no_data(card)
        name = self._new_name(card, self.materials, "material")
        self.context = self.materials[name] = MaterialBuilder(name, card.location)

    def _material(self, card: Card) -> MaterialBuilder:
        if not isinstance(self.context, MaterialBuilder):
            raise DeckError(f"{card.name} must follow a *MATERIAL card", card.location)
        return self.context

    def _k_ELASTIC(self, card: Card) -> None:
        """``*ELASTIC``: isotropic, one row or a temperature table (docs/method.md §41.1, §41.2)."""
        material = self._material(card)
        self._check_params(card, allowed={"TYPE"})
        etype = card.params.get("TYPE") or "ISO"
        if etype.startswith(_ANISOTROPIC):
            raise DeckError(
                f"*ELASTIC, TYPE={etype} is not supported yet (only isotropic: TYPE=ISO)",
                card.location,
            )
        if not etype.startswith("ISO"):
            raise DeckError(
                f"*ELASTIC, TYPE={etype}: ISO (ISOTROPIC), ORTHO, ENGINEERING CONSTANTS or ANISO "
                "expected (ccx 2.20 reads an unknown type as ISO without a word)",
                card.location,
            )
        self._need_data(card)
        rows = []
        for fields, _, loc in card.lines:
            if not 2 <= len(fields) <= 3:
                raise DeckError("*ELASTIC data line: E, nu[, temperature]", loc)
            young = self._float(fields[0], "Young's modulus", loc)
            nu = self._float(fields[1], "Poisson's ratio", loc)
            if young <= 0.0 or not -1.0 < nu < 0.5:
                raise DeckError(f"*ELASTIC needs E > 0 and -1 < nu < 0.5, got {young}, {nu}", loc)
            temperature = None
            if len(fields) == 3 and fields[2].strip():
                temperature = self._float(fields[2], "temperature", loc)
            if len(card.lines) > 1 and temperature is None:
                raise DeckError(
                    "*ELASTIC with several data lines needs a temperature on each line", loc
                )
            if rows and temperature <= rows[-1][2]:
                raise DeckError(
                    f"*ELASTIC: the temperatures must increase, {temperature} follows "
                    f"{rows[-1][2]}",
                    loc,
                )
            rows.append((young, nu, temperature))
        if material.elastic is not None:
            raise DeckError(
                f"material {material.name} has two *ELASTIC cards (first at "
                f"{material.elastic_location})",
                card.location,
            )
        material.elastic = rows[0][:2]  # the table is resolved once the temperatures are known
        material.elastic_rows = tuple(rows)
        material.elastic_row_locations = tuple(loc for _, _, loc in card.lines)
        material.elastic_location = card.location

    def _k_PLASTIC(self, card: Card) -> None:
        """``*PLASTIC``: isotropic hardening, one temperature (docs/method.md §21.6)."""
        material = self._material(card)
        self._check_params(card, allowed={"HARDENING"})
        hardening = card.params.get("HARDENING") or "ISOTROPIC"
        if hardening != "ISOTROPIC":
            raise DeckError(
                f"*PLASTIC, HARDENING={hardening} is not supported yet (only ISOTROPIC)",
                card.location,
            )
        self._need_data(card)
        rows, temperatures = [], set()
        for fields, _, loc in card.lines:
            if not 2 <= len(fields) <= 3:
                raise DeckError(
                    "*PLASTIC data line: yield stress, plastic strain[, temperature]", loc
                )
            stress = self._float(fields[0], "yield stress", loc)
            strain = self._float(fields[1], "equivalent plastic strain", loc)
            if len(fields) == 3 and fields[2].strip():
                temperatures.add(self._float(fields[2], "temperature", loc))
            if len(temperatures) > 1:
                raise DeckError(
                    "temperature-dependent *PLASTIC (several temperatures) is not supported yet",
                    loc,
                )
            if stress <= 0.0 or strain < 0.0:
                raise DeckError(
                    f"*PLASTIC needs a yield stress > 0 and a plastic strain >= 0, got {stress}, "
                    f"{strain}",
                    loc,
                )
            if rows and strain <= rows[-1][1]:
                raise DeckError(
                    f"*PLASTIC: the plastic strains must increase, {strain} follows {rows[-1][1]}",
                    loc,
                )
            rows.append((stress, strain))
        if rows[0][1] != 0.0:
            raise DeckError(
                f"*PLASTIC: the first line's plastic strain must be 0 (initial yield), got "
                f"{rows[0][1]}",
                card.lines[0][2],
            )
        if material.plastic is not None:
            raise DeckError(
                f"material {material.name} has two *PLASTIC cards (first at "
                f"{material.plastic_location})",
                card.location,
            )
        material.plastic = tuple(rows)
        material.plastic_location = card.location

    def _unused_material(self, card: Card) -> None:
        material = self._material(card)
        material.extra[card.name] = tuple(
            self._floats_line(f, card.name, loc) for f, _, loc in card.lines
        )
        material.extra_locations[card.name] = tuple(loc for _, _, loc in card.lines)

    def _k_SOLIDSECTION(self, card: Card) -> None:
        self._check_params(
            card, allowed={"ELSET", "MATERIAL", "ORIENTATION"}, required={"ELSET", "MATERIAL"}
        )
        elset = card.params["ELSET"] or ""
        if elset not in self.elsets:
            raise DeckError(f"element set {elset} is not defined (before this line)", card.location)
        thickness = None  # checked by the model of 2D elements only (3D decks ignore it, as ccx)
        if card.lines and card.lines[0][0] and card.lines[0][0][0]:
            try:
                thickness = float(card.lines[0][0][0].replace("D", "E").replace("d", "e"))
            except ValueError:
                thickness = float("nan")
        self.sections.append(
            SolidSection(
                elset,
                card.params["MATERIAL"] or "",
                card.location,
                thickness,
                self._section_orientation(card),
            )
        )
