"""gmsh builders of the demo geometries: a flat punch on a block, a hemisphere on a block.

Each module defines the physical-group tags of its geometry, a ``COARSE`` set of mesh sizes for
tests, builders that create a new current gmsh model (pass them to
:func:`dolfinx_ntf.meshes.gmsh_io.mesh_from_gmsh`), and a command line that writes a ``.msh`` file::

    python -m dolfinx_ntf.meshes.punch --cell-type tetrahedron -o punch.msh
    python -m dolfinx_ntf.meshes.hertz --coarse -o hertz.msh

The modules need gmsh (Debian's ``python3-gmsh``); ``import dolfinx_ntf`` does not import them.
"""

from dolfinx_ntf.meshes import hertz, punch

__all__ = ["hertz", "punch"]
