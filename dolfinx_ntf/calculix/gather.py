"""The deck runner's results in ccx numbering, the same on every process (docs/method.md §14.5).

Each process contributes what it owns (nodes, cells, springs); the pieces are allgathered and put
in ccx order (rows of the deck's nodes, element numbers, slave nodes), and the sums of element and
spring forces at a node (``RF``) are taken in that order. The printed values therefore do not
depend on the partition: the files of a run on N processes are those of the serial run. On one
process the same code runs without communication.
"""

from __future__ import annotations

import dataclasses
import typing

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.fem.serendipity import element_forces_on_nodes
from dolfinx_ntf.fem.serendipity_quad import quad_forces_on_nodes
from dolfinx_ntf.fem.serendipity_wedge import wedge_forces_on_nodes
from dolfinx_ntf.kernels.discrete_springs import AxialSpring

from .deck import Deck
from .model import CalculixModel

__all__ = ["CcxNumbering", "Discard", "match_rows", "surface_face_nodes"]


class Discard:
    """A file writer that writes nothing (processes other than rank 0)."""

    def __getattr__(self, name: str) -> typing.Callable[..., None]:
        return lambda *args, **kwargs: None


def match_rows(table: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Row of ``table`` with the same set of numbers as each row of ``query`` (-1 if none).

    The first such row when several match.
    """
    if query.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    keys = np.vstack([np.sort(table, axis=1), np.sort(query, axis=1)])
    _, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    first = np.full(int(inverse.max()) + 1, -1, dtype=np.int64)
    n = table.shape[0]
    first[inverse[:n][::-1]] = np.arange(n)[::-1]
    return first[inverse[n:]]


def surface_face_nodes(deck: Deck, block, name: str) -> np.ndarray:
    """Ccx node numbers ``(F, n)`` of an element-face surface's faces, in ccx face order.

    C3D15's triangles (padded to 8 nodes in the element table) give 6 columns; in a surface of
    triangles and quadrilaterals (a master, docs/method.md §38.8) the triangles' last two are -1.
    """
    surface = deck.surfaces[name]
    order = np.argsort(block.ids)
    rows = order[np.searchsorted(block.ids, surface.elements, sorter=order)]
    local = block.type.faces[surface.faces - 1]
    sizes = block.type.face_sizes[surface.faces - 1]
    width = int(sizes.max()) if sizes.size else local.shape[1]
    nodes = block.connectivity[rows[:, None], local[:, :width]]
    if sizes.size and sizes.min() < width:
        nodes = np.where(np.arange(width) < sizes[:, None], nodes, -1)
    return nodes


def _padded(values: np.ndarray) -> np.ndarray:
    """Vectors ``(..., 2)`` of a 2D model with a zero z component ``(..., 3)``; 3D unchanged."""
    if values.shape[-1] == 3:
        return values
    return np.concatenate([values, np.zeros((*values.shape[:-1], 1))], axis=-1)


def _broken(
    form: ufl.Form, V: dolfinx.fem.FunctionSpace
) -> tuple[compat.Form, dolfinx.fem.FunctionSpace]:
    """``form`` tested with the discontinuous space of ``V``'s degree: per-element vectors."""
    mesh = V.mesh
    tensor = (dolfinx.mesh.CellType.hexahedron, dolfinx.mesh.CellType.quadrilateral)
    family = "DQ" if mesh.topology.cell_type in tensor else "DG"
    W = compat.vector_space(mesh, family, compat.space_degree(V))
    (argument,) = form.arguments()
    return dolfinx.fem.form(ufl.replace(form, {argument: ufl.TestFunction(W)})), W


class CcxNumbering:
    """This process's nodes, cells and springs in ccx numbering, and their allgather.

    Args:
        model: The deck's model.
        internal: The bulk internal force form (test function on ``model.V``), whose element
            vectors make the ``RF`` output.
    """

    def __init__(self, model: CalculixModel, internal: ufl.Form) -> None:
        self.model, self.deck = model, model.deck
        V = model.V
        self.comm: MPI.Comm = V.mesh.comm
        index_map = V.dofmap.index_map
        num_owned = index_map.size_local
        # owned dofs at deck nodes (not C3D20's added face and cell centres, dof_node -1)
        self._owned_dofs = np.flatnonzero(model.dof_node[:num_owned] >= 0)
        self.owned_rows = self.deck.node_index(model.dof_node[self._owned_dofs])
        self._global_node = model.dof_node  # ccx node of each global block dof
        if self.comm.size > 1:
            owned = index_map.local_to_global(np.arange(num_owned, dtype=np.int32))
            self._global_node = np.zeros(index_map.size_global, dtype=np.int64)
            for g, nodes in self.comm.allgather((owned, model.dof_node[:num_owned])):
                self._global_node[g] = nodes
        tdim = V.mesh.topology.dim
        self.num_owned_cells = V.mesh.topology.index_map(tdim).size_local
        self._internal = internal
        self._form: compat.Form | None = None  # compiled on first use
        self._W: dolfinx.fem.FunctionSpace | None = None
        self.block = self.deck.elements[model.element_type.name]
        self._faces: dict[str, np.ndarray] = {}

    # -- gathering -------------------------------------------------------------------------------

    def allgather(self, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
        """Every process's arrays, concatenated along the first axis in rank order."""
        if self.comm.size == 1:
            return arrays
        parts = self.comm.allgather(arrays)
        return tuple(np.concatenate([p[k] for p in parts]) for k in range(len(arrays)))

    def nodal(self, values: np.ndarray) -> np.ndarray:
        """A per-dof array ``(num_dofs, k)`` at every deck node ``(N, k)`` (zero off the mesh)."""
        owned = values[self._owned_dofs]
        rows, owned = self.allgather(self.owned_rows, owned)
        out = np.zeros((self.deck.node_ids.size, *values.shape[1:]))
        out[rows] = owned
        return out

    def element_values(
        self,
        element_ids: np.ndarray,
        evaluate: typing.Callable[[np.ndarray], np.ndarray],
        shape: tuple[int, ...],
    ) -> np.ndarray:
        """``evaluate(cells)`` of shape ``(cells, *shape)`` at ccx elements, in their order.

        Each element is evaluated on the process owning its cell.
        """
        cells = self.model.element_cells(element_ids)
        mine = np.flatnonzero((cells >= 0) & (cells < self.num_owned_cells))
        values = evaluate(cells[mine]) if mine.size else np.zeros((0, *shape))
        positions, values = self.allgather(mine, values.reshape(-1, *shape))
        out = np.zeros((np.asarray(element_ids).size, *shape))
        out[positions] = values
        return out

    def ccx_nodes(self, problem: ContactProblem, nodes: np.ndarray) -> np.ndarray:
        """Ccx node numbers of the problem's (halo-extended, docs/method.md §14.1) nodes."""
        if problem.halo is None:
            return self.model.dof_node[nodes]
        return self._global_node[problem.halo.global_nodes[nodes]]

    def master_faces(self, surface: str, nodes: np.ndarray) -> np.ndarray:
        """Ccx node numbers of master faces ``(k, n)`` (ccx numbers, any order), in ccx order."""
        if surface not in self._faces:
            self._faces[surface] = surface_face_nodes(self.deck, self.block, surface)
        table = self._faces[surface]
        rows = match_rows(table, nodes)
        if np.any(rows < 0):
            raise RuntimeError(f"a contact face is not a face of surface {surface}")
        return table[rows]

    # -- forces ----------------------------------------------------------------------------------

    def _element_forces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Owned elements of this process: numbers, node rows ``(E, n)``, forces ``(E, n, 3)``."""
        if self._form is None:
            self._form, self._W = _broken(self._internal, self.model.V)
        vector = dolfinx.fem.petsc.assemble_vector(self._form)
        gdim = self.model.gdim  # 2 for ccx's 2D elements: padded with z = 0 below
        forces = vector.array_r.reshape(-1, gdim).copy()  # broken dofs: one cell each, no sum
        vector.destroy()
        cells = np.arange(self.num_owned_cells)
        values = forces[compat.cell_dofs(self._W)[cells]]
        dofs = compat.cell_dofs(self.model.V)[cells]
        modes = self.model.incompatible_modes
        if modes is not None:  # C3D8I: the condensed modes' forces (docs/method.md §22)
            self.model.u.x.scatter_forward()
            x = compat.petsc_vector(self.model.u)
            extra = np.zeros((self.num_owned_cells, 24))
            extra[modes.cells] = modes.cell_forces(x)
            values = values + extra.reshape(-1, 8, 3)
        if self.model.element_type.num_nodes == 20:  # C3D20: centre forces on the 20 nodes
            values = element_forces_on_nodes(forces.ravel(), self._W).reshape(-1, 20, 3)
            dofs = dofs[:, :20]
        elif self.model.element_type.name == "C3D15":  # face-centre forces on the 15 nodes
            values = wedge_forces_on_nodes(forces.ravel(), self._W).reshape(-1, 15, 3)
            dofs = dofs[:, :15]
        elif gdim == 2 and self.model.element_type.num_nodes == 8:  # CPE8: the centre's too
            values = quad_forces_on_nodes(forces.ravel(), self._W).reshape(-1, 8, 2)
            dofs = dofs[:, :8]
        rows = self.deck.node_index(self.model.dof_node[dofs])
        return self.model.cell_element[cells], rows, _padded(values)

    def _spring_forces(self, problem: ContactProblem) -> tuple[np.ndarray, ...]:
        """This process's springs: (pair, slave node, position) keys, node rows and forces."""
        keys, rows, values = (
            [np.zeros((0, 3), np.int64)],
            [np.zeros(0, np.int64)],
            [np.zeros((0, 3))],
        )
        numbers = problem.pairing.pair_numbers  # a master of several face types: one (§38.8)
        for p, state in zip(numbers, problem.states, strict=True):
            if state.evaluation is None or not state.num_springs:
                continue
            nodes = self.ccx_nodes(problem, state.element_nodes)
            k, m = nodes.shape
            key = np.empty((k, m, 3), dtype=np.int64)
            key[..., 0], key[..., 1], key[..., 2] = p, nodes[:, -1:], np.arange(m)
            keys.append(key.reshape(-1, 3))
            rows.append(self.deck.node_index(nodes).ravel())
            values.append(_padded(state.evaluation.forces.reshape(-1, self.model.gdim)))
        return np.concatenate(keys), np.concatenate(rows), np.vstack(values)

    def nodal_forces(self, problem: ContactProblem) -> np.ndarray:
        """Internal force of the elements plus the springs at every deck node ``(N, 3)``.

        Summed in ccx order (elements by number, springs by pair and slave node), whatever the
        partition. Collective. At the free components of the nodes of node-based slave surfaces
        of 2D elements only the springs, as ccx prints them (docs/method.md §26.3). C3D20/C3D20R:
        each 27-node cell's face- and cell-centre forces move to its 20 ccx nodes first
        (``serendipity.element_forces_on_nodes``, §13.5, §14.10).
        """
        elements, rows, values = self.allgather(*self._element_forces())
        order = np.argsort(elements, kind="stable")
        bulk = np.zeros((self.deck.node_ids.size, 3))
        np.add.at(bulk, rows[order].ravel(), values[order].reshape(-1, 3))
        keys, rows, values = self.allgather(*self._spring_forces(problem))
        order = np.lexsort(keys.T[::-1])
        contact = np.zeros_like(bulk)
        np.add.at(contact, rows[order], values[order])
        if self.model.spring_only_nodes is not None:  # ccx: the 2D node's spring only (§26.3)
            nodes, component = self.model.spring_only_nodes.T
            rows = self.deck.node_index(nodes)
            bulk[rows, component] = -2.0 * contact[rows, component]  # ccx's sign: on the spring
        return bulk + contact + self._discrete_spring_forces()

    def _discrete_spring_forces(self) -> np.ndarray:
        """``(N, 3)`` forces of the spring elements (SPRINGA, SPRING1, SPRING2) at deck nodes.

        Every process evaluates every spring (docs/method.md §18.2): no gathering. As ccx 2.20
        prints them (measured): SPRINGA's force of the current line and length also in steps
        without NLGEOM, whose solution takes the initial line (docs/method.md §18.3).
        """
        forces = np.zeros((self.deck.node_ids.size, 3))
        x = compat.petsc_vector(self.model.u)
        for group, springs in zip(self.deck.springs, self.model.springs):
            element = springs.element
            if isinstance(element, AxialSpring):
                element = dataclasses.replace(element, nlgeom=True)
            ends = springs.end_forces(x, element)[:, : group.connectivity.shape[1]]
            np.add.at(forces, self.deck.node_index(group.connectivity).ravel(), ends.reshape(-1, 3))
        return forces
