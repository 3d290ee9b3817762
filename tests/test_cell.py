"""The cell file: the example loads to the documented frames, and every bad key is named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from accugrid.codegen.cell import load_cell
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import transform_points

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "cell.yaml"

MINIMAL = """\
robot: kr210
tool: {number: 3, z: 250}
base: {number: 2, x: 1500, y: 0, z: 1000, a: 90}
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "cell.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_example_cell_frames():
    cell = load_cell(EXAMPLE)
    assert cell.robot_name == "kr210-paper"
    assert cell.grid_path == EXAMPLE.parent / "grid_200mm.csv"
    assert cell.tool_number == 1 and cell.base_number == 1
    # base Z out of the skin = robot -X; base X along the rows = robot -Y; base Y = robot Z
    np.testing.assert_allclose(cell.robot_T_base[:3, :3] @ [0, 0, 1], [-1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(cell.robot_T_base[:3, :3] @ [1, 0, 0], [0, -1, 0], atol=1e-12)
    np.testing.assert_allclose(
        transform_points(cell.robot_T_base, np.zeros((1, 3)))[0], [1700, 300, 1000]
    )
    np.testing.assert_allclose(cell.flange_T_tool[:3, 3], [0, 0, 250])
    assert cell.base_data[1] is cell.robot_T_base
    np.testing.assert_array_equal(cell.dialects["gcode"].robot_T_program, cell.robot_T_base)


def test_defaults_and_relative_paths(tmp_path):
    cell = load_cell(write(tmp_path, MINIMAL + "grid: sub/m.csv\nbase_data: {5: {x: 10}}\n"))
    assert cell.grid_path == tmp_path / "sub" / "m.csv"
    assert sorted(cell.base_data) == [2, 5]
    np.testing.assert_allclose(cell.base_data[5][:3, 3], [10, 0, 0])
    assert cell.drilling.retract_mm == cell.drilling.approach_mm
    assert (
        cell.dialects["krl"].name == "ACCUGRID"
        and cell.dialects["krl"].decimals == 3 == cell.dialects["gcode"].decimals
    )
    assert cell.configuration.status is None and not cell.configuration.allow_change
    assert cell.configuration.reference_abc == (0.0, 90.0, 0.0)


def test_correction_section_is_one_settings_value(tmp_path):
    text = MINIMAL + "correction: {method: trilinear, iterations: 3}\n"
    settings = load_cell(write(tmp_path, text)).correction
    assert (settings.method, settings.iterations, settings.power) == ("trilinear", 3, 1.0)
    assert load_cell(write(tmp_path, MINIMAL)).correction.method == "idw"


def test_program_frame_overrides_base(tmp_path):
    cell = load_cell(write(tmp_path, MINIMAL + "program_frame: {x: 1, y: 2, z: 3}\n"))
    np.testing.assert_allclose(cell.dialects["gcode"].robot_T_program[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(cell.robot_T_base[:3, 3], [1500, 0, 1000])


def test_sha256_is_of_the_file_bytes(tmp_path):
    import hashlib

    path = write(tmp_path, MINIMAL)
    assert load_cell(path).sha256 == hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.parametrize(
    "extra, key, line",
    [
        ("speeds: {feed: -1}\n", "speeds.feed", 4),
        ("speeds: {feed: fast}\n", "speeds.feed", 4),
        ("speeds: {fed: 1}\n", "speeds.fed", 4),
        ("colour: red\n", "colour", 4),
        ("program: {name: 1ABC}\n", "program.name", 4),
        ("program: {name: A_NAME_THAT_IS_MUCH_TOO_LONG}\n", "program.name", 4),
        ("program:\n  lines_per_file: 10\n", "program.lines_per_file", 5),
        ("drilling: {clearance: 40, approach: 30}\n", "drilling.clearance", 4),
        ("drilling: {travel_motion: spline}\n", "drilling.travel_motion", 4),
        ("configuration: {status: 9}\n", "configuration.status", 4),
        ("configuration: {allow_change: 1}\n", "configuration.allow_change", 4),
        ("outputs: {spindle: 1.5}\n", "outputs.spindle", 4),
        ("base_data: {x: {x: 1}}\n", "base_data.x", 4),
        ("base_data: {2: {x: 1}}\n", "base_data.2", 4),
        ("gcode: {canned_cycles: maybe}\n", "gcode.canned_cycles", 4),
        ("configuration: {reference: {a: 1, q: 2}}\n", "configuration.reference.q", 4),
        ("configuration:\n  reference: {b: x}\n", "configuration.reference.b", 5),
        ("correction: {method: cubic}\n", "correction.method", 4),
        ("correction: {model: ''}\n", "correction.model", 4),
        ("speeds: {ptp_percent: 0}\n", "speeds.ptp_percent", 4),
        ("drilling: {apo_cdis: -1}\n", "drilling.apo_cdis", 4),
        ("program: {decimals: 9}\n", "program.decimals", 4),
        ("outputs: {clamp: 0}\n", "outputs.clamp", 4),
        ("external_axes: {e7: 1}\n", "external_axes.e7", 4),
        ("external_axes:\n  e2: 1e9\n", "external_axes.e2", 5),
        ("gcode: {spindle_rpm: 0}\n", "gcode.spindle_rpm", 4),
        ("gcode: {decimals: 4}\n", "gcode.decimals", 4),
        ("program_frame: {number: 1}\n", "program_frame.number", 4),
        ("configuration: {singular_a5: 91}\n", "configuration.singular_a5", 4),
        ("drilling: {dwell: 61}\n", "drilling.dwell", 4),
        ("speeds: [1, 2]\n", "speeds", 4),
    ],
)
def test_bad_keys_are_named(tmp_path, extra, key, line):
    path = write(tmp_path, MINIMAL + extra)
    with pytest.raises(InputError) as info:
        load_cell(path)
    assert info.value.message.startswith(key + ":")
    assert info.value.path == str(path) and info.value.line == line


@pytest.mark.parametrize(
    "text, needle",
    [
        ("tool: {z: 1}\nbase: {number: 1}\n", "robot"),
        ("robot: kr210\nbase: {number: 1}\n", "tool"),
        ("robot: kr210\ntool: {number: 1, z: nan}\nbase: {number: 1}\n", "tool.z"),
        ("robot: kr210\ntool: {number: 1, q: 1}\nbase: {number: 1}\n", "tool.q"),
        ("robot: kr210\ntool: {number: 40}\nbase: {number: 1}\n", "tool.number"),
        ("robot: [kr210\n", "invalid YAML"),
        ("", "empty cell file"),
        ("- a\n- b\n", "must be a mapping"),
    ],
)
def test_missing_and_malformed(tmp_path, text, needle):
    with pytest.raises(InputError, match=needle):
        load_cell(write(tmp_path, text))


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="cannot read"):
        load_cell(tmp_path / "nope.yaml")


EVERY_KEY = """\
speeds: {travel: 400, approach: 40, feed: 4, ptp_percent: 30}
drilling: {approach: 20, clearance: 3, retract: 25, depth: 7, dwell: 0.2, peck: 1.5,
           travel_motion: lin, apo_cdis: 2, apo_ptp_percent: 40}
program: {name: PANEL_7, lines_per_file: 900, decimals: 4}
outputs: {spindle: 3, clamp: 4}
external_axes: {e1: 100, e6: -5.5}
configuration: {status: 6, turn: 2, allow_change: true, singular_a5: 8,
                reference: {a: 1, b: 89, c: 2}}
correction: {method: trilinear, iterations: 2, power: 2, model: cal.yaml}
gcode: {spindle_rpm: 9000, canned_cycles: false}
program_frame: {x: 5}
"""


def test_every_key_lands_in_its_section_record(tmp_path):
    """Each section record carries the values of the YAML keys it declares, written by hand
    above; ``program.decimals`` is read by both dialects."""
    cell = load_cell(write(tmp_path, MINIMAL + EVERY_KEY))
    d = cell.drilling
    assert (d.approach_mm, d.clearance_mm, d.retract_mm, d.depth_mm) == (20, 3, 25, 7)
    assert (d.dwell_s, d.peck_mm) == (0.2, 1.5)
    assert (d.travel_mm_s, d.approach_mm_s, d.feed_mm_s) == (400, 40, 4)
    k = cell.dialects["krl"]
    assert (k.name, k.lines_per_file, k.decimals, k.travel_motion) == ("PANEL_7", 900, 4, "lin")
    assert (k.ptp_percent, k.apo_cdis_mm, k.apo_ptp_percent) == (30, 2, 40)
    assert (k.spindle_output, k.clamp_output) == (3, 4)
    assert k.external_axes == (100, 0, 0, 0, 0, -5.5)
    g = cell.dialects["gcode"]
    assert (g.decimals, g.spindle_rpm, g.canned_cycles) == (4, 9000, False)
    np.testing.assert_allclose(g.robot_T_program[:3, 3], [5, 0, 0])
    f = cell.configuration
    assert (f.status, f.turn, f.allow_change, f.singular_a5_deg) == (6, 2, True, 8)
    assert f.reference_abc == (1, 89, 2)
    c = cell.correction
    assert (c.method, c.iterations, c.power) == ("trilinear", 2, 2)
    assert cell.model_path == tmp_path / "cal.yaml"


def test_section_records_are_frozen():
    import dataclasses

    cell = load_cell(EXAMPLE)
    for record in (
        cell,
        cell.drilling,
        cell.configuration,
        cell.correction,
        *cell.dialects.values(),
    ):
        with pytest.raises(dataclasses.FrozenInstanceError):
            record.sha256 = "x"


def test_every_dialect_brings_its_own_section():
    """A dialect's cell record comes from its own folder through the registry (issue 10)."""
    import importlib

    from accugrid.codegen.dialects import DIALECTS

    cell = load_cell(EXAMPLE)
    assert set(cell.dialects) == set(DIALECTS)
    for name in DIALECTS:
        module = importlib.import_module(f"accugrid.codegen.{name}.section")
        assert type(cell.dialects[name]).__module__ == module.__name__
        assert module.KEYS and all(isinstance(v, frozenset) for v in module.KEYS.values())
    assert not [name for name in DIALECTS if hasattr(cell, name)]  # the cell names no dialect
    assert (
        cell.dialects["krl"].name,
        cell.dialects["krl"].decimals,
        cell.dialects["gcode"].spindle_rpm,
    ) == ("WING_PANEL", 3, 6000)
