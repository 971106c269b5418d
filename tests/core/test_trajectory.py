r"""Tests of regrasp.core.trajectory: exact derivatives, spline properties, domains and errors.

Finite-difference bound. For a central difference with step h,
:math:`|(f(t+h) - f(t-h)) / 2h - f'(t)| \le \tfrac{h^2}{6} \max|f'''| + \epsilon \max|f| / h`
(truncation + rounding). We allow 50 times the truncation term and 100 times the rounding
term, so a wrong derivative (error of order |f'|) cannot pass.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from regrasp.core.exceptions import InvalidParameterError, TrajectoryError
from regrasp.core.trajectory import (
    EllipseTrajectory,
    Trajectory,
    TrajectorySample,
    WaypointTrajectory,
)

STEP = 1e-5
EPS = np.finfo(float).eps

PAPER_1 = dict(cx=0.0, cy=0.0, a=1.0, b=0.5, omega=2.0, beta_a=1.0)
PAPER_2 = dict(cx=0.0, cy=0.0, a=0.9, b=0.5, omega=2.0, beta_a=0.0)


def fd_tolerance(third_derivative_scale: float, value_scale: float, h: float = STEP) -> float:
    """Bound on the central-difference error (see the module docstring)."""
    return 50.0 * h**2 * third_derivative_scale + 100.0 * EPS * value_scale / h


def interior_times(traj: Trajectory, n: int, seed: int, avoid=(), margin: float = 2 * STEP) -> np.ndarray:
    """Seeded random times at least ``margin`` from the domain ends and from ``avoid``."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(traj.t_start + margin, traj.t_end - margin, size=4 * n)
    if len(avoid):
        far = np.min(np.abs(t[:, None] - np.asarray(avoid)[None, :]), axis=1) > margin
        t = t[far]
    return t[:n]


def check_derivatives(traj: Trajectory, t: np.ndarray, d3: float, d4: float) -> None:
    """velocity vs FD of pose and acceleration vs FD of velocity, componentwise."""
    pose_scale = np.max(np.abs(traj.pose(t))) + 1.0
    vel_scale = np.max(np.abs(traj.velocity(t))) + 1.0
    fd_vel = (traj.pose(t + STEP) - traj.pose(t - STEP)) / (2 * STEP)
    fd_acc = (traj.velocity(t + STEP) - traj.velocity(t - STEP)) / (2 * STEP)
    np.testing.assert_allclose(traj.velocity(t), fd_vel, rtol=0, atol=fd_tolerance(d3, pose_scale))
    np.testing.assert_allclose(traj.acceleration(t), fd_acc, rtol=0, atol=fd_tolerance(d4, vel_scale))


def ellipse_derivative_scales(p: dict) -> tuple[float, float]:
    amp = max(abs(p["a"]), abs(p["b"]), abs(p.get("beta_a", 0.0)))
    w = abs(p["omega"])
    return amp * w**3, amp * w**4


# ---------------------------------------------------------------------- ellipse
@pytest.mark.parametrize("params", [PAPER_1, PAPER_2], ids=["paper1", "paper2"])
def test_paper_ellipses_derivatives(params):
    traj = EllipseTrajectory(**params)
    assert traj.t_start == 0.0 and traj.t_end == pytest.approx(np.pi)
    d3, d4 = ellipse_derivative_scales(params)
    check_derivatives(traj, interior_times(traj, 200, seed=1), d3, d4)


def test_ellipse_closed_form_values():
    traj = EllipseTrajectory(**PAPER_1)
    t = 0.4
    s, c = np.sin(2 * t), np.cos(2 * t)
    np.testing.assert_allclose(traj.pose(t), [s, 0.5 * c, s])
    np.testing.assert_allclose(traj.velocity(t), [2 * c, -1.0 * s, 2 * c])
    np.testing.assert_allclose(traj.acceleration(t), [-4 * s, -2 * c, -4 * s])
    np.testing.assert_allclose(traj.pose(0.0), [0.0, 0.5, 0.0], atol=1e-15)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    cx=st.floats(-2, 2),
    cy=st.floats(-2, 2),
    a=st.floats(-2, 2),
    b=st.floats(-2, 2),
    omega=st.floats(0.1, 10).flatmap(lambda w: st.sampled_from([w, -w])),
    beta0=st.floats(-3, 3),
    beta_a=st.floats(-2, 2),
    t_start=st.floats(-5, 5),
    seed=st.integers(0, 2**16),
)
def test_random_ellipse_derivatives(cx, cy, a, b, omega, beta0, beta_a, t_start, seed):
    params = dict(cx=cx, cy=cy, a=a, b=b, omega=omega, beta0=beta0, beta_a=beta_a)
    traj = EllipseTrajectory(**params, t_start=t_start)
    assert traj.t_end == pytest.approx(t_start + 2 * np.pi / abs(omega))
    d3, d4 = ellipse_derivative_scales(params)
    check_derivatives(traj, interior_times(traj, 30, seed=seed), d3, d4)
    # one full period: pose and derivatives repeat
    for f in (traj.pose, traj.velocity, traj.acceleration):
        np.testing.assert_allclose(f(traj.t_start), f(traj.t_end), atol=1e-9 * (1 + abs(omega)) ** 2)


