"""Tie cards: ``*TIE`` and ``*CYCLIC SYMMETRY MODEL`` (docs/method.md §19).

A ``*TIE`` is a surface tie (tied contact: slave nodes follow the master faces) or, with
``CYCLIC SYMMETRY``, the pair of faces bounding a sector, which a ``*CYCLIC SYMMETRY MODEL``
refers to. ``MULTISTAGE`` and the parameters of cyclic symmetry that change more than the
datum sector's static solution (``NGRAPH`` > 1, ``NPHYS`` other than ``N``, ``MATRIX``,
``CONTACT``) are refused.
"""

from __future__ import annotations

import numpy as np

from .data import CyclicSymmetry, Tie
from .errors import DeckError
from .lexer import Card
from .state import ReaderState


class TieCards(ReaderState):
    """Handlers of ``*TIE`` and ``*CYCLIC SYMMETRY MODEL``."""

    def _k_TIE(self, card: Card) -> None:
        self._check_params(
            card,
            allowed={"NAME", "POSITIONTOLERANCE", "ADJUST", "CYCLICSYMMETRY", "MULTISTAGE"},
            required={"NAME"},
        )
        if "MULTISTAGE" in card.params:
            raise DeckError("*TIE, MULTISTAGE is not supported yet", card.location)
        ties = self.ties
        name = self._new_name(card, ties, "*TIE")
        tolerance = None
        if "POSITIONTOLERANCE" in card.params:
            value = card.params["POSITIONTOLERANCE"] or ""
            tolerance = self._float(value, "POSITION TOLERANCE", card.location)
        adjust = (card.params.get("ADJUST") or "YES") if "ADJUST" in card.params else "YES"
        if adjust not in ("YES", "NO"):
            raise DeckError(f"*TIE, ADJUST={adjust}: use ADJUST=YES or ADJUST=NO", card.location)
        self._need_data(card)
        if len(card.lines) != 1:
            raise DeckError(
                "*TIE takes one data line: slave surface, master surface", card.lines[1][2]
            )
        fields, _, loc = card.lines[0]
        fields = [f for f in fields if f != ""]
        if len(fields) != 2:
            raise DeckError("*TIE data line: slave surface, master surface", loc)
        for surface in fields:
            if surface not in self.surfaces:
                raise DeckError(f"surface {surface} is not defined (before this line)", loc)
        ties[name] = Tie(
            name=name,
            slave=fields[0],
            master=fields[1],
            position_tolerance=tolerance,
            adjust=adjust == "YES",
            cyclic="CYCLICSYMMETRY" in card.params,
            location=card.location,
        )

    def _k_CYCLICSYMMETRYMODEL(self, card: Card) -> None:
        allowed = {"N", "NPHYS", "NGRAPH", "TIE", "ELSET", "CHECK", "MATRIX", "CONTACT"}
        self._check_params(card, allowed=allowed, required={"N"})
        for key in ("MATRIX", "CONTACT"):
            if key in card.params:
                raise DeckError(
                    f"*CYCLIC SYMMETRY MODEL, {key} is not supported yet", card.location
                )
        n = self._float(card.params["N"] or "", "N", card.location)
        if not n > 0:
            raise DeckError(f"*CYCLIC SYMMETRY MODEL: N must be > 0, got {n:g}", card.location)
        if "NPHYS" in card.params:
            nphys = self._float(card.params["NPHYS"] or "", "NPHYS", card.location)
            if nphys != n:
                raise DeckError(
                    "*CYCLIC SYMMETRY MODEL: NPHYS other than N (oversampling) is not supported",
                    card.location,
                )
        if "NGRAPH" in card.params:
            ngraph = self._int(card.params["NGRAPH"] or "", "NGRAPH", card.location)
            if ngraph != 1:
                raise DeckError(
                    "*CYCLIC SYMMETRY MODEL: NGRAPH > 1 (results for several sectors) is not "
                    "supported yet",
                    card.location,
                )
        ties = self.ties
        cyclic = [t for t in ties.values() if t.cyclic]
        tie_name = card.params.get("TIE")
        if tie_name:
            if tie_name not in ties or not ties[tie_name].cyclic:
                raise DeckError(
                    f"*CYCLIC SYMMETRY MODEL: no *TIE {tie_name} with CYCLIC SYMMETRY before it",
                    card.location,
                )
        elif len(cyclic) != 1:
            raise DeckError(
                "*CYCLIC SYMMETRY MODEL needs TIE=... (there are "
                f"{len(cyclic)} *TIE cards with CYCLIC SYMMETRY before it)",
                card.location,
            )
        else:
            tie_name = cyclic[0].name
        self._need_data(card)
        fields, _, loc = card.lines[0]
        fields = [f for f in fields if f != ""]
        if len(card.lines) != 1 or len(fields) != 6:
            raise DeckError(
                "*CYCLIC SYMMETRY MODEL: one data line with the points a and b of the axis "
                "(x, y, z, x, y, z)",
                loc,
            )
        values = [self._float(f, "axis point coordinate", loc) for f in fields]
        if np.allclose(values[:3], values[3:], rtol=0.0, atol=0.0):
            raise DeckError("*CYCLIC SYMMETRY MODEL: the two axis points coincide", loc)
        symmetries = self.cyclic_symmetries
        if any(s.tie == tie_name for s in symmetries):
            raise DeckError(
                f"*CYCLIC SYMMETRY MODEL: tie {tie_name} has a *CYCLIC SYMMETRY MODEL already",
                card.location,
            )
        check = (card.params.get("CHECK") or "YES") != "NO"
        symmetries.append(
            CyclicSymmetry(tie_name, n, tuple(values[:3]), tuple(values[3:]), check, card.location)
        )
