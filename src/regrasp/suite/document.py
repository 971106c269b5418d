"""Setting a suite's drawn values on a scenario's TOML document: a key's path walked through its tables, its fingers
(by name or index) and its arrays (by index), tables made where missing; and the one derived key,
:data:`GRAVITY_ANGLE`."""

from __future__ import annotations

import copy
import math
from collections.abc import Iterable

from ..core.exceptions import ScenarioError, short_repr

__all__ = ["GRAVITY_ANGLE", "apply_values"]

#: The derived key that turns the base scenario's gravity by an angle [rad] (counter-clockwise).
GRAVITY_ANGLE = "hand.gravity_angle"


def _finger(where: str, key: str, fingers: list, part: str | int) -> int:
    """The index of the finger ``part`` names (a name, or an index) in the document's ``fingers`` list."""
    if isinstance(part, int):
        if part < len(fingers):
            return part
    else:
        for i, table in enumerate(fingers):
            if isinstance(table, dict) and table.get("name", f"finger{i + 1}") == part:
                return i
    names = [t.get("name", f"finger{i + 1}") if isinstance(t, dict) else "?" for i, t in enumerate(fingers)]
    raise ScenarioError(where, f"vary.{key}", f"no finger {part!r}: the scenario's fingers are "
                        f"{', '.join(names)} (by name or index 0..{len(fingers) - 1})")


def _set(where: str, document: dict, key: str, path: tuple[str | int, ...], value: object) -> None:
    """``document`` at ``path`` set to ``value`` (tables made where missing); a path that does not fit the document
    is a ScenarioError naming the spec's key."""
    node: object = document
    for depth, part in enumerate(path):
        last = depth == len(path) - 1
        if isinstance(node, list):
            if path[depth - 1] == "fingers" and depth == 1:
                index = _finger(where, key, node, part)
            elif isinstance(part, int) and part < len(node):
                index = part
            else:
                raise ScenarioError(where, f"vary.{key}", f"{'.'.join(map(str, path[:depth]))} is an array of "
                                    f"{len(node)}: expected an index 0..{len(node) - 1}, got {part!r}")
            if last:
                node[index] = value
            node = node[index]
        elif isinstance(node, dict):
            if isinstance(part, int):
                raise ScenarioError(where, f"vary.{key}", f"{'.'.join(map(str, path[:depth]))} is a table: "
                                    f"expected a key, got the index {part}")
            if last:
                node[part] = value
            elif part not in node:
                if part == "fingers":
                    raise ScenarioError(where, f"vary.{key}", "the scenario has no [[fingers]]")
                node[part] = {}
            node = node[part]
        else:
            raise ScenarioError(where, f"vary.{key}", f"{'.'.join(map(str, path[:depth]))} is "
                                f"{short_repr(node)}, neither a table nor an array")


def _turn_gravity(where: str, document: dict, angle: float) -> None:
    """The document's gravity (default: 9.81 m/s² down) turned by ``angle`` [rad], counter-clockwise."""
    hand = document.setdefault("hand", {})
    if not isinstance(hand, dict):
        raise ScenarioError(where, f"vary.{GRAVITY_ANGLE}", "the scenario's [hand] is not a table")
    gx, gy = hand.get("gravity", [0.0, -9.81])
    c, s = math.cos(angle), math.sin(angle)
    hand["gravity"] = [c * gx - s * gy, s * gx + c * gy]


def apply_values(base: dict, values: Iterable[tuple[str, tuple[str | int, ...], object]], where: str) -> dict:
    """A copy of ``base`` (a scenario's TOML document) with each (key, its path, value) set: whole tables first (the
    shorter paths), then the keys in them, then the gravity's turn (:data:`GRAVITY_ANGLE`). ``where``: the spec's
    file, for the messages (a key whose path does not fit the document: a ScenarioError naming it)."""
    document = copy.deepcopy(base)
    ordered = sorted(values, key=lambda kpv: len(kpv[1]))  # (stable: the spec's order among equals)
    angle = None
    for key, path, value in ordered:
        if key == GRAVITY_ANGLE:
            angle = value
            continue
        _set(where, document, key, path, copy.deepcopy(value))
    if angle is not None:
        _turn_gravity(where, document, float(angle))
    return document
