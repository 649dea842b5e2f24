"""Node-to-face penalty contact for dolfinx, reproducing CalculiX 2.20 node-to-surface contact.

Pure-numpy layers (laws, faces, projection, spring areas, search, springs) sit below the dolfinx
glue (surfaces, assembly), the problem and solver, and the outside world (output, CalculiX interop).
See ``docs/architecture.md``.
"""

from dolfinx_ntf.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.laws import ExponentialLaw, Friction, LinearLaw, SurfaceInteraction, TabularLaw
from dolfinx_ntf.output import ContactResults, ContactWriter, contact_results
from dolfinx_ntf.problem import ContactPair, ContactProblem
from dolfinx_ntf.solver import (
    ContactConvergenceError,
    ContactNewtonSolver,
    IncrementResult,
    StaticStep,
    log_progress,
)
from dolfinx_ntf.surfaces import FacetSurface, NodeSurface

__all__ = [
    "ContactConvergenceError",
    "ContactNewtonSolver",
    "ContactPair",
    "ContactProblem",
    "ContactResults",
    "ContactWriter",
    "ExponentialLaw",
    "FacetSurface",
    "Friction",
    "IncrementResult",
    "LinearLaw",
    "NodeSurface",
    "StaticStep",
    "SurfaceInteraction",
    "TabularLaw",
    "component_bc",
    "contact_results",
    "log_progress",
    "small_strain_stress",
]
