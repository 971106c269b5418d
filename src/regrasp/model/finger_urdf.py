r"""Generate URDF text for a planar two-link (2R) finger.

Used to write the shipped ``urdf/*.urdf`` files and, in tests, to build fingers of
any proportion in memory. Each link is a solid cylinder along its local x axis
(length ``l`` [m], radius ``r`` [m], mass ``m`` [kg]); its inertia about the centre
of mass is :math:`I_{xx} = m r^2/2`, :math:`I_{yy} = I_{zz} = m (3 r^2 + l^2)/12`.
The cylinder is also the link's collision shape (URDF cylinders have their axis on
local z, hence ``rpy = (0, pi/2, 0)``). A fixed joint places the ``tip`` frame at the
end of the second link.
"""

from __future__ import annotations

from ..core.exceptions import InvalidParameterError
from ..core.validation import as_mass, as_positive_float


def _link(name: str, length: float, radius: float, mass: float) -> str:
    ixx = mass * radius**2 / 2.0
    iyy = mass * (3.0 * radius**2 + length**2) / 12.0
    half = length / 2.0
    shape = (
        f'<origin xyz="{half!r} 0 0" rpy="0 1.5707963267948966 0"/>'
        f'<geometry><cylinder radius="{radius!r}" length="{length!r}"/></geometry>'
    )
    return f"""  <link name="{name}">
    <inertial>
      <origin xyz="{half!r} 0 0" rpy="0 0 0"/>
      <mass value="{mass!r}"/>
      <inertia ixx="{ixx!r}" ixy="0" ixz="0" iyy="{iyy!r}" iyz="0" izz="{iyy!r}"/>
    </inertial>
    <visual>{shape}</visual>
    <collision>{shape}</collision>
  </link>
"""


def _joint(name: str, parent: str, child: str, x: float, damping: float) -> str:
    return f"""  <joint name="{name}" type="revolute">
    <parent link="{parent}"/>
    <child link="{child}"/>
    <origin xyz="{x!r} 0 0" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3.141592653589793" upper="3.141592653589793" effort="5.0" velocity="20.0"/>
    <dynamics damping="{damping!r}" friction="0.0"/>
  </joint>
"""


#: The longest link or link radius a generated finger may have [m].
MAX_LINK = 10.0


def planar_2r_urdf(
    l1: float,
    l2: float,
    *,
    radius1: float = 0.008,
    radius2: float = 0.007,
    mass1: float | None = None,
    mass2: float | None = None,
    damping: float = 0.0,
    name: str = "planar_2r_finger",
) -> str:
    """URDF text of a planar 2R finger with links along x and revolute z joints.

    Args:
        l1: Link length [m], joint 1 to joint 2.
        l2: Link length [m], joint 2 to the tip.
        radius1: Cylinder radius [m] of link 1 (visual and collision).
        radius2: Cylinder radius [m] of link 2 (visual and collision).
        mass1: Link 1's mass [kg]; default: an aluminium tube of 30 % fill, ``0.3 * 2700 * pi r^2 l``.
        mass2: Link 2's mass [kg]; the same default.
        damping: Viscous joint damping [N·m·s/rad].
        name: Robot name.
    """
    l1 = as_positive_float("l1", l1)
    l2 = as_positive_float("l2", l2)
    radius1 = as_positive_float("radius1", radius1)
    radius2 = as_positive_float("radius2", radius2)
    for label, value in (("l1", l1), ("l2", l2), ("radius1", radius1), ("radius2", radius2)):
        if value > MAX_LINK:
            raise InvalidParameterError(label, value, f"a length of at most {MAX_LINK:g} m")
    damping = as_positive_float("damping", damping, allow_zero=True)
    rho = 0.3 * 2700.0
    m1 = as_mass("mass1", mass1) if mass1 is not None else rho * 3.141592653589793 * radius1**2 * l1
    m2 = as_mass("mass2", mass2) if mass2 is not None else rho * 3.141592653589793 * radius2**2 * l2
    return (
        f'<?xml version="1.0"?>\n<robot name="{name}">\n'
        '  <link name="base"/>\n'
        + _joint("joint1", "base", "link1", 0.0, damping)
        + _link("link1", l1, radius1, m1)
        + _joint("joint2", "link1", "link2", l1, damping)
        + _link("link2", l2, radius2, m2)
        + f"""  <joint name="tip_joint" type="fixed">
    <parent link="link2"/>
    <child link="tip"/>
    <origin xyz="{l2!r} 0 0" rpy="0 0 0"/>
  </joint>
  <link name="tip"/>
</robot>
"""
    )
