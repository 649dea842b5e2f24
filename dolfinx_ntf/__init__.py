"""Node-to-face penalty contact for dolfinx, reproducing CalculiX 2.20 node-to-surface contact.

Pure-numpy layers (laws, faces, projection, spring areas, search, springs) sit below the dolfinx
glue (surfaces, assembly), the problem and solver, and the outside world (output, post-processing,
CalculiX interop). The method is described in ``docs/method.md``, the code in
``docs/architecture.md``.
"""

__version__ = "0.1.0"

from dolfinx_ntf import logs as _logs
from dolfinx_ntf.active_set import ActiveSetNewtonSolver
from dolfinx_ntf.analysis import (
    AddPair,
    Amplitude,
    AnalysisStep,
    ChangeFriction,
    Load,
    RemovePair,
    SetSmallSliding,
    run_steps,
)
from dolfinx_ntf.constraints import LinearConstraint, LinearConstraintBlock
from dolfinx_ntf.dynamics import DynamicStep, kinetic_energy
from dolfinx_ntf.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.laws import (
    DynamicLinearLaw,
    ExponentialLaw,
    Friction,
    LinearLaw,
    PressureOverclosureLaw,
    SurfaceInteraction,
    TabularLaw,
)
from dolfinx_ntf.logs import log_progress
from dolfinx_ntf.output import ContactFields, ContactResults, ContactWriter, contact_results
from dolfinx_ntf.parallel_constraints import (
    GlobalLinearConstraint,
    global_constraints,
    input_node_ids,
)
from dolfinx_ntf.postprocess import contact_area, contact_force, reaction
from dolfinx_ntf.pressure_recovery import BoundaryPressure
from dolfinx_ntf.problem import ContactPair, ContactProblem
from dolfinx_ntf.rigid import (
    RigidCylinder,
    RigidPlane,
    RigidSphere,
    RigidSurface,
    SignedDistanceSurface,
)
from dolfinx_ntf.serendipity import serendipity_constraints
from dolfinx_ntf.solver import (
    ContactConvergenceError,
    ContactDivergenceError,
    ContactNewtonSolver,
    ContactSolverError,
    IncrementResult,
    StaticStep,
)
from dolfinx_ntf.surfaces import FacetSurface, NodeSurface

_logs.route_compiler_lines()

__all__ = [
    "ActiveSetNewtonSolver",
    "AddPair",
    "Amplitude",
    "AnalysisStep",
    "BoundaryPressure",
    "ChangeFriction",
    "ContactConvergenceError",
    "ContactDivergenceError",
    "ContactFields",
    "ContactNewtonSolver",
    "ContactPair",
    "ContactProblem",
    "ContactResults",
    "ContactSolverError",
    "ContactWriter",
    "DynamicLinearLaw",
    "DynamicStep",
    "ExponentialLaw",
    "FacetSurface",
    "Friction",
    "GlobalLinearConstraint",
    "IncrementResult",
    "LinearConstraint",
    "LinearConstraintBlock",
    "LinearLaw",
    "Load",
    "NodeSurface",
    "PressureOverclosureLaw",
    "RemovePair",
    "RigidCylinder",
    "RigidPlane",
    "RigidSphere",
    "RigidSurface",
    "SetSmallSliding",
    "SignedDistanceSurface",
    "StaticStep",
    "SurfaceInteraction",
    "TabularLaw",
    "__version__",
    "component_bc",
    "contact_area",
    "contact_force",
    "contact_results",
    "global_constraints",
    "input_node_ids",
    "kinetic_energy",
    "log_progress",
    "reaction",
    "run_steps",
    "serendipity_constraints",
    "small_strain_stress",
]
