"""Position files as exports and loggers write them: units from headers and declarations (a
contradiction refused at its column), a trailing delimiter in every reader, joints in the wrong
unit and mirrored (swapped) columns refused with the likely fix, and the real UR10 series of
../shared/realdata read through the documented options, checked row by row against values
computed here from the file's text."""

from __future__ import annotations

import csv
import re
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
from conftest import EXAMPLES, REALDATA
from scipy.spatial.transform import Rotation

from accugrid.app.cli import build_parser, main
from accugrid.app.cli_options import reading_format
from accugrid.codegen.points import read_points
from accugrid.compensation.measurements import read_measurements
from accugrid.infra import csvtable
from accugrid.infra.csvtable import TableFormat, parse_table, read_table
from accugrid.infra.errors import InputError

TRACKER = EXAMPLES / "tracker"
CANONICAL = TRACKER / "grid_8.csv"
UR10_FORMAT = TRACKER / "ipa_ur10.yaml"
UR10_OPTIONS = [
    "--delimiter",
    "semicolon",
    "--decimal",
    "comma",
    "--columns",
    "x=Goal x,y=Goal y,z=Goal z,a=Goal yaw,b=Goal pitch,c=Goal roll,a1=shoulder_pan_joint,"
    "a2=shoulder_lift_joint,a3=elbow_joint,a4=wrist_1_joint,a5=wrist_2_joint,a6=wrist_3_joint,"
    "x_meas=measurement_x,y_meas=measurement_y,z_meas=measurement_z",
    "--units",
    "m,rad,x_meas=mm,y_meas=mm,z_meas=mm",
]
SERIES = {"A": "Series_A/measurements_grid.csv", "C": "Series_C/measurements_random_poses.csv"}
JOINTS = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
]


def _format(*options: str) -> TableFormat:
    """The TableFormat the CLI builds from ``options`` (parsed by the real parser)."""
    args = build_parser("identify").parse_args(
        ["identify", "M.csv", "--robot", "kr210", "-o", "O", *options]
    )
    with reading_format(args):
        return csvtable._FORMAT.get()


# -- units -------------------------------------------------------------------------------------


def test_a_metre_export_with_its_mapping_reads_its_header_unit():
    """The tracker export whose headers say (m), read with its column mapping and no --units:
    the same numbers as the canonical mm file (before, 1000x too small and silently so)."""
    mapping = (
        "id=Name,x=Nominal X,y=Nominal Y,z=Nominal Z,x_meas=Measured X,y_meas=Measured Y,"
        "z_meas=Measured Z"
    )
    export = read_measurements(TRACKER / "polyworks_grid_8_m.txt", _format("--columns", mapping))
    canonical = read_measurements(CANONICAL)
    assert np.array_equal(export.commanded, canonical.commanded)
    assert np.array_equal(export.measured, canonical.measured)


@pytest.mark.parametrize(
    ("unit", "scale"), [("[in]", Decimal("25.4")), ("(m)", Decimal(1000)), ("_mm", Decimal(1))]
)
def test_headers_that_name_a_unit_are_read_in_it(unit, scale):
    """``x [in]``, ``x (m)``, ``x_mm``: the column x in that unit, converted exactly."""
    names = ["x", "y", "z", "x_meas", "y_meas", "z_meas"]
    values = ["1.5", "-0.25", "1.125", "1.5625", "-0.375", "1.0001"]
    text = "id," + ",".join(f"{n} {unit}" if unit[0] in "[(" else f"{n}{unit}" for n in names)
    text += "\nP1," + ",".join(values) + "\n"
    table = parse_table(text, "m.csv")
    expected = [float(Decimal(v) * scale) for v in values]
    assert table.floats(names)[0].tolist() == expected
    assert table.header[1:] == names


def test_a_header_unit_contradicting_the_declared_one_is_refused_at_its_column():
    with pytest.raises(InputError) as info:
        parse_table("id,x [m],y,z\nP1,1,2,3\n", "g.csv", TableFormat(units="mm"))
    error = info.value
    assert (error.path, error.line, error.column) == ("g.csv", 1, 2)
    assert "column 'x [m]' is in m by its header, but the units declared for x are mm" in str(error)
    # the same unit twice is no contradiction
    assert parse_table("x [m]\n1.5\n", "g.csv", TableFormat(units="m")).floats(["x"])[0, 0] == 1500


