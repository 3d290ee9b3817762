"""Shared by the rewrite tests: a synthetic measurement grid and a cell file in a temp folder.

The error field is known, so tests can check the applied corrections without trusting the code
under test: ``field="constant"`` gives e = E_CONST everywhere (IDW of equal vertex errors is that
constant), ``field="smooth"`` a linear field that IDW reproduces only approximately.
"""

from __future__ import annotations

import difflib
import re
from pathlib import Path

import numpy as np

E_CONST = np.array([0.25, -0.125, 0.375])  # mm, e = P - M


def error_field(points: np.ndarray, field: str) -> np.ndarray:
    """e(P) (N, 3) mm."""
    if field == "constant":
        return np.tile(E_CONST, (len(points), 1))
    if field == "too_long":  # beyond the default 5 mm safety limit
        return np.tile([6.0, 0.0, 0.0], (len(points), 1))
    x, y, z = points.T
    return np.stack([0.2 + 1e-4 * x, -0.1 + 2e-4 * z, 0.3 - 1e-4 * y], axis=1)


def write_grid(
    path: Path,
    lower=(-1500, -1500, -500),
    upper=(2500, 1500, 2000),
    step=250.0,
    field="smooth",
    abc=None,
) -> Path:
    """A complete measurement CSV (id,x,y,z[,a,b,c],x_meas,y_meas,z_meas) with M = P - e(P);
    ``abc``: the TCP orientation (KUKA A, B, C deg) the grid was measured at."""
    axes = [np.arange(lo, hi + step / 2, step) for lo, hi in zip(lower, upper, strict=True)]
    commanded = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    measured = commanded - error_field(commanded, field)
    rows = ["id,x,y,z," + ("a,b,c," if abc is not None else "") + "x_meas,y_meas,z_meas"]
    for i, (p, m) in enumerate(zip(commanded, measured, strict=True)):
        values = (*p, *abc, *m) if abc is not None else (*p, *m)
        rows.append(f"{i}," + ",".join(f"{v:.4f}" for v in values))
    path.write_text("\n".join(rows) + "\n")
    return path


# ../shared/realworld programs and the options each is rewritten with, in the cell
# write_cell(folder, base_data=REALWORLD_BASE_DATA): case -> (paths under realworld, options)
REALWORLD_BASE_DATA = {11: (1200, -300, 700, 30, 0, 0)}
REALWORLD_REWRITES = {
    "robodk": (["krl/robodk_Program.src"], []),
    "xpoints_alone": (["krl/chinamilling_xPoints.dat"], ["--base", "0"]),
    "xpoints_no_base": (["krl/chinamilling_xPoints.dat"], []),
    "st1_st2_pair": (
        ["krl/chinamilling_st1_st2.src", "krl/chinamilling_xPoints.dat"],
        ["--ignore-external-axes"],
    ),
    "job1_side1": (
        ["krl/chinamilling_St1_Job1_Side1.src", "krl/chinamilling_St1_Job1_Side1.dat"],
        ["--base", "11", "--trust-calls"],
    ),
    "job1_side1_strict_rules": (
        ["krl/chinamilling_St1_Job1_Side1.src", "krl/chinamilling_St1_Job1_Side1.dat"],
        [],
    ),
    "sample_program": (
        ["krl/kukakrlmagic_sample_program.src", "krl/kukakrlmagic_sample_program.dat"],
        ["--base", "0"],
    ),
    "cnc_struc": (
        ["krl/chinamilling_CNC_LOOP.src", "krl/chinamilling_CNC1.dat"],
        ["--base", "0"],
    ),
    "heatsink": (["gcode/norn93_1_heatsink_drill.gcode"], ["--decimals", "3"]),
    "example3_inch": (["gcode/printhor_example3_inch.gcode"], []),
    "lagun_parameters": (["gcode/lagun_HEMA-P005.cnc"], []),
    "my100_inch": (["gcode/my100_MidLeftRightRail-Drill.125in.nc"], []),
    "drill_practice": (["gcode/norn93_drill_practice.gcode"], []),
    "vertical_slot": (["gcode/pygcode_vertical-slot.ngc"], []),
}


RAPID_BASE = (400.0, -250.0, 300.0, 30.0, 10.0, -20.0)  # the RAPID cell's base (wobj), mm, deg
# ../shared/realworld/rapid programs -> the rapid.tool and rapid.wobj of the cell each is
# rewritten in (write_rapid_cell): a tool and a work object the program moves with
REALWORLD_RAPID = {
    "robodk_Program.mod": ("Tool", "Frame2"),
    "harshbhatt99_Module1.mod": ("TCPMarker", "WobjWhiteboard"),
    "juanlopezp_Module1.mod": ("TVentosa", "WO"),
    "edgarivanmm_MainModule.modx": ("gripperIvan", "wobjMesa"),
    "rparak_Module1.mod": ("tool0", "wobjX"),
    "mcoffman1_AA_example_script.mod": ("INST_tool", "INST_workobject"),
    "mjkkirschner_test02_001.prg": ("drill", "block"),
    "zwj12_WeldTestModule.mod": ("toolWeldGun", "wobjX"),
    "kangoananya_iGPS_SC_Acc_Exp.mod": ("tool0", "wobjX"),
    "kangoananya_user.sys": ("tool0", "wobjX"),
    "taeyangshim-stack_user.sys": ("tool0", "wobjX"),
    "bhomaidan1990_currLeft.mod": ("tool0", "wobjX"),
}


