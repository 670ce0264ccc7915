"""redundancy-gym: Gymnasium environments on MuJoCo for redundant robots, with model-based reference policies.

Subcommands: list (the envs and the policies each accepts), eval (a policy over episodes: table and JSON),
train (a stable-baselines3 agent), collect (a reference's episodes as a dataset), baselines (the learned baselines),
render (one episode as a video), bench (benchmarks), warmup (numba's cache filled ahead) and demo (everything into
one folder). Run "redundancy-gym <subcommand> --help" for its options.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from typing import Any

from . import __version__
from .bench.exceptions import BenchError
from .bench.table import BENCHES, BenchArgs, check_bench_args

__all__ = ["main"]

EPILOG = """examples:
  redundancy-gym list
  redundancy-gym eval redundancy_gym/PlanarReach-v0 --policy clik --episodes 20 --env-kwargs '{"obstacle": false}'
  redundancy-gym train redundancy_gym/PlanarReach-v0 --config configs/ppo_planar_reach.yaml --steps 100000
  redundancy-gym eval redundancy_gym/PlanarReach-v0 --policy runs/ppo_PlanarReach-v0.zip
  redundancy-gym collect redundancy_gym/PlanarReach-v0 --policy clik --episodes 50 --out datasets
"""
ENV_HELP = "a registered env id, e.g. redundancy_gym/PlanarReach-v0 (redundancy-gym list shows them all)"
POLICY_HELP = (
    "clik | walking | predictive | global | zero | random | path to an SB3 .zip | a shipped learned "
    "baseline <learner>-<action>, e.g. ppo-nullspace (redundancy-gym list shows which envs each accepts). "
    "A .zip policy is code: SB3 unpickles it, and loading it can run code from the file, so load only files "
    "you trust (one from outside the shipped models is named on stderr)"
)
WRAPPER_HELP = (
    "task_space | nullspace | residual | walking_command: the env in that action wrapper (the same as "
    "its id <Env>-<Wrapper>-v0; redundancy-gym list shows which env takes which)"
)


def _json_object(text: str) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise argparse.ArgumentTypeError(f"not valid JSON: {exc}") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError("must be a JSON object, e.g. '{\"obstacle\": false}'")
    return value


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows each option's default, except the empty ones (None, False), whose help says what happens."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        if action.default is None or action.default is False:
            return action.help
        return super()._get_help_string(action)


class _RawHelpFormatter(_HelpFormatter, argparse.RawDescriptionHelpFormatter):
    """The top-level help: description and examples as written."""


def _add_parser(sub: Any, name: str, help_text: str, **kwargs: Any) -> argparse.ArgumentParser:
    return sub.add_parser(name, help=help_text, description=help_text, formatter_class=_HelpFormatter, **kwargs)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="redundancy-gym", description=__doc__, epilog=EPILOG, formatter_class=_RawHelpFormatter
    )
    parser.add_argument("--version", action="version", version=f"redundancy-gym {__version__}")
    sub = parser.add_subparsers(
        dest="command", required=True, metavar="{list,eval,train,collect,baselines,render,bench,warmup,demo}"
    )

    ls = _add_parser(sub, "list", "list the registered envs: spaces, control period, episode length, policies")
    ls.add_argument("--json", action="store_true", help="print JSON instead of a table")

    ev = _add_parser(sub, "eval", "evaluate a policy; prints a table and writes the evaluation-contract JSON")
    ev.add_argument("env_id", help=ENV_HELP)
    ev.add_argument("--wrapper", metavar="NAME", help=WRAPPER_HELP)
    ev.add_argument(
        "--wrapper-kwargs",
        type=_json_object,
        default={},
        metavar="JSON",
        help="JSON object of the wrapper's options (with --wrapper)",
    )
    ev.add_argument("--policy", required=True, metavar="NAME|ZIP", help=POLICY_HELP)
    ev.add_argument("--episodes", type=int, default=10, metavar="N", help="number of episodes")
    ev.add_argument("--seed", type=int, default=0, metavar="N", help="episode i is reset with seed + i")
    ev.add_argument(
        "--env-kwargs", type=_json_object, default={}, metavar="JSON", help="JSON object passed to gym.make"
    )
    ev.add_argument(
        "--policy-kwargs", type=_json_object, default={}, metavar="JSON", help="JSON object of policy options"
    )
    ev.add_argument("--json", dest="json_path", metavar="PATH", help="write the report to this file (default: no file)")
    ev.add_argument(
        "--warmup",
        type=int,
        default=0,
        metavar="N",
        help="untimed episodes first (seed --seed), so JIT compilation and one-time set-up are not "
        "counted in the step times (with --workers or --ray: one untimed reset and step instead, before the "
        "workers fork or in each spawned one)",
    )
    ev.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="split the episodes across N processes; each keeps its seed, so the JSON is the serial "
        "run's (timings excepted) (default: 1; with --ray the Ray cluster's CPUs)",
    )
    ev.add_argument(
        "--ray",
        nargs="?",
        const="local",
        metavar="ADDRESS",
        help="run the episodes on Ray actors: on the cluster at ADDRESS, or without one on a local Ray "
        "instance (the ray extra); --workers defaults to the cluster's CPUs",
    )
    ev.add_argument(
        "--retries",
        type=int,
        default=0,
        metavar="K",
        help="with --workers: run episodes whose worker raised or died again, up to K times (a run "
        "with failed episodes left names their seeds and exits with status 2)",
    )
    ev.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    tr = _add_parser(
        sub,
        "train",
        "train a stable-baselines3 agent and save a .zip that eval loads; prints the "
        "return, success rate and length of recent episodes as it goes",
    )
    tr.add_argument("env_id", help=ENV_HELP)
    tr.add_argument("--wrapper", metavar="NAME", help=WRAPPER_HELP)
    tr.add_argument(
        "--wrapper-kwargs",
        type=_json_object,
        default={},
        metavar="JSON",
        help="JSON object of the wrapper's options (with --wrapper)",
    )
    tr.add_argument(
        "--algo",
        choices=("ppo", "sac", "bc"),
        default="ppo",
        help="stable-baselines3 algorithm, or bc: behaviour cloning with DAgger from --expert (its "
        "budget is the config's episodes and dagger_rounds, not --steps)",
    )
    tr.add_argument(
        "--expert",
        metavar="NAME",
        help="with --algo bc: the policy to clone (default: the env's reference, clik or walking)",
    )
    tr.add_argument(
        "--config",
        metavar="YAML",
        help="rl-zoo3 style YAML keyed by env id (see configs/); its n_timesteps and n_envs are the "
        "defaults of --steps and --n-envs (default: none, SB3's own defaults)",
    )
    tr.add_argument("--steps", type=int, metavar="N", help="total environment steps (default: n_timesteps of --config)")
    tr.add_argument(
        "--n-envs", type=int, metavar="N", help="envs stepped together (default: n_envs of --config, else 1)"
    )
    tr.add_argument(
        "--vec-env",
        "--vec",
        choices=("dummy", "subproc", "sync", "async"),
        default="dummy",
        help="dummy (= sync): all envs in this process; subproc (= async): one process per env",
    )
    tr.add_argument("--out", metavar="ZIP", help="output .zip path (default: runs/<algo>_<env name>.zip)")
    tr.add_argument(
        "--seed", type=int, default=0, metavar="N", help="seed of the agent; env i is reset with seed + i first"
    )
    tr.add_argument(
        "--env-kwargs",
        type=_json_object,
        default={},
        metavar="JSON",
        help="JSON object passed to gym.make (over the config's env_kwargs)",
    )
    tr.add_argument("--tensorboard", metavar="DIR", help="write TensorBoard logs here (default: none)")
    tr.add_argument(
        "--print-every",
        type=int,
        metavar="STEPS",
        help="steps between printed statistics lines (default: steps / 20, at least 1000)",
    )
    tr.add_argument(
        "--torch-threads",
        type=int,
        default=1,
        metavar="N",
        help="torch CPU threads (more pay off only for networks larger than the default MLP)",
    )
    tr.add_argument(
        "--eval-freq",
        type=int,
        metavar="STEPS",
        help="evaluate the deterministic agent every STEPS steps on a separate env (SB3 EvalCallback; "
        "TensorBoard, best agent saved as <out>_best.zip) (default: never)",
    )
    tr.add_argument("--eval-episodes", type=int, default=5, metavar="N", help="episodes per evaluation")
    tr.add_argument(
        "--eval-seed",
        type=int,
        default=30000,
        metavar="N",
        help="first seed of the evaluation episodes (keep it apart from the seeds you report on)",
    )
    tr.add_argument(
        "--checkpoint-freq",
        type=int,
        metavar="STEPS",
        help="save the agent every STEPS steps into <out>_checkpoints/ (default: never)",
    )
    tr.add_argument(
        "--ray",
        nargs="?",
        const="local",
        metavar="ADDRESS",
        help="a seed sweep on Ray (the cluster at ADDRESS, or a local instance): one task per --seeds "
        "entry, each trained and evaluated on held-out seeds 20000+; writes <out>_seed<S>.zip and "
        "<out>_sweep.json",
    )
    tr.add_argument("--seeds", type=int, nargs="+", metavar="S", help="with --ray: the seeds of the sweep")
    tr.add_argument(
        "--keep",
        choices=("last", "best"),
        default="last",
        help="save the last agent to --out, or the evaluation's best (needs --eval-freq; the last then "
        "goes to <out>_last.zip)",
    )
    tr.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    tr.add_argument(
        "--dataset",
        metavar="DIR",
        help="with --algo bc: learn round 0 from this Minari dataset (redundancy-gym collect) instead of expert "
        "rollouts; with dagger_rounds 0 in the config, from the dataset alone",
    )

    co = _add_parser(
        sub,
        "collect",
        "record a policy's episodes as a Minari dataset (the dataset extra): observations, actions, rewards, "
        "the env's metrics; its env spec, policy, seeds and success rate in the metadata",
    )
    co.add_argument("env_id", help=ENV_HELP)
    co.add_argument("--wrapper", metavar="NAME", help=WRAPPER_HELP)
    co.add_argument(
        "--wrapper-kwargs", type=_json_object, default={}, metavar="JSON", help="JSON object of the wrapper's options"
    )
    co.add_argument(
        "--policy", metavar="NAME|ZIP", help="the policy recorded (default: the env's reference, clik or walking)"
    )
    co.add_argument("--episodes", type=int, default=10, metavar="N", help="number of episodes")
    co.add_argument("--seed", type=int, default=0, metavar="N", help="episode i is reset with seed + i")
    co.add_argument(
        "--out", default="datasets", metavar="DIR", help="root folder of the datasets (MINARI_DATASETS_PATH)"
    )
    co.add_argument("--dataset-id", metavar="ID", help="Minari id (default: redundancy_gym/<env name>/<policy>-v0)")
    co.add_argument(
        "--action-noise",
        type=float,
        default=0.0,
        metavar="SIGMA",
        help="Gaussian noise on the stepped action [fraction of its half range] (DART); the policy's own action "
        "is kept as infos['expert_action']",
    )
    co.add_argument(
        "--env-kwargs", type=_json_object, default={}, metavar="JSON", help="JSON object passed to gym.make"
    )
    co.add_argument(
        "--policy-kwargs", type=_json_object, default={}, metavar="JSON", help="JSON object of policy options"
    )
    co.add_argument("--overwrite", action="store_true", help="replace a dataset of the same id in --out")
    co.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    re = _add_parser(sub, "render", "record one episode as .mp4 or .gif")
    re.add_argument("env_id", help=ENV_HELP)
    re.add_argument("--wrapper", metavar="NAME", help=WRAPPER_HELP)
    re.add_argument(
        "--wrapper-kwargs",
        type=_json_object,
        default={},
        metavar="JSON",
        help="JSON object of the wrapper's options (with --wrapper)",
    )
    re.add_argument("--policy", required=True, metavar="NAME|ZIP", help=POLICY_HELP)
    re.add_argument("--out", required=True, metavar="PATH", help="output .mp4 or .gif path")
    re.add_argument("--seed", type=int, default=0, metavar="N", help="seed of the episode")
    re.add_argument(
        "--env-kwargs", type=_json_object, default={}, metavar="JSON", help="JSON object passed to gym.make"
    )
    re.add_argument(
        "--policy-kwargs", type=_json_object, default={}, metavar="JSON", help="JSON object of policy options"
    )
    re.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    be = _add_parser(sub, "bench", "run a benchmark against its peers and write its figures")
    be.add_argument("name", choices=tuple(BENCHES), help="; ".join(f"{b.name}: {b.summary}" for b in BENCHES.values()))
    be.add_argument("--json", dest="json_path", metavar="PATH", help="output JSON (default: results/bench_<name>.json)")
    be.add_argument(
        "--seed",
        type=int,
        metavar="N",
        help="seed of the benchmark's scenes (default: 0; learned: 20000, its first held-out seed)",
    )
    be.add_argument("--quick", action="store_true", help="short timings (a smoke run, not for quoting)")
    be.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    be.add_argument(
        "--rounds",
        type=int,
        metavar="N",
        help="ssv, envs, ik, walk, pik, scale: alternating timing rounds of ours and the peer (after a "
        "warm-up; ratios are medians over the rounds; default: each bench's, --quick: 3); startup: warm runs "
        "per probe, the median reported (default: 5, --quick: 3)",
    )
    budget = be.add_mutually_exclusive_group()
    budget.add_argument(
        "--seconds",
        type=float,
        metavar="S",
        help="soak only: wall time per env, split over the action sources (default: 10, --quick: 1)",
    )
    budget.add_argument(
        "--steps",
        type=int,
        metavar="N",
        help="soak: steps per env instead of --seconds, split over the action sources; curves: the largest "
        "budget [environment steps] of every run (the smaller ones kept)",
    )
    be.add_argument(
        "--trials",
        type=int,
        metavar="N",
        help="push: trials per impulse level (default: 20, --quick: 5); curves: training seeds per learner "
        "(default: 3, --quick: 1)",
    )
    be.add_argument(
        "--episodes",
        type=int,
        metavar="N",
        help="learned, robustness: episodes per policy (and condition) from --seed (default: 20 and 10, --quick: 2); "
        "curves: held-out episodes per point (default: 10, --quick: 1)",
    )
    be.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="learned, robustness: split each evaluation's episodes across N processes (default: 1); scale: the "
        "worker count compared with the serial loop (default: 2); curves: runs trained at once (default: 1)",
    )
    be.add_argument(
        "--ray",
        nargs="?",
        const="local",
        metavar="ADDRESS",
        help="learned only: evaluate on Ray actors (the cluster at ADDRESS, or a local instance); "
        "--workers defaults to the cluster's CPUs",
    )
    be.add_argument(
        "--envs",
        nargs="+",
        metavar="ENV",
        help="learned: planar_reach, agri_reach, biped_walk, biped_obstacles, biped_terrain; robustness: the first "
        "four (default: all); the other envs' sections of an existing --json of the same seed and episodes are kept; "
        "curves: planar_reach, agri_reach_easy/_medium/_hard, biped_walk, biped_obstacles, or one learner as "
        "ENV-LEARNER (planar_reach-ppo); startup: probes (import, list, quick_start, an env id such as "
        "PlanarReach-v0, policy:clik)",
    )

    wu = _add_parser(
        sub,
        "warmup",
        "fill numba's cache ahead of use: make each env, step it, and run every analytic policy it supports once "
        "(a first episode, test run or cluster worker then loads compiled kernels; NUMBA_CACHE_DIR moves the cache)",
    )
    wu.add_argument("env_ids", nargs="*", metavar="ENV", help="env ids to warm up (default: every registered one)")
    wu.add_argument("--workers", type=int, default=1, metavar="N", help="warm up in N processes")
    wu.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    wu.add_argument(
        "--pack",
        action="store_true",
        help="instead, compile the kernels for the portable x86-64-v3 CPU (in one process) into "
        "redundancy_gym/packed_kernels/, which a wheel built next ships (a new process then copies them into its "
        "numba cache)",
    )

    ba = _add_parser(
        sub,
        "baselines",
        "train the learned baselines of baselines/*.yaml (seeded; each into "
        "baselines/models/<name>.zip with its training record <name>.json); "
        "bench learned then evaluates them",
    )
    ba.add_argument(
        "names",
        nargs="*",
        metavar="NAME",
        help="baselines to train, e.g. ppo-residual-agri_reach (default: all; --list shows them)",
    )
    ba.add_argument("--list", action="store_true", help="list the baselines and their shipped models, train nothing")
    ba.add_argument(
        "--steps",
        type=int,
        metavar="N",
        help="PPO/SAC budget instead of each file's n_timesteps (a smoke run; the shipped models use the files')",
    )
    ba.add_argument("--models", default=None, metavar="DIR", help="where the models go (default: baselines/models)")
    ba.add_argument(
        "--ray",
        nargs="?",
        const="local",
        metavar="ADDRESS",
        help="train the baselines as Ray tasks, one CPU each (the cluster at ADDRESS, or a local "
        "instance); the models come back to this machine",
    )

    de = _add_parser(sub, "demo", "reference controllers on every env: JSON, plots, video into a folder")
    de.add_argument("--out", default="results", metavar="DIR", help="output folder")
    de.add_argument("--episodes", type=int, default=20, metavar="N", help="episodes per evaluation")
    de.add_argument("--seed", type=int, default=0, metavar="N", help="seed of the first episode")
    de.add_argument(
        "--workers",
        type=int,
        default=1,
        metavar="N",
        help="split each evaluation's episodes across N processes (the same results, timings excepted; "
        "the step times are then those of a machine with every core busy)",
    )
    return parser


def _format_shape(shape: Any) -> str:
    return str(tuple(shape))


def list_envs() -> list[dict[str, Any]]:
    """One row per registered env id: spaces, control period, episode length and the policies and wrappers it
    accepts, read from its :data:`~redundancy_gym.registration.ENV_CARDS` entry (no env is built)."""
    import gymnasium as gym

    from .policies import supported_names
    from .registration import ENV_CARDS

    rows = []
    for env_id, card in ENV_CARDS.items():
        dt, steps = card.control_period_s, gym.spec(env_id).max_episode_steps
        rows.append(
            {
                "id": env_id,
                "observation_shape": list(card.observation_shape),
                "action_shape": list(card.action_shape),
                "control_period_s": dt,
                "max_episode_steps": steps,
                "episode_s": None if steps is None else round(dt * steps, 6),
                "policies": [*supported_names(env_id), "SB3 .zip"],
                "wrappers": list(supported_names(env_id, "wrapper")),
            }
        )
    return rows


def format_registry() -> str:
    """The registered policies and action wrappers, with the env ids each supports, as a text table."""
    from . import ENV_IDS
    from .policies import registered, supported_env_ids

    table = [("name", "kind", "supports", "what it does")]
    for entry in registered("policy") + registered("wrapper"):
        supported = supported_env_ids(entry.name, entry.kind)
        ids = "every env" if set(supported) == set(ENV_IDS) else ", ".join(i.split("/")[-1] for i in supported) or "-"
        table.append((entry.name, entry.kind, ids, entry.summary))
    from .policies.shipped_models import SHIPPED_MODELS_DIR, model_name, shipped_models

    stems = shipped_models()
    for stem in stems:  # the learned baselines of baselines/models/, by short name
        learner, action, slug, variant = model_name(stem)
        short = f"{learner}-{action}" + ("" if variant is None else f"-{variant}")
        table.append((short, "model", slug, f"shipped learned baseline baselines/models/{stem}.zip"))
    widths = [max(len(r[i]) for r in table) for i in range(3)]
    text = "\n".join(
        "  ".join(cell.ljust(w) for cell, w in zip(r[:3], widths, strict=True)) + "  " + r[3] for r in table
    )
    found = f"{len(stems)} shipped model(s)" if stems else "no shipped models (*.zip)"
    return f"{text}\n\n{found} in {SHIPPED_MODELS_DIR}"


def format_env_list(rows: list[dict[str, Any]]) -> str:
    """The rows of :func:`list_envs` as a text table."""
    header = ("env id", "observation", "action", "control period", "max steps", "policies")
    table = [header]
    for row in rows:
        dt = row["control_period_s"]
        steps = row["max_episode_steps"]
        episode = f" ({row['episode_s']:g} s)" if row["episode_s"] is not None else ""
        table.append(
            (
                row["id"],
                _format_shape(row["observation_shape"]),
                _format_shape(row["action_shape"]),
                "-" if dt is None else f"{dt * 1e3:g} ms",
                "-" if steps is None else f"{steps}{episode}",
                ", ".join(row["policies"]),
            )
        )
    widths = [max(len(r[i]) for r in table) for i in range(len(header) - 1)]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(r[:-1], widths, strict=False)) + "  " + r[-1] for r in table]
    return "\n".join(lines)


def _apply_wrapper(args: argparse.Namespace) -> None:
    """``--wrapper NAME``: the env id becomes the wrapped id, ``--wrapper-kwargs`` its ``wrapper_kwargs``."""
    from .eval.exceptions import EvalError
    from .policies import registered
    from .registration import WRAPPED_ENV_IDS, wrapped_env_id

    if args.wrapper is None:
        if args.wrapper_kwargs:
            raise EvalError(
                "--wrapper-kwargs needs --wrapper (on a wrapped id, pass the options in --env-kwargs "
                "as '{\"wrapper_kwargs\": {...}}')"
            )
        return
    wrapped = wrapped_env_id(args.env_id, args.wrapper)
    if wrapped is None:
        names = [e.name for e in registered("wrapper")]
        if args.wrapper not in names:
            raise EvalError(f"unknown wrapper {args.wrapper!r}; valid: {', '.join(names)}")
        here = [name for name in names if wrapped_env_id(args.env_id, name)]
        raise EvalError(
            f"no registered {args.wrapper!r} wrapper for {args.env_id}; its wrappers: "
            f"{', '.join(here) or 'none'} (the wrapped ids: {', '.join(WRAPPED_ENV_IDS)})"
        )
    args.env_id = wrapped
    if args.wrapper_kwargs:
        args.env_kwargs = {**args.env_kwargs, "wrapper_kwargs": args.wrapper_kwargs}


def _train(args: argparse.Namespace) -> None:
    from .eval.exceptions import EvalError
    from .learning.training import TrainingConfig, load_config, train

    config = load_config(args.config, args.env_id) if args.config else TrainingConfig(hyperparameters={})
    if args.algo == "bc":
        _train_behaviour_cloning(args, config)
        return
    if args.expert is not None or args.dataset is not None:
        raise EvalError("--expert and --dataset apply to --algo bc only")
    steps = args.steps if args.steps is not None else config.n_timesteps
    if steps is None:
        raise EvalError("give --steps, or a --config whose section has n_timesteps")
    n_envs = args.n_envs if args.n_envs is not None else (config.n_envs or 1)
    if (args.ray is None) != (args.seeds is None):
        raise EvalError("--ray and --seeds go together: a seed sweep on Ray")
    if args.ray is not None:
        from .learning.sweep import train_seed_sweep

        out = args.out or f"runs/{args.algo}_{args.env_id.split('/')[-1]}.zip"
        sweep = train_seed_sweep(
            args.env_id,
            args.algo,
            steps,
            out,
            args.seeds,
            ray_address=args.ray,
            train_kwargs={
                "env_kwargs": {**config.env_kwargs, **args.env_kwargs},
                "hyperparameters": config.hyperparameters,
                "n_envs": n_envs,
                "vec_env": args.vec_env,
                "policy": config.policy,
            },
        )
        print(
            f"success over seeds {sweep['success_mean']:.2f} +- {sweep['success_std']:.2f}, return "
            f"{sweep['return_mean']:.1f} +- {sweep['return_std']:.1f}"
        )
        return
    out = args.out or f"runs/{args.algo}_{args.env_id.split('/')[-1]}.zip"
    source = f" from {args.config}" if args.config else ""
    print(
        f"training {args.algo.upper()} ({config.policy}{source}) on {args.env_id}: {steps} steps, {n_envs} "
        f"env(s) ({args.vec_env}), seed {args.seed}"
    )
    path = train(
        args.env_id,
        args.algo,
        steps,
        out,
        seed=args.seed,
        env_kwargs={**config.env_kwargs, **args.env_kwargs},
        hyperparameters=config.hyperparameters,
        progress_bar=not args.no_progress,
        tensorboard_log=args.tensorboard,
        n_envs=n_envs,
        vec_env=args.vec_env,
        policy=config.policy,
        print_every=args.print_every,
        torch_threads=args.torch_threads,
        eval_freq=args.eval_freq,
        eval_episodes=args.eval_episodes,
        eval_seed=args.eval_seed,
        checkpoint_freq=args.checkpoint_freq,
        keep=args.keep,
    )
    print(f"wrote {path}; evaluate it with: redundancy-gym eval {args.env_id} --policy {path}")


def _collect(args: argparse.Namespace) -> None:
    from .datasets import collect_dataset

    summary = collect_dataset(
        args.env_id,
        args.out,
        policy=args.policy,
        policy_kwargs=args.policy_kwargs,
        env_kwargs=args.env_kwargs,
        episodes=args.episodes,
        seed=args.seed,
        action_noise=args.action_noise,
        dataset_id=args.dataset_id,
        overwrite=args.overwrite,
        progress=not args.no_progress,
    )
    print(f"wrote {summary.format()}")
    print(
        f'load it with: MINARI_DATASETS_PATH={args.out} python -c "import minari; '
        f"print(minari.load_dataset('{summary.dataset_id}'))\"; clone it with: redundancy-gym train "
        f"{args.env_id} --algo bc --dataset {summary.path}"
    )


def _workers(args: argparse.Namespace) -> int:
    """``--workers``, defaulting to 1, or with ``--ray`` to the Ray cluster's CPUs."""
    if args.workers is not None:
        return int(args.workers)
    if args.ray is None:
        return 1
    from .eval.parallel import ray_cpus

    return ray_cpus(args.ray)


