"""An SB3 .zip is code (loading it unpickles objects that can run code from the file): a shipped model loads
quietly, a .zip from anywhere else is named with its path (once per file and process), and the CLI's --help of
eval and render says so."""

from __future__ import annotations

import logging
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from redundancy_gym.cli import main
from redundancy_gym.policies import sb3_policy
from redundancy_gym.policies.sb3_policy import Sb3Policy, is_shipped_model_file
from redundancy_gym.policies.shipped_models import SHIPPED_MODELS_DIR

pytest.importorskip("stable_baselines3")

SHIPPED = SHIPPED_MODELS_DIR / "ppo-nullspace-planar_reach.zip"
LOGGER = "redundancy_gym.policies.sb3_policy"
WARNING = "can run code from the file"


@pytest.fixture(autouse=True)
def _fresh_announcements(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each test starts as a fresh process would: no file announced yet."""
    monkeypatch.setattr(sb3_policy, "_ANNOUNCED", set())


def _messages(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == LOGGER and r.levelno == logging.WARNING]


def test_a_shipped_model_loads_quietly(caplog: pytest.LogCaptureFixture) -> None:
    assert is_shipped_model_file(SHIPPED)
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        policy = Sb3Policy(SHIPPED)
    assert policy.algo == "PPO"
    assert _messages(caplog) == []


def test_a_shipped_model_reached_through_the_clone_symlink_is_shipped() -> None:
    """baselines/models/ of a clone is the package's folder: its files count as shipped."""
    clone = Path(__file__).resolve().parents[2] / "baselines" / "models" / SHIPPED.name
    assert clone.is_file() and is_shipped_model_file(clone)


def test_a_copy_elsewhere_is_named_with_its_path_once(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    copy = tmp_path / "downloaded" / SHIPPED.name  # the same bytes: where it lies is what counts
    copy.parent.mkdir()
    shutil.copyfile(SHIPPED, copy)
    assert not is_shipped_model_file(copy)
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        Sb3Policy(copy)
        Sb3Policy(copy)  # once per file: a second load of the same file says nothing more
    messages = _messages(caplog)
    assert len(messages) == 1, messages
    assert str(copy.resolve()) in messages[0] and WARNING in messages[0]
    assert "load only files you trust" in messages[0]


def test_a_missing_file_fails_before_any_announcement(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, logger=LOGGER), pytest.raises(Exception, match="policy file not found"):
        Sb3Policy(tmp_path / "nope.zip")
    assert _messages(caplog) == []


def test_without_logging_setup_the_path_reaches_stderr(tmp_path: Path) -> None:
    """A plain script (no logging configuration) sees the line on stderr, as the CLI does."""
    copy = tmp_path / "model.zip"
    shutil.copyfile(SHIPPED, copy)
    script = (
        "import sys; from redundancy_gym.policies.sb3_policy import Sb3Policy; "
        "Sb3Policy(sys.argv[1]); Sb3Policy(sys.argv[1]); Sb3Policy(sys.argv[2])"
    )
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    done = subprocess.run(
        [sys.executable, "-c", script, str(copy), str(SHIPPED)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stderr.splitlines() if WARNING in line]
    assert len(lines) == 1 and str(copy.resolve()) in lines[0], done.stderr
    assert done.stdout == ""


@pytest.mark.parametrize("command", ["eval", "render"])
def test_help_says_a_zip_policy_is_code(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main([command, "--help"])
    assert exit_info.value.code == 0
    text = " ".join(capsys.readouterr().out.split())  # argparse wraps the help at the terminal width
    assert "A .zip policy is code" in text and "load only files you trust" in text
    assert WARNING in text
