r"""Object pose trajectories with exact first and second time derivatives.

A trajectory is the pose :math:`X(t) = (x\,[m],\ y\,[m],\ \beta\,[rad])` of the object
frame :math:`C_o` in the hand frame, over a time domain :math:`[t_0, t_1]` [s], together
with :math:`\dot X(t)` ([m/s], [m/s], [rad/s]) and :math:`\ddot X(t)` ([m/s^2], [m/s^2],
[rad/s^2]).

Evaluation accepts a scalar time (result shape (3,)) or a 1-D array of n times (result
shape (n, 3)). Times outside the domain by more than a relative slack of
:math:`10^{-12}` raise :class:`~regrasp.core.exceptions.TrajectoryError`; times inside the
slack are clamped onto the domain.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import CubicSpline

from .exceptions import InvalidParameterError, TrajectoryError
from .validation import MAX_DURATION, as_finite_array, as_finite_float, as_sample_count

#: Relative slack on the time domain (times max(1, |t_start|, |t_end|)).
DOMAIN_RTOL = 1e-12


@dataclass(frozen=True, eq=False)
class TrajectorySample:
    """Pose and derivatives at one time (or at an array of times).

    Attributes:
        time: t [s] (float, or shape (n,)).
        pose: (x [m], y [m], beta [rad]), shape (3,) or (n, 3).
        velocity: d/dt pose ([m/s], [m/s], [rad/s]), same shape as ``pose``.
        acceleration: d²/dt² pose ([m/s^2], [m/s^2], [rad/s^2]), same shape as ``pose``.
    """

    time: float | np.ndarray
    pose: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


class Trajectory(ABC):
    """Base class: a planar object pose X(t) over a closed time domain ``[t_start, t_end]`` [s].

    Subclasses implement :meth:`_evaluate` on a validated 1-D array of times.
    """

    @property
    @abstractmethod
    def t_start(self) -> float:
        """Start of the time domain [s]."""

    @property
    @abstractmethod
    def t_end(self) -> float:
        """End of the time domain [s] (> ``t_start``)."""

    @property
    def duration(self) -> float:
        """t_end - t_start [s]."""
        return self.t_end - self.t_start

    @abstractmethod
    def _evaluate(self, t: np.ndarray, order: int) -> np.ndarray:
        """Derivative of order 0, 1 or 2 of the pose at the 1-D times ``t``, shape (n, 3)."""

    def _sample_at(self, t: float) -> "TrajectorySample | None":
        """:meth:`sample` at one time in the domain, in floats, or None (no such path: the array one)."""
        return None

    def _evaluate_all(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The derivatives of order 0, 1 and 2 at the 1-D times ``t`` (a subclass may share their work)."""
        return self._evaluate(t, 0), self._evaluate(t, 1), self._evaluate(t, 2)

    # ------------------------------------------------------------------ helpers
    def _times_in_domain(self, t) -> tuple[np.ndarray, bool]:
        """``t`` as a 1-D array clamped onto the domain, and whether it was a scalar."""
        if type(t) is float and self.t_start <= t <= self.t_end:  # the common case, without numpy checks
            return np.array([t]), True
        arr = as_finite_array("t", t)
        if arr.ndim > 1:
            raise InvalidParameterError("t", t, "a time [s] or a 1-D array of times")
        scalar = arr.ndim == 0
        arr = np.atleast_1d(arr)
        t0, t1 = self.t_start, self.t_end
        slack = DOMAIN_RTOL * max(1.0, abs(t0), abs(t1))
        outside = (arr < t0 - slack) | (arr > t1 + slack)
        if np.any(outside):
            bad = float(arr[np.flatnonzero(outside)[0]])
            count = int(np.count_nonzero(outside))
            extra = f" ({count} times out of domain)" if count > 1 else ""
            raise TrajectoryError(
                f"time t = {bad!r} s is outside the trajectory's domain [{t0!r}, {t1!r}] s{extra}"
            )
        return np.clip(arr, t0, t1), scalar

    def _derivative(self, t, order: int) -> np.ndarray:
        arr, scalar = self._times_in_domain(t)
        out = self._evaluate(arr, order)
        return out[0] if scalar else out

    # ------------------------------------------------------------------ public API
    def pose(self, t: ArrayLike) -> np.ndarray:
        """X(t) = (x [m], y [m], beta [rad]); shape (3,) for scalar t, (n, 3) for n times."""
        return self._derivative(t, 0)

    def velocity(self, t: ArrayLike) -> np.ndarray:
        """dX/dt ([m/s], [m/s], [rad/s]); shape (3,) or (n, 3)."""
        return self._derivative(t, 1)

    def acceleration(self, t: ArrayLike) -> np.ndarray:
        """d²X/dt² ([m/s^2], [m/s^2], [rad/s^2]); shape (3,) or (n, 3)."""
        return self._derivative(t, 2)

    def sample(self, t: ArrayLike) -> TrajectorySample:
        """Pose, velocity and acceleration at ``t`` (scalar or 1-D array) [s]."""
        if type(t) is float and self.t_start <= t <= self.t_end:  # one time: the subclass's float path, if any
            fast = self._sample_at(t)
            if fast is not None:
                return fast
        arr, scalar = self._times_in_domain(t)
        pose, vel, acc = self._evaluate_all(arr)
        if scalar:
            return TrajectorySample(float(arr[0]), pose[0], vel[0], acc[0])
        return TrajectorySample(arr, pose, vel, acc)

    def times(self, n: int) -> np.ndarray:
        """``n`` uniformly spaced times [s] from ``t_start`` to ``t_end`` inclusive (2 <= n <=
        :data:`~regrasp.core.validation.MAX_SAMPLES`)."""
        return np.linspace(self.t_start, self.t_end, as_sample_count("n", n))