def _warmup(args: argparse.Namespace) -> None:
    from .eval.exceptions import EvalError
    from .eval.warmup import numba_cache_location, pack_kernels, warmup

    if args.pack:
        if args.workers != 1:
            raise EvalError(
                "--pack compiles in one process (numba's cache index is not safe against two), got --workers "
                f"{args.workers}"
            )
        packed = pack_kernels(args.env_ids or None, progress=not args.no_progress)
        print(
            f"{packed.kernels} kernels ({packed.entries} compiled entries, {packed.size_bytes / 2**20:.1f} MiB) "
            f"packed in {packed.folder} in {packed.seconds:.0f} s"
        )
        return
    rows = warmup(args.env_ids or None, workers=args.workers, progress=not args.no_progress)
    width = max(len(row.env_id) for row in rows)
    for row in rows:
        policies = ", ".join(row.policies) or "-"
        print(f"{row.env_id.ljust(width)}  {row.seconds:7.1f} s  (compiling {row.compile_s:5.1f} s)  {policies}")
    print(f"{len(rows)} env id(s) warmed up; numba cache: {numba_cache_location()} (NUMBA_CACHE_DIR moves it)")
    from .kernel_pack import seeding_state

    state = seeding_state()
    print(
        f"kernel pack: {state.pack} (copied into that cache where it lacked them)"
        if state.pack
        else f"kernel pack: none, {state.reason}"
    )


