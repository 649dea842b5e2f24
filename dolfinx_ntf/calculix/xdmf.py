"""``JOB.xdmf`` of a deck with C3D6 wedges: the deck's mesh with wedge cells (docs/method.md §30.6).

dolfinx cannot write fields of the collapsed hexahedra the wedges run as, so this writer takes the
deck's own mesh (its nodes and the C3D8 connectivity, wedges with their repeated nodes) and the
fields gathered at the deck's nodes in ccx order, and rank 0 writes them with
:class:`~dolfinx_ntf.outputs.xdmf_cells.MixedXdmfFile`: the wedges as XDMF ``Wedge`` cells, the
others as ``Hexahedron`` cells, the same fields as :class:`~dolfinx_ntf.ContactWriter` writes. The
file is the same on any number of processes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dolfinx_ntf.outputs.results import ContactFields
from dolfinx_ntf.outputs.xdmf_cells import MixedXdmfFile

from .output_values import OutputValues

__all__ = ["WedgeDeckWriter"]


class WedgeDeckWriter:
    """Writes ``JOB.xdmf`` of a C3D8 deck with wedges (the role of ``ContactWriter``).

    Args:
        path: The ``.xdmf`` file (no ``.h5``: the data are inline).
        values: The job's output values (deck, model, problem and numbering).
        root: True on the process that writes (rank 0); :meth:`write` is collective.
    """

    def __init__(self, path: str | Path, values: OutputValues, *, root: bool) -> None:
        deck = values.deck
        name = values.model.element_type.name
        if name != "C3D8":
            raise NotImplementedError(f"{deck.path}: JOB.xdmf of wedges beside {name} elements")
        self.values = values
        self.fields = ContactFields(values.problem)
        block = deck.elements[name]
        points = np.asarray(deck.node_coords, dtype=np.float64)
        cells = deck.node_index(block.connectivity)
        self._file = MixedXdmfFile(path, points, cells) if root else None
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
