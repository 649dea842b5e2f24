"""Linear constraints by elimination (dolfinx_ntf.fem.constraints, *EQUATION; method §13.1)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers import LOWER_TOP, UPPER_TOP, punch_problem
from helpers.decks import reference_node_deck

import dolfinx.fem

import dolfinx_ntf as ntf
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.fem.constraints import LinearConstraint, elimination_rows

pytestmark = pytest.mark.serial

CCX_TESTS = Path("/usr/share/doc/calculix-ccx-test/examples/test")

# ----------------------------------------------------------------------------- pure numpy


def test_first_free_term_is_dependent_and_chains_are_resolved():
    # u3 = 2 u0 ; u5 = u3 - u1 + 1  ->  u5 = 2 u0 - u1 + 1
    constraints = [
        LinearConstraint([1, 0], [0, 0], [1.0, -2.0]),
        LinearConstraint([1, 1, 0], [2, 0, 1], [2.0, -2.0, 2.0], value=2.0),
    ]
    slaves, M, g = elimination_rows(6, constraints)
    assert slaves.tolist() == [3, 5]
    np.testing.assert_allclose(M.toarray(), [[2, 0, 0, 0, 0, 0], [2, -1, 0, 0, 0, 0]])
    np.testing.assert_allclose(g, [0.0, 1.0])


def test_prescribed_first_term_passes_dependence_to_the_next():
    slaves, M, _ = elimination_rows(6, [LinearConstraint([0, 1], [0, 0], [1.0, -1.0])], [0])
    assert slaves.tolist() == [3]
    np.testing.assert_allclose(M.toarray()[0], [1, 0, 0, 0, 0, 0])


def test_contradictory_or_circular_constraints_are_refused():
    tie = LinearConstraint([0, 1], [2, 2], [1.0, -1.0], name="tie")
    with pytest.raises(ValueError, match="tie: every dof of the constraint is prescribed"):
        elimination_rows(6, [tie], [2, 5])
    with pytest.raises(ValueError, match="redundant"):
        elimination_rows(6, [tie, LinearConstraint([1, 0], [2, 2], [1.0, -1.0])], [2])
    chain = [
        LinearConstraint([0, 1], [0, 0], [1.0, -1.0]),
        LinearConstraint([1, 0], [0, 0], [1.0, -1.0]),
    ]
    with pytest.raises(ValueError, match=r"redundant|circular"):
        elimination_rows(6, chain)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"nodes": [0, 1], "components": [0], "coefficients": [1, 1]}, "one entry per term"),
        ({"nodes": [0], "components": [3], "coefficients": [1]}, "components must be 0, 1 or 2"),
        ({"nodes": [-1], "components": [0], "coefficients": [1]}, "not a mesh node"),
        ({"nodes": [0], "components": [0], "coefficients": [np.nan]}, "finite"),
    ],
)
def test_bad_constraint_is_a_clear_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        LinearConstraint(**kwargs)


# ----------------------------------------------------------------------------- the punch


def _solve(problem, pressure, load=10.0):
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    step = ntf.StaticStep(
        lambda t: setattr(pressure, "value", load * t), initial_increment=0.5, fixed=True
    )
    return solver, step.run(solver, problem.u)


def _two_nodes():
    problem, pressure, ft = punch_problem()
    V = problem.u.function_space
    x = V.tabulate_dof_coordinates()
    top = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(UPPER_TOP))
    low = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_TOP))
    a = int(top[np.argmin(x[top, 0] + 0.1 * x[top, 1])])  # a punch corner
    b = int(low[np.argmax(x[low, 0] + 0.1 * x[low, 1])])  # a far corner of the lower block
    return problem, pressure, a, b


def test_tie_gives_equal_displacement_exactly_with_quadratic_newton():
    free, free_pressure, a, b = _two_nodes()
    tie = LinearConstraint([a, b], [2, 2], [1.0, -1.0], name="tie")
    problem, pressure, _ = punch_problem(constraints=[tie])
    solver, results = _solve(problem, pressure)
    u = problem.u.x.array.reshape(-1, 3)
    assert u[a, 2] == u[b, 2]  # exactly
    assert u[a, 2] < 0
    norms = np.array(solver.residual_norms) / solver.residual_norms[0]
    assert norms[-1] < 1e-10 and norms[-2] < 1e-4  # quadratic: ~1e-7 -> ~1e-13
    # the tie changes the solution: the free punch corner sinks more than the far corner
    _solve(free, free_pressure)
    w = free.u.x.array.reshape(-1, 3)
    assert abs(w[a, 2] - w[b, 2]) > 1e-3
    assert all(r.iterations <= 5 for r in results)


def test_constraint_equilibrium_of_the_eliminated_system():
    """With u_b,x = u_a,z / 2 the reduced residual vanishes: r_a,z + r_b,x / 2 = 0 for the full
    residual, and r_b,x = -(force the constraint carries) is not zero."""
    _, _, a, b = _two_nodes()
    tie = LinearConstraint([b, a], [0, 2], [1.0, -0.5], value=1e-4)
    problem, pressure, _ = punch_problem(constraints=[tie])
    _solve(problem, pressure)
    u = problem.u.x.array.reshape(-1, 3)
    assert u[b, 0] - 0.5 * u[a, 2] == pytest.approx(1e-4, abs=1e-15)
    problem.elimination, elimination = None, problem.elimination  # the unreduced residual
    x = problem.u.vector if hasattr(problem.u, "vector") else problem.u.x.petsc_vec
    b_full = x.duplicate()
    problem.form(x)
    problem.assemble_residual(x, b_full)
    r = b_full.array.reshape(-1, 3)
    problem.elimination = elimination
    assert abs(r[b, 0]) > 1e-3
    assert r[a, 2] + 0.5 * r[b, 0] == pytest.approx(0.0, abs=1e-9 * abs(r[b, 0]))
    b_full.destroy()


def test_dependent_dof_with_a_dirichlet_condition_is_refused():
    problem, _, ft = punch_problem()
    V = problem.u.function_space
    # the punch top has Dirichlet conditions on x and y: a tie of two of its x dofs contradicts
    top = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(UPPER_TOP))
    tie = LinearConstraint([int(top[0]), int(top[1])], [0, 0], [1.0, -1.0], name="x tie")
    with pytest.raises(ValueError, match="x tie: every dof of the constraint is prescribed"):
        punch_problem(constraints=[tie])


# ----------------------------------------------------------------------------- ccx decks


def test_equation_cards_are_read(tmp_path):
    deck = tmp_path / "eq.inp"
    text = (CCX_TESTS / "contact1.inp").read_text() if CCX_TESTS.is_dir() else None
    if text is None:
        pytest.skip("needs the package calculix-ccx-test")
    deck.write_text(text)
    equations = read_deck(deck).equations
    assert len(equations) == 6
    assert equations[0].nodes.tolist() == [4, 3]
    assert equations[0].dofs.tolist() == [3, 3]
    assert equations[0].coefficients.tolist() == [1.0, -1.0]
    deck.write_text(text.replace("4,3,1.,3,3,-1.", "4,3,1.,3,3"))
    with pytest.raises(DeckError, match=r"eq.inp:\d+: \*EQUATION: 2 terms"):
        read_deck(deck)
    deck.write_text(text.replace("4,3,1.,3,3,-1.", "4,3,0.,3,3,-1."))
    with pytest.raises(DeckError, match="dependent\\) coefficient is zero"):
        read_deck(deck)


@pytest.mark.skipif(not CCX_TESTS.is_dir(), reason="needs the package calculix-ccx-test")
@pytest.mark.parametrize("name", ["contact1", "contact3", "contact6"])
def test_ccx_equation_decks_match_ccx(tmp_path, name):
    """ccx's own *EQUATION contact decks at its default controls against its .dat (ccx 2.20's
    output shipped with the test suite, also run here when ccx is installed)."""
    shutil.copy(CCX_TESTS / f"{name}.inp", tmp_path / f"{name}.inp")
    result = run_job(name, tmp_path, progress=False)
    assert result.completed
    ours = read_dat(tmp_path / f"{name}.dat")
    # the reference shipped with the suite (ccx 2.22's adds step/increment headers: skipped)
    text = (CCX_TESTS / f"{name}.dat.ref").read_text(encoding="latin-1")
    kept = [line for line in text.splitlines() if not re.match(r"\s*(S T E P|INCREMENT)\s", line)]
    (tmp_path / "reference.dat").write_text("\n".join(kept) + "\n")
    references = [read_dat(tmp_path / "reference.dat")]
    if shutil.which("ccx"):
        from dolfinx_ntf.calculix.ccx import read_ccx_dat, run_ccx

        ccx_dir = tmp_path / "ccx"
        ccx_dir.mkdir()
        shutil.copy(CCX_TESTS / f"{name}.inp", ccx_dir / f"{name}.inp")
        run_ccx(ccx_dir, name, timeout=120)
        references.append(read_ccx_dat(ccx_dir, name))
    for reference in references:
        assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in reference]
        for mine, theirs in zip(ours, reference):
            np.testing.assert_array_equal(mine.labels, theirs.labels)
            scale = np.abs(theirs.values).max()
            assert np.abs(mine.values - theirs.values).max() <= 1e-6 * scale, mine.name


@pytest.mark.ccx
@pytest.mark.skipif(
    shutil.which("ccx") is None or not CCX_TESTS.is_dir(),
    reason="needs ccx and the package calculix-ccx-test",
)
def test_dependent_slave_node_with_load_and_chain_matches_ccx(tmp_path):
    """contact1 with its slave node 10 dependent (and loaded) and a 3-term equation on it."""
    from dolfinx_ntf.calculix.ccx import read_ccx_dat, run_ccx

    text = (CCX_TESTS / "contact1.inp").read_text()
    old = "2\n9,3,1.,10,3,-1.\n2\n13,3,1.,10,3,-1.\n2\n14,3,1.,10,3,-1.\n"
    new = "2\n10,3,1.,9,3,-1.\n2\n13,3,1.,9,3,-1.\n3\n14,3,1.,9,3,-2.,10,3,1.\n"
    assert old in text
    text = text.replace(old, new).replace("*STATIC\n", "*STATIC\n0.5, 1.\n")
    for where in ("ours", "ccx"):
        (tmp_path / where).mkdir()
        (tmp_path / where / "dep.inp").write_text(text)
    result = run_job("dep", tmp_path / "ours", progress=False)
    run_ccx(tmp_path / "ccx", "dep", timeout=120)
    u = result.last.displacement_of([9, 10, 14])
    assert u[1, 2] == u[0, 2] and u[2, 2] == pytest.approx(u[0, 2], abs=1e-18)
    ours, theirs = read_dat(tmp_path / "ours" / "dep.dat"), read_ccx_dat(tmp_path / "ccx", "dep")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
    for mine, reference in zip(ours, theirs):
        scale = np.abs(reference.values).max()
        assert np.abs(mine.values - reference.values).max() <= 1e-6 * scale, mine.name


@pytest.mark.skipif(not CCX_TESTS.is_dir(), reason="needs the package calculix-ccx-test")
def test_unsupported_reference_nodes_are_refused(tmp_path):
    # two free reference components in one equation
    text = reference_node_deck("*CLOAD\n99,3,-1.\n")
    text = text.replace(
        "      99, 0.5, 0.5, 1.5\n", "      99, 0.5, 0.5, 1.5\n      98, 0., 0., 2.\n"
    )
    text = text.replace("2\n11,3,1.,99,3,-1.\n", "3\n11,3,1.,99,3,-1.,98,3,1.\n")
    (tmp_path / "ref.inp").write_text(text)
    with pytest.raises(ValueError, match=r"ref.inp:\d+: \*EQUATION: more than one component"):
        run_job("ref", tmp_path, progress=False)
    # a force on a prescribed reference component
    text = reference_node_deck("*BOUNDARY\n99,3,3,-1.E-6\n*CLOAD\n99,3,-1.\n")
    (tmp_path / "ref.inp").write_text(text)
    with pytest.raises(ValueError, match=r"node 99 belongs to no element and carries a \*CLOAD"):
        run_job("ref", tmp_path, progress=False)


def _compare_with_ccx(tmp_path: Path, text: str, *, predictor: bool = True):
    """Run ``text`` with both codes; first increment to round-off, second within ccx's controls."""
    from dolfinx_ntf.calculix.ccx import read_ccx_dat, run_ccx

    for where in ("ours", "ccx"):
        (tmp_path / where).mkdir()
        (tmp_path / where / "ref.inp").write_text(text)
    result = run_job("ref", tmp_path / "ours", progress=False, predictor=predictor)
    run_ccx(tmp_path / "ccx", "ref", timeout=120)
    ours, theirs = read_dat(tmp_path / "ours" / "ref.dat"), read_ccx_dat(tmp_path / "ccx", "ref")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
    for mine, reference in zip(ours, theirs):
        # the second increment within ccx's default controls (ccx takes 2 or 11 iterations there,
        # we 3 or 4)
        bound = 1e-12 if mine.time == 0.5 else 1e-3
        scale = np.abs(reference.values).max()
        assert np.abs(mine.values - reference.values).max() <= bound * scale, mine.name
    return result, ours


