"""Central differences of spring forces by the nodal coordinates, for the kernels' tangent tests.

A spring of ``k`` nodes in ``d`` dimensions has ``k d`` force components; its tangent is checked
against ``(f(x + h e_j) - f(x - h e_j)) / 2 h`` column by column, over all N springs at once.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def nodal_differences(
    forces: Callable[..., np.ndarray], arrays: tuple[np.ndarray, ...], h: float
) -> np.ndarray:
    """Central differences of ``forces(*arrays)`` by the nodal coordinates, ``(N, k d, k d)``.

    Args:
        forces: The forces of the N springs, ``(N, k, d)`` or ``(N, k d)``, at the given arrays.
        arrays: ``(N, k, d)`` arrays moved together (positions, and displacements that move with
            them); the first sets the shape.
        h: The step.
    """
    num, k, d = arrays[0].shape
    fd = np.zeros((num, k * d, k * d))
    for node in range(k):
        for c in range(d):
            values = []
            for sign in (1.0, -1.0):
                moved = [a.copy() for a in arrays]
                for a in moved:
                    a[:, node, c] += sign * h
                values.append(forces(*moved).reshape(num, -1))
            fd[:, :, d * node + c] = (values[0] - values[1]) / (2 * h)
    return fd


def relative_error(k: np.ndarray, k_ref: np.ndarray) -> np.ndarray:
    """Per-spring max-norm error relative to the max-norm of the reference."""
    num = len(k)
    diff = np.abs(k - k_ref).reshape(num, -1).max(axis=1)
    return diff / np.abs(k_ref).reshape(num, -1).max(axis=1)
