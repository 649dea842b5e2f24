"""Output request cards: ``*NODE/EL/CONTACT PRINT`` and ``*NODE/EL/CONTACT FILE`` (``OUTPUT``)."""

from __future__ import annotations

from .data import FileRequest, PrintRequest
from .errors import DeckError
from .lexer import Card
from .orientations import OrientationCards

_FILE_KEYWORDS = {
    "NODEFILE": "NODE",
    "NODEOUTPUT": "NODE",
    "ELFILE": "EL",
    "ELEMENTOUTPUT": "EL",
    "CONTACTFILE": "CONTACT",
    "CONTACTOUTPUT": "CONTACT",
}

_PRINT_KEYS = {
    "NODE": ("U", "V", "RF", "NT"),
    "EL": ("S", "E", "PEEQ", "HFL", "ENER", "SDV", "ME"),
    "CONTACT": ("CDIS", "CSTR", "CELS", "CNUM"),
}


def _element_keys(kind: str, keys: tuple[str, ...]) -> tuple[str, ...]:
    """ccx 2.20's ``PE`` is ``PEEQ`` (the same block, measured; ccx's test deck beampiso2)."""
    if kind != "EL":
        return keys
    return tuple("PEEQ" if k == "PE" else k for k in keys)


class OutputCards(OrientationCards):
    """Handlers of the print and file request cards."""

    def _print_card(self, card: Card, kind: str) -> None:
        step = self._in_step(card)
        set_param = {"NODE": "NSET", "EL": "ELSET", "CONTACT": "NSET"}[kind]
        allowed = {set_param, "TOTALS", "FREQUENCY", "FREQUENCYF", "GLOBAL", "TIMEPOINTS"}
        required = {set_param} if kind != "CONTACT" else set()
        self._check_params(card, allowed=allowed, required=required)
        totals = card.params.get("TOTALS") or "NO"
        if totals not in ("YES", "NO", "ONLY"):
            raise DeckError(f"TOTALS={totals}: use YES, NO or ONLY", card.location)
        set_name = None
        if kind != "CONTACT":  # ccx ignores NSET on *CONTACT PRINT (docs/method.md §8.5)
            set_name = card.params[set_param] or ""
            sets = self.nsets if kind == "NODE" else self.elsets
            if set_name not in sets:
                raise DeckError(
                    f"{'node' if kind == 'NODE' else 'element'} set {set_name} is not defined "
                    "(before this line)",
                    card.location,
                )
        self._need_data(card)
        keys = tuple(k for fields, _, _ in card.lines for k in fields if k != "")
        if kind == "CONTACT":  # ccx reads the first four characters only (CDISP is CDIS)
            keys = tuple(k[:4] for k in keys)
        keys = _element_keys(kind, keys)
        for key in keys:
            if key not in _PRINT_KEYS[kind]:
                raise DeckError(
                    f"{card.name} key {key} is not supported yet (supported: "
                    f"{', '.join(_PRINT_KEYS[kind])})",
                    card.location,
                )
        frequency = self._frequency(card)
        time_points = card.params.get("TIMEPOINTS")
        if time_points is not None and time_points not in self.time_points:
            raise DeckError(f"time points {time_points} are not defined (before this line)",
                            card.location)  # fmt: skip
        if not any(p.kind == kind for p in step.new_prints):
            self.prints = [p for p in self.prints if p.kind != kind]
        if kind == "EL":
            self._check_local_axes(card, set_name, keys)
        request = PrintRequest(kind, keys, set_name, totals, frequency, card.location, time_points)
        step.new_prints.append(request)
        self.prints.append(request)

    def _k_NODEPRINT(self, card: Card) -> None:
        self._print_card(card, "NODE")

    def _k_ELPRINT(self, card: Card) -> None:
        self._print_card(card, "EL")

    def _k_CONTACTPRINT(self, card: Card) -> None:
        self._print_card(card, "CONTACT")

    def _file_card(self, card: Card) -> None:
        step = self._in_step(card)
        kind = _FILE_KEYWORDS[card.keyword]
        self._check_params(card, allowed={"NSET", "FREQUENCY", "FREQUENCYF", "GLOBAL", "OUTPUT",
                                          "LASTITERATIONS", "CONTACTELEMENTS",
                                          "SECTIONFORCES"})  # fmt: skip
        keys = tuple(k for fields, _, _ in card.lines for k in fields if k != "")
        if kind == "CONTACT":  # as for *CONTACT PRINT: ccx reads four characters (CDISP is CDIS)
            keys = tuple(k[:4] for k in keys)
        keys = _element_keys(kind, keys)
        set_name = None
        if "NSET" in card.params:  # ccx restricts *NODE/EL FILE to it (docs/method.md §13.2)
            set_name = card.params["NSET"] or ""
            if set_name not in self.nsets:
                raise DeckError(f"node set {set_name} is not defined (before this line)",
                                card.location)  # fmt: skip
        frequency = self._frequency(card)
        if kind == "EL":
            self._check_local_axes(card, None, keys)
        if not any(r.kind == kind for r in step.new_files):
            self.files = [r for r in self.files if r.kind != kind]
        request = FileRequest(card.name, kind, keys, set_name, "CONTACTELEMENTS" in card.params,
                              frequency, card.location)  # fmt: skip
        step.new_files.append(request)
        self.files.append(request)

    _k_NODEFILE = _k_NODEOUTPUT = _k_ELFILE = _k_ELEMENTOUTPUT = _file_card
    _k_CONTACTFILE = _k_CONTACTOUTPUT = _file_card
