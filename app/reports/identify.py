"""The HTML report of ``accugrid identify --report-html``: what the calibrated YAML records in its
``identification:`` section (read back from the text written, so the report and the file say the
same), and the per-pose residual plot.

Verdict: PASS when the held-out max error is within the tolerance on every axis — the nested
cross-validation's estimate when the structure was chosen from the data (not the score the
selection minimised), else the cross-validation's —, FAIL when not, INFO without
cross-validation (``--folds 0``). Lengths mm, angles as named.
"""

from __future__ import annotations

import numpy as np
import yaml

from accugrid.app.reports.html import Figure, Section, Table, report_html
from accugrid.app.reports.plots import rows_png
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.kinematics.structure import CarryOver

__all__ = ["identify_report"]

_IN_TABLES = (  # the summary keys the report's own tables show; any other is listed as it is
    "robot",
    "measurements",
    "controller_tool",
    "tracker_T_robot",
    "poses",
    "rows",
    "identifiable_parameters",
    "condition_number",
    "observability_o1",
    "robust_sigma_mm",
    "outliers",
    "residual_rms_mm",
    "residual_max_mm",
    "cross_validation",
    "validity",
    "parameters",
    "unidentifiable_directions",
    "structure",
)


def _axes_text(value: object) -> str:
    """A summary value as short text: {x, y, z} as 'x 0.0123, y .., z ..', numbers to 6
    significant digits, mappings as 'key: value; ..', lists as '[.., ..]'."""
    if isinstance(value, dict) and set(value) == {"x", "y", "z"}:
        return ", ".join(f"{k} {float(value[k]):.4f}" for k in "xyz")
    if isinstance(value, dict):
        return "; ".join(f"{k}: {_axes_text(v)}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_axes_text(v) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _pose_text(pose: dict) -> str:
    """{x, y, z, a, b, c} as 'x .. y .. z .. mm, a .. b .. c .. deg'."""
    return (
        " ".join(f"{k} {float(pose[k]):.3f}" for k in "xyz")
        + " mm, "
        + " ".join(f"{k} {float(pose[k]):.3f}" for k in "abc")
        + " deg"
    )


def _summary_tables(summary: dict, held_out: dict | None, what: str) -> list[Table]:
    """The identification's summary as tables: the fit, the errors per axis, where the model
    holds."""
    n_params = len(summary.get("parameters", []))
    fit = [
        ["controller tool", _pose_text(summary["controller_tool"])],
        ["poses / rows measured", f"{summary.get('poses')} / {summary.get('rows')}"],
        ["identifiable parameters", f"{summary.get('identifiable_parameters')} of {n_params}"],
        ["condition number", f"{float(summary['condition_number']):.6g}"],
        ["observability O1", f"{float(summary['observability_o1']):.6g}"],
        ["robust sigma of the residuals (mm)", f"{float(summary['robust_sigma_mm']):.4f}"],
        ["outlier rows", ", ".join(map(str, summary.get("outliers") or [])) or "none"],
    ]
    if "tracker_T_robot" in summary:
        fit.insert(2, ["robot base in the tracker frame", _pose_text(summary["tracker_T_robot"])])
    fit += [
        [str(key).replace("_", " "), _axes_text(value)]
        for key, value in summary.items()
        if key not in _IN_TABLES
    ]
    errors = [
        ["residual RMS (fit)", summary["residual_rms_mm"]],
        ["residual max (fit)", summary["residual_max_mm"]],
    ]
    if held_out is not None:
        errors += [[f"held-out RMS ({what})", held_out["rms"]]]
        errors += [[f"held-out max ({what})", held_out["max"]]]
    validity = summary.get("validity") or {}
    if validity.get("validated_max_mm"):
        errors.append(["validated error (max)", validity["validated_max_mm"]])
    tables = [
        Table(["quantity", "value"], fit, "Identification"),
        Table(
            ["error", "X (mm)", "Y (mm)", "Z (mm)"],
            [[name] + [f"{float(v[k]):.4f}" for k in "xyz"] for name, v in errors],
            "Errors per axis, measured - model",
        ),
    ]
    return tables + (_validity_tables(validity) if validity else [])


def _validity_tables(validity: dict) -> list[Table]:
    """Where the model holds: the box of the poses, the tool axis and the tilt from it, the
    axis ranges."""
    box = [
        ["box min (mm)"] + [f"{float(v):.3f}" for v in validity["box_min_mm"]],
        ["box max (mm)"] + [f"{float(v):.3f}" for v in validity["box_max_mm"]],
        ["mean tool Z (unit vector)"] + [f"{float(v):+.4f}" for v in validity["tool_axis"]],
    ]
    joints = [
        [f"A{i}", f"{float(lo):.2f}", f"{float(hi):.2f}"]
        for i, (lo, hi) in enumerate(validity["joints_deg"], 1)
    ]
    return [
        Table(
            ["", "X", "Y", "Z"],
            box,
            "Where the model holds: the identification poses (tool Z within "
            f"{float(validity['tilt_deg']):.2f} deg of their mean)",
        ),
        Table(["axis", "min (deg)", "max (deg)"], joints, "Axis ranges of the poses (KUKA)"),
    ]


def identify_report(
    yaml_text: str,
    residuals: np.ndarray,
    inputs: list[tuple[str, str | None]],
    tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    controller: str = "",
) -> str:
    """The report page: ``yaml_text`` the calibrated robot YAML written, ``residuals`` (N, 3)
    mm measured - model per row, ``inputs`` (role, path), ``controller`` the line on the
    controller's own kinematics (``jobs.identify.controller_text``; "" for none)."""
    summary = yaml.safe_load(yaml_text)["identification"]
    structure = summary.get("structure") or {}
    nested = structure.get("nested")
    cv = summary.get("cross_validation")
    if nested is not None:
        held_out, rms = nested["held_out_max_mm"], nested["held_out_rms_mm"]
        what = (
            f"Nested {nested['folds']}-fold cross-validation (the structure chosen again inside "
            "each outer fold; held-out rows predicted by a model that never saw them)"
        )
    elif cv is not None:
        held_out, rms = cv["predicted_max_mm"], cv["predicted_rms_mm"]
        what = f"{cv['folds']}-fold cross-validation over the poses (held-out rows)"
    else:
        held_out, what = None, "No cross-validation (--folds 0): no pass criterion."
    if held_out is not None:
        what += f": RMS {_axes_text(rms)} mm, max {_axes_text(held_out)} mm."
    if held_out is None:
        verdict = "INFO"
        lines = [what]
    else:
        worst = max(float(held_out[k]) for k in "xyz")
        verdict = "PASS" if worst <= tolerance_mm else "FAIL"
        lines = [f"{what} PASS when the held-out max is within ±{tolerance_mm:g} mm on every axis."]
    lines += _carry_over_lines(structure.get("carry_over"))
    summary_tables = _summary_tables(
        summary,
        None if held_out is None else {"rms": rms, "max": held_out},
        "nested cross-validation" if nested is not None else "cross-validation",
    )
    parameters = Table(
        ["parameter", "value", "std", "unit", "identifiable alone"],
        [
            [p["name"], f"{p['value']:+.6g}", f"{p['std']:.2g}", p["unit"], _yes(p["identifiable"])]
            for p in summary.get("parameters", [])
        ],
        "Identified parameters (value ± standard deviation)",
    )
    directions = summary.get("unidentifiable_directions") or []
    null = Table(
        ["unidentifiable direction (held at 0)"],
        [[d] for d in directions] or [["none"]],
        "Directions the measurements cannot see",
    )
    figure = Figure(
        rows_png(residuals, tolerance_mm, "measured - model (mm)", "row of the measurement file"),
        "Residual of every measured row after identification (fit, not held out); dashed: the "
        f"tolerance ±{tolerance_mm:g} mm.",
    )
    tables = [parameters, null]
    if structure.get("mode") in ("auto", "search"):
        tables.insert(0, _structure_table(structure))
    return report_html(
        "Robot model identification",
        verdict,
        f"±{tolerance_mm:g} mm per axis (held-out max)",
        inputs,
        [
            Section("Validation", lines, summary_tables),
            *([Section("Controller", [controller.strip()])] if controller else []),
            Section("Residuals", figures=[figure]),
            Section("Model", tables=tables),
        ],
        [("robot", str(summary.get("robot", "")))],
    )


def _carry_over_lines(carry: dict | None) -> list[str]:
    """The chosen model held out by joint range against DH + TCP (``carry_over``, mm), with the
    warning when the chosen terms do worse there."""
    if carry is None:
        return []
    chosen, dh = carry["held_out_rms_mm"], carry["dh_held_out_rms_mm"]
    check = CarryOver(*(np.array([float(v[k]) for k in "xyz"]) for v in (chosen, dh)))
    line = (
        f"Held out by joint range (each joint's range in blocks, each predicted from the rest): "
        f"RMS {_axes_text(chosen)} mm; DH + TCP only {_axes_text(dh)} mm."
    )
    if not check.holds:
        line += (
            " The chosen terms do not hold beyond the joint combinations of these poses: measure "
            "poses that cover the targets' joint space (targets without support get the DH-only "
            "fit)."
        )
    return [line]


def _structure_table(structure: dict) -> Table:
    """The cross-validation curve of the structure search: each group added, its parameters and
    the held-out RMS and max (mm); the chosen steps marked."""
    kept = int(structure.get("kept_steps", 0))
    rows = [
        [
            step["added"],
            str(step["parameters"]),
            _slashed(step["held_out_rms_mm"]),
            _slashed(step["held_out_max_mm"]),
            "chosen" if i <= kept else "left out",
        ]
        for i, step in enumerate(structure.get("cv_curve", []))
    ]
    pinned = ", ".join(structure.get("pinned") or []) or "none"
    return Table(
        [
            "group added",
            "parameters",
            "held-out RMS X / Y / Z (mm)",
            "held-out max X / Y / Z (mm)",
            "",
        ],
        rows,
        f"Joint-error structure chosen from the data (pinned: {pinned})",
    )


def _slashed(value: dict) -> str:
    """{x, y, z} mm as 'x / y / z', 4 decimals."""
    return " / ".join(f"{float(value[k]):.4f}" for k in "xyz")


def _yes(flag: bool) -> str:
    return "yes" if flag else "no (combination)"
