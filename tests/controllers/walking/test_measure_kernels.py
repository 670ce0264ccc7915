"""The walking controller's compiled measurement (CompiledMeasurement) agrees with the pinocchio/NumPy path it
replaces; the controller's ``backend`` chooses one of the two (the kernel checks and converts the inputs it does
not read as they are, and never hands them to the pinocchio path); a bad input is named alike in both."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import CompiledMeasurement, WalkingCommand
from redundancy_gym.controllers.walking.zmp_estimator import estimate_zmp
from redundancy_gym.model import ModelError, RobotModel

from .biped_helpers import standing, walking_controller

FRAMES = ("r_ankle_ft", "l_ankle_ft", "r_sole", "l_sole")


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def random_state(model: RobotModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A pinocchio ``(q, v)``: the standing posture moved and turned, joints perturbed, a random velocity."""
    q = standing(model)
    q[:3] += rng.normal(scale=0.2, size=3)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    q[7:] += rng.normal(scale=0.2, size=model.nq - 7)
    return q, rng.normal(size=model.nv)


def reference(
    model: RobotModel,
    q: np.ndarray,
    v: np.ndarray,
    sensors: np.ndarray,
    stance: int,
    planned: tuple[float, float, float],
    stance_frame: bool,
    ground: float,
) -> dict[str, np.ndarray | None]:
    """What WalkingController measured through pinocchio and NumPy before the kernel (its _in_stance_frame)."""
    com, com_velocity, rotations, positions = model.measure(q, v, FRAMES)
    turn, shift = np.eye(3), np.zeros(3)
    if stance_frame:
        rotation = rotations[2 + stance]
        yaw = np.arctan2(rotation[1, 0], rotation[0, 0]) - planned[2]
        c, s = np.cos(yaw), np.sin(yaw)
        turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        real = positions[2 + stance]
        shift = np.array([planned[0], planned[1], 0.0]) - turn @ np.array([real[0], real[1], 0.0])
        com, com_velocity, rotations, positions = (
            turn @ com + shift,
            turn @ com_velocity,
            turn @ rotations,
            positions @ turn.T + shift,
        )
    wrench = sensors.reshape(2, 6)
    contact = estimate_zmp(rotations[:2], positions[:2], wrench[:, :3], wrench[:, 3:], ground=ground)
    return {
        "com": com,
        "com_velocity": com_velocity,
        "rotations": rotations,
        "positions": positions,
        "turn": turn,
        "shift": shift,
        "zmp": contact.zmp,
        "cop": contact.cop,
        "normal_force": contact.normal_force,
        "moment": contact.moment,
    }


