"""Material cards: ``*MATERIAL``, ``*ELASTIC``, ``*PLASTIC``, unused data, ``*SOLID SECTION``."""

from __future__ import annotations

from .data import SolidSection
from .errors import DeckError
from .lexer import Card
from .state import MaterialBuilder, ReaderState


class MaterialCards(ReaderState):
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
        material = self._material(card)
        self._check_params(card, allowed={"TYPE"})
        etype = card.params.get("TYPE") or "ISO"
        if etype != "ISO":
            raise DeckError(
                f"*ELASTIC, TYPE={etype} is not supported yet (only isotropic)", card.location
            )
        self._need_data(card)
        if len(card.lines) > 1:
            raise DeckError(
                "temperature-dependent *ELASTIC (several data lines) is not supported yet",
                card.lines[1][2],
            )
        fields, _, loc = card.lines[0]
        if not 2 <= len(fields) <= 3:
            raise DeckError("*ELASTIC data line: E, nu[, temperature]", loc)
        young = self._float(fields[0], "Young's modulus", loc)
        nu = self._float(fields[1], "Poisson's ratio", loc)
        if young <= 0.0 or not -1.0 < nu < 0.5:
            raise DeckError(f"*ELASTIC needs E > 0 and -1 < nu < 0.5, got {young}, {nu}", loc)
        if material.elastic is not None:
            raise DeckError(
                f"material {material.name} has two *ELASTIC cards (first at "
                f"{material.elastic_location})",
                card.location,
            )
        material.elastic = (young, nu)
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

    def _k_SOLIDSECTION(self, card: Card) -> None:
        self._check_params(card, allowed={"ELSET", "MATERIAL"}, required={"ELSET", "MATERIAL"})
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
            SolidSection(elset, card.params["MATERIAL"] or "", card.location, thickness)
        )
