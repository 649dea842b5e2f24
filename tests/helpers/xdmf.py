"""Reading back the XDMF files of ``outputs.xdmf_cells`` (hexahedra, wedges, quadratic wedges)."""

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from dolfinx_ntf.outputs.xdmf_cells import NODES_PER_CELL


def read_xdmf(path: Path) -> tuple[np.ndarray, list[tuple[int, np.ndarray]], list[dict]]:
    """Points, cells (XDMF type, nodes) and per time step ``{"t": t, name: values}``."""
    root = ET.parse(path).getroot()
    domain = root.find("Domain")
    mesh, series = domain.findall("Grid")
    assert mesh.get("Name") == "mesh" and series.get("CollectionType") == "Temporal"
    topology = mesh.find("Topology")
    assert topology.get("TopologyType") == "Mixed"
    flat = np.array(topology.find("DataItem").text.split(), dtype=np.int64)
    cells, k = [], 0
    while k < flat.size:
        size = NODES_PER_CELL[int(flat[k])]
        cells.append((int(flat[k]), flat[k + 1 : k + 1 + size]))
        k += 1 + size
    assert len(cells) == int(topology.get("NumberOfElements"))
    item = mesh.find("Geometry/DataItem")
    shape = tuple(int(n) for n in item.get("Dimensions").split())
    points = np.array(item.text.split(), dtype=float).reshape(shape)
    steps = []
    include = "{http://www.w3.org/2001/XInclude}include"
    for grid in series.findall("Grid"):
        assert "Grid[@Name='mesh']" in grid.find(include).get("xpointer")
        step = {"t": float(grid.find("Time").get("Value"))}
        for attribute in grid.findall("Attribute"):
            data = attribute.find("DataItem")
            dims = tuple(int(n) for n in data.get("Dimensions").split())
            step[attribute.get("Name")] = np.array(data.text.split(), dtype=float).reshape(dims)
        steps.append(step)
    return points, cells, steps
