"""Robot, calibrated-robot, cell and frame files: an unknown key in any section is a located error
naming the nearest valid key; a misspelled section is never read as absent."""

from __future__ import annotations

import re

import pytest
from conftest import EXAMPLES

from accugrid.app.cli import main
from accugrid.app.jobs.robot_frame import load_frame
from accugrid.codegen.cell import load_cell
from accugrid.infra.errors import InputError
from accugrid.kinematics.robot import BUILTIN, load_robot

ROBOT = ["--robot", "kr210-realistic", "--tool", "0", "0", "250", "0", "0", "0"]


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """A calibrated file as `identify` writes it: errors, joint_errors (compliance, masses,
    harmonics), identification with cross-validation (the DH fit plus the pinned terms)."""
    folder = tmp_path_factory.mktemp("cal")
    plan, meas, out = folder / "plan", folder / "meas.csv", folder / "cal.yaml"
    harmonics = ["--compliance", "--harmonics", "A2:1"]
    assert main(["plan", "identify", *ROBOT, "--count", "40", *harmonics, "-o", str(plan)]) == 0
    poses = str(next(plan.glob("*.csv")))
    assert main(["simulate", *ROBOT, "--poses", poses, "--seed", "1", "-o", str(meas)]) == 0
    assert (
        main(["identify", str(meas), *ROBOT, *harmonics, "--structure", "dh", "-o", str(out)]) == 0
    )
    return out.read_text()


@pytest.fixture(scope="module")
def chosen(tmp_path_factory):
    """A calibrated file whose structure was chosen from the data (identification.structure)."""
    folder = tmp_path_factory.mktemp("auto")
    plan, meas, out = folder / "plan", folder / "meas.csv", folder / "cal.yaml"
    assert main(["plan", "identify", *ROBOT, "--count", "40", "-o", str(plan)]) == 0
    poses = str(next(plan.glob("*.csv")))
    assert main(["simulate", *ROBOT, "--poses", poses, "--seed", "1", "-o", str(meas)]) == 0
    assert main(["identify", str(meas), *ROBOT, "-o", str(out)]) == 0
    return out.read_text()


@pytest.mark.parametrize(
    ("pattern", "replacement", "message"),
    [
        (r"  structure:", "  structur:", "identification.structur: unknown key; did you mean "),
        (r"held_out_max_mm:", "held_out_mx_mm:", "unknown key; did you mean held_out_max_mm?"),
        (r"    kept_steps:", "    kept_step:", "structure.kept_step: unknown key; did you mean "),
    ],
)
def test_a_misspelt_key_in_the_chosen_structure_is_a_located_error(
    chosen, tmp_path, pattern, replacement, message
):
    text, line = misspell(chosen, pattern, replacement)
    path = tmp_path / "cal.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match=re.escape(message)) as error:
        load_robot(path)
    assert error.value.line == line


def test_a_negative_nested_estimate_is_refused(chosen, tmp_path):
    """The nested estimate is the model's claim (the residual-grid check relies on it)."""
    head, nested = chosen.split("    nested:\n")
    text, line = misspell(nested, r"held_out_max_mm: {x: ", "held_out_max_mm: {x: -")
    text, line = head + "    nested:\n" + text, line + head.count("\n") + 1
    path = tmp_path / "cal.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match=r"must be >= 0 mm") as error:
        load_robot(path)
    assert error.value.line == line


def test_every_built_in_robot_and_example_cell_loads():
    for name in BUILTIN:
        assert load_robot(name).name == name
    for cell in ("cell.yaml", "cell_heatsink.yaml"):
        load_cell(EXAMPLES / cell)


def test_a_calibrated_file_as_written_loads(calibrated, tmp_path):
    (tmp_path / "cal.yaml").write_text(calibrated)
    robot = load_robot(tmp_path / "cal.yaml")
    assert robot.errors is not None and robot.joint_errors is not None


MISSPELT = [
    # (line pattern, its misspelling, the message)
    (r"^errors:", "erors:", "erors: unknown key; did you mean errors?"),
    (r"^joint_errors:", "joint_error:", "joint_error: unknown key; did you mean joint_errors?"),
    (r"^tool:", "tol:", "tol: unknown key; did you mean tool?"),
    (r"- {da_mm:", "- {da_m:", "errors[0].da_m: unknown key; did you mean da_mm?"),
    (r"alpha_deg:", "alpha:", "dh[0].alpha: unknown key; did you mean alpha_deg?"),
    (r"  masses:", "  mases:", "joint_errors.mases: unknown key; did you mean masses?"),
    (r"  - link:", "  - lnk:", "joint_errors.masses[0].lnk: unknown key; did you mean link?"),
    (r"  harmonics:", "  harmonic:", "joint_errors.harmonic: unknown key; did you mean harmonics?"),
    (
        r"  controller_tool:",
        "  controler_tool:",
        "identification.controler_tool: unknown key; did you mean controller_tool?",
    ),
    (
        r"    predicted_max_mm:",
        "    predicted_max:",
        "identification.cross_validation.predicted_max: unknown key; did you mean "
        "predicted_max_mm?",
    ),
    (
        r"  measurements:",
        "  measurement:",
        "identification.measurement: unknown key; did you mean measurements?",
    ),
]


