"""``*EL PRINT`` / ``*EL FILE`` ENER, SDV and ME in the deck runner against CalculiX 2.20.

docs/method.md §36. A plastic C3D8 beside an elastic one pulled to 5 % and unloaded (small strain
and NLGEOM), the same bar all elastic (SDV without state variables), an elastic C3D20 cube under
NLGEOM, plastic C3D6 wedges beside plastic C3D8 and elastic wedges: the ``.dat`` titles byte for
byte, the values against ccx's, the ``.frd`` blocks ``MESTRAIN``, ``ENER`` and ``SDV`` in ccx's
order. The refusals (C3D8I, 2D elements, coupled steps) are tested without ccx.
"""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

from mpi4py import MPI

import cases
import numpy as np
import pytest
from helpers.ccx_runs import quiet_logs, run_ccx_and_ours, run_quietly
from helpers.decks import UNIT_C3D8, WARPED_CUBES, mixed_sections, pulled_bar
from hex20 import to_hex20

from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.frd import read_frd
from dolfinx_ntf.calculix.job import run_job

needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")

KEYS = ("ENER", "SDV", "ME")
TITLES = ("internal energy density", "internal state variables", "mechanical strains")


#: Element 1 plastic (metalforming's sheet table), element 2 elastic, on symmetry rollers: pulled
#: to 5 % in ccx's automatic increments, then back to 4 % (ccx's controls near round-off).
def _bar(nlgeom: bool, plastic: bool = True) -> str:
    printed = "*EL PRINT, ELSET=EALL\nS, E, PEEQ, ENER, SDV, ME\n"
    written = "*NODE FILE\nU\n*EL FILE\nE, ENER, SDV, ME\n"
    return pulled_bar(
        mixed_sections(plastic),
        printed + written,
        ", NLGEOM" if nlgeom else "",
        second_requests=printed,
    )


def _title_lines(path: Path) -> list[str]:
    return [line for line in path.read_text().splitlines() if any(t in line for t in TITLES)]


def _blocks(path: Path, name: str):
    return [b for b in read_dat(path) if b.name == name]


def _compare_dat(ccx_dat: Path, ntf_dat: Path, tolerance: dict[str, float]) -> dict[str, float]:
    """ENER, SDV and ME of every increment against ccx's: titles byte for byte, the rows' labels,
    the values within ``tolerance[key]`` of ccx's largest value of that key; the differences."""
    assert _title_lines(ntf_dat) == _title_lines(ccx_dat)
    assert len(_title_lines(ccx_dat)) >= 3
    worst = {}
    for key in KEYS:
        ours, theirs = _blocks(ntf_dat, key), _blocks(ccx_dat, key)
        assert len(ours) == len(theirs) > 0
        scale = max(np.abs(b.values).max(initial=0.0) for b in theirs) or 1.0
        worst[key] = 0.0
        for a, b in zip(ours, theirs):
            assert (a.set, a.time) == (b.set, b.time)
            np.testing.assert_array_equal(a.labels, b.labels)
            assert a.values.shape == b.values.shape
            if b.values.size:
                worst[key] = max(worst[key], float(np.abs(a.values - b.values).max()) / scale)
        assert worst[key] <= tolerance[key], (key, worst[key])
    return worst


