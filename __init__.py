"""accugrid: robot TCP error compensation for drilling, from laser-tracker measurements to
corrected KUKA KRL, ABB RAPID and G-code programs.

The repository's top-level folders install as this one package (``pyproject.toml`` maps them),
one room per layer: ``accugrid.kinematics`` (robot models, IK, error model, frames,
identification), ``accugrid.compensation`` (grid model, correction policy, plans, study),
``accugrid.codegen`` (points and cell files, the neutral program model, one folder per dialect),
``accugrid.app`` (the command line, jobs, reports, plots), ``accugrid.infra`` (errors, guarded
input, YAML/CSV readers, atomic writes, safe text, digests, threads) and ``accugrid.templates``
(Jinja2 templates). The names in ``__all__`` are the library surface; each is
imported on first use (``infra.exports``), so ``import accugrid`` (and the CLI's start-up)
stays cheap.
"""

import os
import sys

from accugrid.infra.exports import lazy_namespace


def _version() -> str:
    """The installed distribution's version: the ``Version:`` of the first ``accugrid`` dist-info
    (or egg-info) on ``sys.path``, where ``importlib.metadata`` looks, without its 40 ms of
    imports at every start-up; ``importlib.metadata`` itself when that finds none."""
    for entry in sys.path:
        try:
            names = sorted(os.listdir(entry or "."))  # dist-info before egg-info, as it does
        except OSError:
            continue
        for name in names:
            stem, _, kind = name.rpartition(".")
            if stem.split("-")[0].lower() == "accugrid" and kind in ("dist-info", "egg-info"):
                found = _metadata_version(os.path.join(entry, name), kind)
                if found:
                    return found
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("accugrid")
    except PackageNotFoundError:  # imported from a source tree that was never installed
        return "0.0.0+source"


def _metadata_version(folder: str, kind: str) -> str | None:
    """The ``Version:`` header of a dist-info's METADATA or an egg-info's PKG-INFO, or None."""
    meta = os.path.join(folder, "METADATA" if kind == "dist-info" else "PKG-INFO")
    try:
        with open(meta, encoding="utf-8") as f:
            for line in f:
                if line.startswith("Version:"):
                    return line[len("Version:") :].strip()
                if not line.strip():
                    return None  # the end of the headers
    except (OSError, UnicodeDecodeError):
        pass
    return None


__version__ = _version()

from accugrid.codegen.dialects import EXPORTS  # noqa: E402 - accugrid.codegen reads __version__

# the names a script needs, by the package that lists (and lazily imports) them
_PUBLIC = {
    "accugrid.infra": ("InputError", "TableFormat"),
    "accugrid.kinematics": (
        "Robot",
        "load_robot",
        "RobotModel",
        "Configuration",
        "pose_set",
        "identify",
        "identification_summary",
        "calibrated_yaml",
    ),
    "accugrid.compensation": (
        "GridModel",
        "CorrectionSettings",
        "Policy",
        "Measurements",
        "read_measurements",
        "model_correct",
        "residual_grid",
        "grid_plan",
        "experiment_plan",
        "identification_plan",
    ),
    "accugrid.codegen": (
        "Points",
        "read_points",
        "Cell",
        "load_cell",
        "Program",
        "build_program",
        *EXPORTS,  # each dialect's renderer, as its plug-in declares (``codegen.dialects``)
    ),
}
_API = {name: package for package, names in _PUBLIC.items() for name in names}

__all__ = ["__version__", *_API]

__getattr__, __dir__ = lazy_namespace(__name__, _API)
