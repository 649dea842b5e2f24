"""``JOB.xdmf`` of a deck with wedges: the deck's mesh with wedge cells (docs/method.md §30.6, §43).

dolfinx cannot write fields of the collapsed hexahedra the wedges run as, so this writer takes the
deck's own mesh (its nodes and the C3D8 connectivity, wedges with their repeated nodes) and the
fields gathered at the deck's nodes in ccx order, and rank 0 writes them with
:class:`~dolfinx_ntf.outputs.xdmf_cells.MixedXdmfFile`: the wedges as XDMF ``Wedge`` cells, the
others as ``Hexahedron`` cells, the same fields as :class:`~dolfinx_ntf.ContactWriter` writes. The
file is the same on any number of processes. C3D15 decks (dolfinx 0.11: dolfinx writes no 18-node
prisms) are written the same way as XDMF ``Wedge_15`` cells at the deck's 15 nodes of each element
(:data:`C3D15_TO_VTK`), whose quadratic interpolation is C3D15's own.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dolfinx_ntf.outputs.results import ContactFields
from dolfinx_ntf.outputs.xdmf_cells import XDMF_WEDGE_15, MixedXdmfFile

from .output_values import OutputValues

__all__ = ["C3D15_TO_VTK", "WedgeDeckWriter"]

#: ccx's C3D15 nodes in ``VTK_QUADRATIC_WEDGE``'s order: ccx's triangle 1-2-3 turns
#: counter-clockwise seen from 4-5-6, VTK's 0-1-2 clockwise (its normal points away from 3-4-5),
#: so the triangles are mirrored (1 <-> 2, 4 <-> 5) and the midside nodes follow their edges
#: (ccx's edges 1-2, 2-3, 3-1, 4-5, 5-6, 6-4, 1-4, 2-5, 3-6 are VTK's in the same sequence).
C3D15_TO_VTK = np.array([0, 2, 1, 3, 5, 4, 8, 7, 6, 11, 10, 9, 12, 14, 13])


class WedgeDeckWriter:
    """Writes ``JOB.xdmf`` of a C3D8 deck with wedges or of a C3D15 deck (``ContactWriter``'s role).

    Args:
        path: The ``.xdmf`` file (no ``.h5``: the data are inline).
        values: The job's output values (deck, model, problem and numbering).
        root: True on the process that writes (rank 0); :meth:`write` is collective.
    """

    def __init__(self, path: str | Path, values: OutputValues, *, root: bool) -> None:
        deck = values.deck
        name = values.model.element_type.name
        if name not in ("C3D8", "C3D15"):
            raise NotImplementedError(f"{deck.path}: JOB.xdmf of wedges beside {name} elements")
        self.values = values
        self.fields = ContactFields(values.problem)
        block = deck.elements[name]
        points = np.asarray(deck.node_coords, dtype=np.float64)
        cells = deck.node_index(block.connectivity)
        self._file = None
        if root and name == "C3D15":
            self._file = MixedXdmfFile(
                path, points, cells[:, C3D15_TO_VTK], cell_type=XDMF_WEDGE_15
            )
        elif root:
            self._file = MixedXdmfFile(path, points, cells)
        #: The file written.
        self.path = Path(path)

    def write(self, t: float) -> None:
        """Write the displacement and the contact fields at time ``t``. Collective.

        Args:
            t: The total time of the increment.
        """
        values, fields = self.values, self.fields
        fields.update()
        numbering = values.numbering
        nodes = np.arange(values.model.u.x.array.size // 3)
        pressure, clearance, status = fields.at_nodes(nodes)
        scalars = np.column_stack([pressure, clearance, status, fields.recovery.at_nodes(nodes)])
        gathered = numbering.nodal(scalars)
        shear = numbering.nodal(fields.shear.x.array.reshape(-1, 3))
        slip = numbering.nodal(fields.slip.x.array.reshape(-1, 3))
        u = values.displacements()
        if self._file is None:
            return
        names = [f.name for f in (*fields.functions, fields.recovered_pressure)]
        data = {values.model.u.name: u}
        data.update({n: gathered[:, k] for k, n in enumerate(names[:3])})
        data[fields.shear.name] = shear
        data[fields.slip.name] = slip
        data[names[3]] = gathered[:, 3]
        self._file.write(t, data)

    def close(self) -> None:
        """Close the file."""
        if self._file is not None:
            self._file.close()