def _compare_frd(ccx_frd: Path, ntf_frd: Path, tolerance: float) -> None:
    """The ``.frd`` blocks in ccx's order (less its ERROR block); MESTRAIN, ENER and SDV with
    ccx's components, within ``tolerance`` of the largest value (5 printed digits)."""
    ours, theirs = read_frd(ntf_frd), read_frd(ccx_frd)
    assert [b.name for b in ours.blocks] == [b.name for b in theirs.blocks if b.name != "ERROR"]
    for name in ("MESTRAIN", "ENER", "SDV"):
        a_blocks, b_blocks = ours.blocks_named(name), theirs.blocks_named(name)
        assert len(a_blocks) == len(b_blocks) > 0
        scale = max(np.abs(b.values).max(initial=0.0) for b in b_blocks) or 1.0
        for a, b in zip(a_blocks, b_blocks):
            assert a.components == b.components
            np.testing.assert_array_equal(a.nodes, b.nodes)
            assert a.values.shape == b.values.shape
            if b.values.size:
                assert np.abs(a.values - b.values).max() <= tolerance * scale, name


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("nlgeom", [False, True], ids=["small", "nlgeom"])
def test_bar_energy_state_and_mechanical_strain(nlgeom: bool, tmp_path: Path) -> None:
    """The plastic and elastic C3D8: ENER, SDV, ME (.dat, .frd) as ccx's; the values are the
    laws' committed ones, the elastic element's energy S:E/2, SDV[0] the PEEQ."""
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "bar", _bar(nlgeom), tight=True)
    # small strain: ccx's printed digits; NLGEOM: within 1e-6 of the largest (as S there)
    tolerance = 1e-6 if nlgeom else 1e-9
    _compare_dat(ccx_dir / "bar.dat", ntf_dir / "bar.dat", dict.fromkeys(KEYS, tolerance))
    _compare_frd(ccx_dir / "bar.frd", ntf_dir / "bar.frd", 2e-5)
    dat = ntf_dir / "bar.dat"
    energy, state, peeq = _blocks(dat, "ENER")[-1], _blocks(dat, "SDV")[-1], _blocks(dat, "PEEQ")
    assert state.values.shape[1] == 13
    np.testing.assert_array_equal(state.values[:, 0], peeq[-1].values[:, 0])
    assert np.all(state.values[:, 7:] == 0.0)  # the back stress of kinematic hardening
    elastic = state.labels[:, 0] == 2
    assert np.all(state.values[elastic] == 0.0) and state.values[~elastic, 0].min() > 0.03
    if not nlgeom:  # the plastic strain is deviatoric: trace 0 to three roundings of 5e-9
        assert np.abs(state.values[:, 1:4].sum(axis=1)).max() <= 1.5e-8
        for e, m in zip(_blocks(dat, "E"), _blocks(dat, "ME")):
            np.testing.assert_array_equal(e.values, m.values)
        # the elastic element's energy is S:E/2 of the printed stress and strain (small strain)
        s, e = _blocks(dat, "S")[-1].values, _blocks(dat, "E")[-1].values
        half = 0.5 * (np.einsum("ni,ni->n", s[:, :3], e[:, :3]) + 2 * (s[:, 3:] * e[:, 3:]).sum(1))
        np.testing.assert_allclose(energy.values[elastic, 0], half[elastic], rtol=1e-5)
        # the plastic element's less its stored part S:(E - Ep)/2 is the dissipated work
        # int sigma_y(a) da = 50 a + H a^2/2, less the trapezoidal rule's error (1.1 % here)
        elastic_strain = e - state.values[:, 1:7]
        stored = 0.5 * (
            np.einsum("ni,ni->n", s[:, :3], elastic_strain[:, :3])
            + 2 * (s[:, 3:] * elastic_strain[:, 3:]).sum(1)
        )
        alpha = state.values[~elastic, 0]
        dissipated = 50.0 * alpha + 50.0 / 0.3 * alpha**2 / 2
        ratio = (energy.values[~elastic, 0] - stored[~elastic]) / dissipated
        assert np.all((0.98 < ratio) & (ratio < 1.0)), ratio


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
def test_bar_without_plastic_sections(tmp_path: Path) -> None:
    """All elastic: SDV prints the rows' labels only and the .frd's SDV block has no
    components and no rows, as ccx 2.20's; ENER is S:E/2 (the energy of a linear path)."""
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "bar", _bar(False, plastic=False), tight=True)
    _compare_dat(ccx_dir / "bar.dat", ntf_dir / "bar.dat", dict.fromkeys(KEYS, 1e-9))
    _compare_frd(ccx_dir / "bar.frd", ntf_dir / "bar.frd", 2e-5)
    text, reference = (d.joinpath("bar.dat").read_text() for d in (ntf_dir, ccx_dir))
    start = reference.index(" internal state variables")
    end = reference.index(" mechanical strains", start)
    assert text[text.index(" internal state variables") :][: end - start] == reference[start:end]
    assert "         1   1\n" in reference[start:end]
    assert all(b.values.shape == (0, 0) for b in read_frd(ntf_dir / "bar.frd").blocks_named("SDV"))


