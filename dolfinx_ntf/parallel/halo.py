"""The node halo: ``V``'s local nodes extended by the contact nodes other processes hold.

docs/method.md §14. Every process keeps dolfinx's local node numbering (owned, then ghost block
dofs of ``V``) and appends the contact nodes it needs but does not hold, its *halo*: the nodes of
the whole master surface and of the slave faces around its owned slave nodes. Halo displacements
come from their owners through a PETSc scatter.
"""

from __future__ import annotations

import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.fem.surfaces import reference_coordinates

__all__ = ["NodeHalo", "planar_padded"]


def planar_padded(values: np.ndarray) -> np.ndarray:
    """Nodal vectors ``(N, 2 or 3)`` as ``(N, 3)``: a 2D mesh's get z = 0, like its coordinates."""
    if values.shape[1] == 3:
        return values
    return np.pad(values, ((0, 0), (0, 3 - values.shape[1])))


class NodeHalo:
    """``V``'s local nodes extended by contact nodes held by other processes.

    Node ``i < num_local`` is ``V``'s local block dof ``i``; node ``num_local + k`` is the global
    node ``extra[k]``. Coordinates have 3 columns on 2D meshes too (z = 0); values of ``V``'s
    vectors have its block size ``bs`` (3, or 2 on a 2D mesh).
    """

    def __init__(self, V: dolfinx.fem.FunctionSpace) -> None:
        index_map = V.dofmap.index_map
        #: Components per node of ``V``'s vectors.
        self.bs: int = V.dofmap.index_map_bs
        self.comm: MPI.Comm = V.mesh.comm
        self.num_owned = index_map.size_local
        self.num_local = index_map.size_local + index_map.num_ghosts
        self.local_global = index_map.local_to_global(
            np.arange(self.num_local, dtype=np.int32)
        ).astype(np.int64)
        self.extra = np.empty(0, dtype=np.int64)
        #: First global node of every process (owned nodes are numbered contiguously).
        self.first_nodes = np.array(self.comm.allgather(int(index_map.local_range[0])))
        self._reference = reference_coordinates(V)
        self._sort()
        #: Scatters to the halo nodes by block size.
        self._scatters: dict[int, tuple[PETSc.Scatter, PETSc.Vec]] = {}

    def _sort(self) -> None:
        self._all = np.concatenate([self.local_global, self.extra])
        self._order = np.argsort(self._all, kind="stable")
        self._sorted = self._all[self._order]

    def owner(self, global_nodes: np.ndarray) -> np.ndarray:
        """Process owning each global node."""
        return np.searchsorted(self.first_nodes, global_nodes, side="right") - 1

    @property
    def reference(self) -> np.ndarray:
        """Reference coordinates of the extended nodes, shape (num_local + extras, 3)."""
        return self._reference

    @property
    def global_nodes(self) -> np.ndarray:
        """Global node of every extended node."""
        return self._all

    def find(self, global_nodes: np.ndarray) -> np.ndarray:
        """Extended index of each global node, -1 where this process has none."""
        g = np.asarray(global_nodes, dtype=np.int64)
        position = np.minimum(np.searchsorted(self._sorted, g), max(self._sorted.size - 1, 0))
        if self._sorted.size == 0:
            return np.full(g.shape, -1, dtype=np.int64)
        return np.where(self._sorted[position] == g, self._order[position], -1)

    def local(self, global_nodes: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """Extended indices of global nodes, appending the unknown ones.

        ``reference``: their coordinates, shape ``global_nodes.shape + (3,)``.
        """
        g = np.asarray(global_nodes, dtype=np.int64)
        index = self.find(g)
        unknown = index < 0
        if np.any(unknown):
            new, first = np.unique(g[unknown], return_index=True)
            self.extra = np.concatenate([self.extra, new])
            self._reference = np.vstack([self._reference, reference[unknown].reshape(-1, 3)[first]])
            self._sort()
            index = self.find(g)
        return index

    # -- values of other processes -----------------------------------------------------------------

    def _scatter_from(self, vector: PETSc.Vec, bs: int | None = None) -> np.ndarray:
        """Values of ``vector`` (block size ``bs``, V's by default) at the halo nodes, (extras, bs).

        Collective.
        """
        bs = self.bs if bs is None else bs
        if bs not in self._scatters:  # made once, like the halo's numbering (collective)
            dofs = (bs * self.extra[:, None] + np.arange(bs)).ravel().astype(PETSc.IntType)
            target = PETSc.Vec().createSeq(dofs.size, comm=PETSc.COMM_SELF)
            source = PETSc.IS().createGeneral(dofs, comm=PETSc.COMM_SELF)
            self._scatters[bs] = (PETSc.Scatter().create(vector, source, target, None), target)
            source.destroy()
        scatter, target = self._scatters[bs]
        scatter.scatter(
            vector, target, addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD
        )
        return target.array_r.reshape(-1, bs).copy()

    def values(self, vector: PETSc.Vec) -> np.ndarray:
        """Values of ``vector`` (V's layout) at the halo nodes, shape (extras, bs). Collective."""
        return self._scatter_from(vector)

    def displacement(self, u: dolfinx.fem.Function) -> np.ndarray:
        """``u`` at every extended node, shape (num_local + extras, 3) (z = 0 in 2D). Collective."""
        values = u.x.array.reshape(-1, self.bs)
        if self.comm.size > 1:
            values = np.vstack([values, self._scatter_from(compat.petsc_vector(u))])
        return planar_padded(values)

    def field(self, f: dolfinx.fem.Function) -> np.ndarray:
        """A field numbered like ``V``'s nodes (e.g. a temperature) at every extended node.

        Shape (num_local + extras, bs) for the block size bs of ``f``'s space. Collective.
        """
        bs = f.function_space.dofmap.index_map_bs
        values = f.x.array.reshape(-1, bs)
        return np.vstack([values, self._scatter_from(compat.petsc_vector(f), bs)])

    def constrained(self, u: dolfinx.fem.Function, bcs: typing.Sequence) -> np.ndarray:
        """Which dofs of the halo nodes the Dirichlet conditions fix, (extras, bs). Collective.

        ``u``: a function of the conditions' space (its block size bs: V's for the displacement).
        """
        bs = u.function_space.dofmap.index_map_bs
        marker = compat.petsc_vector(u).duplicate()
        with marker.localForm() as local:
            local.set(0.0)
            array = local.array
            for bc in bcs:
                dofs, _ = bc.dof_indices()
                array[dofs[dofs < bs * self.num_owned]] = 1.0
        values = self._scatter_from(marker, bs) > 0.5
        marker.destroy()
        return values

    def destroy(self) -> None:
        """Free the PETSc scatter. Collective."""
        for scatter, target in self._scatters.values():
            scatter.destroy()
            target.destroy()
        self._scatters = {}
