"""Contact results per slave node: tables for scripts, dolfinx Functions, and XDMF files.

- :func:`contact_results`: one :class:`ContactResults` table per pair (this process's springs).
- :class:`ContactFields`: contact pressure, clearance and status as dolfinx Functions on the nodes
  of the displacement space (for ParaView, for UFL expressions, for interpolation), and the
  friction fields shear traction and slip as vector Functions on the displacement space.
- :class:`ContactWriter`: the displacement and the fields to an XDMF file, at any time
  (also before the first solve).

All of them read the springs of the problem's current pairing, evaluated at the current
displacement (docs/method.md §8).
"""

from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.io

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.pair import PairState
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.fem.pressure_recovery import BoundaryPressure

__all__ = ["RECOVERY_FIELDS", "ContactFields", "ContactResults", "ContactWriter", "contact_results"]

#: Key of the :class:`ContactFields` that ``contact_results(recovered=True)`` keeps in the
#: problem's :attr:`~dolfinx_ntf.ContactProblem.output_cache` (its compiled forms are reused).
RECOVERY_FIELDS = "recovery_fields"


@dataclass(frozen=True)
class ContactResults:
    """Per-spring results of one pair, in spring order (slave nodes ascending, like ccx's).

    One row per contact spring of this process; a slave node without a spring (open beyond the
    cutoff, or outside the master) has no row. Units are those of the mesh and the material.

    Attributes:
        pair: The pair's name (``"pair 1"``, ... when it has none).
        node: ``(N,)`` slave node of each spring: the index of the node in the displacement space
            ``V`` (a block dof, this process's local numbering), so that ``u.x.array.reshape(-1,
            d)[node]`` is its displacement and ``V.tabulate_dof_coordinates()[node]`` its
            reference position.
        position: ``(N, d)`` current position ``X + u`` of the slave node. Vectors have ``d``
            components, the dimension of the mesh: 3, or 2 on a 2D mesh (docs/guide/two_d.md).
        area: ``(N,)`` spring area ``A_p`` (docs/method.md §2.2).
        clearance: ``(N,)`` ``g_eff``: positive is an open gap, negative a penetration (ccx's
            CDIS).
        pressure: ``(N,)`` ``F_N / A_p``, compression positive (ccx's CSTR); the linear law gives
            a small tension (negative) inside the cutoff.
        normal_force: ``(N,)`` ``F_N = A_p p(d)``.
        energy: ``(N,)`` normal spring energy (ccx's CELS without friction, docs/method.md §8.3).
        force: ``(N, d)`` contact force on the slave node, ``F_N n - F_T`` (the master pushes the
            slave away along the master normal, and friction resists the relative motion).
        normal: ``(N, d)`` unit normal of the master face at the projection point.
        shear: ``(N, d)`` shear traction ``F_T / A_p``: the tangential force per area the slave
            exerts on the master (ccx's CSTR tangential columns); zero without friction.
        slip: ``(N, d)`` accumulated tangential relative displacement ``t`` of the slave node
            relative to the master (ccx's CDIS tangential columns); zero without friction.
        sliding: ``(N,)`` True where the spring slips (``|F_T| = mu F_N``), False in stick.
        friction_energy: ``(N,)`` elastic energy of the tangential spring ``|F_T|^2/(2 K_t)``
            (CalculiX 2.20's CELS adds twice this, docs/method.md §11.4).
        recovered_pressure: ``(N,)`` the recovered contact pressure ``p_h`` at the slave node
            (docs/method.md §15.3), with ``contact_results(problem, recovered=True)``; else None.
    """

    pair: str
    node: np.ndarray
    position: np.ndarray
    area: np.ndarray
    clearance: np.ndarray
    pressure: np.ndarray
    normal_force: np.ndarray
    energy: np.ndarray
    force: np.ndarray
    normal: np.ndarray
    shear: np.ndarray | None = None
    slip: np.ndarray | None = None
    sliding: np.ndarray | None = None
    friction_energy: np.ndarray | None = None
    recovered_pressure: np.ndarray | None = None


def _evaluated(problem: ContactProblem) -> None:
    """Evaluate the springs at the current displacement if an evaluation is missing or stale.

    Collective: a process with stale springs makes all evaluate (docs/method.md §14).
    """
    stale = any(
        s.evaluation is None or s.evaluation.xi.shape[0] != s.num_springs
        for s in problem.pairing.states
    )
    if problem.u.function_space.mesh.comm.allreduce(stale, op=MPI.LOR):
        problem.evaluate(tangent=False)


