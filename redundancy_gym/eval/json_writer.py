"""The one JSON writer of reports (benchmarks, studies, sweeps, the demo's tables)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

__all__ = ["write_json"]


def write_json(report: Any, path: str | Path) -> Path:
    """Write ``report`` (JSON-serializable) to ``path`` with two-space indents and a final newline, creating the
    parent folders; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(report, indent=2) + "\n")
    return path
