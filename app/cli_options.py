"""Command-line options shared by several ``accugrid`` subcommands (same flags, same units).

Each ``add_*`` takes the command's own help text, so ``--help`` still says what the option means
for that command; ``robot_with_tool`` turns ``--robot``/``--tool`` values into a Robot.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from accugrid.compensation.plans import SEED_ABC, SEED_CENTRES, SEED_REPEATS
from accugrid.infra.csvtable import (
    DECIMALS,
    DELIMITERS,
    TableFormat,
    read_table_format,
    reading_as,
)
from accugrid.infra.errors import InputError
from accugrid.infra.units import unit_spec

if TYPE_CHECKING:
    from accugrid.app.jobs.program import ProgramRequest
    from accugrid.compensation.policy import PolicyRequest
    from accugrid.kinematics.identification import Terms
    from accugrid.kinematics.robot import Robot

__all__ = [
    "COORDINATE_MAX",
    "DEFAULT_ROBOT",
    "DEFAULT_TILT_DEG",
    "MAX_CANDIDATES",
    "MAX_COUNT",
    "MAX_POSES",
    "MAX_REPEATS",
    "OUTSIDE_WORDS",
    "add_abc",
    "add_deprecated",
    "add_experiment_arguments",
    "add_frame_number",
    "add_harmonics",
    "add_policy",
    "add_program_arguments",
    "add_robot",
    "add_status",
    "add_table_format",
    "add_tilt",
    "add_tool",
    "harmonics_of",
    "number",
    "parse_centres",
    "parse_steps",
    "policy_request",
    "program_request",
    "reading_format",
    "robot_with_tool",
]


COORDINATE_MAX = 1e6  # |mm| of a coordinate, |deg| of an angle given on the command line
MAX_CANDIDATES = 100_000  # random candidate poses of a pose plan (each is an IK and a Jacobian)
MAX_POSES = 1000  # poses of an identification plan: choosing them grows with poses x candidates
MAX_REPEATS = 1000  # measurements of each point or pose (the seed takes 5)
MAX_COUNT = 100_000  # held-out targets, validation points
DEFAULT_ROBOT = "kr210-paper"  # every command whose --robot may be left out: the seed's arm
DEFAULT_TILT_DEG = 25.0  # --tilt of identification poses, planned or simulated
OUTSIDE_WORDS = {"refuse": "error", "clamp": "clamp"}  # --outside -> CorrectionSettings.outside


def number(
    unit: str,
    lo: float | None = None,
    hi: float | None = None,
    above: bool = False,
    whole: bool = False,
) -> Callable[[str], float]:
    """The argparse ``type`` of every number option: a finite number (``whole``: an integer) in
    [lo, hi] (``above``: lo excluded), ``unit`` (mm, deg, s, ...; "" for counts) in its
    messages; argparse turns the refusal into exit 2 naming the option. -0 reads as 0."""
    said = f" {unit}" if unit else ""

    def parse(text: str) -> float:
        try:
            value = int(text, 10) if whole else float(text)
        except ValueError:
            kind = "a whole number" if whole else "a number"
            raise argparse.ArgumentTypeError(
                f"'{text}' is not {kind}{unit and f' ({unit})'}"
            ) from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(
                f"'{text}' is not a finite number{unit and f' ({unit})'}"
            )
        if lo is not None and (value <= lo if above else value < lo):
            raise argparse.ArgumentTypeError(
                f"'{text}' must be {'>' if above else '>='} {lo:g}{said}"
            )
        if hi is not None and value > hi:
            raise argparse.ArgumentTypeError(f"'{text}' must be <= {hi:g}{said}")
        return value if whole else value + 0.0

    parse.unit = unit  # type: ignore[attr-defined]  # what --help must name (tests check it)
    return parse


class _Deprecated(argparse.Action):
    """An old spelling kept for one release, said once on stderr: an old option (``new``: the
    one to use; ``convert`` maps its value, e.g. m/s to mm/s) or, with ``old_values``, old values
    of a current option (old -> new word)."""

    def __init__(self, option_strings, dest, new="", convert=None, old_values=None, **kwargs):
        super().__init__(option_strings, dest, **kwargs)
        self.new, self.convert, self.old_values = new, convert, old_values

    def __call__(self, parser, namespace, values, option_string=None):
        said = f"{option_string} {_words(values)}"
        if self.old_values is None:
            values = values if self.convert is None else self.convert(values)
            instead = f"{self.new} {_words(values)}"
        elif values in self.old_values:
            values = self.old_values[values]
            instead = f"{option_string} {values}"
        else:
            setattr(namespace, self.dest, values)
            return
        print(f"{parser.prog}: warning: {said} is deprecated, use {instead}", file=sys.stderr)
        setattr(namespace, self.dest, values)


def _words(value: object) -> str:
    """An option's value as typed: numbers as %g, lists space-separated."""
    if isinstance(value, list | tuple):
        return " ".join(_words(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def add_deprecated(
    parser: argparse.ArgumentParser | argparse._MutuallyExclusiveGroup,
    old: str,
    new: str,
    dest: str,
    convert: Callable[[object], object] | None = None,
    **kwargs,
) -> None:
    """``old``, the former spelling of option ``new`` (stored in ``dest``, through ``convert``),
    accepted for one release with a deprecation line on stderr and left out of --help;
    ``kwargs`` as ``add_argument``'s (nargs, type, ...)."""
    parser.add_argument(
        old,
        dest=dest,
        action=_Deprecated,
        new=new,
        convert=convert,
        help=argparse.SUPPRESS,
        **kwargs,
    )


def add_robot(parser: argparse.ArgumentParser, help_text: str, required: bool = False) -> None:
    """``--robot ROBOT``: a built-in robot (``kinematics.robot.BUILTIN``, listed in --help) or a
    robot YAML file; default ``DEFAULT_ROBOT`` unless ``required``."""
    from accugrid.kinematics.robot import BUILTIN  # only the commands that drive a robot

    default = "" if required else f" (default: {DEFAULT_ROBOT})"
    parser.add_argument(
        "--robot",
        required=required,
        default=None if required else DEFAULT_ROBOT,
        metavar="ROBOT",
        help=f"{help_text}: built-in {', '.join(BUILTIN)} or a robot YAML file{default}",
    )


def add_tilt(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--tilt DEG``: identification poses tilted up to DEG from --abc (default
    ``DEFAULT_TILT_DEG``)."""
    parser.add_argument(
        "--tilt",
        type=number("deg", 0, 180),
        default=DEFAULT_TILT_DEG,
        metavar="DEG",
        help=f"{help_text}, deg (default: {DEFAULT_TILT_DEG:g})",
    )


def add_abc(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--abc A B C``: a fixed TCP orientation, KUKA ABC in deg (default: the seed's 0 90 0)."""
    parser.add_argument(
        "--abc",
        nargs=3,
        type=number("deg", -COORDINATE_MAX, COORDINATE_MAX),
        default=list(SEED_ABC),
        metavar=("A", "B", "C"),
        help=f"{help_text}, KUKA A B C in deg (default: 0 90 0)",
    )


def add_tool(parser: argparse.ArgumentParser, help_text: str, default: str = "the flange") -> None:
    """``--tool X Y Z A B C``: flange_T_tool in mm and deg (default: None, said as ``default``)."""
    parser.add_argument(
        "--tool",
        nargs=6,
        type=number("mm or deg", -COORDINATE_MAX, COORDINATE_MAX),
        metavar=("X", "Y", "Z", "A", "B", "C"),
        help=f"{help_text}: flange_T_tool, X Y Z in mm and A B C in deg (default: {default})",
    )


def add_frame_number(parser: argparse.ArgumentParser, what: str) -> None:
    """``--number N``: the controller's ``what`` number (1..32) its printed lines set."""
    parser.add_argument(
        "--number",
        type=number("", 1, 32, whole=True),
        default=1,
        metavar="N",
        help=f"the {what} number of the printed controller lines (default 1)",
    )


def add_status(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--status S``: one KUKA Status 0..7 (default: None, the command's documented choice)."""
    parser.add_argument("--status", type=int, choices=range(8), metavar="S", help=help_text)


def add_harmonics(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--harmonics A2:1,7,160 A3:7 ...``: reducer harmonic orders per axis, each word parsed
    into (axis 1..6, order) pairs (default: none); ``harmonics_of`` gives the terms."""
    parser.add_argument(
        "--harmonics",
        nargs="+",
        type=_axis_orders,
        default=[],
        metavar="AN:K[,K...]",
        help=f"{help_text}; e.g. A2:1,7,160 A3:1,7 (axis 1..6, orders >= 1)",
    )


def harmonics_of(args: argparse.Namespace) -> Terms:
    """The reducer harmonic terms of ``--harmonics``, all words together, checked once more as
    a whole (duplicates dropped, at most ``MAX_HARMONICS``)."""
    from accugrid.kinematics.identification import harmonic_terms  # only the model commands

    return harmonic_terms(pair for pairs in args.harmonics for pair in pairs)


def _axis_orders(text: str) -> Terms:
    """'A2:1,7,160' -> ((2, 1), (2, 7), (2, 160)), ranges checked by ``harmonic_terms``;
    argparse turns the ArgumentTypeError into exit 2."""
    from accugrid.kinematics.identification import harmonic_terms

    axis, sep, orders = text.strip().upper().partition(":")
    try:
        if not sep or not axis.startswith("A"):
            raise ValueError
        number = int(axis[1:])
        return harmonic_terms((number, int(k)) for k in orders.split(","))
    except InputError as error:  # a ValueError too: first
        raise argparse.ArgumentTypeError(f"'{text}': {error.message}") from None
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not AXIS:ORDERS such as A2:1,7,160"
        ) from None


def robot_with_tool(name: str, tool: Sequence[float] | None) -> Robot:
    """``load_robot(name)`` carrying the ``--tool`` pose (mm, deg) when one was given."""
    from accugrid.kinematics.frames import pose_from_xyzabc
    from accugrid.kinematics.robot import load_robot  # only the commands that drive a robot

    robot = load_robot(name)
    if tool is not None:
        robot = robot.with_tool(pose_from_xyzabc(np.array(tool, dtype=float)))
    return robot


def add_experiment_arguments(parser: argparse.ArgumentParser) -> None:
    """--centre/--steps/--repeats as shared by `plan experiment` and `study`."""
    parser.add_argument(
        "--centre",
        nargs=4,
        action="append",
        metavar=("NAME", "X", "Y", "Z"),
        help="a cube centre, mm; repeat for more (default: seed Table 3, D 1700 0 1500, "
        "E 2000 -350 1800, F 1400 350 1900, G 1400 -350 1400, H 2000 350 1400)",
    )
    parser.add_argument(
        "--steps",
        default="20:500:60",
        help="cube steps in mm: FIRST:LAST:INCREMENT or a comma list (default: 20:500:60)",
    )
    parser.add_argument(
        "--repeats",
        type=number("", 1, MAX_REPEATS, whole=True),
        default=SEED_REPEATS,
        help=f"measurements of every point (default: {SEED_REPEATS})",
    )


def parse_steps(text: str) -> np.ndarray:
    """Steps in mm from "FIRST:LAST:INCREMENT" (inclusive) or "S1,S2,..."."""
    try:
        if ":" in text:
            first, last, inc = (float(v) for v in text.split(":"))
            if inc <= 0 or last < first:
                raise ValueError
            steps = np.arange(first, last + 1e-9 * max(1.0, abs(last)), inc)
        else:
            steps = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(
            f"--steps {text!r}: use FIRST:LAST:INCREMENT (increment > 0) or a comma list of mm"
        ) from None
    if not np.all(np.isfinite(steps)) or np.any(steps <= 0):
        raise InputError(f"--steps {text!r}: steps must be finite and > 0 mm")
    return steps


def parse_centres(items: list[list[str]] | None) -> dict[str, tuple[float, float, float]]:
    """--centre NAME X Y Z options (None: the seed's D-H)."""
    if not items:
        return dict(SEED_CENTRES)
    centres: dict[str, tuple[float, float, float]] = {}
    for name, *xyz in items:
        try:
            point = tuple(float(v) for v in xyz)
        except ValueError:
            raise InputError(f"--centre {name}: X Y Z must be numbers (mm), got {xyz}") from None
        if name in centres:
            raise InputError(f"--centre {name} given twice")
        centres[name] = point
    return centres


def add_policy(parser: argparse.ArgumentParser, what: str) -> None:
    """The options of the correction policy (``compensation.policy.PolicyRequest``), the same in
    every command that corrects: ``--allow-partial``, ``--strict``, ``--outside`` (a word of
    ``OUTSIDE_WORDS``; ``error``: its former spelling of refuse) and the orientation against the
    grid's (``--orientation-tol``, ``--orientation-limit``, ``--allow-orientation``); ``what``
    names the command's positions. ``policy_request`` gives the record."""
    from accugrid.compensation.policy import GRID_ORIENTATION_TOL_DEG, ORIENTATION_LIMIT_DEG

    parser.add_argument(
        "--allow-partial",
        action="store_true",
        help=f"write the job although some {what} cannot be corrected (outside the grid, "
        "orientation or Status the grid does not hold for, unreachable): they are left as "
        "they are, counted by reason on stderr and marked (default: refuse the job, exit 2)",
    )
    parser.add_argument(
        "--strict",
        action="store_true",
        help=f"with a model: refuse {what} outside the poses it was identified from (region, "
        "tool tilt, joint ranges) or without its support among them (far from every "
        "calibration pose in joint space, or of high prediction leverage) instead of flagging "
        "them (the latter corrected by the DH-only fit of the same poses)",
    )
    parser.add_argument(
        "--outside",
        choices=[*OUTSIDE_WORDS, "error"],
        default="refuse",
        action=_Deprecated,
        old_values={"error": "refuse"},
        metavar="{refuse,clamp}",
        help=f"{what} outside the grid box: refuse, i.e. not corrected (the job is refused "
        "unless --allow-partial), or clamp: the nearest cell's error, flagged (default: refuse)",
    )
    parser.add_argument(
        "--orientation-tol",
        type=number("deg", 0, 180),
        default=GRID_ORIENTATION_TOL_DEG,
        metavar="DEG",
        help=f"flag {what} whose orientation differs from the grid's by more, deg "
        f"(default: {GRID_ORIENTATION_TOL_DEG:g})",
    )
    parser.add_argument(
        "--orientation-limit",
        type=number("deg", 0, 180),
        default=ORIENTATION_LIMIT_DEG,
        metavar="DEG",
        help=f"without a model: {what} whose orientation differs from the grid's by more are "
        "not corrected (the job is refused unless --allow-partial), deg "
        f"(default: {ORIENTATION_LIMIT_DEG:g})",
    )
    parser.add_argument(
        "--allow-orientation",
        action="store_true",
        help=f"correct (and flag) {what} beyond --orientation-limit",
    )
    parser.add_argument(
        "--max-u95",
        type=number("mm", 0, 1000, above=True),
        metavar="MM",
        help=f"flag {what} whose error budget's 95 percent bound (u95_mm: the calibrated model, "
        "the residual grid, the measured tool and part frame) exceeds this, mm; the job is "
        "refused unless --allow-partial, which writes them corrected and flagged (default: none)",
    )


def policy_request(args: argparse.Namespace) -> PolicyRequest:
    """The policy's options of a command's arguments (``add_policy``)."""
    from accugrid.compensation.policy import PolicyRequest

    return PolicyRequest(
        outside=OUTSIDE_WORDS[args.outside],
        orientation_tol_deg=args.orientation_tol,
        orientation_limit_deg=args.orientation_limit,
        allow_orientation=args.allow_orientation,
        strict=args.strict,
        allow_partial=args.allow_partial,
        max_u95_mm=args.max_u95,
    )


def add_table_format(parser: argparse.ArgumentParser) -> None:
    """How the position files of the command are written (tracker exports as they come):
    ``--format``, ``--columns``, ``--units``, ``--delimiter``, ``--decimal``; see
    ``reading_format``."""
    group = parser.add_argument_group("position files as exported (docs/tracker_files.md)")
    group.add_argument(
        "--format",
        metavar="FORMAT.yaml",
        help="a YAML file saying once how a tracker's export is written (keys columns, units, "
        "delimiter, decimal, with the values of these options); an option on the command line "
        "wins over its key",
    )
    group.add_argument(
        "--columns",
        type=_column_mapping,
        metavar="NAME=HEADER,...",
        help="read the file column HEADER as accugrid's NAME, in every CSV of this command that "
        "has one of the HEADERs, e.g. x=X_nom,y=Y_nom,z=Z_nom,x_meas=X_act,y_meas=Y_act,"
        "z_meas=Z_act; a1..a6 for logged joints; a=YAW,b=PITCH,c=ROLL for a fixed x-y-z "
        "roll-pitch-yaw (the same rotation as KUKA ABC); header names are case-insensitive",
    )
    group.add_argument(
        "--units",
        type=_unit_spec,
        metavar="UNIT,...",
        help="units of the files --columns applies to (without --columns: of every CSV of this "
        "command): a length unit (mm, m, in) for every length column (x,y,z, x_meas..z_meas, "
        "diameter, depth), an angle unit (deg, rad) for every angle column (a,b,c, a1..a6), "
        "NAME=UNIT for one column, e.g. m,rad,x_meas=mm,y_meas=mm,z_meas=mm; converted to mm "
        "and deg on read (default: the unit a header names, x [m], X (in), x_mm; else mm, deg)",
    )
    group.add_argument(
        "--delimiter",
        choices=list(DELIMITERS),
        help="column delimiter of the export (default: found from the header and the first "
        "rows; a file whose header does not hold it is read as found)",
    )
    group.add_argument(
        "--decimal",
        choices=list(DECIMALS),
        help="decimal mark of the export (default: found; a comma-separated file always has a "
        "decimal point)",
    )


def _unit_spec(text: str) -> str:
    """``--units``' text, checked by ``infra.units.unit_spec`` (argparse: exit 2 naming it)."""
    try:
        unit_spec(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def _column_mapping(text: str) -> dict[str, str]:
    mapping: dict[str, str] = {}
    for item in text.split(","):
        name, sep, header = (part.strip() for part in item.partition("="))
        if not sep or not name or not header:
            raise argparse.ArgumentTypeError(f"{item.strip()!r} is not NAME=HEADER")
        if name.lower() in mapping:
            raise argparse.ArgumentTypeError(f"{name} is mapped twice")
        mapping[name.lower()] = header
    if len({h.lower() for h in mapping.values()}) != len(mapping):
        raise argparse.ArgumentTypeError("one HEADER is mapped to two names")
    return mapping


def reading_format(args: argparse.Namespace) -> AbstractContextManager[None]:
    """The block in which every CSV the command reads is read as ``add_table_format``'s
    options say (over the keys of ``--format``'s file)."""
    saved = read_table_format(args.format) if args.format else TableFormat()
    return reading_as(
        TableFormat(
            delimiter=DELIMITERS.get(args.delimiter or "", saved.delimiter),
            decimal=DECIMALS.get(args.decimal or "", saved.decimal),
            columns=args.columns if args.columns is not None else saved.columns,
            units=args.units if args.units is not None else saved.units,
        )
    )


def add_program_arguments(
    parser: argparse.ArgumentParser, dialect: str, output_metavar: str, output: str
) -> None:
    """The options of the program command of ``dialect`` (``commands.program``); ``-o`` with the
    command's metavar and help."""
    parser.add_argument("points", metavar="POINTS", help="drilling points CSV (BASE frame, mm)")
    parser.add_argument("--cell", required=True, metavar="CELL", help="cell YAML file")
    parser.add_argument(
        "--grid",
        metavar="MEAS",
        help="grid measurement CSV (robot frame, mm); overrides the cell file's grid",
    )
    parser.add_argument(
        "--model",
        metavar="CAL",
        help="calibrated robot YAML (accugrid identify): correct by the model, the grid (if any) "
        "then holds its residual; overrides the cell file's correction.model",
    )
    parser.add_argument(
        "--no-correction",
        action="store_true",
        help="write the nominal (uncorrected) program; no grid is read",
    )
    parser.add_argument(
        "--allow-config-change",
        action="store_true",
        help="let a hole that cannot reach the program's KUKA Status take another one "
        "(same as configuration.allow_change in the cell file)",
    )
    parser.add_argument(
        "--templates",
        metavar="DIR",
        help="folder with your copies of the templates (a copy of templates/ or of its "
        f"{dialect}/ folder)",
    )
    add_policy(parser, "holes")
    parser.add_argument(
        "--report-html",
        metavar="FILE",
        help="also write the self-contained HTML report (inputs with SHA-256, a map of the "
        "corrections, the holes flagged or not corrected with the reasons)",
    )
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")
    add_table_format(parser)
    parser.add_argument("-o", "--output", required=True, metavar=output_metavar, help=output)


def program_request(args: argparse.Namespace, dialect: str, title: str) -> ProgramRequest:
    """The request of a program command's arguments (``add_program_arguments``); ``title``: the
    HTML report's."""
    from accugrid.app.jobs.program import ProgramRequest

    return ProgramRequest(
        dialect=dialect,
        points=args.points,
        cell=args.cell,
        output=Path(args.output),
        grid=args.grid,
        model=args.model,
        no_correction=args.no_correction,
        allow_config_change=args.allow_config_change,
        templates=args.templates,
        policy=policy_request(args),
        report_html=Path(args.report_html) if args.report_html else None,
        report_title=title,
    )