def test_ellipse_custom_domain_and_zero_omega():
    traj = EllipseTrajectory(**PAPER_1, t_start=1.0, t_end=1.5)
    assert (traj.t_start, traj.t_end) == (1.0, 1.5)
    with pytest.raises(TrajectoryError, match=r"t = 1\.6 s is outside .*\[1\.0, 1\.5\]"):
        traj.pose(1.6)
    still = EllipseTrajectory(0.1, 0.2, 1.0, 1.0, 0.0, beta0=0.3, t_end=2.0)
    np.testing.assert_allclose(still.pose([0.0, 2.0]), [[0.1, 1.2, 0.3]] * 2)
    np.testing.assert_array_equal(still.velocity(1.0), 0.0)
    assert still.period == np.inf


@pytest.mark.parametrize(
    "kwargs, name, expected",
    [
        (dict(PAPER_1, omega=0.0), "t_end", "omega = 0"),
        (dict(PAPER_1, a=np.nan), "a", "finite"),
        (dict(PAPER_1, omega=np.inf), "omega", "finite"),
        (dict(PAPER_1, t_end=0.0), "t_end", "> t_start"),
        (dict(PAPER_1, t_start=2.0, t_end=1.0), "t_end", "> t_start = 2.0"),
        (dict(PAPER_1, beta_a="x"), "beta_a", "a number"),
    ],
)
def test_ellipse_bad_parameters(kwargs, name, expected):
    with pytest.raises(InvalidParameterError, match=expected) as info:
        EllipseTrajectory(**kwargs)
    assert info.value.name == name


# ---------------------------------------------------------------------- waypoints
def random_waypoints(seed: int, n: int, periodic: bool = False) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    times = np.cumsum(rng.uniform(0.2, 1.0, size=n)) - 0.5
    poses = rng.uniform(-1.0, 1.0, size=(n, 3)) * (0.5, 0.3, 2.0)
    if periodic:
        poses[-1] = poses[0]
    return times, poses


def spline_third_derivative_scale(traj: WaypointTrajectory) -> float:
    """max |X'''| from the (piecewise-constant) third derivative on each interval."""
    knots = traj.waypoint_times
    mids = 0.5 * (knots[:-1] + knots[1:])
    # a cubic's acceleration is linear inside an interval: a central difference there is exact to rounding
    h = 1e-3 * np.diff(knots)
    jerk = (traj.sample(mids + h).acceleration - traj.sample(mids - h).acceleration) / (2 * h)[:, None]
    return float(np.max(np.abs(jerk))) + 1.0


