"""Node-to-face penalty contact for dolfinx, reproducing CalculiX 2.20 node-to-surface contact.

Pure-numpy layers (laws, faces, projection, spring areas, search, springs) sit below the dolfinx
glue (surfaces, assembly), the problem and solver, and the outside world (output, post-processing,
CalculiX interop). The method is described in ``docs/method.md``, the code in
``docs/architecture.md``.

The public names below are imported on first use (PEP 562): ``python -m dolfinx_ntf run JOB``
loads the modules its deck needs, not those of every feature (docs/performance.md, "Start-up").
"""

__version__ = "0.1.0"

import importlib

from dolfinx_ntf import _moved
from dolfinx_ntf import logs as _logs

_logs.route_compiler_lines()
_moved.install()

#: Where each public name lives (module under ``dolfinx_ntf.``).
_LAZY: dict[str, str] = {
    "ActiveSetNewtonSolver": "solvers.active_set",
    "AddPair": "solvers.analysis",
    "Amplitude": "solvers.analysis",
    "AnalysisStep": "solvers.analysis",
    "AxialSpring": "kernels.discrete_springs",
    "BoundaryPressure": "fem.pressure_recovery",
    "CellTemperature": "fem.thermal",
    "ChangeFriction": "solvers.analysis",
    "ContactConvergenceError": "solvers.errors",
    "ContactDamping": "kernels.laws",
    "ContactDivergenceError": "solvers.errors",
    "ContactFields": "outputs.results",
    "ContactNewtonSolver": "solvers.newton",
    "ContactPair": "contact.pair",
    "ContactProblem": "contact.problem",
    "ContactResults": "outputs.results",
    "ContactSNESSolver": "solvers.snes",
    "ContactSolverError": "solvers.errors",
    "ContactWriter": "outputs.results",
    "DirectionalSpring": "kernels.discrete_springs",
    "DiscreteSprings": "fem.discrete_springs",
    "DynamicLinearLaw": "kernels.laws",
    "DynamicStep": "solvers.dynamics",
    "ExponentialLaw": "kernels.laws",
    "FacetSurface": "fem.surfaces",
    "FiniteStrainJ2Plasticity": "fem.finite_plasticity",
    "Friction": "kernels.laws",
    "GapConductance": "kernels.gap_conductance",
    "GlobalLinearConstraint": "parallel.global_constraints",
    "IncompatibleModes": "fem.incompatible_modes",
    "IncrementResult": "solvers.steps",
    "IsotropicHardening": "kernels.plasticity",
    "J2Plasticity": "fem.plasticity",
    "LinearConstraint": "fem.constraints",
    "LinearConstraintBlock": "fem.constraints",
    "LinearLaw": "kernels.laws",
    "LinearSpringLaw": "kernels.discrete_springs",
    "Load": "solvers.analysis",
    "ModalContactForces": "solvers.modal_dynamics",
    "ModalDynamics": "solvers.modal_dynamics",
    "Modes": "solvers.modes",
    "NewtonSolver": "solvers.newton_loop",
    "NodeSurface": "fem.surfaces",
    "PressureOverclosureLaw": "kernels.laws",
    "RayleighDamping": "solvers.modal_dynamics",
    "RemovePair": "solvers.analysis",
    "RigidCylinder": "kernels.rigid",
    "RigidPlane": "kernels.rigid",
    "RigidSphere": "kernels.rigid",
    "RigidSurface": "kernels.rigid",
    "SetSmallSliding": "solvers.analysis",
    "SignedDistanceSurface": "kernels.rigid",
    "StaticStep": "solvers.steps",
    "SurfaceInteraction": "kernels.laws",
    "TabularLaw": "kernels.laws",
    "TabularSpringLaw": "kernels.discrete_springs",
    "ThermalContactProblem": "contact.thermal",
    "ThermalResults": "outputs.thermal",
    "ThermoMechanicalContact": "solvers.coupled",
    "Tie": "contact.ties",
    "component_bc": "fem.elasticity",
    "contact_area": "outputs.postprocess",
    "contact_force": "outputs.postprocess",
    "contact_modes": "solvers.modes",
    "contact_results": "outputs.results",
    "global_constraints": "parallel.global_constraints",
    "heat_flux_field": "outputs.thermal",
    "input_node_ids": "parallel.global_constraints",
    "kinetic_energy": "solvers.dynamics",
    "log_progress": "logs",
    "mandel_strain": "fem.plasticity",
    "modal_forces": "solvers.modal_dynamics",
    "reaction": "outputs.postprocess",
    "run_steps": "solvers.analysis",
    "serendipity_constraints": "fem.serendipity",
    "small_strain_stress": "fem.elasticity",
    "solve_staggered": "solvers.staggered",
    "thermal_results": "outputs.thermal",
    "thermal_solver": "solvers.staggered",
    "thermal_strain": "fem.thermal",
    "thermoelastic_stress": "fem.thermal",
    "tie_constraints": "contact.ties",
}

#: Subpackages reachable as attributes of the package before anything imported them.
_SUBPACKAGES = frozenset(
    {"calculix", "contact", "fem", "kernels", "outputs", "parallel", "solvers"}
)

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


def __getattr__(name: str) -> object:
    """Import the module of a public name (or a subpackage) on first access (PEP 562)."""
    if name in _SUBPACKAGES:
        return importlib.import_module(f".{name}", __name__)
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
