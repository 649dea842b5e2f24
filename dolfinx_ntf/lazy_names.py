"""Public names of a package imported on first access (PEP 562).

``import dolfinx_ntf`` and ``import dolfinx_ntf.calculix`` load none of their modules up front: a
name such as ``dolfinx_ntf.ContactProblem`` imports its module when it is first used, so
``python -m dolfinx_ntf run JOB`` loads the modules its deck needs (docs/performance.md,
"Start-up").
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Collection, Mapping

__all__ = ["lazy_dir", "lazy_getattr"]


def lazy_getattr(
    package: str, names: Mapping[str, str], subpackages: Collection[str] = ()
) -> Callable[[str], object]:
    """A module ``__getattr__`` importing ``names[name]`` (relative to ``package``) on first access.

    Args:
        package: The package's ``__name__``.
        names: Public name -> the module under ``package`` that defines it.
        subpackages: Subpackages returned as modules when accessed as attributes.

    Returns:
        The function to bind as the package's ``__getattr__``; it caches each name it imports
        in the package's namespace, so later accesses skip it.
    """

    def __getattr__(name: str) -> object:
        if name in subpackages:
            return importlib.import_module(f".{name}", package)
        module = names.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f".{module}", package), name)
        setattr(sys.modules[package], name, value)
        return value

    return __getattr__


def lazy_dir(package: str, public: Collection[str]) -> Callable[[], list[str]]:
    """A module ``__dir__`` listing the names already bound and every public name."""

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(public))

    return __dir__