def to_mujoco(q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's qpos (w x y z) and qvel (world linear velocity) of a pinocchio state."""
    qpos = q.copy()
    qpos[3:7] = q[[6, 3, 4, 5]]
    x, y, z, w = q[3:7]
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    qvel = v.copy()
    qvel[:3] = rotation @ v[:3]
    return qpos, qvel


@pytest.mark.parametrize("stance_frame", [True, False])
@pytest.mark.parametrize("mujoco", [True, False])
def test_the_kernel_agrees_with_pinocchio_and_numpy(model: RobotModel, stance_frame: bool, mujoco: bool) -> None:
    measurement = CompiledMeasurement(model, FRAMES)
    rng = np.random.default_rng(3)
    for trial in range(20):
        q, v = random_state(model, rng)
        sensors = rng.normal(scale=50.0, size=12)
        sensors[[2, 8]] = -rng.uniform(0.0, 400.0, size=2)  # one foot unloaded now and then (below 20 N)
        if trial % 5 == 0:
            sensors[2] = -5.0
        stance = trial % 2
        planned = (float(rng.normal()), float(rng.normal()), float(rng.normal()) if trial % 3 else 0.0)
        inputs = to_mujoco(q, v) if mujoco else (q, v)
        m = measurement.measure(
            *inputs, sensors, mujoco=mujoco, stance_frame=stance_frame, stance=stance, planned=planned, ground=0.01
        )
        assert m is not None
        expected = reference(model, q, v, sensors, stance, planned, stance_frame, 0.01)
        np.testing.assert_allclose(m.q, q, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(m.v, v, rtol=0.0, atol=1e-12)
        for name, value in expected.items():
            got = getattr(m, name)
            if value is None:
                assert got is None, name
                continue
            np.testing.assert_allclose(got, value, rtol=0.0, atol=1e-10, err_msg=name)


def test_non_finite_inputs_and_a_zero_quaternion_give_none(model: RobotModel) -> None:
    measurement = CompiledMeasurement(model, FRAMES)
    q, v = random_state(model, np.random.default_rng(0))
    sensors = np.zeros(12)
    kwargs: dict[str, Any] = {"stance_frame": True, "stance": 0, "planned": (0.0, 0.0, 0.0), "ground": 0.0}
    assert measurement.measure(q, v, sensors, mujoco=False, **kwargs) is not None
    for k in range(3):  # a NaN in q, in v, in the sensors
        args = [q.copy(), v.copy(), sensors.copy()]
        args[k][5] = np.nan
        assert measurement.measure(*args, mujoco=False, **kwargs) is None
    qpos, qvel = to_mujoco(q, v)
    qpos[3:7] = 0.0
    assert measurement.measure(qpos, qvel, sensors, mujoco=True, **kwargs) is None


def test_step_mujoco_is_step_on_the_converted_state(model: RobotModel) -> None:
    """step_mujoco (the policy's path) and step on from_mujoco_state give the same walk; lists take the checked
    path with the same result; a NaN configuration is named as before."""
    controllers = [walking_controller(model) for _ in range(3)]
    for controller in controllers:
        controller.start(standing(model), 0.5)
    rng = np.random.default_rng(1)
    forces = np.array([[0.0, 0.0, -300.0], [0.0, 0.0, -290.0]])
    torques = np.array([[1.0, -2.0, 0.0], [0.5, 3.0, 0.0]])
    wrenches = np.concatenate([forces, torques], axis=1).reshape(-1)
    q = controllers[0].q_ref.copy()
    while controllers[0].time < 1.0:
        v = rng.normal(scale=0.05, size=model.nv)
        qpos, qvel = to_mujoco(q, v)
        a = controllers[0].step_mujoco(qpos, qvel, wrenches)
        b = controllers[1].step(*model.from_mujoco_state(qpos, qvel), forces, torques)
        q_list, v_list = (x.tolist() for x in model.from_mujoco_state(qpos, qvel))
        c = controllers[2].step(q_list, v_list, forces.tolist(), torques.tolist())
        np.testing.assert_allclose(a.joint_targets, b.joint_targets, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(c.joint_targets, b.joint_targets, rtol=0.0, atol=1e-12)
        assert a.contact.zmp is not None and b.contact.zmp is not None  # both feet loaded
        np.testing.assert_allclose(a.contact.zmp, b.contact.zmp, rtol=0.0, atol=1e-12)
        q = a.ik.q
    bad = q.copy()
    bad[9] = np.nan
    with pytest.raises(ModelError, match="non-finite"):
        controllers[1].step(bad, np.zeros(model.nv), forces, torques)


# ------------------------------------------------------------------ the backend switch
def _walked(model: RobotModel, backend: str, steps: int, convert: bool = False) -> list[WalkingCommand]:
    """``steps`` periods of a walk on one recorded state sequence (lists instead of arrays with ``convert``)."""
    controller = walking_controller(model, backend=backend)
    controller.start(standing(model), 0.5)
    rng = np.random.default_rng(4)
    forces = np.array([[0.0, 0.0, -300.0], [0.0, 0.0, -290.0]])
    torques = np.array([[1.0, -2.0, 0.0], [0.5, 3.0, 0.0]])
    q, commands = controller.q_ref.copy(), []
    for _ in range(steps):
        v = rng.normal(scale=0.05, size=model.nv)
        inputs = (q, v, forces, torques)
        command = controller.step(*(x.tolist() for x in inputs) if convert else inputs)
        commands.append(command)
        q = command.ik.q
    return commands


def test_python_backend_measures_on_the_reference_and_agrees_with_the_kernel(
    model: RobotModel, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``backend="python"`` runs the pinocchio/NumPy measurement (and no kernel), ``"compiled"`` the kernel (and never
    the pinocchio path, lists included): the same walk to round-off."""
    from redundancy_gym.controllers.walking import WalkingController  # noqa: PLC0415

    reference = WalkingController._measure_python
    calls = {"python": 0, "compiled": 0}

    def counted(self: WalkingController, *args: object) -> object:
        calls["python"] += 1
        return reference(self, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(WalkingController, "_measure_python", counted)
    python = _walked(model, "python", 25)
    assert calls["python"] == 25
    calls["python"] = 0
    compiled, converted = _walked(model, "compiled", 25), _walked(model, "compiled", 25, convert=True)
    assert calls["python"] == 0  # no fallback: the kernel measured every period, lists too
    for a, b, c in zip(python, compiled, converted, strict=True):
        np.testing.assert_allclose(b.joint_targets, a.joint_targets, rtol=0.0, atol=1e-9)
        assert a.contact.zmp is not None and b.contact.zmp is not None  # both feet loaded
        np.testing.assert_allclose(b.contact.zmp, a.contact.zmp, rtol=0.0, atol=1e-9)
        np.testing.assert_array_equal(c.joint_targets, b.joint_targets)  # the same kernel on the same numbers


@pytest.mark.parametrize("backend", ["compiled", "python"])
@pytest.mark.parametrize(
    ("bad", "error", "match"),
    [
        ("q", ModelError, "configuration contains non-finite values"),
        ("v", ModelError, "velocity contains non-finite values"),
        ("forces", ControllerError, "the ankle sensor forces must be finite"),
        ("torques", ControllerError, "the ankle sensor torques must be finite"),
        ("torques_shape", ControllerError, "torques"),
        ("quaternion", ModelError, "base quaternion of qpos is zero"),
    ],
)
def test_a_bad_measurement_input_raises_the_same_named_error_in_both_backends(
    model: RobotModel, backend: str, bad: str, error: type[Exception], match: str
) -> None:
    """The kernel's rejection (a non-finite input, a zero quaternion) is no fallback: the input is named, with the
    error of the reference path, whichever backend runs."""
    controller = walking_controller(model, backend=backend)
    controller.start(standing(model), 0.5)
    q, v = controller.q_ref.copy(), np.zeros(model.nv)
    forces, torques = np.array([[0.0, 0.0, -300.0], [0.0, 0.0, -290.0]]), np.zeros((2, 3))
    if bad == "quaternion":
        qpos, qvel = to_mujoco(q, v)
        qpos[3:7] = 0.0
        with pytest.raises(error, match=match):
            controller.step_mujoco(qpos, qvel, np.concatenate([forces, torques], axis=1).reshape(-1))
        return
    inputs = {"q": q, "v": v, "forces": forces, "torques": torques}
    if bad == "torques_shape":
        inputs["torques"] = np.zeros(3)
    else:
        inputs[bad] = inputs[bad].copy()
        inputs[bad].flat[2] = np.nan
    with pytest.raises(error, match=match):
        controller.step(**inputs)


def test_compiled_backend_says_at_construction_that_it_does_not_cover_the_model(
    model: RobotModel, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A model the compiled kinematics do not cover (here: its serial chain refused as for a spherical joint) was
    measured through pinocchio without a word; now ``backend="compiled"`` raises naming the joint and the way out,
    and ``backend="python"`` builds the controller."""
    other = RobotModel.from_mjcf(BIPED_XML)

    def refused() -> None:
        raise ModelError("joint 'r_hip' is JointModelSpherical; compiled kinematics support JointModelRX, ...")

    monkeypatch.setattr(other, "serial_chain", refused)
    with pytest.raises(ControllerError, match=r"backend='compiled' needs .*JointModelSpherical.*backend='python'"):
        walking_controller(other, backend="compiled")
    assert walking_controller(other, backend="python")._measurement is None


def test_backends_are_the_one_shared_tuple_and_the_old_names_still_import() -> None:
    import redundancy_gym.controllers.walking as walking  # noqa: PLC0415
    from redundancy_gym import kernel_options  # noqa: PLC0415
    from redundancy_gym.controllers.walking import WalkingIkConfig, measure_kernels  # noqa: PLC0415
    from redundancy_gym.policies import options  # noqa: PLC0415

    assert walking.BACKENDS is kernel_options.BACKENDS and options.BACKENDS is kernel_options.BACKENDS
    assert WalkingIkConfig().backend == kernel_options.DEFAULT_BACKEND
    with pytest.raises(ControllerError, match=r"backend must be one of compiled, python; got 'fortran'"):
        WalkingIkConfig(backend="fortran")
    for module in (walking, measure_kernels):
        with pytest.warns(DeprecationWarning, match="Measurement is now MeasurementResult"):
            assert module.Measurement is walking.MeasurementResult
    assert "Measurement" not in walking.__all__
    with pytest.raises(AttributeError):
        _ = walking.NoSuchName
