"""The KRL section of the cell: what only the KUKA KRL emitter reads (``cell.dialects["krl"]``).

The YAML keys stay where the cell file has them (``program:``, ``speeds.ptp_percent``,
``drilling.travel_motion``/``apo_*``, ``outputs:``, ``external_axes:``); ``KEYS`` declares them
for the cell reader, and ``read_section`` builds and validates the record in one place.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.codegen.cellfile import DISTANCE_MAX_MM, FRAME_MAX_MM, CellReader, SectionKeys
from accugrid.codegen.krl.names import KRL_RESERVED

__all__ = ["KEYS", "KrlSection", "read_section"]

EXTERNAL_AXES = tuple(f"e{i}" for i in range(1, 7))
KEYS: SectionKeys = {
    "program": frozenset({"name", "lines_per_file", "decimals"}),
    "speeds": frozenset({"ptp_percent"}),
    "drilling": frozenset({"travel_motion", "apo_cdis", "apo_ptp_percent"}),
    "outputs": frozenset({"spindle", "clamp"}),
    "external_axes": frozenset(EXTERNAL_AXES),
}


@dataclass(frozen=True)
class KrlSection:
    """name: the module (NAME.src/.dat, sub-programs NAME_001...; a KRL name of at most 20
    characters); lines_per_file: longest .src/.dat before the job is split; decimals of
    positions (mm) and angles (deg); travel_motion "ptp" (PTP ... C_PTP) or "lin" (LIN ...
    C_DIS) between holes; ptp_percent: BAS #VEL_PTP (%); apo_cdis_mm: $APO.CDIS (mm);
    apo_ptp_percent: $APO.CPTP (%); spindle_output / clamp_output: $OUT numbers (clamp None:
    no clamp); external_axes: E1..E6 of every E6POS (mm or deg)."""

    name: str = "ACCUGRID"
    lines_per_file: int = 5000
    decimals: int = 3
    travel_motion: str = "ptp"
    ptp_percent: float = 50.0
    apo_cdis_mm: float = 5.0
    apo_ptp_percent: float = 50.0
    spindle_output: int = 1
    clamp_output: int | None = None
    external_axes: tuple[float, ...] = (0.0,) * 6


def read_section(r: CellReader, robot_T_base: np.ndarray) -> KrlSection:
    """The KRL record of the cell ``r`` reads (``robot_T_base``, the cell's base frame, is not
    needed: positions are written in it); InputError naming the key and line."""
    name = r.value("program", "name", "ACCUGRID")
    if not isinstance(name, str) or not _is_krl_name(name) or len(name) > 20:
        raise r.error(
            "program.name",
            "must be a KRL name: a letter or _, then letters, digits or _, at most 20 "
            f"characters (4 are kept for the sub-program suffix), not a KRL keyword, got "
            f"{name!r}",
        )
    return KrlSection(
        name=name,
        lines_per_file=r.integer("program", "lines_per_file", 5000, 50, 10**7),
        decimals=r.integer("program", "decimals", 3, 1, 6),
        travel_motion=r.choice("drilling", "travel_motion", "ptp", ("ptp", "lin")),
        ptp_percent=r.number("speeds", "ptp_percent", 50.0, 0.0, 100.0, True),
        apo_cdis_mm=r.number("drilling", "apo_cdis", 5.0, 0.0, DISTANCE_MAX_MM),
        apo_ptp_percent=r.number("drilling", "apo_ptp_percent", 50.0, 0.0, 100.0),
        spindle_output=r.integer("outputs", "spindle", 1, 1, 4096),
        clamp_output=r.integer("outputs", "clamp", None, 1, 4096, optional=True),
        external_axes=tuple(
            r.number("external_axes", e, 0.0, -FRAME_MAX_MM, FRAME_MAX_MM) for e in EXTERNAL_AXES
        ),
    )


def _is_krl_name(name: str) -> bool:
    return (
        bool(name)
        and name.upper() not in KRL_RESERVED
        and (name[0].isascii() and (name[0].isalpha() or name[0] == "_"))
        and all(ch.isascii() and (ch.isalnum() or ch == "_") for ch in name)
    )
