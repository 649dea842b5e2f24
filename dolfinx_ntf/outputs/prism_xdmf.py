"""XDMF time series of point fields on an 18-node prism mesh (docs/method.md §43).

dolfinx 0.11 reads and solves on meshes of 18-node prisms (gmsh's 15- and 18-node prisms, C3D15,
docs/method.md §40) but writes none ("Could not find VTK string"). :class:`PrismXdmfFile` writes
such a mesh itself through :class:`~dolfinx_ntf.outputs.xdmf_cells.MixedXdmfFile`: every cell as
an XDMF ``Wedge_18`` (ParaView's ``VTK_BIQUADRATIC_QUADRATIC_WEDGE``) of its 18 geometry nodes in
VTK's order (:data:`PRISM18_TO_VTK`), and per time step the nodal values of degree-2 Lagrange
Functions (the displacement of :func:`~dolfinx_ntf.fem.serendipity_wedge.wedge15_space`, or a
scalar on one of its components). Nothing is lost: C3D15's space lies inside the 18-node prism's,
so the file's 18-node interpolation, with the face centres' constrained values, is the solution.

Points and cells are written in the mesh's input order (``geometry.input_global_indices``,
``topology.original_cell_index``), gathered on rank 0, so the file is the same on any number of
processes. The constructor and :meth:`PrismXdmfFile.write` are collective; rank 0 writes.
"""

from __future__ import annotations

import typing
from pathlib import Path

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.outputs.xdmf_cells import XDMF_WEDGE_18, MixedXdmfFile

__all__ = ["PRISM18_TO_VTK", "PrismXdmfFile"]

#: basix's (and gmsh's) degree-2 prism nodes in ``VTK_BIQUADRATIC_QUADRATIC_WEDGE``'s order.
#: basix's triangle 0-1-2 turns counter-clockwise seen from 3-4-5, VTK's clockwise (its normal
#: points away from 3-4-5), so the triangles are mirrored (1 <-> 2, 4 <-> 5); VTK's edges
#: 0-1, 1-2, 2-0, 3-4, 4-5, 5-3, 0-3, 1-4, 2-5 and quadrilateral centres 0-1-4-3, 1-2-5-4,
#: 2-0-3-5 are then basix's edges 0-2, 1-2, 0-1, 3-5, 4-5, 3-4, 0-3, 2-5, 1-4 (nodes 7, 9, 6,
#: 13, 14, 12, 8, 11, 10) and faces 0-2-3-5, 1-2-4-5, 0-1-3-4 (nodes 16, 17, 15).
PRISM18_TO_VTK = np.array([0, 2, 1, 3, 5, 4, 7, 9, 6, 13, 14, 12, 8, 11, 10, 16, 17, 15])


class PrismXdmfFile:
    """Writes degree-2 Lagrange Functions on an 18-node prism mesh to an XDMF file (``Wedge_18``).

    Args:
        path: The ``.xdmf`` file (no ``.h5``: the data are inline); rank 0's path is used.
        mesh: A mesh of prisms with degree-2 geometry (18 nodes per cell), e.g. from
            :func:`~dolfinx_ntf.meshes.gmsh_io.mesh_from_gmsh` on dolfinx 0.11.

    Raises:
        ValueError: The mesh is not of 18-node prisms.
    """

    def __init__(self, path: str | Path, mesh: dolfinx.mesh.Mesh) -> None:
        if mesh.topology.cell_type != dolfinx.mesh.CellType.prism:
            raise ValueError("PrismXdmfFile: a mesh of prisms is needed")
        nodes = compat.geometry_dofs(mesh).astype(np.int64)
        if nodes.shape[1] != 18:
            raise ValueError(
                f"PrismXdmfFile: 18-node prisms are needed, the mesh has {nodes.shape[1]} nodes "
                "per cell"
            )
        self.mesh = mesh
        self._comm = mesh.comm
        num_owned = mesh.topology.index_map(3).size_local
        #: Input index of each local geometry node.
        self._input = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
        original = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)[:num_owned]
        gathered = self._comm.gather(
            (original, self._input[nodes[:num_owned]], self._input, mesh.geometry.x), root=0
        )
        self._spaces: dict[int, tuple[dolfinx.fem.FunctionSpace, np.ndarray, np.ndarray]] = {}
        self._file: MixedXdmfFile | None = None
        #: The file written.
        self.path = Path(path)
        if gathered is None:
            return
        order = np.concatenate([g[0] for g in gathered])
        cells = np.concatenate([g[1] for g in gathered])[np.argsort(order, kind="stable")]
        #: Input indices of the file's points (sorted), on rank 0.
        self.inputs = np.unique(np.concatenate([g[2] for g in gathered]))
        points = np.zeros((self.inputs.size, 3))
        for _, _, inputs, x in gathered:
            points[np.searchsorted(self.inputs, inputs)] = x
        cells = np.searchsorted(self.inputs, cells)[:, PRISM18_TO_VTK]
        self._file = MixedXdmfFile(path, points, cells, cell_type=XDMF_WEDGE_18)

    def _owned_nodes(self, V: dolfinx.fem.FunctionSpace) -> tuple[np.ndarray, np.ndarray]:
        """Input indices of the geometry nodes whose dof this process owns, and those dofs."""
        key = id(V)  # the space is kept with its entry: the id is not reused meanwhile
        if key not in self._spaces:
            if (
                V.mesh is not self.mesh
                or compat.space_degree(V) != 2
                or compat.space_family(V) != "Lagrange"  # DG: a node's value per cell
            ):
                raise ValueError(
                    "PrismXdmfFile.write: Functions of degree-2 Lagrange spaces on the file's "
                    "mesh are needed"
                )
            dofs = compat.cell_dofs(V).astype(np.int64)
            nodes = compat.geometry_dofs(self.mesh).astype(np.int64)
            dof_of_node = np.full(self._input.size, -1, dtype=np.int64)
            dof_of_node[nodes.ravel()] = dofs.ravel()  # the same local order (basix's P2 prism)
            owned = np.flatnonzero(
                (dof_of_node >= 0) & (dof_of_node < V.dofmap.index_map.size_local)
            )
            self._spaces[key] = (V, self._input[owned], dof_of_node[owned])
        return self._spaces[key][1:]

    def write(self, t: float, functions: typing.Sequence[dolfinx.fem.Function]) -> None:
        """Append one time step with the Functions' nodal values (by their names). Collective.

        Args:
            t: The time.
            functions: Scalar or 3-vector Functions of degree-2 Lagrange spaces on the mesh.

        Raises:
            ValueError: A Function of another space or shape.
        """
        fields: dict[str, np.ndarray] = {}
        for f in functions:
            V = f.function_space
            bs = V.dofmap.index_map_bs
            if bs not in (1, 3):
                raise ValueError(f"PrismXdmfFile.write: {f.name!r} has {bs} components, not 1 or 3")
            inputs, dofs = self._owned_nodes(V)
            values = f.x.array.reshape(-1, bs)[dofs]
            gathered = self._comm.gather((inputs, values), root=0)
            if gathered is None:
                continue
            out = np.zeros((self.inputs.size, bs))
            for rows, vals in gathered:
                out[np.searchsorted(self.inputs, rows)] = vals
            fields[f.name] = out[:, 0] if bs == 1 else out
        if self._file is not None:
            self._file.write(t, fields)

    def close(self) -> None:
        """Close the file (later writes are refused)."""
        if self._file is not None:
            self._file.close()

    def __enter__(self) -> PrismXdmfFile:
        return self

    def __exit__(self, *args: typing.Any) -> None:
        self.close()
