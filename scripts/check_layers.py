"""Check that dolfinx_ntf's layers import only downwards (``make lint`` runs it).

The package's folders are its layers, lowest first::

    kernels                               pure numpy: no dolfinx, ufl, basix, mpi4py, petsc4py
    compat, logs, lazy_names, validation  version shims and generic helpers
    fem, meshes                           dolfinx glue
    parallel                              MPI pieces
    contact                               pairs, pairing, the nonlinear problem
    solvers, outputs                      Newton, steps; results and post-processing
    calculix                              the deck runner and CalculiX's file formats
    dolfinx_ntf (__init__, __main__)      the public API and the command line

A module may import its own layer and any lower one; ``solvers`` and ``outputs`` share a rank
but do not import each other. No layer imports ``dolfinx.nls``, which dolfinx deprecated in 0.10
and removed after 0.11. Imports inside functions count too (a lazy import is still an import).
Exit status 1 and one line per offending import otherwise::

    python scripts/check_layers.py [PACKAGE_DIR]
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

RANK = {
    "kernels": 0,
    "compat": 1,
    "logs": 1,
    "lazy_names": 1,
    "validation": 1,
    "fem": 2,
    "meshes": 2,
    "parallel": 3,
    "contact": 4,
    "solvers": 5,
    "outputs": 5,
    "calculix": 6,
    "__init__": 7,
    "_moved": 7,
    "__main__": 7,
}
#: Pairs of layers of one rank that must not import each other.
SIBLINGS = {frozenset({"solvers", "outputs"})}
#: Third-party packages the numpy kernels must not import.
NOT_IN_KERNELS = ("dolfinx", "ufl", "basix", "ffcx", "mpi4py", "petsc4py", "gmsh")
#: Modules no layer may import: dolfinx deprecated its Newton solver in 0.10 and removed it after
#: 0.11 (solvers/newton_loop.py is the package's own).
NOWHERE = ("dolfinx.nls",)


def layer_of(module: str) -> str | None:
    """The layer of ``dolfinx_ntf.<layer>...``, or None outside the package."""
    parts = module.split(".")
    if parts[0] != "dolfinx_ntf":
        return None
    return parts[1] if len(parts) > 1 else "__init__"


def imported_modules(path: Path, package: str) -> list[tuple[int, str]]:
    """(line, module) of every import in the file, relative imports resolved."""
    tree = ast.parse(path.read_text(), filename=str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if module == "dolfinx_ntf":  # from dolfinx_ntf import compat, validation
                found += [(node.lineno, f"dolfinx_ntf.{alias.name}") for alias in node.names]
            else:
                found.append((node.lineno, module))
    return found


def violations(package_dir: Path) -> list[str]:
    """One message per import that goes up a layer or into a forbidden package."""
    messages = []
    for path in sorted(package_dir.rglob("*.py")):
        relative = path.relative_to(package_dir.parent).with_suffix("")
        parts = list(relative.parts)
        module = ".".join(parts)
        package = ".".join(parts[:-1]) if parts[-1] != "__init__" else ".".join(parts)
        if parts[-1] == "__init__":
            module = ".".join(parts[:-1])
        own = layer_of(module)
        if own not in RANK:
            messages.append(f"{path}: module in no known layer ({own}); add it to RANK")
            continue
        for line, imported in imported_modules(path, package):
            top = imported.split(".")[0]
            if any(imported == gone or imported.startswith(gone + ".") for gone in NOWHERE):
                messages.append(f"{path}:{line}: imports {imported}, which dolfinx has removed")
                continue
            if own == "kernels" and top in NOT_IN_KERNELS:
                messages.append(f"{path}:{line}: the numpy kernels import {imported}")
                continue
            target = layer_of(imported)
            if target is None or target == own:
                continue
            if target not in RANK:
                messages.append(f"{path}:{line}: import of {imported}, in no known layer")
            elif RANK[target] > RANK[own]:
                messages.append(
                    f"{path}:{line}: {own} (layer {RANK[own]}) imports {imported} "
                    f"({target}, layer {RANK[target]})"
                )
            elif frozenset({own, target}) in SIBLINGS:
                messages.append(f"{path}:{line}: {own} imports its sibling layer {imported}")
    return messages


def main(argv: list[str]) -> int:
    """Print the violations; 1 if there are any."""
    package_dir = Path(argv[0]) if argv else Path(__file__).resolve().parents[1] / "dolfinx_ntf"
    messages = violations(package_dir)
    for message in messages:
        print(message)
    if not messages:
        print(f"layers: {package_dir.name} imports only downwards")
    return 1 if messages else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