def _baselines(args: argparse.Namespace) -> None:
    from .learning.baselines import BASELINES_DIR, baselines, train_baseline

    chosen = baselines(args.names)
    if args.list:
        print(f"{len(chosen)} baseline(s) in {BASELINES_DIR}:")
        for b in chosen:
            record = b.record()
            trained = "not trained" if record is None else f"{record.env_steps} steps, {record.cpu_s / 60:.1f} CPU-min"
            print(f"{b.name:32s} {b.learner:4s} {b.env_id:45s} {trained}")
        return
    if args.ray is not None:
        from .learning.sweep import train_baselines_on_ray
        from .policies.shipped_models import SHIPPED_MODELS_DIR

        for path in train_baselines_on_ray(
            [b.name for b in chosen], args.models or SHIPPED_MODELS_DIR, ray_address=args.ray, steps=args.steps
        ):
            print(f"wrote {path}")
        return
    for k, b in enumerate(chosen, 1):
        print(f"[{k}/{len(chosen)}] {b.name}: {b.learner} on {b.env_id} ({b.config})", flush=True)
        options = {} if args.models is None else {"models_dir": args.models}
        path = train_baseline(b, steps=args.steps, **options)
        record = b.record() if args.models is None else None
        cost = "" if record is None else f" ({record.env_steps} steps, {record.cpu_s / 60:.1f} CPU-min)"
        print(f"wrote {path}{cost}", flush=True)


