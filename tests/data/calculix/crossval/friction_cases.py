"""Cross-validation decks with friction and analyses made of steps (docs/method.md §11).

Same meshes and conventions as ``cases.py``: a block (body 0, clamped at its bottom) and a punch
(body 1) on it, non-matching grids, ccx's tolerances tightened. The punch top is driven by
prescribed displacements (or a pressure), so that removing the contact pair leaves the punch
supported.
"""

from __future__ import annotations

from pathlib import Path

from cases import BOTTOM, E1, E2, LINEAR, LOWER, NU1, NU2, PUNCH, TOP, Case, blocks, facet_tag

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.calculix.writer import (
    TIGHT_FIELD_CONTROLS,
    BoundarySpec,
    OutputSpec,
    PressureSpec,
    StepSpec,
    write_inp,
)

__all__ = ["CASES"]

_OUTPUT = OutputSpec(node_print=("U",), contact_print=("CDIS", "CSTR", "CELS", "CNUM"))
#: ccx advises lambda about K/100 (docs/method.md §11.5); K = 50 E1 here.
STICK_SLOPE = 500.0


def _pair(ft, mu: float, stick_slope: float = STICK_SLOPE) -> ntf.ContactPair:
    interaction = ntf.SurfaceInteraction(LINEAR, ntf.Friction(mu, stick_slope))
    return ntf.ContactPair(
        ntf.FacetSurface(ft, facet_tag(1, BOTTOM)), ntf.FacetSurface(ft, facet_tag(0, TOP)),
        interaction,
    )  # fmt: skip


def _top(ft, components, value=0.0, name="TOP"):
    return BoundarySpec(ntf.FacetSurface(ft, facet_tag(1, TOP)), components, value, name=name)


def _step(increments: int, **kwargs) -> StepSpec:
    return StepSpec(increments=increments, field_controls=TIGHT_FIELD_CONTROLS, output=_OUTPUT,
                    **kwargs)  # fmt: skip


def _write(directory: Path, name: str, V, ct, ft, pairs, steps, heading: str) -> None:
    write_inp(
        directory / f"{name}.inp",
        displacement_space=V,
        materials={1: (E1, NU1), 2: (E2, NU2)},
        cell_tags=ct,
        pairs=pairs,
        fixed=[BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE")],
        steps=steps,
        heading=heading,
    )


def _hex_stick_punch(directory: Path) -> None:
    V, ct, ft = blocks([LOWER, PUNCH])
    steps = [
        _step(2, boundaries=[_top(ft, (0, 1))],
              pressures=[PressureSpec(ntf.FacetSurface(ft, facet_tag(1, TOP)), 20.0)]),
        _step(2, boundaries=[_top(ft, (0,), 1e-3, name="DRAG")]),
    ]  # fmt: skip
    heading = "C3D8 punch pressed by a pressure, then its top moved sideways: friction sticks"
    _write(directory, "hex_stick_punch", V, ct, ft, [_pair(ft, 0.5)], steps, heading)


def _hex_sliding_block(directory: Path) -> None:
    V, ct, ft = blocks([LOWER, PUNCH])
    steps = [
        # the pressure on the block keeps it loaded while the pair is removed (an unloaded model
        # converges in ccx with an exactly zero residual, dolfinx_ntf's round-off never counts)
        _step(2, boundaries=[_top(ft, (0, 1)), _top(ft, (2,), -0.004, name="PRESS")],
              pressures=[PressureSpec(ntf.FacetSurface(ft, facet_tag(0, TOP)), 2.0)]),
        _step(3, boundaries=[_top(ft, (0,), 0.04, name="DRAG")]),
        _step(3, boundaries=[_top(ft, (0,), 0.0, name="BACK")],
              change_friction={1: ntf.Friction(0.4, STICK_SLOPE)}),
        _step(1, boundaries=[_top(ft, (2,), 0.01, name="LIFT")], model_change={1: "REMOVE"}),
        _step(2, boundaries=[_top(ft, (2,), -0.004, name="PRESS2")], model_change={1: "ADD"}),
    ]  # fmt: skip
    _write(directory, "hex_sliding_block", V, ct, ft, [_pair(ft, 0.2)], steps,
           "C3D8 punch pressed, dragged (slip), dragged back after *CHANGE FRICTION (mu 0.2 -> "
           "0.4), lifted with the pair removed, pressed again after ADD")  # fmt: skip


def _hex_adjust_gap(directory: Path) -> None:
    punch = ((0.11, 0.13, 0.003), (0.6, 0.6, 0.4), (3, 3, 2))  # 0.003 above the block
    V, ct, ft = blocks([LOWER, punch])
    pair = _pair(ft, 0.3)
    pair.adjust = 0.005
    steps = [
        _step(2, boundaries=[_top(ft, (0, 1))],
              pressures=[PressureSpec(ntf.FacetSurface(ft, facet_tag(1, TOP)), 20.0)]),
    ]  # fmt: skip
    _write(directory, "hex_adjust_gap", V, ct, ft, [pair], steps,
           "C3D8 punch 0.003 above the block, ADJUST=0.005, friction, pressure")  # fmt: skip


def _tet_adjust_set(directory: Path) -> None:
    punch = ((0.11, 0.13, -0.001), (0.6, 0.6, 0.4), (3, 3, 2))  # overlaps the block by 0.001
    V, ct, ft = blocks([LOWER, punch], cell="tetrahedron")
    pair = _pair(ft, 0.3)
    facets = ft.find(facet_tag(1, BOTTOM))
    pair.adjust = ntf.NodeSurface(compat.incident_entities(V.mesh, facets, 2, 0), "BOTTOM1")
    steps = [
        _step(2, boundaries=[_top(ft, (0, 1))],
              pressures=[PressureSpec(ntf.FacetSurface(ft, facet_tag(1, TOP)), 20.0)]),
    ]  # fmt: skip
    _write(directory, "tet_adjust_set", V, ct, ft, [pair], steps,
           "C3D4 punch overlapping the block by 0.001, ADJUST=node set of its bottom")  # fmt: skip


CASES: tuple[Case, ...] = (
    Case("hex_stick_punch", "C3D8, LINEAR, friction (mu 0.5, lambda 500): pressed, then "
         "dragged by 1e-3: stick, 2 + 2 increments", _hex_stick_punch),
    Case("hex_sliding_block", "C3D8, LINEAR, friction: press, drag 0.04 (slip), *CHANGE FRICTION "
         "and drag back, *MODEL CHANGE REMOVE and lift, ADD and press, 2+3+3+1+2 increments",
         _hex_sliding_block),
    Case("hex_adjust_gap", "C3D8, LINEAR, friction, punch 0.003 above the block moved onto it by "
         "ADJUST=0.005, pressure, 2 increments", _hex_adjust_gap),
    Case("tet_adjust_set", "C3D4, LINEAR, friction, punch overlapping by 0.001 moved out by "
         "ADJUST=<node set>, pressure, 2 increments", _tet_adjust_set),
)  # fmt: skip
"""Every friction cross-validation deck."""
