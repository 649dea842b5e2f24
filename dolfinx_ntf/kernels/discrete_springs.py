"""Discrete spring elements between two nodes: forces and tangents, vectorized over springs.

CalculiX's spring elements (docs/method.md §18), pure numpy. A spring has two end nodes; a
grounded end is a node that does not move. Its element dofs are ``[node 1 x, y, z, node 2 x, y,
z]``, and it returns the internal forces (the residual contribution: the forces the nodes need to
hold the spring stretched) and their derivative with respect to the nodal displacements.

- :class:`AxialSpring` (ccx SPRINGA): the force ``F(e)`` acts along the line between the nodes,
  ``e = L - L0`` the elongation; with ``nlgeom`` the line and the length are the current ones,
  otherwise the initial line and the elongation linearized on it, ``e = (u2 - u1) . n0``.
- :class:`DirectionalSpring` (ccx SPRING1, SPRING2): the force ``F(e)`` with
  ``e = u1 . n1 - u2 . n2`` acts along the fixed unit direction ``n1`` on node 1 and ``-n2`` on
  node 2 (SPRING1: node 2 is grounded).

The force ``F`` is a :class:`LinearSpringLaw` ``k e`` or a :class:`TabularSpringLaw` (piecewise
linear in the elongation, constant beyond the table as ccx extrapolates).
"""

from __future__ import annotations

import typing
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "AxialSpring",
    "DirectionalSpring",
    "LinearSpringLaw",
    "SpringElement",
    "SpringLaw",
    "TabularSpringLaw",
]


