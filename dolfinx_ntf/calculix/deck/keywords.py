"""Which keywords belong where: model definition, steps, material and interaction blocks."""

from __future__ import annotations

from .lexer import normalized_name

# Constraints and kinematic couplings: "not supported yet".
_UNSUPPORTED_CONSTRAINTS = {
    normalized_name(k)
    for k in (
        "RIGID BODY", "MPC", "NETWORK MPC", "COUPLING", "KINEMATIC",
        "DISTRIBUTING", "DISTRIBUTING COUPLING", "PRE-TENSION SECTION", "CLEARANCE", "GAP",
        "DASHPOT", "MASS", "CHANGE CONTACT TYPE",
        "CHANGE KINEMATIC", "CHANGE TIE", "RETAINED NODAL DOFS",
    )
}  # fmt: skip


# Material data a static step does not use.
_UNUSED_MATERIAL = {
    normalized_name(k) for k in ("DENSITY", "EXPANSION", "CONDUCTIVITY", "SPECIFIC HEAT")
}

# Interaction data a static mechanical step does not use.
_UNUSED_INTERACTION = {normalized_name(k) for k in ("CONTACT DAMPING", "GAP CONDUCTANCE")}

# Keywords that continue the current *MATERIAL / *SURFACE INTERACTION block.
_CONTEXT_KEYWORDS = (
    {"ELASTIC", "PLASTIC", "FRICTION", "SURFACEBEHAVIOR"} | _UNUSED_MATERIAL | _UNUSED_INTERACTION
)

_STEP_KEYWORDS = {
    normalized_name(k)
    for k in (
        "STATIC", "CLOAD", "DLOAD", "NODE PRINT", "EL PRINT", "CONTACT PRINT", "NODE FILE",
        "EL FILE", "CONTACT FILE", "NODE OUTPUT", "ELEMENT OUTPUT", "CONTACT OUTPUT", "CONTROLS",
        "CHANGE FRICTION", "MODEL CHANGE", "END STEP", "DYNAMIC", "FREQUENCY",
        "MODAL DYNAMIC", "MODAL DAMPING", "COUPLED TEMPERATURE-DISPLACEMENT", "HEAT TRANSFER",
        "TEMPERATURE", "CFLUX", "DFLUX", "FILM",
    )
}  # fmt: skip

_MODEL_KEYWORDS = {
    normalized_name(k)
    for k in (
        "NODE", "ELEMENT", "NSET", "ELSET", "SURFACE", "MATERIAL", "ELASTIC", "SOLID SECTION",
        "CONTACT PAIR", "SURFACE INTERACTION", "SURFACE BEHAVIOR", "DENSITY", "EXPANSION",
        "CONDUCTIVITY", "SPECIFIC HEAT", "CONTACT DAMPING", "GAP CONDUCTANCE", "EQUATION",
        "INITIAL CONDITIONS", "SPRING", "TIE", "CYCLIC SYMMETRY MODEL", "SHELL SECTION",
        "TRANSFORM", "ORIENTATION",
    )
}  # fmt: skip