#: WARPED_CUBES pressed on top under NLGEOM: made C3D20 by ``to_hex20``.
CUBE = (
    WARPED_CUBES.format(E=1000.0, NU=0.3)
    + """*STEP, NLGEOM
*STATIC
1., 1.
*DLOAD
2, P2, 10.0
*EL PRINT, ELSET=EALL
S, E, ENER, SDV, ME
*NODE FILE
U
*EL FILE
ENER, SDV, ME
*END STEP
"""
)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
def test_c3d20_under_nlgeom(tmp_path: Path) -> None:
    """An elastic C3D20 pair (warped) under NLGEOM: ENER (second Piola-Kirchhoff stress and
    Green-Lagrange strain, per reference volume) and ME at its 27 points and in the .frd."""

    def write(directory: Path) -> None:
        path = directory / "cube.inp"
        path.write_text(CUBE)
        to_hex20(path)

    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "cube", write)
    # measured 1.2e-6 (ENER) and 2.0e-7 (ME): S of this deck differs by 6.0e-7
    worst = _compare_dat(ccx_dir / "cube.dat", ntf_dir / "cube.dat", dict.fromkeys(KEYS, 3e-6))
    _compare_frd(ccx_dir / "cube.frd", ntf_dir / "cube.frd", 2e-5)
    energy = _blocks(ntf_dir / "cube.dat", "ENER")[0]
    assert np.bincount(energy.labels[:, 0])[1:].tolist() == [27, 27]
    assert worst["SDV"] == 0.0 and energy.values.min() > 0.0


def _wedge_block(plastic: bool, nlgeom: bool) -> tuple[str, int]:
    """A 2 x 2 x 2 block, every other hexahedron split into two C3D6 wedges (numbered first),
    the others C3D8, sheared and compressed in 4 increments; the deck and its wedge count."""

    def nid(i: int, j: int, k: int) -> int:
        return 1 + i + 3 * (j + 3 * k)

    lines = ["*NODE, NSET=NALL"]
    for k in range(3):
        for j in range(3):
            for i in range(3):
                x = i / 2 + (0.05 * np.sin(1.5 * j + k / 2) if i == 1 else 0.0)
                lines.append(f"{nid(i, j, k)}, {x:.6f}, {j / 2:.6f}, {k / 2:.6f}")
    wedges, hexes = [], []
    for k in range(2):
        for j in range(2):
            for i in range(2):
                low = [nid(i, j, k), nid(i + 1, j, k), nid(i + 1, j + 1, k), nid(i, j + 1, k)]
                up = [nid(i, j, k + 1), nid(i + 1, j, k + 1), nid(i + 1, j + 1, k + 1),
                      nid(i, j + 1, k + 1)]  # fmt: skip
                a, b, c, d = low
                A, B, C, D = up
                if (i + j + k) % 2 == 1:
                    hexes.append(low + up)
                elif (i + j) % 2 == 0:
                    wedges += [[a, b, c, A, B, C], [a, c, d, A, C, D]]
                else:
                    wedges += [[a, b, d, A, B, D], [b, c, d, B, C, D]]
    lines.append("*ELEMENT, TYPE=C3D6, ELSET=EALL")
    lines += [", ".join(map(str, [e, *w])) for e, w in enumerate(wedges, start=1)]
    lines.append("*ELEMENT, TYPE=C3D8, ELSET=EALL")
    lines += [", ".join(map(str, [len(wedges) + e, *h])) for e, h in enumerate(hexes, 1)]
    bottom = ", ".join(str(nid(i, j, 0)) for j in range(3) for i in range(3))
    top = ", ".join(str(nid(i, j, 2)) for j in range(3) for i in range(3))
    table = "*PLASTIC\n300., 0.\n400., 0.1\n" if plastic else ""
    lines.append(f"""*NSET, NSET=BOT
{bottom}
*NSET, NSET=TOP
{top}
*MATERIAL, NAME=EL
*ELASTIC
210000., 0.3
{table}*SOLID SECTION, ELSET=EALL, MATERIAL=EL
*BOUNDARY
BOT, 1, 3
*STEP{", NLGEOM" if nlgeom else ""}
*STATIC
0.25, 1.
*BOUNDARY
TOP, 3, 3, -0.01
TOP, 1, 1, 0.02
TOP, 2, 2, 0.0
*EL PRINT, ELSET=EALL
S, E, PEEQ, ENER, SDV, ME
*END STEP""")
    return "\n".join(lines) + "\n", len(wedges)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize(
    ("nlgeom", "tolerance"), [(False, 1e-9), (True, 1e-5)], ids=["small", "nlgeom"]
)
def test_plastic_wedges(nlgeom: bool, tolerance: float, tmp_path: Path) -> None:
    """Plastic C3D6 wedges beside plastic C3D8 (the wedges' two points): ENER, SDV and ME as
    ccx's (its printed digits; NLGEOM within 1e-5 of the largest, as S of this deck)."""
    text, count = _wedge_block(plastic=True, nlgeom=nlgeom)
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "w", text)
    _compare_dat(ccx_dir / "w.dat", ntf_dir / "w.dat", dict.fromkeys(KEYS, tolerance))
    state = _blocks(ntf_dir / "w.dat", "SDV")[-1]
    points = np.bincount(state.labels[:, 0])[1:]
    assert points.tolist() == [2] * count + [8] * (points.size - count)
    assert state.values[: 2 * count, 0].min() > 0.0  # the wedges yielded


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
def test_elastic_wedges_under_nlgeom(tmp_path: Path) -> None:
    """Elastic wedges beside C3D8 under NLGEOM: ENER and ME at the wedges' two points."""
    text, count = _wedge_block(plastic=False, nlgeom=True)
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "w", text)
    _compare_dat(ccx_dir / "w.dat", ntf_dir / "w.dat", dict.fromkeys(KEYS, 1e-6))
    energy = _blocks(ntf_dir / "w.dat", "ENER")[-1]
    assert energy.values[: 2 * count].min() > 0.0
    assert np.abs(energy.values[0] - energy.values[1]).max() > 0.0  # two points, not one


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize(
    ("name", "tolerance"),
    [("tet10_exponential", 2e-7), ("tet_nlgeom_pressure", 6e-6)],
    ids=["C3D10", "C3D4-nlgeom"],
)
def test_tetrahedra(name: str, tolerance: float, tmp_path: Path) -> None:
    """Cross-validation decks of tetrahedral punches with ENER, SDV and ME printed: as ccx's
    within the differences of S and E of the same decks (3.5e-8 and 3.3e-6, measured)."""
    (case,) = [c for c in cases.CASES if c.name == name]

    def write(directory: Path) -> None:
        case.write(directory)
        path = directory / f"{name}.inp"
        request = "*EL PRINT, ELSET=EALL\nS, E, ENER, SDV, ME\n*END STEP"
        text = path.read_text().replace("*END STEP", request)
        assert "ENER" in text
        path.write_text(text)

    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, name, write)
    dat = f"{name}.dat"
    worst = _compare_dat(ccx_dir / dat, ntf_dir / dat, dict.fromkeys(KEYS, tolerance))
    assert worst["SDV"] == 0.0


