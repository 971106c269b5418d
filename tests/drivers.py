"""A rollout's supervisor driver that fails on demand (the simulation loop's tests)."""

from regrasp.core.exceptions import RegraspError


class Driver:
    """The rollout's supervisor driver, failing on demand at step ``fail_at``."""

    def __init__(self, inner, fail_at=None, error=RegraspError("no torque")):
        self.inner, self.fail_at, self.error, self.calls = inner, fail_at, error, 0

    def step(self, meas, dt):
        if self.calls == self.fail_at:
            raise self.error
        self.calls += 1
        return self.inner.step(meas, dt)


def driver(rollout, **kw):
    from regrasp.rollout.build import SupervisorDriver

    return Driver(SupervisorDriver(rollout.supervisor), **kw)