def test_a_header_naming_an_angle_unit_on_a_length_is_refused():
    with pytest.raises(
        InputError, match=r"column 'x \[rad\]' names the unit rad, but x holds lengths"
    ):
        parse_table("x [rad],y,z\n1,2,3\n", "g.csv")


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("km", "unknown unit 'km'"),
        ("x=rad", "rad is not a unit of lengths"),
        ("a1=mm", "mm is not a unit of angles"),
        ("q=mm", "q is not a length or angle column"),
        ("m,in", "the unit of length is declared twice"),
    ],
)
def test_bad_units_are_refused_by_the_parser(spec, message, capsys):
    with pytest.raises(SystemExit) as info:
        main(["correct", "p.csv", "--grid", "g.csv", "-o", "o.csv", "--units", spec])
    assert info.value.code == 2
    assert message in capsys.readouterr().err


def test_an_inch_points_file_is_refused_by_the_program_job_naming_the_unit(tmp_path, capsys):
    """Targets of a points file in inch read as mm all lie inside the robot's base: refused,
    naming inch, nothing written; with [in] headers the same numbers make the program (--units
    in would apply to the job's grid too). The cell's BASE is the robot frame here, as for the
    example's robot-frame holes."""
    source = (EXAMPLES / "wing_panel_robot.csv").read_text().splitlines()
    header = next(i for i, line in enumerate(source) if line.startswith("id,"))
    names = source[header].split(",")
    rows = list(csv.reader(source[header + 1 :]))
    lengths = [names.index(n) for n in ("x", "y", "z", "diameter", "depth")]
    inch = [
        [f"{float(c) / 25.4:.6f}" if i in lengths and c else c for i, c in enumerate(row)]
        for row in rows
    ]
    points = tmp_path / "inch.csv"
    points.write_text("\n".join(",".join(r) for r in [names, *inch]) + "\n")
    cell = tmp_path / "cell.yaml"
    base = "base: {number: 1, x: 0, y: 0, z: 0, a: 0, b: 0, c: 0}"
    text = (EXAMPLES / "cell.yaml").read_text()
    cell.write_text(re.sub(r"^base: .*$", base, text, flags=re.M))
    (tmp_path / "grid_200mm.csv").write_bytes((EXAMPLES / "grid_200mm.csv").read_bytes())
    out = tmp_path / "out"
    assert main(["krl", str(points), "--cell", str(cell), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{points}:" in err and len(err.splitlines()) == 1
    assert "every target lies within" in err
    assert "are the file's lengths in in? (read them with --units in)" in err
    assert not out.exists()
    named = tmp_path / "named.csv"
    header_in = [f"{n} [in]" if i in lengths else n for i, n in enumerate(names)]
    named.write_text("\n".join(",".join(r) for r in [header_in, *inch]) + "\n")
    assert main(["krl", str(named), "--cell", str(cell), "-o", str(tmp_path / "o2")]) == 0


# -- trailing delimiter ---------------------------------------------------------------------


READERS = {
    "measurements": lambda p: read_measurements(p).measured,
    "points": lambda p: read_points(p).xyz,
    "table": lambda p: read_table(p).floats(["x", "y", "z"]),
}


@pytest.mark.parametrize("reader", sorted(READERS))
@pytest.mark.parametrize("delimiter", [",", ";"])
def test_every_reader_takes_a_trailing_delimiter(tmp_path, reader, delimiter):
    text = CANONICAL.read_text()
    if reader == "points":  # a points file: ids and positions
        text = "id,x,y,z\nH1,1250.5,-550,1150\nH2,1333.25,-420.75,1280.125\n"
    plain = tmp_path / "plain.csv"
    plain.write_text(text.replace(",", delimiter))
    trailing = tmp_path / "trailing.csv"
    trailing.write_text(
        "".join(
            line if line.startswith("#") else line.rstrip("\n") + delimiter + "\n"
            for line in plain.read_text().splitlines(keepends=True)
        )
    )
    assert np.array_equal(READERS[reader](trailing), READERS[reader](plain))


def test_a_trailing_delimiter_only_on_the_rows_and_a_filled_last_cell(tmp_path):
    assert parse_table("x,y,z\n1,2,3,\n", "t.csv").floats(["x", "y", "z"]).tolist() == [[1, 2, 3]]
    with pytest.raises(InputError) as info:
        parse_table("x,y,z,\n1,2,3,4\n", "t.csv")
    assert (info.value.line, info.value.message) == (2, "4 fields, but the header has 3")


def test_fit_frame_and_transform_take_a_trailing_delimiter(tmp_path, capsys):
    files = {}
    for flag, name in (
        ("--base-plane", "base_plane.csv"),
        ("--a1-circle", "a1_circle.csv"),
        ("--flange-holes", "flange_holes.csv"),
    ):
        lines = (TRACKER / name).read_text().splitlines(keepends=True)
        files[flag] = tmp_path / name
        files[flag].write_text(
            "".join(x if x.startswith("#") else x.rstrip("\n") + ",\n" for x in lines)
        )
    frame = tmp_path / "frame.yaml"
    plain = tmp_path / "plain.yaml"
    args = [x for flag, path in files.items() for x in (flag, str(path))]
    assert main(["fit-frame", *args, "-o", str(frame)]) == 0
    args = [x for flag, path in files.items() for x in (flag, str(TRACKER / path.name))]
    assert main(["fit-frame", *args, "-o", str(plain)]) == 0
    assert [ln for ln in frame.read_text().splitlines() if "sha256" not in ln] == [
        ln for ln in plain.read_text().splitlines() if "sha256" not in ln
    ]
    out = tmp_path / "out.csv"
    assert (
        main(["transform", str(files["--base-plane"]), "--frame", str(frame), "-o", str(out)]) == 0
    )
    body = [ln for ln in out.read_text().splitlines() if not ln.startswith("#")]
    assert all(ln.endswith(",") for ln in body)


# -- joints in the wrong unit, swapped columns ----------------------------------------------


def _ur10_rows(series: str) -> tuple[list[str], list[list[str]]]:
    """The header and rows of a UR10 series, split by the csv module (independent reader)."""
    path = REALDATA / "ipa-ur10" / SERIES[series]
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f, delimiter=";"))
    return rows[0], rows[1:]


