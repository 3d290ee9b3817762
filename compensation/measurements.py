"""Laser-tracker measurements in, one averaged error per vertex of a regular grid out.

A measurement row is a commanded TCP position P and the measured position M (robot frame, mm),
optionally with the commanded orientation a,b,c (KUKA ABC, deg). Rows with the same commanded
position are repeats and are averaged. Together the commanded positions must form a complete
axis-aligned regular grid; anything else is an InputError that says what is wrong and where.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from accugrid.infra.csvtable import Table, TableFormat, parse_table
from accugrid.infra.digest import sha256_hex
from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import read_input_text
from accugrid.infra.units import mm_text
from accugrid.kinematics.frames import abc_to_matrix, rotation_angle_deg

__all__ = [
    "COORD_MAX_MM",
    "COORD_TOL_MM",
    "ORIENTATION_TOL_DEG",
    "REPEAT_TOL_MM",
    "Measurements",
    "VertexGrid",
    "build_grid",
    "check_joint_limits",
    "measurements_from_arrays",
    "read_measurements",
]

COORD_TOL_MM = 1e-3  # two commanded coordinates closer than this are the same grid level
REPEAT_TOL_MM = 0.5  # largest allowed distance of a repeat from the mean of its vertex
ORIENTATION_TOL_DEG = 0.1  # every row must be commanded at the same a,b,c within this
COORD_MAX_MM = 1e6  # positions beyond 1 km are refused at their cell (no robot reaches them)
JOINT_MAX_DEG = 3600.0  # logged axis angles beyond ten turns are refused at their cell
JOINT_COLUMNS = [f"a{i}" for i in range(1, 7)]  # the logged axis angles
RADIAN_SPAN = 0.5  # deg: joints that move less over a whole series are not told from radians
MIRROR_SHARE = 0.2  # a mirrored fit this much better than the rigid one is a mirror image
MIRROR_MIN_MM = 10.0  # ... when the rigid fit misses by more than this RMS
_SHOW = 5  # how many offending items an error message lists


@dataclass
class Measurements:
    """Rows of a measurement session: commanded and measured (N, 3) mm, a,b,c (N, 3) deg or None.

    ``path``/``lines`` locate each row for error messages (``path`` None for arrays).
    ``joints``: the logged axis angles a1..a6 (N, 6) deg or None (``joint_unit``: the file's,
    deg or rad); ``joint_decimals`` (N, 6) and ``position_decimals`` (N, 3): digits after the
    point as printed, in deg and mm (``Table.decimals``: for the round-off the logged numbers
    carry); ``status``: column ``s`` (N,) int KUKA Status or None.
    """

    commanded: np.ndarray
    measured: np.ndarray
    abc: np.ndarray | None
    path: str | None = None
    lines: np.ndarray | None = None
    sha256: str | None = None
    joints: np.ndarray | None = None
    joint_decimals: np.ndarray | None = None
    position_decimals: np.ndarray | None = None
    status: np.ndarray | None = None
    joint_unit: str = "deg"

    def __repr__(self) -> str:
        source = f" from {os.path.basename(self.path)}" if self.path else ""
        extra = [
            name for name, v in (("a,b,c", self.abc), ("a1..a6", self.joints)) if v is not None
        ]
        return (
            f"Measurements({len(self.commanded)} rows{source}"
            + "".join(f", {name}" for name in extra)
            + ")"
        )

    def where(self, row: int) -> str:
        """Human location of a row: 'line 12' for a file, 'row 3' (0-based) for arrays."""
        return f"line {self.lines[row]}" if self.lines is not None else f"row {row}"

    def pose_set(self, robot, status: np.ndarray | int | None):
        """These rows as ``kinematics.identification.pose_set`` of ``robot`` (its tool the one
        they were measured with), each row located by ``where``; ``status`` the Status of rows
        without logged joints."""
        from accugrid.kinematics.identification import pose_set  # identification jobs only

        return pose_set(
            robot,
            self.commanded,
            self.measured,
            abc_deg=self.abc,
            joints_deg=self.joints,
            status=status,
            joint_decimals=self.joint_decimals,
            position_decimals=self.position_decimals,
            labels=[self.where(r) for r in range(len(self.commanded))],
            path=self.path,
        )


@dataclass
class VertexGrid:
    """An axis-aligned regular grid with one averaged error per vertex.

    origin, step (3,) mm; counts (3,) int; errors (nx, ny, nz, 3) mm, e = P - M;
    repeats (nx, ny, nz) int; spread_mm: largest distance of a repeat from its vertex mean;
    noise_mm: a row's scatter about its vertex mean, 1 sigma per axis (None: no repeats);
    abc (3,) deg the common orientation, status the common KUKA Status (None: not recorded).
    """

    origin: np.ndarray
    step: np.ndarray
    counts: np.ndarray
    errors: np.ndarray
    repeats: np.ndarray
    spread_mm: float
    abc: np.ndarray | None
    status: int | None = (
        None  # the KUKA Status the grid was measured in (column s), None: not recorded
    )
    noise_mm: float | None = None


def read_measurements(path: str | os.PathLike[str], fmt: TableFormat | None = None) -> Measurements:
    """Read a measurement CSV (docs/formats.md): x,y,z,x_meas,y_meas,z_meas required; a,b,c, the
    logged joints a1..a6 (all six or none) and the Status s optional. ``fmt``: how a tracker
    export is written (delimiter, decimal mark, column mapping, units; default: found)."""
    path = os.fspath(path)
    raw, text = read_input_text(path)
    table = parse_table(text, path, fmt)
    table.require(["x", "y", "z", "x_meas", "y_meas", "z_meas"])
    if not len(table):
        raise InputError("no measurement rows", path)
    abc = _abc_columns(table)
    joints = joint_decimals = None
    if any(table.has(n) for n in JOINT_COLUMNS):
        table.require(JOINT_COLUMNS)
        joints = table.floats(JOINT_COLUMNS)
        table.check_bounds(joints, JOINT_COLUMNS, JOINT_MAX_DEG, "deg", _DEGREES_AS_RADIANS)
        _check_not_radians(table, joints)
        joint_decimals = table.decimals(JOINT_COLUMNS)
    columns = {}
    for names in (["x", "y", "z"], ["x_meas", "y_meas", "z_meas"]):
        columns[names[0]] = table.floats(names)
        table.check_bounds(columns[names[0]], names, COORD_MAX_MM, "mm")
    _check_not_mirrored(table, columns["x"], columns["x_meas"])
    return Measurements(
        commanded=columns["x"],
        measured=columns["x_meas"],
        abc=abc,
        path=path,
        lines=np.asarray(table.lines),
        sha256=sha256_hex(raw),
        joints=joints,
        joint_decimals=joint_decimals,
        position_decimals=table.decimals(["x", "y", "z"]),
        status=_status_column(table),
        joint_unit=table.units.get("a1", "deg"),
    )


_DEGREES_AS_RADIANS = ": degrees read as radians? (check the joints' unit: --units)"


def _check_not_radians(table: Table, joints_deg: np.ndarray) -> None:
    """InputError at column a1's header when joints read as degrees all lie within +-2 pi
    while the series moves them: radians read as degrees."""
    if table.units.get("a1", "deg") != "deg" or len(joints_deg) < 2:
        return
    moved = np.ptp(joints_deg, axis=0).max() > RADIAN_SPAN
    if moved and np.abs(joints_deg).max() <= 2.0 * np.pi:
        raise InputError(
            f"the logged joints a1..a6 all lie within +-{2.0 * np.pi:.1f} deg over "
            f"{len(joints_deg)} rows: radians read as degrees? (read them with --units rad, or "
            "a1=rad,...,a6=rad beside the other units)",
            table.path,
            table.header_line,
            table.index("a1") + 1,
        )


def _check_not_mirrored(table: Table, commanded: np.ndarray, measured: np.ndarray) -> None:
    """InputError at column x_meas's header when the measured positions (N, 3) are a mirror image
    of the commanded ones (N, 3), in any frame: two columns swapped or one of the wrong sign.
    Compares the best rigid fit (a rotation) with the best mirrored one (orthogonal
    Procrustes); a set that is nearly flat, or fits neither way, passes."""
    if len(commanded) < 4:
        return
    p, m = commanded - commanded.mean(axis=0), measured - measured.mean(axis=0)
    u, s, vt = np.linalg.svd(p.T @ m)
    d = np.sign(np.linalg.det(u @ vt)) or 1.0
    total = (p * p).sum() + (m * m).sum()
    rms = [
        np.sqrt(max(total - 2.0 * (s[0] + s[1] + sign * s[2]), 0.0) / len(p)) for sign in (d, -d)
    ]  # rotation, mirror
    if rms[1] < MIRROR_SHARE * rms[0] and rms[0] > MIRROR_MIN_MM:
        raise InputError(
            f"the measured positions x_meas,y_meas,z_meas are a mirror image of the commanded "
            f"x,y,z (best rigid fit RMS {rms[0]:.1f} mm, mirrored {rms[1]:.2f} mm): two columns "
            "swapped or one of the wrong sign? check the file's columns (--columns)",
            table.path,
            table.header_line,
            table.index("x_meas") + 1,
        )


def check_joint_limits(meas: Measurements, limits_deg: np.ndarray, robot: str) -> None:
    """InputError at the first row whose logged joints lie beyond the robot's limits (6, 2) deg
    when the file says why: two joint columns whose values fit the limits exchanged (swapped
    columns), or joints declared rad (degrees read as radians). Otherwise nothing: the limits
    of a robot file may be narrower than the controller's."""
    if meas.joints is None:
        return
    q = meas.joints
    beyond = (q < limits_deg[:, 0]) | (q > limits_deg[:, 1])
    if not beyond.any():
        return
    swapped = [
        (i, j)
        for i in range(6)
        for j in range(i + 1, 6)
        if beyond[:, [i, j]].any()
        and (limits_deg[i, 0] <= q[:, j]).all()
        and (q[:, j] <= limits_deg[i, 1]).all()
        and (limits_deg[j, 0] <= q[:, i]).all()
        and (q[:, i] <= limits_deg[j, 1]).all()
    ]
    if swapped:
        i, j = swapped[0]
        hint = f": columns a{i + 1} and a{j + 1} swapped? (they fit the limits exchanged)"
    elif meas.joint_unit == "rad":
        hint = _DEGREES_AS_RADIANS
    else:
        return
    rows, axes = np.nonzero(beyond)
    r, i = int(rows[0]), int(axes[0])
    lo, hi = limits_deg[i]
    raise InputError(
        f"logged joint a{i + 1} {q[r, i]:.3f} deg is beyond {robot}'s limits [{lo:g}, {hi:g}] "
        f"deg ({rows.size} such cells){hint}",
        *_located(meas, r),
    )


