"""The robot-frame YAML file written by ``accugrid fit-frame`` and read by ``accugrid transform``,
and the transform of a CSV's tracker-frame columns with it.

The frame is ``tracker_T_robot``: keys ``x, y, z`` (mm) and ``a, b, c`` (KUKA ABC, deg) define it;
the optional ``matrix`` (4×4) is a convenience copy and must agree with them. The fit residuals
and checks are informational and ignored when reading.
"""

from __future__ import annotations

import csv
import io
import json
import os
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from accugrid import __version__
from accugrid.codegen.cellfile import frame_lines
from accugrid.infra.atomic import JobFiles
from accugrid.infra.csvtable import Table, parse_table, read_table
from accugrid.infra.digest import file_sha256, sha256_hex
from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import read_input_text
from accugrid.infra.textsafe import comment_text, fixed
from accugrid.infra.yamlfile import Schema, load_yaml
from accugrid.kinematics.base_frame import SMR_RADIUS_MM, RobotFrameFit, fit_robot_frame
from accugrid.kinematics.fitting import CircleFit
from accugrid.kinematics.frames import invert, pose_from_xyzabc, transform_points, xyzabc_from_pose

__all__ = [
    "DECIMALS",
    "FRAME_SCHEMA",
    "KEYS",
    "MATRIX_TOL",
    "TRIPLES",
    "fit_frame_files",
    "frame_yaml",
    "load_frame",
    "transform_csv",
]

KEYS = ("x", "y", "z", "a", "b", "c")
# A frame file (``frame_yaml`` writes it, ``load_frame`` reads tracker_T_robot; the rest is a
# record of the fit)
FRAME_SCHEMA: Schema = {
    "accugrid": None,
    "tracker_T_robot": {**dict.fromkeys(KEYS), "matrix": None},
    "smr_radius_mm": None,
    "inputs": None,
    "fits": None,
    "checks": None,
}
TRIPLES = {"xyz": ("x", "y", "z"), "meas": ("x_meas", "y_meas", "z_meas")}  # transform columns
DECIMALS = 4  # of a transformed number, mm
MATRIX_TOL = 1e-6
"""Largest difference accepted between ``matrix`` and the pose from x..c (rotation entries, and
translation in mm scaled by 1/1000, i.e. 1 µm)."""


def _circle_yaml(fit: CircleFit) -> str:
    return (
        f"{{points: {fit.n_points}, radius_mm: {fixed(fit.radius_mm, 4)}, "
        f"arc_deg: {fixed(fit.arc_deg, 2)}, rms_mm: {fixed(fit.rms_mm, 4)}, "
        f"max_mm: {fixed(fit.max_mm, 4)}}}"
    )


def frame_yaml(fit: RobotFrameFit, inputs: Mapping[str, tuple[str, str]]) -> str:
    """The YAML text for a fitted frame; ``inputs`` maps base_plane/a1_circle/flange_holes to
    (file name, SHA-256 hex)."""
    pose = fit.tracker_T_robot
    lines = [
        "# Robot base frame fitted from laser-tracker points (accugrid fit-frame, seed Sec. 4.1).",
        "# tracker_T_robot is the robot frame in the tracker frame: x, y, z in mm, a, b, c",
        "# KUKA ABC in degrees (R = Rz(a) Ry(b) Rx(c)). A tracker point p maps to the robot",
        "# frame as p_robot = inv(tracker_T_robot) p.",
        f"accugrid: {json.dumps(__version__)}",
        "tracker_T_robot:",
    ]
    lines += frame_lines(pose, 6, 8)
    lines.append("  matrix:")
    for row in pose:
        cells = [fixed(v, 10) for v in row[:3]] + [fixed(row[3], 6)]
        lines.append(f"    - [{', '.join(cells)}]")
    lines.append(f"smr_radius_mm: {fixed(fit.base_offset_mm, 4)}")
    lines.append("inputs:")
    for key, (name, digest) in inputs.items():
        lines.append(f"  {key}: {{file: {json.dumps(str(name))}, sha256: {digest}}}")
    plane = fit.plane
    lines += [
        "fits:  # residuals are point-to-plane / point-to-circle distances of the SMR centres",
        f"  base_plane: {{points: {plane.n_points}, rms_mm: {fixed(plane.rms_mm, 4)}, "
        f"max_mm: {fixed(plane.max_mm, 4)}}}",
        f"  a1_circle: {_circle_yaml(fit.a1_circle)}",
        f"  flange_holes: {_circle_yaml(fit.flange_holes)}",
        "checks:",
        f"  axis_tilt_deg: {fixed(fit.axis_tilt_deg, 4)}  # A1 axis vs base-plane normal",
        f"  flange_axis_deg: {fixed(fit.flange_axis_deg, 4)}  # flange-hole circle normal vs "
        "robot X (about 0 at mechanical zero)",
    ]
    return "\n".join(lines) + "\n"