def misspell(text, pattern, replacement):
    """``text`` with the first line matching ``pattern`` changed; (text, 1-based line)."""
    lines = text.splitlines(keepends=True)
    at = next(i for i, line in enumerate(lines) if re.search(pattern, line))
    lines[at] = re.sub(pattern, replacement, lines[at], count=1)
    return "".join(lines), at + 1


@pytest.mark.parametrize(("pattern", "replacement", "message"), MISSPELT)
def test_a_misspelt_key_in_any_section_is_a_located_error(
    calibrated, tmp_path, pattern, replacement, message
):
    text, line = misspell(calibrated, pattern, replacement)
    path = tmp_path / "cal.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as error:
        load_robot(path)
    assert error.value.message == message
    key = replacement.lstrip(" -{")
    column = text.splitlines()[line - 1].index(key) + 1
    assert (error.value.path, error.value.line, error.value.column) == (str(path), line, column)


def test_correct_with_a_misspelt_errors_section_fails_instead_of_correcting_less(
    calibrated, tmp_path, capsys
):
    """The misspelt ``errors:`` was read as no DH errors (0.68 mm instead of 4.15 mm)."""
    text, line = misspell(calibrated, r"^errors:", "erors:")
    (tmp_path / "cal.yaml").write_text(text)
    points = tmp_path / "points.csv"
    points.write_text("x,y,z,a,b,c\n1700,0,1500,0,90,0\n")
    argv = ["correct", points, "--model", tmp_path / "cal.yaml", "-o", tmp_path / "out.csv"]
    assert main([str(a) for a in argv]) == 2
    assert f"cal.yaml:{line}:1: erors: unknown key; did you mean errors?" in capsys.readouterr().err
    assert not (tmp_path / "out.csv").exists()


def test_a_negative_validated_error_is_refused(calibrated, tmp_path):
    text, line = misspell(calibrated, r"predicted_max_mm: {x: ", "predicted_max_mm: {x: -")
    path = tmp_path / "cal.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match=r"predicted_max_mm.x' must be >= 0 mm") as error:
        load_robot(path)
    assert error.value.line == line


def test_a_list_where_a_section_belongs_is_refused(tmp_path):
    text = (EXAMPLES.parent / "kinematics" / "robots" / "kr210-paper.yaml").read_text()
    path = tmp_path / "robot.yaml"
    path.write_text(text + "joint_errors: [1, 2]\n")
    with pytest.raises(InputError, match="'joint_errors' must be a mapping"):
        load_robot(path)


@pytest.mark.parametrize(
    ("pattern", "replacement", "message"),
    [
        (r"^drilling:", "driling:", "driling: unknown key; did you mean drilling?"),
        (r"^  depth:", "  dept:", "drilling.dept: unknown key; did you mean depth?"),
        (r"^  feed:", "  fed:", "speeds.fed: unknown key; did you mean feed?"),
        (r"^program:", "zzz:", "zzz: unknown key (allowed: "),
    ],
)
def test_a_misspelt_cell_key_is_located_with_a_hint(tmp_path, pattern, replacement, message):
    text, line = misspell((EXAMPLES / "cell.yaml").read_text(), pattern, replacement)
    path = tmp_path / "cell.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as error:
        load_cell(path)
    assert error.value.message.startswith(message)
    assert (error.value.line, error.value.column) == (
        line,
        len(replacement) - len(replacement.lstrip()) + 1,
    )


def test_a_misspelt_frame_file_key_is_located(tmp_path, capsys):
    """A frame file as fit-frame writes it, with 'matrix' misspelt: its check would be skipped."""
    tracker = EXAMPLES / "tracker"
    frame = tmp_path / "frame.yaml"
    files = ["--base-plane", "base_plane.csv", "--a1-circle", "a1_circle.csv"]
    files += ["--flange-holes", "flange_holes.csv"]
    argv = ["fit-frame", *(f if f.startswith("--") else str(tracker / f) for f in files)]
    assert main([*argv, "-o", str(frame)]) == 0
    load_frame(frame)
    text, line = misspell(frame.read_text(), r"  matrix:", "  matirx:")
    frame.write_text(text)
    with pytest.raises(InputError) as error:
        load_frame(frame)
    assert error.value.message == "tracker_T_robot.matirx: unknown key; did you mean matrix?"
    assert (error.value.line, error.value.column) == (line, 3)