def write_rapid_cell(folder: Path, tool: str, wobj: str) -> Path:
    """cell.yaml of an IRB 6700 with a constant error field over +-6 m, base ``RAPID_BASE`` and
    the RAPID names of its tool and work object."""
    write_grid(folder / "grid.csv", (-6000,) * 3, (6000,) * 3, 3000.0, field="constant")
    x, y, z, a, b, c = RAPID_BASE
    (folder / "cell.yaml").write_text(
        "robot: irb6700\ngrid: grid.csv\ntool: {number: 1, x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}\n"
        f"base: {{number: 1, x: {x}, y: {y}, z: {z}, a: {a}, b: {b}, c: {c}}}\n"
        f"rapid: {{tool: {tool}, wobj: {wobj}}}\n"
    )
    return folder / "cell.yaml"


def write_cell(folder: Path, field="smooth", base_data=None, program_frame=None, **grid) -> Path:
    """cell.yaml + grid.csv in ``folder``; base 1 = robot frame unless ``base_data`` says more.

    ``base_data``: {n: (x, y, z, a, b, c)}; number 1 is the cell's ``base``.
    """
    write_grid(folder / "grid.csv", field=field, **grid)
    base_data = dict(base_data or {})
    base1 = base_data.pop(1, (0, 0, 0, 0, 0, 0))
    lines = [
        "robot: kr210",
        "grid: grid.csv",
        "tool: {number: 1, x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}",
        "base: {number: 1, " + _frame(base1) + "}",
    ]
    if base_data:
        lines.append("base_data:")
        lines += [f"  {n}: {{{_frame(f)}}}" for n, f in base_data.items()]
    if program_frame is not None:
        lines.append("program_frame: {" + _frame(program_frame) + "}")
    cell = folder / "cell.yaml"
    cell.write_text("\n".join(lines) + "\n")
    return cell


def _frame(f) -> str:
    return ", ".join(f"{k}: {v}" for k, v in zip("xyzabc", f, strict=True))


def const_model():
    """A grid model over +-600 mm whose error is E_CONST everywhere (corrected = P + E_CONST)."""
    from accugrid.compensation import GridModel

    axes = [np.arange(-600.0, 601.0, 300.0)] * 3
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return GridModel.from_measurements((pts, pts - E_CONST))


def rewrite_gcode(path: str, text: str, opts, robot_T_program: np.ndarray | None = None):
    """One G-code program rewritten through its plug-in, in the program frame (default: the
    robot frame)."""
    from accugrid.codegen.dialects import plugin_of
    from accugrid.codegen.gcode.section import GcodeSection
    from accugrid.codegen.rewrite import rewrite

    frame = np.eye(4) if robot_T_program is None else robot_T_program
    return rewrite(plugin_of("gcode"), {path: text}, opts, GcodeSection(frame))


def rewrite_krl(texts: dict[str, str], opts, base_data: dict | None = None):
    """KRL files (path -> text) rewritten through their plug-in with BASE_DATA ``base_data``."""
    from accugrid.codegen.dialects import plugin_of
    from accugrid.codegen.krl.rewrite import KrlPlacement
    from accugrid.codegen.rewrite import rewrite

    return rewrite(plugin_of("krl"), texts, opts, KrlPlacement(base_data or {}))


TOKEN = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?|\s+|[^\d\s.+-]+|.", re.S)
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?$")
ADDED = re.compile(r"(?: ?[ZzRr][-+]?(?:\d+\.\d*|\.\d+|\d+) ?)+")  # words a rewrite may add


def changed_lines(before: str, after: str, added_words: bool = False) -> set[int]:
    """Lines whose numbers differ; fails when anything but a number differs, except (with
    ``added_words``) ` Z<number>` / ` R<number>` words added to a line (G-code cycles)."""
    old_lines, new_lines = before.split("\n"), after.split("\n")
    assert len(old_lines) == len(new_lines), "line count changed"
    lines = set()
    for number, (x, y) in enumerate(zip(old_lines, new_lines, strict=True), start=1):
        if x == y:
            continue
        a, b = TOKEN.findall(x), TOKEN.findall(y)
        for op, i1, i2, j1, j2 in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
            if op == "equal":
                continue
            old, new = a[i1:i2], b[j1:j2]
            assert len(new) >= len(old), (old, new)
            for ta, tb in zip(old, new[: len(old)], strict=True):
                assert NUMBER.match(ta) and NUMBER.match(tb), (ta, tb)
            extra = "".join(new[len(old) :])
            assert not extra or (added_words and ADDED.fullmatch(extra)), extra
        lines.add(number)
    return lines
