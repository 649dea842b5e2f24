"""The decks and the machinery of ``benchmarks/vs_ccx.py``, on the small decks (seconds, no timing).

The decks must be what the benchmark claims (ties, law, controls, incrementation) and valid ccx
input: ``read_deck`` reads them and, where ccx is installed, ccx 2.20 runs the coarse quarter
sphere to the end. The benchmark itself must turn a failing run into a row of its table.
"""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import ccx_decks
import ccx_suite
import numpy as np
import pytest
import vs_ccx

from dolfinx_ntf.calculix.ccx import read_sta, run_ccx
from dolfinx_ntf.calculix.deck import read_deck, surface_nodes

pytestmark = pytest.mark.serial

needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")


def _write(name: str, directory: Path):
    (deck,) = ccx_decks.select_decks([name])
    deck.write(directory)
    return read_deck(directory / f"{name}.inp")


def _law(deck) -> tuple:
    (pair,) = deck.contact_pairs
    behavior = deck.interactions[pair.interaction].behavior
    return behavior.pressure_overclosure, behavior.values[:2]


def _on_lines(values: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """Which ``values`` equal one of ``lines`` exactly."""
    return np.isin(values, lines)


def test_tie_punch_slave_nodes_lie_exactly_on_master_nodes_and_edges(tmp_path):
    deck = _write("tie_punch", tmp_path)
    assert list(deck.elements) == ["C3D8"]
    assert _law(deck) == ("LINEAR", (1e7, 3.0))
    (step,) = deck.steps
    assert step.static.direct and step.static.initial_increment == step.static.period
    controls = step.field_controls()
    assert controls["R_n"] == 1e-9 and controls["C_n"] == 1e-9
    assert step.contact_elements

    (pair,) = deck.contact_pairs
    slave = deck.node_coords[deck.node_index(surface_nodes(deck, pair.slave))]
    master = deck.node_coords[deck.node_index(surface_nodes(deck, pair.master))]
    assert slave.shape[0] == 49
    assert np.all(slave[:, 2] == 0.0) and np.all(master[:, 2] == 0.0)
    # Exact ties: the slave grid lines x, y = 30, 50, 70 are master grid lines, bit for bit.
    master_lines = np.unique(master[:, 0])
    on_x, on_y = _on_lines(slave[:, 0], master_lines), _on_lines(slave[:, 1], master_lines)
    assert np.count_nonzero(on_x & on_y) == 9  # above master nodes
    assert np.count_nonzero(on_x ^ on_y) == 24  # above master edges
    assert set(slave[on_x, 0]) == {30.0, 50.0, 70.0}


@pytest.mark.parametrize("n", sorted(ccx_decks.PUNCH_SIZES))
def test_punch_sizes_keep_the_ties(n):
    model = ccx_decks.punch_model(ccx_decks.PUNCH_SIZES[n])
    x = model.V.mesh.geometry.x
    top = x[np.isclose(x[:, 2], 0.0)]
    inside = (top[:, 0] >= 30.0) & (top[:, 0] <= 70.0) & (top[:, 1] >= 30.0) & (top[:, 1] <= 70.0)
    # Both bodies have nodes at z = 0; within the punch footprint a master node under a slave
    # node shows as an exact duplicate (x, y). Every fifth punch grid line is a block grid line.
    _, counts = np.unique(top[inside][:, :2], axis=0, return_counts=True)
    assert np.count_nonzero(counts == 2) == (n // 5 + 1) ** 2
    assert model.step.field_controls is None  # ccx's defaults: ccx 2.20 stalls at 1e-9 here


def test_punch_sizes_span_the_benchmark_range():
    dofs = [ccx_decks.punch_model(s).num_dofs for _, s in sorted(ccx_decks.PUNCH_SIZES.items())]
    assert dofs == sorted(dofs)
    assert 25_000 <= dofs[1] <= 35_000  # "about 30k dofs"
    assert 70_000 <= dofs[2] <= 90_000  # "up to about 80k dofs"


def test_bad_punch_divisions():
    with pytest.raises(ValueError, match=r"PunchSpec.punch_layers must be a positive integer"):
        ccx_decks.punch_model(
            ccx_decks.PunchSpec(punch=6, punch_layers=0, block=10, block_layers=5)
        )


def test_unknown_deck_names_are_listed():
    with pytest.raises(ValueError, match=r"unknown deck.*'nope'.*known: tie_punch"):
        ccx_decks.select_decks(["nope"])
    quick = {d.name for d in ccx_decks.select_decks(quick=True)}
    assert {"tie_punch", "quarter_sphere_coarse"} <= quick
    assert not {"punch_30", "quarter_sphere"} & quick


@pytest.mark.ccx
def test_coarse_quarter_sphere_is_a_fixed_increment_deck_ccx_runs(tmp_path):
    deck = _write("quarter_sphere_coarse", tmp_path)
    assert list(deck.elements) == ["C3D4"]
    assert _law(deck) == ("LINEAR", (1e7, 3.0))
    (step,) = deck.steps
    assert step.static.direct
    assert (step.static.initial_increment, step.static.period) == (0.25, 1.0)
    press = [b for b in step.boundaries if b.target == "PRESS"]
    assert [(b.first_dof, b.last_dof, b.value) for b in press] == [
        (3, 3, -ccx_decks.QUARTER_SPHERE_COARSE.indentation)
    ]
    if shutil.which("ccx") is None:
        pytest.skip("CalculiX ccx is not installed")
    run_ccx(tmp_path, "quarter_sphere_coarse", timeout=120)
    rows = read_sta(tmp_path / "quarter_sphere_coarse.sta")
    assert [r.increment for r in rows] == [1, 2, 3, 4]
    assert rows[-1].total_time == pytest.approx(1.0)


def test_sphere_facet_tags_reproduce_the_gmsh_groups():
    """The pinned meshes get their facet tags from the geometry: the same as gmsh's groups."""
    spec = ccx_decks.QUARTER_SPHERE_COARSE
    mesh, cell_tags, facet_tags = ccx_decks._gmsh_sphere(spec)
    body = np.zeros(mesh.topology.index_map(3).size_local, dtype=np.int32)
    body[cell_tags.indices] = cell_tags.values
    tags = ccx_decks.sphere_facet_tags(mesh, body)
    np.testing.assert_array_equal(tags.indices, facet_tags.indices)
    np.testing.assert_array_equal(tags.values, facet_tags.values)
    assert len(np.unique(tags.values)) == 6


def test_pinned_sphere_mesh_is_checked_against_its_sizes(tmp_path, monkeypatch):
    model = ccx_decks.quarter_sphere_model(ccx_decks.QUARTER_SPHERE_COARSE)
    assert 3_000 < model.num_dofs < 6_000
    other = dataclasses.replace(ccx_decks.QUARTER_SPHERE_COARSE, size_fine=0.25)
    with pytest.raises(ValueError, match=r"was made for .*size_fine.: 0.3.*remake it"):
        ccx_decks.quarter_sphere_model(other)
    monkeypatch.setattr(ccx_decks, "MESHES", tmp_path)
    with pytest.raises(ValueError, match=r"quarter_sphere_coarse.npz is missing"):
        ccx_decks.quarter_sphere_model(ccx_decks.QUARTER_SPHERE_COARSE)


def test_progress_lines_give_iterations_and_cutbacks():
    lines = [
        " increment 1 attempt 1",
        " increment size= 2.500000e-01",
        " increment 1 converged: time 0.25, 8 iterations, 19 contact elements, residual 1e-10",
        " increment 2 attempt 1",
        " Number of contact spring elements=30",
        " increment 2 attempt 2",
        " increment 2 converged: time 0.375, 5 iterations, 3 nodes changed face, 20 contact",
        " *ERROR: step 1, increment 3, attempt 1: no convergence",
    ]
    progress = vs_ccx.parse_progress("\n".join(lines))
    assert progress.iterations == [8, 5]
    assert progress.attempts == [1, 2]


def test_report_keeps_other_platforms_sections(tmp_path):
    path = tmp_path / "performance.md"
    vs_ccx.write_report(path, "Debian 12 / dolfinx 0.5.2", ["## twelve", "old"])
    vs_ccx.write_report(path, "Debian 13 / dolfinx 0.9.0", ["## thirteen"])
    vs_ccx.write_report(path, "Debian 12 / dolfinx 0.5.2", ["## twelve", "new"])
    text = path.read_text()
    assert text.startswith("# Performance: dolfinx_ntf against CalculiX 2.20")
    assert "## thirteen" in text and "new" in text and "old" not in text
    assert text.count("## twelve") == 1


@pytest.mark.ccx
@needs_ccx
def test_a_failing_run_is_a_row_of_the_table(tmp_path):
    """ccx runs the deck; dolfinx_ntf rejects a temperature-dependent TABULAR law: a row."""
    (source,) = ccx_decks.select_decks(["hex_linear_pressure"])
    law = "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE="
    table = "TABULAR\n0., 0., 0.\n500., 0.01, 0.\n0., 0., 100.\n500., 0.01, 100.\n"

    def write(directory: Path) -> None:
        source.write(directory)
        path = directory / "hex_linear_pressure.inp"
        text = path.read_text()
        start = text.index(law) + len(law)
        end = text.index("\n", text.index("\n", start) + 1) + 1  # the LINEAR card and its line
        path.write_text(text[:start] + table + text[end:])

    deck = ccx_decks.BenchDeck("hex_linear_pressure", "temperature TABULAR", write)
    result = vs_ccx.run_deck(deck, tmp_path, runs=2)
    assert result.failure("ccx") == ""
    assert "temperature-dependent" in result.failure("dolfinx_ntf")
    assert len(result.timed("ccx")) == 2 and len(result.timed("dolfinx_ntf")) == 1
    assert result.ccx.iterations and not result.ntf.iterations
    assert all(m.peak_rss > 0 and m.wall > 0 for m in result.runs)
    (_, _, row) = vs_ccx.table([result])
    assert "**failed**" in row and "| - |" in row


def _fake_result(name: str, when, wall: float, *, ccx_fails: bool = False):
    result = vs_ccx.DeckResult(name, f"deck {name}", 300)
    result.measured = when
    for k in range(3):
        ok = not (ccx_fails and k)
        error = "" if ok else "*ERROR: diverges"
        result.runs.append(vs_ccx.Measurement("ccx", 1.0, 0.9, 2**20, ok, error))
        result.runs.append(vs_ccx.Measurement("dolfinx_ntf", wall, wall, 2**21, True, "", 0.5))
    result.ccx = vs_ccx.Progress([3], [1])
    result.ntf = vs_ccx.Progress([3], [1])
    return result


def test_update_replaces_only_the_rows_of_the_decks_run_again(tmp_path):
    import datetime as dt

    env = {"os": "Debian 12", "dolfinx": "0.5.2", "petsc": "3.18.5", "ccx": "2.20",
           "python": "3.11", "cpu": "CPU", "cores": "2", "memory": "24 GiB"}  # fmt: skip
    first = dt.datetime(2026, 11, 29, 5, 43, tzinfo=dt.timezone.utc)
    later = dt.datetime(2026, 11, 29, 8, 30, tzinfo=dt.timezone.utc)
    full = vs_ccx.section(
        [_fake_result(n, first, 2.0, ccx_fails=n == "b") for n in "abc"], env, [0.5], first, 2, 1
    )
    path = tmp_path / "performance.md"
    vs_ccx.write_report(path, "Debian 12 / dolfinx 0.5.2", full)
    old = vs_ccx.read_section(path, "Debian 12 / dolfinx 0.5.2")
    assert old == full[:-1]  # the trailing blank line is not kept

    again = vs_ccx.section([_fake_result("b", later, 0.4)], env, [3.0], later, 2, 1)
    merged = vs_ccx.merge_section(old, again, ["a", "b", "c"])
    text = "\n".join(merged)
    assert "| `a` | 300 |" in text and "| `c` | 300 |" in text
    assert "| 2.00 (1.50 + 0.50) | 2.00 |" in text  # a and c keep their old wall times
    assert "| `b` | 2026-11-29 08:30 | 1.00, 1.00 |" in text  # b re-measured, ccx ok now
    assert "| `a` | 2026-11-29 05:43 |" in text
    assert "Failures" not in text  # b's old ccx failure went with its old row
    assert "Updated (`--update`): `b` re-measured 2026-11-29 08:30 UTC" in text
    assert [line.split(" |")[0] for line in merged if line.startswith("| `")] == [
        "| `a`", "| `b`", "| `c`"
    ] * 2  # fmt: skip
    # Updating again drops the note it supersedes; a section of other versions is refused.
    twice = vs_ccx.merge_section(merged, again, ["a", "b", "c"])
    assert "\n".join(twice).count("Updated (`--update`)") == 1
    other = vs_ccx.section([_fake_result("b", later, 0.4)], {**env, "petsc": "3.22"}, [], later,
                           2, 1)  # fmt: skip
    with pytest.raises(ValueError, match=r"PETSc 3.18.5.*PETSc 3.22.*every deck"):
        vs_ccx.merge_section(old, other)


def test_update_dates_the_rows_of_a_section_written_without_dates():
    import datetime as dt

    env = {"os": "Debian 13", "dolfinx": "0.9.0", "petsc": "3.22.5", "ccx": "2.20",
           "python": "3.13", "cpu": "CPU", "cores": "2", "memory": "24 GiB"}  # fmt: skip
    first = dt.datetime(2026, 11, 29, 5, 43, tzinfo=dt.timezone.utc)
    full = vs_ccx.section([_fake_result(n, first, 2.0) for n in "ab"], env, [0.5], first, 2, 1)
    undated = [line.replace("| measured [UTC] ", "").replace("| 2026-11-29 05:43 ", "")
               for line in full]  # fmt: skip
    undated = [line[:-4] if line.startswith("|---") and line.count("|") == 9 else line
               for line in undated]  # fmt: skip
    later = dt.datetime(2026, 11, 29, 8, 30, tzinfo=dt.timezone.utc)
    merged = vs_ccx.merge_section(undated, vs_ccx.section([_fake_result("b", later, 0.4)], env,
                                                          [], later, 2, 1))  # fmt: skip
    text = "\n".join(merged)
    assert "| `a` | 2026-11-29 05:43 | 1.00, 1.00 |" in text
    assert "| `b` | 2026-11-29 08:30 | 1.00, 1.00 |" in text
    head = next(line for line in merged if line.startswith("| deck | measured"))
    assert merged[merged.index(head) + 1].count("|") == head.count("|")


def test_update_keeps_and_replaces_cel_comparison_rows():
    """A section with the .cel table merged into one without it, then again (both kept)."""
    import datetime as dt

    from dolfinx_ntf.calculix.cel import CelDifference

    env = {"os": "Debian 12", "dolfinx": "0.5.2", "petsc": "3.18.5", "ccx": "2.20",
           "python": "3.11", "cpu": "CPU", "cores": "2", "memory": "24 GiB"}  # fmt: skip
    first = dt.datetime(2026, 11, 29, 5, 43, tzinfo=dt.timezone.utc)
    later = dt.datetime(2026, 11, 29, 8, 30, tzinfo=dt.timezone.utc)
    old = vs_ccx.section([_fake_result(n, first, 2.0) for n in "ab"], env, [0.5], first, 2, 1)
    assert not any(line.startswith("Contact element sets") for line in old)

    def with_cel(name, differing):
        result = _fake_result(name, later, 0.4)
        result.cel = [CelDifference("contactelements_st1_in1_at1_it1", differing, (), ())]
        return result

    new = vs_ccx.section([with_cel("b", (7,))], env, [0.5], later, 2, 1)
    merged = vs_ccx.merge_section(old[:-1], new, ["a", "b"])
    text = "\n".join(merged)
    assert "| `b` | 1 | in1 it1 | in1 it1: 1/0/0 |" in text
    again = vs_ccx.section([with_cel("a", ())], env, [0.5], later, 2, 1)
    text = "\n".join(vs_ccx.merge_section(merged[:-1], again, ["a", "b"]))
    assert "| `a` | 1 | none | identical |" in text and "| `b` | 1 | in1 it1" in text
    assert text.index("| `a` | 1 | none") < text.index("Timed runs:")


def test_table_splits_dolfinx_ntf_wall_time_into_start_up_and_job():
    """Wall 2.0 s of which ``run_job`` 0.5 s: 1.5 s start-up, in the table and the details."""
    result = _fake_result("punch_20", None, 2.0)
    assert result.mean_startup() == pytest.approx(1.5)
    (_, _, row) = vs_ccx.table([result])
    assert "| 2.00 (1.50 + 0.50) |" in row
    (_, _, details) = vs_ccx._details([result])
    assert "| 1.50 | 0.50 |" in details


@pytest.mark.skipif(not ccx_suite.SUITE.is_dir(), reason="calculix-ccx-test is not installed")
def test_suite_decks_are_the_node_to_surface_decks_dolfinx_ntf_reads(tmp_path):
    decks = vs_ccx.suite_decks()
    names = [d.name for d in decks]
    everything = [name for name, _ in ccx_suite.node_to_surface_decks(None)]
    assert names and set(names) <= set(everything)  # all 17 are read since issues 22-24
    assert not set(names) & {d.name for d in ccx_decks.DECKS}
    for deck in decks:
        assert deck.quick
        deck.write(tmp_path)
        assert read_deck(tmp_path / f"{deck.name}.inp").steps
    for name in set(everything) - set(names):
        text = dict(ccx_suite.node_to_surface_decks([name]))[name]
        (tmp_path / f"{name}.inp").write_text(text, encoding="latin-1")
        with pytest.raises((ValueError, NotImplementedError)):
            read_deck(tmp_path / f"{name}.inp")