@pytest.fixture(scope="module")
def realdata() -> Path:
    if not (REALDATA / "ipa-ur10").is_dir():
        pytest.fail(f"{REALDATA} is missing: the real tracker data must sit beside the checkout")
    return REALDATA


def test_radians_read_as_degrees_are_refused_at_the_joint_column(realdata, tmp_path):
    """The UR10 series with its joints declared in degrees (rad,... left out): every joint lies
    within +-6.3 deg over the whole series: refused at column a1's header, naming --units rad."""
    wrong = _format("--format", str(UR10_FORMAT), "--units", "m,x_meas=mm,y_meas=mm,z_meas=mm")
    path = realdata / "ipa-ur10" / SERIES["C"]
    with pytest.raises(InputError) as info:
        read_measurements(path, wrong)
    error = info.value
    assert (error.line, error.column) == (1, 8)  # shoulder_pan_joint
    assert "radians read as degrees? (read them with --units rad" in error.message


def test_degrees_read_as_radians_are_refused_by_identify(tmp_path, capsys):
    """Joints logged in degrees but declared rad land beyond the robot's limits: identify
    refuses at the first such row naming the unit mix-up, exit 2, nothing written."""
    from accugrid.kinematics.robot import load_robot

    robot = load_robot("kr210")
    q_deg = np.array([[10.0, -80.0, 95.0, 5.0, 30.0, 10.0], [-20.0, -70.0, 100.0, -5.0, 40.0, 0.0]])
    q_deg = np.vstack([q_deg, q_deg + 3.0, q_deg - 4.0, q_deg + [7, 2, -3, 9, 5, 1]])
    xyz = robot.fk(np.radians(q_deg))[:, :3, 3]
    names = ",".join(["x", "y", "z", "x_meas", "y_meas", "z_meas"] + [f"a{i}" for i in range(1, 7)])
    rows = [",".join(f"{v:.4f}" for v in [*p, *p, *q]) for p, q in zip(xyz, q_deg, strict=True)]
    meas = tmp_path / "deg.csv"
    meas.write_text(names + "\n" + "\n".join(rows) + "\n")
    out = tmp_path / "cal.yaml"
    argv = ["identify", str(meas), "--robot", "kr210", "--structure", "dh", "-o", str(out)]
    assert main([*argv, "--units", "rad"]) == 2
    err = capsys.readouterr().err
    assert f"{meas}:2:" in err and "degrees read as radians?" in err and len(err.splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("swap", ["x_meas,y_meas", "x,z", "sign"])
def test_mirrored_measured_columns_are_refused_at_the_header(swap):
    """x_meas and y_meas swapped (or x and z, or one measured column of the wrong sign): the
    measured positions are a mirror image of the commanded ones, in any frame."""
    canonical = read_measurements(CANONICAL)
    rng = np.random.default_rng(3)
    commanded = rng.uniform(-800, 1500, (20, 3))
    rotation = Rotation.from_euler("ZYX", [40, -10, 170], degrees=True).as_matrix()
    measured = commanded @ rotation.T + [2500, -1300, 100] + rng.normal(0, 0.05, (20, 3))
    if swap == "sign":
        measured[:, 1] *= -1
    header = ["x", "y", "z", "x_meas", "y_meas", "z_meas"]
    if swap != "sign":
        i, j = (header.index(n) for n in swap.split(","))
        header[i], header[j] = header[j], header[i]
    text = ",".join(header) + "\n"
    text += "".join(
        ",".join(f"{v:.4f}" for v in row) + "\n" for row in np.hstack([commanded, measured])
    )
    with pytest.raises(InputError) as info:
        read_measurements(_write(text))
    assert info.value.line == 1 and info.value.column == header.index("x_meas") + 1
    assert "mirror image of the commanded x,y,z" in info.value.message
    # unswapped, in the same tracker frame: read
    plain = ",".join(["x", "y", "z", "x_meas", "y_meas", "z_meas"]) + "\n"
    measured[:, 1] *= -1 if swap == "sign" else 1
    good = np.hstack([commanded, commanded @ rotation.T + [2500, -1300, 100]])
    plain += "".join(",".join(f"{v:.4f}" for v in row) + "\n" for row in good)
    assert len(read_measurements(_write(plain)).commanded) == 20
    assert len(canonical.commanded) == 8  # the example grid (robot frame) passes


def _write(text: str) -> str:
    import tempfile

    handle = tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False)
    handle.write(text)
    handle.close()
    return handle.name


