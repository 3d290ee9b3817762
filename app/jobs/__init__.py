"""Each command's job as one call: a frozen request record in (never argparse's ``Namespace``),
the files to write and the lines to print out. One module per command it serves, named after
it: ``program`` (``krl``, ``gcode``, ``rapid``), ``rewrite``, ``correct`` and ``correct_model``,
``simulate``, ``plan``, ``study``, ``identify``, ``identify_tool``, ``validate``, ``fit_part``, and
``robot_frame`` (``fit-frame``, ``transform``: the robot-frame file). The names of ``__all__``
(each job's call) are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "write_program": "accugrid.app.jobs.program",
    "rewrite_job": "accugrid.app.jobs.rewrite",
    "correct_points": "accugrid.app.jobs.correct",
    "simulate_files": "accugrid.app.jobs.simulate",
    "plan_files": "accugrid.app.jobs.plan",
    "study_files": "accugrid.app.jobs.study",
    "calibrate": "accugrid.app.jobs.identify",
    "identify_tool_files": "accugrid.app.jobs.identify_tool",
    "validate_files": "accugrid.app.jobs.validate",
    "fit_part_files": "accugrid.app.jobs.fit_part",
    "fit_frame_files": "accugrid.app.jobs.robot_frame",
    "transform_csv": "accugrid.app.jobs.robot_frame",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
