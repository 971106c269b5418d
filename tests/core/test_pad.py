"""The fingertip pad's value type (``regrasp.core.pad``): its force law and sign conventions, its energy, the critical
damping and the RK4 rate bound, each against an independent computation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.pad import Pad


def test_force_law_and_sign_conventions():
    """f_n = k δ + c δ̇ while the tip is in and the pad pushes; never a pull: 0 off the surface (δ <= 0) and 0 when
    the tip leaves faster than the spring pushes."""
    pad = Pad(1e4, 20.0, preload=0.3)
    assert pad.preload_depth == pytest.approx(0.3 / 1e4)
    assert pad.normal_force(1e-4, 0.0) == pytest.approx(1.0)  # pressed 0.1 mm: 1 N, pushing (positive)
    assert pad.normal_force(1e-4, 0.01) == pytest.approx(1.0 + 0.2)  # going in: more
    assert pad.normal_force(1e-4, -0.01) == pytest.approx(1.0 - 0.2)  # coming out: less
    assert pad.normal_force(1e-4, -0.1) == 0.0  # coming out faster than k δ / c: no pull
    assert pad.normal_force(0.0, 1.0) == 0.0 and pad.normal_force(-1e-5, 1.0) == 0.0  # off the surface
    rng = np.random.default_rng(0)
    for depth, rate in zip(rng.uniform(-1e-4, 1e-4, 200), rng.uniform(-0.1, 0.1, 200)):
        f = pad.normal_force(depth, rate)
        assert f >= 0.0
        assert f == (max(0.0, 1e4 * depth + 20.0 * rate) if depth > 0 else 0.0)


def test_energy_is_the_springs_potential():
    """d/dδ of the elastic energy is the spring force k δ₊ (central differences), and 0 off the surface."""
    pad = Pad(3e4)
    for depth in (-2e-5, 1e-6, 5e-5):
        h = 1e-9
        derivative = (pad.energy(depth + h) - pad.energy(depth - h)) / (2 * h)
        assert derivative == pytest.approx(max(0.0, 3e4 * depth), rel=1e-6, abs=1e-9)


def test_critical_damping_gives_a_double_real_eigenvalue():
    """c = 2 sqrt(k m): m δ̈ + c δ̇ + k δ = 0 has a double eigenvalue -sqrt(k/m) (numpy's eigenvalues of its
    first-order form)."""
    k, m = 1e5, 0.01
    pad = Pad.critically_damped(k, m, preload=0.2)
    assert pad.preload == 0.2
    lam = np.linalg.eigvals(np.array([[0.0, 1.0], [-k / m, -pad.damping / m]]))
    np.testing.assert_allclose(lam.real, -math.sqrt(k / m), rtol=1e-6)
    assert np.abs(lam.imag).max() < 1e-3 * math.sqrt(k / m)


def test_rate_bound_bounds_the_eigenvalues_and_sets_the_substeps():
    """Λ(w) is at least every eigenvalue's magnitude of δ̈ = -w (k δ + c δ̇), and at most 2.5 times the largest, over
    under- and over-damped pads; the substeps keep dt Λ / n <= step_rate."""
    rng = np.random.default_rng(1)
    for _ in range(200):
        k, c, w = 10 ** rng.uniform(2, 7), 10 ** rng.uniform(-2, 3), 10 ** rng.uniform(0, 3)
        pad = Pad(k, c)
        top = np.abs(np.linalg.eigvals(np.array([[0.0, 1.0], [-w * k, -w * c]]))).max()
        assert top <= pad.rate_bound(w) * (1 + 1e-9) and pad.rate_bound(w) <= 2.5 * top
        n = pad.substeps_for(1e-3, w)
        assert n >= 1 and 1e-3 * pad.rate_bound(w) / n <= pad.step_rate * (1 + 1e-9)
        assert n == 1 or 1e-3 * pad.rate_bound(w) / (n - 1) > pad.step_rate
    assert Pad(1e9, substeps=3).substeps_for(1e-3, 100.0) == 3


@pytest.mark.parametrize("kwargs", [dict(stiffness=0.0), dict(stiffness=-1.0), dict(stiffness=math.inf),
                                    dict(stiffness=1e4, damping=-1.0), dict(stiffness=1e4, preload=math.nan),
                                    dict(stiffness=1e4, substeps=0), dict(stiffness=1e4, substeps=2.0),
                                    dict(stiffness=1e4, step_rate=3.0), dict(stiffness=1e4, step_rate=0.0),
                                    dict(stiffness="stiff"), dict(stiffness=1e4, separation_gap=-1e-6)])
def test_bad_pads_are_typed_errors(kwargs):
    with pytest.raises(InvalidParameterError):
        Pad(**kwargs)
    with pytest.raises(InvalidParameterError):
        Pad.critically_damped(1e4, 0.0)
