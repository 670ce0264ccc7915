"""docs/architecture.md: geometry <- model <- controllers <- policies/wrappers <- eval <- datasets <- learning
<- studies <- bench <- demo <- cli; assets <- envs <- policies, wrappers, eval.

The core (geometry, model, controllers) never imports gymnasium, mujoco, dm_control, envs, policies, wrappers or
anything above them; envs never import controllers, policies or wrappers; policies never import wrappers (a wrapper
may build a policy); eval never imports learning, studies, bench, demo or cli, and so on up the floors; no two
sibling packages of ``controllers/`` import each other; and the package has no import circle between its modules.
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


FLOORS = ("eval", "datasets", "learning", "studies", "bench", "demo", "cli")
"""The floors above policies and wrappers, lowest first: each may import those below it, never those above."""


def _forbidden(layer: str) -> set[str]:
    core = {"envs", "policies", "wrappers", *FLOORS}
    if layer in FLOORS:
        ours = set(FLOORS[FLOORS.index(layer) + 1 :])
    else:
        ours = {
            "geometry": {"model", "controllers"} | core,
            "model": {"controllers"} | core,
            "controllers": core,
            "envs": {"controllers", "policies", "wrappers", *FLOORS},
            "policies": {"envs", "wrappers", *FLOORS},
            "wrappers": set(FLOORS),
        }[layer]
    return {f"redundancy_gym.{name}" for name in ours}


# where a module may import the simulation side: envs simulate; wrappers are gymnasium wrappers; the policy
# registry builds the registered envs (lazily) for its messages; an SB3 .zip needs stable-baselines3 (lazily)
SIMULATION_ALLOWED = {"envs", "wrappers", "policies/registry.py", "policies/sb3_policy.py"}


def _files(layer: str) -> list[Path]:
    """The files of a layer: a package's, or the one module ``demo.py`` / ``cli.py``."""
    module = PACKAGE / f"{layer}.py"
    return [module] if module.is_file() else sorted((PACKAGE / layer).rglob("*.py"))


@pytest.mark.parametrize("layer", ["geometry", "model", "controllers", "envs", "policies", "wrappers", *FLOORS[:-1]])
def test_layer_imports(layer: str) -> None:
    files = _files(layer)
    assert files
    for path in files:
        imported = _imports(path)
        bad = {name for name in imported for f in _forbidden(layer) if name == f or name.startswith(f + ".")}
        assert not bad, f"{path.name} imports {bad}"
        if layer in FLOORS:
            continue  # the floors above wrappers run the simulation
        if layer not in SIMULATION_ALLOWED and f"{layer}/{path.name}" not in SIMULATION_ALLOWED:
            sim = {name for name in imported if name.split(".")[0] in SIMULATION}
            assert not sim, f"{path.relative_to(PACKAGE)} imports {sim}"


def _module_graph() -> dict[str, set[str]]:
    """Module -> the package modules it imports, at import time or lazily inside a function (a lazy import closes
    a circle as well, only later). A module's own parent packages are left out: Python imports them before the
    module anyway (``from .. import validation`` names the parent only to reach its submodule)."""
    modules = {
        ".".join(p.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__"): p
        for p in PACKAGE.rglob("*.py")
    }
    return {
        module: {n for n in _imports(path) if n in modules and n != module and not module.startswith(n + ".")}
        for module, path in modules.items()
    }


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Import circles between modules (paths that come back to where they started)."""
    found = []
    for start in graph:
        stack = [(start, [start])]
        while stack:
            node, path = stack.pop()
            for nxt in graph[node]:
                if nxt == start:
                    found.append([*path, start])
                elif nxt not in path:
                    stack.append((nxt, [*path, nxt]))
    return found


CONTROLLER_PACKAGES = ("tasks", "objectives", "clik", "predictive", "kernels", "walking", "ikd")


def _package_imports(graph: dict[str, set[str]], package: str) -> set[str]:
    """The sibling controller packages that the modules of ``controllers/<package>/`` import."""
    prefix = f"redundancy_gym.controllers.{package}"
    out = set()
    for module, imported in graph.items():
        if module == prefix or module.startswith(prefix + "."):
            for name in imported:
                parts = name.split(".")
                if len(parts) > 2 and parts[1] == "controllers" and parts[2] in CONTROLLER_PACKAGES:
                    out.add(parts[2])
    return out - {package}


def test_controller_packages_exist() -> None:
    for package in CONTROLLER_PACKAGES:
        assert (PACKAGE / "controllers" / package / "__init__.py").is_file(), package
    flat = sorted(p.name for p in (PACKAGE / "controllers").glob("*.py"))
    assert flat == ["__init__.py", "exceptions.py"], flat


def test_no_sibling_controller_packages_import_each_other() -> None:
    graph = _module_graph()
    uses = {package: _package_imports(graph, package) for package in CONTROLLER_PACKAGES}
    both = {tuple(sorted((a, b))) for a, used in uses.items() for b in used if a in uses.get(b, set())}
    assert not both, f"sibling controller packages importing each other: {sorted(both)}"
    assert "ikd" in uses["walking"]  # the check sees the walking IKD's use of the IKD package


def test_no_import_circles() -> None:
    assert not _circles(_module_graph())


def test_the_circle_check_sees_a_circle() -> None:
    graph = {"redundancy_gym.a": {"redundancy_gym.b"}, "redundancy_gym.b": {"redundancy_gym.a"}}
    assert _circles(graph)


def test_the_check_sees_imports() -> None:
    """The parser resolves relative imports, so the test above can fail."""
    names = _imports(PACKAGE / "controllers" / "clik" / "clik.py")
    assert "redundancy_gym.model" in names and "numpy" in names
    assert "redundancy_gym.assets.planar_arm_scene" in _imports(PACKAGE / "envs" / "planar_reach.py")
    assert "redundancy_gym.eval.json_writer" in _imports(PACKAGE / "bench" / "table.py")


def test_a_floor_may_not_import_one_above() -> None:
    assert "redundancy_gym.learning" in _forbidden("eval") and "redundancy_gym.cli" in _forbidden("demo")
    assert "redundancy_gym.eval" not in _forbidden("learning")
