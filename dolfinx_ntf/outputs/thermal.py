"""Results of thermal contact: heat flow per spring and the heat flux as a field.

docs/method.md §20. :func:`thermal_results` gives one table per pair of the springs' heat flows
(like :func:`~dolfinx_ntf.contact_results` for the mechanical springs); :func:`heat_flux_field`
puts the flux density ``q/A`` at the slave nodes into a Function of the temperature space, to
write with dolfinx's ``XDMFFile`` beside the temperature.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import dolfinx.fem

from dolfinx_ntf import validation
from dolfinx_ntf.contact.thermal import ThermalContactProblem

__all__ = ["ThermalResults", "heat_flux_field", "thermal_results"]


@dataclass(frozen=True)
class ThermalResults:
    """Per-spring heat flows of one pair at the last evaluation (this process's springs).

    Attributes:
        pair: The pair's name (``"pair 1"``, ... when it has none).
        node: ``(N,)`` slave node of each spring, a local index of the temperature space (and of
            the displacement space's nodes).
        temperature: ``(N,)`` slave temperature T_s.
        master_temperature: ``(N,)`` master temperature T_m at the projection point.
        conductance: ``(N,)`` h(p, T_mean).
        flow: ``(N,)`` heat flow into the slave node ``q = A h (T_m - T_s)``.
        flux: ``(N,)`` heat flux density ``q / A``.
    """

    pair: str
    node: np.ndarray
    temperature: np.ndarray
    master_temperature: np.ndarray
    conductance: np.ndarray
    flow: np.ndarray
    flux: np.ndarray


def thermal_results(thermal: ThermalContactProblem) -> list[ThermalResults]:
    """The heat flows of every pair's springs at the last evaluation (local springs). Collective.

    Args:
        thermal: The thermal problem (evaluated by a solve).
    """
    validation.check_type(thermal, ThermalContactProblem, "thermal_results: thermal")
    results = []
    states = thermal.contact.states
    evaluations = thermal.evaluations or [None] * len(states)
    temperatures = thermal.temperatures()  # collective: before any branch
    for i, (state, th) in enumerate(zip(states, evaluations)):
        name = state.pair.name or f"pair {i + 1}"
        if th is None:
            empty = np.zeros(0)
            results.append(
                ThermalResults(name, np.zeros(0, np.int64), empty, empty, empty, empty, empty)
            )
            continue
        node = state.slave.nodes[state.spring_slave]
        area = state.evaluation.area
        slave_t = temperatures[node]
        results.append(
            ThermalResults(
                name,
                node,
                slave_t,
                slave_t + th.temperature_jump,
                th.conductance,
                th.flow,
                np.divide(th.flow, area, out=np.zeros_like(th.flow), where=area > 0),
            )
        )
    return results


def heat_flux_field(
    thermal: ThermalContactProblem, out: dolfinx.fem.Function | None = None
) -> dolfinx.fem.Function:
    """The springs' heat flux density ``q/A`` at their slave nodes, zero elsewhere. Collective.

    Args:
        thermal: The thermal problem (evaluated by a solve).
        out: A Function of the temperature space to fill (a new one named ``heat_flux`` by
            default).
    """
    if out is None:
        f = dolfinx.fem.Function(thermal.T.function_space)
        f.name = "heat_flux"
    else:
        f = out
    f.x.array[:] = 0.0
    for res in thermal_results(thermal):
        owned = res.node < f.x.array.size  # springs sit on owned slave nodes (docs/method.md §14)
        f.x.array[res.node[owned]] += res.flux[owned]
    f.x.scatter_forward()
    return f