class SpringLaw(typing.Protocol):
    """Force of a spring as a function of its elongation."""

    def __call__(self, elongation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Force ``F(e)`` and slope ``F'(e)`` at the elongations ``e`` (shape (S,))."""


@dataclass(frozen=True)
class LinearSpringLaw:
    """``F(e) = k e`` (ccx ``*SPRING`` with a spring constant).

    Args:
        stiffness: The spring constant ``k`` (force per length), one value or one per spring.
    """

    stiffness: float | np.ndarray

    def __post_init__(self) -> None:
        k = np.asarray(self.stiffness, dtype=float)
        if not np.all(np.isfinite(k)):
            raise ValueError(f"LinearSpringLaw: the stiffness must be finite, got {self.stiffness}")

    def __call__(self, elongation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Force ``k e`` and slope ``k``."""
        k = np.broadcast_to(np.asarray(self.stiffness, dtype=float), elongation.shape)
        return k * elongation, k.copy()


@dataclass(frozen=True)
class TabularSpringLaw:
    """Piecewise linear ``F(e)`` through ``(elongation[i], force[i])`` (ccx ``*SPRING, NONLINEAR``).

    Beyond the table the force stays constant (slope zero), as in CalculiX.

    Args:
        elongation: Increasing elongations (at least two).
        force: The forces at those elongations.
    """

    elongation: np.ndarray = field(repr=False)
    force: np.ndarray = field(repr=False)

    def __post_init__(self) -> None:
        e = np.asarray(self.elongation, dtype=float).ravel()
        f = np.asarray(self.force, dtype=float).ravel()
        if e.size < 2 or e.size != f.size:
            raise ValueError(
                "TabularSpringLaw: need at least two (elongation, force) points of equal count, "
                f"got {e.size} elongations and {f.size} forces"
            )
        if not (np.all(np.isfinite(e)) and np.all(np.isfinite(f))):
            raise ValueError("TabularSpringLaw: the table must be finite")
        if np.any(np.diff(e) <= 0.0):
            raise ValueError(
                f"TabularSpringLaw: the elongations must increase strictly, got {e.tolist()}"
            )
        object.__setattr__(self, "elongation", e)
        object.__setattr__(self, "force", f)

    def __call__(self, elongation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Interpolated force and the slope of its segment (zero outside the table)."""
        e, f = self.elongation, self.force
        force = np.interp(elongation, e, f)
        segment = np.clip(np.searchsorted(e, elongation, side="right") - 1, 0, e.size - 2)
        slope = (f[segment + 1] - f[segment]) / (e[segment + 1] - e[segment])
        inside = (elongation >= e[0]) & (elongation <= e[-1])
        return force, np.where(inside, slope, 0.0)


class SpringElement(typing.Protocol):
    """A two-node spring: internal forces and tangent from the end nodes' positions."""

    def evaluate(
        self, reference: np.ndarray, displacement: np.ndarray, *, tangent: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Forces (S, 6) and tangent (S, 6, 6) of S springs.

        ``reference`` and ``displacement`` have shape (S, 2, 3): node 1 and node 2 of each spring.
        """


@dataclass(frozen=True)
class AxialSpring:
    """A spring along the line between its nodes (ccx SPRINGA).

    Args:
        law: The force as a function of the elongation ``L - L0``.
        nlgeom: Follow the current line and length (geometrically nonlinear, ccx with
            ``NLGEOM``); False keeps the initial line (ccx without ``NLGEOM``).
    """

    law: SpringLaw
    nlgeom: bool = True

    def evaluate(
        self, reference: np.ndarray, displacement: np.ndarray, *, tangent: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Forces ``[-F n, F n]`` (S, 6) and their derivative (S, 6, 6)."""
        initial = reference[:, 1] - reference[:, 0]
        length0 = np.linalg.norm(initial, axis=1)
        bad = np.flatnonzero(length0 <= 0.0)
        if bad.size:
            raise ValueError(
                f"AxialSpring: spring {bad[0]} has coincident end nodes (zero length): its line "
                "of action is undefined; use a DirectionalSpring"
            )
        if self.nlgeom:
            current = initial + displacement[:, 1] - displacement[:, 0]
            length = np.linalg.norm(current, axis=1)
            bad = np.flatnonzero(length <= 0.0)
            if bad.size:
                raise ValueError(f"AxialSpring: spring {bad[0]} has been compressed to a point")
            n = current / length[:, None]
            elongation = length - length0
        else:
            n = initial / length0[:, None]
            elongation = np.einsum("si,si->s", displacement[:, 1] - displacement[:, 0], n)
        force, slope = self.law(elongation)
        f2 = force[:, None] * n
        forces = np.concatenate([-f2, f2], axis=1)
        if not tangent:
            return forces, None
        nn = n[:, :, None] * n[:, None, :]
        block = slope[:, None, None] * nn
        if self.nlgeom:  # the rotation of the line: F/L (I - n n)
            block = block + (force / length)[:, None, None] * (np.eye(3) - nn)
        return forces, _two_node_matrix(block, block, block, block)


@dataclass(frozen=True)
class DirectionalSpring:
    """A spring acting in fixed directions (ccx SPRING1, SPRING2).

    ``e = u1 . n1 - u2 . n2``; node 1 gets ``F(e) n1``, node 2 ``-F(e) n2``.

    Args:
        law: The force as a function of ``e``.
        first_direction: ``n1``, a unit vector (e.g. ``(1, 0, 0)`` for dof 1).
        second_direction: ``n2``; default ``n1``.
    """

    law: SpringLaw
    first_direction: tuple[float, float, float]
    second_direction: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        for name in ("first_direction", "second_direction"):
            value = getattr(self, name)
            if value is None:
                continue
            n = np.asarray(value, dtype=float)
            if n.shape != (3,) or not np.isclose(np.linalg.norm(n), 1.0):
                raise ValueError(f"DirectionalSpring: {name} must be a unit 3-vector, got {value}")

    def evaluate(
        self, reference: np.ndarray, displacement: np.ndarray, *, tangent: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Forces ``[F n1, -F n2]`` (S, 6) and their derivative (S, 6, 6)."""
        n1 = np.asarray(self.first_direction, dtype=float)
        n2 = n1 if self.second_direction is None else np.asarray(self.second_direction, float)
        elongation = displacement[:, 0] @ n1 - displacement[:, 1] @ n2
        force, slope = self.law(elongation)
        forces = np.concatenate([force[:, None] * n1, -force[:, None] * n2], axis=1)
        if not tangent:
            return forces, None
        s = slope[:, None, None]
        return forces, _two_node_matrix(
            s * np.outer(n1, n1), s * np.outer(n1, n2), s * np.outer(n2, n1), s * np.outer(n2, n2)
        )


def _two_node_matrix(
    k11: np.ndarray, k12: np.ndarray, k21: np.ndarray, k22: np.ndarray
) -> np.ndarray:
    """The (S, 6, 6) matrix ``[[k11, -k12], [-k21, k22]]`` of (S, 3, 3) blocks, with signs given.

    The off-diagonal blocks enter negated (an axial spring's ``[[K, -K], [-K, K]]``).
    """
    matrix = np.empty((k11.shape[0], 6, 6))
    matrix[:, :3, :3], matrix[:, :3, 3:] = k11, -k12
    matrix[:, 3:, :3], matrix[:, 3:, 3:] = -k21, k22
    return matrix
