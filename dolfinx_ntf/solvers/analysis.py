"""Analyses made of steps: loads with amplitudes, Dirichlet changes and contact changes per step.

An analysis is a list of :class:`AnalysisStep` run one after the other on one problem and solver by
:func:`run_steps` (docs/method.md §11.6). Each step has

- a procedure that does the incrementation: a :class:`~dolfinx_ntf.solvers.steps.Step`, the
  :class:`~dolfinx_ntf.StaticStep` by default or a :class:`~dolfinx_ntf.DynamicStep` (any
  dataclass with ``set_load`` and ``period`` fields and a ``run(solver, u)`` method will do);
- loads (:class:`Load`): values of Constants or Functions (pressures, prescribed displacements)
  that ramp linearly over the step from their value at its start, as in CalculiX, or follow an
  :class:`Amplitude`;
- Dirichlet conditions that replace the previous step's (``bcs``; None keeps them);
- contact changes from this step on (:class:`ChangeFriction`, :class:`RemovePair`,
  :class:`AddPair`, :class:`SetSmallSliding`).

The friction state is kept across steps (a pair added back starts afresh unless the problem keeps
CalculiX's stale state, docs/method.md §11.3).
"""

from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

import dolfinx.fem

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.problem import ContactPair
from dolfinx_ntf.kernels.laws import Friction, SurfaceInteraction
from dolfinx_ntf.solvers.steps import (
    IncrementResult,
    IncrementSolver,
    StaticStep,
    Step,
    check_solver,
)

__all__ = [
    "AddPair",
    "Amplitude",
    "AnalysisStep",
    "ChangeFriction",
    "Load",
    "RemovePair",
    "SetSmallSliding",
    "run_steps",
]


@dataclass(frozen=True)
class Amplitude:
    """A piecewise-linear load factor of time (CalculiX ``*AMPLITUDE``), constant outside.

    Args:
        times: Increasing times.
        values: Factors at those times.
        total_time: Evaluate at the total time of the analysis instead of the step time.
    """

    times: typing.Sequence[float]
    values: typing.Sequence[float]
    total_time: bool = False

    def __post_init__(self) -> None:
        """Check the table (``ValueError`` naming the problem)."""
        times = np.asarray(self.times, dtype=float)
        values = np.asarray(self.values, dtype=float)
        if times.ndim != 1 or times.shape != values.shape or times.size < 1:
            raise ValueError(
                f"Amplitude: times and values must be 1-D of the same length >= 1, got shapes "
                f"{times.shape} and {values.shape}"
            )
        if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
            raise ValueError("Amplitude: times and values must be finite")
        if np.any(np.diff(times) < 0):
            raise ValueError(f"Amplitude: times must not decrease, got {times.tolist()}")

    def __call__(self, t: float) -> float:
        """The factor at time ``t``."""
        return float(np.interp(t, self.times, self.values))


@dataclass
class Load:
    """A value that a step drives: ``target`` reaches ``value`` at the end of the step.

    Without an amplitude the value ramps linearly over the step from what ``target`` holds when
    the step starts (CalculiX's rule for static steps); with one it is ``value * amplitude(t)``.

    Args:
        target: A ``dolfinx.fem.Constant`` (its ``value``) or ``dolfinx.fem.Function`` (its
            array), e.g. a pressure or the values of a Dirichlet condition.
        value: The reference value (scalar or array shaped like the target).
        amplitude: Optional :class:`Amplitude`.
    """

    target: dolfinx.fem.Constant | dolfinx.fem.Function
    value: float | npt.ArrayLike
    amplitude: Amplitude | None = None

    def __post_init__(self) -> None:
        """Check the target kind."""
        if not isinstance(self.target, (dolfinx.fem.Constant, dolfinx.fem.Function)):
            raise TypeError(
                "Load: target must be a dolfinx.fem.Constant or dolfinx.fem.Function, got "
                f"{validation.describe(self.target)}"
            )
        if self.amplitude is not None:
            validation.check_type(self.amplitude, Amplitude, "Load: amplitude")

    def _get(self) -> np.ndarray:
        if isinstance(self.target, dolfinx.fem.Constant):
            return np.array(self.target.value, dtype=float, copy=True)
        return self.target.x.array.copy()

    def _set(self, value: np.ndarray) -> None:
        if isinstance(self.target, dolfinx.fem.Constant):
            self.target.value = value
        else:
            self.target.x.array[:] = value
            self.target.x.scatter_forward()


@dataclass(frozen=True)
class ChangeFriction:
    """New friction of a pair from this step on (CalculiX ``*CHANGE FRICTION``); state kept.

    ``friction=None`` makes the pair frictionless.
    """

    pair: ContactPair
    friction: Friction | None


