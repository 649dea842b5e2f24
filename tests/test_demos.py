"""The demos are tests too: both run on their coarse meshes and their summaries are checked.

Serial here; tests/parallel/test_parallel.py runs the punch demo on 2 and 3 processes.
"""

import itertools
from pathlib import Path

import pytest
from helpers.demos import load_demo

pytestmark = pytest.mark.serial


def test_punch_demo_balances_the_load(tmp_path):
    summary = load_demo("punch").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    assert summary["increments"] == 4
    assert summary["load"][-1] == pytest.approx(100.0 * 40 * 40)
    # Equilibrium of the punch: Σ F_z and Σ p A n_z equal the load; Σ p A exceeds it by the tilt
    # of the master normals only (measured 2.5e-7).
    assert summary["vertical_error"] < 1e-8
    assert summary["normal_error"] < 1e-8
    assert summary["reaction_error"] < 1e-8  # the block bottom carries the load (reaction helper)
    assert 0 < summary["pressure_area_deviation"] < 1e-5
    # All 5 x 5 punch-bottom nodes are in contact from the first increment on; the pressure peaks
    # at the punch edges (measured 2.1 times the mean).
    assert summary["springs"] == [25, 25, 25, 25]
    assert summary["contact_area"] == pytest.approx(40 * 40, rel=1e-3)
    assert summary["max_pressure"] > 1.5 * summary["mean_pressure"]
    # Measured 4, 2, 2, 2 iterations (3-4 on the default mesh).
    assert max(summary["iterations"]) <= 6
    assert Path(summary["xdmf"]).exists() and Path(summary["xdmf"]).with_suffix(".h5").exists()


def test_hertz_demo_is_close_to_hertz(tmp_path):
    summary = load_demo("hertz_sphere").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    assert summary["equilibrium_error"] < 1e-8
    assert summary["unpaired_penetrations"] == 0
    # Measured on the coarse mesh (about 4 elements across the contact radius): total force
    # 3.61e5 N, force of the fitted profile -2.4 %, contact radius -3.5 %, peak pressure +4.7 %
    # (fit) and +4.2 % (nodal maximum); on the default mesh -0.6 % radius, +2.3 % peak pressure.
    assert summary["force"] == pytest.approx(3.61e5, rel=0.1)
    assert abs(summary["fit_force_error"]) < 0.06
    assert abs(summary["a_error"]) < 0.08
    assert abs(summary["p0_error"]) < 0.10
    assert abs(summary["p_max_error"]) < 0.15
    # Hertz's radius falls between the last closed node and the first open one.
    assert summary["a_last_closed"] < summary["a_hertz"] < summary["a_first_open"]
    # Measured 3-5 Newton iterations per increment, no cutback.
    assert summary["increments"] == 8
    assert max(summary["iterations"]) <= 8
    assert Path(summary["xdmf"]).exists() and Path(summary["png"]).exists()
    assert (
        Path(summary["deformed_png"]).stat().st_size > 10_000
    )  # the deformed mesh, coloured by p_h


def test_hertz_cylinder_2d_demo_is_close_to_hertz(tmp_path):
    summary = load_demo("hertz_cylinder_2d").main(
        ["--coarse", "--quiet", "--output", str(tmp_path)]
    )
    assert summary["passed"]
    # The springs carry F'/2 and the block's bottom reacts with it (measured 2e-13 both).
    assert summary["load_error"] < 1e-8 and summary["equilibrium_error"] < 1e-8
    # Measured on the coarse mesh (five elements across b): b -1.2 % and p0 +0.8 % (fit), peak
    # nodal pressure -0.5 %; on the default mesh b -0.2 %, p0 +0.7 %.
    assert abs(summary["b_error"]) < 0.02
    assert abs(summary["p0_error"]) < 0.02
    assert abs(summary["p_max_error"]) < 0.03
    # Hertz's half-width falls between the last closed node and the first open one.
    assert summary["b_last_closed"] < summary["b_hertz"] < summary["b_first_open"]
    # Measured 8, 7, 5, 7 Newton iterations, no cutback.
    assert summary["increments"] == 4
    assert max(summary["iterations"]) <= 10
    assert Path(summary["xdmf"]).exists() and Path(summary["png"]).stat().st_size > 10_000


