"""Old import paths of the 0.1 layout, kept importable for one release with a :class:`DeprecationWarning`.

The layout of ``docs/architecture.md`` moved modules out of ``eval/`` (into ``learning/``, ``studies/``, ``bench/``
and the top-level ``demo``) and grouped ``controllers/`` into ``tasks/``, ``objectives/``, ``clik/``,
``predictive/`` and ``kernels/``. ``import redundancy_gym.eval.bench_ssv`` (or any other old module path in
:data:`MOVED_MODULES`) still works: a finder on ``sys.meta_path`` hands out the module at its new place under the old
name and warns. Names that a package exported and that now live in a package it must not import (the dependency
direction) are forwarded lazily by :func:`forward_attributes`.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings
from collections.abc import Callable, Mapping, Sequence
from types import ModuleType
from typing import Any

__all__ = ["MOVED_MODULES", "forward_attributes", "install"]

_P = "redundancy_gym."
MOVED_MODULES: Mapping[str, str] = {
    _P + old: _P + new
    for old, new in {
        "controllers.task": "controllers.tasks.task",
        "controllers.frame_position_task": "controllers.tasks.frame_position_task",
        "controllers.frame_axis_task": "controllers.tasks.frame_axis_task",
        "controllers.objective": "controllers.objectives.objective",
        "controllers.actuated_objective": "controllers.objectives.actuated_objective",
        "controllers.collision_objective": "controllers.objectives.collision_objective",
        "controllers.joint_limit_objective": "controllers.objectives.joint_limit_objective",
        "controllers.posture_objective": "controllers.objectives.posture_objective",
        "controllers.collision_kernels": "controllers.objectives.collision_kernels",
        "controllers.compiled_clik": "controllers.clik.compiled_clik",
        "controllers.clik_kernels": "controllers.clik.clik_kernels",
        "controllers.acceleration_clik": "controllers.clik.acceleration_clik",
        "controllers.redundancy_resolution": "controllers.clik.redundancy_resolution",
        "controllers.kernel_buffers": "controllers.kernels.buffers",
        "controllers.predictive_ik": "controllers.predictive.predictive_ik",
        "controllers.predictive_kernels": "controllers.predictive.predictive_kernels",
        "controllers.receding_horizon": "controllers.predictive.receding_horizon",
        "controllers.ikd.walking_ikd": "controllers.walking.walking_ikd",
        "eval.training": "learning.training",
        "eval.training_record": "learning.training_record",
        "eval.behaviour_cloning": "learning.behaviour_cloning",
        "eval.baselines": "learning.baselines",
        "eval.sweep": "learning.sweep",
        "eval.point_to_point": "studies.point_to_point",
        "eval.ikd_study": "studies.ikd_study",
        "eval.walking_plots": "studies.walking_plots",
        "eval.obstacle_plots": "studies.obstacle_plots",
        "eval.bench_envs": "bench.envs",
        "eval.bench_ik": "bench.ik",
        "eval.bench_learned": "bench.learned",
        "eval.bench_pik": "bench.pik",
        "eval.bench_push": "bench.push",
        "eval.bench_scale": "bench.scale",
        "eval.bench_soak": "bench.soak",
        "eval.bench_ssv": "bench.ssv",
        "eval.bench_walk": "bench.walk",
        "eval.bench_timing": "bench.timing",
        "eval.coal_shapes": "bench.coal_shapes",
        "eval.demo": "demo",
    }.items()
}
"""Old module path -> its place since 0.2 (the old path warns and goes in 0.3)."""


def _warn(old: str, new: str, stacklevel: int) -> None:
    warnings.warn(
        f"{old} moved to {new}; the old path goes in redundancy_gym 0.3", DeprecationWarning, stacklevel=stacklevel
    )


class _MovedFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old module path and loads it as the module at its new place (the same module object)."""

    def find_spec(
        self,
        fullname: str,
        path: Sequence[str] | None,
        target: ModuleType | None = None,
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED_MODULES:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        new = MOVED_MODULES[spec.name]
        _warn(spec.name, new, stacklevel=6)
        module = importlib.import_module(new)
        # importlib overwrites these on the returned module; exec_module puts the new module's own back
        self._saved = (module.__spec__, module.__loader__)
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__, module.__loader__ = self._saved


def install() -> None:
    """Put the finder of old module paths on ``sys.meta_path`` (once; ``import redundancy_gym`` calls it)."""
    if not any(isinstance(finder, _MovedFinder) for finder in sys.meta_path):
        sys.meta_path.append(_MovedFinder())


def forward_attributes(package: str, names: Mapping[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package`` that hands out each of ``names`` (name -> the module that now
    holds it) with a :class:`DeprecationWarning`, importing that module only when the name is asked for."""

    def __getattr__(name: str) -> Any:
        if name not in names:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        _warn(f"{package}.{name}", f"{names[name]}.{name}", stacklevel=3)
        return getattr(importlib.import_module(names[name]), name)

    return __getattr__