def _number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if np.isfinite(value) else None


def load_frame(path: str | os.PathLike[str]) -> np.ndarray:
    """Read tracker_T_robot (4, 4) mm from a frame YAML; InputError naming file, line and key."""
    path = os.fspath(path)
    doc = load_yaml(path)
    doc.check_keys(FRAME_SCHEMA)
    data = doc.data

    def fail(message: str, *keys: str) -> InputError:
        return InputError(message, path, doc.line(*keys))

    if not isinstance(data, dict) or "tracker_T_robot" not in data:
        raise fail("missing key 'tracker_T_robot' (is this a file written by accugrid fit-frame?)")
    frame = data["tracker_T_robot"]
    if not isinstance(frame, dict):
        raise fail("key 'tracker_T_robot' must be a mapping of x, y, z, a, b, c", "tracker_T_robot")
    values = []
    for key in KEYS:
        if key not in frame:
            raise fail(f"missing key 'tracker_T_robot.{key}'", "tracker_T_robot")
        number = _number(frame[key])
        if number is None:
            raise fail(
                f"key 'tracker_T_robot.{key}' must be a finite number, got {frame[key]!r}",
                "tracker_T_robot",
                key,
            )
        values.append(number)
    pose = pose_from_xyzabc(np.array(values))
    if "matrix" in frame:
        _check_matrix(frame["matrix"], pose, fail)
    return pose


def _check_matrix(matrix: object, pose: np.ndarray, fail) -> None:
    where = ("tracker_T_robot", "matrix")
    rows = matrix if isinstance(matrix, list) else []
    cells = [_number(v) for row in rows if isinstance(row, list) for v in row]
    if len(rows) != 4 or len(cells) != 16 or any(v is None for v in cells):
        raise fail("key 'tracker_T_robot.matrix' must be 4 rows of 4 finite numbers", *where)
    given = np.array(cells, dtype=float).reshape(4, 4)
    scale = np.array([1.0, 1.0, 1.0, 1e-3])
    worst = float(np.max(np.abs(given - pose) * scale))
    if worst > MATRIX_TOL:
        raise fail(
            "key 'tracker_T_robot.matrix' disagrees with x, y, z, a, b, c (largest difference "
            f"{worst:.2e}); edit both or delete the matrix",
            *where,
        )


def transform_csv(
    table_path: str | os.PathLike[str],
    frame_path: str | os.PathLike[str],
    output: str | os.PathLike[str],
    columns: str | None = None,
    inverse: bool = False,
) -> JobFiles:
    """``accugrid transform``: the CSV at ``table_path`` with one or both triples x,y,z and
    x_meas,y_meas,z_meas (``columns`` "xyz", "meas", "both"; None: "meas" when the file has
    them, else "xyz") mapped from the tracker frame into the robot frame of ``frame_path``
    (tracker_T_robot; ``inverse``: back), 4 decimals of mm, written in the file's own delimiter,
    decimal mark and unit of each column (read as ``reading_as`` says); every other cell,
    comment and blank line as it was, a comment naming the frame file first. InputError on a
    bad file."""
    text = read_input_text(table_path)[1]
    table = parse_table(text, table_path)
    tracker_T_robot = load_frame(frame_path)
    pose = tracker_T_robot if inverse else invert(tracker_T_robot)
    triples = _chosen(table, columns)
    names = [n for triple in triples for n in triple]
    mapped = {}
    for triple in triples:
        values = _mapped(table, triple, pose)
        for k, name in enumerate(triple):
            mapped[table.index(name)] = values[:, k]
    direction = (
        "from the robot frame into the tracker frame"
        if inverse
        else "from the tracker frame into the robot frame"
    )
    note = (
        f"accugrid transform: {','.join(names)} mapped {direction} with "
        f"{Path(frame_path).name} sha256 {file_sha256(frame_path)}"
    )
    body = _rewrite(text, table, mapped)
    return JobFiles(
        {output: f"# {comment_text(note, limit=400)}\n{body}"},
        [table_path, frame_path],
        [f"{output}: {len(table)} row(s), {note}"],
    )


def _chosen(table: Table, choice: str | None) -> list[tuple[str, str, str]]:
    """The column triples to map, each checked to be complete in the header."""
    if choice is None:
        choice = "meas" if any(table.has(n) for n in TRIPLES["meas"]) else "xyz"
    keys = ["xyz", "meas"] if choice == "both" else [choice]
    triples = [TRIPLES[k] for k in keys]
    for triple in triples:
        table.require(triple)
    return triples


def _mapped(table: Table, triple: tuple[str, str, str], pose: np.ndarray) -> np.ndarray:
    """(N, 3) mapped values of one triple; NaN rows where all three cells are empty."""
    values = table.floats(list(triple), allow_empty=True)
    empty = np.isnan(values)
    partial = np.flatnonzero(empty.any(axis=1) & ~empty.all(axis=1))
    if partial.size:
        r = int(partial[0])
        name = triple[int(np.flatnonzero(empty[r])[0])]
        raise InputError(
            f"empty cell in column '{name}' while the rest of {','.join(triple)} is filled",
            *table.where(r, name),
        )
    return transform_points(pose, values)