@dataclass(frozen=True)
class RemovePair:
    """The pair generates no springs from this step on (``*MODEL CHANGE, REMOVE``)."""

    pair: ContactPair


@dataclass(frozen=True)
class AddPair:
    """A removed pair generates springs again from this step on (``*MODEL CHANGE, ADD``)."""

    pair: ContactPair


@dataclass(frozen=True)
class SetSmallSliding:
    """Small sliding (pairing at increment starts only) on or off for a pair from this step on.

    ``small_sliding`` True pairs ``pair`` only at increment starts, False on ccx's schedule.
    """

    pair: ContactPair
    small_sliding: bool


ContactChange = ChangeFriction | RemovePair | AddPair | SetSmallSliding


@dataclass
class AnalysisStep:
    """One step of an analysis (see the module docstring).

    Args:
        procedure: Incrementation (default ``StaticStep(no-op)``: one increment over a period of
            1). Its own ``set_load`` is called after the step's loads are set.
        loads: Values driven over the step.
        bcs: Dirichlet conditions of this step (replacing the previous ones), or None to keep
            them.
        changes: Contact changes applied before the step starts.
        name: Label for messages.
        results: Filled by :func:`run_steps` with the step's increments.
    """

    procedure: Step | None = None
    loads: typing.Sequence[Load] = ()
    bcs: typing.Sequence[compat.DirichletBC] | None = None
    changes: typing.Sequence[ContactChange] = ()
    name: str = ""
    results: list[IncrementResult] = field(default_factory=list, repr=False)


def _no_load(t: float) -> None:
    """A procedure's default load control: the step's loads do everything."""


def _apply_change(change: ContactChange, pairs: list[ContactPair], owner: str) -> None:
    if not any(change.pair is p for p in pairs):
        raise ValueError(f"{owner}: {type(change).__name__}: the pair is not in the problem")
    pair = change.pair
    if isinstance(change, ChangeFriction):
        pair.interaction = SurfaceInteraction(pair.interaction.law, change.friction)
    elif isinstance(change, RemovePair):
        pair.active = False
    elif isinstance(change, AddPair):
        pair.active = True
    elif isinstance(change, SetSmallSliding):
        pair.small_sliding = bool(change.small_sliding)
    else:
        raise TypeError(f"{owner}: unknown contact change {validation.describe(change)}")


def run_steps(
    solver: IncrementSolver, steps: typing.Sequence[AnalysisStep]
) -> list[list[IncrementResult]]:
    """Run the steps one after the other on ``solver``'s problem (docs/method.md §11.6).

    Returns:
        The converged increments of every step (also in ``step.results``).

    Raises:
        ContactConvergenceError: A step failed (earlier steps' results stay in their ``results``).
    """
    check_solver(solver, "run_steps: solver")
    problem = solver.problem
    pairs = [s.pair for s in problem.states]
    total = 0.0
    out = []
    for index, step in enumerate(steps):
        owner = f"run_steps: step {index + 1}" + (f" ({step.name})" if step.name else "")
        validation.check_type(step, AnalysisStep, owner)
        procedure = step.procedure if step.procedure is not None else StaticStep(_no_load)
        if not (dataclasses.is_dataclass(procedure) and hasattr(procedure, "set_load")):
            raise TypeError(
                f"{owner}: procedure must be a dataclass with a set_load field and a run(solver, "
                f"u) method, such as StaticStep; got {validation.describe(procedure)}"
            )
        for change in step.changes:
            _apply_change(change, pairs, owner)
        if step.bcs is not None:
            problem.set_bcs(list(step.bcs))
        starts = [load._get() for load in step.loads]
        period = float(procedure.period)
        own = procedure.set_load
        start_total = total

        def set_load(t, loads=step.loads, starts=starts, period=period, own=own, t0=start_total):
            for load, start in zip(loads, starts):
                if load.amplitude is None:
                    value = start + (np.asarray(load.value, dtype=float) - start) * (t / period)
                else:
                    time = t0 + t if load.amplitude.total_time else t
                    value = np.asarray(load.value, dtype=float) * load.amplitude(time)
                load._set(value)
            own(t)

        runner = dataclasses.replace(procedure, set_load=set_load)
        if isinstance(runner, Step):
            step.results = runner.run(solver, problem.u, start_time=start_total)
        else:  # a procedure of the user's own: the results are shifted afterwards
            step.results = [
                dataclasses.replace(result, total_time=start_total + result.time)
                for result in runner.run(solver, problem.u)
            ]
        out.append(step.results)
        total += period
    return out