@pytest.mark.parametrize("boundary", ["natural", "clamped", "periodic"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_waypoint_spline_properties(boundary, seed):
    times, poses = random_waypoints(seed, n=6 + seed, periodic=boundary == "periodic")
    traj = WaypointTrajectory(times, poses, boundary=boundary)
    assert (traj.t_start, traj.t_end) == (times[0], times[-1])
    # interpolates the waypoints
    np.testing.assert_allclose(traj.pose(times), poses, atol=1e-12)
    # exact derivatives (the 4th derivative of a cubic is zero between knots)
    d3 = spline_third_derivative_scale(traj)
    check_derivatives(traj, interior_times(traj, 200, seed=seed, avoid=times), d3, 0.0)
    # C2 at the interior knots
    knots = times[1:-1]
    delta = 1e-9
    tol = 4 * delta * d3 + 1e-9
    for f in (traj.pose, traj.velocity, traj.acceleration):
        np.testing.assert_allclose(f(knots - delta), f(knots + delta), atol=tol)
    # boundary conditions
    if boundary == "clamped":
        np.testing.assert_allclose(traj.velocity([times[0], times[-1]]), 0.0, atol=1e-12)
    elif boundary == "natural":
        np.testing.assert_allclose(traj.acceleration([times[0], times[-1]]), 0.0, atol=1e-10)
    else:
        for f in (traj.pose, traj.velocity, traj.acceleration):
            np.testing.assert_allclose(f(times[0]), f(times[-1]), atol=1e-10)


def test_waypoint_two_points_natural_is_linear_and_clamped_is_smoothstep():
    times, poses = [1.0, 3.0], [[0.0, 0.0, 0.0], [2.0, -4.0, 1.0]]
    lin = WaypointTrajectory(times, poses)
    np.testing.assert_allclose(lin.velocity(2.2), [1.0, -2.0, 0.5])
    np.testing.assert_allclose(lin.acceleration(2.2), 0.0, atol=1e-14)
    smooth = WaypointTrajectory(times, poses, boundary="clamped")
    s = 0.5  # t = 2: the cubic Hermite with zero end slopes is 3s^2 - 2s^3
    np.testing.assert_allclose(smooth.pose(2.0), (3 * s**2 - 2 * s**3) * np.array(poses[1]))


def test_unwrap_angle():
    times = [0.0, 1.0, 2.0]
    poses = [[0.0, 0.0, 3.0], [0.0, 0.0, -3.0], [0.0, 0.0, -2.5]]  # -3 is 3 + (2pi - 6)
    unwrapped = WaypointTrajectory(times, poses, unwrap_angle=True)
    np.testing.assert_allclose(unwrapped.pose(1.0)[2], 2 * np.pi - 3.0)
    np.testing.assert_allclose(unwrapped.waypoint_poses[:, 2], np.unwrap([3.0, -3.0, -2.5]))
    raw = WaypointTrajectory(times, poses)
    assert raw.pose(1.0)[2] == pytest.approx(-3.0)


def test_unwrapped_full_turn_cannot_be_periodic():
    times = [0.0, 1.0, 2.0, 3.0]
    poses = [[0, 0, 0.0], [0, 0, 2.0], [0, 0, -2.0], [0, 0, 0.0]]
    # beta 0 -> 2 -> -2 (= 2pi - 2) -> 0 (= 2pi after unwrapping): a full turn
    with pytest.raises(TrajectoryError, match="after unwrapping"):
        WaypointTrajectory(times, poses, boundary="periodic", unwrap_angle=True)
    WaypointTrajectory(times, poses, boundary="periodic")  # fine without unwrapping


# ---------------------------------------------------------------------- shared API
@pytest.fixture(params=["ellipse", "waypoints"])
def trajectory(request) -> Trajectory:
    if request.param == "ellipse":
        return EllipseTrajectory(**PAPER_1)
    times, poses = random_waypoints(5, 7)
    return WaypointTrajectory(times, poses, boundary="clamped")


def test_vectorised_equals_scalar(trajectory):
    t = trajectory.times(17)
    for f in (trajectory.pose, trajectory.velocity, trajectory.acceleration):
        batch = f(t)
        assert batch.shape == (17, 3)
        assert f(float(t[3])).shape == (3,)
        np.testing.assert_array_equal(batch, np.array([f(float(ti)) for ti in t]))


def test_sample(trajectory):
    t = 0.3 * trajectory.t_start + 0.7 * trajectory.t_end
    sample = trajectory.sample(t)
    assert isinstance(sample, TrajectorySample)
    assert sample.time == t
    np.testing.assert_array_equal(sample.pose, trajectory.pose(t))
    np.testing.assert_array_equal(sample.velocity, trajectory.velocity(t))
    np.testing.assert_array_equal(sample.acceleration, trajectory.acceleration(t))
    with pytest.raises(AttributeError):
        sample.time = 0.0
    many = trajectory.sample(trajectory.times(5))
    assert many.pose.shape == many.velocity.shape == many.acceleration.shape == (5, 3)


def test_times(trajectory):
    t = trajectory.times(11)
    assert t[0] == trajectory.t_start and t[-1] == trajectory.t_end
    np.testing.assert_allclose(np.diff(t), trajectory.duration / 10)
    for bad in (1, 0, -3, 2.0, True, "5", 10**6, 2**63 - 1):
        with pytest.raises(InvalidParameterError, match=r"in \[2, 100000\]") as info:
            trajectory.times(bad)
        assert info.value.name == "n"


def test_out_of_domain(trajectory):
    t0, t1 = trajectory.t_start, trajectory.t_end
    # within the 1e-12 relative slack: accepted and clamped
    np.testing.assert_array_equal(trajectory.pose(t1 + 1e-14), trajectory.pose(t1))
    for bad in (t0 - 1e-6, t1 + 1e-6, t1 + 10.0):
        for f in (trajectory.pose, trajectory.velocity, trajectory.acceleration, trajectory.sample):
            with pytest.raises(TrajectoryError, match=r"outside the trajectory's domain") as info:
                f(bad)
            assert repr(float(bad)) in str(info.value) and repr(t1) in str(info.value)
    with pytest.raises(TrajectoryError, match=r"2 times out of domain"):
        trajectory.pose([t0, t1 + 1.0, t1 + 2.0])
    with pytest.raises(InvalidParameterError, match="finite"):
        trajectory.pose(np.nan)
    with pytest.raises(InvalidParameterError, match="1-D"):
        trajectory.pose(np.zeros((2, 2)))


# ---------------------------------------------------------------------- bad waypoints
GOOD_TIMES = [0.0, 1.0, 2.0]
GOOD_POSES = [[0.0, 0.0, 0.0], [1.0, 0.5, 0.2], [0.0, 0.0, 0.0]]


@pytest.mark.parametrize(
    "times, poses, boundary, error, expected",
    [
        ([0.0, 2.0, 1.0], GOOD_POSES, "natural", TrajectoryError, r"strictly increasing: times\[1\] = 2\.0"),
        ([0.0, 1.0, 1.0], GOOD_POSES, "natural", TrajectoryError,
         r"strictly increasing: times\[1\] = 1\.0 s and times\[2\] = 1\.0"),
        ([0.0, np.nan, 2.0], GOOD_POSES, "natural", InvalidParameterError, "finite"),
        (GOOD_TIMES, [[0.0, 0.0, np.inf]] * 3, "natural", InvalidParameterError, "finite"),
        (GOOD_TIMES, [[0.0, 0.0]] * 3, "natural", InvalidParameterError, r"shape \(nx3\)"),
        (GOOD_TIMES, GOOD_POSES[:2], "natural", InvalidParameterError, r"shape \(3, 3\)"),
        ([[0.0, 1.0, 2.0]], GOOD_POSES, "natural", InvalidParameterError, r"shape \(n\)"),
        ([0.0], [[0.0, 0.0, 0.0]], "natural", TrajectoryError, "at least 2 waypoints, got 1"),
        ([0.0], [[0.0, 0.0, 0.0]], "clamped", TrajectoryError, "at least 2 waypoints, got 1"),
        ([0.0, 1.0], [[0.0, 0.0, 0.0]] * 2, "periodic", TrajectoryError, "at least 3 waypoints, got 2"),
        (GOOD_TIMES, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.1, 0.0]], "periodic", TrajectoryError,
         r"first and last poses equal, got \[0\.0, 0\.0, 0\.0\] and \[0\.0, 0\.1, 0\.0\]"),
        (GOOD_TIMES, GOOD_POSES, "not-a-knot", InvalidParameterError, "natural, clamped, periodic"),
    ],
)
def test_bad_waypoints(times, poses, boundary, error, expected):
    with pytest.raises(error, match=expected):
        WaypointTrajectory(times, poses, boundary=boundary)


