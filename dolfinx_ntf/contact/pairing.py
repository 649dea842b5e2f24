"""Which slave node springs onto which master face: :class:`Pairing` (docs/method.md §3).

A :class:`Pairing` owns the state of every contact pair (:class:`~dolfinx_ntf.contact.pair.
PairState`), the node halo of the processes' contact nodes (docs/method.md §14), the current
coordinates, the search (§3.2), CalculiX's ADJUST (§11.5), the tie frame of the stable search and
the friction anchors of new springs (§11.3). :class:`~dolfinx_ntf.ContactProblem` tells it when
increments and steps start and when to pair; it reads the springs back from :attr:`Pairing.states`.
"""

from __future__ import annotations

import dataclasses
import logging
import typing

from mpi4py import MPI

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.adjust import adjusted_nodes, move_reference_nodes
from dolfinx_ntf.contact.assembly import SpringBlocks
from dolfinx_ntf.contact.pair import ContactPair, PairState, fallback_scale
from dolfinx_ntf.fem import serendipity
from dolfinx_ntf.fem.surfaces import (
    NodeSurface,
    SlaveSurface,
    SurfaceFaces,
    master_face_groups,
    reference_coordinates,
    resolve_master,
    resolve_slave,
)
from dolfinx_ntf.kernels.edges import (
    EdgeType,
    axisymmetric_edge_spring_areas,
    ccx_edge_spring_areas,
    edge_spring_areas,
)
from dolfinx_ntf.kernels.faces import QUAD4
from dolfinx_ntf.kernels.friction_state import FrictionState
from dolfinx_ntf.kernels.rigid import RigidSurface, check_in_plane, rigid_master
from dolfinx_ntf.kernels.search import MasterFaceGroup, MasterSurface
from dolfinx_ntf.kernels.segment_search import MasterCurve
from dolfinx_ntf.kernels.spring_areas import spring_areas
from dolfinx_ntf.kernels.springs import SpringEvaluation
from dolfinx_ntf.kernels.tie_frame import TieFrame, frame_from_moments, point_moments
from dolfinx_ntf.logs import details_logger
from dolfinx_ntf.parallel import collectives, master_exchange, surface_distribution
from dolfinx_ntf.parallel.halo import NodeHalo, planar_padded

__all__ = ["SEARCH_TOLERANCE", "Pairing", "slave_areas"]

logger = logging.getLogger("dolfinx_ntf")

#: Relative walk tolerance of the triangle search (docs/method.md §3.2).
SEARCH_TOLERANCE = 1e-3


def _refuse_shared_nodes(
    comm: MPI.Comm,
    name: str,
    slave_nodes: np.ndarray,
    master_nodes: np.ndarray,
    reference: np.ndarray,
    gdim: int,
) -> None:
    """Raise on every process if a node is on both surfaces of pair ``name`` (naming the first)."""
    both = np.intersect1d(slave_nodes, master_nodes)
    error = None
    if both.size:
        where = ", ".join(f"{c:.6g}" for c in reference[both[0]][:gdim])
        error = ValueError(
            f"{name}: {both.size} node(s) belong to both the slave and the master surface "
            f"(first at ({where}))"
        )
    validation.raise_collectively(comm, error)


