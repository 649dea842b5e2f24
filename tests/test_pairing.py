"""The pairing schedule: the default search keeps nodes on their faces (no ping-pong), CalculiX's
search lets nodes on shared edges flip faces at every re-pairing."""

import pytest
from test_problem import _setup, _solve

import dolfinx_ntf as ntf

pytestmark = pytest.mark.serial


@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
def test_default_search_changes_no_faces_on_a_tie_deck(cell):
    """The punch's slave nodes lie exactly above master nodes and edges (ties)."""
    changes, iterations = {}, {}
    for stable in (True, False):
        problem, pressure, _ = _setup(cell, walk_from_previous_face=stable)
        counts = []
        problem.pairing_callbacks.append(lambda p, counts=counts: counts.append(p.face_changes))
        _, results = _solve(problem, pressure)
        changes[stable] = sum(counts)
        iterations[stable] = [r.iterations for r in results]
    assert changes[True] == 0
    assert all(a <= b for a, b in zip(iterations[True], iterations[False]))
    if cell == "tetrahedron":  # hexahedra have no ping-pong in either mode on this deck
        assert changes[False] > 0
        assert max(iterations[True]) < min(iterations[False])


def test_stable_search_is_the_default():
    problem, _, _ = _setup("hexahedron")
    assert problem.walk_from_previous_face
    assert isinstance(problem.face_changes, int)
    assert ntf.ContactProblem.__init__.__kwdefaults__["walk_from_previous_face"] is True
