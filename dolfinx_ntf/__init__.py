"""Node-to-face penalty contact for dolfinx, reproducing CalculiX 2.20 node-to-surface contact.

Pure-numpy layers (laws, faces, projection, spring areas, search, springs) sit below the dolfinx
glue (surfaces, assembly), the problem and solver, and the outside world (output, post-processing,
CalculiX interop). The method is described in ``docs/method.md``, the code in
``docs/architecture.md``.
"""

__version__ = "0.1.0"

from dolfinx_ntf import _moved
from dolfinx_ntf import logs as _logs
from dolfinx_ntf.contact.pair import ContactPair
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.contact.thermal import ThermalContactProblem
from dolfinx_ntf.contact.ties import Tie, tie_constraints
from dolfinx_ntf.fem.constraints import LinearConstraint, LinearConstraintBlock
from dolfinx_ntf.fem.discrete_springs import DiscreteSprings
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.fem.finite_plasticity import FiniteStrainJ2Plasticity
from dolfinx_ntf.fem.incompatible_modes import IncompatibleModes
from dolfinx_ntf.fem.plasticity import J2Plasticity, mandel_strain
from dolfinx_ntf.fem.pressure_recovery import BoundaryPressure
from dolfinx_ntf.fem.serendipity import serendipity_constraints
from dolfinx_ntf.fem.surfaces import FacetSurface, NodeSurface
from dolfinx_ntf.fem.thermal import CellTemperature, thermal_strain, thermoelastic_stress
from dolfinx_ntf.kernels.discrete_springs import (
    AxialSpring,
    DirectionalSpring,
    LinearSpringLaw,
    TabularSpringLaw,
)
from dolfinx_ntf.kernels.gap_conductance import GapConductance
from dolfinx_ntf.kernels.laws import (
    ContactDamping,
    DynamicLinearLaw,
    ExponentialLaw,
    Friction,
    LinearLaw,
    PressureOverclosureLaw,
    SurfaceInteraction,
    TabularLaw,
)
from dolfinx_ntf.kernels.plasticity import IsotropicHardening
from dolfinx_ntf.kernels.rigid import (
    RigidCylinder,
    RigidPlane,
    RigidSphere,
    RigidSurface,
    SignedDistanceSurface,
)
from dolfinx_ntf.logs import log_progress
from dolfinx_ntf.outputs.postprocess import contact_area, contact_force, reaction
from dolfinx_ntf.outputs.results import (
    ContactFields,
    ContactResults,
    ContactWriter,
    contact_results,
)
from dolfinx_ntf.outputs.thermal import ThermalResults, heat_flux_field, thermal_results
from dolfinx_ntf.parallel.global_constraints import (
    GlobalLinearConstraint,
    global_constraints,
    input_node_ids,
)
from dolfinx_ntf.solvers.active_set import ActiveSetNewtonSolver
from dolfinx_ntf.solvers.analysis import (
    AddPair,
    Amplitude,
    AnalysisStep,
    ChangeFriction,
    Load,
    RemovePair,
    SetSmallSliding,
    run_steps,
)
from dolfinx_ntf.solvers.coupled import ThermoMechanicalContact
from dolfinx_ntf.solvers.dynamics import DynamicStep, kinetic_energy
from dolfinx_ntf.solvers.errors import (
    ContactConvergenceError,
    ContactDivergenceError,
    ContactSolverError,
)
from dolfinx_ntf.solvers.modal_dynamics import (
    ModalContactForces,
    ModalDynamics,
    RayleighDamping,
    modal_forces,
)
from dolfinx_ntf.solvers.modes import Modes, contact_modes
from dolfinx_ntf.solvers.newton import ContactNewtonSolver
from dolfinx_ntf.solvers.newton_loop import NewtonSolver
from dolfinx_ntf.solvers.snes import ContactSNESSolver
from dolfinx_ntf.solvers.staggered import solve_staggered, thermal_solver
from dolfinx_ntf.solvers.steps import IncrementResult, StaticStep

_logs.route_compiler_lines()
_moved.install()

__all__ = [
    "ActiveSetNewtonSolver",
    "AddPair",
    "Amplitude",
    "AnalysisStep",
    "AxialSpring",
    "BoundaryPressure",
    "CellTemperature",
    "ChangeFriction",
    "ContactConvergenceError",
    "ContactDamping",
    "ContactDivergenceError",
    "ContactFields",
    "ContactNewtonSolver",
    "ContactPair",
    "ContactProblem",
    "ContactResults",
    "ContactSNESSolver",
    "ContactSolverError",
    "ContactWriter",
    "DirectionalSpring",
    "DiscreteSprings",
    "DynamicLinearLaw",
    "DynamicStep",
    "ExponentialLaw",
    "FacetSurface",
    "FiniteStrainJ2Plasticity",
    "Friction",
    "GapConductance",
    "GlobalLinearConstraint",
    "IncompatibleModes",
    "IncrementResult",
    "IsotropicHardening",
    "J2Plasticity",
    "LinearConstraint",
    "LinearConstraintBlock",
    "LinearLaw",
    "LinearSpringLaw",
    "Load",
    "ModalContactForces",
    "ModalDynamics",
    "Modes",
    "NewtonSolver",
    "NodeSurface",
    "PressureOverclosureLaw",
    "RayleighDamping",
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
    "TabularSpringLaw",
    "ThermalContactProblem",
    "ThermalResults",
    "ThermoMechanicalContact",
    "Tie",
    "__version__",
    "component_bc",
    "contact_area",
    "contact_force",
    "contact_modes",
    "contact_results",
    "global_constraints",
    "heat_flux_field",
    "input_node_ids",
    "kinetic_energy",
    "log_progress",
    "mandel_strain",
    "modal_forces",
    "reaction",
    "run_steps",
    "serendipity_constraints",
    "small_strain_stress",
    "solve_staggered",
    "thermal_results",
    "thermal_solver",
    "thermal_strain",
    "thermoelastic_stress",
    "tie_constraints",
]
