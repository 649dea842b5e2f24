"""Contact surfaces across MPI processes: what each process gathers and where entries go.

docs/method.md §14. Every process keeps dolfinx's local node numbering (owned, then ghost block
dofs of ``V``) and appends the contact nodes it needs but does not hold, its *halo*: the nodes of
the whole master surface and of the slave faces around its owned slave nodes. Each spring lives on
the process owning its slave node, so it is evaluated once; the pure-numpy layers (search, springs,
areas) run unchanged on the extended numbering, and the same master surface on every process makes
the pairing independent of the partition. Halo displacements come from their owners through a
PETSc scatter; matrix couplings are sent to the owners of their rows before the pattern is grown.

The surfaces are allgathered once, at setup: up to :data:`MAX_GATHERED_FACES` faces per surface.
"""

from __future__ import annotations

import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat, validation
from dolfinx_ntf.surfaces import (
    NodeSurface,
    SlaveSurface,
    SurfaceFaces,
    boundary_faces,
    reference_coordinates,
)

__all__ = [
    "MAX_GATHERED_FACES",
    "NodeHalo",
    "collectively",
    "distribute_pair",
    "distribute_slave",
    "send_to_owners",
]

#: Faces of one contact surface (over all processes) that setup allgathers (docs/method.md §14.2).
MAX_GATHERED_FACES = 2_000_000


def collectively(comm: MPI.Comm, function: typing.Callable, *args, **kwargs) -> typing.Any:
    """``function(*args, **kwargs)``; an exception on any process is raised on all. Collective.

    ``function`` must reach its own collective calls on all processes or raise on all before them.
    """
    result, error = None, None
    try:
        result = function(*args, **kwargs)
    except Exception as exc:  # an unexpected error on one process must not leave the others waiting
        error = exc
    validation.raise_collectively(comm, error)
    return result


class NodeHalo:
    """``V``'s local nodes extended by contact nodes held by other processes.

    Node ``i < num_local`` is ``V``'s local block dof ``i``; node ``num_local + k`` is the global
    node ``extra[k]``.
    """

    def __init__(self, V: dolfinx.fem.FunctionSpace) -> None:
        index_map = V.dofmap.index_map
        self.comm: MPI.Comm = V.mesh.comm
        self.num_owned = index_map.size_local
        self.num_local = index_map.size_local + index_map.num_ghosts
        self.local_global = index_map.local_to_global(
            np.arange(self.num_local, dtype=np.int32)
        ).astype(np.int64)
        self.extra = np.empty(0, dtype=np.int64)
        self._reference = reference_coordinates(V)
        self._sort()
        self._scatter: PETSc.Scatter | None = None

    def _sort(self) -> None:
        self._all = np.concatenate([self.local_global, self.extra])
        self._order = np.argsort(self._all, kind="stable")
        self._sorted = self._all[self._order]

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

    def _scatter_from(self, vector: PETSc.Vec) -> np.ndarray:
        """Values of ``vector`` (V's layout) at the halo nodes, shape (extras, 3). Collective."""
        if self._scatter is None:
            dofs = (3 * self.extra[:, None] + np.arange(3)).ravel().astype(PETSc.IntType)
            self._target = PETSc.Vec().createSeq(dofs.size, comm=PETSc.COMM_SELF)
            source = PETSc.IS().createGeneral(dofs, comm=PETSc.COMM_SELF)
            self._scatter = PETSc.Scatter().create(vector, source, self._target, None)
            source.destroy()
        self._scatter.scatter(
            vector, self._target, addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD
        )
        return self._target.array_r.reshape(-1, 3).copy()

    def values(self, vector: PETSc.Vec) -> np.ndarray:
        """Values of ``vector`` (V's layout) at the halo nodes, shape (extras, 3). Collective."""
        return self._scatter_from(vector)

    def displacement(self, u: dolfinx.fem.Function) -> np.ndarray:
        """``u`` at every extended node, shape (num_local + extras, 3). Collective."""
        values = u.x.array.reshape(-1, 3)
        if self.comm.size == 1:
            return values
        return np.vstack([values, self._scatter_from(compat.petsc_vector(u))])

    def constrained(self, u: dolfinx.fem.Function, bcs: typing.Sequence) -> np.ndarray:
        """Which dofs of the halo nodes the Dirichlet conditions fix, (extras, 3). Collective."""
        marker = compat.petsc_vector(u).duplicate()
        with marker.localForm() as local:
            local.set(0.0)
            array = local.array
            for bc in bcs:
                dofs, _ = bc.dof_indices()
                array[dofs[dofs < 3 * self.num_owned]] = 1.0
        values = self._scatter_from(marker) > 0.5
        marker.destroy()
        return values

    def destroy(self) -> None:
        """Free the PETSc scatter. Collective."""
        if self._scatter is not None:
            self._scatter.destroy()
            self._target.destroy()
            self._scatter = None