def _status_column(table: Table) -> np.ndarray | None:
    """Column ``s`` as KUKA Status ints 0..7 (N,), or None; InputError at a bad cell."""
    if not table.has("s"):
        return None
    values = table.floats(["s"])[:, 0]
    bad = np.flatnonzero((values != np.round(values)) | (values < 0) | (values > 7))
    if bad.size:
        raise InputError(
            f"column 's' must be a KUKA Status 0..7, got {values[bad[0]]:g}",
            *table.where(int(bad[0]), "s"),
        )
    return values.astype(int)


def _abc_columns(table: Table) -> np.ndarray | None:
    present = [table.has(n) for n in ("a", "b", "c")]
    if not any(present):
        return None
    if not all(present):
        table.require(["a", "b", "c"])
    return table.floats(["a", "b", "c"])


def measurements_from_arrays(
    commanded: np.ndarray, measured: np.ndarray, abc: np.ndarray | None = None
) -> Measurements:
    """Wrap (N, 3) arrays; InputError for wrong shapes or non-finite values (naming the row)."""
    arrays = {"commanded": commanded, "measured": measured}
    if abc is not None:
        arrays["abc"] = abc
    checked = {}
    for name, value in arrays.items():
        value = np.asarray(value, dtype=float)
        if value.ndim != 2 or value.shape[1] != 3 or not len(value):
            raise InputError(f"{name} must be a non-empty (N, 3) array, got shape {value.shape}")
        bad = np.flatnonzero(~np.isfinite(value).all(axis=1))
        if bad.size:
            raise InputError(f"{name} row {bad[0]} is not finite: {value[bad[0]].tolist()}")
        checked[name] = value
    lengths = {len(v) for v in checked.values()}
    if len(lengths) != 1:
        raise InputError(f"commanded, measured (and abc) differ in length: {sorted(lengths)}")
    return Measurements(checked["commanded"], checked["measured"], checked.get("abc"))


