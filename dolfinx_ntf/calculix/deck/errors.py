"""Where a deck line is and what goes wrong there: ``Location``, ``DeckError``, ``DeckWarning``.

``not_supported`` makes the error of a feature the model cannot run yet.

See docs/method.md §8.5.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass


class Location(typing.NamedTuple):
    """A line of a deck file (1-based), printed as ``file:line``.

    A named tuple: the reader makes one per line of the deck (10^5 and more), so it must be cheap.
    """

    file: str
    line: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}"


class DeckError(ValueError):
    """Bad or unsupported deck input; the message starts with ``file:line``."""

    def __init__(self, message: str, location: Location | None = None) -> None:
        self.location = location
        super().__init__(f"{location}: {message}" if location is not None else message)


@dataclass(frozen=True)
class DeckWarning:
    """A keyword or parameter that was read and skipped because it cannot change the solution.

    Attributes:
        keyword: the keyword as ccx spells it (``*EL FILE``).
        parameter: the parameter as written (``POSITION=NODES``), or None for the whole keyword.
        reason: why skipping it is safe.
        location: where the card is.
    """

    keyword: str
    parameter: str | None
    reason: str
    location: Location

    def __str__(self) -> str:
        what = "keyword" if self.parameter is None else f"parameter {self.parameter}"
        return (
            f" *WARNING reading {self.keyword}: {what} ignored ({self.reason}) at {self.location}"
        )


def not_supported(what: str, location: Location | str) -> NotImplementedError:
    """The error for ``what`` (a keyword or parameter at ``location``) not supported yet."""
    return NotImplementedError(f"{location}: {what} is not supported yet")
