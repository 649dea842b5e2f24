"""Two structured rectangles stacked along y, meshed by gmsh (separate nodes on the contact line).

Physical groups: the cells of the lower rectangle 1 and of the upper 2; lines ``LOWER_TOP`` (the
master), ``UPPER_BOTTOM`` (the slave), ``UPPER_TOP``, ``LOWER_BOTTOM`` and ``LEFT`` (the left
sides of both: a symmetry line in plane strain, the axis in axisymmetry).
"""

from __future__ import annotations

import gmsh

LOWER_TOP, UPPER_BOTTOM, UPPER_TOP, LOWER_BOTTOM, LEFT = 3, 4, 5, 6, 7


def rectangle(x0: float, y0: float, x1: float, y1: float, nx: int, ny: int) -> tuple:
    """A structured triangulated rectangle: its surface and lines (bottom, right, top, left)."""
    g = gmsh.model.geo
    p = [g.addPoint(x0, y0, 0), g.addPoint(x1, y0, 0), g.addPoint(x1, y1, 0), g.addPoint(x0, y1, 0)]
    lines = [g.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    surface = g.addPlaneSurface([g.addCurveLoop(lines)])
    for line, n in zip(lines, (nx, ny, nx, ny)):
        g.mesh.setTransfiniteCurve(line, n + 1)
    g.mesh.setTransfiniteSurface(surface)
    return surface, lines


def stacked_rectangles(name: str, lower: tuple, upper: tuple, order: int) -> None:
    """Mesh ``upper`` on ``lower`` (each ``(x0, y0, x1, y1, nx, ny)``) in a new gmsh model."""
    gmsh.model.add(name)
    lower_surface, lower_lines = rectangle(*lower)
    upper_surface, upper_lines = rectangle(*upper)
    gmsh.model.geo.synchronize()
    model = gmsh.model
    model.addPhysicalGroup(2, [lower_surface], 1)
    model.addPhysicalGroup(2, [upper_surface], 2)
    model.addPhysicalGroup(1, [lower_lines[2]], LOWER_TOP)
    model.addPhysicalGroup(1, [upper_lines[0]], UPPER_BOTTOM)
    model.addPhysicalGroup(1, [upper_lines[2]], UPPER_TOP)
    model.addPhysicalGroup(1, [lower_lines[0]], LOWER_BOTTOM)
    model.addPhysicalGroup(1, [lower_lines[3], upper_lines[3]], LEFT)
    model.mesh.generate(2)
    model.mesh.setOrder(order)
