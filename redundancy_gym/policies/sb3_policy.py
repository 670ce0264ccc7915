"""A stable-baselines3 model loaded from a ``.zip`` as a policy.

``predict(..., deterministic=True)`` runs the network's weights in a compiled kernel
(:mod:`~redundancy_gym.policies.mlp_inference`, a few microseconds instead of SB3's 95-130 us of per-call
overhead) where the model is a plain MLP (:func:`mlp_inference_from_sb3` reads its weights); :attr:`Sb3Policy.fast_path`
says whether it is, and :meth:`Sb3Policy.sb3_predict` is SB3's own ``predict`` (to time against it).

A model trained behind SB3's ``VecNormalize`` needs its observation statistics: saved with
``VecNormalize.save`` as ``<stem>_vecnormalize.pkl`` beside ``<stem>.zip`` (:func:`vecnormalize_path`), they are
loaded with the model and every ``predict`` (both paths) normalizes the observation as ``VecNormalize`` does.

A ``.zip`` is code, not data: stable-baselines3 unpickles the objects it holds (the policy class, schedules,
spaces), and unpickling can run any code the file's author put there. Loading one from outside the package's
shipped models (:data:`~redundancy_gym.policies.shipped_models.SHIPPED_MODELS_DIR`) logs where it came from, once
per file and process, so that a user sees which file ran.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..sb3_import import LEARN_EXTRA_HINT, import_stable_baselines3
from .exceptions import PolicyError
from .mlp_inference import MlpInference
from .options import env_name
from .shipped_models import SHIPPED_MODELS_DIR

__all__ = [
    "SB3_ALGOS",
    "SB3_CONTRIB_ALGOS",
    "ObservationNormalization",
    "Sb3Policy",
    "is_shipped_model_file",
    "mlp_inference_from_sb3",
    "vecnormalize_path",
]

SB3_ALGOS = ("PPO", "SAC", "TD3", "A2C", "DDPG")
SB3_CONTRIB_ALGOS = ("TQC", "CrossQ")
"""sb3-contrib's algorithms a ``.zip`` may hold (tried after :data:`SB3_ALGOS` where sb3-contrib is installed; the
learning curves' sample-efficient learner)."""

_LOG = logging.getLogger(__name__)
# Without a logging configuration, Python's last-resort handler prints WARNING records to stderr: the CLI and a
# plain script show the line with no setup, and an application that configures logging routes or silences it.
_ANNOUNCED: set[Path] = set()


def is_shipped_model_file(path: str | Path) -> bool:
    """Whether ``path`` is one of the package's own shipped models (in ``SHIPPED_MODELS_DIR``, symlinks resolved)."""
    return Path(path).resolve().parent == SHIPPED_MODELS_DIR.resolve()


def vecnormalize_path(model_path: str | Path) -> Path:
    """Where the ``VecNormalize`` statistics of the model saved at ``model_path`` (``<stem>.zip``) are kept:
    ``<stem>_vecnormalize.pkl`` in the same folder."""
    path = Path(model_path)
    return path.with_name(f"{path.stem}_vecnormalize.pkl")


@dataclass(frozen=True)
class ObservationNormalization:
    """SB3 ``VecNormalize``'s observation normalization: ``clip((obs - mean) / sqrt(var + epsilon), -clip, clip)``
    in float32, as ``VecNormalize.normalize_obs`` gives it to the agent.

    Attributes:
        mean, var: the running mean and variance of each observation entry, frozen at saving.
        epsilon: added to the variance; clip: the bound of a normalized entry.
    """

    mean: NDArray[np.float64]
    var: NDArray[np.float64]
    epsilon: float
    clip: float

    @classmethod
    def load(cls, path: str | Path) -> ObservationNormalization:
        """The statistics of a ``VecNormalize.save`` file (a pickle: it can run code, as a ``.zip`` can).

        Raises:
            PolicyError: the file is no ``VecNormalize`` pickle, or does not normalize observations.
        """
        import pickle

        try:
            with open(path, "rb") as handle:
                saved = pickle.load(handle)
            rms, epsilon, clip = saved.obs_rms, float(saved.epsilon), float(saved.clip_obs)
            norm_obs = bool(saved.norm_obs)
        except Exception as exc:  # an unpickling error, or an object without VecNormalize's attributes
            raise PolicyError(f"{path} is not a VecNormalize file saved by stable-baselines3: {exc}") from None
        if not norm_obs or not hasattr(rms, "mean"):
            raise PolicyError(f"{path} does not normalize observations (norm_obs=False or Dict statistics)")
        return cls(np.asarray(rms.mean, dtype=np.float64), np.asarray(rms.var, dtype=np.float64), epsilon, clip)

    def __call__(self, observation: NDArray[np.floating]) -> NDArray[np.float32]:
        """``observation`` (one, or a batch) normalized: ``VecNormalize``'s arithmetic, to the bit."""
        scaled = (observation - self.mean) / np.sqrt(self.var + self.epsilon)
        return np.clip(scaled, -self.clip, self.clip).astype(np.float32)