def _gather_faces(
    halo: NodeHalo, faces: SurfaceFaces, what: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All processes' faces of a surface: global nodes, reference coordinates, this process's facet.

    Duplicates (faces of ghost cells) are dropped; the order is the same on every process. The
    facet is -1 where the face's cell is not on this process.
    """
    comm = halo.comm
    total = comm.allreduce(int(faces.faces.shape[0]), op=MPI.SUM)
    if total > MAX_GATHERED_FACES:
        raise NotImplementedError(
            f"{what}: {total} faces over all processes; contact surfaces of more than "
            f"{MAX_GATHERED_FACES} faces are not supported in parallel yet (docs/method.md §14.2)"
        )
    g = halo.local_global[faces.faces]
    x = halo.reference[faces.faces]
    parts = comm.allgather((g, x))
    n = faces.faces.shape[1]
    all_g = np.vstack([p[0].reshape(-1, n) for p in parts]).astype(np.int64)
    all_x = np.vstack([p[1].reshape(-1, n, 3) for p in parts])
    key = np.sort(all_g, axis=1)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    facets = np.full(first.size, -1, dtype=np.int32)
    start = sum(p[0].shape[0] for p in parts[: comm.rank])
    facets[inverse[start : start + faces.faces.shape[0]]] = faces.facets
    return all_g[first], all_x[first], facets


def _exterior_faces_touching(
    V: dolfinx.fem.FunctionSpace, halo: NodeHalo, slave_global: np.ndarray, what: str
) -> SurfaceFaces:
    """This process's exterior faces with a corner among the (global) slave nodes."""
    mesh = V.mesh
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    faces = boundary_faces(V, exterior, what=what)
    corners = halo.local_global[faces.faces[:, : faces.face_type.num_corners]]
    touching = np.isin(corners, slave_global).any(axis=1)
    return SurfaceFaces(faces.face_type, faces.faces[touching], faces.facets[touching])


def distribute_pair(
    V: dolfinx.fem.FunctionSpace,
    halo: NodeHalo,
    surface: object,
    slave: SlaveSurface,
    master: SurfaceFaces,
    what: str,
) -> tuple[SlaveSurface, SurfaceFaces]:
    """A pair's surfaces as this process needs them, in the halo's extended numbering. Collective.

    The master: every face of every process. The slave: the slave nodes this process owns, and
    every slave face (of any process) holding one of them, so that spring areas are complete at
    partition cuts (docs/method.md §14.1).
    """
    g, x, facets = _gather_faces(halo, master, f"{what} master")
    master = SurfaceFaces(master.face_type, halo.local(g, x).astype(np.int32), facets)
    return distribute_slave(V, halo, surface, slave, what), master


def distribute_slave(
    V: dolfinx.fem.FunctionSpace,
    halo: NodeHalo,
    surface: object,
    slave: SlaveSurface,
    what: str,
) -> SlaveSurface:
    """The slave nodes this process owns and every slave face holding one of them. Collective.

    For :func:`distribute_pair`, and alone for a rigid master (no master nodes, docs/method.md
    §14.6).
    """
    comm = halo.comm
    slave_global = np.unique(
        np.concatenate(comm.allgather(halo.local_global[slave.nodes])).astype(np.int64)
    )
    faces = slave.faces
    if isinstance(surface, NodeSurface):  # vertices given on one process touch faces of others
        faces = _exterior_faces_touching(V, halo, slave_global, f"{what} slave")
        if faces.face_type is not slave.faces.face_type:  # C3D20: quad9 facets as quad8 (§13.5)
            n = slave.faces.face_type.num_nodes
            faces = SurfaceFaces(slave.faces.face_type, faces.faces[:, :n], faces.facets)
    g, x, facets = _gather_faces(halo, faces, f"{what} slave")
    owned_global = halo.local_global[: halo.num_owned]
    mine = np.intersect1d(slave_global, owned_global)
    keep = np.isin(g, mine).any(axis=1)
    slave_faces = SurfaceFaces(
        faces.face_type, halo.local(g[keep], x[keep]).astype(np.int32), facets[keep]
    )
    nodes = np.sort(halo.find(mine))
    faceless = None  # midside nodes of a node-based surface (docs/method.md §13.5, §14.10)
    marked = slave.nodes[slave.faceless] if slave.faceless is not None else slave.nodes[:0]
    if comm.allreduce(int(marked.size), op=MPI.MAX):
        marked = np.concatenate(comm.allgather(halo.local_global[marked]))
        faceless = np.isin(halo.global_nodes[nodes], marked)
    return SlaveSurface(nodes, slave_faces, faceless)


def send_to_owners(comm: MPI.Comm, keys: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """Send each ``keys[i]`` to process ``owner[i]``; returns the keys received. Collective."""
    order = np.argsort(owner, kind="stable")
    counts = np.bincount(owner, minlength=comm.size).astype(np.int64)
    received = np.asarray(comm.alltoall(counts.tolist()), dtype=np.int64)
    out = np.empty(int(received.sum()), dtype=np.int64)
    comm.Alltoallv(
        [np.ascontiguousarray(keys[order], dtype=np.int64), counts, MPI.INT64_T],
        [out, received, MPI.INT64_T],
    )
    return out