def _check_domain(t_start: float, t_end: float, start: str = "t_start", end: str = "t_end") -> None:
    """A domain is t_start < t_end <= t_start + :data:`~regrasp.core.validation.MAX_DURATION` (an hour of motion
    is far longer than any hand's task, and a longer one sampled by a planner is sampled too coarsely), within
    ±``MAX_DURATION`` of time 0 (a time that large has so few digits left that a millisecond's phase or a
    microsecond's interval is lost); ``start``, ``end``: the parameters named by an error."""
    if not t_end > t_start:
        raise InvalidParameterError(end, t_end, f"a time [s] > t_start = {t_start!r} s")
    if t_end - t_start > MAX_DURATION:
        raise InvalidParameterError(end, t_end, f"a domain of at most {MAX_DURATION:g} s "
                                    f"(this one runs from {t_start:.4g} s to {t_end:.4g} s)")
    for name, t in ((start, t_start), (end, t_end)):
        if abs(t) > MAX_DURATION:
            raise InvalidParameterError(name, t, f"a time within ±{MAX_DURATION:g} s of 0 (shift the time origin)")


class EllipseTrajectory(Trajectory):
    r"""The paper's elliptic trajectory family.

    .. math::

        x = c_x + a \sin\omega t, \quad y = c_y + b \cos\omega t, \quad
        \beta = \beta_0 + \beta_a \sin\omega t .

    Paper trajectory 1: ``a=1, b=0.5, omega=2, beta_a=1``; trajectory 2:
    ``a=0.9, b=0.5, omega=2, beta_a=0``.

    The formula is defined for all t, but the trajectory still has a domain
    ``[t_start, t_end]`` and raises outside it; by default one period,
    ``t_end = t_start + 2 pi / |omega|``. ``omega = 0`` (a constant pose) requires an
    explicit ``t_end``.

    Args:
        cx: Centre's x [m] (hand frame).
        cy: Centre's y [m] (hand frame).
        a: Semi-axis [m] along x (any finite sign).
        b: Semi-axis [m] along y (any finite sign).
        omega: Angular frequency ω [rad/s].
        beta0: Mean orientation β0 [rad].
        beta_a: Orientation amplitude βa [rad].
        t_start: Start of the time domain [s].
        t_end: End of the time domain [s].
    """

    def __init__(
        self,
        cx: float,
        cy: float,
        a: float,
        b: float,
        omega: float,
        beta0: float = 0.0,
        beta_a: float = 0.0,
        t_start: float = 0.0,
        t_end: float | None = None,
    ):
        self.cx = as_finite_float("cx", cx)
        self.cy = as_finite_float("cy", cy)
        self.a = as_finite_float("a", a)
        self.b = as_finite_float("b", b)
        self.omega = as_finite_float("omega", omega)
        self.beta0 = as_finite_float("beta0", beta0)
        self.beta_a = as_finite_float("beta_a", beta_a)
        t0 = as_finite_float("t_start", t_start)
        if t_end is None:
            if self.omega == 0.0:
                raise InvalidParameterError(
                    "t_end", None, "an explicit end time [s] when omega = 0 (no period to default to)"
                )
            t1 = t0 + 2.0 * np.pi / abs(self.omega)
            if not t1 - t0 <= MAX_DURATION:
                raise InvalidParameterError("omega", omega, f"a frequency whose period 2 pi / |omega| is at most "
                                            f"{MAX_DURATION:g} s (or an explicit t_end)")
        else:
            t1 = as_finite_float("t_end", t_end)
        _check_domain(t0, t1)
        self._t_start = t0
        self._t_end = t1
        self._amplitude = np.array([self.a, self.b, self.beta_a])
        self._offset = np.array([self.cx, self.cy, self.beta0])
        self._floats = (tuple(self._offset.tolist()), tuple(self._amplitude.tolist()))  # (_sample_at)
        w = max(1.0, abs(self.omega))
        for name, amplitude in (("a", self.a), ("b", self.b), ("beta_a", self.beta_a)):
            extent = abs(amplitude) * w * w  # bounds X, X' and X'' (a product overflows to inf, never raises)
            if amplitude != 0.0 and not (extent <= 1e150):
                raise InvalidParameterError(name, amplitude, f"an amplitude whose pose, velocity and acceleration "
                                            f"stay finite with omega = {self.omega:g} (|{name}| omega² <= 1e150)")

    @property
    def t_start(self) -> float:
        return self._t_start

    @property
    def t_end(self) -> float:
        return self._t_end

    @property
    def period(self) -> float:
        """2 pi / |omega| [s] (inf for omega = 0)."""
        return np.inf if self.omega == 0.0 else 2.0 * np.pi / abs(self.omega)

    def _evaluate(self, t: np.ndarray, order: int) -> np.ndarray:
        r"""The k-th derivative: with :math:`s = \sin\omega t,\ c = \cos\omega t`,
        :math:`(x, y, \beta)' = \omega (a c, -b s, \beta_a c)` and
        :math:`(x, y, \beta)'' = -\omega^2 (a s, b c, \beta_a s)`."""
        phase = self.omega * t
        s, c = np.sin(phase), np.cos(phase)
        # Columns (x, y, beta): x and beta follow sin, y follows cos.
        if order == 0:
            basis = np.stack([s, c, s], axis=-1)
            return self._offset + self._amplitude * basis
        if order == 1:
            basis = np.stack([c, -s, c], axis=-1)
            return self.omega * self._amplitude * basis
        basis = np.stack([-s, -c, -s], axis=-1)
        return self.omega**2 * self._amplitude * basis

    def _sample_at(self, t: float) -> TrajectorySample:
        """:meth:`_evaluate_all` at one time, in floats (the same arithmetic, ``math``'s sine and cosine)."""
        (ox, oy, ob), (ax, ay, ab) = self._floats
        w = self.omega
        phase = w * t
        s, c = math.sin(phase), math.cos(phase)
        wa, w2 = w * self._amplitude, w**2 * self._amplitude
        return TrajectorySample(t, np.array([ox + ax * s, oy + ay * c, ob + ab * s]),
                                wa * np.array([c, -s, c]), w2 * np.array([-s, -c, -s]))

    def _evaluate_all(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_evaluate` of orders 0, 1, 2 from one sine and cosine (the same arithmetic)."""
        phase = self.omega * t
        s, c = np.sin(phase), np.cos(phase)
        return (self._offset + self._amplitude * np.stack([s, c, s], axis=-1),
                self.omega * self._amplitude * np.stack([c, -s, c], axis=-1),
                self.omega**2 * self._amplitude * np.stack([-s, -c, -s], axis=-1))

    def __repr__(self) -> str:
        return (
            f"EllipseTrajectory(cx={self.cx!r}, cy={self.cy!r}, a={self.a!r}, b={self.b!r}, "
            f"omega={self.omega!r}, beta0={self.beta0!r}, beta_a={self.beta_a!r}, "
            f"t_start={self.t_start!r}, t_end={self.t_end!r})"
        )


_BOUNDARIES = ("natural", "clamped", "periodic")

#: The shortest interval [s] between two waypoints: a microsecond, far below any control period (1 ms), and long
#: enough that the spline's slopes (a pose's change over the interval) stay representable.
MIN_WAYPOINT_INTERVAL = 1e-6
#: The largest pose, velocity and acceleration a waypoint spline may reach (as the ellipse's amplitudes): far from
#: overflow when squared or multiplied by a mass.
MAX_SPLINE_EXTENT = 1e150


def _fitted_spline(t: np.ndarray, p: np.ndarray, boundary: str) -> CubicSpline:
    """The cubic spline through the poses ``p`` at the times ``t``, if its pose, velocity and acceleration stay
    within :data:`MAX_SPLINE_EXTENT` over every interval, else a :class:`TrajectoryError` naming the poses."""
    h = np.diff(t)
    with np.errstate(all="ignore"):  # (an overflow is reported below, as an error)
        try:
            spline = CubicSpline(t, p, axis=0, bc_type=boundary, extrapolate=False)
        except ValueError:  # (scipy: "dydx must contain only finite values")
            k = int(np.argmax(np.max(np.abs(np.diff(p, axis=0)), axis=1) / h))
            spline = None
        else:
            # on an interval of length h the spline is c0 x³ + c1 x² + c2 x + c3 (0 <= x <= h): each derivative's
            # magnitude is at most the sum of its terms' at x = h (NaN and inf fail the test)
            c0, c1, c2, c3 = np.abs(spline.c)
            hh = h[:, None]
            bounds = (((c0 * hh + c1) * hh + c2) * hh + c3, (3.0 * c0 * hh + 2.0 * c1) * hh + c2,
                      6.0 * c0 * hh + 2.0 * c1)
            ok = np.all([np.all(b <= MAX_SPLINE_EXTENT, axis=1) for b in bounds], axis=0)
            if ok.all():
                return spline
            k = int(np.flatnonzero(~ok)[0])
    raise TrajectoryError(f"the waypoint spline's pose, velocity or acceleration exceeds {MAX_SPLINE_EXTENT:g} "
                          f"between times[{k}] = {float(t[k])!r} s and times[{k + 1}] = {float(t[k + 1])!r} s: the "
                          "poses change too much for their times", name="poses")


class WaypointTrajectory(Trajectory):
    r"""C² cubic spline through time-stamped poses (one ``scipy`` CubicSpline per coordinate).

    Boundary conditions (applied to x, y and beta alike):

    * ``"natural"``: zero acceleration at both ends;
    * ``"clamped"``: zero velocity at both ends;
    * ``"periodic"``: velocity and acceleration match at both ends; the first and last
      poses must be equal and at least 3 waypoints are needed.

    Args:
        times: (n,) strictly increasing waypoint times [s], n >= 2.
        poses: (n, 3) waypoint poses (x [m], y [m], beta [rad]) in the hand frame.
        boundary: One of ``"natural"``, ``"clamped"``, ``"periodic"``.
        unwrap_angle: Apply ``np.unwrap`` to beta before fitting (removes 2 pi jumps);
            the periodic check is made after unwrapping.

    Raises:
        InvalidParameterError: wrong shapes, non-finite values, unknown boundary.
        TrajectoryError: too few waypoints, times not strictly increasing, periodic
            boundary with different first and last poses.
    """

    def __init__(self, times: ArrayLike, poses: ArrayLike, *, boundary: str = "natural", unwrap_angle: bool = False):
        if not isinstance(boundary, str) or boundary not in _BOUNDARIES:
            raise InvalidParameterError("boundary", boundary, f"one of {', '.join(_BOUNDARIES)}")
        t = as_finite_array("times", times, (-1,))
        p = as_finite_array("poses", poses, (-1, 3))
        n = t.shape[0]
        if p.shape[0] != n:
            raise InvalidParameterError(
                "poses", poses, f"one pose (x, y, beta) per waypoint time: shape ({n}, 3)"
            )
        min_n = 3 if boundary == "periodic" else 2
        if n < min_n:
            raise TrajectoryError(
                f"a {boundary} waypoint trajectory needs at least {min_n} waypoints, got {n}"
            )
        steps = np.diff(t)
        if np.any(steps <= 0.0):
            k = int(np.flatnonzero(steps <= 0.0)[0])
            raise TrajectoryError(
                f"waypoint times must be strictly increasing: times[{k}] = {float(t[k])!r} s and "
                f"times[{k + 1}] = {float(t[k + 1])!r} s", name="times"
            )
        if np.any(steps < MIN_WAYPOINT_INTERVAL):
            k = int(np.flatnonzero(steps < MIN_WAYPOINT_INTERVAL)[0])
            raise TrajectoryError(
                f"waypoint times must be at least {MIN_WAYPOINT_INTERVAL:g} s apart: times[{k}] = {float(t[k])!r} s "
                f"and times[{k + 1}] = {float(t[k + 1])!r} s", name="times"
            )
        _check_domain(float(t[0]), float(t[-1]), "times", "times")
        if unwrap_angle:
            p = p.copy()
            p[:, 2] = np.unwrap(p[:, 2])
        if boundary == "periodic":
            size = max(1.0, float(np.max(np.abs(p))))
            gap = p[-1] - p[0]
            if np.any(np.abs(gap) > 1e-12 * size):
                hint = (
                    " (after unwrapping beta; a full turn cannot be periodic in beta)"
                    if unwrap_angle
                    else ""
                )
                raise TrajectoryError(
                    f"periodic boundary needs the first and last poses equal, got "
                    f"{p[0].tolist()} and {p[-1].tolist()}{hint}"
                )
            p = p.copy()
            p[-1] = p[0]
        self._times = t
        self._poses = p
        self._times.setflags(write=False)
        self._poses.setflags(write=False)
        self._boundary = boundary
        self._spline = _fitted_spline(t, p, boundary)

    @property
    def t_start(self) -> float:
        return float(self._times[0])

    @property
    def t_end(self) -> float:
        return float(self._times[-1])

    @property
    def waypoint_times(self) -> np.ndarray:
        """(n,) waypoint times [s] (read-only)."""
        return self._times

    @property
    def waypoint_poses(self) -> np.ndarray:
        """(n, 3) waypoint poses as fitted (beta unwrapped if requested; read-only)."""
        return self._poses

    @property
    def boundary(self) -> str:
        """The boundary condition: "natural", "clamped" or "periodic"."""
        return self._boundary

    def _evaluate(self, t: np.ndarray, order: int) -> np.ndarray:
        return self._spline(t, order)

    def __repr__(self) -> str:
        return (
            f"WaypointTrajectory({len(self._times)} waypoints, t in [{self.t_start!r}, "
            f"{self.t_end!r}] s, boundary={self._boundary!r})"
        )


__all__ = ["MIN_WAYPOINT_INTERVAL", "Trajectory", "TrajectorySample", "EllipseTrajectory", "WaypointTrajectory"]


class RepeatedTrajectory(Trajectory):
    """A periodic trajectory repeated past its domain: X(t) = base(t_start + (t - t_start) mod P).

    Args:
        base: A periodic trajectory (an ellipse, or waypoints with a ``"periodic"`` boundary).
        t_end: End of the extended domain [s] (> the base's ``t_start``).
    """

    def __init__(self, base: Trajectory, t_end: float):
        if not isinstance(base, Trajectory):
            raise InvalidParameterError("base", base, "a Trajectory")
        period = getattr(base, "period", None)
        if period is None and getattr(base, "boundary", None) == "periodic":
            period = base.t_end - base.t_start
        if period is None or not math.isfinite(period) or period <= 0:
            raise InvalidParameterError("base", base, "a periodic trajectory (an ellipse with omega != 0, or "
                                        "waypoints with a periodic boundary)")
        t1 = as_finite_float("t_end", t_end)
        _check_domain(base.t_start, t1)
        self.base = base
        self._period = float(period)
        self._t_end = t1

    @property
    def t_start(self) -> float:
        return self.base.t_start

    @property
    def t_end(self) -> float:
        return self._t_end

    @property
    def period(self) -> float:
        """The base's period [s]."""
        return self._period

    def _evaluate(self, t: np.ndarray, order: int) -> np.ndarray:
        t0 = self.base.t_start
        local = t0 + np.mod(t - t0, self._period)
        return self.base._evaluate(np.clip(local, t0, self.base.t_end), order)

    def _sample_at(self, t: float) -> TrajectorySample | None:
        t0, base = self.base.t_start, self.base
        local = min(max(t0 + (t - t0) % self._period, t0), base.t_end)
        out = base._sample_at(local)
        return None if out is None else TrajectorySample(t, out.pose, out.velocity, out.acceleration)

    def _evaluate_all(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t0 = self.base.t_start
        return self.base._evaluate_all(np.clip(t0 + np.mod(t - t0, self._period), t0, self.base.t_end))

    def __repr__(self) -> str:
        return f"RepeatedTrajectory({self.base!r}, t_end={self._t_end!r})"