def _announce_origin(path: Path) -> None:
    """Log, once per file in this process, that ``path`` is loaded from outside the shipped models: unpickling it
    can run code from the file."""
    where = path.resolve()
    if is_shipped_model_file(where) or where in _ANNOUNCED:
        return
    _ANNOUNCED.add(where)
    _LOG.warning(
        "loading the policy file %s (not one of redundancy_gym's shipped models): an SB3 .zip or VecNormalize .pkl "
        "holds pickled objects "
        "and loading it can run code from the file; load only files you trust",
        where,
    )


class Sb3Policy:
    """A stable-baselines3 model loaded from a ``.zip``; ``predict`` gives the model's actions.

    A deterministic ``predict`` of a plain MLP (PPO, A2C, SAC, TD3, DDPG on a ``Box`` observation) runs
    :attr:`inference`, the network's weights in one compiled kernel call, instead of SB3's ``predict``: the same
    actions to within torch's float32 rounding (:mod:`~redundancy_gym.policies.mlp_inference`), in a few
    microseconds. A stochastic ``predict``, and every ``predict`` of another architecture, is SB3's.

    Args:
        path: the ``.zip`` written by ``model.save``. Loading it can run code from the file (SB3 unpickles its
            objects): load only files you trust; one from outside the shipped models is logged with its path.
        env: the environment (checked against the model's spaces by SB3).
        algo: the SB3 algorithm class name; tried in the order PPO, SAC, TD3, A2C, DDPG, then sb3-contrib's TQC and
            CrossQ (where installed), when omitted.
        fast_path: run a plain MLP's deterministic ``predict`` on the compiled fast path (False: SB3's always, for
            torch's float32 actions to the last bit: on a biped, a difference of 1e-6 can move a fall by steps).

    Attributes:
        model: the loaded SB3 model; algo: its class name.
        normalization: the observation statistics of ``<stem>_vecnormalize.pkl`` beside the ``.zip``
            (:func:`vecnormalize_path`), applied before every ``predict``, or None where there is no such file.
        inference: the fast path, or None.
        fast_path: whether a deterministic ``predict`` runs :attr:`inference`.
        fast_path_reason: the network the fast path runs (``"PPO MLP 20 -> 64x64 -> 4 (tanh)"``), or why there is
            none (``"observation space Dict (only a Box is a plain MLP's input)"``); logged at INFO level then.
    """

    def __init__(self, path: str | Path, env: Any = None, algo: str | None = None, fast_path: bool = True) -> None:
        path = Path(path)
        if not path.is_file():
            raise PolicyError(f"policy file not found: {path}")
        if not isinstance(fast_path, bool):
            raise PolicyError(f"fast_path={fast_path!r}; valid: True, False")
        try:
            sb3 = import_stable_baselines3()
        except ImportError as exc:  # the 'learn' extra
            raise PolicyError(f"loading a .zip policy needs stable-baselines3: {LEARN_EXTRA_HINT}") from exc
        _announce_origin(path)  # before the load: a file that runs code has been named by then
        sb3_contrib: Any = None
        try:
            import sb3_contrib
        except ImportError:
            pass
        names = (algo,) if algo else SB3_ALGOS + (SB3_CONTRIB_ALGOS if sb3_contrib is not None else ())
        errors = []
        for name in names:
            cls = getattr(sb3, name, None) if name in SB3_ALGOS else getattr(sb3_contrib, name, None)
            if cls is None:
                raise PolicyError(
                    f"unknown SB3 algorithm {name!r}; valid: {', '.join(SB3_ALGOS + SB3_CONTRIB_ALGOS)} (the last "
                    "two with sb3-contrib)"
                )
            try:
                self.model = cls.load(str(path), device="cpu")
                self.algo = name
                break
            except Exception as exc:  # SB3 raises assorted errors for a class mismatch
                errors.append(f"{name}: {type(exc).__name__}")
        else:
            raise PolicyError(f"{path} is not a stable-baselines3 model of {', '.join(names)} ({'; '.join(errors)})")
        if env is not None:
            self._check_spaces(path, env)
        stats = vecnormalize_path(path)
        self.normalization: ObservationNormalization | None = None
        if stats.is_file():
            _announce_origin(stats)
            self.normalization = ObservationNormalization.load(stats)
            shape = getattr(self.model.observation_space, "shape", None)
            if self.normalization.mean.shape != shape:
                raise PolicyError(
                    f"{stats} holds statistics of shape {self.normalization.mean.shape}, but {path} observes {shape}"
                )
        self.inference: MlpInference | None
        if fast_path:
            self.inference, self.fast_path_reason = mlp_inference_from_sb3(self.model)
        else:
            self.inference, self.fast_path_reason = None, "turned off (fast_path=False)"
        self.fast_path = self.inference is not None
        if self.inference is None and fast_path:
            _LOG.info("%s: no fast path (%s); predict runs stable-baselines3's", path.name, self.fast_path_reason)

    def _check_spaces(self, path: Path, env: Any) -> None:
        """A model trained on another env fails here, naming both, instead of at its first ``predict``."""
        for kind in ("observation", "action"):
            trained = getattr(self.model, f"{kind}_space", None)
            here = getattr(env, f"{kind}_space", None)
            shapes = (getattr(trained, "shape", None), getattr(here, "shape", None))
            if None not in shapes and shapes[0] != shapes[1]:
                raise PolicyError(
                    f"{path} was trained with {kind} shape {shapes[0]}, but {env_name(env)} has "
                    f"{shapes[1]}: it was trained on another env (or other env kwargs)"
                )

    def predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.floating], Any]:
        """The model's action for one observation, or its actions for a batch (``(n, *observation_shape)``), and
        ``state`` back (SB3's contract; a plain MLP has no state): :attr:`inference`'s where
        :attr:`fast_path` and ``deterministic``, else SB3's :meth:`sb3_predict`.

        Raises:
            PolicyError: on the fast path, an observation of neither shape (SB3 raises a ValueError).
        """
        if self.normalization is not None:
            observation = self.normalization(observation)
        if deterministic and self.inference is not None:
            return self.inference(observation), state
        return self._sb3_predict(observation, state, episode_start, deterministic)

    def sb3_predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.floating], Any]:
        """SB3's own ``model.predict``, whatever the fast path (an evaluation times both: ``sb3_predict_us``); the
        observation normalized first where the model has :attr:`normalization`."""
        if self.normalization is not None:
            observation = self.normalization(observation)
        return self._sb3_predict(observation, state, episode_start, deterministic)

    def _sb3_predict(
        self, observation: NDArray[np.floating], state: Any, episode_start: Any, deterministic: bool
    ) -> tuple[NDArray[np.floating], Any]:
        return self.model.predict(observation, state=state, episode_start=episode_start, deterministic=deterministic)


