"""The compiled control step (regrasp.kernels.control) against the reference path (``compiled=False``)."""

import numpy as np
import pytest

from internal_force_cases import EDGES, KINDS, Y0, make_hand, polygon
from regrasp.core.contact import Friction
from regrasp.core.exceptions import SingularFingerError, UnreachableError
from regrasp.dynamics.control import Gains
from regrasp.dynamics.grasp import Grasp
from regrasp.dynamics.internal_force.problem import InternalForceInfeasibleError
from regrasp.dynamics.internal_force.settings import InternalForceSettings
from regrasp.dynamics.laws import FixedContactController, Proposition1Controller
from regrasp.dynamics.reduced import ReducedModel


def controllers(kind, seed, **kwargs):
    m, modes = KINDS[kind]
    rng = np.random.default_rng(seed)
    hand = make_hand(m, gravity=9.81 * np.array([np.sin(a := rng.uniform(-0.4, 0.4)), -np.cos(a)]))
    model = ReducedModel(hand, Grasp(polygon(), EDGES[m], modes), rng.uniform(-0.01, 0.01, m))
    cls = FixedContactController if model.grasp.p == 0 else Proposition1Controller
    gains = Gains.critically_damped(rng.uniform(5.0, 30.0), model.n)
    mu = rng.uniform(0.45, 1.0, m)
    return (cls(model, gains, mu, **kwargs), cls(model, gains, mu, compiled=False, **kwargs)), model, rng


@pytest.mark.parametrize("qp", [InternalForceSettings(f_min=0.3), InternalForceSettings(target_cone_margin=0.2),
                                None])
@pytest.mark.parametrize("kind", list(KINDS))
def test_compiled_control_step_equals_the_reference_path(kind, qp):
    (fast, reference), model, rng = controllers(kind, 7, internal_force=qp)
    assert fast.compiled and not reference.compiled
    compared = answered = 0
    for _ in range(40):
        n = model.n
        S = np.concatenate([[rng.uniform(-0.02, 0.02), Y0 + rng.uniform(-0.015, 0.015), rng.uniform(-0.15, 0.15)],
                            rng.uniform(-0.012, 0.012, n - 3)])
        args = (S, rng.uniform(-0.05, 0.05, n), S + rng.uniform(-0.003, 0.003, n), rng.uniform(-0.05, 0.05, n),
                rng.uniform(-1.0, 1.0, n))
        try:
            expected = reference(*args)
        except (UnreachableError, SingularFingerError) as exc:
            with pytest.raises(type(exc)):
                fast(*args)
            continue
        except Exception as exc:  # noqa: BLE001 (an infeasible QP: the compiled step raises the same)
            with pytest.raises(type(exc)):
                fast(*args)
            continue
        answered += fast.compiled_step(np.array(args, dtype=float), 0.0) is not None  # (no state: a pure step)
        got = fast(*args)
        scale = max(1.0, np.abs(expected.tau).max())
        np.testing.assert_allclose(got.tau, expected.tau, rtol=0, atol=1e-10 * scale)
        for name in ("command", "error", "error_rate", "friction_estimate"):
            np.testing.assert_array_equal(getattr(got, name), getattr(expected, name))
        force_scale = max(1.0, np.abs(expected.contact_forces).max())
        for name in ("contact_forces", "contact_forces_surface", "cone_margins"):
            np.testing.assert_allclose(getattr(got, name), getattr(expected, name), rtol=0, atol=1e-10 * force_scale)
        if qp is None:
            assert got.internal is None and expected.internal is None
        else:
            assert got.internal.null_space_dim == expected.internal.null_space_dim
            assert got.internal.feasible == expected.internal.feasible
            np.testing.assert_allclose(got.internal.f_c, expected.internal.f_c, rtol=0, atol=1e-10 * force_scale)
            assert got.internal.cone_margin == pytest.approx(expected.internal.cone_margin, abs=1e-10 * force_scale)
        compared += 1
    assert compared >= 20 and answered >= compared - 2  # (the compiled step answered, not the reference path)


def test_a_law_that_estimates_friction_or_a_reference_model_takes_the_reference_path():
    (fast, _), model, _ = controllers("m3p1-left", 3)
    assert fast.compiled
    reference_model = ReducedModel(model.hand, model.grasp, model.xi, compiled=False)
    assert not Proposition1Controller(reference_model, fast.gains, fast.friction).compiled


@pytest.mark.parametrize("reversible", [True, False])
@pytest.mark.parametrize("qp", [InternalForceSettings(f_min=0.3), InternalForceSettings(target_cone_margin=0.2),
                                None])