def test_sliding_block_2d_demo_slips_at_mu(tmp_path):
    summary = load_demo("sliding_block_2d").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    # Press (2 increments), small drag (1), drag (4), mu raised and drag (4); 9 springs.
    assert summary["increments"] == 11 and summary["springs"] == 9
    # Measured: after the small drag F_x / F_y = 0.019 and no spring slips; at the end of the
    # drags every spring slips with |F_T| = mu F_N to 3e-16, sum |F_T| = mu sum F_N to 1e-16,
    # and F_x / F_y = 0.200008, 0.299984 (the tilt of the base's deformed top).
    assert summary["stick_sliding"] == 0 and 0.01 < summary["ratio_stick"] < 0.05
    assert summary["end_sliding"] == [9, 9]
    assert summary["slip_error"] < 1e-12 and summary["coulomb_error"] < 1e-12
    assert summary["ratio_drag"] == pytest.approx(0.2, rel=1e-3)
    assert summary["ratio_mu"] == pytest.approx(0.3, rel=1e-3)
    assert summary["equilibrium_error"] < 1e-8
    assert Path(summary["xdmf"]).exists() and Path(summary["png"]).stat().st_size > 10_000


def test_impact_demo_keeps_the_energy(tmp_path):
    summary = load_demo("impact").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    # Total energy (kinetic + strain + spring + gravity) with ccx's alpha = -0.05 and 0.25 us
    # increments: measured 0.75 % lost by the end, never more (bound 1 %).
    assert summary["energy_drift"] < 0.01
    # The block touches the base after GAP / v0 = 2 us, stays about 30 us (measured 2.0 to
    # 32.25 us) and leaves upwards with 0.78 of its momentum; the contact impulse matches the
    # change of its momentum (trapezoidal rule; measured 1e-12).
    assert summary["contact_start"] == pytest.approx(2.0e-6, abs=0.3e-6)
    assert 25e-6 < summary["contact_end"] < 38e-6
    assert summary["contact_force"][-1] == 0.0
    assert 0.5 < summary["restitution"] < 1.0
    assert summary["momentum_error"] < 1e-6
    assert max(summary["iterations"]) <= 8
    assert Path(summary["xdmf"]).exists() and Path(summary["png"]).exists()


def test_sliding_block_demo_sticks_then_slips(tmp_path):
    summary = load_demo("sliding_block").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    assert summary["increments"] == 17 and summary["springs"] == 25
    # stick: the central node follows tau = lambda t during the press and the small drag
    assert summary["centre_sticks"] and summary["stick_law_error"] < 1e-10
    # slip: |tau| = mu p at every sliding spring, all of them at the end of each drag; the mean
    # shear then is +-mu p (measured +0.9997, -1.0000, +1.0000), the last one with the raised mu
    assert summary["slip_error"] < 1e-10
    assert summary["end_sliding"] == [25, 25, 25]
    assert summary["mean_ratio_drag"] == pytest.approx(1.0, abs=2e-3)
    assert summary["mean_ratio_back"] == pytest.approx(-1.0, abs=2e-3)
    assert summary["mean_ratio_mu"] == pytest.approx(1.0, abs=2e-3)
    assert summary["equilibrium_error"] < 1e-8
    assert Path(summary["png"]).exists() and Path(summary["xdmf"]).exists()


def test_frictional_punch_demo_has_stick_and_slip_zones(tmp_path):
    summary = load_demo("frictional_punch").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    # measured on the coarse mesh: the 5 central nodes stick, the 20 of the rim slip
    assert (summary["stick_nodes"], summary["slip_nodes"]) == (5, 20)
    assert summary["stick_radius"] <= summary["slip_radius"]
    assert summary["slip_error"] < 1e-10 and summary["stick_margin"] < 0
    assert summary["equilibrium_error"] < 1e-8
    assert summary["max_shear_over_pressure"] <= 0.2 * (1 + 1e-10)
    assert Path(summary["png"]).exists() and Path(summary["xdmf"]).exists()


def test_compare_continuumload_demo(tmp_path):
    rows = load_demo("compare_continuum").main(["--coarse", "--quiet"])
    by = {row["method"]: row for row in rows}
    assert set(by) == {"ntf-rigid", "ntf-active", "ntf-meshed", "penalty", "nitsche"}
    # A clamped flat block and the analytical plane are the same master: same springs, same force.
    assert by["ntf-meshed"]["force"] == pytest.approx(by["ntf-rigid"]["force"], rel=1e-8)
    assert by["ntf-meshed"]["dofs"] > 2 * by["ntf-rigid"]["dofs"]
    # The active-set Newton converges to the same solution (tolerances differ).
    assert by["ntf-active"]["force"] == pytest.approx(by["ntf-rigid"]["force"], rel=1e-6)
    for row in rows:
        # The recovered pressure carries the reaction (quadrature degree 8 for the UFL forms;
        # measured within 5e-4 on this mesh).
        assert abs(row["pressure_force_error"]) < 2e-3, row["method"]
        # Hertz on 2.5 elements across the contact radius: measured a within 1 %, p0 within 3 %.
        assert abs(row["a_error"]) < 0.03 and abs(row["p0_error"]) < 0.06, row["method"]
        if row["method"].startswith("ntf"):  # projected UFL pressures spill to the next node
            # The edge lies between the bracketing nodes, within one fine element (1 mm) of Hertz's
            # (gmsh 4.8: 2.819 < a = 2.824 < 3.051; gmsh 4.13's mesh: 2.854 > a = 2.828).
            assert abs(row["a_last_closed"] - row["a_hertz"]) < 1.0, row["method"]
            assert row["a_first_open"] > row["a_hertz"], row["method"]
        assert len(row["iterations"]) == 4 and max(row["iterations"]) <= 8, row["method"]
    # Penalties penetrate (~p0/K), Nitsche much less.
    assert by["nitsche"]["penetration"] < 0.5 * by["penalty"]["penetration"]