@pytest.mark.parametrize("times, poses, error, name, expected", [
    # issue 25: times spanning ±1.7e308 (scipy's "dydx must contain only finite values" traceback before)
    ([-1.7e308, 0.0, 1.7e308], GOOD_POSES, InvalidParameterError, "times", "a domain of at most 3600 s"),
    # times 1e-300 s apart (scipy's overflow warnings, then a NaN pose in `plan`, before)
    ([0.0, 1e-300, 2e-300], GOOD_POSES, TrajectoryError, "times", r"at least 1e-06 s apart: times\[0\] = 0\.0 s"),
    ([0.0, 1.0, 1.0 + 5e-7], GOOD_POSES, TrajectoryError, "times", r"times\[1\] = 1\.0 s and times\[2\]"),
    ([1e9, 1e9 + 1.0, 1e9 + 2.0], GOOD_POSES, InvalidParameterError, "times", "within ±3600 s of 0"),
    ([-4000.0, -3999.0, -3998.0], GOOD_POSES, InvalidParameterError, "times", "within ±3600 s of 0"),
    # poses that change too fast for their times: the spline's derivatives would overflow
    ([0.0, 1e-6, 2e-6], [[0.0, 0.0, 0.0], [1e200, 0.0, 0.0], [0.0, 0.0, 0.0]], TrajectoryError, "poses",
     r"exceeds 1e\+150 between times\[0\] = 0\.0 s and times\[1\] = 1e-06 s"),
    ([0.0, 1e-6, 2e-6], [[0.0, 0.0, 0.0], [1e308, 0.0, 0.0], [-1e308, 0.0, 0.0]], TrajectoryError, "poses",
     "exceeds 1e\\+150"),
    ([0.0, 1.0, 2.0], [[0.0, 0.0, 0.0], [0.0, 1e300, 0.0], [0.0, 0.0, 0.0]], TrajectoryError, "poses",
     "exceeds 1e\\+150"),
], ids=["span ±1.7e308", "1e-300 apart", "5e-7 apart", "at 1e9 s", "at -4000 s", "1e200 in 1 us",
        "±1e308 in 1 us", "1e300 in 1 s"])
