"""``*ORIENTATION`` and ``*SOLID SECTION, ORIENTATION=``: material axes of isotropic sections.

See docs/method.md §41.3. An orientation turns the material axes; the reader's materials are
isotropic (``*ELASTIC`` of TYPE=ISO, ``*PLASTIC`` with isotropic hardening), so it cannot change
the solution, and ccx 2.20 writes the same ``.dat`` and ``.frd`` with and without it when the
element outputs are requested in global axes (measured). ccx writes S, E and ME in the
orientation's axes (in ``.dat`` lines followed by its name) for ``*EL PRINT`` without
``GLOBAL=YES`` (its default is NO) and for ``*EL FILE, GLOBAL=NO``: such requests over oriented
elements are refused; PEEQ, ENER and SDV are written the same in either case.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import DeckError, Location
from .lexer import Card
from .state import ReaderState

#: Element output keys ccx 2.20 writes in an orientation's axes without GLOBAL=YES (measured:
#: S, E and ME turned, and ``*EL PRINT`` lines followed by the orientation's name; PEEQ, ENER and
#: SDV, its plastic strain included, as in global axes).
_TURNED_KEYS = ("S", "E", "ME")

#: Smallest ``|a|`` and ``|a x b|`` relative to the points' size for a rectangular system.
_DEGENERATE = 1e-12


@dataclass(frozen=True, eq=False)
class Orientation:
    """One ``*ORIENTATION``: ``system`` ``"RECTANGULAR"`` or ``"CYLINDRICAL"``, points ``a``, ``b``.

    ``rotation`` is the optional extra rotation of a rectangular system: ``(local axis 1..3,
    angle in degrees)``.
    """

    name: str
    system: str
    a: tuple[float, float, float]
    b: tuple[float, float, float]
    rotation: tuple[int, float] | None
    location: Location


class OrientationCards(ReaderState):
    """The ``*ORIENTATION`` handler and the check of element outputs over oriented sections."""

    def _k_ORIENTATION(self, card: Card) -> None:
        self._check_params(card, allowed={"NAME", "SYSTEM", "DEFINITION"}, required={"NAME"})
        name = self._new_name(card, self.orientations, "orientation")
        system = card.params.get("SYSTEM") or "RECTANGULAR"
        if system not in ("RECTANGULAR", "CYLINDRICAL"):
            raise DeckError(
                f"*ORIENTATION, SYSTEM={system}: RECTANGULAR or CYLINDRICAL expected", card.location
            )
        definition = card.params.get("DEFINITION") or "COORDINATES"
        if definition != "COORDINATES":
            raise DeckError(
                f"*ORIENTATION, DEFINITION={definition} is not supported (only COORDINATES: "
                "two points on the data line)",
                card.location,
            )
        self._need_data(card)
        fields, _, loc = card.lines[0]
        if len(fields) != 6:
            raise DeckError(
                "*ORIENTATION data line: the coordinates of points a and b (six numbers; "
                "*DISTRIBUTION names are not supported)",
                loc,
            )
        values = np.array([self._float(f, "coordinate", loc) for f in fields])
        a, b = values[:3], values[3:]
        size = max(float(np.abs(values).max()), 1.0)
        if system == "RECTANGULAR" and (
            np.linalg.norm(a) <= _DEGENERATE * size
            or np.linalg.norm(np.cross(a, b)) <= _DEGENERATE * size**2
        ):
            raise DeckError(
                "*ORIENTATION: point a must not be the origin and point b not on the axis "
                "through a",
                loc,
            )
        if system == "CYLINDRICAL" and np.linalg.norm(b - a) <= _DEGENERATE * size:
            raise DeckError("*ORIENTATION: the axis points a and b coincide", loc)
        rotation = None
        if len(card.lines) > 1:
            fields, _, loc = card.lines[1]
            if system != "RECTANGULAR" or len(card.lines) > 2 or len(fields) != 2:
                raise DeckError(
                    "*ORIENTATION: the second data line (local axis 1..3, angle) is for "
                    "rectangular systems only",
                    loc,
                )
            axis = fields[0].strip()
            if axis not in ("1", "2", "3"):
                raise DeckError(f"*ORIENTATION: local axis {axis!r}: 1, 2 or 3 expected", loc)
            rotation = (int(axis), self._float(fields[1], "angle", loc))
        self.orientations[name] = Orientation(
            name, system, tuple(a.tolist()), tuple(b.tolist()), rotation, card.location
        )

    def _section_orientation(self, card: Card) -> str | None:
        """The ``ORIENTATION`` of a ``*SOLID SECTION`` card, which must be defined before it."""
        name = card.params.get("ORIENTATION")
        if name is None:
            return None
        if name not in self.orientations:
            raise DeckError(f"orientation {name} is not defined (before this line)", card.location)
        return name

    def _check_local_axes(self, card: Card, elset: str | None, keys: tuple[str, ...]) -> None:
        """Refuse element outputs ccx would write in an orientation's axes (module doc).

        ``elset`` is the ``*EL PRINT`` set, None for ``*EL FILE`` (every element); ``keys`` the
        requested keys: only the tensors S, E and ME turn (PEEQ, ENER and SDV are written as
        in global axes, measured).
        """
        if all(section.orientation is None for section in self.sections):
            return  # GLOBAL changes nothing (decks without orientations read as before)
        turned = [key for key in keys if key in _TURNED_KEYS]
        if not turned:
            return
        is_print = elset is not None
        global_axes = card.params.get("GLOBAL") or ("NO" if is_print else "YES")
        if global_axes not in ("YES", "NO"):
            raise DeckError(f"GLOBAL={global_axes}: YES or NO expected", card.location)
        if global_axes == "YES":
            return
        members = np.unique(self.elsets[elset]) if is_print else None
        for section in self.sections:
            if section.orientation is None:
                continue
            if members is not None and not np.any(np.isin(self.elsets[section.elset], members)):
                continue
            default = " (the default of *EL PRINT)" if "GLOBAL" not in card.params else ""
            raise DeckError(
                f"{card.name} {', '.join(turned)} with GLOBAL=NO{default} over elements of the "
                f"section at {section.location} (ORIENTATION={section.orientation}): ccx 2.20 "
                "writes them in the orientation's axes, which is not supported; write "
                "GLOBAL=YES",
                card.location,
            )