@pytest.mark.ccx
@pytest.mark.skipif(
    shutil.which("ccx") is None or not CCX_TESTS.is_dir(),
    reason="needs ccx and the package calculix-ccx-test",
)
def test_loaded_free_reference_node_matches_ccx(tmp_path):
    """Face nodes tied to a node in no element that carries the load: the first equation gives
    the node's displacement, its force acts on the face by virtual work."""
    result, ours = _compare_with_ccx(tmp_path, reference_node_deck("*CLOAD\n99,3,-1.\n"))
    top = result.last.displacement_of([11, 12, 15, 16])[:, 2]
    assert np.all(top == top[0]) and top[0] < 0
    u = next(b for b in ours if b.name == "U" and b.time == 1.0)
    assert u.rows[-1][0] == 99 and u.rows[-1][3] == pytest.approx(top[0], rel=1e-6)


@pytest.mark.ccx
@pytest.mark.skipif(
    shutil.which("ccx") is None or not CCX_TESTS.is_dir(),
    reason="needs ccx and the package calculix-ccx-test",
)
def test_prescribed_reference_node_matches_ccx(tmp_path):
    """Face nodes tied to a node in no element whose displacement is prescribed: its value becomes
    the constraints' right-hand side; ccx prints it as the node's displacement."""
    # Without the predictor: from it both codes start the second increment at the same residual
    # (6269 % of the average force), creep down (ccx 11 iterations, we 10) and stop within
    # R_n = 0.005 at states 9e-3 apart (reaction forces); from u_n we converge in 3, closer to
    # the solution than ccx's state. The predictor is not what this test checks.
    text = reference_node_deck("*BOUNDARY\n99,3,3,-1.E-6\n")
    result, ours = _compare_with_ccx(tmp_path, text, predictor=False)
    np.testing.assert_array_equal(result.last.displacement_of([11, 12, 15, 16])[:, 2], -1e-6)
    assert ours[0].rows[-1][1:] == (0.0, 0.0, -5e-7)


