"""The cell file: the example loads to the documented frames, and every bad key is named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from accugrid.codegen.cell import load_cell
from accugrid.kinematics.errors import InputError
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
    np.testing.assert_array_equal(cell.robot_T_program, cell.robot_T_base)


def test_defaults_and_relative_paths(tmp_path):
    cell = load_cell(write(tmp_path, MINIMAL + "grid: sub/m.csv\nbase_data: {5: {x: 10}}\n"))
    assert cell.grid_path == tmp_path / "sub" / "m.csv"
    assert sorted(cell.base_data) == [2, 5]
    np.testing.assert_allclose(cell.base_data[5][:3, 3], [10, 0, 0])
    assert cell.retract_mm == cell.approach_mm
    assert cell.program_name == "ACCUGRID" and cell.decimals == 3
    assert cell.status is None and not cell.allow_config_change
    assert cell.reference_abc == (0.0, 90.0, 0.0)


def test_correction_section_is_one_settings_value(tmp_path):
    text = MINIMAL + "correction: {method: trilinear, iterations: 3}\n"
    settings = load_cell(write(tmp_path, text)).correction
    assert (settings.method, settings.iterations, settings.power) == ("trilinear", 3, 1.0)
    assert load_cell(write(tmp_path, MINIMAL)).correction.method == "idw"


def test_program_frame_overrides_base(tmp_path):
    cell = load_cell(write(tmp_path, MINIMAL + "program_frame: {x: 1, y: 2, z: 3}\n"))
    np.testing.assert_allclose(cell.robot_T_program[:3, 3], [1, 2, 3])
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
