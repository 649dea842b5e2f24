"""Friction history of the slave nodes of one contact pair (docs/method.md §11.3).

Pure numpy, no dolfinx: the state belongs to the pairing, not to the problem. Per slave node it
holds the relative displacement ``a``, the accumulated tangential relative displacement ``t`` and
the slip ``t_p`` (global Cartesian 3-vectors, CalculiX's nine state variables; on a 2D mesh their
third components stay 0) three times over:

- committed: the values at the end of the last converged increment;
- start: the values the current increment starts from (``a_n``, ``t_n``, ``t_p,n``);
- current: the values of the last evaluation.

The state is indexed by the slave node (not by the spring), so a node that changes master face
keeps it, as in CalculiX. :meth:`begin_increment` restores ``start`` and ``current`` from the
committed values, which also undoes a failed attempt before a cutback; :meth:`commit` accepts a
converged increment.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FrictionState"]


class FrictionState:
    """Friction history of ``num_nodes`` slave nodes.

    Args:
        num_nodes: Number of slave nodes of the pair.
        reset_on_separation: A node that was not in contact at the last converged increment
            starts afresh when it gets a spring (its relative displacement at that moment is the
            reference, no accumulated slip). False keeps the stale state as CalculiX does: a node
            keeps its values after contact is lost, and a node that was never in contact starts
            from zero, so its whole relative displacement before contact counts as tangential
            motion.
    """

    def __init__(self, num_nodes: int, *, reset_on_separation: bool = True) -> None:
        self.reset_on_separation = bool(reset_on_separation)
        self.num_nodes = int(num_nodes)
        shape = (self.num_nodes, 3)
        self.committed = {k: np.zeros(shape) for k in ("a", "t", "slip")}
        self.start = {k: np.zeros(shape) for k in ("a", "t", "slip")}
        self.current = {k: np.zeros(shape) for k in ("a", "t", "slip")}
        #: Nodes with a spring at the end of the last converged increment.
        self.in_contact = np.zeros(self.num_nodes, dtype=bool)
        #: Nodes whose start values were anchored in the current increment.
        self._anchored = np.zeros(self.num_nodes, dtype=bool)

    def reset(self) -> None:
        """Forget the whole history (a pair that is reactivated starts fresh)."""
        for values in (self.committed, self.start, self.current):
            for array in values.values():
                array[:] = 0.0
        self.in_contact[:] = False
        self._anchored[:] = False

    def begin_increment(self) -> None:
        """Start an increment (or a new attempt of it) from the committed values."""
        for key, value in self.committed.items():
            self.start[key][:] = value
            self.current[key][:] = value
        self._anchored[:] = False

    def fresh(self, nodes: np.ndarray) -> np.ndarray:
        """Which of ``nodes`` (slave indices) need a fresh start now (reset mode only)."""
        nodes = np.asarray(nodes, dtype=np.int64)
        if not self.reset_on_separation:
            return np.zeros(nodes.size, dtype=bool)
        return ~self.in_contact[nodes] & ~self._anchored[nodes]

    def anchor(self, nodes: np.ndarray, a: np.ndarray) -> None:
        """Start ``nodes`` afresh at relative displacement ``a`` ``(k, 3)``: no slip, ``t = 0``."""
        nodes = np.asarray(nodes, dtype=np.int64)
        for values in (self.start, self.current):
            values["a"][nodes] = a
            values["t"][nodes] = 0.0
            values["slip"][nodes] = 0.0
        self._anchored[nodes] = True

    def start_values(self, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(a_n, t_n, t_p,n)`` of ``nodes``, each ``(k, 3)``."""
        return tuple(self.start[k][nodes] for k in ("a", "t", "slip"))

    def store(self, nodes: np.ndarray, a: np.ndarray, t: np.ndarray, slip: np.ndarray) -> None:
        """Record an evaluation of ``nodes``; other nodes keep their last values.

        ``a``, ``t`` and ``slip`` are ``(k, d)``: ``d = 3``, or 2 from the springs of a 2D mesh
        (the third components then stay 0).
        """
        dim = np.shape(a)[-1]
        self.current["a"][nodes, :dim] = a
        self.current["t"][nodes, :dim] = t
        self.current["slip"][nodes, :dim] = slip

    def commit(self, nodes_in_contact: np.ndarray) -> None:
        """Accept the converged increment; ``nodes_in_contact``: the nodes with a spring now."""
        for key, value in self.current.items():
            self.committed[key][:] = value
        self.in_contact[:] = False
        self.in_contact[np.asarray(nodes_in_contact, dtype=np.int64)] = True
