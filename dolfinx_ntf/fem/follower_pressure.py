"""Pressures on faces that follow the deformation, as an element term: :class:`FollowerPressure`.

docs/method.md §34.4. Where ``ds`` is not available (dolfinx 0.11 prism meshes have two facet
types), a pressure on faces given by their nodes is integrated by ``kernels.faces``: nodal forces
``f_j = -p Σ_q w_q φ_j (q_ξ x q_η)`` on the current faces (reference coordinates plus
displacements) and their derivative by the node coordinates. The faces are kept in the global
numbering like :class:`~dolfinx_ntf.fem.discrete_springs.DiscreteSprings`: each evaluation sums
the face nodes' displacements over the processes (each node from its owner) and rank 0
evaluates and inserts every face (PETSc sends rows to their owners). All methods are collective.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.fem.discrete_springs import GlobalBlocks
from dolfinx_ntf.kernels.faces import FaceType, pressure_forces, pressure_stiffness

__all__ = ["FollowerPressure", "PressureFaces"]


@dataclass(frozen=True)
class PressureFaces:
    """Faces of one type under pressure.

    Attributes:
        face_type: The face type (``TRI6``, ``QUAD8``, ...).
        nodes: ``(F, n)`` global block indices of the faces' nodes in CalculiX order (the same on
            every process).
        reference: ``(F, n, 3)`` reference coordinates of those nodes.
        group: ``(F,)`` index of each face's pressure in ``FollowerPressure``'s ``pressures``.
        rule: Points ``(q, 2)`` and weights ``(q,)`` of the face rule; None: the type's own.
    """

    face_type: FaceType
    nodes: np.ndarray
    reference: np.ndarray
    group: np.ndarray
    rule: tuple[np.ndarray, np.ndarray] | None = None


class FollowerPressure:
    """Pressures on the current faces: residual ``-f`` and Jacobian ``-df/du`` (element term).

    Args:
        V: The displacement space (3D vector Lagrange).
        faces: The faces, by type.
        pressures: The pressure of each group (``.value`` read at each evaluation, e.g. the
            ``dolfinx.fem.Constant`` a load schedule sets).
    """

    def __init__(
        self,
        V: dolfinx.fem.FunctionSpace,
        faces: typing.Sequence[PressureFaces],
        pressures: typing.Sequence[typing.Any],
    ) -> None:
        if V.dofmap.index_map_bs != 3 or V.mesh.geometry.dim != 3:
            raise ValueError("FollowerPressure: a 3D vector displacement space is needed")
        self._comm = V.mesh.comm
        self.faces = list(faces)
        self.pressures = list(pressures)
        index_map = V.dofmap.index_map
        self._first = int(index_map.local_range[0])
        self._size = int(index_map.size_local)
        for block in self.faces:
            if block.group.size and int(block.group.max()) >= len(self.pressures):
                raise ValueError("FollowerPressure: a face's group has no pressure")

    def node_couplings(self) -> np.ndarray:
        """(K, 2) global node pairs of every face (rank 0 adds them all)."""
        if self._comm.rank != 0:
            return np.zeros((0, 2), dtype=np.int64)
        pairs = [
            np.stack(
                [np.repeat(b.nodes, b.nodes.shape[1], axis=1), np.tile(b.nodes, b.nodes.shape[1])],
                axis=2,
            ).reshape(-1, 2)
            for b in self.faces
        ]
        return np.concatenate(pairs) if pairs else np.zeros((0, 2), dtype=np.int64)

    def _displacements(self, x: PETSc.Vec, nodes: np.ndarray) -> np.ndarray:
        """(F, n, 3) displacements of global ``nodes`` in ``x``, on every process."""
        local = nodes - self._first
        owned = (local >= 0) & (local < self._size)
        values = np.zeros((*nodes.shape, 3))
        values[owned] = x.array_r.reshape(-1, 3)[local[owned]]
        result = np.empty_like(values)
        self._comm.Allreduce(values, result, op=MPI.SUM)
        return result

    def _fixed(self, bcs: typing.Sequence[compat.DirichletBC], dofs: np.ndarray) -> np.ndarray:
        """Global unrolled ``dofs`` that a Dirichlet condition holds (every process's)."""
        held = [3 * self._first + np.asarray(bc.dof_indices()[0], dtype=np.int64) for bc in bcs]
        local = np.concatenate(held) if held else np.zeros(0, np.int64)
        local = local[(local >= 3 * self._first) & (local < 3 * (self._first + self._size))]
        fixed = np.isin(dofs, local).astype(np.int8)
        result = np.empty_like(fixed)
        self._comm.Allreduce(fixed, result, op=MPI.MAX)
        return result.astype(bool)

    def evaluate(
        self, x: PETSc.Vec, bcs: typing.Sequence[compat.DirichletBC], *, tangent: bool = True
    ) -> GlobalBlocks:
        """Rank 0's blocks of every face at ``x`` (the others' are empty), in global dofs.

        Args:
            x: The displacement vector (owned values are read).
            bcs: Dirichlet conditions: their dofs get index -1 (rows and columns skipped).
            tangent: Compute the stiffness blocks too.
        """
        width = 3 * max((b.face_type.num_nodes for b in self.faces), default=0)
        dofs, vectors, matrices = [], [], []
        values = np.array([float(np.asarray(p.value)) for p in self.pressures])
        for block in self.faces:
            u = self._displacements(x, block.nodes)
            block_dofs = (3 * block.nodes[:, :, None] + np.arange(3)).reshape(len(block.nodes), -1)
            fixed = self._fixed(bcs, block_dofs)
            if self._comm.rank != 0:
                continue
            coords = block.reference + u
            p = values[block.group]
            m = block_dofs.shape[1]
            pad = width - m  # faces of several types: blocks padded with skipped dofs
            vector = -pressure_forces(block.face_type, coords, p, block.rule).reshape(-1, m)
            dofs.append(np.pad(np.where(fixed, -1, block_dofs), ((0, 0), (0, pad)), "constant",
                               constant_values=-1))  # fmt: skip
            vectors.append(np.pad(vector, ((0, 0), (0, pad))))
            if tangent:
                matrix = -pressure_stiffness(block.face_type, coords, p, block.rule)
                matrices.append(np.pad(matrix, ((0, 0), (0, pad), (0, pad))))
        if not dofs:
            return GlobalBlocks(
                np.zeros((0, width), np.int64), np.zeros((0, width, width)) if tangent else None,
                np.zeros((0, width)),
            )  # fmt: skip
        return GlobalBlocks(
            np.concatenate(dofs),
            np.concatenate(matrices) if tangent else None,
            np.concatenate(vectors),
        )

    def force_sum(self) -> tuple[float, int]:
        """Nothing: external loads do not enter ccx's average element force (§7.1)."""
        return 0.0, 0