class Pairing:
    """The contact pairs' states and their (re-)pairing at the current displacement.

    Collective calls (every process must reach them in the same order; one misplaced call hangs
    all, docs/method.md §14.4) happen only at these places:

    - construction: the halo, the C3D20 flag, each pair's surfaces (resolved and distributed
      collectively, with the check of nodes on both sides), ``extend_numbering``, the check of
      distinct pairs and the increment-start displacement;
    - :meth:`current_coordinates` and :meth:`begin_increment` (halo scatter, the finiteness check);
    - :meth:`pair` and :meth:`unpaired_contacts`, inside one ``collective_errors`` block each
      (``parallel/collectives.py``): in the search, a checkpoint before the update of a
      ``collective`` master, a checkpoint before the tie frame (a sum over the processes), the
      master patch's enlargement (``enlarge`` of ``parallel/master_exchange.py``, then the
      halo's growth and ``extend_numbering``); at the first pairing, a checkpoint before ADJUST,
      ADJUST's node count, and a checkpoint before the coordinates it changed. Then the spring
      counts.

    Args:
        u: The displacement (3D vector Lagrange).
        pairs: The contact pairs, already checked.
        face_centres: Face-centre nodes of C3D20's space (docs/method.md §13.5), maybe empty.
        linear_midsides: Midside nodes of C3D8 cells in that space (§27): their faces are quad4
            faces and they are never slave nodes; None: none.
        extend_numbering: Called with the halo (several processes) once the pairs are resolved
            and whenever the halo grows, so that the contact numbering follows. Collective.
        max_depth: Reject nodes deeper than this below the master face.
        walk_from_previous_face: Start each node's search at its current face (stable search).
        reset_friction_on_separation: Fresh friction state for nodes that touch again.
        overlap_ramp: ``"first_increment"`` or ``"linear"`` (docs/method.md §11.6).
        small_sliding_rule: ``"per_pair"`` or ``"last_pair"`` (docs/method.md §11.6).
    """

    def __init__(
        self,
        u: dolfinx.fem.Function,
        pairs: typing.Sequence[ContactPair],
        *,
        face_centres: np.ndarray,
        linear_midsides: np.ndarray | None = None,
        extend_numbering: typing.Callable[[NodeHalo], None],
        max_depth: float | None = None,
        walk_from_previous_face: bool = True,
        reset_friction_on_separation: bool = True,
        overlap_ramp: str = "first_increment",
        small_sliding_rule: str = "per_pair",
    ) -> None:
        if small_sliding_rule not in ("per_pair", "last_pair"):
            raise ValueError(
                "ContactProblem: small_sliding_rule must be 'per_pair' or 'last_pair', "
                f"got {small_sliding_rule!r}"
            )
        if overlap_ramp not in ("first_increment", "linear"):
            raise ValueError(
                "ContactProblem: overlap_ramp must be 'first_increment' or 'linear', "
                f"got {overlap_ramp!r}"
            )
        V = u.function_space
        self.u = u
        self.max_depth = max_depth
        self.walk_from_previous_face = walk_from_previous_face
        self.reset_friction_on_separation = bool(reset_friction_on_separation)
        self.overlap_ramp = overlap_ramp
        self.small_sliding_rule = small_sliding_rule
        #: Steps begun so far (:meth:`begin_step`); the linear overlap ramp lasts step 1.
        self.step_count = 0
        self.time_fraction = 1.0  # relative step time tau at the end of the current increment
        self.static = True
        #: Slave nodes ADJUST moved (over all processes, all pairs; docs/method.md §11.5).
        self.adjusted = 0
        self._extend_numbering = extend_numbering
        self._reference = reference_coordinates(V)
        #: ``reference_coordinates(V)`` for the surfaces' faces while the pairs are resolved
        #: (one pass over the nodes instead of one per surface); None afterwards.
        self._surface_reference: np.ndarray | None = self._reference
        #: Contact nodes of other processes (docs/method.md §14); None in serial.
        self.halo = NodeHalo(V) if V.mesh.comm.size > 1 else None
        self._face_centres = face_centres
        self._midsides = np.zeros(0, np.int64) if linear_midsides is None else linear_midsides
        self._serendipity = bool(V.mesh.comm.allreduce(face_centres.size, op=MPI.MAX))
        #: One state per pair, several for a master of several face types (one per type, in
        #: a row, sharing the pair, its slave surface and search, docs/method.md §38.8).
        self.states: list[PairState] = []
        for i, pair in enumerate(pairs):
            resolved = self._resolve(i, pair)
            self.states += resolved if isinstance(resolved, list) else [resolved]
        self._surface_reference = None
        if self.halo is not None:
            self._reference = self.halo.reference
            extend_numbering(self.halo)
        self._check_distinct_pairs()
        self._increment_start_u = self._displacement().copy()

    def _as_quad8(self, faces: SurfaceFaces) -> SurfaceFaces:
        """C3D20's quad9 facets as quad8 faces, C3D8's as quad4 (collective: one face type)."""
        faces = serendipity.as_quad8(faces, self._face_centres, self._midsides)
        comm = self.u.function_space.mesh.comm
        if comm.size > 1 and comm.allreduce(faces.face_type is QUAD4, op=MPI.LOR):
            if faces.faces.shape[0] == 0:  # a process without faces: the others' type
                return SurfaceFaces(QUAD4, np.zeros((0, 4), faces.faces.dtype), faces.facets)
        return faces

    def _resolve(self, index: int, pair: ContactPair) -> PairState | list[PairState]:
        name = pair.name or f"pair {index + 1}"
        V = self.u.function_space
        comm = V.mesh.comm
        if V.mesh.topology.dim == 2:
            return self._resolve_2d(name, pair)
        if pair.thickness != 1.0:
            raise ValueError(
                f"{name}: thickness = {pair.thickness:g} is for 2D meshes; a 3D mesh has its own"
            )
        if pair.area_weights != "consistent":
            raise ValueError(f"{name}: area_weights = 'ccx' is for 2D meshes; this mesh is 3D")
        if pair.fallback_area != "edge":
            raise ValueError(
                f"{name}: fallback_area = {pair.fallback_area!r} is for 2D meshes; this mesh is 3D"
            )
        if pair.axisymmetric:
            raise ValueError(
                f"{name}: axisymmetric = True is for 2D meshes of the meridian half-plane; this "
                "mesh is 3D"
            )
        slave = collectives.collectively(
            comm, resolve_slave, V, pair.slave, what=f"{name} slave",
            reference=self._surface_reference,
        )  # fmt: skip
        if self._serendipity:  # C3D20: quad8 slave faces, no face-centre slave nodes
            faces = self._as_quad8(slave.faces)
            keep = ~np.isin(slave.nodes, self._face_centres) & ~np.isin(slave.nodes, self._midsides)
            faceless = None if slave.faceless is None else slave.faceless[keep]
            slave = dataclasses.replace(
                slave, nodes=slave.nodes[keep], faces=faces, faceless=faceless
            )
        if isinstance(pair.master, RigidSurface):  # docs/method.md §15.1
            if pair.interaction.friction is not None or pair.adjust is not None:
                raise NotImplementedError(
                    f"{name}: friction and ADJUST against a rigid analytical master are not "
                    "supported yet; use a meshed master"
                )
            if self.halo is not None:  # the owned slave nodes; no master nodes (§14.6)
                slave = collectives.collectively(
                    comm,
                    surface_distribution.distribute_slave,
                    V,
                    self.halo,
                    pair.slave,
                    slave,
                    name,
                )
            faces, master = rigid_master(pair.master, lambda: self.time_fraction, f"{name} master")
            friction = FrictionState(slave.nodes.size)  # stays empty: the bookkeeping is shared
            return PairState(
                pair, slave, faces, master, np.zeros(slave.nodes.size), friction=friction,
                was_active=pair.active,
            )  # fmt: skip
        groups = collectives.collectively(
            comm, master_face_groups, V, pair.master, what=f"{name} master",
            reference=self._surface_reference,
        )  # fmt: skip
        if len(groups) > 1:  # a master of several face types (docs/method.md §38.8)
            return self._resolve_face_groups(name, pair, slave, groups)
        master_faces = groups[0]
        if self._serendipity:
            master_faces = self._as_quad8(master_faces)
        patch = None
        if self.halo is not None and master_exchange.uses_exchange(comm, master_faces):  # §14.8
            slave, patch = collectives.collectively(
                comm, master_exchange.distribute_pair, self.halo, self.u, pair.slave, slave,
                master_faces, name,
            )  # fmt: skip
            master_faces = patch.faces
        elif self.halo is not None:
            slave, master_faces = collectives.collectively(
                comm,
                surface_distribution.distribute_pair,
                V,
                self.halo,
                pair.slave,
                slave,
                master_faces,
                name,
            )
        if patch is None and master_faces.faces.shape[0] == 0:
            raise ValueError(f"{name}: the master surface has no faces")
        reference = self._reference if self.halo is None else self.halo.reference
        master = patch or MasterSurface(
            master_faces.face_type, master_faces.faces, name=f"{name} master", coords=reference
        )
        _refuse_shared_nodes(comm, name, slave.nodes, master_faces.nodes, reference, 3)
        friction = FrictionState(
            slave.nodes.size, reset_on_separation=self.reset_friction_on_separation
        )
        adjust_nodes = self._adjust_nodes(name, pair)
        return PairState(
            pair,
            slave,
            master_faces,
            master,
            np.zeros(slave.nodes.size),
            friction=friction,
            was_active=pair.active,
            adjust_nodes=adjust_nodes,
        )

    def _resolve_face_groups(
        self,
        name: str,
        pair: ContactPair,
        slave: SlaveSurface,
        groups: tuple[SurfaceFaces, ...],
    ) -> list[PairState]:
        """One state per face type of a master of several types, one search (§38.8).

        The states share the slave surface, the friction history (a node moving from a face of
        one type to one of the other keeps it) and the initial overlaps; the surface is
        triangulated and searched once (:class:`~dolfinx_ntf.kernels.search.MasterFaceGroup`).
        On several processes every process holds every master face (the exchanged patches of
        §14.8 hold one type: refused above their threshold). ADJUST is refused.
        """
        comm = self.u.function_space.mesh.comm
        if pair.adjust is not None:
            raise NotImplementedError(
                f"{name}: ADJUST with a master surface of several face types "
                f"({', '.join(g.face_type.name for g in groups)}) is not supported"
            )
        if self._serendipity:
            groups = tuple(self._as_quad8(g) for g in groups)
        if self.halo is not None:
            total = comm.allreduce(sum(int(g.faces.shape[0]) for g in groups))
            if total > master_exchange.EXCHANGE_ABOVE_FACES:
                raise NotImplementedError(
                    f"{name}: a master surface of several face types with {total} faces on "
                    f"{comm.size} processes: above {master_exchange.EXCHANGE_ABOVE_FACES} faces "
                    "the master is exchanged by patches of one face type (docs/method.md §14.8)"
                )
            slave = collectives.collectively(
                comm, surface_distribution.distribute_slave, self.u.function_space, self.halo,
                pair.slave, slave, name,
            )  # fmt: skip
            groups = tuple(
                collectives.collectively(
                    comm, surface_distribution.distribute_master, self.halo, g, f"{name} master"
                )
                for g in groups
            )
        kept = [g for g in groups if g.faces.shape[0]]  # the same on every process (gathered)
        if not kept:
            raise ValueError(f"{name}: the master surface has no faces")
        reference = self._reference if self.halo is None else self.halo.reference
        surface = MasterSurface(
            kept[0].face_type,
            kept[0].faces,
            name=f"{name} master",
            coords=reference,
            more=tuple((g.face_type, g.faces) for g in kept[1:]),
        )
        nodes = np.unique(np.concatenate([g.nodes for g in kept]))
        _refuse_shared_nodes(comm, name, slave.nodes, nodes, reference, 3)
        friction = FrictionState(
            slave.nodes.size, reset_on_separation=self.reset_friction_on_separation
        )
        overlap = np.zeros(slave.nodes.size)
        views = MasterFaceGroup.groups(surface, f"{name} master")
        return [
            PairState(pair, slave, g, view, overlap, friction=friction, was_active=pair.active)
            for g, view in zip(kept, views, strict=True)
        ]

    def _resolve_2d(self, name: str, pair: ContactPair) -> PairState:
        """A pair on a 2D mesh: springs on master edges, rigid lines or circles.

        Friction works on meshed master edges (one tangent direction, docs/method.md §17); like
        in 3D it is refused against a rigid master. On several processes the surfaces are
        distributed as in 3D (docs/method.md §14.1): the master edges of every process are
        gathered on each, the slave nodes go to their owners with every slave edge holding one of
        them. Collective.
        """
        V = self.u.function_space
        comm = V.mesh.comm
        slave = collectives.collectively(
            comm, resolve_slave, V, pair.slave, what=f"{name} slave",
            reference=self._surface_reference,
        )  # fmt: skip
        if pair.axisymmetric and pair.fallback_area != "ccx_ring":
            midside = slave.faceless is not None and bool(np.any(slave.faceless))
            if comm.allreduce(midside, op=MPI.LOR):
                raise NotImplementedError(
                    f"{name}: an axisymmetric pair cannot give the midside nodes of a node surface "
                    "CalculiX's fallback area (it is not a ring area); use a FacetSurface or a "
                    "NodeSurface without midside_nodes"
                )
        if isinstance(pair.master, RigidSurface):  # a line or a circle in the plane (§15.1)
            if pair.interaction.friction is not None or pair.adjust is not None:
                raise NotImplementedError(
                    f"{name}: friction and ADJUST against a rigid analytical master are not "
                    "supported yet (in 2D as in 3D); use a meshed master"
                )
            check_in_plane(pair.master, f"{name} master")
            if self.halo is not None:  # the owned slave nodes and their edges
                slave = collectives.collectively(
                    comm, surface_distribution.distribute_slave, V, self.halo, pair.slave, slave,
                    name,
                )  # fmt: skip
            slave = self._planar_slave(name, pair, slave)
            faces, master = rigid_master(
                pair.master, lambda: self.time_fraction, f"{name} master", dim=2
            )
            return PairState(
                pair, slave, faces, master, np.zeros(slave.nodes.size),
                friction=FrictionState(slave.nodes.size), was_active=pair.active,
            )  # fmt: skip
        master_faces = collectives.collectively(
            comm, resolve_master, V, pair.master, what=f"{name} master",
            reference=self._surface_reference,
        )  # fmt: skip
        if self.halo is not None:  # every master edge; the owned slave nodes and their edges
            slave, master_faces = collectives.collectively(
                comm, surface_distribution.distribute_pair, V, self.halo, pair.slave, slave,
                master_faces, name,
            )  # fmt: skip
        slave = self._planar_slave(name, pair, slave)
        if master_faces.faces.shape[0] == 0:  # the gathered surface: the same on every process
            raise ValueError(f"{name}: the master surface has no edges")
        reference = self._reference if self.halo is None else self.halo.reference
        factor, ring = fallback_scale(pair)
        master = MasterCurve(
            master_faces.face_type, master_faces.faces, name=f"{name} master", coords=reference,
            fallback_factor=factor, fallback_ring=ring,
        )  # fmt: skip
        _refuse_shared_nodes(comm, name, slave.nodes, master_faces.nodes, reference, 2)
        friction = FrictionState(
            slave.nodes.size, reset_on_separation=self.reset_friction_on_separation
        )
        return PairState(
            pair, slave, master_faces, master, np.zeros(slave.nodes.size), friction=friction,
            was_active=pair.active, adjust_nodes=self._adjust_nodes(name, pair),
        )  # fmt: skip

    def _adjust_nodes(self, name: str, pair: ContactPair) -> np.ndarray | None:
        """The nodes of an ADJUST node set as extended nodes (None: a distance, or no ADJUST).

        Collective: the node set is resolved on every process and joined over them.
        """
        if not isinstance(pair.adjust, NodeSurface):
            return None
        V = self.u.function_space
        comm = V.mesh.comm
        nodes = collectives.collectively(
            comm, resolve_slave, V, pair.adjust, what=f"{name} adjust",
            reference=self._surface_reference,
        ).nodes  # fmt: skip
        if self.halo is not None:  # the union over processes, as extended nodes
            held = self.halo.local_global[nodes]
            nodes = self.halo.find(np.unique(np.concatenate(comm.allgather(held))))
            nodes = nodes[nodes >= 0]
        return nodes

    def _planar_slave(self, name: str, pair: ContactPair, slave: SlaveSurface) -> SlaveSurface:
        """The pair's thickness and model on a 2D slave surface.

        In axisymmetry the nodes on the axis without ring area (line3 corners) get no spring
        (docs/method.md §17).
        """
        slave = dataclasses.replace(
            slave,
            thickness=pair.thickness,
            axisymmetric=pair.axisymmetric,
            area_weights=pair.area_weights,
        )
        if not pair.axisymmetric:
            return slave
        reference = self._reference if self.halo is None else self.halo.reference
        keep = slave_areas(slave, reference) > 0.0
        if np.all(keep):
            return slave
        details_logger.info(
            " %s: %d slave node(s) on the axis without ring area get no spring",
            name,
            int(np.count_nonzero(~keep)),
        )
        faceless = None if slave.faceless is None else slave.faceless[keep]
        return dataclasses.replace(slave, nodes=slave.nodes[keep], faceless=faceless)

    # -- checks ------------------------------------------------------------------------------------

    def _surfaces(self) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """(name, slave nodes, master face keys) of every pair, for checks and messages.

        A master face is known by its sorted nodes (:func:`_face_keys`), not by its facet: faces
        given by their nodes (``FaceNodesSurface``) and other processes' faces have none.
        """
        return [
            (s.pair.name or f"pair {i + 1}", s.slave.nodes, _face_keys(s.master_faces))
            for i, s in enumerate(self.states)
        ]

    def _check_distinct_pairs(self) -> None:
        """Pairs on the same slave nodes and master faces: an error if identical, else a warning.

        A slave node in two pairs that share master faces gets two springs on the same face: double
        stiffness and, for identical pairs, each pair reporting half the contact pressure.
        Collective.
        """
        comm = self.u.function_space.mesh.comm
        surfaces = self._surfaces()
        for i, (name_i, slave_i, master_i) in enumerate(surfaces):
            for name_j, slave_j, master_j in surfaces[i + 1 :]:
                comparable = master_i.dtype == master_j.dtype  # faces of one node count
                same = (
                    comparable
                    and np.array_equal(slave_i, slave_j)
                    and np.array_equal(master_i, master_j)
                )
                shared = np.intersect1d(slave_i, slave_j)
                if not comparable or not np.intersect1d(master_i, master_j).size:
                    shared = shared[:0]
                if comm.allreduce(bool(same), op=MPI.LAND):
                    raise ValueError(
                        f"ContactProblem: pairs '{name_i}' and '{name_j}' are the same (identical "
                        "slave nodes and master faces): every slave node would get two springs "
                        "and each pair would report half the contact pressure; remove one of them"
                    )
                count = comm.allreduce(int(shared.size), op=MPI.SUM)
                if count and comm.rank == 0:
                    where = ""
                    if shared.size:
                        x = self._reference[shared[0]]
                        where = f" (first at ({x[0]:.6g}, {x[1]:.6g}, {x[2]:.6g}))"
                    validation.warn(
                        f"ContactProblem: pairs '{name_i}' and '{name_j}' share {count} slave "
                        f"node(s) and master faces{where}: those nodes can get two springs on the "
                        "same face (double stiffness and force)"
                    )

    def _check_finite(self) -> None:
        """A non-finite displacement at a contact node: a ValueError naming node and position.

        Collective: every process raises or none does.
        """
        surfaces = []
        bs = self.u.function_space.dofmap.index_map_bs
        num_local = self.u.x.array.size // bs  # halo nodes are checked by their owners
        for (name, slave, _), state in zip(self._surfaces(), self.states):
            master = state.master_faces.nodes
            surfaces += [(f"{name} slave", slave), (f"{name} master", master[master < num_local])]
        values = self.u.x.array.reshape(-1, bs)
        error = None
        for name, nodes in surfaces:
            bad = nodes[~np.all(np.isfinite(values[nodes]), axis=1)]
            if bad.size:
                x, d = self._reference[bad[0]], values[bad[0]]
                error = ValueError(
                    f"the displacement u is not finite at {bad.size} node(s) of the {name} "
                    f"surface, first at node {int(bad[0])} (reference position ({x[0]:.6g}, "
                    f"{x[1]:.6g}, {x[2]:.6g}), u = ({d[0]:.6g}, {d[1]:.6g}, {d[2]:.6g})); set u "
                    "to finite values before solving"
                )
                break
        validation.raise_collectively(self.u.function_space.mesh.comm, error)

    # -- state -------------------------------------------------------------------------------------

    @property
    def reference(self) -> np.ndarray:
        """Reference coordinates of the nodes (local with ghosts, then the halo's), shape (N, 3)."""
        return self._reference

    @property
    def small_sliding(self) -> bool:
        """True when no pair is re-paired inside increments (all pairs small sliding)."""
        return all(self.is_small_sliding(s) for s in self.states)

    def is_small_sliding(self, state: PairState) -> bool:
        """Whether the pair of ``state`` is paired at increment starts only."""
        if self.small_sliding_rule == "last_pair":
            return bool(self.states[-1].pair.small_sliding)
        return bool(state.pair.small_sliding)

    @property
    def has_friction(self) -> bool:
        """Whether any pair has friction now (the Jacobian is then unsymmetric)."""
        return any(s.pair.interaction.friction is not None for s in self.states)

    @property
    def face_changes(self) -> int:
        """Slave nodes that kept a spring at the last pairing but moved to another master face."""
        return sum(s.face_changes for s in self.states)

    @property
    def pair_numbers(self) -> list[int]:
        """The pair (0-based, in the problem's order) of each state.

        The states of one master's face types share it (docs/method.md §38.8).
        """
        numbers: dict[int, int] = {}
        return [numbers.setdefault(id(s.pair), len(numbers)) for s in self.states]

    @property
    def num_springs(self) -> int:
        """Contact spring elements of this process over all pairs."""
        return sum(s.num_springs for s in self.states)

    def current_coordinates(self) -> np.ndarray:
        """Node coordinates X + u (local nodes with ghosts, then the halo's). Collective."""
        return self._reference + self._displacement()

    def _displacement(self) -> np.ndarray:
        """u at the local nodes with ghosts, then at the halo's, shape (N, 3). Collective."""
        return self.nodal_vectors(self.u)

    def nodal_vectors(self, f: dolfinx.fem.Function) -> np.ndarray:
        """A Function on u's space at the local nodes with ghosts, then the halo's (N, 3).

        Collective (e.g. the velocity of the contact damping, docs/method.md §29).
        """
        if self.halo is not None:
            return self.halo.displacement(f)
        return planar_padded(f.x.array.reshape(-1, f.function_space.dofmap.index_map_bs))

    def _halo_grew(self) -> None:
        """Nodes were appended to the halo (a master patch grew, docs/method.md §14.8). Collective.

        The scatter, the contact numbering and the increment-start displacement follow.
        """
        known = self._increment_start_u.shape[0]
        self.halo.destroy()  # rebuilt on next use, with the new nodes
        self._reference = self.halo.reference
        self._extend_numbering(self.halo)
        start = compat.petsc_vector(self.u).duplicate()
        start.array[:] = self._increment_start_u[: self.halo.num_owned].ravel()
        extra = self.halo.values(start)[known - self.halo.num_local :]
        start.destroy()
        self._increment_start_u = np.vstack([self._increment_start_u, extra])

    def gap_shift(self, state: PairState, slave_index: np.ndarray) -> np.ndarray | float:
        """g0 (1 - tau) in static steps, 0 otherwise (docs/method.md §3.5, §11.6)."""
        if not self.static:
            return 0.0
        return state.overlap[slave_index] * (1.0 - self.time_fraction)

    def reserved_blocks(self) -> list[SpringBlocks]:
        """Couplings a new matrix reserves beyond the current springs.

        Every slave node that the last pairing located, with the faces around its face, so that
        nodes moving to a neighbouring face or coming into contact need no new pattern (and no
        new symbolic factorization).
        """
        blocks = []
        for state in self.states:
            if state.found_face is None:
                continue
            located = np.flatnonzero(state.found_face >= 0)
            which, patch = state.master.face_patches(state.found_face[located])
            nodes = np.hstack(
                [state.master_faces.faces[patch], state.slave.nodes[located[which]][:, None]]
            )
            blocks.append(SpringBlocks(nodes, nodes))
        return blocks

    def destroy(self) -> None:
        """Release the halo's PETSc objects. Collective."""
        if self.halo is not None:
            self.halo.destroy()

    # -- schedule ----------------------------------------------------------------------------------

    def begin_step(self) -> None:
        """A new step starts (ends the linear overlap ramp of step 1)."""
        self.step_count += 1
        if self.step_count > 1:
            for state in self.states:
                state.overlap[:] = 0.0

    def begin_increment(self, time_fraction: float, *, static: bool) -> None:
        """An increment starts at the last converged displacement (docs/method.md §3.5).

        Checks the displacement at the contact nodes (collectively), keeps it as the friction
        anchors' start and ends the overlap ramp where it ends.
        """
        self._check_finite()
        self.time_fraction = float(time_fraction)
        self.static = static
        self._increment_start_u = self._displacement().copy()  # halo nodes too: anchors
        keep = self.overlap_ramp == "linear" and self.step_count <= 1 and static
        for state in self.states:
            if not keep:
                state.overlap[:] = 0.0
            state.friction.begin_increment()

    def end_increment(self) -> None:
        """Accept the converged increment: commit the friction state (docs/method.md §11.3).

        States sharing a friction history (the face types of one master, §38.8) commit it once
        with all their springs.
        """
        shared: dict[int, tuple[FrictionState, list[np.ndarray]]] = {}
        for state in self.states:
            shared.setdefault(id(state.friction), (state.friction, []))[1].append(
                state.spring_slave
            )
        for friction, springs in shared.values():
            friction.commit(np.concatenate(springs))

    # -- pairing -----------------------------------------------------------------------------------

    def pair(
        self, *, record_overlap: bool = False, large_sliding_only: bool = False
    ) -> tuple[int, int]:
        """Pair every slave node with a master face at the current displacement. Collective.

        Args:
            record_overlap: Record the initial overlap and ADJUST (first pairing of the analysis).
            large_sliding_only: Re-pair only the pairs without small sliding.

        Returns:
            The springs and the face changes (:attr:`face_changes`) summed over the processes.
        """
        before = {id(state): state.spring_slave for state in self.states}
        coords = self.current_coordinates()
        comm = self.u.function_space.mesh.comm
        with collectives.collective_errors(
            comm
        ):  # an error on one process is raised on all (§14.4)
            for state in self.states:
                if large_sliding_only and self.is_small_sliding(state):
                    continue
                self._pair_one(state, coords, record_overlap)
                if record_overlap and state.pair.adjust is not None:  # ADJUST may have moved nodes
                    collectives.checkpoint(comm)
                    coords = self.current_coordinates()
        self._count_changes_between_types(before)
        count, changes = (
            int(v) for v in comm.allreduce(np.array([self.num_springs, self.face_changes]))
        )
        return count, changes

    def _count_changes_between_types(self, before: dict[int, np.ndarray]) -> None:
        """Add to ``face_changes`` the nodes that moved between a master's face types (§38.8).

        The states of one master's face types share its friction history; a slave node whose
        spring moved from one of them to another changed its face.
        """
        siblings: dict[int, list[PairState]] = {}
        for state in self.states:
            siblings.setdefault(id(state.friction), []).append(state)
        for group in siblings.values():
            if len(group) < 2:
                continue
            for state in group:
                others = [before[id(o)] for o in group if o is not state]
                moved = np.intersect1d(state.spring_slave, np.concatenate(others))
                state.face_changes += int(moved.size)

    def _pair_one(self, state: PairState, coords: np.ndarray, record_overlap: bool) -> None:
        empty = np.empty(0, dtype=np.int64)
        if not state.pair.active:
            state.spring_slave, state.spring_face, state.spring_area, state.xi = (
                empty,
                empty,
                np.empty(0),
                None,
            )
            state.was_active = False
            state.held_springs, state.held_areas = empty, None
            return
        if not state.was_active:  # reactivated: a fresh friction history (ccx keeps the old one)
            if self.reset_friction_on_separation:
                state.friction.reset()
            state.was_active = True
        previous = np.full(state.slave.nodes.size, -1, dtype=np.int64)
        previous[state.spring_slave] = state.spring_face
        found, face, areas, evaluation = self._search(state, coords, previous)
        if record_overlap and state.pair.adjust is not None:
            collectives.checkpoint(self.u.function_space.mesh.comm)  # before ADJUST's collectives
        if (
            record_overlap
            and state.pair.adjust is not None
            and self._adjust(state, found, evaluation)
        ):
            coords = self.current_coordinates()
            found, face, areas, evaluation = self._search(state, coords, previous)
        state.found_face = face
        gap = evaluation.gap
        if record_overlap and isinstance(state.pair.master, RigidSurface):
            self._record_rigid_overlap(state, coords, previous)
        elif record_overlap:
            state.overlap[found] = np.minimum(gap, 0.0)
        create = self._creates_spring(state, found, gap, areas)
        state.spring_slave = found[create]
        state.spring_face = face[found][create].astype(np.int64)
        state.spring_area = areas[found][
            create
        ]  # 0 = no slave face: springs.py applies the fallback
        state.xi = evaluation.xi[create]
        state.held_springs = (
            np.flatnonzero(state.spring_area == 0.0) if state.pair.hold_fallback_area else empty
        )
        state.held_areas = None
        if state.pair.interaction.friction is not None:
            fresh = state.friction.fresh(state.spring_slave)
            if np.any(fresh):  # anchor at the increment start (docs/method.md §11.3)
                u = self._increment_start_u
                nodes = state.element_nodes[fresh]
                phi = evaluation.phi[create][fresh]
                a = u[nodes[:, -1]] - np.einsum("nj,nji->ni", phi, u[nodes[:, :-1]])
                state.friction.anchor(state.spring_slave[fresh], a)
        current = np.full(state.slave.nodes.size, -1, dtype=np.int64)
        current[state.spring_slave] = state.spring_face
        state.face_changes = int(
            np.count_nonzero((previous >= 0) & (current >= 0) & (previous != current))
        )

    def _record_rigid_overlap(
        self, state: PairState, coords: np.ndarray, previous: np.ndarray
    ) -> None:
        """The initial overlap on a rigid master at its place at the start of the step (§3.5).

        The pairing sees a rigid master where its motion puts it at the end of the increment; a
        meshed master moved by Dirichlet conditions is still at its start when the first pairing
        records the overlap, and so is the rigid one here: only what overlaps before any motion
        is ramped, the motion's own penetration acts in full.
        """
        end = self.time_fraction
        self.time_fraction = 0.0
        try:
            found, _, _, evaluation = self._search(state, coords, previous)
        finally:
            self.time_fraction = end
        state.overlap[found] = np.minimum(evaluation.gap, 0.0)

    def _search(
        self, state: PairState, coords: np.ndarray, previous: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, SpringEvaluation]:
        """Master face of every slave node at ``coords`` (``previous``: current face or -1).

        Returns the slave indices with a face, the face of every slave node (-1: none), the spring
        areas of all slave nodes, and the springs' kinematics (no tangent) of the found nodes.
        """
        comm = self.u.function_space.mesh.comm
        areas = slave_areas(state.slave, coords)
        if state.master.collective:
            collectives.checkpoint(comm)  # the patch's update is collective (§14.4)
        state.master.update(coords)
        points = coords[state.slave.nodes]
        tolerances = np.where(areas > 0, SEARCH_TOLERANCE * np.sqrt(areas), 0.0)
        start, frame = None, None
        if self.walk_from_previous_face:
            collectives.checkpoint(comm)  # the tie frame sums over the processes
            start, frame = previous, self._tie_frame(state, points, areas)
        options = {"tie_frame": frame, "ccx_ties": not self.walk_from_previous_face}
        face = state.master.locate(
            points, tolerances, max_depth=self.max_depth, start_faces=start, **options
        )
        # A patch too small somewhere (§14.8): it grew, the halo and the numbering follow.
        while master_exchange.enlarge(state.master, face, self.current_coordinates):
            self._halo_grew()
            state.master_faces = state.master.faces
            coords = self.current_coordinates()
            state.master.update(coords)
            face = state.master.locate(
                points, tolerances, max_depth=self.max_depth, start_faces=start, **options
            )
        found = np.flatnonzero(face >= 0)
        evaluation = state.master.evaluate_springs(
            state.master_faces.face_type,
            coords[state.master_faces.faces[face[found]]],
            points[found],
            areas[found],
            state.pair.interaction.law,
            tangent=False,
            xi0=self._previous_xi(state, found, face),
        )
        return found, face, areas, evaluation

    def _tie_frame(
        self, state: PairState, points: np.ndarray, areas: np.ndarray
    ) -> TieFrame | None:
        """Frame of master surface and slave nodes deciding search ties (docs/method.md §3.2).

        Collective: the slave nodes' moments are summed over the processes.
        """
        moments = state.master.surface_moments()
        if moments is None:
            return None  # a rigid master: one face, no ties
        origin, moments = moments
        slave = point_moments(points, areas, origin)
        comm = self.u.function_space.mesh.comm
        return frame_from_moments(moments + comm.allreduce(slave, op=MPI.SUM), origin)

    def _adjust(self, state: PairState, found: np.ndarray, evaluation: SpringEvaluation) -> int:
        """ADJUST: move the selected slave nodes onto the master (docs/method.md §11.5)."""
        adjust = state.pair.adjust
        in_set = None
        if state.adjust_nodes is not None:
            in_set = np.isin(state.slave.nodes[found], state.adjust_nodes)
        move = adjusted_nodes(evaluation.gap, None if in_set is not None else float(adjust), in_set)
        count = self.u.function_space.mesh.comm.allreduce(int(np.count_nonzero(move)))
        if count:  # on every process: the moves reach ghost and halo copies (§14.6)
            delta = planar_padded(-evaluation.gap[move, None] * evaluation.normal[move])
            move_reference_nodes(
                self.u.function_space,
                self._reference,
                state.slave.nodes[found[move]],
                delta,
                self.halo,
            )
            details_logger.info(" ADJUST: %d slave node(s) moved onto the master", count)
        self.adjusted += count
        return count

    def _creates_spring(
        self, state: PairState, found: np.ndarray, gap: np.ndarray, areas: np.ndarray
    ) -> np.ndarray:
        """Which of the found slave nodes get a spring: effective gap within the law's cutoff."""
        cutoff = state.pair.interaction.law.cutoff(areas[found])
        return gap - self.gap_shift(state, found) <= cutoff

    def unpaired_contacts(self) -> int:
        """Slave nodes that a pairing now would give a spring but that have none. Collective.

        For example nodes that penetrated after the pairing froze at iteration 8.
        """
        coords = self.current_coordinates()
        count = 0
        comm = self.u.function_space.mesh.comm
        with collectives.collective_errors(comm):
            for state in self.states:
                if not state.pair.active:
                    continue
                current = np.full(state.slave.nodes.size, -1, dtype=np.int64)
                current[state.spring_slave] = state.spring_face
                found, _, areas, evaluation = self._search(state, coords, current)
                create = self._creates_spring(state, found, evaluation.gap, areas)
                count += int(np.count_nonzero(create & (current[found] < 0)))
        return comm.allreduce(count)

    @staticmethod
    def _previous_xi(state: PairState, found: np.ndarray, face: np.ndarray) -> np.ndarray:
        """Projection start points: the last one where a node keeps its face, else the centre."""
        xi0 = np.tile(state.master_faces.face_type.center, (found.size, 1))
        if state.xi is not None and state.num_springs:
            previous_face = np.full(state.slave.nodes.size, -1, dtype=np.int64)
            previous_face[state.spring_slave] = state.spring_face
            previous_xi = np.zeros((state.slave.nodes.size, xi0.shape[1]))
            previous_xi[state.spring_slave] = state.xi
            same = previous_face[found] == face[found]
            xi0[same] = previous_xi[found[same]]
        return xi0


