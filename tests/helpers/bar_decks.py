"""The mesh of the two-bar thermal contact decks (test_ccx_heat_decks, test_ccx_thermal_decks)."""

from __future__ import annotations

import numpy as np


def stacked_bars(
    elements: int, gap: float = 0.0, length: float = 1.0
) -> tuple[list[str], list[list[int]], dict[tuple[int, int], list[int]]]:
    """Two unit-square bars of ``elements`` C3D8 each along z: lower z in [-length, 0], upper
    z in [gap, gap + length], nodes numbered from 1 layer by layer.

    Returns the ``*NODE`` data lines, each element's 8 nodes and the nodes of each layer
    (``layers[bar, i]``, bar 0 the lower, i from its bottom; 4 nodes counterclockwise from (0, 0)).
    """
    nodes: list[str] = []
    cells: list[list[int]] = []
    layers: dict[tuple[int, int], list[int]] = {}
    number = 0
    for bar, (z0, z1) in enumerate(((-length, 0.0), (gap, gap + length))):
        for i, z in enumerate(np.linspace(z0, z1, elements + 1)):
            ids = []
            for x, y in ((0, 0), (1, 0), (1, 1), (0, 1)):
                number += 1
                nodes.append(f"{number}, {x}., {y}., {float(z)!r}")
                ids.append(number)
            layers[bar, i] = ids
        cells += [layers[bar, i] + layers[bar, i + 1] for i in range(elements)]
    return nodes, cells, layers


def ids(values: list[int]) -> str:
    """Node or element numbers as a deck's data line."""
    return ", ".join(map(str, values))
