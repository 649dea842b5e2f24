"""The demos imported by path, for the tests that run them (test_demos.py, the parallel runs)."""

from __future__ import annotations

import importlib.util
import types
from pathlib import Path

DEMOS = Path(__file__).resolve().parents[2] / "demos"


def load_demo(name: str) -> types.ModuleType:
    """Import ``demos/<name>.py`` by path under a name that cannot shadow anything."""
    spec = importlib.util.spec_from_file_location(f"_demo_{name}", DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
