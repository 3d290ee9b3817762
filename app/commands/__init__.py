"""One module per ``accugrid`` subcommand (see ``app.cli``): ``NAME``,
``add_arguments(parser)`` and ``run(args) -> int``. A command parses its arguments, refuses
existing outputs (``atomic.check_targets``), calls one domain function (e.g.
``jobs.correct.correct_points``, ``jobs.plan.plan_files``), which returns the job's files
and the lines to print (``atomic.JobFiles``), writes them as one job (``atomic.write_files``)
and prints the lines.

``COMMANDS`` names them with their one-line help, so the parser (and ``accugrid --help``) is
built without importing any command module; only the command that runs is imported.
"""

__all__ = ["COMMANDS"]

# NAME -> (module in this package, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "compare": (
        "compare",
        "grid only vs model vs model + residual grid against the number of measured points",
    ),
    "correct": (
        "correct",
        "corrected points CSV: P' = P + e from a measured error grid and/or a calibrated model",
    ),
    "fanuc": (
        "fanuc",
        "corrected FANUC TP drilling program (.ls) from a points CSV",
    ),
    "fit-frame": (
        "fit_frame",
        "robot base frame (tracker_T_robot) from tracker points on base, A1 arc and flange holes",
    ),
    "fit-part": (
        "fit_part",
        "part frame (robot_T_base) from datums measured by the tracker and their CAD coordinates",
    ),
    "gcode": (
        "gcode",
        "corrected RS274NGC (LinuxCNC) drilling program from a points CSV",
    ),
    "identify": (
        "identify",
        "calibrated robot model (DH errors, TCP) from tracker measurements at scattered poses",
    ),
    "identify-tool": (
        "identify_tool",
        "the drill's TCP and axis measured on the calibrated arm (SMR at 6+ orientations)",
    ),
    "krl": (
        "krl",
        "corrected KUKA KRL drilling program (.src/.dat) from a points CSV",
    ),
    "plan": (
        "plan",
        "measurement plans: grid, ISO 9283 cube, the seed's step experiment, identification poses",
    ),
    "rapid": (
        "rapid",
        "corrected ABB RAPID drilling module (.mod) from a points CSV",
    ),
    "rewrite": (
        "rewrite",
        "correct the positions of an existing KRL, G-code or RAPID program in place (pre-flight)",
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
