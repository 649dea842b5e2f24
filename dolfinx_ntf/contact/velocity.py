"""The nodal velocity a dynamic step gives the contact springs: :class:`NodeVelocity`.

Contact damping (docs/method.md §29) needs the velocity of every spring node at every iterate.
A Newmark-type integrator makes it an affine function of the displacement within an increment,
``v = offset + rate u`` (``rate = gamma/(beta dt)``); the step driver updates ``offset`` and
``rate`` at every increment start, and :class:`~dolfinx_ntf.ContactProblem` evaluates it at the
spring nodes (its halo's included) from the current ``u``.
"""

from __future__ import annotations

from dataclasses import dataclass

import dolfinx.fem

__all__ = ["NodeVelocity"]


@dataclass
class NodeVelocity:
    """``v = offset + rate u`` at every node, for the current increment.

    Attributes:
        offset: A Function on the displacement space (ghost values up to date).
        rate: ``dv/du`` (0: the velocity is ``offset``, e.g. at the start of a step).
    """

    offset: dolfinx.fem.Function
    rate: float = 0.0
