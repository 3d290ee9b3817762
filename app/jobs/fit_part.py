"""``accugrid fit-part``: the part frame (``robot_T_base``) from datums measured by the tracker
and their CAD coordinates, written as a part file (``codegen.part_file``), with each dialect's
line that sets the base frame on its controller."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.app.jobs.robot_frame import load_frame
from accugrid.codegen.dialects import DIALECTS, plugin_of
from accugrid.codegen.part_file import part_yaml
from accugrid.infra.atomic import JobFiles
from accugrid.infra.csvtable import Table, read_table
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import invert, transform_points, xyzabc_from_pose
from accugrid.kinematics.part_frame import PartFit, fit_part_frame, thermal_scale

__all__ = ["PartRequest", "fit_part_files"]


@dataclass(frozen=True)
class PartRequest:
    """DATUMS (id, x, y, z mm: robot frame, or tracker frame with ``frame``, a fit-frame
    file), NOMINAL (id, x, y, z mm: CAD, part frame), the output; ``scale``: "rigid" or "fit";
    ``cte_per_k`` with ``temperature_c``: the scale of a part at that temperature; ``number``:
    the base number of the printed controller lines."""

    datums: str
    nominal: str
    output: str
    frame: str | None = None
    scale: str = "rigid"
    cte_per_k: float | None = None
    temperature_c: float | None = None
    number: int = 1


def _points(path: str) -> tuple[Table, list[str], np.ndarray]:
    """A datum table: the table, its ids (stripped) and x, y, z (N, 3) mm."""
    table = read_table(path)
    table.require(["id", "x", "y", "z"])
    ids = [cell.strip() for cell in table.text("id")]
    for r, name in enumerate(ids):
        if not name:
            raise InputError("empty id: every datum needs its id", *table.where(r, "id"))
    return table, ids, table.floats(["x", "y", "z"])


def _nominal(path: str) -> tuple[dict[str, int], np.ndarray]:
    """The CAD datums: id -> row, and x, y, z (N, 3) mm; a repeated id is an error."""
    table, ids, xyz = _points(path)
    rows: dict[str, int] = {}
    for r, name in enumerate(ids):
        if name in rows:
            raise InputError(
                f"datum {name} repeats line {table.lines[rows[name]]}", *table.where(r, "id")
            )
        rows[name] = r
    return rows, xyz


def _few(ids, most: int = 12) -> str:
    """The first ``most`` ids, comma-separated, "..." when there are more."""
    ids = list(ids)
    return ", ".join(ids[:most]) + (", ..." if len(ids) > most else "")


def _scale(req: PartRequest) -> tuple[float | None, str]:
    """The scale to fit with (None: fit it) and its source word."""
    if (req.cte_per_k is None) != (req.temperature_c is None):
        raise InputError("--cte and --temperature go together")
    if req.cte_per_k is not None:
        if req.scale == "fit":
            raise InputError("--scale fit and --cte fix the scale twice: give one of them")
        return thermal_scale(req.cte_per_k, req.temperature_c), "cte"
    return (None, "fit") if req.scale == "fit" else (1.0, "rigid")


def fit_part_files(req: PartRequest) -> JobFiles:
    """The part file at ``req.output`` and the lines to print. Datums measured several times
    (one id on several rows) are averaged. InputError (located at the datum's row) for fewer
    than 3 datums, datums on one line, an id the CAD file lacks, or a moved datum."""
    scale, scale_from = _scale(req)
    cad_rows, cad = _nominal(req.nominal)
    table, ids, measured = _points(req.datums)
    if not ids:
        raise InputError("no datums: the part frame needs at least 3", req.datums)
    if req.frame is not None:
        measured = transform_points(invert(load_frame(req.frame)), measured)
    names, first, group = np.unique(np.array(ids, dtype=object), True, True)
    order = np.argsort(first)  # datums in the order of their first row
    names, first = names[order], first[order]
    group = np.argsort(order)[group]
    for name, r in zip(names, first, strict=True):
        if name not in cad_rows:
            raise InputError(
                f"datum {name} is not in {Path(req.nominal).name} (its ids: {_few(cad_rows)})",
                *table.where(int(r), "id"),
            )
    counts = np.bincount(group, minlength=len(names))
    means = np.zeros((len(names), 3))
    np.add.at(means, group, measured)
    means /= counts[:, None]
    nominal = cad[[cad_rows[name] for name in names]]
    where = [table.where(int(r), "id") for r in first]
    fit = fit_part_frame(nominal, means, list(names), scale, where)
    inputs = {"datums": req.datums, "nominal": req.nominal}
    if req.frame is not None:
        inputs["frame"] = req.frame
    digests = {key: (Path(p).name, file_sha256(p)) for key, p in inputs.items()}
    text = part_yaml(fit, list(names), nominal, means, scale_from, digests)
    unmeasured = [name for name in cad_rows if name not in set(names)]
    lines = _summary(req, fit, list(names), nominal, counts, unmeasured)
    return JobFiles({req.output: text}, list(inputs.values()), lines)


def _summary(
    req: PartRequest,
    fit: PartFit,
    names: list[str],
    nominal: np.ndarray,
    counts: np.ndarray,
    unmeasured: list[str],
) -> list[str]:
    x, y, z, a, b, c = xyzabc_from_pose(fit.robot_T_base)
    per_axis, u95 = fit.sigma_at(nominal)
    centre = fit.sigma_at(fit.nominal_centroid[None])[1][0]
    lines = [
        f"{req.output}: robot_T_base x {x:.3f} y {y:.3f} z {z:.3f} mm, a {a:.4f} b {b:.4f} "
        f"c {c:.4f} deg; scale {fit.scale:.9f}; {len(names)} datums",
        f"residual RMS {np.sqrt(np.mean(fit.residuals_mm**2)):.4f} mm, noise sigma "
        f"{fit.sigma_mm:.4f} mm per axis ({fit.dof} degrees of freedom); the frame's 95 % "
        f"bound: {centre:.4f} mm at the datums' centre, {u95.max():.4f} mm at the farthest datum",
    ]
    for i, name in enumerate(names):
        miss = fit.loo_mm[i]
        others = "" if np.isnan(miss) else f", the others put it {miss:.4f} mm off"
        lines.append(
            f"  datum {name}: residual {fit.residuals_mm[i]:.4f} mm{others}; 1 sigma "
            f"{' '.join(f'{v:.4f}' for v in per_axis[i])} mm"
            + (f" ({counts[i]} measurements averaged)" if counts[i] > 1 else "")
        )
    if np.isnan(fit.loo_mm).all():
        lines.append(
            f"{len(names)} datums: a moved datum cannot be told from the others (measure 4 or "
            "more, any 3 of them off one line)"
        )
    else:
        worst = int(np.nanargmax(fit.loo_ratio))
        lines.append(
            f"largest miss: datum {names[worst]}, {fit.loo_ratio[worst]:.1f}x what the others' "
            "residuals lead to expect (a moved datum is refused from 10x)"
        )
    if fit.scale != 1.0:
        lines.append(
            f"the part is {fit.scale:.9f} times its CAD size: scale the x, y, z of its points "
            "file and of its datums' CAD file by it and fit again without --scale/--cte for a "
            "cell (a cell's base is rigid and refuses a scaled part)"
        )
    if unmeasured:
        lines.append(f"not measured: {_few(unmeasured)}")
    for name, dialect in DIALECTS.items():
        lines.append(f"{dialect.title}: {plugin_of(name).base_line(req.number, fit.robot_T_base)}")
    lines.append(f"cell: base: {{file: {os.fspath(req.output)}, number: {req.number}}}")
    return lines