def _pair_results(index: int, state: PairState, coords: np.ndarray, dim: int) -> ContactResults:
    """The table of one pair; vectors of ``dim`` components (coordinates are 3D, z = 0 in 2D)."""
    ev = state.evaluation
    nodes = state.slave.nodes[state.spring_slave]
    law = state.pair.interaction.law
    num = nodes.size
    tf = ev.tangential
    zeros = np.zeros((num, dim))
    return ContactResults(
        pair=state.pair.name or f"pair {index + 1}",
        node=nodes,
        position=coords[nodes, :dim],
        area=ev.area,
        clearance=-ev.overclosure,
        pressure=ev.normal_force / ev.area,
        normal_force=ev.normal_force,
        energy=law.energy(ev.overclosure, ev.area),
        force=-ev.forces[:, -1, :],
        normal=ev.normal,
        shear=zeros if tf is None else tf.force / ev.area[:, None],
        slip=zeros.copy() if tf is None else tf.t,
        sliding=np.zeros(num, dtype=bool) if tf is None else tf.sliding,
        friction_energy=np.zeros(num) if tf is None else tf.energy,
    )


def contact_results(problem: ContactProblem, *, recovered: bool = False) -> list[ContactResults]:
    """Results of every pair at the current pairing (local springs of this process).

    Before the first pairing (e.g. before any solve) every table is empty.

    Args:
        problem: The contact problem.
        recovered: Also give the recovered pressure at each slave node (docs/method.md §15.3):
            the projection of all pairs' spring forces onto the slave faces. Collective; the
            first call compiles its forms, later calls on the same problem reuse them.
    """
    validation.check_type(problem, ContactProblem, "contact_results: problem")
    _evaluated(problem)
    coords = problem.pairing.current_coordinates()
    dim = problem.u.function_space.dofmap.index_map_bs
    pairing = problem.pairing  # a master of several face types: a state per type (§38.8)
    results = [
        _pair_results(i, s, coords, dim)
        for i, s in zip(pairing.pair_numbers, pairing.states, strict=True)
    ]
    if recovered:
        fields = problem.output_cache.get(RECOVERY_FIELDS)
        if fields is None:
            fields = problem.output_cache[RECOVERY_FIELDS] = ContactFields(problem)
        else:
            fields.update()
        results = [
            dataclasses.replace(res, recovered_pressure=fields.recovery.at_nodes(res.node))
            for res in results
        ]
    return results


