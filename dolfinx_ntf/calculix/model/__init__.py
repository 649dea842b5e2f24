"""A parsed CalculiX deck as dolfinx objects: mesh, UFL residual, loads per step and contact pairs.

``build_model`` turns a :class:`~dolfinx_ntf.calculix.deck.Deck` into a :class:`CalculixModel`,
one module per part:

    - ``mesh``: the mesh of the deck's one element type and the maps between ccx node/element
      numbers and dolfinx block dofs/cells (:class:`MeshMaps`);
    - ``surfaces``: element-face surfaces as facet tags wrapped in
      :class:`~dolfinx_ntf.FacetSurface`, ``TYPE=NODE`` surfaces as
      :class:`~dolfinx_ntf.NodeSurface`;
    - ``bulk``: Lamé parameters per cell and the stresses of small-strain elasticity or, with
      ``NLGEOM``, total-Lagrangian St.Venant-Kirchhoff;
    - ``loads``: the loads and prescribed displacements of every step with ccx's rules
      (:class:`StepLoads`);
    - ``equations``: the ``*EQUATION`` constraints (docs/method.md §13.1);
    - ``contact``: the contact pairs with their pressure-overclosure laws and friction;
    - ``calculix_model``: :class:`CalculixModel`, the residual with ccx's quadrature and
      ``*DLOAD`` pressures, and ``build_model``.

On several processes (docs/method.md §14.5) every process reads the whole deck; the mesh is
distributed by dolfinx from rank 0's cells, and the numbering maps hold this process's nodes and
cells only (-1 elsewhere); ``*EQUATION`` terms are numbered globally (docs/method.md §14.9).
"""

from .calculix_model import CalculixModel, build_model
from .contact import friction_of
from .equations import FreeReference
from .loads import Schedule, StepLoads
from .mesh import CELL_PERMUTATIONS, INTEGRATION_POINTS, MeshMaps

__all__ = [
    "CELL_PERMUTATIONS",
    "INTEGRATION_POINTS",
    "CalculixModel",
    "FreeReference",
    "MeshMaps",
    "Schedule",
    "StepLoads",
    "build_model",
    "friction_of",
]
