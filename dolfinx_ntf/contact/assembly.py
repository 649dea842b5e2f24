"""Insertion of spring elements into dolfinx's PETSc Jacobian and residual (dolfinx glue).

Contact couples nodes that share no cell, so the bulk form's sparsity pattern lacks those entries.
Letting PETSc allocate them on the fly costs minutes on large meshes; instead
:class:`ContactAssembler` grows the pattern of dolfinx's bulk matrix by merging a small contact
matrix (``MatAXPY`` with ``DIFFERENT_NONZERO_PATTERN``, done in C): once when a matrix is created,
and again inside a Newton solve when a re-pairing brings new couplings (the same Mat object grows,
so the solver bound to it keeps working).

Values are inserted with *global* unblocked indices (``3 * global_node + component``); rows and
columns of Dirichlet dofs get index -1, which PETSc ignores, so Dirichlet rows stay exactly as
dolfinx makes them.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import scipy.sparse

import dolfinx.fem
import dolfinx.fem.petsc

from dolfinx_ntf import compat
from dolfinx_ntf.fem.discrete_springs import GlobalBlocks
from dolfinx_ntf.parallel import collectives
from dolfinx_ntf.parallel.halo import NodeHalo

__all__ = ["ContactAssembler", "SpringBlocks", "coupling_matrix"]


@dataclass(frozen=True)
class SpringBlocks:
    """Dense element blocks to add: ``values[e]`` couples ``row_nodes[e]`` with ``col_nodes[e]``.

    Nodes are local block dofs; ``values`` has shape (E, bs a, bs b) for ``row_nodes`` (E, a) and
    ``col_nodes`` (E, b), bs the space's block size (3 for the displacement, 1 for a temperature).
    ``vector`` (E, bs a) is the residual contribution of the rows (only for square element
    blocks).
    """

    row_nodes: np.ndarray
    col_nodes: np.ndarray
    values: np.ndarray | None = None
    vector: np.ndarray | None = None


def _unblocked(nodes: np.ndarray, bs: int = 3) -> np.ndarray:
    """(E, a) node indices -> (E, bs a) dof indices, node-major."""
    return (bs * nodes[:, :, None] + np.arange(bs)).reshape(nodes.shape[0], bs * nodes.shape[1])


def _add_rows(b: PETSc.Vec, rows: np.ndarray, values: np.ndarray) -> None:
    """Add ``values`` to the global ``rows`` of ``b`` (same shape), skipping ``-1`` rows."""
    rows = rows.ravel()
    keep = rows >= 0
    b.setValues(
        rows[keep].astype(PETSc.IntType), values.ravel()[keep], addv=PETSc.InsertMode.ADD_VALUES
    )


class ContactAssembler:
    """Adds spring blocks to dolfinx's residual vectors and Jacobian matrices of one space."""

    def __init__(
        self,
        V: dolfinx.fem.FunctionSpace,
        jacobian_form: compat.Form,
        bcs: typing.Sequence[compat.DirichletBC] = (),
    ) -> None:
        """Prepare global numbering and the Dirichlet mask.

        Args:
            V: The vector displacement space (block size 3), or a scalar space numbered like its
                nodes (the temperature of thermal contact, docs/method.md §20).
            jacobian_form: The compiled bulk Jacobian form; its sparsity pattern is the base of
                every matrix.
            bcs: Dirichlet conditions on ``V``; their dofs receive no contact entries.
        """
        self._bs = V.dofmap.index_map_bs
        if self._bs not in (1, V.mesh.topology.dim) or self._bs > 3:
            raise ValueError(
                "contact needs a vector displacement space with one component per dimension of "
                "the mesh (or a scalar space, e.g. the temperature), got block size "
                f"{self._bs} on a {V.mesh.topology.dim}D mesh"
            )
        self._form = jacobian_form
        index_map = V.dofmap.index_map
        self._comm = V.mesh.comm
        num_nodes = index_map.size_local + index_map.num_ghosts
        self._num_owned = index_map.size_local
        self._num_global = index_map.size_global
        self._global_node = index_map.local_to_global(np.arange(num_nodes, dtype=np.int32)).astype(
            np.int64
        )
        self._global_dof = _unblocked(self._global_node[:, None], self._bs).ravel()
        self._first_nodes = np.asarray(self._comm.allgather(int(index_map.local_range[0])))
        self._halo: NodeHalo | None = None
        self._u: dolfinx.fem.Function | None = None
        self.set_bcs(bcs)
        self._pattern_keys = np.empty(0, dtype=np.int64)
        self.matrix_rebuilds = 0
        self.pattern_merges = 0

    def set_bcs(self, bcs: typing.Sequence[compat.DirichletBC]) -> None:
        """Dirichlet conditions whose dofs receive no contact entries. Collective in parallel."""
        self._bcs = list(bcs)
        self._global_dof_masked = self._global_dof.copy()
        for bc in bcs:
            dofs, _ = bc.dof_indices()
            self._global_dof_masked[dofs] = -1
        if self._halo is not None:  # collective, even where the halo is empty
            fixed = self._halo.constrained(self._u, self._bcs).ravel()
            self._global_dof_masked[self._global_dof.size - fixed.size :][fixed] = -1

    def extend(self, halo: NodeHalo, u: dolfinx.fem.Function) -> None:
        """Number the halo's nodes too: contact nodes of other processes. Collective.

        See docs/method.md §14.
        """
        self._halo, self._u = halo, u
        self._global_node = halo.global_nodes.copy()
        self._global_dof = _unblocked(self._global_node[:, None], self._bs).ravel()
        self.set_bcs(self._bcs)

    # -- sparsity ----------------------------------------------------------------------------------

    def _coupling_keys(
        self, blocks: typing.Sequence[SpringBlocks], couplings: np.ndarray | None = None
    ) -> np.ndarray:
        """Sorted unique global node couplings (row * N + col) of the blocks and ``couplings``.

        ``couplings``: (K, 2) global node pairs (element terms, e.g. discrete springs).
        """
        keys = [np.empty(0, dtype=np.int64)]
        if couplings is not None and len(couplings):
            pairs = np.asarray(couplings, dtype=np.int64)
            keys.append(pairs[:, 0] * self._num_global + pairs[:, 1])
        for blk in blocks:
            rows = self._global_node[blk.row_nodes]
            cols = self._global_node[blk.col_nodes]
            keys.append((rows[:, :, None] * self._num_global + cols[:, None, :]).ravel())
        return np.unique(np.concatenate(keys))

    def has_pattern(
        self, blocks: typing.Sequence[SpringBlocks], couplings: np.ndarray | None = None
    ) -> bool:
        """Whether the current matrix pattern holds every coupling of ``blocks`` and ``couplings``.

        Only contact couplings are tracked; couplings the bulk form also has count as missing until
        merged, which costs one merge at most. ``couplings``: (K, 2) global node pairs.
        """
        keys = self._coupling_keys(blocks, couplings)
        has = bool(np.all(np.isin(keys, self._pattern_keys, assume_unique=True)))
        return bool(self._comm.allreduce(has, op=MPI.LAND))

    def create_matrix(
        self, blocks: typing.Sequence[SpringBlocks] = (), couplings: np.ndarray | None = None
    ) -> PETSc.Mat:
        """A new matrix with the bulk pattern plus the couplings of ``blocks`` and earlier ones.

        ``couplings``: more (K, 2) global node pairs to hold (element terms).
        """
        A = dolfinx.fem.petsc.create_matrix(self._form)  # sizes, block size, local-to-global map
        offsets, columns = compat.sparsity_graph(self._form)  # owned rows, global block columns
        keys = np.union1d(self._coupling_keys(blocks, couplings), self._pattern_keys)
        bulk = scipy.sparse.csr_matrix(
            (np.ones(columns.size, dtype=np.int8), columns, offsets),
            shape=(self._num_owned, self._num_global),
        )
        # The bulk and contact pattern in one preallocation, fixed by explicit zeros (the first
        # final assembly would squeeze out unused preallocation): one pass, where the bulk's zeros
        # and a merge of the contact pattern took twice as long (docs/method.md §14.3)
        indptr, indices = self._scalar_pattern(bulk + self._owned_couplings(keys))
        A.setPreallocationCSR((indptr, indices))
        self._pattern_keys = keys
        A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        if A.getBlockSize() != self._bs or A.getLGMap()[0].getBlockSize() != self._bs:
            raise RuntimeError("the matrix pattern lost the block structure")
        self.matrix_rebuilds += 1
        return A

    def _owned_couplings(self, keys: np.ndarray) -> scipy.sparse.csr_matrix:
        """Block pattern ``(owned nodes, global nodes)`` of the node couplings ``keys``.

        In parallel each coupling goes to the process owning its row. Collective.
        """
        first = int(self._first_nodes[self._comm.rank])
        if self._comm.size > 1:
            owner = np.searchsorted(self._first_nodes, keys // self._num_global, side="right") - 1
            keys = np.unique(collectives.send_to_owners(self._comm, keys, owner))
        rows = keys // self._num_global
        return scipy.sparse.csr_matrix(
            (np.ones(keys.size, dtype=np.int8), (rows - first, keys % self._num_global)),
            shape=(self._num_owned, self._num_global),
        )

    def _scalar_pattern(self, block: scipy.sparse.csr_matrix) -> tuple[np.ndarray, np.ndarray]:
        """CSR ``(indptr, indices)`` in PETSc's integers of the dofs of a block pattern, sorted."""
        bs = self._bs
        pattern = scipy.sparse.kron(block, np.ones((bs, bs), dtype=np.int8), format="csr")
        pattern.sort_indices()
        return pattern.indptr.astype(PETSc.IntType), pattern.indices.astype(PETSc.IntType)

    def _merge(
        self, A: PETSc.Mat, keys: np.ndarray, blocks: typing.Sequence[SpringBlocks] = ()
    ) -> None:
        """Grow ``A``'s pattern by node couplings ``keys`` and add the blocks' values.

        Through a separate matrix merged with DIFFERENT_NONZERO_PATTERN (same Mat object, so a
        solver bound to it keeps working).
        """
        bs = self._bs
        n_local, n_global = bs * self._num_owned, bs * self._num_global
        C = PETSc.Mat().createAIJ(
            ((n_local, n_global), (n_local, n_global)),
            bsize=bs,
            csr=self._scalar_pattern(self._owned_couplings(keys)),
            comm=self._comm,
        )
        self._set_values(C, blocks)
        C.assemble()
        A.assemble()
        A.axpy(1.0, C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        C.destroy()
        if A.getBlockSize() != bs or A.getLGMap()[0].getBlockSize() != bs:
            raise RuntimeError("merging the contact pattern lost the matrix block structure")
        self._pattern_keys = np.union1d(self._pattern_keys, keys)

    # -- values ------------------------------------------------------------------------------------

    def _set_values(self, A: PETSc.Mat, blocks: typing.Sequence[SpringBlocks]) -> None:
        for blk in blocks:
            if blk.values is None or blk.row_nodes.shape[0] == 0:
                continue
            rows = self._global_dof_masked[_unblocked(blk.row_nodes, self._bs)].astype(
                PETSc.IntType
            )
            cols = self._global_dof_masked[_unblocked(blk.col_nodes, self._bs)].astype(
                PETSc.IntType
            )
            A.setValuesRCV(rows, cols, blk.values, addv=PETSc.InsertMode.ADD_VALUES)

    def add_to_matrix(
        self, A: PETSc.Mat, blocks: typing.Sequence[SpringBlocks], *, check_pattern: bool = True
    ) -> None:
        """Add the blocks to an assembled-or-flushed ``A``; grows its pattern if couplings miss.

        Args:
            A: The matrix; call ``A.assemble()`` afterwards.
            blocks: Element blocks; Dirichlet rows and columns are skipped.
            check_pattern: Check for missing couplings (skip when the pattern was checked for these
                springs).
        """
        if check_pattern:
            keys = self._coupling_keys(blocks)
            missing = ~np.isin(keys, self._pattern_keys, assume_unique=True)
            if self._comm.allreduce(bool(np.any(missing)), op=MPI.LOR):
                self._merge(A, keys, blocks)
                self.pattern_merges += 1
                return
        self._set_values(A, blocks)

    def add_global_to_matrix(self, A: PETSc.Mat, blocks: typing.Sequence[GlobalBlocks]) -> None:
        """Add element blocks in global dofs to ``A`` (its pattern holds them; -1 is skipped).

        Call ``A.assemble()`` afterwards.
        """
        for blk in blocks:
            if blk.values is None or blk.dofs.shape[0] == 0:
                continue
            dofs = blk.dofs.astype(PETSc.IntType)
            A.setValuesRCV(dofs, dofs, blk.values, addv=PETSc.InsertMode.ADD_VALUES)

    def add_global_to_vector(self, b: PETSc.Vec, blocks: typing.Sequence[GlobalBlocks]) -> None:
        """Add the residual of element blocks in global dofs to ``b`` (-1 is skipped).

        Ends with a vector assembly so off-process rows reach their owners.
        """
        for blk in blocks:
            _add_rows(b, blk.dofs, blk.vector)
        b.assemblyBegin()
        b.assemblyEnd()

    def add_to_vector(
        self,
        b: PETSc.Vec,
        blocks: typing.Sequence[SpringBlocks],
        *,
        dirichlet_rows: bool = False,
    ) -> None:
        """Add the blocks' residual contributions to ``b`` (global indices).

        Call before dolfinx's ``set_bc``; ends with a vector assembly so off-process rows reach
        their owners.

        Args:
            b: The vector.
            blocks: Element blocks.
            dirichlet_rows: Add to the rows of Dirichlet dofs too (reaction forces); by default
                they are skipped.
        """
        numbering = self._global_dof if dirichlet_rows else self._global_dof_masked
        for blk in blocks:
            if blk.vector is None or blk.row_nodes.shape[0] == 0:
                continue
            _add_rows(b, numbering[_unblocked(blk.row_nodes, self._bs)], blk.vector)
        b.assemblyBegin()
        b.assemblyEnd()


def coupling_matrix(
    rows: ContactAssembler, columns: ContactAssembler, blocks: typing.Sequence[SpringBlocks]
) -> PETSc.Mat:
    """A new matrix coupling two spaces with exactly the entries of ``blocks``. Collective.

    The off-diagonal block of a coupled problem (e.g. heat flows by displacements, docs/method.md
    §20.2): rows of ``rows``'s space, columns of ``columns``'s, the two numbered over the same
    nodes (halo included). ``values[e]`` has shape (bs_r a, bs_c b); Dirichlet rows and columns of
    either assembler are left out (dolfinx's rule for off-diagonal blocks).

    Args:
        rows: The assembler of the row space.
        columns: The assembler of the column space.
        blocks: Element blocks whose ``row_nodes`` and ``col_nodes`` are nodes of both.
    """
    comm = rows._comm
    row_list, col_list, value_list = [np.empty(0, np.int64)], [np.empty(0, np.int64)], [np.empty(0)]
    for blk in blocks:
        if blk.values is None or blk.row_nodes.shape[0] == 0:
            continue
        r = rows._global_dof_masked[_unblocked(blk.row_nodes, rows._bs)]
        c = columns._global_dof_masked[_unblocked(blk.col_nodes, columns._bs)]
        shape = blk.values.shape
        row_list.append(np.broadcast_to(r[:, :, None], shape).ravel())
        col_list.append(np.broadcast_to(c[:, None, :], shape).ravel())
        value_list.append(blk.values.ravel())
    r, c, values = (np.concatenate(x) for x in (row_list, col_list, value_list))
    keep = (r >= 0) & (c >= 0)
    r, c, values = r[keep], c[keep], values[keep]
    num_columns = columns._bs * columns._num_global
    keys = np.unique(r * num_columns + c)
    first = rows._bs * rows._first_nodes
    if comm.size > 1:  # the pattern goes to the process owning each row
        owner = np.searchsorted(first, keys // num_columns, side="right") - 1
        keys = np.unique(collectives.send_to_owners(comm, keys, owner))
    n_rows, n_columns = rows._bs * rows._num_owned, columns._bs * columns._num_owned
    start = int(first[comm.rank])
    pattern = scipy.sparse.csr_matrix(
        (np.ones(keys.size, dtype=np.int8), (keys // num_columns - start, keys % num_columns)),
        shape=(n_rows, num_columns),
    )
    pattern.sort_indices()
    A = PETSc.Mat().createAIJ(
        ((n_rows, rows._bs * rows._num_global), (n_columns, num_columns)),
        csr=(pattern.indptr.astype(PETSc.IntType), pattern.indices.astype(PETSc.IntType)),
        comm=comm,
    )
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
    if r.size:  # petsc4py divides by the number of rows
        A.setValuesRCV(
            r.astype(PETSc.IntType)[:, None],
            c.astype(PETSc.IntType)[:, None],
            values[:, None, None],
            addv=PETSc.InsertMode.ADD_VALUES,
        )
    A.assemble()
    return A
