"""The main job of ``make demo``: reference controllers on every env, eval JSON, plots and a video."""

from __future__ import annotations

from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from .eval.evaluate import evaluate, format_report
from .eval.json_writer import write_json
from .eval.plots import plot_clearance, plot_traces
from .eval.speed_error import plot_speed_error, speed_error_markdown
from .eval.video import record_episode
from .studies.obstacle_plots import plot_footholds_top_view, plot_swing_trajectories, record_obstacle_walk
from .studies.point_to_point import FIG_5_10, plot_point_to_point, rollout_point_to_point
from .studies.terrain_plots import plot_terrain_walk, record_terrain_walk
from .studies.walking_plots import plot_angular_momentum, plot_com_zmp, record_walk

__all__ = ["run_demo"]

_PLANAR = "redundancy_gym/PlanarReach-v0"
_AGRI = "redundancy_gym/AgriReach-v0"
_BIPED = "redundancy_gym/BipedWalk-v0"
_OBSTACLES = "redundancy_gym/BipedObstacles-v0"
_TERRAIN = "redundancy_gym/BipedTerrain-v0"
# time limit of the demo's BipedObstacles episodes [control steps of 4 ms]: 10 s, where the beam and the triangle
# course take 6.2 s (0.4 s start, course_end 2.32 m at 0.4 m/s); an episode with an obstacle contact does not end at
# the course's end but at the time limit, which the registration sets for the longest random course (45 s)
_OBSTACLE_DEMO_STEPS = 2500
# frame rate of the BipedObstacles videos [1/s]: every 10th control step; software rendering (osmesa) takes about
# 55 ms a frame here, so 50 fps would double the step's time
_OBSTACLE_VIDEO_FPS = 25.0


