"""``*CONTROLS`` of a deck as the Newton solver's convergence controls.

The values live where they are used first: the names and ccx's defaults of ``*CONTROLS,
PARAMETERS=FIELD`` with the deck reader that parses them, the tight values with the Newton solver
whose default they are. This module gathers them for the deck runner and the deck writer and turns
a step's ``*CONTROLS`` into the solver's settings.

TIGHT_FIELD_CONTROLS are ``*CONTROLS, PARAMETERS=FIELD`` values that make ccx converge to round-off
level. ccx's defaults stop Newton when the largest residual is 0.5 % of the average nodal force
(R_n = 0.005, after I_P = 9 iterations R_p = 0.02), which leaves displacements off by up to 1e-5
and contact stresses by up to 1e-4 of the converged answer (measured on the cross-validation decks).
With these values ccx needs zero or one more iteration per increment, and tightening further (all
criteria 1e-14) no longer changes a printed digit of the ``.dat`` file.
"""

from __future__ import annotations

from dolfinx_ntf.solvers.convergence import CCX_FIELD_CONTROLS, TIGHT_FIELD_CONTROLS

from .deck import FIELD_CONTROL_DEFAULTS, FIELD_CONTROL_NAMES, Step

__all__ = [
    "CCX_FIELD_CONTROLS",
    "DEFAULT_RELAXATION_ITERATION",
    "FIELD_CONTROL_DEFAULTS",
    "FIELD_CONTROL_NAMES",
    "TIGHT_FIELD_CONTROLS",
    "relaxation_iteration",
    "solver_controls",
]

#: ccx's I_P (third ``*CONTROLS, PARAMETERS=TIME INCREMENTATION`` value) when the deck gives none.
DEFAULT_RELAXATION_ITERATION = 9


def solver_controls(step: Step, *, tight: bool) -> dict[str, float]:
    """The field controls of ``step`` for the Newton solver (``TIGHT_FIELD_CONTROLS`` if tight).

    Controls without a value (``q_0``, ``q_u`` by default) are left out.
    """
    controls = TIGHT_FIELD_CONTROLS if tight else step.field_controls()
    return {k: float(v) for k, v in controls.items() if v is not None}


def relaxation_iteration(step: Step) -> int:
    """ccx's I_P of ``step``: after this many iterations ``R_p`` replaces ``R_n``."""
    timing = [v for line in step.controls.get("TIMEINCREMENTATION", ()) for v in line]
    if len(timing) > 2 and timing[2] is not None:
        return int(timing[2])
    return DEFAULT_RELAXATION_ITERATION