@pytest.mark.parametrize("kind", ["m3p1-left", "m3p1-bottom"])
def test_compiled_sliding_step_equals_the_reference_path(kind, qp, reversible):
    """Proposition 3 with three fingers: the same torques, forces, friction estimates and sliding directions
    (which both update, step after step, from the same measured rates), compiled or not."""
    from regrasp.dynamics.laws import Proposition3Controller

    m, modes = KINDS[kind]
    rng = np.random.default_rng(11)
    model = ReducedModel(make_hand(m), Grasp(polygon(), EDGES[m], modes), rng.uniform(-0.01, 0.01, m))
    gains = Gains.critically_damped(15.0, model.n)
    mu = [Friction(s, 0.6 * s) for s in rng.uniform(0.5, 1.0, m)]
    fast = Proposition3Controller(model, gains, mu, internal_force=qp, reversible=reversible, direction=-1.0)
    reference = Proposition3Controller(model, gains, mu, internal_force=qp, reversible=reversible, direction=-1.0,
                                       compiled=False)
    assert fast.compiled and not reference.compiled
    compared = 0
    for _ in range(40):
        n = model.n
        S = np.concatenate([[rng.uniform(-0.02, 0.02), Y0 + rng.uniform(-0.015, 0.015), rng.uniform(-0.15, 0.15)],
                            rng.uniform(-0.012, 0.012, n - 3)])
        S_dot = rng.uniform(-0.05, 0.05, n) * (rng.random(n) < 0.8)  # (some rates exactly zero)
        args = (S, S_dot, S + rng.uniform(-0.003, 0.003, n), rng.uniform(-0.05, 0.05, n), rng.uniform(-1.0, 1.0, n))
        try:
            expected = reference(*args)
        except Exception as exc:  # noqa: BLE001 (unreachable, singular, infeasible: the compiled step the same)
            with pytest.raises(type(exc)):
                fast(*args)
            assert fast.directions == reference.directions
            continue
        got = fast(*args)
        assert fast.directions == reference.directions
        scale = max(1.0, np.abs(expected.tau).max())
        np.testing.assert_allclose(got.tau, expected.tau, rtol=0, atol=1e-10 * scale)
        force_scale = max(1.0, np.abs(expected.contact_forces).max())
        for name in ("contact_forces", "contact_forces_surface", "cone_margins", "friction_estimate"):
            np.testing.assert_allclose(getattr(got, name), getattr(expected, name), rtol=0, atol=1e-10 * force_scale)
        if qp is not None:
            np.testing.assert_allclose(got.internal.f_c, expected.internal.f_c, rtol=0, atol=1e-10 * force_scale)
        compared += 1
    assert compared >= 20


def _limited_model(kind, rng, effort):
    """A model of ``kind`` whose fingers' joints are limited to ``effort`` [N m], and the same without limits."""
    from internal_force_cases import fingers
    from regrasp.model.hand import Hand

    m, modes = KINDS[kind]
    gravity = 9.81 * np.array([np.sin(a := rng.uniform(-0.4, 0.4)), -np.cos(a)])
    xi = rng.uniform(-0.01, 0.01, m)
    hands = [Hand([f.with_placement(effort_limit=e) for f in fingers()[:m]], gravity_in_hand=gravity)
             for e in (effort, np.inf)]
    return [ReducedModel(hand, Grasp(polygon(), EDGES[m], modes), xi) for hand in hands]


@pytest.mark.parametrize("kind,effort,binding", [("m3p0", 0.05, 3), ("m3p1-left", 0.055, 2),
                                                  ("m3p1-bottom", 0.08, 3)])
def test_compiled_step_equals_the_reference_path_with_torque_limits_active(kind, effort, binding):
    """Joints limited to ``effort`` [N m], below what many random states' least squeeze needs (the fixed law, or
    Proposition 3's sliding step): both paths keep every |τ_j| <= effort + 1e-9 N m (the QP's torque rows), agree,
    and fail alike, naming the limit, where no squeeze keeps it."""
    from regrasp.dynamics.laws import Proposition3Controller

    rng = np.random.default_rng(5)
    limited, free = _limited_model(kind, rng, effort)
    gains = Gains.critically_damped(15.0, limited.n)
    mu = [Friction(s, 0.6 * s) for s in rng.uniform(0.6, 1.0, limited.grasp.m)]
    qp = InternalForceSettings(f_min=0.3)
    cls = FixedContactController if limited.grasp.p == 0 else Proposition3Controller
    fast, reference = (cls(limited, gains, mu, internal_force=qp, compiled=c) for c in (None, False))
    unlimited = cls(free, gains, mu, internal_force=qp)
    assert fast.compiled and not reference.compiled and fast.effort_limit == [effort] * 6
    bound = raised = 0
    for _ in range(40):
        n = limited.n
        S = np.concatenate([[rng.uniform(-0.02, 0.02), Y0 + rng.uniform(-0.015, 0.015), rng.uniform(-0.15, 0.15)],
                            rng.uniform(-0.012, 0.012, n - 3)])
        args = (S, rng.uniform(-0.05, 0.05, n), S + rng.uniform(-0.003, 0.003, n), rng.uniform(-0.05, 0.05, n),
                rng.uniform(-1.0, 1.0, n))
        try:
            without = unlimited(*args)
        except (UnreachableError, SingularFingerError, InternalForceInfeasibleError):
            continue
        try:
            expected = reference(*args)
        except InternalForceInfeasibleError as exc:
            with pytest.raises(InternalForceInfeasibleError):
                fast(*args)
            assert exc.torque is not None and exc.torque.effort == effort
            raised += 1
            continue
        got = fast(*args)
        for out in (got, expected):
            assert np.abs(out.tau).max() <= effort + 1e-9
        np.testing.assert_allclose(got.tau, expected.tau, rtol=0, atol=1e-10)
        np.testing.assert_allclose(got.contact_forces, expected.contact_forces, rtol=0, atol=1e-9)
        bound += np.abs(without.tau).max() > effort
    assert bound >= binding and raised >= 3
