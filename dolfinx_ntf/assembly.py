"""Insertion of spring elements into dolfinx's PETSc Jacobian and residual (dolfinx glue).

Contact couples nodes that share no cell, so the bulk form's sparsity pattern lacks those entries. Letting PETSc
allocate them on the fly costs minutes on large meshes; instead :class:`ContactAssembler` creates matrices whose
pattern is the bulk pattern plus the needed contact couplings, and when new couplings appear inside one Newton solve
(the matrix is then bound to the solver) merges a small contact matrix into the Jacobian, which grows its pattern.

Values are inserted with *global* unblocked indices (``3 * global_node + component``); rows and columns of Dirichlet
dofs get index -1, which PETSc ignores, so Dirichlet rows stay exactly as dolfinx makes them.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass

import numpy as np
import scipy.sparse
from petsc4py import PETSc

import dolfinx.fem
import dolfinx.fem.petsc

__all__ = ["SpringBlocks", "ContactAssembler"]


@dataclass(frozen=True)
class SpringBlocks:
    """Dense element blocks to add: ``values[e]`` couples ``row_nodes[e]`` with ``col_nodes[e]``.

    Nodes are local block dofs; ``values`` has shape (E, 3 a, 3 b) for ``row_nodes`` (E, a) and ``col_nodes``
    (E, b). ``vector`` (E, 3 a) is the residual contribution of the rows (only for square element blocks).
    """

    row_nodes: np.ndarray
    col_nodes: np.ndarray
    values: np.ndarray | None = None
    vector: np.ndarray | None = None


def _unblocked(nodes: np.ndarray, bs: int = 3) -> np.ndarray:
    """(E, a) node indices -> (E, bs a) dof indices, node-major."""
    return (bs * nodes[:, :, None] + np.arange(bs)).reshape(nodes.shape[0], bs * nodes.shape[1])


class ContactAssembler:
    """Adds spring blocks to dolfinx's residual vectors and Jacobian matrices of one displacement space."""

    def __init__(self, V: dolfinx.fem.FunctionSpace, jacobian_form: dolfinx.fem.FormMetaClass,
                 bcs: typing.Sequence[dolfinx.fem.DirichletBCMetaClass] = ()) -> None:
        """Prepare global numbering and the Dirichlet mask.

        Args:
            V: The vector displacement space (block size 3).
            jacobian_form: The compiled bulk Jacobian form; its sparsity pattern is the base of every matrix.
            bcs: Dirichlet conditions on ``V``; their dofs receive no contact entries.
        """
        self._bs = V.dofmap.index_map_bs
        if self._bs != 3:
            raise ValueError(f"contact needs a 3D vector displacement space, got block size {self._bs}")
        self._form = jacobian_form
        index_map = V.dofmap.index_map
        self._comm = V.mesh.comm
        num_nodes = index_map.size_local + index_map.num_ghosts
        self._num_owned = index_map.size_local
        self._num_global = index_map.size_global
        self._global_node = index_map.local_to_global(np.arange(num_nodes, dtype=np.int32)).astype(np.int64)
        self._global_dof = _unblocked(self._global_node[:, None], self._bs).ravel()
        self._global_dof_masked = self._global_dof.copy()
        for bc in bcs:
            dofs, _ = bc.dof_indices()
            self._global_dof_masked[dofs] = -1
        self._pattern_keys = np.empty(0, dtype=np.int64)
        self._lgmap = PETSc.LGMap().create(self._global_node.astype(PETSc.IntType), bsize=self._bs,
                                           comm=self._comm)
        self.matrix_rebuilds = 0
        self.pattern_merges = 0

    # -- sparsity ------------------------------------------------------------------------------------------

    def _coupling_keys(self, blocks: typing.Sequence[SpringBlocks]) -> np.ndarray:
        """Sorted unique global node couplings (row * N + col) of the blocks."""
        keys = [np.empty(0, dtype=np.int64)]
        for blk in blocks:
            rows = self._global_node[blk.row_nodes]
            cols = self._global_node[blk.col_nodes]
            keys.append((rows[:, :, None] * self._num_global + cols[:, None, :]).ravel())
        return np.unique(np.concatenate(keys))

    def has_pattern(self, blocks: typing.Sequence[SpringBlocks]) -> bool:
        """Whether the current matrix pattern holds every coupling of ``blocks``."""
        keys = self._coupling_keys(blocks)
        return bool(np.all(np.isin(keys, self._pattern_keys, assume_unique=True)))

    def create_matrix(self, blocks: typing.Sequence[SpringBlocks] = ()) -> PETSc.Mat:
        """A new matrix with the bulk pattern plus the couplings of ``blocks`` (and of earlier matrices)."""
        sp = dolfinx.fem.create_sparsity_pattern(self._form)
        sp.assemble()
        graph = sp.graph
        rows = np.repeat(np.arange(graph.num_nodes, dtype=np.int64), np.diff(graph.offsets))
        bulk = self._global_node[rows] * self._num_global + self._global_node[graph.array]
        keys = np.union1d(self._coupling_keys(blocks), self._pattern_keys)
        owned_first, owned_last = self._global_node[0], self._global_node[0] + self._num_owned
        keys = keys[(keys // self._num_global >= owned_first) & (keys // self._num_global < owned_last)]
        self._pattern_keys = np.union1d(keys, bulk)
        csr = self._unblocked_pattern(self._pattern_keys, owned_first)
        n_local, n_global = self._bs * self._num_owned, self._bs * self._num_global
        A = PETSc.Mat().createAIJ(((n_local, n_global), (n_local, n_global)), bsize=self._bs,
                                  csr=(csr.indptr.astype(PETSc.IntType), csr.indices.astype(PETSc.IntType)),
                                  comm=self._comm)
        A.setLGMap(self._lgmap, self._lgmap)
        A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        A.assemble()
        self.matrix_rebuilds += 1
        return A

    def _unblocked_pattern(self, keys: np.ndarray, first_row: int) -> scipy.sparse.csr_matrix:
        """Unblocked CSR (owned rows, global columns) of node couplings ``keys``."""
        bs = self._bs
        rows, cols = keys // self._num_global - first_row, keys % self._num_global
        block = scipy.sparse.csr_matrix((np.ones(keys.size, dtype=np.int8), (rows, cols)),
                                        shape=(self._num_owned, self._num_global))
        pattern = scipy.sparse.kron(block, np.ones((bs, bs), dtype=np.int8), format="csr")
        pattern.sort_indices()
        return pattern

    # -- values --------------------------------------------------------------------------------------------

    def _triplets(self, blocks: typing.Sequence[SpringBlocks]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rows, cols, vals = [], [], []
        for blk in blocks:
            if blk.values is None or blk.row_nodes.shape[0] == 0:
                continue
            r = self._global_dof_masked[_unblocked(blk.row_nodes, self._bs)]
            c = self._global_dof_masked[_unblocked(blk.col_nodes, self._bs)]
            rr = np.broadcast_to(r[:, :, None], blk.values.shape)
            cc = np.broadcast_to(c[:, None, :], blk.values.shape)
            keep = (rr >= 0) & (cc >= 0)
            rows.append(rr[keep])
            cols.append(cc[keep])
            vals.append(blk.values[keep])
        if not rows:
            return (np.empty(0, dtype=np.int64),) * 2 + (np.empty(0),)
        return np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)

    def add_to_matrix(self, A: PETSc.Mat, blocks: typing.Sequence[SpringBlocks]) -> None:
        """Add the blocks to an assembled-or-flushed ``A``; grows its pattern if couplings are missing.

        ``A`` is left unassembled when values were set directly; call ``A.assemble()`` afterwards.
        """
        rows, cols, vals = self._triplets(blocks)
        n = self._bs * self._num_global
        coo = scipy.sparse.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
        coo.sum_duplicates()
        row_ids = np.flatnonzero(np.diff(coo.indptr))
        indptr = np.concatenate([[0], coo.indptr[row_ids + 1]]).astype(PETSc.IntType)
        if not self.has_pattern(blocks):
            self._merge(A, row_ids, indptr, coo, blocks)
            return
        A.setValuesIJV(indptr, coo.indices.astype(PETSc.IntType), coo.data, addv=PETSc.InsertMode.ADD_VALUES,
                       rowmap=row_ids.astype(PETSc.IntType))

    def _merge(self, A: PETSc.Mat, row_ids: np.ndarray, indptr: np.ndarray, coo: scipy.sparse.csr_matrix,
               blocks: typing.Sequence[SpringBlocks]) -> None:
        """Add the values through a separate matrix merged with DIFFERENT_NONZERO_PATTERN (pattern grows)."""
        A.assemble()
        owned = (row_ids >= self._global_dof[0]) & (row_ids < self._global_dof[0] + self._bs * self._num_owned)
        if not np.all(owned):
            raise NotImplementedError("merging contact couplings of rows owned by another process")
        n_local, n_global = A.getSizes()[0]
        local = scipy.sparse.csr_matrix((coo.data, coo.indices, coo.indptr), shape=coo.shape)[
            self._global_dof[0]:self._global_dof[0] + n_local]
        C = PETSc.Mat().createAIJ(((n_local, n_global), (n_local, n_global)),
                                  csr=(local.indptr.astype(PETSc.IntType), local.indices.astype(PETSc.IntType),
                                       local.data), comm=self._comm)
        C.assemble()
        A.axpy(1.0, C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        C.destroy()
        self._pattern_keys = np.union1d(self._pattern_keys, self._coupling_keys(blocks))
        self.pattern_merges += 1

    def add_to_vector(self, b: PETSc.Vec, blocks: typing.Sequence[SpringBlocks]) -> None:
        """Add the blocks' residual contributions to ``b`` (global indices; Dirichlet rows skipped).

        Call before dolfinx's ``set_bc``; ends with a vector assembly so off-process rows reach their owners.
        """
        for blk in blocks:
            if blk.vector is None or blk.row_nodes.shape[0] == 0:
                continue
            rows = self._global_dof_masked[_unblocked(blk.row_nodes, self._bs)].ravel()
            keep = rows >= 0
            b.setValues(rows[keep].astype(PETSc.IntType), blk.vector.ravel()[keep],
                        addv=PETSc.InsertMode.ADD_VALUES)
        b.assemblyBegin()
        b.assemblyEnd()
