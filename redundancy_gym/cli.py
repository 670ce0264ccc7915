"""The ``redundancy-gym`` command: ``eval``, ``train``, ``demo``, ``render``, ``bench``."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from typing import Any

__all__ = ["main"]


def _json_object(text: str) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise argparse.ArgumentTypeError(f"not valid JSON: {exc}") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError("must be a JSON object, e.g. '{\"obstacle\": false}'")
    return value


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="redundancy-gym", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    ev = sub.add_parser("eval", help="evaluate a policy; prints a table and writes the evaluation-contract JSON")
    ev.add_argument("env_id", help="e.g. redundancy_gym/PlanarReach-v0")
    ev.add_argument("--policy", required=True,
                    help="clik | walking | predictive | global | zero | random | path to an SB3 .zip")
    ev.add_argument("--episodes", type=int, default=10)
    ev.add_argument("--seed", type=int, default=0)
    ev.add_argument("--env-kwargs", type=_json_object, default={}, help="JSON object passed to gym.make")
    ev.add_argument("--policy-kwargs", type=_json_object, default={}, help="JSON object of policy options")
    ev.add_argument("--json", dest="json_path", help="write the report here")
    ev.add_argument("--no-progress", action="store_true")

    tr = sub.add_parser("train", help="train a stable-baselines3 agent and save a .zip that eval loads")
    tr.add_argument("env_id")
    tr.add_argument("--algo", choices=("ppo", "sac"), default="ppo")
    tr.add_argument("--steps", type=int, required=True)
    tr.add_argument("--out", required=True, help="output .zip path")
    tr.add_argument("--seed", type=int, default=0)
    tr.add_argument("--env-kwargs", type=_json_object, default={})
    tr.add_argument("--config", help="YAML of SB3 keyword arguments (see configs/)")
    tr.add_argument("--no-progress", action="store_true")

    de = sub.add_parser("demo", help="reference controllers on every env: JSON, plots, video into a folder")
    de.add_argument("--out", default="results")
    de.add_argument("--episodes", type=int, default=20)
    de.add_argument("--seed", type=int, default=0)

    re = sub.add_parser("render", help="record one episode as .mp4 or .gif")
    re.add_argument("env_id")
    re.add_argument("--policy", required=True)
    re.add_argument("--out", required=True)
    re.add_argument("--seed", type=int, default=0)
    re.add_argument("--env-kwargs", type=_json_object, default={})
    be = sub.add_parser("bench", help="run a benchmark against its peers and write its figures")
    be.add_argument("name", choices=("ssv", "envs", "ik", "walk", "pik"),
                    help="ssv: swept-sphere distances against coal; envs: steps/s against Gymnasium's Pusher/Humanoid; "
                         "ik: the AgriReach CLIK control step against mink's solve_ik (needs the 'bench' extra); "
                         "walk: the BipedWalk controller step, and its compiled whole-body IK against pinocchio's; "
                         "pik: predictive IK against local CLIK and the global optimum")
    be.add_argument("--json", dest="json_path", help="default: results/bench_<name>.json")
    be.add_argument("--seed", type=int, default=0)
    be.add_argument("--quick", action="store_true", help="short timings (a smoke run, not for quoting)")
    be.add_argument("--no-progress", action="store_true")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status."""
    args = _parser().parse_args(argv)
    os.environ.setdefault("MUJOCO_GL", "osmesa")
    from .controllers.exceptions import PolicyError
    from .envs.exceptions import EnvConfigError
    from .eval.exceptions import EvalError

    try:
        if args.command == "eval":
            from .eval.evaluate import evaluate, format_report

            report = evaluate(args.env_id, args.policy, episodes=args.episodes, seed=args.seed,
                              env_kwargs=args.env_kwargs, policy_kwargs=args.policy_kwargs,
                              progress=not args.no_progress)
            contract = report.to_json()
            print(format_report(contract))
            if args.json_path:
                print(f"wrote {report.write_json(args.json_path)}")
        elif args.command == "train":
            from .eval.training import load_hyperparameters, train

            hyper = load_hyperparameters(args.config) if args.config else None
            path = train(args.env_id, args.algo, args.steps, args.out, seed=args.seed, env_kwargs=args.env_kwargs,
                         hyperparameters=hyper, progress_bar=not args.no_progress)
            print(f"wrote {path}")
        elif args.command == "demo":
            from .eval.demo import run_demo

            run_demo(args.out, episodes=args.episodes, seed=args.seed)
        elif args.command == "render":
            from .eval.video import record_episode

            path, summary = record_episode(args.env_id, args.policy, args.out, seed=args.seed,
                                           env_kwargs=args.env_kwargs)
            print(f"wrote {path} ({summary.length} steps, success={summary.success})")
        elif args.command == "bench":
            json_path = args.json_path or f"results/bench_{args.name}.json"
            if args.name == "ssv":
                from .eval.bench_ssv import format_ssv_bench, run_ssv_bench, write_ssv_bench

                timing = {"min_time": 0.002, "repeats": 2} if args.quick else {}
                report = run_ssv_bench(seed=args.seed, progress=not args.no_progress, **timing)
                print(format_ssv_bench(report))
                print(f"wrote {write_ssv_bench(report, json_path)}")
            elif args.name == "ik":
                from .eval.bench_ik import format_ik_bench, run_ik_bench, write_ik_bench

                kwargs = {"repeats": 1, "scaling": (10, 100)} if args.quick else {}
                report = run_ik_bench(seed=args.seed, progress=not args.no_progress, **kwargs)
                print(format_ik_bench(report))
                print(f"wrote {write_ik_bench(report, json_path)}")
            elif args.name == "pik":
                from .eval.bench_pik import format_pik_bench, run_pik_bench
                from .eval.bench_ssv import write_ssv_bench as write_pik_bench

                report = run_pik_bench(seed=args.seed, episodes=2 if args.quick else 10, quick=args.quick,
                                       progress=not args.no_progress)
                print(format_pik_bench(report))
                print(f"wrote {write_pik_bench(report, json_path)}")
            elif args.name == "walk":
                from .eval.bench_ssv import write_ssv_bench as write_walk_bench
                from .eval.bench_walk import format_walk_bench, run_walk_bench

                kwargs = {"duration": 1.0, "repeats": 1} if args.quick else {}
                report = run_walk_bench(seed=args.seed, progress=not args.no_progress, **kwargs)
                print(format_walk_bench(report))
                print(f"wrote {write_walk_bench(report, json_path)}")
            else:
                from .eval.bench_envs import format_envs_bench, run_envs_bench, write_envs_bench

                report = run_envs_bench(seconds=0.3 if args.quick else 3.0, seed=args.seed,
                                        progress=not args.no_progress)
                print(format_envs_bench(report))
                print(f"wrote {write_envs_bench(report, json_path)}")
    except (EvalError, PolicyError, EnvConfigError, ValueError) as exc:
        print(f"redundancy-gym {args.command}: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
