"""Contact surfaces across MPI processes: what each process gathers and where entries go.

docs/method.md §14. Every process keeps dolfinx's local node numbering (owned, then ghost block
dofs of ``V``) and appends the contact nodes it needs but does not hold, its *halo*: the nodes of
the whole master surface and of the slave faces around its owned slave nodes. Each spring lives on
the process owning its slave node, so it is evaluated once; the pure-numpy layers (search, springs,
areas) run unchanged on the extended numbering, and the same master surface on every process makes
the pairing independent of the partition. Halo displacements come from their owners through a
PETSc scatter; matrix couplings are sent to the owners of their rows before the pattern is grown.

The surfaces are distributed once, at setup: the master surface is allgathered (or exchanged by
bounding boxes, ``master_exchange``); each slave face goes only to the processes owning one of its
nodes, so a process's share grows with its own part of the slave surface (§14.1, §14.2). An error
inside a pairing on one process is raised on all (:func:`collective_errors`, §14.4).
"""

from __future__ import annotations

import contextlib
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
    "NodeHalo",
    "alltoallv",
    "checkpoint",
    "collective_errors",
    "collectively",
    "distribute_pair",
    "distribute_slave",
    "send_to_owners",
]


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


def checkpoint(comm: MPI.Comm, error: Exception | None = None) -> None:
    """Raise on every process if any process has an ``error``. Collective.

    One allreduce of a flag; the message goes round only on failure. Inside
    :func:`collective_errors` every process calls it before each collective call (docs/method.md
    §14.4).
    """
    if comm.size == 1:
        return
    flag = np.array([int(error is not None)], dtype=np.int32)
    comm.Allreduce(MPI.IN_PLACE, flag, op=MPI.MAX)
    if flag[0]:
        try:
            validation.raise_collectively(comm, error)
        except Exception as exc:
            exc.raised_collectively = True  # the enclosing blocks do not check it again
            raise


@contextlib.contextmanager
def collective_errors(comm: MPI.Comm) -> typing.Iterator[None]:
    """An exception inside the block on any process is raised on all. Collective.

    Collective calls inside the block must be preceded by :func:`checkpoint` on every process: a
    process that failed leaves the block and meets the others at their next checkpoint (or at the
    block's end), where all raise.
    """
    try:
        yield
    except Exception as exc:
        if not getattr(exc, "raised_collectively", False):
            checkpoint(comm, exc)
        raise
    checkpoint(comm)


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
        #: First global node of every process (owned nodes are numbered contiguously).
        self.first_nodes = np.array(self.comm.allgather(int(index_map.local_range[0])))
        self._reference = reference_coordinates(V)
        self._sort()
        self._scatter: PETSc.Scatter | None = None

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


def alltoallv(comm: MPI.Comm, parts: list[np.ndarray], dtype: type, mpi_type: MPI.Datatype):
    """Send ``parts[q]`` (flat) to process ``q``; the received parts concatenated. Collective.

    The received parts follow the sending processes' order.
    """
    counts = np.array([p.size for p in parts], dtype=np.int64)
    received = np.asarray(comm.alltoall(counts.tolist()), dtype=np.int64)
    out = np.empty(int(received.sum()), dtype=dtype)
    send = np.concatenate(parts).astype(dtype) if parts else np.empty(0, dtype)
    comm.Alltoallv([send, counts, mpi_type], [out, received, mpi_type])
    return out


def _marked_at_owners(halo: NodeHalo, nodes: np.ndarray) -> np.ndarray:
    """Which owned nodes any process lists in its ``nodes`` (local indices). Collective.

    Each process sends the global numbers of its listed ghosts to their owners.
    """
    nodes = np.asarray(nodes, dtype=np.int64)
    marked = np.zeros(halo.num_owned, dtype=bool)
    marked[nodes[nodes < halo.num_owned]] = True
    ghosts = halo.local_global[nodes[nodes >= halo.num_owned]]
    received = send_to_owners(halo.comm, ghosts, halo.owner(ghosts))
    marked[received - halo.first_nodes[halo.comm.rank]] = True
    return marked


def _marked_locally(V: dolfinx.fem.FunctionSpace, halo: NodeHalo, owned: np.ndarray) -> np.ndarray:
    """``owned`` (a flag per owned node) at every local node (ghosts from owners). Collective."""
    marker = dolfinx.fem.Function(V)
    marker.x.array[:] = 0.0
    marker.x.array[: 3 * halo.num_owned : 3] = owned
    marker.x.scatter_forward()
    return marker.x.array[: 3 * halo.num_local : 3] > 0.5


