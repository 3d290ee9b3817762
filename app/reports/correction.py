"""The HTML report of a correction job (``correct``, ``krl``, ``gcode``, ``rapid``, ``rewrite``
with ``--report-html``): the outputs with their SHA-256, the robot, tool, base and cell, what was
checked for every position, the correction applied per position on a plan view of the holes'
best-fit plane, its statistics, and every position flagged or left uncorrected with the
correction policy's words (``compensation.policy.Verdict``).

The box on top says what was done, never PASS: every drilling position corrected, or how many
were left as they are (a job written with --allow-partial, in the FAIL colour). Where the robot
lands is measured afterwards by ``accugrid validate``. Lengths mm.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Iterable, Iterator, Mapping
from os import PathLike

import numpy as np

from accugrid.app.reports.html import Figure, Section, Table, report_html
from accugrid.app.reports.plots import correction_map_png
from accugrid.compensation.policy import Policy, Verdict
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM

__all__ = [
    "CORRECTED",
    "FLAGGED",
    "NOT_CORRECTED",
    "SKIPPED",
    "ReportedFiles",
    "cell_setup",
    "checks_text",
    "correction_report",
    "verdict_states",
]

_LISTED = 100  # positions listed in the table of flagged / not corrected ones


CORRECTED, FLAGGED, NOT_CORRECTED, SKIPPED = 0, 1, 2, 3  # the states of a position
_STATE_WORDS = ("corrected", "flagged", "not corrected", "skipped")


def verdict_states(verdict: Verdict) -> tuple[np.ndarray, list[str]]:
    """The state (N,) of each position of the policy's ``verdict`` and its words (N)."""
    reasons = verdict.reasons()
    state = np.where(verdict.corrected, CORRECTED, NOT_CORRECTED)
    state[verdict.corrected & np.array([bool(r) for r in reasons], dtype=bool)] = FLAGGED
    return state, reasons


def cell_setup(cell) -> list[tuple[str, str]]:
    """The robot, tool, base and cell file of a ``codegen.cell_record.Cell``: (key, text) lines, the
    tool (flange_T_tool) and base (robot_T_base) as their number in the cell, x, y, z mm and
    a, b, c deg as the cell file writes them."""
    from accugrid.kinematics.frames import xyzabc_from_pose

    def pose(number: int, matrix: np.ndarray) -> str:
        x, y, z, a, b, c = xyzabc_from_pose(matrix)
        return f"{number}: x {x:.3f} y {y:.3f} z {z:.3f} mm, a {a:.3f} b {b:.3f} c {c:.3f} deg"

    return [
        ("robot", cell.robot_name),
        ("tool", pose(cell.tool_number, cell.flange_T_tool)),
        ("base", pose(cell.base_number, cell.robot_T_base)),
        ("cell", str(cell.path)),
    ]


def checks_text(policy: Policy) -> str:
    """What the correction policy checked for every drilling position, one sentence."""
    checks = []
    if policy.grid is not None:
        name = policy.grid_name
        box = f"inside the {name} box"
        if policy.settings.outside == "clamp":
            box += " (outside: the nearest cell's error, flagged)"
        checks.append(box)
        orientation = f"orientation within {policy.orientation_tol_deg:g} deg of the {name}'s"
        if policy.calibrated is None and not policy.allow_orientation:
            orientation += f" (flagged beyond, refused beyond {policy.orientation_limit_deg:g})"
        checks.append(orientation)
        if policy.grid_status is not None:
            checks.append(f"KUKA Status {policy.grid_status}, the {name}'s")
    if policy.calibrated is not None:
        checks.append(
            "reached by the controller in its own Status and landed by the calibrated arm "
            "within 0.001 mm"
        )
        checks.append(f"|A5| at least {policy.singular_deg:g} deg from the wrist singularity")
        if policy.validity is not None:
            checks.append(
                "inside the poses the model was identified from"
                + (" (refused beyond)" if policy.strict else " (flagged beyond)")
            )
    if policy.settings.max_correction_mm is not None:
        checks.append(f"|correction| at most {policy.settings.max_correction_mm:g} mm")
    return (
        "Checked for every drilling position before writing: "
        + "; ".join(checks)
        + ". Not checked here: where the robot lands (measure it: accugrid validate)."
    )


class ReportedFiles(Mapping):
    """A job's ``files`` (path -> bytes, text or text in pieces, as ``atomic.write_files`` takes
    them, possibly rendered on demand and fetched once) with the report at ``report`` last:
    ``render(outputs)`` makes its text from (path, SHA-256) of every file, hashed while each was
    written."""

    def __init__(
        self,
        files: Mapping,
        report: PathLike | str,
        render: Callable[[list[tuple[str, str]]], str],
    ) -> None:
        self._files, self._report, self._render = files, report, render
        self._digests: dict[object, str] = {}

    def __iter__(self) -> Iterator:
        yield from self._files
        yield self._report

    def __len__(self) -> int:
        return len(self._files) + 1

    def __getitem__(self, key):
        if key == self._report:
            return self._page()
        return self._hashed(key, self._files[key])

    def _hashed(self, key, data) -> Iterator[bytes | str]:
        digest = hashlib.sha256()
        for part in [data] if isinstance(data, (bytes, bytearray, str)) else data:
            digest.update(part.encode("utf-8") if isinstance(part, str) else part)
            yield part
        self._digests[key] = digest.hexdigest()

    def _page(self) -> Iterable[str]:
        missing = [str(key) for key in self._files if key not in self._digests]
        if missing:  # the mapping's order writes the report last: a caller broke it
            raise RuntimeError(f"the report is made before {', '.join(missing)} is written")
        yield self._render([(str(key), self._digests[key]) for key in self._files])


