"""Cyclic symmetry of a sector, static case (nodal diameter 0): docs/method.md §19.2.

A structure of ``N`` identical sectors under a cyclic symmetric load deforms cyclic symmetrically:
the two faces bounding one sector have the same displacements in cylindrical coordinates. Each
node of the dependent (slave) face is matched with the node of the independent (master) face at
the same radius and axial position (ccx measures the distance in radial planes, ignoring the
circumferential offset), and ``u_s = R^T u_m`` with ``R`` the rotation about the axis that carries
the slave node onto its master node: three linear constraints per slave node.

Pure numpy/scipy.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["ANGLE_CHECK", "CyclicMatch", "cyclic_rows", "rotation_matrix"]

ANGLE_CHECK = 0.01
"""ccx's CHECK: the sector angle of the geometry may differ from 2π/N by this much (radians)."""


def rotation_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    """The ``(3, 3)`` rotation by ``angle`` (right hand) about the direction ``axis``."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * cross + (1.0 - np.cos(angle)) * (cross @ cross)


class CyclicMatch:
    """Slave nodes matched with master nodes of a sector's two cyclic faces.

    Args:
        slave_x: ``(S, 3)`` slave node coordinates.
        master_x: ``(M, 3)`` master node coordinates.
        point_a, point_b: Two points of the symmetry axis (it points from a to b).
        num_sectors: ``N``, sectors of the full structure (ccx's parameter N).
        tolerance: Largest distance, in a radial plane, of a slave node to its master node.

    Attributes:
        master: ``(S,)`` row of ``master_x`` matched with each slave, -1 for none.
        distance: ``(S,)`` its distance in the radial plane.
        angle: Signed angle (about the axis) that carries the slave face onto the master face.
        on_axis: ``(S,)`` slave nodes on the axis (radius within the tolerance).
    """

    def __init__(
        self,
        slave_x: np.ndarray,
        master_x: np.ndarray,
        point_a: np.ndarray,
        point_b: np.ndarray,
        num_sectors: float,
        tolerance: float,
    ) -> None:
        a = np.asarray(point_a, dtype=float)
        axis = np.asarray(point_b, dtype=float) - a
        if not np.linalg.norm(axis) > 0.0:
            raise ValueError("cyclic symmetry: the two points of the axis coincide")
        if not num_sectors > 0:
            raise ValueError(f"cyclic symmetry: N must be > 0, got {num_sectors}")
        self.axis = axis / np.linalg.norm(axis)
        self.origin = a
        slave_h, slave_r, slave_phi = self._cylindrical(slave_x)
        master_h, master_r, master_phi = self._cylindrical(master_x)
        self.on_axis = slave_r <= tolerance
        tree = cKDTree(np.column_stack([master_r, master_h]))
        distance, master = tree.query(np.column_stack([slave_r, slave_h]), k=1)
        master = np.where(distance <= tolerance, master, -1)
        self.master = master.astype(np.int64)
        self.distance = distance
        sector = 2.0 * np.pi / num_sectors
        found = (master >= 0) & ~self.on_axis
        if np.any(found):
            turn = np.angle(np.exp(1j * (master_phi[master[found]] - slave_phi[found])))
            self.angle = float(np.mean(turn))
        else:
            self.angle = sector
        self.sector = sector
        self.angle_error = abs(abs(self.angle) - sector)

    def _cylindrical(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Axial position, radius and angle (about the axis) of points ``(P, 3)``."""
        d = np.asarray(x, dtype=float).reshape(-1, 3) - self.origin
        h = d @ self.axis
        radial = d - h[:, None] * self.axis
        r = np.linalg.norm(radial, axis=1)
        e1 = np.cross(self.axis, [1.0, 0.0, 0.0])
        if np.linalg.norm(e1) < 0.5:
            e1 = np.cross(self.axis, [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(self.axis, e1)
        return h, r, np.arctan2(radial @ e2, radial @ e1)

    @property
    def rotation(self) -> np.ndarray:
        """``R``: ``x_master = R x_slave`` (about the axis through ``point_a``)."""
        return rotation_matrix(self.axis, self.angle)


def cyclic_rows(
    slaves: np.ndarray, masters: np.ndarray, rotation: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The constraints ``u_s - R^T u_m = 0``, one per slave node and component.

    Args:
        slaves: ``(S,)`` slave node ids.
        masters: ``(S,)`` the matched master node ids.
        rotation: ``R`` with ``x_master = R x_slave``.

    Returns:
        ``(nodes, components, coefficients)``, each ``(3 S, 4)``: row ``3 k + c`` states
        ``u[s_k, c] - Σ_d R[d, c] u[m_k, d] = 0``, the slave term first (the dependent dof).
    """
    slaves = np.asarray(slaves, dtype=np.int64)
    masters = np.asarray(masters, dtype=np.int64)
    s = slaves.size
    nodes = np.repeat(np.column_stack([slaves, masters, masters, masters]), 3, axis=0)
    c = np.tile(np.arange(3), s)
    components = np.column_stack([c, np.zeros_like(c), np.ones_like(c), np.full_like(c, 2)])
    R = np.asarray(rotation, dtype=float)
    coefficients = np.column_stack([np.ones(3 * s), -np.tile(R.T, (s, 1))])
    return nodes, components, coefficients
