"""Action wrappers over the model-based pipeline: the learner commands a task-space velocity
(:class:`TaskSpaceAction`), the nullspace input of (5.100) (:class:`NullspaceAction`) or a residual on the
reference policy (:class:`ResidualAction`), or the biped's walking velocity (:class:`WalkingCommandAction`). Each
registers in the one registry of :mod:`redundancy_gym.policies` (read by :func:`make_wrapper`, the wrapped env ids
and ``redundancy-gym list``), and records its constructor arguments, so that ``gym.make(env.spec)`` rebuilds a
wrapper applied by hand.
"""

from __future__ import annotations

from .exceptions import WrapperActionError, WrapperError
from .nullspace_action import NullspaceAction, NullspaceActionConfig
from .residual_action import REFERENCE_POLICIES, ResidualAction, ResidualActionConfig
from .task_space_action import TaskSpaceAction, TaskSpaceActionConfig
from .walking_command_action import WalkingCommandAction, WalkingCommandActionConfig
from .wrapped_env import make_wrapped_env, make_wrapper, wrapper_option_names

__all__ = [
    "REFERENCE_POLICIES",
    "NullspaceAction",
    "NullspaceActionConfig",
    "ResidualAction",
    "ResidualActionConfig",
    "TaskSpaceAction",
    "TaskSpaceActionConfig",
    "WalkingCommandAction",
    "WalkingCommandActionConfig",
    "WrapperActionError",
    "WrapperError",
    "make_wrapped_env",
    "make_wrapper",
    "wrapper_option_names",
]