@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
def test_python_tie_matches_ccx_on_the_exported_deck(tmp_path):
    """The punch with a tie solved in Python and by ccx on the deck write_inp exports."""
    from helpers import LOWER_BOTTOM, POISSON_RATIO, YOUNGS_MODULUS

    from dolfinx_ntf.calculix.ccx import read_ccx_dat, run_ccx
    from dolfinx_ntf.calculix.writer import BoundarySpec, PressureSpec, StepSpec, write_inp
    from dolfinx_ntf.solvers.convergence import TIGHT_FIELD_CONTROLS

    _, _, a, b = _two_nodes()
    tie = LinearConstraint([a, b], [2, 2], [1.0, -1.0], name="tie")
    problem, pressure, ft = punch_problem(constraints=[tie])
    _solve(problem, pressure)
    numbering = write_inp(
        tmp_path / "tie.inp",
        displacement_space=problem.u.function_space,
        materials=(YOUNGS_MODULUS, POISSON_RATIO),
        pairs=[problem.states[0].pair],
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, LOWER_BOTTOM)),
            BoundarySpec(ntf.FacetSurface(ft, UPPER_TOP), components=(0, 1)),
        ],
        steps=[
            StepSpec(
                pressures=[PressureSpec(ntf.FacetSurface(ft, UPPER_TOP), 10.0)],
                increments=2,
                field_controls=TIGHT_FIELD_CONTROLS,
            )
        ],
        constraints=[tie],
    )
    assert "*EQUATION" in (tmp_path / "tie.inp").read_text()
    run_ccx(tmp_path, "tie", timeout=120)
    last = [block for block in read_ccx_dat(tmp_path, "tie") if block.name == "U"][-1]
    assert last.time == 1.0
    ours = problem.u.x.array.reshape(-1, 3)
    rows = np.searchsorted(last.labels, numbering.node_ids, sorter=np.argsort(last.labels))
    theirs = last.values[np.argsort(last.labels)[rows]]
    scale = np.abs(theirs).max()
    assert np.abs(ours - theirs).max() < 1e-6 * scale
    assert theirs[a, 2] == pytest.approx(theirs[b, 2], abs=1e-7 * scale)
