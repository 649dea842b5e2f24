"""C3D15 wedges: what the deck runner needs of them and what it refuses (docs/method.md §34).

A C3D15 deck becomes an 18-node prism mesh with a degree-2 space whose quadrilateral face
centres are constrained to the serendipity wedge (``fem/serendipity_wedge.py``), integrated at
ccx's 9 points. dolfinx holds one cell type per mesh and runs degree-2 spaces on prisms from 0.11
on only (0.5.2's FFCx refuses prisms, 0.9 aborts the process while assembling P2 on prisms,
§32.5): older releases refuse the deck, naming the element's line.
"""

from __future__ import annotations

import numpy as np

from dolfinx_ntf import compat

from ..deck import Deck, ElementBlock
from ..elements import ELEMENT_TYPES

__all__ = ["C3D15_MIN_DOLFINX", "c3d15_metadata", "c3d15_rule", "check_c3d15_deck"]

#: The first dolfinx release that assembles degree-2 spaces on prisms (docs/method.md §32.5).
C3D15_MIN_DOLFINX = (0, 11)

#: Output keys whose ``.frd`` values need ccx's C3D15 extrapolation (not reproduced).
_FRD_STRESS_KEYS = {"S", "E", "ME", "PEEQ"}


def c3d15_rule() -> tuple[np.ndarray, np.ndarray]:
    """ccx's 9 points of C3D15 on dolfinx's reference prism and their weights (sum 1/2).

    The 3-point triangle rule (weights 1/6) times 3 Gauss points along the axis (5/18, 8/18,
    5/18 on ``[0, 1]``), triangle points fastest: ccx's ``*EL PRINT`` order.
    """
    points = ELEMENT_TYPES["C3D15"].integration_points
    axis = np.repeat([5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0], 3)
    return np.array(points), axis / 6.0


def c3d15_metadata() -> dict:
    """UFL integral metadata of :func:`c3d15_rule` (FFCx's custom rule)."""
    points, weights = c3d15_rule()
    return {
        "quadrature_rule": "custom",
        "quadrature_degree": 2,
        "quadrature_points": tuple(map(tuple, points.tolist())),
        "quadrature_weights": tuple(weights.tolist()),
    }


def check_c3d15_deck(deck: Deck, block: ElementBlock) -> None:
    """Refuse a C3D15 deck this dolfinx or the runner cannot reproduce (naming the deck line).

    Raises:
        NotImplementedError: dolfinx older than 0.11, pressures and element-face surfaces,
            contact or tie surfaces, thermal,
            dynamic or modal steps, ``.frd`` stresses or strains.
    """
    where = f"{block.locations[0]}: C3D15 (element {int(block.ids[0])})"
    if compat.DOLFINX_VERSION < C3D15_MIN_DOLFINX:
        version = ".".join(map(str, compat.DOLFINX_VERSION))
        why = (
            "its FFCx refuses forms on prisms"
            if compat.DOLFINX_VERSION < (0, 7)
            else "degree-2 spaces on prisms abort the process while assembling"
        )
        raise NotImplementedError(
            f"{where}: 15-node wedges need dolfinx 0.11 or later (an 18-node prism mesh with a "
            f"degree-2 space); dolfinx {version} cannot: {why} (docs/method.md §32.5, §34)"
        )
    for step in deck.steps:
        if step.dloads:
            raise NotImplementedError(
                f"{step.dloads[0].location}: *DLOAD pressures on C3D15 faces are not supported "
                "yet: dolfinx 0.11 numbers a prism mesh's triangles and quadrilaterals apart and "
                f"does not assemble ds over them (give *CLOAD nodal forces; {where})"
            )
    if any(s.type == "ELEMENT" for s in deck.surfaces.values()):
        name, surface = next((n, s) for n, s in deck.surfaces.items() if s.type == "ELEMENT")
        raise NotImplementedError(
            f"{surface.location}: *SURFACE {name}: element faces of C3D15 elements are not "
            f"supported yet (prism meshes have two facet types; {where})"
        )
    if deck.contact_pairs or deck.ties:
        card = deck.contact_pairs[0] if deck.contact_pairs else deck.ties[0]
        raise NotImplementedError(
            f"{card.location}: contact and tie surfaces on C3D15 elements are not supported yet "
            f"({where}; docs/method.md §34)"
        )
    for step in deck.steps:
        if step.dynamic or step.frequency or step.coupled or step.modal_dynamic:
            raise NotImplementedError(
                f"{step.location}: dynamic, modal and thermal steps with C3D15 elements are not "
                f"supported yet (their mass and heat forms were not checked against ccx; {where})"
            )
        for request in step.file_requests:
            keys = _FRD_STRESS_KEYS.intersection(request.keys)
            if request.kind == "EL" and keys:
                raise NotImplementedError(
                    f"{request.location}: {request.keyword} {', '.join(sorted(keys))} of C3D15 "
                    "elements is not supported yet (ccx's extrapolation of C3D15 stresses to the "
                    f"nodes is not reproduced; *EL PRINT prints them at ccx's 9 points; {where})"
                )
