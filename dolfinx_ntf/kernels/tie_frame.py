"""A frame intrinsic to the contact pair, to decide exact ties of the search (docs/method.md §3.2).

A slave node exactly above a master edge or vertex is equally near to the centroids of several
master triangles, and nothing local decides which one the walk starts from: the half turn about the
normal through the edge swaps them. The stable search (``walk_from_previous_face=True``) breaks such
ties by position in a frame that moves with the model instead of the global axes, so that the same
faces are chosen whatever the node numbering and wherever the model is rotated or translated:

- origin: the centroid, and axes: the principal axes (largest second moment first), of the master
  surface (area-weighted, exact integrals over its triangles) together with the slave nodes
  (weighted by their spring areas);
- the sign of each axis: that of the third moment along it, else of the master's vector area along
  it; one axis left undecided is fixed by handedness (rotations, not reflections, are symmetries to
  respect).

Where two second moments are equal or two signs undecided, the model has (to ``FRAME_DIGITS``
digits) a symmetry that the frame cannot see through, and there is no frame: the caller falls back
to the global axes. Moments are plain sums, so the slave part can be summed over processes.

Pure numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "FRAME_DIGITS",
    "MOMENT_SIZE",
    "TieFrame",
    "frame_from_moments",
    "point_moments",
    "triangle_moments",
]

FRAME_DIGITS = 6
"""Second moments (and third moments, vector areas) equal to this many digits count as equal."""
MOMENT_SIZE = 1 + 3 + 9 + 27 + 3
"""Length of a moment vector: weight, first, second, third moments, vector area."""


@dataclass(frozen=True)
class TieFrame:
    """Origin and (3, 3) orthonormal axes (rows) of the intrinsic frame."""

    origin: np.ndarray
    axes: np.ndarray

    def first(self, points: np.ndarray, candidates: np.ndarray, tolerance: float) -> np.ndarray:
        """Index of the lexicographically first candidate point in this frame, for each row.

        Args:
            points: (N, k, 3) positions.
            candidates: (N, k) which positions take part (at least one per row).
            tolerance: Frame coordinates closer than this are equal.

        Returns:
            (N,) index into ``k``: the least first frame coordinate, among those equal to it the
            least second one, and so on.
        """
        local = (np.asarray(points, dtype=float) - self.origin) @ self.axes.T
        keep = np.asarray(candidates, dtype=bool).copy()
        for axis in range(3):
            value = np.where(keep, local[..., axis], np.inf)
            keep &= value <= value.min(axis=1, keepdims=True) + tolerance
        return np.argmax(keep, axis=1)


def triangle_moments(a: np.ndarray, b: np.ndarray, c: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Exact area moments (about ``origin``) of triangles with corners ``a, b, c`` (each (T, 3)).

    Returns:
        Moment vector of length ``MOMENT_SIZE``.
    """
    v = np.stack([a, b, c], axis=1) - np.asarray(origin, dtype=float)  # (T, 3, 3)
    m = 0.5 * np.cross(b - a, c - a)
    area = np.linalg.norm(m, axis=1)
    s = v.sum(axis=1)
    second = (np.einsum("t,tki,tkj->ij", area, v, v) + np.einsum("t,ti,tj->ij", area, s, s)) / 12.0
    third = (
        np.einsum("t,ti,tj,tk->ijk", area, s, s, s)
        + np.einsum("t,tai,taj,tk->ijk", area, v, v, s)
        + np.einsum("t,tai,tj,tak->ijk", area, v, s, v)
        + np.einsum("t,ti,taj,tak->ijk", area, s, v, v)
        + 2.0 * np.einsum("t,tai,taj,tak->ijk", area, v, v, v)
    ) / 60.0
    first = np.einsum("t,ti->i", area, s) / 3.0
    return np.concatenate([[area.sum()], first, second.ravel(), third.ravel(), m.sum(axis=0)])


def point_moments(points: np.ndarray, weights: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Moments (about ``origin``) of weighted points ((N, 3), (N,)); no vector area.

    Returns:
        Moment vector of length ``MOMENT_SIZE``.
    """
    d = np.asarray(points, dtype=float).reshape(-1, 3) - np.asarray(origin, dtype=float)
    w = np.asarray(weights, dtype=float).reshape(-1)
    return np.concatenate(
        [
            [w.sum()],
            w @ d,
            np.einsum("n,ni,nj->ij", w, d, d).ravel(),
            np.einsum("n,ni,nj,nk->ijk", w, d, d, d).ravel(),
            np.zeros(3),
        ]
    )


def frame_from_moments(moments: np.ndarray, origin: np.ndarray) -> TieFrame | None:
    """The intrinsic frame of a moment vector taken about ``origin``; None where it is not unique.

    Returns:
        The frame, or None if the total weight is zero, two principal second moments are equal,
        or the signs of two axes are undecided (to ``FRAME_DIGITS`` digits).
    """
    moments = np.asarray(moments, dtype=float)
    weight = moments[0]
    if not weight > 0.0:
        return None
    mean = moments[1:4] / weight
    second = moments[4:13].reshape(3, 3) / weight
    third = moments[13:40].reshape(3, 3, 3) / weight
    vector_area = moments[40:43]
    covariance = second - np.outer(mean, mean)
    values, vectors = np.linalg.eigh(0.5 * (covariance + covariance.T))
    values, axes = values[::-1], vectors[:, ::-1].T  # largest second moment first
    tol = 10.0**-FRAME_DIGITS
    if not values[0] > 0.0 or np.any(values[:-1] - values[1:] <= tol * values[0]):
        return None
    c = axes @ mean  # mean along each axis
    raw2 = np.einsum("ai,ij,aj->a", axes, second, axes)
    raw3 = np.einsum("ai,aj,ak,ijk->a", axes, axes, axes, third)
    skew = raw3 - 3.0 * c * raw2 + 2.0 * c**3  # third central moment along each axis
    area = axes @ vector_area
    sign = np.where(np.abs(skew) > tol * values[0] ** 1.5, np.sign(skew), 0.0)
    sign = np.where((sign == 0.0) & (np.abs(area) > tol * weight), np.sign(area), sign)
    undecided = np.flatnonzero(sign == 0.0)
    if undecided.size > 1:
        return None
    axes = axes * np.where(sign == 0.0, 1.0, sign)[:, None]
    if undecided.size == 1 and np.linalg.det(axes) < 0.0:
        axes[undecided[0]] *= -1.0
    return TieFrame(origin=np.asarray(origin, dtype=float) + mean, axes=axes)