def run_demo(
    out_dir: str | Path = "results", *, episodes: int = 20, seed: int = 0, progress: bool = True, workers: int = 1
) -> list[Path]:
    """Evaluate the ``clik`` reference on PlanarReach (with and without obstacle) and AgriReach (medium and hard
    crops), the ``walking`` reference on BipedWalk and on BipedObstacles (beam and triangle), the shipped learned
    baselines against every analytic reference (appended to the speed-vs-error report), the references under
    dynamics randomization (a short ``bench robustness``) and the kinematic IKD study; write JSON, PNG and MP4, and a
    small Minari dataset of each reference per env (``datasets/``, listed with its size in ``datasets.json``).

    ``workers``: processes each evaluation's episodes are split across (the same numbers, timings excepted; with
    both cores busy the step times are those of a loaded machine).

    Returns the paths written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    traces = {}
    for obstacle in (False, True):
        tag = "obstacle" if obstacle else "free"
        report = evaluate(
            _PLANAR,
            "clik",
            episodes=episodes,
            seed=seed,
            env_kwargs={"obstacle": obstacle},
            keep_traces=True,
            progress=progress,
            workers=workers,
        )
        contract = report.to_json()
        written.append(report.write_json(out / f"planar_reach_clik_{tag}.json"))
        print(f"\n== PlanarReach-v0, clik, obstacle={obstacle}\n{format_report(contract)}")
        traces[f"clik, obstacle={obstacle} (seed {seed})"] = report.traces[0]
    written.append(
        plot_traces(
            traces,
            out / "planar_reach_clik.png",
            title="PlanarReach-v0: velocity-level CLIK (DLS) with joint-limit objective",
        )
    )
    written.append(_clearance(out, episodes=min(episodes, 5), seed=seed, progress=progress, workers=workers))
    for obstacle in (False, True):
        tag = "obstacle" if obstacle else "free"
        path, _ = record_episode(
            _PLANAR,
            "clik",
            out / f"planar_reach_clik_{tag}.mp4",
            seed=seed,
            env_kwargs={"obstacle": obstacle},
            progress=progress,
        )
        written.append(path)
    written.extend(_speed_error(out, episodes=min(episodes, 5), seed=seed, progress=progress, workers=workers))
    written.extend(_learned(out, episodes=min(episodes, 5), progress=progress, workers=workers))
    written.extend(_robustness(out, episodes=min(episodes, 2), progress=progress, workers=workers))
    written.extend(_agri(out, episodes=episodes, seed=seed, progress=progress, workers=workers))
    written.extend(_biped(out, episodes=min(episodes, 10), seed=seed, progress=progress, workers=workers))
    written.extend(_biped_obstacles(out, episodes=min(episodes, 5), seed=seed, progress=progress, workers=workers))
    written.extend(_biped_terrain(out, seed=seed, progress=progress))
    written.extend(_predictive(out, seed=seed))
    written.extend(_ikd_study(out, progress=progress))
    written.append(_datasets(out, seed=seed, progress=progress))
    for path in written:
        print(f"wrote {path}")
    return written


def _agri(out: Path, *, episodes: int, seed: int, progress: bool, workers: int = 1) -> list[Path]:
    """The grasp-approach CLIK reference on AgriReach, medium and hard crops: JSON and one video; the fig. 5.10
    self-collision plot."""
    written = []
    for difficulty in ("medium", "hard"):
        report = evaluate(
            _AGRI,
            "clik",
            episodes=episodes,
            seed=seed,
            env_kwargs={"difficulty": difficulty},
            progress=progress,
            workers=workers,
        )
        written.append(report.write_json(out / f"agri_reach_clik_{difficulty}.json"))
        print(f"\n== AgriReach-v0, clik, difficulty={difficulty}\n{format_report(report.to_json())}")
    path, _ = record_episode(
        _AGRI,
        "clik",
        out / "agri_reach_clik_medium.mp4",
        seed=seed,
        env_kwargs={"difficulty": "medium"},
        progress=progress,
    )
    written.append(path)
    traces = {
        label: rollout_point_to_point(FIG_5_10, collision_avoidance=on)
        for label, on in (("without collision avoidance", False), ("with nullspace collision avoidance", True))
    }
    written.append(
        plot_point_to_point(
            traces,
            out / "agri_self_collision_fig_5_10.png",
            "9-DoF arm, point-to-point move (fig. 5.10 analogue), kinematic CLIK",
        )
    )
    return written


def _biped(out: Path, *, episodes: int, seed: int, progress: bool, workers: int = 1) -> list[Path]:
    """The walking reference on BipedWalk at 0.5 and 0.7 m/s: JSON, CoM/ZMP plot, L_z with and without (5.62),
    one video."""
    written = []
    for speed in (0.5, 0.7):
        report = evaluate(
            _BIPED,
            "walking",
            episodes=episodes,
            seed=seed,
            env_kwargs={"target_speed": speed},
            progress=progress,
            workers=workers,
        )
        written.append(report.write_json(out / f"biped_walk_walking_{speed:.1f}.json"))
        print(f"\n== BipedWalk-v0, walking, target_speed={speed}\n{format_report(report.to_json())}")
    trace = record_walk(0.7, 6.0, seed)
    written.append(
        plot_com_zmp(
            trace, out / "biped_walk_com_zmp.png", "BipedWalk-v0 at 0.7 m/s: CoM and ZMP, planned and measured"
        )
    )
    written.append(
        plot_com_zmp(
            record_walk(0.7, 6.0, seed, ik="ikd"),
            out / "biped_walk_com_zmp_ikd.png",
            "BipedWalk-v0 at 0.7 m/s, IKD walker: CoM and ZMP, planned and measured",
        )
    )
    walks = {}
    for on in (False, True):
        walk = trace if on else record_walk(0.7, 6.0, seed, momentum_minimization=False)
        peak = float(np.max(np.abs(walk.lz[walk.time > 1.0])))
        label = "W = gamma I + J_Lz^T J_Lz (5.62)" if on else "W = I (no minimization)"
        walks[f"{label}: peak |L_z| {peak:.2f} kg m^2/s"] = walk
    written.append(
        plot_angular_momentum(
            walks, out / "biped_walk_lz_fig_5_11.png", "Vertical angular momentum, 0.7 m/s, MuJoCo (fig. 5.11 analogue)"
        )
    )
    path, _ = record_episode(
        _BIPED,
        "walking",
        out / "biped_walk_walking.mp4",
        seed=seed,
        env_kwargs={"target_speed": 0.7},
        progress=progress,
    )
    written.append(path)
    return written


def _biped_obstacles(out: Path, *, episodes: int, seed: int, progress: bool, workers: int = 1) -> list[Path]:
    """The walking reference (SSTA and RCA) on BipedObstacles, the monograph's beam and triangle courses: per course
    an eval JSON, the swing-foot figure (figs. 5.16 / 5.19 analogue), the footholds' top view (fig. 5.17 analogue)
    and one video at 25 fps; every episode is limited to 10 s (:data:`_OBSTACLE_DEMO_STEPS`). About 36 s on 2
    cores (one busy), two thirds of it rendering."""
    written = []
    for course in ("beam", "triangle"):
        env_kwargs = {"course": course, "max_episode_steps": _OBSTACLE_DEMO_STEPS}
        report = evaluate(
            _OBSTACLES,
            "walking",
            episodes=episodes,
            seed=seed,
            env_kwargs=env_kwargs,
            progress=progress,
            workers=workers,
        )
        written.append(report.write_json(out / f"biped_obstacles_walking_{course}.json"))
        print(f"\n== BipedObstacles-v0, walking, course={course}\n{format_report(report.to_json())}")
        trace = record_obstacle_walk(course, seed)
        what = "stepping over the 16.1 cm beam" if course == "beam" else "swinging around the 30 cm triangular prism"
        written.append(
            plot_swing_trajectories(
                trace,
                out / f"biped_obstacles_{course}_swing.png",
                f"BipedObstacles-v0, {course} course (seed {seed}): swing feet {what}, nominal vs SSTA vs RCA "
                "(figs. 5.16 / 5.19 analogue)",
            )
        )
        written.append(
            plot_footholds_top_view(
                trace,
                out / f"biped_obstacles_{course}_top.png",
                f"BipedObstacles-v0, {course} course (seed {seed}): footholds and swing paths from above "
                "(fig. 5.17 analogue)",
            )
        )
        path, _ = record_episode(
            _OBSTACLES,
            "walking",
            out / f"biped_obstacles_{course}.mp4",
            seed=seed,
            env_kwargs=env_kwargs,
            max_fps=_OBSTACLE_VIDEO_FPS,
            progress=progress,
        )
        written.append(path)
    return written


DEMO_TERRAINS: dict[str, dict[str, Any]] = {
    "stairs": {
        "segments": [{"kind": "stairs", "steps": 4, "rise": 0.12, "tread": 0.3, "landing": 0.8}],
        "first_segment_distance": 1.0,
    },
    "stepping_stones": {"terrain": "stepping_stones"},
}
"""The terrains of ``make demo``'s BipedTerrain figures: four 12 cm steps up and down, and a seeded stepping-stone
field."""


def _biped_terrain(out: Path, *, seed: int, progress: bool) -> list[Path]:
    """The walking reference on BipedTerrain: a side view of a staircase and of stepping stones (terrain, planned
    and measured feet and CoM, ZMP over time), and a video of the stairs at 25 fps. About 40 s."""
    written = []
    for name, env_kwargs in DEMO_TERRAINS.items():
        trace = record_terrain_walk(env_kwargs, seed)
        written.append(
            plot_terrain_walk(
                trace,
                out / f"biped_terrain_{name}.png",
                f"BipedTerrain-v0, {name.replace('_', ' ')} (seed {seed}): the walking reference from the side",
            )
        )
    path, _ = record_episode(
        _TERRAIN,
        "walking",
        out / "biped_terrain_stairs.mp4",
        seed=seed,
        env_kwargs=DEMO_TERRAINS["stairs"],
        max_fps=_OBSTACLE_VIDEO_FPS,
        progress=progress,
    )
    written.append(path)
    return written


DEMO_DATASETS: dict[str, tuple[str, dict[str, Any], int]] = {
    "redundancy_gym/PlanarReach-v0": ("clik", {}, 2),
    "redundancy_gym/AgriReach-v0": ("clik", {"difficulty": "medium"}, 2),
    "redundancy_gym/BipedWalk-v0": ("walking", {}, 1),
    "redundancy_gym/BipedObstacles-v0": ("walking", {}, 1),
    "redundancy_gym/BipedTerrain-v0": ("walking", {"terrain": "platform"}, 1),
}
"""``make demo``'s datasets: env id -> (reference policy, env kwargs, episodes)."""