def _exterior_faces_touching(
    V: dolfinx.fem.FunctionSpace, marked: np.ndarray, what: str
) -> SurfaceFaces:
    """This process's exterior faces with a corner among the ``marked`` local nodes."""
    mesh = V.mesh
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    faces = boundary_faces(V, exterior, what=what)
    touching = marked[faces.faces[:, : faces.face_type.num_corners]].any(axis=1)
    return SurfaceFaces(faces.face_type, faces.faces[touching], faces.facets[touching])


def _unique_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(rows, axis=0, return_index=True, return_inverse=True)[1:]``, by a lexsort.

    The first occurrence of every distinct row, in the rows' lexicographic order, and the index
    of every row among them.
    """
    order = np.lexsort(rows.T[::-1])  # stable: equal rows keep their order
    ordered = rows[order]
    new = np.ones(rows.shape[0], dtype=bool)
    new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    inverse = np.empty(rows.shape[0], dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    return order[new], inverse


def _send_faces_to_owners(halo: NodeHalo, faces: SurfaceFaces) -> tuple[np.ndarray, np.ndarray]:
    """Send each face to the other processes owning one of its nodes, once each. Collective.

    Sends global node numbers and reference coordinates; returns the faces received, in the
    order of the sending processes.
    """
    comm, n = halo.comm, faces.faces.shape[1]
    g = halo.local_global[faces.faces].astype(np.int64)
    owner = np.sort(halo.owner(g), axis=1)
    once = np.ones(owner.shape, dtype=bool)  # each owner once per face
    once[:, 1:] = owner[:, 1:] != owner[:, :-1]
    once &= owner != comm.rank  # this process's own faces stay here
    to = owner[once]
    face = np.repeat(np.arange(g.shape[0]), n).reshape(-1, n)[once]
    order = np.argsort(to, kind="stable")  # by owner, then the faces in their order
    to, face = to[order], face[order]
    split = np.searchsorted(to, np.arange(1, comm.size))
    nodes = [p.ravel() for p in np.split(g[face], split)]
    x = [p.ravel() for p in np.split(halo.reference[faces.faces[face]], split)]
    received_g = alltoallv(comm, nodes, np.int64, MPI.INT64_T).reshape(-1, n)
    received_x = alltoallv(comm, x, np.float64, MPI.DOUBLE).reshape(-1, n, 3)
    return received_g, received_x


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
    mine = _marked_at_owners(halo, slave.nodes)  # owned nodes some process lists as slave
    faces = slave.faces
    if isinstance(surface, NodeSurface):  # vertices given on one process touch faces of others
        faces = _exterior_faces_touching(V, _marked_locally(V, halo, mine), f"{what} slave")
        if faces.face_type is not slave.faces.face_type:  # C3D20: quad9 facets as quad8 (§13.5)
            n = slave.faces.face_type.num_nodes
            faces = SurfaceFaces(slave.faces.face_type, faces.faces[:, :n], faces.facets)
    g, x = _send_faces_to_owners(halo, faces)
    # the faces received and this process's own (for their facets); duplicates dropped, sorted
    g = np.vstack([g, halo.local_global[faces.faces]])
    x = np.vstack([x, halo.reference[faces.faces]])
    first, inverse = _unique_rows(np.sort(g, axis=1))
    facets = np.full(first.size, -1, dtype=np.int32)
    facets[inverse[g.shape[0] - faces.faces.shape[0] :]] = faces.facets
    g, x = g[first], x[first]
    keep = np.isin(g, halo.local_global[: halo.num_owned][mine]).any(axis=1)
    slave_faces = SurfaceFaces(
        faces.face_type, halo.local(g[keep], x[keep]).astype(np.int32), facets[keep]
    )
    nodes = np.flatnonzero(mine)
    faceless = None  # midside nodes of a node-based surface (docs/method.md §13.5, §14.10)
    marked = slave.nodes[slave.faceless] if slave.faceless is not None else slave.nodes[:0]
    if comm.allreduce(int(marked.size), op=MPI.MAX):
        faceless = _marked_at_owners(halo, marked)[nodes]
    return SlaveSurface(nodes, slave_faces, faceless)


def send_to_owners(comm: MPI.Comm, keys: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """Send each ``keys[i]`` to process ``owner[i]``; returns the keys received. Collective."""
    order = np.argsort(owner, kind="stable")
    split = np.searchsorted(np.asarray(owner)[order], np.arange(1, comm.size))
    return alltoallv(comm, np.split(np.asarray(keys)[order], split), np.int64, MPI.INT64_T)
