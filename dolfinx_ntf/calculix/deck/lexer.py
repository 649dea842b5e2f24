"""Deck lines to cards: comments, ``*INCLUDE`` files, keyword lines, parameters, data fields.

See docs/method.md §8.5. Names are upper case without blanks, as ccx prints them.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from .errors import DeckError, Location

INT_RE = re.compile(r"^[+-]?\d+$")


def normalized_name(text: str) -> str:
    """Ccx name normalization: upper case, blanks removed."""
    return "".join(text.split()).upper()


@dataclass
class Card:
    """A keyword line of the deck with its data lines (what the card readers parse)."""

    keyword: str  # blank-free upper-case keyword, e.g. "SOLIDSECTION"
    text: str  # keyword as written (upper-case), for messages
    params: dict[str, str | None]
    raw_params: dict[str, str | None]
    location: Location
    lines: list[tuple[list[str], str, Location]] = field(default_factory=list)

    @property
    def name(self) -> str:
        """The keyword as ccx spells it (``*SOLID SECTION``), for messages."""
        return CANONICAL_KEYWORDS.get(self.keyword, self.text)


def _split_keyword_line(text: str, location: Location) -> Card:
    fields = text[1:].split(",")
    keyword_text = fields[0].strip().upper()
    params: dict[str, str | None] = {}
    raw: dict[str, str | None] = {}
    for item in fields[1:]:
        if not item.strip():
            continue
        key, sep, value = item.partition("=")
        key = normalized_name(key)
        params[key] = normalized_name(value) if sep else None
        raw[key] = value.strip() if sep else None
    return Card(normalized_name(keyword_text), keyword_text, params, raw, location)


def _data_fields(text: str) -> list[str]:
    if text.isascii() and text.isprintable():  # most lines: the blank is the only white space
        fields = text.replace(" ", "").upper().split(",")
    else:
        fields = normalized_name(text).split(",")
    if fields and fields[-1] == "":
        fields.pop()
    return fields


# Canonical spelling of every keyword mentioned in messages, by blank-free form.
_KEYWORDS = """
AMPLITUDE; BEAM GENERAL SECTION; BEAM SECTION; BOUNDARY; BOUNDARYF; BUCKLE; CFD; CFLUX;
CHANGE FRICTION; CHANGE MATERIAL; CHANGE PLASTIC; CHANGE SURFACE BEHAVIOR; CHANGE SOLID SECTION;
CLEARANCE; CLOAD; COMPLEX FREQUENCY; CONDUCTIVITY; CONTACT DAMPING; CONTACT FILE; CONTACT OUTPUT;
CONTACT PAIR; CONTACT PRINT; CONTROLS; COUPLED TEMPERATURE-DISPLACEMENT; COUPLING; CREEP;
CYCLIC HARDENING; CYCLIC SYMMETRY MODEL; DAMPING; DASHPOT; DEFORMATION PLASTICITY; DENSITY;
DEPVAR; DESIGNVARIABLES; DFLUX; DISTRIBUTING; DISTRIBUTING COUPLING; DLOAD; DSLOAD; DYNAMIC;
ELASTIC; ELECTRICAL CONDUCTIVITY; ELECTROMAGNETICS; ELEMENT; ELEMENT OUTPUT; EL FILE; EL PRINT;
ELSET; END STEP; EQUATION; EXPANSION; FACE PRINT; FILM; FLUID CONSTANTS; FLUID SECTION;
FREQUENCY; FRICTION; GAP; GAP CONDUCTANCE; GAP HEAT GENERATION; GREEN; HEADING; HEAT TRANSFER;
HYPERELASTIC; HYPERFOAM; INCLUDE; INITIAL CONDITIONS; INITIAL STRAIN INCREASE; KINEMATIC;
MAGNETIC PERMEABILITY; MASS; MASS FLOW; MATERIAL; MEMBRANE SECTION; MODAL DAMPING; MODAL DYNAMIC;
MODEL CHANGE; MPC; NETWORK MPC; NO ANALYSIS; NODAL THICKNESS; NODE; NODE FILE; NODE OUTPUT;
NODE PRINT; NORMAL; NSET; OBJECTIVE; ORIENTATION; OUTPUT; PHYSICAL CONSTANTS; PLASTIC; PREPRINT;
PRE-TENSION SECTION; RADIATE; REFINE MESH; RESTART; RETAINED NODAL DOFS; RIGID BODY;
SECTION PRINT; SELECT CYCLIC SYMMETRY MODES; SENSITIVITY; SHELL SECTION; SOLID SECTION;
SPECIFIC GAS CONSTANT; SPECIFIC HEAT; SPRING; STATIC; STEADY STATE DYNAMICS; STEP; SUBMODEL;
SUBSTRUCTURE GENERATE; SUBSTRUCTURE MATRIX OUTPUT; SURFACE; SURFACE BEHAVIOR;
SURFACE INTERACTION; TEMPERATURE; TIE; TIME POINTS; TRANSFORM; TRANSFORMF; UNCOUPLED
TEMPERATURE-DISPLACEMENT; USER ELEMENT; USER MATERIAL; USER SECTION; VALUES AT INFINITY;
VIEWFACTOR; VISCO; CONSTRAINT; FILTER; GEOMETRIC CONSTRAINT; ROBUSTDESIGN; CRACK PROPAGATION;
CHANGE CONTACT TYPE; CHANGE KINEMATIC; CHANGE TIE; ELECTROMAGNETICS; EMODAL DAMPING
"""
CANONICAL_KEYWORDS: dict[str, str] = {
    normalized_name(k): "*" + " ".join(k.split())
    for k in _KEYWORDS.replace("\n", " ").split(";")
    if k.strip()
}


def check_params(card: Card, allowed: set[str], required: set[str] = frozenset()) -> None:
    """A ``DeckError`` for a parameter of ``card`` not in ``allowed`` or a missing ``required``."""
    for key in card.params:
        if key not in allowed:
            raise DeckError(f"parameter {key} of {card.name} is not supported", card.location)
    for key in required:
        if key not in card.params or card.params[key] in (None, ""):
            raise DeckError(f"{card.name} needs the parameter {key}=...", card.location)


def _lines(
    path: Path, main: Path, include_loc: Location | None, stack: tuple[Path, ...]
) -> Iterator[tuple[str, Location]]:
    resolved = path.resolve()
    if resolved in stack:
        raise DeckError(f"*INCLUDE of {path} is recursive", include_loc)
    try:
        text = path.read_text(encoding="latin-1")
    except OSError as exc:
        where = "deck" if include_loc is None else "*INCLUDE file"
        raise DeckError(f"cannot read {where} {path}: {exc.strerror}", include_loc) from None
    name = str(path)
    for number, line in enumerate(text.splitlines(), start=1):
        location = Location(name, number)
        stripped = line.lstrip()
        if stripped.startswith("*") and not stripped.startswith("**"):
            card = _split_keyword_line(stripped.rstrip(), location)
            if card.keyword == "INCLUDE":
                included = _include_path(card, path, main)
                yield from _lines(included, main, location, (*stack, resolved))
                continue
        yield line, location


def _include_path(card: Card, current: Path, main: Path) -> Path:
    check_params(card, allowed={"INPUT"}, required={"INPUT"})
    name = (card.raw_params["INPUT"] or "").strip().strip('"')
    if not name:
        raise DeckError("*INCLUDE needs INPUT=<file>", card.location)
    candidate = Path(name)
    if not candidate.is_absolute():
        for base in (current.parent, main.parent):
            if (base / candidate).exists():
                return base / candidate
        return current.parent / candidate
    return candidate


def read_cards(path: Path) -> Iterator[Card]:
    """The cards of deck ``path`` with its ``*INCLUDE`` files, each with its data lines."""
    card: Card | None = None
    for line, location in _lines(path, path, None, ()):
        stripped = line.strip()
        if not stripped or stripped.startswith("**"):
            continue
        if stripped.startswith("*"):
            if card is not None:
                yield card
            card = _split_keyword_line(stripped, location)
        elif card is None:
            raise DeckError("data line before the first keyword", location)
        else:
            card.lines.append((_data_fields(stripped), line, location))
    if card is not None:
        yield card
