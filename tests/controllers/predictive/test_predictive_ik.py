"""Predictive IK (monograph 5.6): exact adjoint gradients against finite differences of the total cost, the
task held along the rollout, conjugate gradient against steepest descent, bad inputs."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from redundancy_gym.assets import AGRI_ARM_TCP, AGRI_ARM_XML, BIPED_XML, PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.controllers import (
    CollisionObjective,
    ControllerError,
    FrameAxisTask,
    FramePositionTask,
    JointLimitObjective,
    PredictiveIk,
)
from redundancy_gym.geometry import PSS, Segment
from redundancy_gym.model import RobotModel, collision_model_from_mjcf

DT = 0.01


def _planar(**kwargs: Any) -> tuple[PredictiveIk, np.ndarray, np.ndarray]:
    """The arm of fig. 5.30 with the default PlanarReach obstacle; the TCP moves down the line at 0.45 m/s."""
    model = RobotModel.from_mjcf(PLANAR_ARM_XML)
    obstacle = [Segment("obstacle", (PSS(np.array([0.7, 0.0, -0.12]), 0.1),))]
    collision = CollisionObjective(collision_model_from_mjcf(model, obstacle), activation_distance=0.15, slope=5.0)
    limits = JointLimitObjective.from_model(model, activation_distance=0.35, weight=0.6)
    pik = PredictiveIk(
        model, FramePositionTask(PLANAR_ARM_TCP, "xz"), joint_limits=limits, collision=collision, **kwargs
    )
    wdot = np.zeros((200, 6))
    wdot[:, 1] = -0.45 * np.sin(np.linspace(0.0, np.pi, 200)) ** 2  # a rest-to-rest move of 0.45 m
    return pik, np.array([-1.3, 1.0, 0.9, 0.5]), wdot


def _finite_difference_error(
    pik: PredictiveIk,
    q0: np.ndarray,
    params: np.ndarray,
    wdot: np.ndarray,
    u_b: np.ndarray | None,
    rng: np.random.Generator,
) -> tuple[float, float]:
    roll, gradient = pik.gradient(q0, params, wdot, DT, u_b)
    eps, worst = 1e-6, 0.0
    for _ in range(25):
        k, i = int(rng.integers(params.shape[0])), int(rng.integers(params.shape[1]))
        step = np.zeros_like(params)
        step[k, i] = eps
        cost = [pik.rollout(q0, params + s * step, wdot, DT, u_b).cost for s in (1.0, -1.0)]
        worst = max(worst, abs((cost[0] - cost[1]) / (2 * eps) - gradient[k, i]))
    return worst, float(np.max(np.abs(gradient)))


@pytest.mark.parametrize("augmented", [False, True], ids=("velocity_level", "augmented"))
def test_planar_gradient_matches_finite_differences(augmented: bool) -> None:
    pik, q0, wdot = _planar(augmented=augmented, input_weight=0.01)
    rng = np.random.default_rng(0)
    params = rng.normal(size=(100, 4)) * 0.5
    roll = pik.rollout(q0, params, wdot[:100], DT, rng.normal(size=4))
    assert roll.terms["collision"] > 0.0  # the obstacle term is active along this rollout
    error, scale = _finite_difference_error(pik, q0, params, wdot[:100], rng.normal(size=4) if augmented else None, rng)
    assert error < 1e-7 * max(scale, 1.0)


def test_agri_axis_task_gradient_matches_finite_differences() -> None:
    """The 5-D tool-axis task (its rows turn with the tool), self-collision and joint limits, prismatic lift."""
    model = RobotModel.from_mjcf(AGRI_ARM_XML)
    collision = CollisionObjective(collision_model_from_mjcf(model), activation_distance=0.1, slope=5.0)
    limits = JointLimitObjective.from_model(model, activation_distance=0.3, weight=0.6)
    pik = PredictiveIk(model, FrameAxisTask(AGRI_ARM_TCP, 0), joint_limits=limits, collision=collision)
    rng = np.random.default_rng(0)
    q0 = rng.uniform(model.lower_limits, model.upper_limits) * 0.5
    wdot = rng.normal(size=(60, 6)) * 0.2
    params = rng.normal(size=(60, model.nv)) * 0.3
    roll = pik.rollout(q0, params, wdot, DT)
    assert roll.terms["collision"] > 0.0 and roll.terms["joint_limits"] > 0.0
    error, scale = _finite_difference_error(pik, q0, params, wdot, None, rng)
    assert error < 1e-7 * max(scale, 1.0)


def test_rollout_follows_the_task_velocity_and_the_input_only_moves_the_nullspace() -> None:
    pik, q0, wdot = _planar(damping=0.0)
    rng = np.random.default_rng(1)
    model = pik.model
    task = pik.task
    for params in (np.zeros((50, 4)), rng.normal(size=(50, 4))):
        roll = pik.rollout(q0, params, wdot[:50], DT)
        for k in (0, 17, 49):
            model.update(roll.q[k])
            np.testing.assert_allclose(task.jacobian(model) @ roll.qdot[k], wdot[k, :2], atol=1e-12)
    # the same TCP path for any input: only the redundant motion changes
    a = pik.rollout(q0, np.zeros((50, 4)), wdot[:50], DT).q[-1]
    b = pik.rollout(q0, rng.normal(size=(50, 4)), wdot[:50], DT).q[-1]
    model.update(a)
    tcp_a = task.value(model)
    model.update(b)
    assert np.max(np.abs(task.value(model) - tcp_a)) < 2e-3  # Euler drift of the two paths only
    assert np.max(np.abs(a - b)) > 0.05


def test_conjugate_gradient_reaches_a_tight_tolerance_in_fewer_iterations_than_steepest_descent() -> None:
    """Fig. 5.32: from the minimum-norm solution (u = 0), iterations to come within 1e-4 of the cost decrease
    both can reach."""
    pik, q0, wdot = _planar()
    costs = {}
    for method in ("fletcher_reeves", "steepest_descent"):
        result = pik.optimize(q0, wdot, DT, np.zeros((200, 4)), max_iterations=80, tolerance=0.0, method=method)
        assert all(b <= a for a, b in zip(result.costs, result.costs[1:], strict=False))  # every step lowers the cost
        costs[method] = np.array(result.costs)
    best = min(c.min() for c in costs.values())
    start = costs["fletcher_reeves"][0]
    assert start > best

    def reach(c: np.ndarray) -> int:
        hit = np.flatnonzero((c - best) <= 1e-4 * (start - best))
        return int(hit[0]) if hit.size else len(c)

    assert reach(costs["fletcher_reeves"]) < reach(costs["steepest_descent"])


def test_optimize_stops_by_the_printed_rules() -> None:
    pik, q0, wdot = _planar()
    result = pik.optimize(q0, wdot[:80], DT, np.zeros((80, 4)), max_iterations=3, tolerance=0.0)
    assert result.status == "max_iterations" and result.iterations == 3
    result = pik.optimize(q0, wdot[:80], DT, np.zeros((80, 4)), max_iterations=200, tolerance=1e-3)
    assert result.status == "converged" and result.iterations < 200
    assert result.costs[-1] < result.costs[0]


def test_predictive_ik_rejects_bad_inputs() -> None:
    pik, q0, wdot = _planar()
    with pytest.raises(ControllerError, match="fletcher_reeves"):
        pik.optimize(q0, wdot, DT, np.zeros((200, 4)), method="newton")
    with pytest.raises(ControllerError, match="shape"):
        pik.rollout(q0[:3], np.zeros((200, 4)), wdot, DT)
    with pytest.raises(ControllerError, match="wdot"):
        pik.rollout(q0, np.zeros((200, 4)), wdot[:10], DT)
    with pytest.raises(ControllerError, match="finite"):
        pik.rollout(q0, np.full((200, 4), np.nan), wdot, DT)
    with pytest.raises(ControllerError, match="dt"):
        pik.rollout(q0, np.zeros((200, 4)), wdot, 0.0)
    with pytest.raises(ControllerError, match="fixed-base"):
        PredictiveIk(RobotModel.from_mjcf(BIPED_XML), FramePositionTask("r_sole"))
    with pytest.raises(ControllerError, match="velocity_weight"):
        PredictiveIk(pik.model, pik.task, velocity_weight=-1.0)


def test_follow_is_the_plan_input_on_the_plan_and_pulls_back_to_it() -> None:
    pik, q0, wdot = _planar()
    plan = pik.optimize(q0, wdot[:50], DT, np.zeros((50, 4)), max_iterations=5).rollout
    assert np.array_equal(plan.follow(10, plan.q[10], 3.0), plan.u[10])
    off = plan.q[10] + np.array([0.01, 0.0, -0.02, 0.0])
    assert np.allclose(plan.follow(10, off, 3.0) - plan.u[10], -3.0 * (off - plan.q[10]))
    halfway = 0.5 * (plan.q[10] + plan.q[11])
    assert np.allclose(plan.follow(10, halfway, 3.0, fraction=0.5), plan.u[10])
    assert np.allclose(plan.follow(80, plan.q[-1], 3.0), 0.0)  # after the end: hold the last configuration
    with pytest.raises(ControllerError, match="fraction"):
        plan.follow(10, q0, 3.0, fraction=1.0)
    with pytest.raises(ControllerError, match="gain"):
        plan.follow(10, q0, -1.0)


def test_hard_case_fig_5_10_global_plan_drifts_open_loop_and_follow_holds_it() -> None:
    """The whole fig. 5.10 move of the 9-DoF arm planned once (with the grasp reference's wide collision
    potential, weight 1: the plan grazes the arm's own links): the plan's inputs alone, run with task feedback
    from the same start, drift from the planned joint path (the nullspace has no restoring term) until the arm
    whips through a different self-motion; following the plan with :meth:`PredictiveRollout.follow` keeps it
    within 0.1 rad (open loop: more than 1 rad)."""
    from redundancy_gym.policies.predictive_policy import PredictivePolicyConfig, predictive_problem  # noqa: PLC0415
    from redundancy_gym.studies.point_to_point import FIG_5_10, prepare_point_to_point  # noqa: PLC0415

    setup = prepare_point_to_point(FIG_5_10)
    grasp, q0, steps = setup.policy, setup.q_start, setup.steps
    table = np.array([np.concatenate(setup.path(k * DT)) for k in range(steps)])
    pik = predictive_problem(
        grasp.model,
        grasp.task,
        grasp.joint_limits,
        grasp.collision,
        PredictivePolicyConfig(collision_weight=1.0, collision_activation=0.1, collision_slope=4.0).for_task("grasp"),
        augmented=False,
    )
    # a global plan on the reference loop, as the global policy's: over 300 iterations the compiled loop's
    # round-off ends at another iterate (one that follow() does not hold within 0.1 rad)
    plan = pik.optimize(
        q0, table[:, 6:], DT, np.zeros((steps, 9)), max_iterations=300, tolerance=1e-9, backend="python"
    ).rollout
    deviation: dict[float, float] = {}
    speed: dict[float, float] = {}
    for gain in (0.0, float(grasp.config.gain)):
        q, worst = q0.copy(), 0.0
        for k in range(steps):
            qdot, _ = pik.command(q, plan.follow(k, q, gain), table[k, :6], table[k, 6:], float(grasp.config.gain))
            q = q + DT * qdot
            worst = max(worst, float(np.max(np.abs(q - plan.q[k + 1]))))
            speed[gain] = max(speed.get(gain, 0.0), float(np.max(np.abs(qdot))))
        deviation[gain] = worst
    gain = float(grasp.config.gain)
    assert deviation[gain] < 0.1 < 1.0 < deviation[0.0]
    assert speed[gain] < 1.5 * np.max(np.abs(plan.qdot)) < speed[0.0]


def _agri_axis(augmented: bool = False) -> tuple[PredictiveIk, np.ndarray, np.ndarray]:
    """The 9-DoF arm with the tool-axis task, self-collision (active) and joint limits; 60 samples of a smooth
    reference."""
    model = RobotModel.from_mjcf(AGRI_ARM_XML)
    collision = CollisionObjective(collision_model_from_mjcf(model), activation_distance=0.1, slope=5.0)
    limits = JointLimitObjective.from_model(model, activation_distance=0.3, weight=0.6)
    pik = PredictiveIk(
        model,
        FrameAxisTask(AGRI_ARM_TCP, 0),
        joint_limits=limits,
        collision=collision,
        augmented=augmented,
        input_weight=0.01,
    )
    rng = np.random.default_rng(3)
    q0 = rng.uniform(model.lower_limits, model.upper_limits) * 0.5
    wdot = np.zeros((60, 6))
    wdot[:, 0] = 0.2 * np.sin(np.linspace(0.0, np.pi, 60))
    wdot[:, 4] = 0.3
    return pik, q0, wdot


@pytest.mark.parametrize("augmented", [False, True], ids=("velocity_level", "augmented"))
@pytest.mark.parametrize("method", ["fletcher_reeves", "polak_ribiere", "steepest_descent"])
@pytest.mark.parametrize("problem", ["planar", "agri"])
def test_compiled_optimize_takes_the_python_loops_iterates(problem: str, method: str, augmented: bool) -> None:
    """The fused kernel (the adjoint pass on the rollout's kept kinematics, line-search trials stopped above the
    Armijo threshold, no gradient at the last iterate) takes the same steps as the Python loop on the separate
    rollout and adjoint kernels: equal to round-off (the sums run in another order; the conjugate directions
    grow the difference to ~1e-8 in six iterations), the same status, iterations and forward integrations."""
    if problem == "planar":
        pik, q0, wdot = _planar(augmented=augmented, input_weight=0.01)
        wdot, n = wdot[:120], 4
    else:
        pik, q0, wdot = _agri_axis(augmented)
        n = 9
    rng = np.random.default_rng(7)
    initial = rng.normal(size=(wdot.shape[0], n)) * 0.1
    u_b = rng.normal(size=n) * 0.1 if augmented else None
    for iterations in (0, 1, 6):
        a = pik.optimize(
            q0, wdot, DT, initial, u_b=u_b, max_iterations=iterations, tolerance=0.0, method=method, backend="python"
        )
        b = pik.optimize(
            q0, wdot, DT, initial, u_b=u_b, max_iterations=iterations, tolerance=0.0, method=method, backend="compiled"
        )
        assert (a.status, a.iterations, a.rollouts) == (b.status, b.iterations, b.rollouts)
        np.testing.assert_allclose(b.costs, a.costs, rtol=1e-11)
        scale = max(1.0, float(np.max(np.abs(a.params))))
        assert np.max(np.abs(b.params - a.params)) < 1e-6 * scale
        for name in ("q", "qdot", "u"):
            np.testing.assert_allclose(getattr(b.rollout, name), getattr(a.rollout, name), atol=1e-6)
        # the step comes from the parabola's curvature, a difference of nearly equal costs: ill-conditioned
        assert b.rollout.cost == b.costs[-1] and b.step == pytest.approx(a.step, rel=1e-2)
        for term, value in a.rollout.terms.items():
            assert b.rollout.terms[term] == pytest.approx(value, rel=1e-10, abs=1e-14)
    if problem == "planar":
        assert a.rollout.terms["collision"] > 0.0  # the obstacle shapes the steps compared


def test_compiled_optimize_stops_and_fails_like_the_python_loop() -> None:
    pik, q0, wdot = _planar()
    for tolerance in (1e-3, 0.0):
        a = pik.optimize(
            q0, wdot[:80], DT, np.zeros((80, 4)), max_iterations=200, tolerance=tolerance, backend="python"
        )
        b = pik.optimize(
            q0, wdot[:80], DT, np.zeros((80, 4)), max_iterations=200, tolerance=tolerance, backend="compiled"
        )
        assert a.status == b.status and (a.status == "converged") == (tolerance > 0.0)
        if tolerance > 0.0:
            assert a.iterations == b.iterations
        # 200 iterations: round-off has grown along the conjugate directions; both end at the optimum
        assert b.costs[-1] == pytest.approx(a.costs[-1], rel=1e-5)
    # a first guess that leaves the arm's reach: the kinematics fail on both paths
    with pytest.raises(ControllerError):
        pik.optimize(q0, wdot[:80], DT, np.full((80, 4), 1e200), max_iterations=2, backend="python")
    with pytest.raises(ControllerError, match="overflowed"):
        pik.optimize(q0, wdot[:80], DT, np.full((80, 4), 1e200), max_iterations=2, backend="compiled")
    with pytest.raises(ControllerError, match="u_b"):
        _planar(augmented=True)[0].optimize(
            q0, wdot[:80], DT, np.zeros((80, 4)), u_b=np.full(4, np.nan), backend="compiled"
        )


def test_receding_horizon_compiled_equals_python_and_warm_step_keeps_the_optimum() -> None:
    """Algorithm 12 on the planar arm: the compiled updates apply the Python loop's inputs (to round-off) with as
    many forward integrations. With ``warm_step`` each line search starts from the last update's step; from one
    state it reaches the same optimum as a cold start."""
    from redundancy_gym.controllers.predictive.receding_horizon import RecedingHorizon  # noqa: PLC0415

    pik, q0, wdot = _planar(augmented=True, input_weight=0.01)
    horizons = {
        name: RecedingHorizon(pik, 100, DT, iterations=2, **kwargs)
        for name, kwargs in (("python", {"backend": "python"}), ("compiled", {}), ("warm", {"warm_step": True}))
    }
    q = {name: q0.copy() for name in horizons}
    rollouts = {name: 0 for name in horizons}
    for k in range(30):
        for name, horizon in horizons.items():
            update = horizon.update(q[name], wdot[k : k + 100])
            rollouts[name] += update.result.rollouts
            q[name] = q[name] + DT * update.result.rollout.qdot[0]
        np.testing.assert_allclose(horizons["compiled"].last.u, horizons["python"].last.u, atol=1e-9)
    assert rollouts["compiled"] == rollouts["python"]
    # from one state, the warm-started step reaches the same optimum as a cold start (many iterations)
    warm, cold = horizons["warm"], horizons["compiled"]
    params, u_b = warm._params, warm._u_b
    best = [
        pik.optimize(
            q["warm"],
            wdot[30:130],
            DT,
            params,
            u_b=u_b,
            max_iterations=150,
            tolerance=1e-12,
            step=step,
            backend="compiled",
        )
        for step in (warm._step, 1.0)
    ]
    assert best[0].costs[-1] == pytest.approx(best[1].costs[-1], rel=1e-4)
    assert cold._step == 1.0 and warm._step != 1.0


# ------------------------------------------------------------------ the backend switch
def test_backend_defaults_to_the_compiled_twin_and_is_checked_naming_the_choices(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """One switch with one default: ``optimize`` and the receding horizon run the compiled loop unless told
    ``backend="python"``; an unknown backend is named with the valid choices."""
    from redundancy_gym.controllers.predictive.receding_horizon import RecedingHorizon  # noqa: PLC0415
    from redundancy_gym.kernel_options import BACKENDS, DEFAULT_BACKEND  # noqa: PLC0415

    assert BACKENDS == ("compiled", "python") and DEFAULT_BACKEND == "compiled"
    pik, q0, wdot = _planar()
    args = (q0, wdot[:40], DT, np.full((40, 4), 0.05))
    calls: list[str] = []
    fused = PredictiveIk._optimize_compiled

    def spy(self: PredictiveIk, *a: object) -> object:
        calls.append("compiled")
        return fused(self, *a)  # type: ignore[arg-type]

    monkeypatch.setattr(PredictiveIk, "_optimize_compiled", spy)
    default = pik.optimize(*args, max_iterations=3, tolerance=0.0)
    assert calls == ["compiled"]
    python = pik.optimize(*args, max_iterations=3, tolerance=0.0, backend="python")
    assert calls == ["compiled"]  # the reference loop, not the fused kernel
    np.testing.assert_allclose(default.params, python.params, rtol=0.0, atol=1e-9)
    RecedingHorizon(pik, 40, DT, iterations=1).update(q0, wdot[:40])
    assert calls == ["compiled", "compiled"]
    assert RecedingHorizon(pik, 10, DT).backend == DEFAULT_BACKEND
    message = r"backend must be one of compiled, python; got 'gpu'"
    with pytest.raises(ControllerError, match=message):
        pik.optimize(*args, backend="gpu")
    with pytest.raises(ControllerError, match=message):
        RecedingHorizon(pik, 10, DT, backend="gpu")
    with pytest.raises(ControllerError, match=r"backend must be one of compiled, python; got True"):
        pik.optimize(*args, backend=True)  # type: ignore[arg-type]


@pytest.mark.parametrize("compiled", [True, False])
def test_deprecated_compiled_keyword_still_chooses_the_twin_and_warns(compiled: bool) -> None:
    from redundancy_gym.controllers.predictive.receding_horizon import RecedingHorizon  # noqa: PLC0415

    pik, q0, wdot = _planar(augmented=True, input_weight=0.01)
    backend = "compiled" if compiled else "python"
    args = (q0, wdot[:40], DT, np.full((40, 4), 0.05))
    with pytest.warns(DeprecationWarning, match=f"compiled={compiled} is deprecated.*backend='{backend}'"):
        old = pik.optimize(*args, u_b=np.zeros(4), max_iterations=3, tolerance=0.0, compiled=compiled)
    new = pik.optimize(*args, u_b=np.zeros(4), max_iterations=3, tolerance=0.0, backend=backend)
    np.testing.assert_array_equal(old.params, new.params)
    assert old.rollouts == new.rollouts
    with pytest.warns(DeprecationWarning, match="compiled=.*is deprecated"):
        horizon = RecedingHorizon(pik, 10, DT, compiled=compiled)
    assert horizon.backend == backend
    with pytest.warns(DeprecationWarning, match="RecedingHorizon.compiled is deprecated"):
        assert horizon.compiled is compiled
    # a backend other than the default that contradicts the old keyword is an error, not a silent choice
    if not compiled:
        return
    with pytest.warns(DeprecationWarning), pytest.raises(ControllerError, match="contradicts backend='python'"):
        pik.optimize(*args, u_b=np.zeros(4), backend="python", compiled=True)
