"""Contact results per slave node: tables for scripts and dolfinx Functions written to XDMF."""

from __future__ import annotations

import typing
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.io

from dolfinx_ntf.problem import ContactProblem, PairState

__all__ = ["ContactResults", "ContactWriter", "contact_results"]


@dataclass(frozen=True)
class ContactResults:
    """Per-spring results of one pair, in spring order (slave nodes ascending, like ccx's).

    ``clearance`` is g_eff (negative = penetration), ``pressure`` = F_N / A_p (compression
    positive), ``energy`` the spring energy of spec §8.1, ``force`` the contact force on the slave
    node (3-vector).
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


def _pair_results(index: int, state: PairState, coords: np.ndarray) -> ContactResults:
    ev = state.evaluation
    nodes = state.slave.nodes[state.spring_slave]
    law = state.pair.interaction.law
    if ev is None or ev.xi.shape[0] != nodes.size:
        raise RuntimeError("contact results requested before the springs were evaluated")
    return ContactResults(
        pair=state.pair.name or f"pair {index + 1}",
        node=nodes,
        position=coords[nodes],
        area=ev.area,
        clearance=-ev.overclosure,
        pressure=ev.normal_force / ev.area,
        normal_force=ev.normal_force,
        energy=law.energy(ev.overclosure, ev.area),
        force=-ev.forces[:, -1, :],
        normal=ev.normal,
    )


def contact_results(problem: ContactProblem) -> list[ContactResults]:
    """Results of every pair at the last evaluation (local springs of this process)."""
    coords = problem.current_coordinates()
    return [_pair_results(i, s, coords) for i, s in enumerate(problem.states)]


class ContactWriter:
    """Writes displacement, contact pressure, clearance and status to XDMF.

    XDMF keeps vertex values only, so use a P1 displacement space (P2 midside values are dropped by
    dolfinx).
    """

    def __init__(self, problem: ContactProblem, path: str, comm: MPI.Comm | None = None) -> None:
        u = problem.u
        mesh = u.function_space.mesh
        self.problem = problem
        self._file = dolfinx.io.XDMFFile(comm or mesh.comm, path, "w")
        self._file.write_mesh(mesh)
        Q, dofs = u.function_space.sub(0).collapse()
        self._node_of_q = np.asarray(dofs) // 3
        self._q_of_node = np.full(problem.u.x.array.size // 3, -1, dtype=np.int64)
        self._q_of_node[self._node_of_q] = np.arange(self._node_of_q.size)
        self.pressure = dolfinx.fem.Function(Q, name="contact_pressure")
        self.clearance = dolfinx.fem.Function(Q, name="contact_clearance")
        self.status = dolfinx.fem.Function(Q, name="contact_status")

    def update(self) -> None:
        """Fill the contact Functions from the problem's current springs."""
        for f in (self.pressure, self.clearance, self.status):
            f.x.array[:] = 0.0
        for res in contact_results(self.problem):
            q = self._q_of_node[res.node]
            self.pressure.x.array[q] += res.pressure
            self.clearance.x.array[q] = res.clearance
            self.status.x.array[q] = (res.clearance < 0).astype(float)

    def write(self, t: float) -> None:
        """Write all fields at time ``t``."""
        self.update()
        for f in (self.problem.u, self.pressure, self.clearance, self.status):
            self._file.write_function(f, t)

    def close(self) -> None:
        """Close the file."""
        self._file.close()

    def __enter__(self) -> ContactWriter:
        return self

    def __exit__(self, *args: typing.Any) -> None:
        self.close()
