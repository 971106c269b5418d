"""Drake's physics settings (regrasp.plants.drake.model.DrakeSettings): every field checked on construction
(tests/field_checks.py; no Drake needed)."""

from field_checks import field_tests, fields_of
from regrasp.plants.drake.model import APPROXIMATIONS, DrakeSettings

TABLE = fields_of(DrakeSettings(), {
    "pos": ("tip_radius", "time_step", "point_contact_stiffness", "stiction_tolerance", "object_thickness"),
    "nonneg": ("hunt_crossley_dissipation", "near_rigid_threshold", "contact_depth"), "choice": ("approximation",)},
    choices={"approximation": APPROXIMATIONS})

test_each_field_refuses_bad_values, test_each_field_refuses_generated_bad_values = field_tests(TABLE)
