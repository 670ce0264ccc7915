import numpy as np
import pytest

from redundancy_gym.geometry import GeometryError, PiecewisePotential


@pytest.mark.parametrize("t", [0.2, 0.5, 0.8])
def test_c2_conditions(t: float) -> None:
    """(5.55)-(5.57): slope at 0, C2 at the switch t d_a, zero value/slope/curvature at d_a."""
    pot = PiecewisePotential(activation_distance=0.3, slope=2.0, switch_ratio=t)
    da = 0.3
    assert pot.derivative(0.0) == pytest.approx(-2.0)  # (5.55) with s_0 = -slope
    eps = 1e-9
    left, right = pot.evaluate([t * da - eps]), pot.evaluate([t * da + eps])
    for a, b in ((left.value, right.value), (left.slope, right.slope), (left.curvature, right.curvature)):
        assert a[0] == pytest.approx(b[0], abs=1e-6)
    at = pot.evaluate([da - 1e-12, da, da + 1e-3])
    assert np.allclose(at.value, 0.0, atol=1e-20) and np.allclose(at.slope, 0.0, atol=1e-12)
    assert np.allclose(at.curvature, 0.0, atol=1e-9)


def test_derivatives_match_finite_differences() -> None:
    pot = PiecewisePotential(activation_distance=0.25, slope=1.5, switch_ratio=0.4)
    d = np.linspace(-0.2, 0.4, 301)
    h = 1e-6
    res = pot.evaluate(d)
    fd1 = (pot.value(d + h) - pot.value(d - h)) / (2 * h)
    fd2 = (pot.derivative(d + h) - pot.derivative(d - h)) / (2 * h)
    assert np.allclose(res.slope, fd1, atol=1e-6)
    assert np.allclose(res.curvature, fd2, atol=1e-4)


def test_repulsive_and_monotone() -> None:
    pot = PiecewisePotential(0.3)
    d = np.linspace(-0.5, 0.5, 1001)
    v = pot.value(d)
    assert np.all(np.diff(v) <= 1e-15) and np.all(v >= 0)
    assert np.all(pot.derivative(d[d < 0.3]) < 0)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(activation_distance=0.0),
        dict(activation_distance=0.1, slope=-1.0),
        dict(activation_distance=0.1, switch_ratio=1.0),
    ],
)
def test_invalid_parameters(kwargs: dict) -> None:
    with pytest.raises(GeometryError):
        PiecewisePotential(**kwargs)


def test_non_finite_distance_raises() -> None:
    with pytest.raises(GeometryError):
        PiecewisePotential(0.1).value([np.nan])


@pytest.mark.parametrize("cls", ["QuadraticPotential", "CubicPotential"])
def test_h_c2_and_h_c3_derivatives_and_activation(cls: str) -> None:
    import redundancy_gym.geometry as g

    pot = getattr(g, cls)(activation_distance=0.2, gain=3.0)
    d = np.linspace(-0.1, 0.3, 81)
    val = pot.evaluate(d)
    h = 1e-6
    np.testing.assert_allclose(val.slope, (pot.evaluate(d + h).value - pot.evaluate(d - h).value) / (2 * h), atol=1e-5)
    smooth = np.abs(d - 0.2) > 1e-3  # H_c2's curvature jumps at d_a
    np.testing.assert_allclose(
        val.curvature[smooth], ((pot.evaluate(d + h).slope - pot.evaluate(d - h).slope) / (2 * h))[smooth], atol=1e-5
    )
    assert np.all(val.value[d >= 0.2] == 0.0) and np.all(val.value[d < 0.2] > 0.0)
    assert np.all(np.diff(val.value) <= 0.0)  # repulsive: grows as the distance shrinks
    at = pot.evaluate(np.array([0.2 - 1e-9, 0.2]))
    assert abs(at.value[0] - at.value[1]) < 1e-12 and abs(at.slope[0] - at.slope[1]) < 1e-7  # C1 at d_a


def test_only_h_c3_is_c2_at_the_activation_distance() -> None:
    from redundancy_gym.geometry import CubicPotential, QuadraticPotential

    inside = np.array([0.2 - 1e-9])
    assert abs(CubicPotential(0.2, 3.0).evaluate(inside).curvature[0]) < 1e-7
    assert QuadraticPotential(0.2, 3.0).evaluate(inside).curvature[0] == pytest.approx(6.0)


def test_scalar_kernel_matches_the_vectorized_potential() -> None:
    """``piecewise_potential_kernel`` (inside compiled controllers) is (5.58)/(5.59) on every branch."""
    from redundancy_gym.geometry import piecewise_potential_kernel

    pot = PiecewisePotential(activation_distance=0.25, slope=3.0, switch_ratio=0.4)
    d = np.linspace(-0.1, 0.4, 501)
    ref = pot.evaluate(d)
    out = np.array([piecewise_potential_kernel(x, 0.25, 3.0, 0.4) for x in d])
    np.testing.assert_allclose(out[:, 0], ref.value, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(out[:, 1], ref.slope, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(out[:, 2], ref.curvature, rtol=1e-12, atol=1e-15)
