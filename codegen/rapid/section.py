"""The RAPID section of the cell: what only the ABB RAPID dialect reads (``cell.dialects
["rapid"]``), from ``rapid:``, ``program.decimals`` and the tooldata names of ``tool_data:``.
``KEYS`` declares the keys for the cell reader; ``read_section`` builds and validates the
record."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.codegen.cellfile import DISTANCE_MAX_MM, CellReader, SectionKeys
from accugrid.codegen.rapid.names import rapid_name_problem

__all__ = ["KEYS", "RapidSection", "read_section"]

KEYS: SectionKeys = {
    "rapid": frozenset({"module", "tool", "wobj", "tool_mass", "spindle", "zone"}),
    "program": frozenset({"decimals"}),
}


@dataclass(frozen=True)
class RapidSection:
    """module: the MODULE name (None: the output file's stem); tool, wobj: the names of the
    tooldata (the cell's tool, TCP in the flange frame) and the wobjdata (the cell's base frame,
    ``robot_T_wobj`` (4, 4) mm) the program moves with, and that ``rewrite`` accepts; tool_mass:
    the tool load, kg; spindle: the digital output switching the spindle; zone_mm: the zonedata
    TCP radius of travel and retract moves, mm; decimals of positions (mm); tool_names: the
    tooldata name (lower case) of each ``tool_data:`` entry that has one (``name:``, and tool0,
    the flange) -> its tool number, None when the cell has no ``tool_data:``."""

    robot_T_wobj: np.ndarray
    module: str | None = None
    tool: str = "tDrill"
    wobj: str = "wobjPanel"
    tool_mass: float = 5.0
    spindle: str = "doSpindle"
    zone_mm: float = 5.0
    decimals: int = 3
    tool_names: dict[str, int] | None = None


def read_section(r: CellReader, robot_T_base: np.ndarray) -> RapidSection:
    """The RAPID record of the cell ``r`` reads (the work object is the cell's base frame,
    ``robot_T_base``); InputError naming the key and line."""
    names = {}
    for key, default in (("tool", "tDrill"), ("wobj", "wobjPanel"), ("spindle", "doSpindle")):
        value = r.value("rapid", key, default)
        problem = rapid_name_problem(value) if isinstance(value, str) else "must be a name"
        if problem:
            raise r.error(f"rapid.{key}", f"{problem}, got {value!r}")
        names[key] = value
    module = r.value("rapid", "module", None)
    if module is not None:
        problem = rapid_name_problem(module) if isinstance(module, str) else "must be a name"
        if problem:
            raise r.error("rapid.module", f"{problem}, got {module!r}")
    if names["wobj"].lower() == "wobj0":
        raise r.error("rapid.wobj", "wobj0 is the robot's world frame, not the cell's base")
    return RapidSection(
        robot_T_wobj=robot_T_base,
        module=module,
        tool_mass=r.number("rapid", "tool_mass", 5.0, 0.0, 10000.0, True),
        zone_mm=r.number("rapid", "zone", 5.0, 0.0, DISTANCE_MAX_MM),
        decimals=r.integer("program", "decimals", 3, 1, 6),
        tool_names=_tool_names(r),
        **names,
    )


def _tool_names(r: CellReader) -> dict[str, int] | None:
    """The tooldata names the cell's ``tool_data:`` entries give (its keys and frames already
    checked by the cell's reader): lower-case name -> tool number, tool0 (the flange) 0; None
    without ``tool_data:``."""
    data = r.top.get("tool_data")
    if data is None:
        return None
    names = {"tool0": 0}
    for n, entry in data.items():
        name = entry.get("name")
        if name is None:
            continue
        key = f"tool_data.{n}.name"
        if not isinstance(name, str) or not name.isidentifier() or not name.isascii():
            raise r.error(key, f"must be a RAPID tooldata name, got {name!r}")
        if name.lower() in names:
            raise r.error(key, f"{name} names tool {names[name.lower()]} already")
        names[name.lower()] = int(n)
    return names
