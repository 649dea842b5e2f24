"""Discrete springs between mesh nodes, or from a node to the ground: :class:`DiscreteSprings`.

The dolfinx glue of ``kernels/discrete_springs.py`` (docs/method.md §18). A spring joins two nodes
of the displacement space that may share no cell and, in parallel, may be owned by different
processes. So the springs are kept in the *global* numbering: the end nodes are located once by
their coordinates; at each evaluation the end displacements of all springs are summed over the
processes (one ``Allreduce`` of ``6 S`` numbers), and each spring is evaluated and inserted by the
owner of its first node, with global dof indices (PETSc sends rows owned elsewhere to their
owners). Rows and columns of Dirichlet dofs get index -1 (skipped), as for the contact springs.

A :class:`DiscreteSprings` is an element term of a :class:`~dolfinx_ntf.ContactProblem`
(``problem.element_terms.append(springs)``): the problem reserves its couplings in the matrix
pattern and adds its blocks to the residual and the Jacobian. All methods are collective.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import scipy.spatial

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.kernels.discrete_springs import SpringElement

__all__ = ["DiscreteSprings", "GlobalBlocks"]


@dataclass(frozen=True)
class GlobalBlocks:
    """Element blocks in global unblocked dof indices: ``values[e]`` couples ``dofs[e]``.

    ``dofs`` (E, m) with -1 for dofs to skip (Dirichlet, ground), ``values`` (E, m, m) or None,
    ``vector`` (E, m) the residual contribution.
    """

    dofs: np.ndarray
    values: np.ndarray | None
    vector: np.ndarray


class DiscreteSprings:
    """Springs of one kind between pairs of mesh nodes, or from a mesh node to the ground.

    Args:
        V: The displacement space (3D vector Lagrange).
        element: The spring (``AxialSpring`` for ccx SPRINGA, ``DirectionalSpring`` for SPRING1
            and SPRING2) with its force law.
        first: (S, 3) coordinates of the first node of each spring; each must be a node of ``V``
            (within ``tolerance``).
        second: (S, 3) coordinates of the second nodes; None grounds every spring's second end at
            its first node (SPRING1).
        ground: The ``second`` points are fixed anchor points instead of mesh nodes (an axial
            spring to the ground).
        tolerance: Largest distance between a point and its node; default 1e-8 of the mesh size.
        nodes: (S, 2) global block indices of the end nodes (-1: grounded) when the caller knows
            them (coincident nodes cannot be told apart by coordinates); the points then only
            give the geometry.

    The same points on every process (the union is not taken): springs are few.
    """

    def __init__(
        self,
        V: dolfinx.fem.FunctionSpace,
        element: SpringElement,
        first: np.typing.ArrayLike,
        second: np.typing.ArrayLike | None = None,
        *,
        ground: bool = False,
        tolerance: float | None = None,
        nodes: np.ndarray | None = None,
    ) -> None:
        if V.dofmap.index_map_bs != 3 or V.mesh.geometry.dim != 3:
            raise ValueError("DiscreteSprings: a 3D vector displacement space is needed")
        if not callable(getattr(element, "evaluate", None)):
            raise TypeError(
                "DiscreteSprings: element must be an AxialSpring or a DirectionalSpring, got "
                f"{type(element).__name__}"
            )
        self.element = element
        self._comm = V.mesh.comm
        first = _points(first, "first")
        if second is None:
            second, ground = first.copy(), True
        second = _points(second, "second")
        if second.shape != first.shape:
            raise ValueError(
                f"DiscreteSprings: first and second need the same shape, got {first.shape} and "
                f"{second.shape}"
            )
        #: (S, 2, 3) reference coordinates of the ends (the anchor for a grounded end).
        self.reference = np.stack([first, second], axis=1)
        index_map = V.dofmap.index_map
        first_global = int(index_map.local_range[0])
        if nodes is not None:
            self.global_nodes = np.asarray(nodes, dtype=np.int64).reshape(-1, 2)
            if self.global_nodes.shape[0] != first.shape[0]:
                raise ValueError("DiscreteSprings: nodes needs one row per spring")
            local = self.global_nodes - first_global
            self._local = np.where((local >= 0) & (local < index_map.size_local), local, -1)
        else:
            self.global_nodes, self._local = self._locate(V, ground, tolerance)
        #: Springs this process evaluates and inserts (those whose first node it owns).
        self.mine = self._local[:, 0] >= 0
        self._forces = np.zeros((0, 6))

    def _locate(
        self, V: dolfinx.fem.FunctionSpace, ground: bool, tolerance: float | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(S, 2) global nodes at the end points and (S, 2) owned local nodes (-1 elsewhere)."""
        index_map = V.dofmap.index_map
        first_global = int(index_map.local_range[0])
        owned = index_map.size_local
        coordinates = V.tabulate_dof_coordinates()[:owned]
        if tolerance is None:
            extent = self._comm.allreduce(
                float(np.ptp(coordinates, axis=0).max()) if owned else 0.0, op=MPI.MAX
            )
            tolerance = 1e-8 * max(extent, 1.0)
        points = self.reference.reshape(-1, 3)
        if owned:
            distance, nearest = scipy.spatial.cKDTree(coordinates).query(points)
        else:
            distance, nearest = np.full(points.shape[0], np.inf), np.zeros(points.shape[0], int)
        here = distance <= tolerance
        if ground:
            here.reshape(-1, 2)[:, 1] = False
        found = _allreduce(self._comm, here.astype(np.int64), MPI.SUM)
        needed = np.ones(points.shape[0], bool)
        if ground:
            needed.reshape(-1, 2)[:, 1] = False
        missing = np.flatnonzero(needed & (found != 1))
        if missing.size:
            spring, end = divmod(int(missing[0]), 2)
            raise ValueError(
                f"DiscreteSprings: end {end + 1} of spring {spring}, "
                f"{points[missing[0]].tolist()}, is not a node of the displacement space "
                f"(within {tolerance:.3g}; {missing.size} such ends)"
            )
        global_node = np.where(here, first_global + nearest, -1).astype(np.int64)
        global_nodes = _allreduce(self._comm, global_node, MPI.MAX).reshape(-1, 2)
        return global_nodes, np.where(here, nearest, -1).reshape(-1, 2)

    @property
    def num_springs(self) -> int:
        """Number of springs (on every process)."""
        return int(self.reference.shape[0])

    def node_couplings(self) -> np.ndarray:
        """(K, 2) global node pairs whose matrix entries this process adds."""
        nodes = self.global_nodes[self.mine]
        rows = np.repeat(nodes, 2, axis=1).ravel()
        cols = np.tile(nodes, (1, 2)).ravel()
        keep = (rows >= 0) & (cols >= 0)
        return np.stack([rows[keep], cols[keep]], axis=1)

    def displacements(self, x: PETSc.Vec) -> np.ndarray:
        """(S, 2, 3) displacements of the spring ends in ``x`` (zero at grounded ends)."""
        values = x.array_r.reshape(-1, 3)
        ends = np.zeros((self.num_springs, 2, 3))
        here = self._local >= 0
        ends[here] = values[self._local[here]]
        return _allreduce(self._comm, ends, MPI.SUM)

    def evaluate(
        self, x: PETSc.Vec, bcs: typing.Sequence[compat.DirichletBC], *, tangent: bool = True
    ) -> GlobalBlocks:
        """The forces (and tangent) of this process's springs at ``x``, in global dofs.

        Args:
            x: The displacement vector (owned values are read).
            bcs: Dirichlet conditions: their dofs get index -1 (rows and columns skipped).
            tangent: Compute the stiffness blocks too.
        """
        displacement = self.displacements(x)
        forces, matrix = self.element.evaluate(
            self.reference[self.mine], displacement[self.mine], tangent=tangent
        )
        self._forces = forces
        return GlobalBlocks(self._dofs(bcs)[self.mine], matrix, forces)

    def end_forces(self, x: PETSc.Vec, element: SpringElement | None = None) -> np.ndarray:
        """(S, 2, 3) internal forces at both ends of every spring at ``x``, on every process.

        For reactions and printed nodal forces; a grounded end's entry is the ground's share.
        ``element``: evaluate with this element instead of the springs' own (CalculiX prints
        SPRINGA forces of the current line also without NLGEOM, docs/method.md §18.3).
        """
        element = self.element if element is None else element
        forces, _ = element.evaluate(self.reference, self.displacements(x), tangent=False)
        return forces.reshape(-1, 2, 3)

    def _dofs(self, bcs: typing.Sequence[compat.DirichletBC]) -> np.ndarray:
        """(S, 6) global dofs of the spring ends, -1 at grounded ends and Dirichlet dofs."""
        here = self._local >= 0
        local_dofs = 3 * self._local[:, :, None] + np.arange(3)
        fixed = np.zeros(local_dofs.shape, bool)
        for bc in bcs:
            constrained, _ = bc.dof_indices()
            fixed |= here[:, :, None] & np.isin(local_dofs, constrained)
        fixed = _allreduce(self._comm, fixed.astype(np.int8), MPI.MAX).astype(bool)
        dofs = 3 * self.global_nodes[:, :, None] + np.arange(3)
        dofs[(self.global_nodes < 0)[:, :, None] | fixed] = -1
        return dofs.reshape(-1, 6)

    def force_sum(self) -> tuple[float, int]:
        """Sum of the absolute nodal forces of this process's springs at the last evaluation."""
        return float(np.abs(self._forces).sum()), int(self._forces.size)


def _points(points: np.typing.ArrayLike, name: str) -> np.ndarray:
    """``points`` as an (S, 3) float array."""
    array = np.asarray(points, dtype=float)
    if array.ndim == 1 and array.size == 3:
        array = array[None, :]
    if array.ndim != 2 or array.shape[1] != 3 or not np.all(np.isfinite(array)):
        raise ValueError(
            f"DiscreteSprings: {name} must be finite (S, 3) coordinates, got shape {array.shape}"
        )
    return array


def _allreduce(comm: MPI.Comm, array: np.ndarray, op: MPI.Op) -> np.ndarray:
    """Element-wise reduction of ``array`` over the processes (a new array)."""
    result = np.empty_like(np.ascontiguousarray(array))
    comm.Allreduce(np.ascontiguousarray(array), result, op=op)
    return result
