"""The increments of a ``*MODAL DYNAMIC`` step as ccx 2.20 takes them (docs/method.md §25.3).

Measured with ccx 2.20 on a cantilever under a constant load (printing every increment):

- fixed increments (the default; ccx 2.20 also keeps them for a bare ``DIRECT``, which it does not
  recognize, and for ``DIRECT=YES``): the initial increment over and over until the step time
  reaches or passes the period; the last increment is not shortened (``3e-6`` over a period of
  ``1e-5`` prints at 3, 6, 9 and 12e-6);
- ``DIRECT=NO``: the initial increment (even above the maximum), then each increment 1.5 times
  the last, at most the maximum, the last one cut to end at the period (``1e-6`` over ``1e-5``:
  1, 2.5, 4.75, 8.125, 10e-6).

DELTMX bounds the change of the loads within an increment; this runner's loads are constant over
the step (``*CLOAD`` without amplitude), so it never binds.
"""

from __future__ import annotations

from .deck import Static

__all__ = ["modal_increments"]

#: Relative tolerance on the period when summing increments (200 x 1e-7 reaches 2e-5).
_END = 1e-9


def modal_increments(static: Static, *, variable: bool, max_increments: int) -> list[float]:
    """The increment sizes of the step, in order.

    Args:
        static: The step's data line (initial increment, period, maximum).
        variable: ``DIRECT=NO`` (growing increments) rather than fixed ones.
        max_increments: The step's INC: more increments are an error, as in ccx.
    """
    period, dt = static.period, min(static.initial_increment, static.period)
    maximum = static.maximum if static.maximum is not None else float("inf")
    sizes: list[float] = []
    t = 0.0
    while t < period * (1.0 - _END):
        if variable and t + dt > period:
            dt = period - t
        sizes.append(dt)
        t += dt
        if len(sizes) > max_increments:
            raise ValueError(
                f"the *MODAL DYNAMIC step needs more than INC={max_increments} increments"
            )
        if variable:
            dt = min(1.5 * dt, maximum)
    return sizes
