"""Builders shared by the tests (``pythonpath`` of pyproject.toml puts ``tests`` on the path).

- ``bar_decks``: the mesh of the two-bar thermal contact decks.
- ``bars``: a clamped-free bar held to axial motion (the modal tests).
- ``blocks``: two blocks stacked along z without gmsh, the punch and drag problems on them.
- ``serial_answer``: partitions, and runs on several processes compared with the serial run.
- ``decks``: decks with every output request, run serially and on all processes.
- ``demos``: the demos imported by path (``load_demo``).
- ``spring_faces``: random master faces and slave nodes of the spring-kernel tests.
- ``prism_blocks``: gmsh punch-on-base models of prisms and hexahedra (docs/method.md §32).
- ``spring_differences``: central differences of spring forces by the nodal coordinates.

The names most tests use are imported here: ``from helpers import punch_problem``.
"""

from .bars import axial_bar
from .blocks import (
    BLOCK_CONTACT,
    BLOCK_TOP,
    LOWER,
    LOWER_BOTTOM,
    LOWER_TOP,
    MU,
    POISSON_RATIO,
    PRESSURE,
    PUNCH,
    STICK_SLOPE,
    UPPER,
    UPPER_BOTTOM,
    UPPER_TOP,
    YOUNGS_MODULUS,
    block_on_springs,
    box_grid,
    displacement_fields,
    drag_conditions,
    drag_problem,
    elastic_residual,
    punch_bulk,
    punch_conditions,
    punch_problem,
    rigid_block,
    solve_increments,
    two_blocks,
)

__all__ = [
    "BLOCK_CONTACT",
    "BLOCK_TOP",
    "LOWER",
    "LOWER_BOTTOM",
    "LOWER_TOP",
    "MU",
    "POISSON_RATIO",
    "PRESSURE",
    "PUNCH",
    "STICK_SLOPE",
    "UPPER",
    "UPPER_BOTTOM",
    "UPPER_TOP",
    "YOUNGS_MODULUS",
    "axial_bar",
    "block_on_springs",
    "box_grid",
    "displacement_fields",
    "drag_conditions",
    "drag_problem",
    "elastic_residual",
    "punch_bulk",
    "punch_conditions",
    "punch_problem",
    "rigid_block",
    "solve_increments",
    "two_blocks",
]
