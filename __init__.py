"""accugrid: robot TCP error compensation for drilling, from laser-tracker measurements to
corrected KUKA KRL and G-code programs.

The repository's top-level folders install as this one package (``pyproject.toml`` maps them):
``accugrid.kinematics`` (robot models, IK, error model, frames), ``accugrid.compensation`` (grid
model, plans, study), ``accugrid.codegen`` (points and cell files, program model, dialects, CLI) and
``accugrid.templates`` (Jinja2 templates). The names in ``__all__`` are the library surface; each is
imported on first use, so ``import accugrid`` (and the CLI's start-up) stays cheap.
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("accugrid")
except PackageNotFoundError:  # imported from a source tree that was never installed
    __version__ = "0.0.0+source"

# public name -> module that defines it
_API = {
    "InputError": "accugrid.kinematics.errors",
    "Robot": "accugrid.kinematics.robot",
    "load_robot": "accugrid.kinematics.robot",
    "RobotModel": "accugrid.kinematics.model",
    "Configuration": "accugrid.kinematics.configuration",
    "GridModel": "accugrid.compensation.grid",
    "CorrectionSettings": "accugrid.compensation.settings",
    "Measurements": "accugrid.compensation.measurements",
    "read_measurements": "accugrid.compensation.measurements",
    "Points": "accugrid.codegen.points",
    "read_points": "accugrid.codegen.points",
    "Cell": "accugrid.codegen.cell",
    "load_cell": "accugrid.codegen.cell",
    "Program": "accugrid.codegen.program",
    "build_program": "accugrid.codegen.program",
    "render_krl": "accugrid.codegen.krl.emit",
    "render_gcode": "accugrid.codegen.gcode.emit",
}

__all__ = ["__version__", *_API]


def __getattr__(name: str):
    if name not in _API:
        raise AttributeError(f"module 'accugrid' has no attribute {name!r}")
    value = getattr(import_module(_API[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
