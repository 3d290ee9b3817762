"""The UR10 laser-tracker series of ``../shared/realdata/ipa-ur10`` for the real-data benches.

Each series is read as it comes, through ``examples/tracker/ipa_ur10.yaml`` and the project's
own reader (what ``accugrid identify --format examples/tracker/ipa_ur10.yaml`` reads): the
commanded pose (m, rad), the logged joints (rad) and the tracker's measurement (mm, tracker
frame). The arm is the built-in ``ur10`` with the T-Mac's origin 109 mm along the flange z as its
TCP. ``calibrate`` is the calibration every real-data bench scores: the rows as the command line
turns them into poses (``Measurements.pose_set``: the logged joints are what the robot did, the
controller's own model not being the nominal one), the default identification (the structure
chosen from the data) and the DH-only fit, tracker frame identified, and the default's support
record (``kinematics.support``), region (``kinematics.validity``) and error budget
(``compensation.budget``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, fields, replace
from functools import cache
from pathlib import Path

import numpy as np

from accugrid.compensation.budget import ModelBudget, budget_section
from accugrid.compensation.measurements import Measurements, read_measurements
from accugrid.infra.csvtable import read_table_format
from accugrid.infra.yamlfile import YamlDoc
from accugrid.kinematics.frames import abc_to_matrix
from accugrid.kinematics.identification import Identification, identify
from accugrid.kinematics.robot import Robot, load_robot
from accugrid.kinematics.structure import Selection, identify_structure
from accugrid.kinematics.support import Structure, Support, support_section
from accugrid.kinematics.validity import Validity

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT.parent / "shared" / "realdata" / "ipa-ur10"
FORMAT_FILE = ROOT / "examples" / "tracker" / "ipa_ur10.yaml"
FILES = {"A": "Series_A/measurements_grid.csv", "C": "Series_C/measurements_random_poses.csv"}
TCP_MM = 109.0  # the T-Mac's origin along the flange z


def _ur10() -> Robot:
    tool = np.eye(4)
    tool[2, 3] = TCP_MM
    return load_robot("ur10").with_tool(tool)


ROBOT = _ur10()


@dataclass(frozen=True)
class Series:
    """Rows of one series as read (``measurements``) and their arrays: commanded positions ``p``
    (N, 3) mm and rotations ``rot`` (N, 3, 3) (robot base frame), logged joints ``q`` (N, 6) rad,
    measured positions ``m`` (N, 3) mm (tracker frame)."""

    measurements: Measurements

    @property
    def p(self) -> np.ndarray:
        return self.measurements.commanded

    @property
    def rot(self) -> np.ndarray:
        return abc_to_matrix(self.measurements.abc)

    @property
    def q(self) -> np.ndarray:
        return np.radians(self.measurements.joints)

    @property
    def m(self) -> np.ndarray:
        return self.measurements.measured

    def __len__(self) -> int:
        return len(self.measurements.commanded)

    def rows(self, index: np.ndarray) -> Series:
        """The rows ``index`` (int (K,) or bool (N,)) of this series."""
        meas, n = self.measurements, len(self)
        taken = {
            f.name: value[index]
            for f in fields(meas)
            if isinstance(value := getattr(meas, f.name), np.ndarray) and len(value) == n
        }
        return Series(replace(meas, **taken))


@cache
def read_series(name: str) -> Series:
    """Series "A" or "C", read as it comes (``FORMAT_FILE``)."""
    return Series(read_measurements(REAL / FILES[name], read_table_format(FORMAT_FILE)))


def random_pick(rows: int, poses: int, seed: int = 0) -> np.ndarray:
    """``poses`` random row indices of ``rows`` (the same each run for one ``seed``)."""
    return np.random.default_rng(seed).permutation(rows)[:poses]


@dataclass(frozen=True)
class Fit:
    """The default identification, its selection, the DH-only fit of the same poses, the
    support record, the region of its poses, the default's error budget (term (a)) and its wall
    and CPU time (s; one process, BLAS on one thread)."""

    default: Identification
    selection: Selection
    dh: Identification
    support: Support
    validity: Validity
    budget: ModelBudget
    seconds: tuple[float, float]


def calibrate(series: Series, rows: np.ndarray) -> Fit:
    """The default and the DH-only identification from the rows ``rows`` of ``series`` (tracker
    frame identified), with the default's support record, region and error budget, as
    ``identify`` writes them."""
    data = series.rows(rows).measurements.pose_set(ROBOT, None)
    started, cpu = time.perf_counter(), time.process_time()
    result, selection = identify_structure(ROBOT, data, base_frame=True)
    seconds = (time.perf_counter() - started, time.process_time() - cpu)
    dh = identify(ROBOT, data, base_frame=True, folds=5)
    structure = Structure(True, False, tuple(selection.harmonics), tuple(selection.gravity))
    held_out = selection.curve[selection.kept].rms_mm
    sections = {
        "support": support_section(result.robot, data.q, data.group, structure, dh),
        "budget": budget_section(
            result.robot, data.q, data.group, structure, result.residuals, held_out
        ),
    }
    doc = YamlDoc({"identification": sections}, {}, "identify")
    support = Support.from_doc(doc, result.robot, structure)
    budget = ModelBudget.from_doc(doc, result.robot, structure)
    validity = Validity.of_poses(data.commanded, data.rotations, data.q)
    return Fit(result, selection, dh, support, validity, budget, seconds)


def model_points(result: Identification, q: np.ndarray) -> np.ndarray:
    """The identified arm's TCP (N, 3) mm, robot frame, at joints q (N, 6) rad."""
    return (result.robot.true_robot() or result.robot).fk(q)[:, :3, 3]


def in_frame(result: Identification, q: np.ndarray) -> np.ndarray:
    """The identified arm's TCP (N, 3) mm in its identified tracker frame at joints q (N, 6)."""
    frame = result.tracker_T_robot
    return model_points(result, q) @ frame[:3, :3].T + frame[:3, 3]


def own_estimate(model: Fit, q: np.ndarray) -> np.ndarray:
    """Each target's own error estimate (N,) mm at joints q (N, 6) rad: the nested estimate (3D
    RMS) scaled by the target's prediction variance against the calibration poses' average,
    sqrt((3 + h(q)) / (3 + mean leave-one-out h)), h the leverage in noise units (3 axes of
    noise plus the model's own variance there)."""
    support = model.support
    inside = support.leverage(support.joints)
    loo = np.mean(inside / np.maximum(1.0 - inside / 3.0, 1e-9))
    nested = float(np.linalg.norm(model.selection.nested.rms_mm))
    return nested * np.sqrt((3.0 + support.leverage(q)) / (3.0 + loo))


def flagged_anywhere(fit: Fit, series: Series) -> np.ndarray:
    """(N,) bool: the poses of ``series`` a corrected position there would be flagged at for
    where it lies: without the model's support, or outside its poses' region (box, tool tilt,
    a joint's range)."""
    box, tilt, joint, _ = fit.validity.excess(series.p, series.rot, series.q)
    return (fit.support.ratio(series.q) > 1.0) | (box > 0) | (tilt > 0) | (joint > 0)
