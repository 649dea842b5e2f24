"""What the reader does with keywords and parameters it does not use (ccx's leniency).

See docs/method.md §8.5.
"""

from __future__ import annotations

from .lexer import normalized_name

# What the reader does with the keywords and parameters it does not use. ccx 2.20 prints a warning
# for every keyword and parameter it does not recognize and goes on; here a skipped keyword or
# parameter must also be one that cannot change the solution, the others are refused:
#   keyword -> {parameter: (action, reason)}, action "warn" (one DeckWarning, the card is read
#   without it) or "refuse" (DeckError); parameter "" is the whole keyword, "*" any parameter.
# Keywords and parameters in neither this table nor a handler are refused as well.
_OUTPUT_ONLY = "output only: ccx 2.20 ignores it"
_TIME_POINTS = "ccx cuts the increments to reach the time points"
_FILE_RULES = {
    "POSITION": ("warn", _OUTPUT_ONLY),
    "ELSET": ("warn", "not a file request parameter: ccx 2.20 ignores it and writes every node"),
    "TIME POINTS": ("refuse", _TIME_POINTS),
}
LENIENCY: dict[str, dict[str, tuple[str, str]]] = {
    "*HEADING": {"*": ("warn", "ccx ignores *HEADING parameters")},
    "*NSET": {"FREQUENCY": ("warn", "not a *NSET parameter: ccx ignores it")},
    "*ELSET": {"FREQUENCY": ("warn", "not a *ELSET parameter: ccx ignores it")},
    "*NODE FILE": _FILE_RULES,
    "*EL FILE": _FILE_RULES,
    "*CONTACT FILE": _FILE_RULES,
    "*NODE OUTPUT": _FILE_RULES,
    "*ELEMENT OUTPUT": _FILE_RULES,
    "*CONTACT OUTPUT": _FILE_RULES,
    "*OUTPUT": {"": ("warn", "output database only"), "TIME POINTS": ("refuse", _TIME_POINTS)},
    "*FACE PRINT": {"": ("warn", "output only"), "TIME POINTS": ("refuse", _TIME_POINTS)},
    "*SECTION PRINT": {"": ("warn", "output only"), "TIME POINTS": ("refuse", _TIME_POINTS)},
    "*PREPRINT": {"": ("warn", "Abaqus printout control: ccx ignores it")},
    "*RESTART": {
        "": ("warn", "restart files are not written"),
        "READ": ("refuse", "starts from the state of an earlier run"),
    },
    "*BOUNDARY": {
        "FIXED": ("refuse", "holds the displacement of the previous step"),
        "USER": ("refuse", "values from a user subroutine"),
        "SUBMODEL": ("refuse", "values from a global model"),
    },
    "*STEP": {"AMPLITUDE": ("refuse", "ramps or steps the loads")},
}
LENIENCY_RULES = {
    normalized_name(k[1:]): {
        normalized_name(p) if p not in ("", "*") else p: (a, r, p) for p, (a, r) in rules.items()
    }
    for k, rules in LENIENCY.items()
}

# Skipped output keywords whose FREQUENCY still sets the frequency of every output (ccx rule).
SETS_FREQUENCY = {"OUTPUT", "FACEPRINT", "SECTIONPRINT"}
