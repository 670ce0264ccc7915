"""DESIGN.md: geometry <- model <- controllers <- policies/wrappers <- eval <- cli; assets <- envs.

The core (geometry, model, controllers except policies.py) never imports gymnasium, mujoco, dm_control, envs
or eval; envs never import controllers.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "redundancy_gym"
SIMULATION = {"gymnasium", "mujoco", "dm_control", "stable_baselines3", "torch"}


def _imports(path: Path) -> set[str]:
    """Absolute module names imported by a file (relative imports resolved inside the package)."""
    module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    package = module.rsplit(".", 1)[0] if path.name != "__init__.py" else module.removesuffix(".__init__")
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
                names.add(target)
                names.update(f"{target}.{alias.name}" for alias in node.names)
            else:
                names.add(node.module or "")
    return names


def _forbidden(layer: str) -> set[str]:
    ours = {"geometry": {"model", "controllers", "envs", "eval", "cli"},
            "model": {"controllers", "envs", "eval", "cli"},
            "controllers": {"envs", "eval", "cli"},
            "envs": {"controllers", "eval", "cli"}}[layer]
    return {f"redundancy_gym.{name}" for name in ours}


@pytest.mark.parametrize("layer", ["geometry", "model", "controllers", "envs"])
def test_layer_imports(layer: str) -> None:
    files = sorted((PACKAGE / layer).glob("*.py"))
    assert files
    for path in files:
        imported = _imports(path)
        bad = {name for name in imported for f in _forbidden(layer) if name == f or name.startswith(f + ".")}
        assert not bad, f"{path.name} imports {bad}"
        if layer != "envs" and path.name != "policies.py":
            sim = {name for name in imported if name.split(".")[0] in SIMULATION}
            assert not sim, f"{path.name} imports {sim}"


def test_the_check_sees_imports() -> None:
    """The parser resolves relative imports, so the test above can fail."""
    names = _imports(PACKAGE / "controllers" / "clik.py")
    assert "redundancy_gym.model" in names and "numpy" in names
    assert "redundancy_gym.assets.planar_arm_scene" in _imports(PACKAGE / "envs" / "planar_reach.py")