def _face_keys(faces: SurfaceFaces) -> np.ndarray:
    """Sorted unique faces as one scalar each (their sorted nodes), for set comparisons.

    A rigid master's face has no nodes: no keys, as its facets were none.
    """
    rows = np.ascontiguousarray(np.sort(faces.faces.astype(np.int64), axis=1))
    if rows.shape[1] == 0:
        return np.zeros(0, dtype=np.dtype((np.void, rows.dtype.itemsize)))
    key = np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))
    return np.unique(rows.view(key).ravel())


def slave_areas(slave: SlaveSurface, coords: np.ndarray) -> np.ndarray:
    """Spring areas of the slave nodes (0 for ``faceless`` nodes: the fallback applies)."""
    faces = slave.faces
    if isinstance(faces.face_type, EdgeType) and slave.area_weights == "ccx":  # §23.3
        areas = ccx_edge_spring_areas(
            faces.face_type, faces.faces, coords, slave.nodes,
            thickness=slave.thickness, axisymmetric=slave.axisymmetric,
        )  # fmt: skip
    elif isinstance(faces.face_type, EdgeType) and slave.axisymmetric:  # rings (§17.2)
        areas = axisymmetric_edge_spring_areas(faces.face_type, faces.faces, coords, slave.nodes)
    elif isinstance(faces.face_type, EdgeType):  # 2D: tributary length times the thickness
        areas = slave.thickness * edge_spring_areas(
            faces.face_type, faces.faces, coords, slave.nodes
        )
    else:  # each face type's shares (a C3D15 surface of triangles and quadrilaterals, §38)
        areas = sum(
            spring_areas(group.face_type, group.faces, coords, slave.nodes)
            for group in slave.face_groups
        )
    if slave.faceless is not None:
        areas[slave.faceless] = 0.0
    return areas