def _plane_axes(points: np.ndarray) -> np.ndarray:
    """Rows u, v, n (3, 3): the in-plane axes and the normal of the best-fit plane of points
    (N, 3) in their frame. n: the direction of least spread, its largest component positive;
    u: the frame's axis after n's largest (cyclic: X for Z, Y for X, Z for Y) projected onto the
    plane, v = n x u: a panel in the frame's XY plane is drawn in X and Y, one in its YZ plane
    in Y and Z."""
    if len(points) < 3:
        return np.eye(3)
    normal = np.linalg.svd(points - points.mean(axis=0))[2][2]
    normal = normal * np.sign(normal[np.argmax(np.abs(normal))])
    axis = np.eye(3)[(int(np.argmax(np.abs(normal))) + 1) % 3]
    u = axis - (axis @ normal) * normal
    u /= np.linalg.norm(u)
    return np.array([u, np.cross(normal, u), normal])


def correction_report(
    title: str,
    points: np.ndarray,
    command: np.ndarray,
    state: np.ndarray,
    reasons: list[str],
    label: Callable[[int], str],
    inputs: list[tuple[str, str | None]],
    frame: str = "robot frame",
    tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    outputs: list[tuple[str, str]] | None = None,
    setup: list[tuple[str, str]] | None = None,
    checked: str = "",
) -> str:
    """The report page: positions and commands (N, 3) mm in ``frame`` (the part's frame of the
    holes; NaN rows: positions that are not points, left off the map), ``state`` (N,) of
    CORRECTED..SKIPPED, the policy's ``reasons`` (N), ``label(i)`` naming position i (file:line,
    id), ``inputs`` (role, path), ``outputs`` (path, SHA-256) of the files written, ``setup``
    (key, text): the robot, tool, base and cell; ``checked``: what the policy checked.
    SKIPPED: what is not a drilling position (a frame, a constant), listed, never a failure."""
    state = np.asarray(state)
    correction = np.where(state[:, None] <= FLAGGED, command - points, 0.0)
    corrected = state <= FLAGGED
    on_map = np.flatnonzero(np.isfinite(points).all(axis=1) & (state != SKIPPED))
    holes = on_map[state[on_map] <= FLAGGED]  # the plane of the holes, not of a home position
    axes = _plane_axes(points[holes if len(holes) >= 3 else on_map])
    in_plane = correction @ axes.T  # u, v, n components
    length = np.linalg.norm(correction, axis=1)
    stats = []
    done = np.flatnonzero(corrected)
    if done.size:
        for k, axis in enumerate("XYZ"):
            c = correction[done, k]
            stats.append(
                [axis, f"{c.min():+.3f}", f"{c.max():+.3f}", f"{c.mean():+.3f}", f"{c.std():.3f}"]
            )
        c = in_plane[done, 2]
        stats.append(
            ["normal n", f"{c.min():+.3f}", f"{c.max():+.3f}", f"{c.mean():+.3f}", f"{c.std():.3f}"]
        )
        c = length[done]
        stats.append(
            ["|c|", f"{c.min():.3f}", f"{c.max():.3f}", f"{c.mean():.3f}", f"{c.std():.3f}"]
        )
    listed = np.flatnonzero(state != CORRECTED)
    rows = [[label(int(i)), _STATE_WORDS[state[i]], reasons[i]] for i in listed[:_LISTED]]
    counts = np.bincount(state, minlength=4)
    drilling = len(state) - counts[SKIPPED]
    done_count = counts[CORRECTED] + counts[FLAGGED]
    plane = ", ".join(
        f"{name} ({' '.join(f'{v:+.3f}' for v in axes[k])})" for k, name in enumerate("uvn")
    )
    notes = [
        f"{len(state)} positions: {done_count} corrected "
        f"({counts[FLAGGED]} of them flagged), {counts[NOT_CORRECTED]} not corrected, "
        f"{counts[SKIPPED]} skipped (not drilling positions).",
        f"Correction c = command - target, {frame}, mm; the plan view lies in the holes' "
        f"best-fit plane: {plane} in the {frame}, n its normal.",
    ]
    if checked:
        notes.insert(1, checked)
    if listed.size > _LISTED:
        notes.append(f"The table lists the first {_LISTED} of {listed.size} such positions.")
    uv = (points[on_map] - points[on_map].mean(axis=0)) @ axes[:2].T if on_map.size else points
    figure = Figure(
        correction_map_png(
            uv,
            in_plane[on_map],
            corrected[on_map],
            state[on_map] == FLAGGED,
            f"best-fit plane, {frame}",
        ),
        "Plan view of the positions on the holes' best-fit plane (u, v), coloured by the length "
        "of their correction; red arrows: its in-plane part (scaled, at most 400 drawn); black "
        "crosses: not corrected; orange rings: flagged.",
    )
    tables = [
        Table(["axis", "min (mm)", "max (mm)", "mean (mm)", "std (mm)"], stats, "Correction"),
        Table(
            ["position", "status", "reason"],
            rows or [["none", "", ""]],
            "Positions flagged, not corrected or skipped",
        ),
    ]
    if counts[NOT_CORRECTED]:
        box, said = (
            "FAIL",
            f"{counts[NOT_CORRECTED]} of {drilling} drilling positions not corrected",
        )
    else:
        box, said = "INFO", f"all {drilling} drilling positions corrected"
    return report_html(
        title,
        box,
        f"±{tolerance_mm:g} mm per axis, checked after correction by accugrid validate",
        inputs,
        [Section("Corrections", notes, tables[:1], [figure]), Section("Positions", [], tables[1:])],
        [*(setup or []), ("correction", f"{said}; accuracy not measured (accugrid validate)")],
        outputs=outputs,
        verdict_text=said,
    )