# -- refusals and the reader (no ccx) -------------------------------------------------------------


def test_keys_are_read(tmp_path: Path) -> None:
    """ENER, SDV and ME are element keys of *EL PRINT and *EL FILE."""
    path = tmp_path / "bar.inp"
    path.write_text(_bar(False))
    step = read_deck(path).steps[0]
    assert [r.keys for r in step.prints if r.kind == "EL"] == [
        ("S", "E", "PEEQ", "ENER", "SDV", "ME")
    ]
    assert [r.keys for r in step.file_requests if r.kind == "EL"] == [("E", "ENER", "SDV", "ME")]


@pytest.mark.serial
@pytest.mark.parametrize("key", KEYS)
def test_c3d8i_is_refused(key: str, tmp_path: Path) -> None:
    """C3D8I (its condensed modes, not measured): refused naming the element type and line."""
    text = _bar(False, plastic=False).replace("TYPE=C3D8,", "TYPE=C3D8I,")
    text = text.replace("S, E, PEEQ, ENER, SDV, ME\n", f"S, {key}\n", 1)
    text = text.replace("E, ENER, SDV, ME\n", "U\n")
    text = text.replace("S, E, PEEQ, ENER, SDV, ME\n", "S\n")
    (tmp_path / "deck.inp").write_text(text)
    line = text.splitlines().index("*EL PRINT, ELSET=EALL") + 1
    with pytest.raises(NotImplementedError) as info:
        run_quietly("deck", tmp_path)
    assert f"deck.inp:{line}: *EL PRINT {key} (" in str(info.value)
    assert "C3D8I" in str(info.value)


