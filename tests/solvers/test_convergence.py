"""The force-scaled convergence test on sequences of numbers: CalculiX's test accepts a runaway
iterate whose forces have grown with it, the bounded test does not, and both accept an ordinary
quadratically converging solve."""

import pytest

from dolfinx_ntf.solvers.convergence import TIGHT_FIELD_CONTROLS, ForceScaledTest

#: (q, r, c, du) after each update of a body with no support under a unit load: the first
#: update leaves forces of order 1, the second and third run away to 1e16 with the residual at
#: 5, 46 times the first (the numbers the false convergence showed).
RUNAWAY = [(1.0, 0.5, 1.0, 1.0), (1e14, 4.0, 1e12, 1e12), (1.8e16, 5.0, 1e14, 1e14)]
#: An ordinary solve: forces of order 1, residuals falling quadratically.
ORDINARY = [(1.0, 1e-3, 1e-2, 1.0), (1.0, 1e-7, 1e-4, 1.0), (1.0, 1e-14, 1e-8, 1.0)]


def _decisions(test: ForceScaledTest, iterates, start=(0.0, 0.109)) -> list[bool]:
    test.begin_solve(0.0)
    test.begin_iterations(*start)
    return [test.converged(k + 1, *iterate) for k, iterate in enumerate(iterates)]


def test_calculix_scale_accepts_a_runaway_the_bounded_one_refuses():
    controls = dict(TIGHT_FIELD_CONTROLS)
    assert _decisions(ForceScaledTest(controls), RUNAWAY)[-1]  # CalculiX's: R_l q~ > 5
    assert not any(_decisions(ForceScaledTest(controls, bounded=True), RUNAWAY))


@pytest.mark.parametrize("bounded", [False, True])
def test_ordinary_solve_converges_either_way(bounded):
    decisions = _decisions(ForceScaledTest(dict(TIGHT_FIELD_CONTROLS), bounded=bounded), ORDINARY)
    assert decisions == [False, False, True]


#: (q, r, c, du) of a soft exponential joint's first increment (a punch, p0 = 0.01 MPa): the first
#: update overshoots into the exponential branch, forces run to 1e10 and come back; at the last
#: the residual is 0.7 of the first while the contact force is still 45 % off the load.
RETURNING = [
    (1e9, 7e10, 26.0, 26.0),
    (1e8, 2e9, 1.1, 26.0),
    (1e5, 2e3, 1.0, 26.0),
    (100.0, 61.0, 0.69, 26.0),
]


def test_a_solve_that_ran_away_and_came_back_is_judged_by_the_forces_it_came_back_to():
    controls = dict(TIGHT_FIELD_CONTROLS)
    start = (80.0, 87.7)
    assert _decisions(ForceScaledTest(controls), RETURNING, start)[-1]  # R_n q~ = 5e5 > 61
    bounded = ForceScaledTest(controls, bounded=True)
    assert not any(_decisions(bounded, RETURNING, start))  # q~ = 100: 61 > R_n q~
    settled = [(100.0, 0.1, 1e-3, 26.0), (100.0, 1e-9, 1e-7, 26.0)]
    assert [bounded.converged(5 + k, *iterate) for k, iterate in enumerate(settled)] == [
        False,
        True,
    ]


def test_residual_above_the_first_passes_only_on_the_converged_scale():
    """A residual above the increment's first converges only if it is small on the scale of the
    converged increments: an increment that starts in equilibrium (first residual 0) still ends."""
    test = ForceScaledTest(dict(TIGHT_FIELD_CONTROLS), bounded=True)
    assert _decisions(test, ORDINARY)[-1]
    test.end_solve()
    quiet = [(1.0, 1e-13, 1e-9, 1e-9), (1.0, 2e-13, 1e-12, 1e-9)]
    assert _decisions(test, quiet, start=(1.0, 0.0))[-1]  # 2e-13 <= R_n * 1
    # forces jump a millionfold: the residual 1e-8 passes on their scale, not on the converged
    loud = [(1.0, 1e-13, 1e-9, 1e-9), (1e6, 1e-8, 1e-12, 1e-9)]
    assert not _decisions(test, loud, start=(1.0, 0.0))[-1]
    calculix = ForceScaledTest(dict(TIGHT_FIELD_CONTROLS), past_averages=[1.0])
    assert _decisions(calculix, loud, start=(1.0, 0.0))[-1]