def _datasets(out: Path, *, seed: int, progress: bool) -> Path:
    """A small Minari dataset of the reference on every env (``redundancy-gym collect``), into ``out/datasets``;
    ``datasets.json`` lists each with its episodes, steps, success rate and size. About a minute."""
    from .datasets import DatasetError, collect_dataset

    rows = []
    for env_id, (policy, env_kwargs, episodes) in DEMO_DATASETS.items():
        try:
            summary = collect_dataset(
                env_id,
                out / "datasets",
                policy=policy,
                env_kwargs=env_kwargs,
                episodes=episodes,
                seed=seed,
                overwrite=True,
                progress=progress,
            )
        except DatasetError as exc:  # Minari missing: the rest of the demo stands
            print(f"datasets skipped: {exc}")
            break
        print(summary.format())
        rows.append(
            {
                "env_id": env_id,
                "env_kwargs": env_kwargs,
                "dataset_id": summary.dataset_id,
                "path": str(summary.path),
                "episodes": summary.episodes,
                "steps": summary.steps,
                "success_rate": summary.success_rate,
                "size_bytes": summary.size_bytes,
            }
        )
    return write_json({"datasets": rows}, out / "datasets.json")


def _predictive(out: Path, *, seed: int) -> list[Path]:
    """Predictive IK against local CLIK and the global optimum, in kinematic rollouts: the fig. 5.31 analogue
    (PlanarReach obstacle scene, 1 s horizon), the fig. 5.35 analogue (the fig. 5.10 self-collision move of the
    9-DoF arm, 0.15 s and 2 s horizons) and the figs. 5.33/5.34 analogue (the second joint's velocity with and
    without the augmented state at a 0.2 s prediction sample)."""
    from .studies.predictive_figures import (  # noqa: PLC0415
        JUMP_SAMPLE_TIME,
        agri_self_collision_traces,
        planar_kinematic_traces,
        plot_joint_velocity,
        plot_pseudoenergy,
    )

    written = [
        plot_pseudoenergy(
            planar_kinematic_traces(seed=seed),
            out / "planar_reach_pseudoenergy_fig_5_31.png",
            "PlanarReach, obstacle: local CLIK vs predictive IK (1 s) vs global (fig. 5.31 analogue)",
        )
    ]
    written.append(
        plot_pseudoenergy(
            agri_self_collision_traces(),
            out / "agri_self_collision_pseudoenergy_fig_5_35.png",
            "9-DoF arm, fig. 5.10 self-collision move: revolute joints (fig. 5.35 analogue)",
            joints=slice(1, None),
        )
    )
    jumps = planar_kinematic_traces(seed=seed, sample_time=JUMP_SAMPLE_TIME, local=False)
    written.append(
        plot_joint_velocity(
            jumps,
            1,
            out / "planar_reach_velocity_jumps_fig_5_33.png",
            f"PlanarReach, MPC 1 s with {JUMP_SAMPLE_TIME:g} s samples: joint 2 (figs. 5.33/5.34 analogue)",
        )
    )
    return written


