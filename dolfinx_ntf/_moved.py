"""The module paths of dolfinx_ntf before its layers became folders (version 0.2), still importable.

``import dolfinx_ntf.solver`` or ``from dolfinx_ntf.gmsh_io import mesh_from_gmsh`` in a user's
script finds the module at its new path (``dolfinx_ntf.meshes.gmsh_io``) and warns once with a
:class:`DeprecationWarning` naming it. The old ``solver`` module was split into the modules of
``dolfinx_ntf.solvers``, whose package re-exports its names. The old ``dolfinx_ntf.parallel``
module is now a package of its own and is not aliased.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings

__all__ = ["MOVED_MODULES", "install"]

#: Old module name (under ``dolfinx_ntf.``) -> its path now (under ``dolfinx_ntf.``).
MOVED_MODULES: dict[str, str] = {
    "active_set": "solvers.active_set",
    "adjust": "contact.adjust",
    "analysis": "solvers.analysis",
    "assembly": "contact.assembly",
    "bulk_jacobian": "fem.bulk_jacobian",
    "constraints": "fem.constraints",
    "continuum": "fem.continuum",
    "dynamics": "solvers.dynamics",
    "elasticity": "fem.elasticity",
    "faces": "kernels.faces",
    "friction": "kernels.friction",
    "friction_state": "kernels.friction_state",
    "gmsh_io": "meshes.gmsh_io",
    "laws": "kernels.laws",
    "master_exchange": "parallel.master_exchange",
    "measures": "fem.measures",
    "nullspace": "solvers.nullspace",
    "output": "outputs.results",
    "parallel_constraints": "parallel.global_constraints",
    "postprocess": "outputs.postprocess",
    "pressure_recovery": "fem.pressure_recovery",
    "problem": "contact.problem",
    "projection": "kernels.projection",
    "rigid": "kernels.rigid",
    "search": "kernels.search",
    "serendipity": "fem.serendipity",
    "solver": "solvers",  # the package re-exports the names of the split module
    "spring_areas": "kernels.spring_areas",
    "springs": "kernels.springs",
    "start_slope": "kernels.start_slope",
    "surfaces": "fem.surfaces",
    "tie_frame": "kernels.tie_frame",
}


class _MovedModuleFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``dolfinx_ntf.<old>`` as the module at its new path."""

    def find_spec(self, fullname, path=None, target=None):
        prefix, _, name = fullname.partition(".")
        if prefix != "dolfinx_ntf" or name not in MOVED_MODULES:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        new = "dolfinx_ntf." + MOVED_MODULES[spec.name.partition(".")[2]]
        warnings.warn(
            f"{spec.name} is now {new}; the old name will be removed", DeprecationWarning, 2
        )
        return importlib.import_module(new)

    def exec_module(self, module: types.ModuleType) -> None:
        pass  # the module at the new path is already executed


def install() -> None:
    """Put the finder of the old module paths on ``sys.meta_path`` (once)."""
    if not any(isinstance(finder, _MovedModuleFinder) for finder in sys.meta_path):
        sys.meta_path.append(_MovedModuleFinder())
