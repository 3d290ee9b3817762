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

from accugrid.app.plots import rows_png
from accugrid.app.report_html import Figure, Section, Table, report_html
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM

__all__ = ["identify_report"]

_SHOWN = (
    "parameters",
    "unidentifiable_directions",
    "cross_validation",
    "measurements",
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


def identify_report(
    yaml_text: str,
    residuals: np.ndarray,
    inputs: list[tuple[str, str | None]],
    tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    controller: str = "",
) -> str:
    """The report page: ``yaml_text`` the calibrated robot YAML written, ``residuals`` (N, 3)
    mm measured - model per row, ``inputs`` (role, path), ``controller`` the line on the
    controller's own kinematics (``calibration.controller_text``; "" for none)."""
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
    facts = [
        (str(key).replace("_", " "), _axes_text(value))
        for key, value in summary.items()
        if key not in _SHOWN
    ]
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
            Section("Validation", lines),
            *([Section("Controller", [controller.strip()])] if controller else []),
            Section("Residuals", figures=[figure]),
            Section("Model", tables=tables),
        ],
        facts,
    )


def _structure_table(structure: dict) -> Table:
    """The cross-validation curve of the structure search: each group added, its parameters and
    the held-out RMS and max (mm); the chosen steps marked."""
    kept = int(structure.get("kept_steps", 0))
    rows = [
        [
            step["added"],
            str(step["parameters"]),
            _axes_text(step["held_out_rms_mm"]),
            _axes_text(step["held_out_max_mm"]),
            "chosen" if i <= kept else "left out",
        ]
        for i, step in enumerate(structure.get("cv_curve", []))
    ]
    pinned = ", ".join(structure.get("pinned") or []) or "none"
    return Table(
        ["group added", "parameters", "held-out RMS (mm)", "held-out max (mm)", ""],
        rows,
        f"Joint-error structure chosen from the data (pinned: {pinned})",
    )


def _yes(flag: bool) -> str:
    return "yes" if flag else "no (combination)"
