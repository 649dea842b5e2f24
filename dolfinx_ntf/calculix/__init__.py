"""CalculiX interoperability: deck reader, ``.dat``/``.cel`` writers and a ``ccx`` runner.

Pure Python/numpy (no dolfinx import), so decks and ccx results can be handled anywhere.
"""