def _rewrite(text: str, table: Table, mapped: dict[int, np.ndarray]) -> str:
    """The CSV text with the mapped cells (mm) replaced, each in its column's unit and the
    file's decimal mark; every other line kept as it was."""
    lines = text.splitlines(keepends=True)
    row_at = {line: r for r, line in enumerate(table.lines)}
    written = {i: _cell_text(table, table.header[i].lower()) for i in mapped}
    reader = csv.reader(lines, delimiter=table.delimiter, strict=True)
    out: list[str] = []
    end = 0
    for record in reader:
        start, end = end, reader.line_num
        r = row_at.get(start + 1)
        if r is None:
            out.extend(lines[start:end])
            continue
        cells = list(record)
        for i, values in mapped.items():
            if not np.isnan(values[r]):
                cells[i] = written[i](values[r])
        ending = lines[end - 1][len(lines[end - 1].rstrip("\r\n")) :] or "\n"
        buffer = io.StringIO()
        csv.writer(buffer, delimiter=table.delimiter, lineterminator=ending).writerow(cells)
        out.append(buffer.getvalue())
    return "".join(out)


def _cell_text(table: Table, name: str) -> Callable[[float], str]:
    """How a value in mm is written into column ``name`` of ``table``: in the column's unit
    (``DECIMALS`` of mm: more decimals for m and in) with the file's decimal mark."""
    scale, extra = {"m": (1e-3, 3), "in": (1 / 25.4, 2)}.get(table.units.get(name, ""), (1.0, 0))

    def text(value_mm: float) -> str:
        return fixed(value_mm * scale, DECIMALS + extra).replace(".", table.decimal)

    return text


def fit_frame_files(
    base_plane: str,
    a1_circle: str,
    flange_holes: str,
    output: str,
    plot: str | None = None,
    smr_radius_mm: float = SMR_RADIUS_MM,
) -> JobFiles:
    """``accugrid fit-frame``: the robot-frame YAML (``frame_yaml``) at ``output`` fitted from
    three tracker CSVs (x,y,z mm: mounting surface, flange while A1 turns, flange holes at
    mechanical zero; seed Sec. 4.1), and with ``plot`` a PNG of the fit. InputError on a bad
    file or a fit that is refused."""
    if plot and Path(plot).resolve() == Path(output).resolve():
        raise InputError("--plot and -o name the same file", plot)
    if not (np.isfinite(smr_radius_mm) and smr_radius_mm >= 0.0):
        raise InputError(f"--smr-radius must be a number >= 0 mm, got {smr_radius_mm}")
    inputs = {"base_plane": base_plane, "a1_circle": a1_circle, "flange_holes": flange_holes}
    loaded = {key: _tracker_points(path) for key, path in inputs.items()}
    fit = fit_robot_frame(
        loaded["base_plane"][0],
        loaded["a1_circle"][0],
        loaded["flange_holes"][0],
        smr_radius_mm=smr_radius_mm,
        sources=(base_plane, a1_circle, flange_holes),
    )
    digests = {key: (Path(path).name, sha256_hex(loaded[key][1])) for key, path in inputs.items()}
    files: dict[str, bytes | str] = {output: frame_yaml(fit, digests)}
    if plot:
        from accugrid.app.reports.plots import frame_fit_png

        files[plot] = frame_fit_png(fit, {key: value[0] for key, value in loaded.items()})
    return JobFiles(files, list(inputs.values()), [_fit_summary(output, fit)])


def _tracker_points(path: str) -> tuple[np.ndarray, bytes]:
    """The x,y,z columns (N, 3) mm of a tracker CSV and the file's bytes (for its SHA-256)."""
    table = read_table(path)
    table.require(["x", "y", "z"])
    return table.floats(["x", "y", "z"]), Path(path).read_bytes()


def _fit_summary(path: str, fit: RobotFrameFit) -> str:
    x, y, z, a, b, c = xyzabc_from_pose(fit.tracker_T_robot)
    return (
        f"{path}: tracker_T_robot x {x:.3f} y {y:.3f} z {z:.3f} mm, a {a:.4f} b {b:.4f} "
        f"c {c:.4f} deg; residual RMS/max mm: plane {fit.plane.rms_mm:.4f}/{fit.plane.max_mm:.4f}, "
        f"A1 circle {fit.a1_circle.rms_mm:.4f}/{fit.a1_circle.max_mm:.4f} "
        f"({fit.a1_circle.arc_deg:.1f} deg of arc), "
        f"flange holes {fit.flange_holes.rms_mm:.4f}/{fit.flange_holes.max_mm:.4f}"
    )