def _ikd_study(out: Path, *, progress: bool) -> list[Path]:
    """The kinematic IKD study (monograph 5.5.3): JSON and the figs. 5.21, 5.23, 5.24 and 5.27 analogues, on the plain
    LIPM plan and on the walking controller's plan with its multi-body ZMP correction (about 20 s)."""
    from .studies.ikd_study import (  # noqa: PLC0415
        IkdStudyConfig,
        format_ikd_study,
        plot_ikd_study,
        run_ikd_study,
        write_ikd_study,
    )

    written: list[Path] = []
    for correction, suffix in ((False, ""), (True, "_corrected")):
        config = IkdStudyConfig(correction=correction)
        print(
            f"\n== IKD study ({config.plan_name}): 6 steps at 0.5 m/s, 1 ms, IKD k sweep, CLIK, error compensation",
            flush=True,
        )
        study = run_ikd_study(config, progress=progress)
        print(format_ikd_study(study.to_json()))
        written += [write_ikd_study(study, out / f"ikd_study{suffix}.json"), *plot_ikd_study(study, out, suffix)]
    return written


def _clearance(out: Path, *, episodes: int, seed: int, progress: bool, workers: int = 1) -> Path:
    """Clearance to the obstacle over time, CLIK with and without the nullspace collision objective."""
    traces = {}
    for mode, label in (("off", "clik without collision objective"), ("auto", "clik with collision objective")):
        report = evaluate(
            _PLANAR,
            "clik",
            episodes=episodes,
            seed=seed,
            policy_kwargs={"collision_avoidance": mode},
            keep_traces=True,
            progress=progress,
            workers=workers,
        )
        c = report.to_json()
        traces[f"{label}: collisions {c['collision_rate']:.0%}, min {1e3 * c['min_clearance']:.1f} mm"] = report.traces[
            0
        ]
    return plot_clearance(
        traces,
        out / "planar_reach_clearance.png",
        f"PlanarReach-v0 with obstacle (seed {seed}; an episode ends at contact)",
    )