def test_a_mapped_column_missing_from_the_export_is_named(realdata):
    wrong = _format("--format", str(UR10_FORMAT), "--columns", "x=Goal x,a1=shoulder_joint")
    with pytest.raises(InputError) as info:
        read_measurements(realdata / "ipa-ur10" / SERIES["C"], wrong)
    assert info.value.line == 1
    assert "column mapping a1=shoulder_joint: no column 'shoulder_joint' in the header" in str(
        info.value
    )


# -- the real UR10 series, as they come --------------------------------------------------------


@pytest.mark.parametrize("series", sorted(SERIES))
def test_the_ur10_series_read_as_they_come(realdata, series):
    """Series A and C read with the format file (and with the same options on the command
    line): every row against the file's text read here by the csv module, metres times 1000 in
    exact decimals, radians to degrees, roll-pitch-yaw (fixed x-y-z) as KUKA ABC compared as
    rotation matrices by scipy."""
    path = realdata / "ipa-ur10" / SERIES[series]
    meas = read_measurements(path, _format("--format", str(UR10_FORMAT)))
    again = read_measurements(path, _format(*UR10_OPTIONS))
    for field in ("commanded", "measured", "abc", "joints"):
        assert np.array_equal(getattr(meas, field), getattr(again, field)), field
    header, rows = _ur10_rows(series)
    column = {name: i for i, name in enumerate(header)}

    def cells(names):
        return [[row[column[n]].replace(",", ".") for n in names] for row in rows]

    assert len(meas.commanded) == len(rows)
    goal = np.array(
        [[float(Decimal(v) * 1000) for v in r] for r in cells(["Goal x", "Goal y", "Goal z"])]
    )
    assert np.array_equal(meas.commanded, goal)
    measured = np.array(cells(["measurement_x", "measurement_y", "measurement_z"]), dtype=float)
    assert np.array_equal(meas.measured, measured)
    joints = np.degrees(np.array(cells(JOINTS), dtype=float))
    np.testing.assert_allclose(meas.joints, joints, rtol=1e-15, atol=1e-12)
    rpy = np.array(cells(["Goal roll", "Goal pitch", "Goal yaw"]), dtype=float)
    commanded_R = Rotation.from_euler("xyz", rpy).as_matrix()  # extrinsic: Rz(yaw) Ry(p) Rx(r)
    kuka_R = Rotation.from_euler("ZYX", meas.abc, degrees=True).as_matrix()
    np.testing.assert_allclose(kuka_R, commanded_R, atol=1e-12)