def build_grid(
    meas: Measurements, coord_tol_mm: float = COORD_TOL_MM, repeat_tol_mm: float = REPEAT_TOL_MM
) -> VertexGrid:
    """Detect the regular grid of the commanded points and average the repeats of each vertex.

    InputError when the points are not a complete axis-aligned regular grid (uneven spacing,
    stray or missing vertices), when repeats disagree by more than ``repeat_tol_mm``, or when
    the rows were commanded at different orientations.
    """
    for what, tol in (("coordinate", coord_tol_mm), ("repeat", repeat_tol_mm)):
        if not (np.isfinite(tol) and tol >= 0.0):
            raise InputError(f"the {what} tolerance must be a finite number >= 0 mm, got {tol}")
    origin, step, counts, index = _detect_axes(meas, coord_tol_mm)
    flat = np.ravel_multi_index(index.T, tuple(counts))
    n_vertices = int(np.prod(counts))
    repeats = np.bincount(flat, minlength=n_vertices)
    missing = np.flatnonzero(repeats == 0)
    if missing.size:
        ijk = np.column_stack(np.unravel_index(missing[:_SHOW], tuple(counts)))
        listed = "; ".join(mm_text(origin + v * step, 4) for v in ijk)
        raise InputError(
            f"{missing.size} of {n_vertices} grid vertices not measured "
            f"(grid {_fmt_counts(counts)} at step {mm_text(step, 4)} mm), e.g. {listed}"
            + _sparse_planes(meas, origin, step, counts, index, repeats > 0),
            meas.path,
        )
    error_rows = meas.commanded - meas.measured
    sums = np.zeros((n_vertices, 3))
    np.add.at(sums, flat, error_rows)
    mean = sums / repeats[:, None]
    spread = np.linalg.norm(error_rows - mean[flat], axis=1)
    worst = int(np.argmax(spread))
    if spread[worst] > repeat_tol_mm:
        same = np.flatnonzero(flat == flat[worst])
        rows = ", ".join(meas.where(r) for r in same[:_SHOW])
        raise InputError(
            f"repeated measurements of {mm_text(meas.commanded[worst], 4)} disagree: one lies "
            f"{spread[worst]:.3f} mm from their mean (limit {repeat_tol_mm:g} mm; {rows})",
            meas.path,
            None if meas.lines is None else int(meas.lines[worst]),
        )
    return VertexGrid(
        origin=origin,
        step=step,
        counts=counts,
        errors=mean.reshape(*counts, 3),
        repeats=repeats.reshape(tuple(counts)),
        spread_mm=float(spread.max()),
        abc=_common_orientation(meas),
        status=_common_status(meas),
        noise_mm=_repeat_noise(spread, len(flat), n_vertices),
    )


