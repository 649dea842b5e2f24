"""The ``*PLASTIC`` sections of a deck: one J2 law per plastic section.

docs/method.md §21.6, §21.7. Each section whose material has a ``*PLASTIC`` table gets a J2 law
over its cells, at ccx's integration points (C3D8: 2x2x2 Gauss): the small-strain
:class:`~dolfinx_ntf.J2Plasticity` without NLGEOM, Simo's finite-strain
:class:`~dolfinx_ntf.fem.finite_plasticity.FiniteStrainJ2Plasticity` with it, as ccx 2.20 does.
The elastic form covers the other cells only. What the laws cannot reproduce of ccx is refused
before anything runs: decks mixing NLGEOM and small-strain steps, element types other than
C3D8, coupled, dynamic and frequency steps.
"""

from __future__ import annotations

import typing

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.fem.finite_plasticity import FiniteStrainJ2Plasticity
from dolfinx_ntf.fem.plasticity import J2Plasticity
from dolfinx_ntf.kernels.plasticity import IsotropicHardening
from dolfinx_ntf.kernels.wedge_rule import wedge_rule

from ..deck import Deck, ElementBlock
from ..elements import ElementType

__all__ = ["check_plastic_deck", "has_plasticity", "plastic_laws"]

#: Tags of the plastic wedges: ``PLASTIC_WEDGE_TAG + 16 law + class`` (above ``WEDGE_TAG``'s).
PLASTIC_WEDGE_TAG = 2000

#: Element types whose plastic sections are reproduced (measured against ccx 2.20).
PLASTIC_ELEMENT_TYPES = ("C3D8",)


def has_plasticity(deck: Deck) -> bool:
    """Whether a section of the deck has a material with a ``*PLASTIC`` table."""
    return any(deck.materials[s.material].plastic is not None for s in deck.sections)


def check_plastic_deck(deck: Deck, etype: ElementType) -> None:
    """Refuse what the plastic sections cannot reproduce (NotImplementedError naming the line)."""
    if not has_plasticity(deck):
        return
    where = next(
        deck.materials[s.material].plastic_location
        for s in deck.sections
        if deck.materials[s.material].plastic is not None
    )
    if etype.name not in PLASTIC_ELEMENT_TYPES:
        raise NotImplementedError(
            f"{where}: *PLASTIC with {etype.name} elements is not supported yet (only "
            f"{', '.join(PLASTIC_ELEMENT_TYPES)})"
        )
    kinds = {step.nlgeom for step in deck.steps}
    if len(kinds) > 1:
        step = next(s for s in deck.steps if s.nlgeom != deck.steps[0].nlgeom)
        raise NotImplementedError(
            f"{step.location}: a *PLASTIC material (first at {where}) in a deck that mixes NLGEOM "
            "and small-strain steps is not supported yet (ccx switches between its finite- and "
            "small-strain plasticity; the history would have to pass between them)"
        )
    for step in deck.steps:
        what = (
            "*DYNAMIC"
            if step.dynamic is not None
            else "*FREQUENCY"
            if step.frequency is not None
            else "*COUPLED TEMPERATURE-DISPLACEMENT or *HEAT TRANSFER"
            if step.coupled is not None
            else None
        )
        if what is not None:
            raise NotImplementedError(
                f"{step.location}: {what} steps with a *PLASTIC material (first at {where}) are "
                "not supported yet (static steps only)"
            )


def plastic_laws(
    deck: Deck,
    block: ElementBlock,
    u: dolfinx.fem.Function,
    element_cell: np.ndarray,
    quadrature_degree: int,
    finite: bool = False,
    elastic_values: np.ndarray | None = None,
    wedge_classes: np.ndarray | None = None,
    rule_classes: typing.Sequence[int] = (),
) -> tuple[list[J2Plasticity | FiniteStrainJ2Plasticity], compat.MeshTags]:
    """One J2 law per plastic section, and the cell tags of the materials.

    Every local cell (ghosts included) is tagged 0 (elastic) or ``k + 1`` (the ``k``-th law);
    the elastic form integrates over tag 0 with the same tags (UFL wants one ``subdomain_data``).

    Args:
        deck: The deck.
        block: Its element block.
        u: The displacement.
        element_cell: Local cell of each element of ``block`` (-1 elsewhere).
        quadrature_degree: ccx's volume rule of the element type.
        finite: Simo's finite-strain laws (the deck's steps are NLGEOM), else small-strain ones.
        elastic_values: Tag of each local cell outside the plastic sections (default 0), e.g.
            the wedges' integration rules (``wedge_rules.py``); values below ``1 + laws`` are
            not allowed there.
        wedge_classes: The collapse class of each local cell (-1: no wedge): the wedges of a
            plastic
            section get a law of their own per class, with ccx's two-point C3D6 rule
            (``quadrature_rule``, tag ``PLASTIC_WEDGE_TAG + 16 law + class``; docs/method.md
            §30.5), after the sections' laws.
        rule_classes: The collapse classes present on any process (the same on all).

    Returns:
        The laws (plastic sections in deck order) and the cell tags.
    """
    mesh = u.function_space.mesh
    tdim = mesh.topology.dim
    cell_map = mesh.topology.index_map(tdim)
    section_of = np.full(cell_map.size_local + cell_map.num_ghosts, -1, dtype=np.int64)
    order = np.argsort(block.ids)
    for k, section in enumerate(deck.sections):  # a later section wins, as in lame()
        members = np.unique(deck.elsets[section.elset])
        members = members[np.isin(members, block.ids)]
        cells = element_cell[order[np.searchsorted(block.ids, members, sorter=order)]]
        section_of[cells[cells >= 0]] = k
    values = np.zeros(section_of.size, dtype=np.int32)
    if elastic_values is not None:
        values[:] = elastic_values
    plastic = [k for k, s in enumerate(deck.sections) if deck.materials[s.material].plastic]
    for tag, k in enumerate(plastic, 1):
        values[section_of == k] = tag
    wedge_laws = []  # (tag, section, class)
    if wedge_classes is not None:
        for tag, k in enumerate(plastic, 1):
            for c in rule_classes:
                wedge_tag = PLASTIC_WEDGE_TAG + 16 * tag + c
                values[(section_of == k) & (wedge_classes == c)] = wedge_tag
                wedge_laws.append((wedge_tag, k, c))
    tags = dolfinx.mesh.meshtags(mesh, tdim, np.arange(values.size, dtype=np.int32), values)
    law = FiniteStrainJ2Plasticity if finite else J2Plasticity
    laws = []
    for tag, k, c in [(tag, k, None) for tag, k in enumerate(plastic, 1)] + wedge_laws:
        material = deck.materials[deck.sections[k].material]
        stress, strain = zip(*material.plastic)
        young, nu = material.elastic
        hardening = IsotropicHardening(yield_stress=stress, plastic_strain=strain)
        laws.append(
            law(
                u,
                young,
                nu,
                hardening,
                quadrature_degree=quadrature_degree,
                cell_tags=tags,
                tag=tag,
                quadrature_rule=None if c is None else wedge_rule(c),
            )
        )
    return laws, tags
