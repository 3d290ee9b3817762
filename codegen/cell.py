"""The cell file: robot, grid, tool, base frames and the drilling process, as YAML.

Read with ``kinematics.yamlfile.load_yaml``; every key is validated and an error names the key
(``tool.z``) with its file line. Paths in the file are relative to the file. Lengths mm, angles
deg, speeds mm/s, times s. The commented reference is ``examples/cell.yaml``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from accugrid.codegen.textsafe import KRL_RESERVED
from accugrid.compensation.interpolation import METHODS
from accugrid.compensation.settings import CorrectionSettings
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.yamlfile import YamlDoc, load_yaml

__all__ = ["ANGLE_MAX_DEG", "DISTANCE_MAX_MM", "FRAME_MAX_MM", "Cell", "load_cell"]

_FRAME_KEYS = ("x", "y", "z", "a", "b", "c")
# Bounds on every length and angle a program can carry (speeds, times and counts have their own)
FRAME_MAX_MM = 1e6  # |x|, |y|, |z| of a frame, external axis positions
ANGLE_MAX_DEG = 360.0  # |a|, |b|, |c|
DISTANCE_MAX_MM = 1e4  # approach, clearance, retract, depth, peck, apo_cdis
_TOP_KEYS = {
    "robot",
    "grid",
    "tool",
    "base",
    "base_data",
    "program_frame",
    "program",
    "speeds",
    "drilling",
    "outputs",
    "configuration",
    "correction",
    "gcode",
    "external_axes",
}


@dataclass(frozen=True)
class Cell:
    """A validated cell file. Poses are (4, 4) homogeneous transforms in mm."""

    path: Path
    robot_name: str
    grid_path: Path | None
    model_path: Path | None  # correction.model: a calibrated robot YAML (accugrid identify)
    tool_number: int
    flange_T_tool: np.ndarray
    base_number: int
    robot_T_base: np.ndarray
    base_data: dict[int, np.ndarray]
    robot_T_program: np.ndarray
    # program
    program_name: str = "ACCUGRID"
    lines_per_file: int = 5000
    decimals: int = 3
    # speeds (mm/s) and motion
    travel_mm_s: float = 500.0
    approach_mm_s: float = 50.0
    feed_mm_s: float = 5.0
    ptp_percent: float = 50.0
    travel_motion: str = "ptp"
    apo_cdis_mm: float = 5.0
    apo_ptp_percent: float = 50.0
    # drilling (mm along the drill axis, s)
    approach_mm: float = 30.0
    clearance_mm: float = 2.0
    retract_mm: float = 30.0
    depth_mm: float = 10.0
    dwell_s: float = 0.5
    peck_mm: float = 0.0
    # outputs
    spindle_output: int = 1
    clamp_output: int | None = None
    # robot configuration
    status: int | None = None
    turn: int | None = None
    allow_config_change: bool = False
    singular_a5_deg: float = 5.0
    reference_abc: tuple[float, float, float] = (0.0, 90.0, 0.0)
    # correction (method, power, iterations; the safety limit is the default)
    correction: CorrectionSettings = CorrectionSettings()
    # G-code
    spindle_rpm: float = 6000.0
    canned_cycles: bool = True
    external_axes: tuple[float, ...] = field(default=(0.0,) * 6)
    sha256: str = ""

    def grid_file(self, override: str | os.PathLike[str] | None = None, hint: str = "") -> Path:
        """The measurement to correct with: ``override`` (--grid), else the cell's ``grid``;
        InputError when there is neither (``hint`` completes the message)."""
        if override is not None:
            return Path(override)
        if self.grid_path is None:
            raise InputError(
                f"no grid: name one in the cell file (grid:), give --grid{hint}", self.path
            )
        return self.grid_path


def load_cell(path: str | os.PathLike[str]) -> Cell:
    """Read and validate a cell YAML file; InputError naming the key and line on any problem."""
    path = Path(path)
    doc = load_yaml(path)
    return _Reader(path, doc).cell(doc.data, doc.sha256)


class _Reader:
    """Validation with key paths and YAML lines for the messages."""

    def __init__(self, path: Path, doc: YamlDoc) -> None:
        self.path = path
        self.doc = doc

    def error(self, key: str, message: str) -> InputError:
        return InputError(f"{key}: {message}", os.fspath(self.path), self.doc.line(*key.split(".")))

    # -- typed getters -------------------------------------------------------------------
    def mapping(self, data: object, key: str, allowed: set[str] | None = None) -> dict:
        if data is None:
            return {}
        if not isinstance(data, Mapping):
            raise self.error(key, f"must be a mapping, got {type(data).__name__}")
        if allowed is not None:
            for k in data:
                if str(k) not in allowed:
                    raise self.error(
                        f"{key}.{k}" if key else str(k),
                        f"unknown key (allowed: {', '.join(sorted(allowed))})",
                    )
        return {str(k): v for k, v in data.items()}

    def number(
        self,
        data: dict,
        name: str,
        key: str,
        default: float | None,
        lo=None,
        hi=None,
        strict_lo=False,
    ) -> float:
        full = f"{key}.{name}" if key else name
        value = data.get(name, default)
        if value is None:
            raise self.error(full, "is required")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(full, f"must be a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise self.error(full, "must be a finite number")
        if lo is not None and (value <= lo if strict_lo else value < lo):
            raise self.error(full, f"must be {'>' if strict_lo else '>='} {lo:g}, got {value:g}")
        if hi is not None and value > hi:
            raise self.error(full, f"must be <= {hi:g}, got {value:g}")
        return value

    def integer(self, data: dict, name: str, key: str, default, lo=None, hi=None, optional=False):
        full = f"{key}.{name}" if key else name
        value = data.get(name, default)
        if value is None:
            if optional:
                return None
            raise self.error(full, "is required")
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(full, f"must be an integer, got {value!r}")
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise self.error(full, f"must be between {lo} and {hi}, got {value}")
        return value

    def boolean(self, data: dict, name: str, key: str, default: bool) -> bool:
        value = data.get(name, default)
        if not isinstance(value, bool):
            raise self.error(f"{key}.{name}", f"must be true or false, got {value!r}")
        return value

    def frame(self, data: object, key: str, numbered: bool) -> tuple[int | None, np.ndarray]:
        allowed = set(_FRAME_KEYS) | ({"number"} if numbered else set())
        d = self.mapping(data, key, allowed)
        if not d:
            raise self.error(key, "is required (x, y, z in mm; a, b, c in deg)")
        number = self.integer(d, "number", key, None, 1, 32) if numbered else None
        xyzabc = [self.number(d, k, key, 0.0, -FRAME_MAX_MM, FRAME_MAX_MM) for k in "xyz"]
        xyzabc += [self.number(d, k, key, 0.0, -ANGLE_MAX_DEG, ANGLE_MAX_DEG) for k in "abc"]
        return number, pose_from_xyzabc(np.array(xyzabc))

    def abc(self, data: object, key: str, default: tuple) -> tuple[float, float, float]:
        if data is None:
            return default
        d = self.mapping(data, key, {"a", "b", "c"})
        return tuple(self.number(d, k, key, 0.0, -ANGLE_MAX_DEG, ANGLE_MAX_DEG) for k in "abc")

    # -- the file ------------------------------------------------------------------------
    def cell(self, data: object, sha256: str) -> Cell:
        top = self.mapping(data, "", _TOP_KEYS)
        if not top:
            raise InputError("empty cell file", os.fspath(self.path))
        robot = top.get("robot")
        if not isinstance(robot, str) or not robot.strip():
            raise self.error("robot", "is required: a built-in robot name or a robot YAML path")
        if robot.endswith((".yaml", ".yml")):
            robot = os.fspath(self.path.parent / robot)
        grid = top.get("grid")
        if grid is not None and (not isinstance(grid, str) or not grid.strip()):
            raise self.error("grid", "must be a file path")
        grid_path = None if grid is None else self.path.parent / grid
        tool_number, flange_T_tool = self.frame(top.get("tool"), "tool", True)
        base_number, robot_T_base = self.frame(top.get("base"), "base", True)
        base_data = {base_number: robot_T_base}
        for n, frame in self.mapping(top.get("base_data"), "base_data").items():
            try:
                number = int(n)
            except ValueError:
                raise self.error(f"base_data.{n}", "key must be a BASE_DATA number") from None
            if not 1 <= number <= 32:
                raise self.error(f"base_data.{n}", "BASE_DATA number must be 1..32")
            if number == base_number:
                raise self.error(f"base_data.{n}", "repeats base.number; define it in base")
            base_data[number] = self.frame(frame, f"base_data.{n}", False)[1]
        if top.get("program_frame") is None:
            robot_T_program = robot_T_base
        else:
            robot_T_program = self.frame(top["program_frame"], "program_frame", False)[1]

        prog = self.mapping(top.get("program"), "program", {"name", "lines_per_file", "decimals"})
        name = prog.get("name", "ACCUGRID")
        if not isinstance(name, str) or not _is_krl_name(name) or len(name) > 20:
            raise self.error(
                "program.name",
                "must be a KRL name: a letter or _, then letters, digits or _, at most 20 "
                f"characters (4 are kept for the sub-program suffix), not a KRL keyword, got "
                f"{name!r}",
            )
        sp = self.mapping(
            top.get("speeds"), "speeds", {"travel", "approach", "feed", "ptp_percent"}
        )
        dr = self.mapping(
            top.get("drilling"),
            "drilling",
            {
                "approach",
                "clearance",
                "retract",
                "depth",
                "dwell",
                "peck",
                "travel_motion",
                "apo_cdis",
                "apo_ptp_percent",
            },
        )
        motion = dr.get("travel_motion", "ptp")
        if motion not in ("ptp", "lin"):
            raise self.error("drilling.travel_motion", f"must be ptp or lin, got {motion!r}")
        out = self.mapping(top.get("outputs"), "outputs", {"spindle", "clamp"})
        cf = self.mapping(
            top.get("configuration"),
            "configuration",
            {"status", "turn", "allow_change", "singular_a5", "reference"},
        )
        co = self.mapping(
            top.get("correction"), "correction", {"method", "iterations", "power", "model"}
        )
        model = co.get("model")
        if model is not None and (not isinstance(model, str) or not model.strip()):
            raise self.error("correction.model", "must be a calibrated robot YAML path")
        model_path = None if model is None else self.path.parent / model
        method = co.get("method", "idw")
        if method not in METHODS:
            raise self.error("correction.method", f"must be {' or '.join(METHODS)}, got {method!r}")
        gc = self.mapping(top.get("gcode"), "gcode", {"spindle_rpm", "canned_cycles"})
        ext = self.mapping(
            top.get("external_axes"), "external_axes", {f"e{i}" for i in range(1, 7)}
        )
        approach = self.number(dr, "approach", "drilling", 30.0, 0.0, DISTANCE_MAX_MM, True)
        clearance = self.number(dr, "clearance", "drilling", 2.0, 0.0, DISTANCE_MAX_MM)
        if clearance >= approach:
            raise self.error(
                "drilling.clearance",
                f"must be smaller than drilling.approach ({approach:g} mm), got {clearance:g}",
            )
        return Cell(
            path=self.path,
            robot_name=robot,
            grid_path=grid_path,
            model_path=model_path,
            tool_number=tool_number,
            flange_T_tool=flange_T_tool,
            base_number=base_number,
            robot_T_base=robot_T_base,
            base_data=base_data,
            robot_T_program=robot_T_program,
            program_name=name,
            lines_per_file=self.integer(prog, "lines_per_file", "program", 5000, 50, 10**7),
            decimals=self.integer(prog, "decimals", "program", 3, 1, 6),
            travel_mm_s=self.number(sp, "travel", "speeds", 500.0, 0.0, 2000.0, True),
            approach_mm_s=self.number(sp, "approach", "speeds", 50.0, 0.0, 2000.0, True),
            feed_mm_s=self.number(sp, "feed", "speeds", 5.0, 0.0, 2000.0, True),
            ptp_percent=self.number(sp, "ptp_percent", "speeds", 50.0, 0.0, 100.0, True),
            travel_motion=motion,
            apo_cdis_mm=self.number(dr, "apo_cdis", "drilling", 5.0, 0.0, DISTANCE_MAX_MM),
            apo_ptp_percent=self.number(dr, "apo_ptp_percent", "drilling", 50.0, 0.0, 100.0),
            approach_mm=approach,
            clearance_mm=clearance,
            retract_mm=self.number(dr, "retract", "drilling", approach, 0.0, DISTANCE_MAX_MM, True),
            depth_mm=self.number(dr, "depth", "drilling", 10.0, 0.0, DISTANCE_MAX_MM, True),
            dwell_s=self.number(dr, "dwell", "drilling", 0.5, 0.0, 60.0),
            peck_mm=self.number(dr, "peck", "drilling", 0.0, 0.0, DISTANCE_MAX_MM),
            spindle_output=self.integer(out, "spindle", "outputs", 1, 1, 4096),
            clamp_output=self.integer(out, "clamp", "outputs", None, 1, 4096, optional=True),
            status=self.integer(cf, "status", "configuration", None, 0, 7, optional=True),
            turn=self.integer(cf, "turn", "configuration", None, 0, 63, optional=True),
            allow_config_change=self.boolean(cf, "allow_change", "configuration", False),
            singular_a5_deg=self.number(cf, "singular_a5", "configuration", 5.0, 0.0, 90.0),
            reference_abc=self.abc(
                cf.get("reference"), "configuration.reference", (0.0, 90.0, 0.0)
            ),
            correction=CorrectionSettings(
                method=method,
                iterations=self.integer(co, "iterations", "correction", 1, 1, 10),
                power=self.number(co, "power", "correction", 1.0, 0.0, 10.0, True),
            ),
            spindle_rpm=self.number(gc, "spindle_rpm", "gcode", 6000.0, 0.0, 10**6, True),
            canned_cycles=self.boolean(gc, "canned_cycles", "gcode", True),
            external_axes=tuple(
                self.number(ext, f"e{i}", "external_axes", 0.0, -FRAME_MAX_MM, FRAME_MAX_MM)
                for i in range(1, 7)
            ),
            sha256=sha256,
        )


def _is_krl_name(name: str) -> bool:
    return (
        bool(name)
        and name.upper() not in KRL_RESERVED
        and (name[0].isascii() and (name[0].isalpha() or name[0] == "_"))
        and all(ch.isascii() and (ch.isalnum() or ch == "_") for ch in name)
    )
