"""The volume measures of a deck with C3D6 wedges: ccx's two-point rule on the wedge cells.

docs/method.md §30.5. The wedges are collapsed C3D8 cells (``deck/wedges.py``); their integrals
take ccx's C3D6 rule (:func:`~dolfinx_ntf.fem.collapsed_wedges.wedge_metadata`, one integral per
collapse class), the other cells C3D8's 2x2x2 Gauss points. UFL wants one ``subdomain_data`` per
form, so one set of cell tags carries both the wedges' classes and the plastic sections
(``plasticity.py``): :data:`WEDGE_TAG` ``+ class`` on an elastic wedge, 0 on another elastic cell,
a law's tag on its cells. The wedges of a plastic section get laws of their own with the same
rule (``plasticity.py``; their stresses in a DG1 carrier, ``QuadratureLaw``'s ``quadrature_rule``).
"""

from __future__ import annotations

import typing

from mpi4py import MPI

import numpy as np

import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.collapsed_wedges import wedge_cells, wedge_metadata

from .mixed import CellMeasures

__all__ = ["WEDGE_TAG", "WedgeRules", "wedge_rules"]

#: Tag of the elastic wedges of collapse class 0 (class ``c``: ``WEDGE_TAG + c``).
WEDGE_TAG = 1000


class WedgeRules:
    """The wedges' collapse classes of a mesh and the cell values that select their rules.

    Attributes:
        classes_of_cells: ``(cells,)`` collapse class of each local cell, -1 if no wedge.
        values: ``(cells,)`` tag of each local cell outside plastic sections: ``WEDGE_TAG +
            class`` on a wedge, 0 elsewhere.
        classes: The collapse classes present on any process (the same on all), ascending.
    """

    def __init__(self, classes_of_cells: np.ndarray, classes: list[int]) -> None:
        """Keep the classes and the cell values they give."""
        self.classes_of_cells = classes_of_cells
        self.values = np.where(classes_of_cells >= 0, WEDGE_TAG + classes_of_cells, 0).astype(
            np.int32
        )
        self.classes = classes

    def measures(
        self,
        mesh: dolfinx.mesh.Mesh,
        tags: compat.MeshTags,
        degree: int,
        law_measures: typing.Sequence[ufl.Measure] = (),
    ) -> tuple[CellMeasures, CellMeasures]:
        """The measures of the elastic cells and of all cells (with the laws' own measures).

        Args:
            mesh: The mesh.
            tags: The cell tags made of :attr:`values` (and the laws' tags).
            degree: C3D8's quadrature degree (2x2x2 Gauss points).
            law_measures: The plastic laws' measures (``dx`` of each law, on the same tags).
        """
        rules: dict[int, int | dict | None] = {0: degree}
        rules.update({WEDGE_TAG + c: wedge_metadata(c) for c in self.classes})
        every = CellMeasures(mesh, tags, rules)
        every.measures += list(law_measures)
        return CellMeasures(mesh, tags, rules), every

    def tags(self, mesh: dolfinx.mesh.Mesh) -> compat.MeshTags:
        """Cell tags of :attr:`values` (a deck without plastic sections)."""
        cells = np.arange(self.values.size, dtype=np.int32)
        return dolfinx.mesh.meshtags(mesh, mesh.topology.dim, cells, self.values)


def wedge_rules(mesh: dolfinx.mesh.Mesh, comm: MPI.Comm) -> WedgeRules:
    """The wedge cells of ``mesh`` and their classes (collective: every process's classes)."""
    classes = wedge_cells(mesh)
    present = sorted(set().union(*comm.allgather(set(np.unique(classes[classes >= 0]).tolist()))))
    return WedgeRules(classes, present)