def _train_behaviour_cloning(args: argparse.Namespace, config: Any) -> None:
    """``train --algo bc``: the config section's keys are :func:`train_behaviour_cloning`'s options."""
    import inspect

    from .eval.exceptions import EvalError
    from .learning.behaviour_cloning import train_behaviour_cloning

    if args.steps is not None or args.n_envs is not None:
        raise EvalError(
            "--steps and --n-envs do not apply to --algo bc: its budget is the config's episodes, "
            "dagger_rounds and dagger_episodes"
        )
    if args.eval_freq is not None or args.checkpoint_freq is not None or args.keep != "last":
        raise EvalError(
            "--eval-freq, --checkpoint-freq and --keep apply to ppo and sac, not to --algo bc (it "
            "reports its learner's success after every DAgger round)"
        )
    options = dict(config.hyperparameters)
    valid = set(inspect.signature(train_behaviour_cloning).parameters) - {
        "env_id",
        "out",
        "env_kwargs",
        "seed",
        "progress",
        "log",
        "torch_threads",
    }
    unknown = sorted(set(options) - valid)
    if unknown:
        raise EvalError(
            f"unknown behaviour-cloning option(s) {', '.join(unknown)} in {args.config}; valid: "
            f"{', '.join(sorted(valid))}"
        )
    if "net_arch" in options:
        options["net_arch"] = tuple(options["net_arch"])
    if args.expert is not None:
        options["expert"] = args.expert
    if args.dataset is not None:
        options["dataset"] = args.dataset
    out = args.out or f"runs/bc_{args.env_id.split('/')[-1]}.zip"
    source = f"the dataset {args.dataset}" if args.dataset else options.get("expert") or "the reference"
    print(f"behaviour cloning on {args.env_id} from {source}, seed {args.seed}")
    summary = train_behaviour_cloning(
        args.env_id,
        out,
        env_kwargs={**config.env_kwargs, **args.env_kwargs},
        seed=args.seed,
        progress=not args.no_progress,
        torch_threads=args.torch_threads,
        **options,
    )
    print(f"wrote {summary.path}; evaluate it with: redundancy-gym eval {args.env_id} --policy {summary.path}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status."""
    parser = _parser()
    args = parser.parse_args(argv)
    from .envs.exceptions import EnvConfigError
    from .eval.exceptions import EvalError
    from .policies import PolicyError

    if args.command == "bench":
        bench_args = BenchArgs(
            json_path=args.json_path or f"results/bench_{args.name}.json",
            seed=args.seed,
            quick=args.quick,
            progress=not args.no_progress,
            rounds=args.rounds,
            seconds=args.seconds,
            steps=args.steps,
            trials=args.trials,
            episodes=args.episodes,
            workers=args.workers,
            ray=args.ray,
            envs=None if args.envs is None else tuple(args.envs),
        )
        try:  # an option the bench does not take is a usage error, as argparse reports them
            bench_entry = check_bench_args(args.name, bench_args)
        except BenchError as exc:
            parser.error(str(exc))
    try:
        if args.command in ("eval", "train", "render", "collect"):
            _apply_wrapper(args)
        if args.command == "list":
            rows = list_envs()
            print(json.dumps(rows, indent=2) if args.json else f"{format_env_list(rows)}\n\n{format_registry()}")
        elif args.command == "eval":
            from .eval.evaluate import evaluate, format_report

            workers = _workers(args)
            report = evaluate(
                args.env_id,
                args.policy,
                episodes=args.episodes,
                seed=args.seed,
                env_kwargs=args.env_kwargs,
                policy_kwargs=args.policy_kwargs,
                progress=not args.no_progress,
                warmup=args.warmup,
                workers=workers,
                retries=args.retries,
                ray_address=args.ray,
            )
            contract = report.to_json()
            print(format_report(contract))
            if args.json_path:
                print(f"wrote {report.write_json(args.json_path)}")
        elif args.command == "train":
            _train(args)
        elif args.command == "collect":
            _collect(args)
        elif args.command == "baselines":
            _baselines(args)
        elif args.command == "demo":
            from .demo import run_demo

            run_demo(args.out, episodes=args.episodes, seed=args.seed, workers=args.workers)
        elif args.command == "render":
            from .eval.video import record_episode

            path, summary = record_episode(
                args.env_id,
                args.policy,
                args.out,
                seed=args.seed,
                env_kwargs=args.env_kwargs,
                policy_kwargs=args.policy_kwargs,
                progress=not args.no_progress,
            )
            print(f"wrote {path} ({summary.length} steps, success={summary.success})")
        elif args.command == "bench":
            return bench_entry.run(bench_args)
        elif args.command == "warmup":
            _warmup(args)
    except (EvalError, PolicyError, EnvConfigError, ValueError) as exc:
        print(f"redundancy-gym {args.command}: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
