"""Print the defaults the concepts page names, from the code (a block of ``docs/generate.py``)."""

from pprint import pp

from regrasp.core.contact import DEFAULT_CONE_MARGIN
from regrasp.core.health import HealthCriteria
from regrasp.core.intervals import DANGER_FRACTION
from regrasp.schedule.problem import RegraspSettings

print(f"{DANGER_FRACTION = }")
print(f"{DEFAULT_CONE_MARGIN = }")
pp(RegraspSettings(), width=100)
pp(HealthCriteria(), width=100)