def test_a_soft_joint_that_overshoots_converges_to_equilibrium(monkeypatch):
    """With p0 = 0.01 MPa the first update presses the punch far into the exponential branch:
    forces run to 1e10 and come back. The increment ends in equilibrium (it once ended 45 % off
    the load: the force scale remembered the runaway iterates)."""
    import dolfinx_ntf as ntf

    demo = load_demo("preloaded_modes")
    monkeypatch.setattr(demo, "LAW", ntf.ExponentialLaw(c0=0.5, p0=0.01))
    summary = demo.main(["--coarse", "--quiet"])
    for row in summary["rows"]:
        assert row["contact_force"] == pytest.approx(row["load"], rel=1e-6)
    assert summary["rows"][0]["iterations"] > 10  # the overshoot happened


def test_preloaded_modes_demo_bounces_on_the_joint_stiffness():
    summary = load_demo("preloaded_modes").main(["--coarse", "--quiet"])
    rows = summary["rows"]
    assert [r["load"] for r in rows] == pytest.approx([400.0, 800.0, 1200.0, 1600.0])
    for row in rows:
        # The springs carry the load exactly; their stiffness is beta F (EXPONENTIAL law).
        assert row["contact_force"] == pytest.approx(row["load"], rel=1e-7)  # measured 1.2e-8
        # The bounce is the rigid punch on the springs, lowered by the bodies' compliance
        # (measured 0.04 % to 0.15 % below, growing with the joint's stiffness), and it moves the
        # punch's mass along z (measured 1.0008 to 1.0032 of it: the block moves with it).
        ratio = row["bounce"] / row["rigid_estimate"]
        assert 0.995 < ratio < 1.0
        assert row["bounce_mass"] == pytest.approx(summary["punch_mass"], rel=5e-3)
    ratios = [r["bounce"] / r["rigid_estimate"] for r in rows]
    assert all(later < earlier for earlier, later in itertools.pairwise(ratios))
    # Frequency as the square root of the preload.
    assert rows[-1]["bounce"] / rows[0]["bounce"] == pytest.approx(2.0, rel=5e-3)
    assert abs(summary["floating"]) < 1e-3 * rows[0]["bounce"]  # no springs: the punch floats


def test_hot_block_demo_balances_heat_and_force(tmp_path):
    summary = load_demo("hot_block").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    # Three transient increments and the steady state; 5 x 5 slave nodes, all in contact.
    assert summary["increments"] == 4 and summary["springs"] == 25
    # The springs carry the load in every increment (measured 9e-13).
    assert summary["force_error"] < 1e-8
    # Steady state: the heat through the contact is the heat entering at the hot top and leaving
    # at the cold bottom, within the converged residual's bound (measured 4e-12 W against a bound
    # of 6e-11 W on a flow of 49.74 W); the transient storage balance likewise (7e-14 W).
    assert summary["heat_through_contact"] < 0  # into the slave (hot) side: negative
    assert summary["balance_top"] <= summary["balance_bound"] < 1e-8
    assert summary["balance_bottom"] <= summary["balance_bound"]
    assert summary["storage_error"] <= summary["storage_bound"] < 1e-6
    assert summary["heat_in_top"] == pytest.approx(-summary["heat_in_bottom"], rel=1e-10)
    # The cold block is wider than the hot one: its spreading makes the flow exceed the 1D series
    # estimate with the mean conductance (measured 49.74 W against 35.78 W), never fall below it.
    assert summary["heat_in_top"] > summary["series_estimate"]
    # The conductance varies with the pressure over the interface (measured p 3.6 to 27.2 MPa:
    # h from 0.0053 to the table's end 0.02) and the jump T_m - T_s is q/(h A) at every spring.
    assert summary["pressure_range"][0] < 10.0 < summary["pressure_range"][1]
    assert summary["conductance_range"][1] == pytest.approx(0.02)
    assert summary["conductance_range"][0] < 0.01
    assert summary["jump_error"] < 1e-8
    assert summary["jump_range"][1] < 0  # the master (cold) side is colder at every spring
    assert min(summary["t_min"]) >= 293.0 - 1e-9 and max(summary["t_max"]) <= 373.0 + 1e-9
    # Measured 6, 4, 4, 4 Newton iterations.
    assert max(summary["iterations"]) <= 10
    assert Path(summary["xdmf"]).exists() and Path(summary["xdmf"]).with_suffix(".h5").exists()
    assert Path(summary["png"]).stat().st_size > 10_000
    assert Path(summary["interface_png"]).stat().st_size > 10_000


