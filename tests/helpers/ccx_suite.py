"""Files of CalculiX's test suite (``calculix-ccx-test``): gzipped (Debian 12) or not (13, sid)."""

from __future__ import annotations

import gzip

from .decks import CCX_TESTS


def suite_file_exists(name: str) -> bool:
    """True if ``name`` (e.g. ``contact5.inp``) is installed, gzipped or not."""
    return (CCX_TESTS / name).exists() or (CCX_TESTS / f"{name}.gz").exists()


def suite_text(name: str) -> str:
    """The text of ``name`` (e.g. ``contact5.dat.ref``), gzipped (Debian 12) or not."""
    plain = CCX_TESTS / name
    if plain.exists():
        return plain.read_text()
    return gzip.decompress((CCX_TESTS / f"{name}.gz").read_bytes()).decode()
