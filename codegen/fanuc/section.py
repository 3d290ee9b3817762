"""The FANUC section of the cell: what only the FANUC TP dialect reads (``cell.dialects
["fanuc"]``), from ``fanuc:`` and ``program.decimals``. The program's user frame and tool frame
are the cell's base and tool: their numbers must be ones the controller has (UFRAME 1..9, UTOOL
1..10; user frame 0 is the world frame, the robot frame, and tool frame 0 the faceplate).
``KEYS`` declares the keys for the cell reader; ``read_section`` builds and validates the
record."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.codegen.cellfile import CellReader, SectionKeys
from accugrid.codegen.fanuc.names import program_name_problem
from accugrid.infra.errors import InputError

__all__ = ["KEYS", "UFRAME_MAX", "UTOOL_MAX", "WHOLE_SPEED", "FanucSection", "read_section"]

WHOLE_SPEED = "a FANUC linear speed is a whole number of mm/sec, at least 1"

UFRAME_MAX = 9  # user frames 1..9 (0: the world frame)
UTOOL_MAX = 10  # tool frames 1..10
KEYS: SectionKeys = {
    "fanuc": frozenset({"program", "joint_percent", "cnt", "spindle"}),
    "program": frozenset({"decimals"}),
}


@dataclass(frozen=True)
class FanucSection:
    """uframe, utool: the user frame (the cell's base, ``robot_T_uframe`` (4, 4) mm in the
    robot frame, FANUC's world frame) and tool frame numbers the program runs in, and that
    ``rewrite`` corrects positions of; program: the program name (None: the output file's
    stem); joint_percent: the speed of the joint moves between holes (%); cnt: their
    termination (CNT 0..100); spindle: the digital output switching the spindle (DO); decimals
    of positions (mm)."""

    robot_T_uframe: np.ndarray
    uframe: int
    utool: int
    program: str | None = None
    joint_percent: int = 50
    cnt: int = 50
    spindle: int = 1
    decimals: int = 3
    problem: InputError | None = None  # a frame number FANUC has not, located in the cell

    def check(self) -> FanucSection:
        """This section, InputError (at the cell's key) when a frame number is one FANUC has
        not."""
        if self.problem is not None:
            raise self.problem
        return self


def read_section(r: CellReader, robot_T_base: np.ndarray) -> FanucSection:
    """The FANUC record of the cell ``r`` reads (the user frame is the cell's base frame,
    ``robot_T_base``); InputError naming the key and line. Every cell is read by every dialect:
    a base or tool number FANUC has not, or an approach speed or feed that is no whole number
    of mm/sec, is kept as the located error ``problem`` raises when the cell drives a FANUC
    program."""
    numbers = []
    problem = None
    for key, limit, what in (("base", UFRAME_MAX, "user"), ("tool", UTOOL_MAX, "tool")):
        frame = r.top.get(key)
        number = frame.get("number") if isinstance(frame, dict) else None
        numbers.append(number if isinstance(number, int) else 0)
        if problem is None and not (isinstance(number, int) and 1 <= number <= limit):
            problem = r.error(
                f"{key}.number",
                f"is the FANUC {what} frame of the program: 1..{limit}, got {number}",
            )
    for key in ("approach", "feed"):  # the cell's own (the cell reader checks their range)
        speed = r.top.get("speeds", {}).get(key) if isinstance(r.top.get("speeds"), dict) else None
        if problem is None and isinstance(speed, (int, float)) and not _whole(speed):
            problem = r.error(f"speeds.{key}", f"{WHOLE_SPEED}, got {speed}")
    program = r.value("fanuc", "program", None)
    if program is not None:
        why = program_name_problem(program) if isinstance(program, str) else "must be a name"
        if why:
            raise r.error("fanuc.program", f"{why}, got {program!r}")
    return FanucSection(
        robot_T_uframe=robot_T_base,
        uframe=numbers[0],
        utool=numbers[1],
        program=None if program is None else program.upper(),
        joint_percent=r.integer("fanuc", "joint_percent", 50, 1, 100),
        cnt=r.integer("fanuc", "cnt", 50, 0, 100),
        spindle=r.integer("fanuc", "spindle", 1, 1, 4096),
        decimals=r.integer("program", "decimals", 3, 1, 6),
        problem=problem,
    )


def _whole(mm_s: float) -> bool:
    """Whether a linear speed (mm/s) is one a TP motion takes: a whole number of mm/sec."""
    return float(mm_s).is_integer() and mm_s >= 1