def _repeat_noise(spread: np.ndarray, rows: int, vertices: int) -> float | None:
    """A row's scatter about its vertex mean, 1 sigma per axis mm (pooled over the vertices,
    3 (rows - vertices) degrees of freedom) from the rows' distances ``spread`` (rows,) mm;
    None without repeats."""
    if rows <= vertices:
        return None
    return float(np.sqrt(np.sum(spread**2) / (3 * (rows - vertices))))


def _common_status(meas: Measurements) -> int | None:
    """The one KUKA Status of a grid measurement (column s), None when not recorded; InputError
    at the first row in another Status: a grid holds in the Status it was measured in."""
    if meas.status is None or not len(meas.status):
        return None
    other = np.flatnonzero(meas.status != meas.status[0])
    if other.size:
        i = int(other[0])
        raise InputError(
            f"a grid is measured in one KUKA Status: column s is {int(meas.status[i])} here, "
            f"{int(meas.status[0])} in the first row",
            *_located(meas, i),
        )
    return int(meas.status[0])


def _detect_axes(
    meas: Measurements, tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per axis: group coordinates into levels, check even spacing; vertex index (N, 3) per row."""
    origin, step, counts = np.empty(3), np.empty(3), np.empty(3, dtype=int)
    index = np.empty(meas.commanded.shape, dtype=np.int64)
    for axis, name in enumerate("xyz"):
        values = meas.commanded[:, axis]
        order = np.argsort(values, kind="stable")
        starts = np.concatenate(([True], np.diff(values[order]) > tol))
        level_of_sorted = np.cumsum(starts) - 1
        n_levels = int(level_of_sorted[-1]) + 1
        level = np.empty(len(values), dtype=np.int64)
        level[order] = level_of_sorted
        centres = np.bincount(level, weights=values) / np.bincount(level)
        if n_levels < 2:
            raise InputError(
                f"the commanded points span a single {name} value ({centres[0]:.4f} mm): "
                "a grid needs at least 2 levels per axis",
                *_located(meas, 0),
            )
        gaps = np.diff(centres)
        spacing = (centres[-1] - centres[0]) / (n_levels - 1)
        off = np.abs(gaps - spacing) > tol
        if off.any():
            members = np.bincount(level)
            stray = np.flatnonzero(members < np.median(members))
            culprit = int(stray[0]) if stray.size else int(np.flatnonzero(off)[0]) + 1
            first_row = int(np.flatnonzero(level == culprit)[0])
            raise InputError(
                _uneven_message(name, centres, members, tol), *_located(meas, first_row)
            )
        origin[axis], step[axis], counts[axis] = centres[0], spacing, n_levels
        index[:, axis] = level
    return origin, step, counts, index


def _located(meas: Measurements, row: int) -> tuple[str | None, int | None]:
    """(path, line) of a row, for InputError; the line is None for arrays."""
    return meas.path, None if meas.lines is None else int(meas.lines[row])


def _sparse_planes(
    meas: Measurements,
    origin: np.ndarray,
    step: np.ndarray,
    counts: np.ndarray,
    index: np.ndarray,
    measured: np.ndarray,
) -> str:
    """'; planes with few vertices (stray points?): ...' for grid planes less than half measured."""
    covered = measured.reshape(tuple(counts))
    found = []
    for axis, name in enumerate("xyz"):
        per_plane = covered.sum(axis=tuple(a for a in range(3) if a != axis))
        full = int(np.prod(counts)) // int(counts[axis])
        for level in np.flatnonzero(per_plane < full / 2):
            first = int(np.flatnonzero(index[:, axis] == level)[0])
            found.append(
                f"{name}={origin[axis] + level * step[axis]:.4f} has {per_plane[level]} of "
                f"{full} vertices ({meas.where(first)})"
            )
    return (
        "; planes with few vertices (stray points?): " + ", ".join(found[:_SHOW]) if found else ""
    )


def _uneven_message(name: str, centres: np.ndarray, members: np.ndarray, tol: float) -> str:
    gaps = ", ".join(f"{g:.4f}" for g in np.diff(centres)[:12])
    levels = ", ".join(f"{c:.4f}" for c in centres[:12]) + (" ..." if len(centres) > 12 else "")
    text = (
        f"uneven grid spacing along {name}: levels {levels} mm, gaps {gaps} mm "
        f"(must be equal within {tol:g} mm)"
    )
    typical = np.median(members)
    stray = np.flatnonzero(members < typical)
    if stray.size:
        listed = ", ".join(f"{name}={centres[i]:.4f} ({members[i]} rows)" for i in stray[:_SHOW])
        text += f"; sparsely populated levels (stray points?): {listed}"
    return text


def _common_orientation(meas: Measurements) -> np.ndarray | None:
    """The one a,b,c of the session (deg), or None; InputError if rows differ by > tolerance."""
    if meas.abc is None:
        return None
    reference = meas.abc[0]
    angle = rotation_angle_deg(abc_to_matrix(meas.abc), abc_to_matrix(reference))
    bad = int(np.argmax(angle))
    if angle[bad] > ORIENTATION_TOL_DEG:
        raise InputError(
            f"a grid holds for one TCP orientation, but this row's a,b,c "
            f"{mm_text(meas.abc[bad], 4)} deg differs by {angle[bad]:.3f} deg from the first row's "
            f"{mm_text(reference, 4)} deg (limit {ORIENTATION_TOL_DEG:g} deg)",
            meas.path,
            None if meas.lines is None else int(meas.lines[bad]),
        )
    return reference.copy()


def _fmt_counts(counts: np.ndarray) -> str:
    return "x".join(str(int(c)) for c in counts)