class ContactFields:
    """Contact pressure, clearance and status per slave node, as dolfinx Functions.

    The Functions live on the scalar Lagrange space of one displacement component (same mesh,
    degree and nodes as ``u``), so their values sit on the same nodes as ``u``'s:

    - ``pressure`` (name ``contact_pressure``): ``F_N / A_p`` of the node's spring, summed over the
      pairs the node belongs to; 0 at nodes without a spring.
    - ``clearance`` (name ``contact_clearance``): ``g_eff`` of the node's spring (negative =
      penetration); 0 at nodes without a spring (see ``status``).
    - ``status`` (name ``contact_status``): 1 where the node's spring is closed (``g_eff < 0``),
      0 where it is open or there is no spring.

    - ``recovered_pressure`` (name ``contact_pressure_recovered``): the spring forces turned into a
      traction field on the slave faces, ``∫ p_h phi_i ds = F_N,i`` (docs/method.md §15.3); unlike
      the nodal law values it stays meaningful on quadratic faces, and ``∫ p_h ds`` is the total
      normal force. It lives on its own copy of the scalar space.

    Call :meth:`update` after a solve (the writer does it before writing). Nodal pressures are
    spring forces over lumped areas: on unstructured linear tetrahedra they scatter by about
    +-15 % from node to node around a smooth distribution (docs/method.md §10).

    Args:
        problem: The contact problem.
    """

    def __init__(self, problem: ContactProblem) -> None:
        validation.check_type(problem, ContactProblem, "ContactFields: problem")
        self.problem = problem
        Q, dofs = compat.component_space(problem.u.function_space, 0)
        #: The scalar space of the fields.
        self.space = Q
        self._dim = problem.u.function_space.dofmap.index_map_bs  # 3, or 2 on a 2D mesh
        node_of_q = np.asarray(dofs) // self._dim
        self._q_of_node = np.full(problem.u.x.array.size // self._dim, -1, dtype=np.int64)
        self._q_of_node[node_of_q] = np.arange(node_of_q.size)
        self.pressure = dolfinx.fem.Function(Q, name="contact_pressure")
        self.clearance = dolfinx.fem.Function(Q, name="contact_clearance")
        self.status = dolfinx.fem.Function(Q, name="contact_status")
        V = problem.u.function_space
        #: Shear traction ``F_T / A_p`` (vector, on ``u``'s space; 0 without friction).
        self.shear = dolfinx.fem.Function(V, name="contact_shear")
        #: Accumulated tangential relative displacement ``t`` (vector, on ``u``'s space).
        self.slip = dolfinx.fem.Function(V, name="contact_slip")
        # -1: a facet of another process (docs/method.md §14.1)
        slave_facets = [f[f >= 0] for f in (s.slave.faces.facets for s in problem.pairing.states)]
        #: Projection of the spring forces onto the slave faces (docs/method.md §15.3).
        self.recovery = BoundaryPressure(
            problem.u.function_space,
            np.concatenate(slave_facets) if slave_facets else np.zeros(0, dtype=np.int32),
        )
        self.recovered_pressure = self.recovery.pressure
        self.update()

    @property
    def functions(self) -> tuple[dolfinx.fem.Function, dolfinx.fem.Function, dolfinx.fem.Function]:
        """``(pressure, clearance, status)``."""
        return self.pressure, self.clearance, self.status

    def at_nodes(self, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Values of ``(pressure, clearance, status)`` at nodes of the displacement space.

        Args:
            nodes: Block dof indices of ``u``'s space (as :attr:`ContactResults.node`).
        """
        q = self._q_of_node[np.asarray(nodes, dtype=np.int64)]
        return tuple(f.x.array[q].copy() for f in self.functions)

    def update(self) -> None:
        """Fill the Functions from the problem's current springs."""
        for f in (*self.functions, self.shear, self.slip):
            f.x.array[:] = 0.0
        shear = self.shear.x.array.reshape(-1, self._dim)
        slip = self.slip.x.array.reshape(-1, self._dim)
        nodes, forces = [], []
        states = self.problem.pairing.states
        for res, state in zip(contact_results(self.problem), states, strict=True):
            np.add.at(shear, res.node, res.shear)
            slip[res.node] = res.slip
            q = self._q_of_node[res.node]
            np.add.at(self.pressure.x.array, q, res.pressure)
            self.clearance.x.array[q] = res.clearance
            self.status.x.array[q] = np.maximum(
                self.status.x.array[q], (res.clearance < 0).astype(float)
            )
            nodes.append(res.node)
            # 2D: the recovery integrates over edge lengths, the springs carry length x thickness
            forces.append(res.normal_force / state.slave.thickness)
        self.recovery.from_forces(
            np.concatenate(nodes) if nodes else np.zeros(0, dtype=np.int64),
            np.concatenate(forces) if forces else np.zeros(0),
        )
        for f in (*self.functions, self.shear, self.slip):  # springs live on their slave's owner
            f.x.scatter_forward()


class ContactWriter:
    """Writes the displacement and the :class:`ContactFields` to an XDMF file (for ParaView).

    Each :meth:`write` adds a time step: ``u`` and ``contact_pressure``, ``contact_clearance``,
    ``contact_status``, ``contact_shear``, ``contact_slip`` and ``contact_pressure_recovered``. The
    initial state can be written before the first solve (zero fields). XDMF keeps vertex values
    only, so a P2 displacement loses its midside values in the file.

    Args:
        problem: The contact problem.
        path: The ``.xdmf`` file to create (with its ``.h5`` data file beside it); its folder must
            exist and be writable.
        comm: Communicator (default: the mesh's).
    """

    def __init__(
        self, problem: ContactProblem, path: str | typing.Any, comm: MPI.Comm | None = None
    ) -> None:
        validation.check_type(problem, ContactProblem, "ContactWriter: problem")
        mesh = problem.u.function_space.mesh
        comm = comm or mesh.comm
        path = validation.check_writable(path, comm, "ContactWriter")
        self.problem = problem
        #: The ``.xdmf`` file written.
        self.path = path
        self.fields = ContactFields(problem)
        self._closed = False
        try:
            self._file = dolfinx.io.XDMFFile(comm, str(path), "w")
        except RuntimeError as error:
            raise OSError(f"ContactWriter: cannot create {str(path)!r}: {error}") from error
        self._file.write_mesh(mesh)

    @property
    def pressure(self) -> dolfinx.fem.Function:
        """The contact pressure Function (see :class:`ContactFields`)."""
        return self.fields.pressure

    @property
    def clearance(self) -> dolfinx.fem.Function:
        """The contact clearance Function (see :class:`ContactFields`)."""
        return self.fields.clearance

    @property
    def status(self) -> dolfinx.fem.Function:
        """The contact status Function (see :class:`ContactFields`)."""
        return self.fields.status

    def update(self) -> None:
        """Fill the contact Functions from the problem's current springs."""
        self.fields.update()

    def write(self, t: float) -> None:
        """Write the displacement and the contact fields at time ``t``.

        Raises:
            ValueError: The writer is closed.
        """
        if self._closed:
            raise ValueError(f"ContactWriter.write: the writer of {self.path} is closed")
        self.fields.update()
        fields = self.fields
        for f in (
            self.problem.u,
            *fields.functions,
            fields.shear,
            fields.slip,
            fields.recovered_pressure,
        ):
            self._file.write_function(f, t)

    def close(self) -> None:
        """Close the file (a second call does nothing)."""
        if not self._closed:
            self._file.close()
            self._closed = True

    def __enter__(self) -> ContactWriter:
        return self

    def __exit__(self, *args: typing.Any) -> None:
        self.close()
