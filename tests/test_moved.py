"""The old import paths of the 0.1 layout still work for one release, warn, and give the very module or object at
its new place (redundancy_gym._moved)."""

from __future__ import annotations

import importlib
import sys

import pytest

import redundancy_gym  # noqa: F401 - installs the finder
from redundancy_gym._moved import MOVED_MODULES


@pytest.mark.parametrize("old", sorted(MOVED_MODULES))
def test_an_old_module_path_is_the_new_module(old: str) -> None:
    new = importlib.import_module(MOVED_MODULES[old])
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match="moved to"):
        module = importlib.import_module(old)
    assert module is new
    assert module.__spec__.name == MOVED_MODULES[old]  # the new module keeps its own spec


def test_every_new_place_exists_and_no_old_file_is_left() -> None:
    for old, new in MOVED_MODULES.items():
        assert importlib.util.find_spec(new) is not None, new
        path = redundancy_gym.__path__[0] + "/" + "/".join(old.split(".")[1:]) + ".py"
        assert not importlib.util.find_spec(old) or not __import__("os").path.exists(path), old


def test_old_package_attributes_warn_and_forward() -> None:
    from redundancy_gym.controllers import walking
    from redundancy_gym.learning import training_record

    with pytest.warns(DeprecationWarning, match="redundancy_gym.learning"):
        from redundancy_gym.eval import TrainingRecord
    assert TrainingRecord is training_record.TrainingRecord
    with pytest.warns(DeprecationWarning, match="controllers.walking"):
        from redundancy_gym.controllers.ikd import WalkingIkd
    assert WalkingIkd is walking.WalkingIkd
    with pytest.raises(ImportError):
        from redundancy_gym.eval import NoSuchName  # noqa: F401
