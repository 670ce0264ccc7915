"""Tasks: an error and its Jacobian (the task interface :class:`Task` and its frame tasks)."""

from .frame_axis_task import FrameAxisTask
from .frame_position_task import FramePositionTask
from .task import Task

__all__ = [
    "FrameAxisTask",
    "FramePositionTask",
    "Task",
]