def test_a_ur10_row_by_hand(realdata):
    """Row 2 of series C, each number worked out by hand from its text (the docs quote it)."""
    meas = read_measurements(
        realdata / "ipa-ur10" / SERIES["C"], _format("--format", str(UR10_FORMAT))
    )
    # 0,0103459;-0,480444;1,00632 m; roll 3,10253 pitch 1,66683 yaw 1,57927 rad
    assert meas.commanded[1].tolist() == [10.3459, -480.444, 1006.32]
    np.testing.assert_allclose(meas.abc[1], np.degrees([1.57927, 1.66683, 3.10253]), atol=1e-12)
    assert meas.measured[1].tolist() == [335.14778, -3134.3677, -221.16088]
    np.testing.assert_allclose(meas.joints[1, 0], -4.08444 * 180 / np.pi, atol=1e-12)
    assert meas.lines[1] == 3
    # the round-off of '-4,08444' rad is half of 1e-5 rad, in deg
    np.testing.assert_allclose(0.5 * 10.0 ** -meas.joint_decimals[1, 0], np.degrees(0.5e-5))


def test_transform_maps_a_ur10_series_and_keeps_its_layout(realdata, tmp_path):
    """transform with the format file: the tracker columns mapped by a frame, written back with
    semicolons and decimal commas in mm; the time stamps, temperatures and std columns as they
    were."""
    frame = tmp_path / "frame.yaml"
    frame.write_text("tracker_T_robot: {x: 100, y: -200, z: 50, a: 90, b: 0, c: 0}\n")
    src = realdata / "ipa-ur10" / SERIES["C"]
    out = tmp_path / "robot_frame.csv"
    argv = ["transform", str(src), "--frame", str(frame), "--format", str(UR10_FORMAT)]
    assert main([*argv, "-o", str(out)]) == 0
    header, rows = _ur10_rows("C")
    lines = out.read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("# accugrid transform: x_meas,y_meas,z_meas mapped")
    assert lines[1] == ";".join(header)
    got = [line.split(";") for line in lines[2:]]
    assert len(got) == len(rows)
    names = ["measurement_x", "measurement_y", "measurement_z"]
    index = [header.index(n) for n in names]
    for r in (0, 1, len(rows) - 1):
        assert [c for i, c in enumerate(got[r]) if i not in index] == [
            c for i, c in enumerate(rows[r]) if i not in index
        ]
        tracker = np.array([float(rows[r][i].replace(",", ".")) for i in index])
        # robot = Rz(-90) (tracker - t): x' = y - (-200), y' = -(x - 100)
        expected = [tracker[1] + 200, -(tracker[0] - 100), tracker[2] - 50]
        mapped = [float(got[r][i].replace(",", ".")) for i in index]
        np.testing.assert_allclose(mapped, expected, atol=5e-5)