def _learned(out: Path, *, episodes: int, progress: bool, workers: int = 1) -> list[Path]:
    """The learned baselines against the analytic references, per env, on the first ``episodes`` held-out seeds of
    ``bench learned`` (seeds 20000 onwards, never trained on): a section appended to ``speed_vs_error.md`` and a
    time-vs-error plot per env (``speed_vs_error_learned_<env>.png``, learned policies with their own markers)."""
    from .bench.learned import HELD_OUT_SEED, learned_markdown, plot_learned_bench, run_learned_bench  # noqa: PLC0415

    table = run_learned_bench(episodes=episodes, seed=HELD_OUT_SEED, progress=progress, workers=workers)
    command = f"redundancy-gym bench learned --episodes {episodes}"
    text = "\n## Learned baselines against the analytic references\n\n" + learned_markdown(table, command=command)
    markdown = out / "speed_vs_error.md"
    with markdown.open("a") as handle:
        handle.write(text)
    print(text)
    path = write_json(table, out / "learned.json")
    return [path, *plot_learned_bench(table, out, prefix="speed_vs_error_learned_")]


DEMO_ROBUSTNESS = ("nominal", "level 0.1", "latency 1", "dynamics=0.1")
"""The plants of ``make demo``'s short robustness run (``bench robustness`` runs every one of its ``CONDITIONS``)."""


def _robustness(out: Path, *, episodes: int, progress: bool, workers: int = 1) -> list[Path]:
    """The references under dynamics randomization (``bench robustness``, a short run: :data:`DEMO_ROBUSTNESS`, the
    first ``episodes`` of its held-out seeds): ``robustness.md``, ``robustness.json`` and one figure per env
    (``robustness_<env>.png``)."""
    from .bench.robustness import (  # noqa: PLC0415
        CONDITIONS,
        plot_robustness_bench,
        robustness_markdown,
        run_robustness_bench,
    )

    conditions = [c for c in CONDITIONS if c.label in DEMO_ROBUSTNESS]
    table = run_robustness_bench(episodes=episodes, conditions=conditions, progress=progress, workers=workers)
    text = robustness_markdown(table, command=f"redundancy-gym bench robustness --episodes {episodes}")
    print(text)
    markdown = out / "robustness.md"
    title = "# The references on plants that differ from their model (a short run)"
    markdown.write_text(f"{title}\n\nThe plants of this short run: {', '.join(DEMO_ROBUSTNESS)}.\n\n{text}")
    return [write_json(table, out / "robustness.json"), markdown, *plot_robustness_bench(table, out)]