def _sequential(module: Any, where: str) -> tuple[list[tuple[Any, Any, str]] | None, str]:
    """The ``(weight, bias, activation)`` layers of a torch ``Sequential`` of ``Linear`` layers, each followed by
    at most one ``Tanh`` or ``ReLU``, or None and what else it holds."""
    from torch import nn

    supported: dict[type, str] = {nn.Tanh: "tanh", nn.ReLU: "relu"}
    if type(module) is not nn.Sequential:
        return None, f"{where} is a {type(module).__name__}, not a Sequential of Linear layers"
    layers: list[tuple[Any, Any, str]] = []
    for child in module:
        if type(child) is nn.Linear:
            if child.bias is None:
                return None, f"{where} has a Linear layer without bias"
            layers.append((child.weight, child.bias, "identity"))
        elif type(child) in supported and layers and layers[-1][2] == "identity":
            layers[-1] = (*layers[-1][:2], supported[type(child)])
        else:
            return None, (
                f"{where} holds {type(child).__name__} (supported: Linear, each followed by at most one Tanh or ReLU)"
            )
    return layers, ""


def _linear(module: Any, where: str) -> tuple[list[tuple[Any, Any, str]] | None, str]:
    """The one layer of a torch ``Linear`` with bias, or None and what it is instead."""
    from torch import nn

    if type(module) is not nn.Linear or module.bias is None:
        return None, f"{where} is a {type(module).__name__}, not a Linear layer with bias"
    return [(module.weight, module.bias, "identity")], ""