def test_plastic_indentation_demo_leaves_a_dent(tmp_path):
    summary = load_demo("plastic_indentation").main(
        ["--coarse", "--quiet", "--output", str(tmp_path)]
    )
    assert summary["passed"]
    # 4 loading increments, 4 + 2 withdrawing ones (after the seating increment).
    assert summary["increments"] == 10
    # The contact force is the bottom's reaction (measured 2.5e-12 of the peak).
    assert summary["equilibrium_error"] < 1e-8
    # Plastic flow under the ball; the ball leaves the dent within the first withdrawal (measured
    # 0.1764 mm of 0.1999 mm at the peak on the coarse mesh): no spring, no force at the end.
    assert summary["alpha_max"] > 0.05 and summary["yielding_at_peak"] > 0
    assert summary["final_springs"] == 0 and summary["final_force"] == 0.0
    assert 0.5 * summary["dent_at_peak"] < summary["residual_dent"] < summary["dent_at_peak"]
    # Reverse plasticity while withdrawing (measured 534 points, plastic strain changes 9.5e-4):
    # small beside the peak's plastic strains.
    assert summary["alpha_changed_unloading"] < 0.05 * summary["alpha_max"]
    # The elastic control springs back entirely and starts at Hertz's force (measured +6.7 %,
    # then +11.8 %, +16.7 %, +19.4 % as the contact grows against the clamped block).
    assert abs(summary["elastic_residual_dent"]) < 1e-8 * 0.2
    assert abs(summary["hertz_error"]) < 0.1
    assert summary["softer_than_elastic"] and summary["cycle_work"] > 0
    assert max(summary["iterations"]) <= 15  # measured 7-8 in the plastic loading
    assert Path(summary["xdmf"]).exists() and Path(summary["png"]).stat().st_size > 10_000


def test_prism_punch_demo_balances_the_load(tmp_path):
    summary = load_demo("prism_punch").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    # a gmsh mesh of prisms beside hexahedra, read as one mesh of hexahedra
    assert summary["cells"] == 300
    assert summary["increments"] == 2
    assert summary["reaction_error"] < 1e-8
    assert summary["force_error"] < 1e-7  # measured 1.9e-8: the last Newton residual
    # every slave node of the prisms' triangles is closed; the flat punch's pressure is lowest at
    # the centre and highest at its rim (measured 43 and 196 MPa for a mean of 100)
    assert summary["closed"] == summary["springs"] == 41
    assert summary["centre_pressure"] < summary["mean_pressure"] < summary["max_pressure"]
    assert Path(summary["png"]).stat().st_size > 10_000


def test_curved_prisms_demo(tmp_path):
    """The ring of gmsh's 15-node prisms: dolfinx 0.11 solves it, older releases say why not."""
    from dolfinx_ntf import compat

    summary = load_demo("curved_prisms").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    if compat.DOLFINX_VERSION < (0, 11):
        assert summary["passed"] is None
        assert "needs dolfinx 0.11" in summary["skipped"]
        return
    assert summary["passed"]
    # the clamp's reaction (constrained centres' forces handed on) equals the load: 7.3e-13
    assert summary["equilibrium_error_15"] < 1e-9 and summary["equilibrium_error_18"] < 1e-9
    assert summary["load_15"][1] == pytest.approx(50.0 * 20 * 20, rel=1e-12)
    # Castigliano's thin curved beam: 0.988 on the coarse mesh, 0.995 on the default one
    assert 0.97 < summary["ratio_castigliano"] < 1.0
    # 18-node prisms: gmsh's centres on these ruled faces are the quad8 ones (2.3e-13)
    assert summary["difference_18"] < 1e-9
    assert Path(summary["png"]).stat().st_size > 10_000
