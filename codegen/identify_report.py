"""The HTML report of ``accugrid identify --report-html``: what the calibrated YAML records in its
``identification:`` section (read back from the text written, so the report and the file say the
same), and the per-pose residual plot.

Verdict: PASS when the cross-validated (held-out) max error is within the tolerance on every
axis, FAIL when not, INFO without cross-validation (``--folds 0``). Lengths mm, angles as named.
"""

from __future__ import annotations

import numpy as np
import yaml

from accugrid.codegen.plots import rows_png
from accugrid.codegen.report_html import Figure, Section, Table, report_html
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM

__all__ = ["identify_report"]

_SHOWN = ("parameters", "unidentifiable_directions", "cross_validation", "measurements")


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
) -> str:
    """The report page: ``yaml_text`` the calibrated robot YAML written, ``residuals`` (N, 3)
    mm measured - model per row, ``inputs`` (role, path)."""
    summary = yaml.safe_load(yaml_text)["identification"]
    cv = summary.get("cross_validation")
    if cv is None:
        verdict = "INFO"
    else:
        held_out = [float(cv["predicted_max_mm"][k]) for k in "xyz"]
        verdict = "PASS" if max(held_out) <= tolerance_mm else "FAIL"
    facts = [
        (str(key).replace("_", " "), _axes_text(value))
        for key, value in summary.items()
        if key not in _SHOWN
    ]
    lines = []
    if cv is not None:
        lines.append(
            f"{cv['folds']}-fold cross-validation over the poses (held-out rows predicted by a "
            f"model fitted without them): RMS {_axes_text(cv['predicted_rms_mm'])} mm, max "
            f"{_axes_text(cv['predicted_max_mm'])} mm. PASS when the held-out max is within "
            f"±{tolerance_mm:g} mm on every axis."
        )
    else:
        lines.append("No cross-validation (--folds 0): no pass criterion.")
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
    return report_html(
        "Robot model identification",
        verdict,
        f"±{tolerance_mm:g} mm per axis (held-out max)",
        inputs,
        [
            Section("Validation", lines),
            Section("Residuals", figures=[figure]),
            Section("Model", tables=[parameters, null]),
        ],
        facts,
    )


def _yes(flag: bool) -> str:
    return "yes" if flag else "no (combination)"