def _speed_error(out: Path, *, episodes: int, seed: int, progress: bool, workers: int = 1) -> list[Path]:
    """Time against error, one markdown section and plot per setting: every PlanarReach reference variant and the
    trivial policies (obstacle off; tracking error max), local against predictive and global IK on PlanarReach
    with its obstacle and on AgriReach (pseudoenergy; tracking and goal error in the tables), and the walking
    reference's variants on BipedWalk, the IKD walker among them (speed error). Each controller runs one untimed
    warm-up episode first."""
    from .eval.speed_error import plot_speed_error_panels  # noqa: PLC0415

    def run(env_id: str, variants: dict, env_kwargs: dict, n: int) -> dict:
        measure = partial(
            evaluate, env_id, seed=seed, env_kwargs=env_kwargs, progress=progress, warmup=1, workers=workers
        )
        return {
            label: measure(policy, episodes=n, policy_kwargs=kwargs).to_json()
            for label, (policy, kwargs) in variants.items()
        }

    free = run(
        _PLANAR,
        {
            "clik (dls)": ("clik", {"method": "dls"}),
            "clik (pseudoinverse)": ("clik", {"method": "pseudoinverse"}),
            "clik (transpose)": ("clik", {"method": "transpose"}),
            "clik (dls, no joint-limit objective)": ("clik", {"method": "dls", "joint_limit_weight": 0.0}),
            "zero": ("zero", {}),
            "random": ("random", {}),
        },
        {"obstacle": False},
        episodes,
    )
    obstacle = run(
        _PLANAR,
        {
            "clik (local)": ("clik", {}),
            "predictive (1 s, augmented)": ("predictive", {"horizon": 1.0}),
            "predictive (1 s, velocity level)": ("predictive", {"horizon": 1.0, "augmented": False}),
            "global (one solve at the episode start)": ("global", {}),
        },
        {"obstacle": True},
        episodes,
    )
    agri = run(
        _AGRI,
        {
            "clik (local)": ("clik", {}),
            "predictive (0.15 s)": ("predictive", {"horizon": 0.15}),
            "predictive (2 s)": ("predictive", {"horizon": 2.0}),
            "global (one solve at the episode start)": ("global", {}),
        },
        {"difficulty": "medium"},
        episodes,
    )
    walking = {
        "walking (compiled IK)": ("walking", {}),
        "walking (pinocchio IK, backend python)": ("walking", {"backend": "python"}),
        "walking, W = I (no L_z minimization)": ("walking", {"momentum_minimization": False}),
        "walking, no self-collision objective": ("walking", {"self_collision_weight": 0.0}),
        "walking, IKD (hybrid stabilization)": ("walking", {"ik": "ikd"}),
    }
    biped = run(_BIPED, walking, {"target_speed": 0.7}, 2)  # 10 s walks that barely vary with the seed
    sections = [
        speed_error_markdown(
            free,
            "PlanarReach-v0 without obstacle: CLIK variants and trivial policies",
            columns=("tracking_rms", "tracking_max"),
            rank=("tracking_max",),
        ),
        speed_error_markdown(
            obstacle,
            "PlanarReach-v0 with obstacle: local vs predictive vs global IK",
            columns=("tracking_rms", "tracking_max"),
            rank=("pseudoenergy", "tracking_max"),
        ),
        speed_error_markdown(
            agri,
            "AgriReach-v0 (medium): local vs predictive vs global IK",
            columns=("tracking_rms", "tracking_max", "goal", "time_to_goal"),
            rank=("pseudoenergy", "tracking_rms", "goal"),
        ),
        speed_error_markdown(
            biped,
            "BipedWalk-v0 at 0.7 m/s: walking reference variants",
            columns=("speed", "speed_rms"),
            rank=("speed", "pseudoenergy"),
        ),
    ]
    intro = (
        "Times are each policy's own compute time per step on this machine (the simulator excluded), after "
        "one untimed warm-up episode per controller, so one-time JIT compilation and set-up are not counted. "
        "The amortized step time is the mean over all steps and includes a plan-once controller's solve at "
        "every episode's first step, which the last column shows alone; times vary with the machine's load, "
        "so amortized times within 20 % count as a tie, errors within 5 % (or the stated absolute amount). "
        "A policy with success rate 0 is marked failed and left out of the fastest / most accurate "
        "sentences. Plots: amortized time per step against the section's first error "
        "(`speed_vs_error*.png`).\n\n"
    )
    text = "\n".join(sections)
    markdown = out / "speed_vs_error.md"
    markdown.parent.mkdir(parents=True, exist_ok=True)
    markdown.write_text("# Speed vs error\n\n" + intro + text)
    print("\n" + text)
    return [
        markdown,
        plot_speed_error(
            free,
            out / "speed_vs_error.png",
            "PlanarReach-v0 without obstacle: time vs tracking error",
            error="tracking_max",
        ),
        plot_speed_error_panels(
            [
                (obstacle, "PlanarReach-v0 with obstacle", "pseudoenergy"),
                (agri, "AgriReach-v0 (medium)", "pseudoenergy"),
            ],
            out / "speed_vs_error_predictive.png",
            "Local vs predictive vs global IK: time vs pseudoenergy",
        ),
        plot_speed_error(
            agri,
            out / "speed_vs_error_agri_tracking.png",
            "AgriReach-v0 (medium): time vs tracking error",
            error="tracking_rms",
        ),
        plot_speed_error(
            biped, out / "speed_vs_error_biped.png", "BipedWalk-v0 at 0.7 m/s: time vs speed error", error="speed"
        ),
    ]