def _network(model: Any) -> tuple[list[tuple[Any, Any, str]] | None, bool, str]:
    """The actor's layers of ``model``'s policy and whether a ``tanh`` follows them, or None and why not."""
    from stable_baselines3.common.distributions import DiagGaussianDistribution, SquashedDiagGaussianDistribution
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.common.torch_layers import FlattenExtractor, MlpExtractor
    from stable_baselines3.sac.policies import Actor as SacActor
    from stable_baselines3.sac.policies import SACPolicy
    from stable_baselines3.td3.policies import Actor as Td3Actor
    from stable_baselines3.td3.policies import TD3Policy

    policy = model.policy
    kind = type(policy)
    if kind is ActorCriticPolicy:
        if type(policy.pi_features_extractor) is not FlattenExtractor:
            return None, False, f"features extractor {type(policy.pi_features_extractor).__name__} (not Flatten)"
        if type(policy.mlp_extractor) is not MlpExtractor:
            return None, False, f"mlp_extractor {type(policy.mlp_extractor).__name__} (not SB3's MlpExtractor)"
        if type(policy.action_dist) is not DiagGaussianDistribution:
            # gSDE, categorical and other distributions have another mode (and state-dependent noise)
            return None, False, f"action distribution {type(policy.action_dist).__name__} (not DiagGaussian)"
        body, why = _sequential(policy.mlp_extractor.policy_net, "mlp_extractor.policy_net")
        head, why_head = _linear(policy.action_net, "action_net")
        if body is None or head is None:
            return None, False, why or why_head
        return body + head, False, ""
    if kind is SACPolicy:
        actor = policy.actor
        if type(actor) is not SacActor or actor.use_sde:
            return None, False, "a SAC actor with state-dependent exploration (gSDE) or of its own class"
        if type(actor.features_extractor) is not FlattenExtractor:
            return None, False, f"features extractor {type(actor.features_extractor).__name__} (not Flatten)"
        if type(actor.action_dist) is not SquashedDiagGaussianDistribution:
            return None, False, f"action distribution {type(actor.action_dist).__name__} (not SquashedDiagGaussian)"
        body, why = _sequential(actor.latent_pi, "actor.latent_pi")
        head, why_head = _linear(actor.mu, "actor.mu")
        if body is None or head is None:
            return None, False, why or why_head
        return body + head, True, ""
    if kind is TD3Policy:  # DDPG's too
        actor = policy.actor
        if type(actor) is not Td3Actor:
            return None, False, f"a TD3 actor of its own class {type(actor).__name__}"
        if type(actor.features_extractor) is not FlattenExtractor:
            return None, False, f"features extractor {type(actor.features_extractor).__name__} (not Flatten)"
        layers, why = _sequential(actor.mu, "actor.mu")
        return layers, False, why
    return None, False, f"policy class {kind.__name__} (supported: ActorCriticPolicy, SACPolicy, TD3Policy MLPs)"


def mlp_inference_from_sb3(model: Any) -> tuple[MlpInference | None, str]:
    """The fast path of ``model`` (a loaded SB3 ``PPO``, ``A2C``, ``SAC``, ``TD3`` or ``DDPG``): its deterministic
    actor as an :class:`MlpInference` and a description of the network, or ``None`` and why it is no plain MLP
    on a ``Box`` observation (then ``model.predict`` is the only way to its actions).

    The weights are copied: training the model further does not change the returned network.
    """
    from gymnasium import spaces
    from stable_baselines3.common.preprocessing import is_image_space

    policy = getattr(model, "policy", None)
    obs_space = getattr(model, "observation_space", None)
    action_space = getattr(model, "action_space", None)
    if policy is None:
        return None, f"{type(model).__name__} has no SB3 policy"
    if not isinstance(obs_space, spaces.Box):
        return None, f"observation space {type(obs_space).__name__} (only a Box is a plain MLP's input)"
    if not isinstance(action_space, spaces.Box):
        return None, f"action space {type(action_space).__name__} (only a Box has a continuous mean action)"
    if policy.normalize_images and is_image_space(obs_space):
        return None, "image observations (scaled by 1/255 and usually fed to a CNN)"
    layers, squash, why = _network(model)
    if layers is None:
        return None, why
    dtypes = {str(p.dtype) for w, b, _ in layers for p in (w, b)}
    if dtypes != {"torch.float32"}:
        return None, f"parameters of dtype {', '.join(sorted(dtypes))} (the kernel computes in float32)"
    arrays = [(w.detach().cpu().numpy(), b.detach().cpu().numpy(), act) for w, b, act in layers]
    try:
        inference = MlpInference(
            arrays,
            obs_space.shape,
            action_space.low,
            action_space.high,
            squash=squash,
            unscale=bool(policy.squash_output),
        )
    except PolicyError as exc:  # a network whose sizes do not fit its spaces: SB3's predict fails on it too
        return None, str(exc)
    algo = type(model).__name__
    return inference, f"{algo} {inference.description}" + (", tanh-squashed" if squash else "")
