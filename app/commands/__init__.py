"""One module per ``accugrid`` subcommand (see ``app.cli``): ``NAME``,
``add_arguments(parser)`` and ``run(args) -> int``. A command parses its arguments, refuses
existing outputs (``atomic.check_targets``), calls one domain function (e.g.
``jobs.correct.correct_points``, ``jobs.plan.plan_files``), which returns the job's files
and the lines to print (``atomic.JobFiles``), writes them as one job (``atomic.write_files``)
and prints the lines.

``COMMANDS`` names them with their one-line help, so the parser (and ``accugrid --help``) is
built without importing any command module; only the command that runs is imported. One module,
``program``, serves a command per registered dialect (``codegen.dialects.DIALECTS``), named as
the dialect, its help from the dialect's plug-in; it gives each by ``command(name)``.
"""

from accugrid.codegen.dialects import DIALECTS, plugin_of

__all__ = ["COMMANDS"]

# NAME -> (module in this package, one-line help), besides the program commands
_COMMANDS: dict[str, tuple[str, str]] = {
    "compare": (
        "compare",
        "grid only vs model vs model + residual grid against the number of measured points",
    ),
    "correct": (
        "correct",
        "corrected points CSV: P' = P + e from a measured error grid and/or a calibrated model",
    ),
    "fit-frame": (
        "fit_frame",
        "robot base frame (tracker_T_robot) from tracker points on base, A1 arc and flange holes",
    ),
    "fit-part": (
        "fit_part",
        "part frame (robot_T_base) from datums measured by the tracker and their CAD coordinates",
    ),
    "identify": (
        "identify",
        "calibrated robot model (DH errors, TCP) from tracker measurements at scattered poses",
    ),
    "identify-tool": (
        "identify_tool",
        "the drill's TCP and axis measured on the calibrated arm (SMR at 6+ orientations)",
    ),
    "plan": (
        "plan",
        "measurement plans: grid, ISO 9283 cube, the seed's step experiment, identification poses",
    ),
    "rewrite": (
        "rewrite",
        "correct the positions of an existing robot program in place (pre-flight): "
        + ", ".join(d.title for d in DIALECTS.values()),
    ),
    "simulate": (
        "simulate",
        "simulate a laser-tracker measurement of a robot: a grid (seed Fig. 3) or given poses",
    ),
    "study": (
        "study",
        "grid-step study of the seed (Tables 4-5, Fig. 12): simulated or measured",
    ),
    "validate": (
        "validate",
        "check a calibrated model on points measured after correction: statistics, ISO 9283, "
        "pass/fail",
    ),
    "transform": (
        "transform",
        "map tracker-frame x,y,z / x_meas,y_meas,z_meas columns into the robot frame",
    ),
}
_PROGRAMS = {name: ("program", plugin_of(name).help.summary) for name in DIALECTS}
COMMANDS = dict(sorted({**_COMMANDS, **_PROGRAMS}.items()))