#: A C3D8 cube heated by 3 (expansion 1e-2: a thermal strain x = 0.03), held at x = 0 and 1.
HEATED = (
    UNIT_C3D8
    + """*NSET, NSET=X0
1, 4, 5, 8
*NSET, NSET=Y0
1, 2, 5, 6
*NSET, NSET=Z0
1, 2, 3, 4
*NSET, NSET=X1
2, 3, 6, 7
*MATERIAL, NAME=M
*ELASTIC
1000.0, 0.3
*EXPANSION
1e-2
*CONDUCTIVITY
50.
*SPECIFIC HEAT
400.
*DENSITY
7.8e-9
*SOLID SECTION, ELSET=EALL, MATERIAL=M
*INITIAL CONDITIONS, TYPE=TEMPERATURE
NALL, 0.
*BOUNDARY
X0, 1, 1
Y0, 2, 2
Z0, 3, 3
X1, 1, 1
*STEP{nlgeom}
*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE
1., 1.
*BOUNDARY
NALL, 11, 11, 3.
*EL PRINT, ELSET=EALL
S, E, ENER, SDV, ME
*END STEP
"""
)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize(
    ("nlgeom", "tolerance"), [(False, 1e-9), (True, 1e-4)], ids=["small", "nlgeom"]
)
def test_heated_cube(nlgeom: bool, tolerance: float, tmp_path: Path) -> None:
    """A coupled step: ME is the strain of ``grad u - x I`` (NLGEOM: its Green-Lagrange strain),
    E the total strain, ENER ``S : ME / 2``, as ccx's (small strain: its printed digits; NLGEOM:
    as S and E of this steady coupled step, 7e-5 and 2.6e-5 at ccx's own controls)."""
    text = HEATED.format(nlgeom=", NLGEOM" if nlgeom else "")
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "cube", text)
    _compare_dat(ccx_dir / "cube.dat", ntf_dir / "cube.dat", dict.fromkeys(KEYS, tolerance))
    x = 0.03
    for directory in (ccx_dir, ntf_dir):  # ME from E: the stretches less x, to printed digits
        dat = directory / "cube.dat"
        total, mechanical = _blocks(dat, "E")[0].values, _blocks(dat, "ME")[0].values
        if nlgeom:
            stretch = np.sqrt(1 + 2 * total[:, :3])
            expected = ((stretch - x) ** 2 - 1) / 2
        else:
            expected = total[:, :3] - x
        np.testing.assert_allclose(mechanical[:, :3], expected, rtol=0, atol=2e-7)
        assert abs(mechanical[0, 0] - (-x + (x**2 / 2 if nlgeom else 0.0))) < 1e-7  # held in x


# -- on several processes -------------------------------------------------------------------------


def _without_clock(path: Path) -> list[str]:
    """The lines of an ``.frd`` file but its wall-clock date and time."""
    return [line for line in path.read_text().splitlines() if "1UDATE" not in line
            and "1UTIME" not in line]  # fmt: skip


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
def test_bar_on_all_processes(tmp_path: Path) -> None:
    """The plastic and elastic bar under NLGEOM on 1 or 2 processes (one element each): ENER,
    SDV and ME as ccx's, the .dat and .frd files the serial run's byte for byte (rank 0
    compares; the .frd less its clock)."""
    comm = MPI.COMM_WORLD
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "bar", _bar(True), comm=comm, tight=True)
    failure = None
    if comm.rank == 0:
        try:
            serial_dir = ntf_dir.parent / "serial"
            serial_dir.mkdir()
            (serial_dir / "bar.inp").write_text(_bar(True))
            with quiet_logs(logging.ERROR):
                run_job("bar", serial_dir, comm=MPI.COMM_SELF, progress=False, tight=True)
            _compare_dat(ccx_dir / "bar.dat", ntf_dir / "bar.dat", dict.fromkeys(KEYS, 1e-6))
            _compare_frd(ccx_dir / "bar.frd", ntf_dir / "bar.frd", 2e-5)
            assert (ntf_dir / "bar.dat").read_text() == (serial_dir / "bar.dat").read_text()
            frd = [_without_clock(d / "bar.frd") for d in (ntf_dir, serial_dir)]
            assert frd[0] == frd[1]
            assert " -4  MESTRAIN    6    1" in frd[0]
        except Exception as error:  # every rank fails, none waits
            failure = repr(error)
    failure = comm.bcast(failure, root=0)
    assert failure is None, failure