def test_waypoint_times_and_poses_whose_spline_cannot_be_represented(times, poses, error, name, expected):
    with pytest.raises(error, match=expected) as info:
        WaypointTrajectory(times, poses)
    assert info.value.name == name and "\n" not in str(info.value)


@pytest.mark.parametrize("boundary", ["natural", "clamped", "periodic"])
def test_waypoints_a_microsecond_apart_near_the_largest_times_are_a_finite_spline(boundary):
    """The bounds' edge cases are accepted: a microsecond apart, at ±3600 s, with derivatives finite."""
    for times in ([0.0, 1e-6, 2e-6], [3600.0 - 2e-3, 3600.0 - 1e-3, 3600.0], [-3600.0, -1800.0, 0.0]):
        traj = WaypointTrajectory(times, [[0.0, 0.1, 0.0], [0.001, 0.1, 0.01], [0.0, 0.1, 0.0]], boundary=boundary)
        t = traj.times(11)
        assert all(np.isfinite(f(t)).all() for f in (traj.pose, traj.velocity, traj.acceleration))


def test_an_ellipse_far_from_time_0_is_refused_at_its_key():
    with pytest.raises(InvalidParameterError, match="invalid t_start = 1000000000.0: expected a time within ±3600 s"):
        EllipseTrajectory(**PAPER_1, t_start=1e9, t_end=1e9 + 1.0)


def test_waypoint_inputs_are_copied():
    times, poses = np.array(GOOD_TIMES), np.array(GOOD_POSES)
    traj = WaypointTrajectory(times, poses)
    before = traj.pose(1.0).copy()
    poses[1] = 100.0
    times[2] = 50.0
    np.testing.assert_array_equal(traj.pose(1.0), before)
    assert traj.t_end == 2.0


def test_a_sample_is_each_derivative_exactly():
    """``sample`` (one sine and cosine for all three derivatives; one float: in floats) equals ``pose``,
    ``velocity`` and ``acceleration``, for an ellipse and for it repeated, at one time and at many."""
    from regrasp.core.trajectory import EllipseTrajectory, RepeatedTrajectory

    base = EllipseTrajectory(cx=0.01, cy=0.12, a=0.02, b=0.01, omega=1.3, beta0=0.1, beta_a=0.2)
    for traj in (base, RepeatedTrajectory(base, base.t_start + 3 * base.period)):
        times = np.linspace(traj.t_start, traj.t_end, 57)
        for t in (*times.tolist(), times):  # (one float: math's sine, to numpy's last bit or one ulp off)
            out = traj.sample(t)
            for got, want in ((out.pose, traj.pose(t)), (out.velocity, traj.velocity(t)),
                              (out.acceleration, traj.acceleration(t))):
                np.testing.assert_allclose(got, want, rtol=1e-15, atol=1e-18)
            assert out.time is t or np.array_equal(out.time, t)
