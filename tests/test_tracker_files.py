"""Tracker exports as they come: delimiter and decimal mark found from the file, a column
mapping, lengths in m or inch; every example under examples/tracker reads as the canonical CSV."""

from __future__ import annotations

from decimal import Decimal

import numpy as np
import pytest
from conftest import EXAMPLES
from hypothesis import given
from hypothesis import strategies as st

from accugrid.app.cli import main
from accugrid.codegen.points import parse_points
from accugrid.compensation.measurements import read_measurements
from accugrid.infra.csvtable import TableFormat, parse_table
from accugrid.infra.errors import InputError

TRACKER = EXAMPLES / "tracker"
CANONICAL = TRACKER / "grid_8.csv"
SIX = ("x", "y", "z", "x_meas", "y_meas", "z_meas")
# each example with the options that describe it (as the docs give them)
EXAMPLES_AND_OPTIONS = {
    "sa_grid_8.csv": [
        "--columns",
        "id=Point,x=X Nominal,y=Y Nominal,z=Z Nominal,"
        "x_meas=X Actual,y_meas=Y Actual,z_meas=Z Actual",
    ],
    "polyworks_grid_8.csv": [
        "--columns",
        "id=Name,x=Nominal X,y=Nominal Y,z=Nominal Z,"
        "x_meas=Measured X,y_meas=Measured Y,z_meas=Measured Z",
    ],
    "polyworks_grid_8_m.txt": [
        "--units",
        "m",
        "--columns",
        "id=Name,x=Nominal X (m),y=Nominal Y (m),z=Nominal Z (m),"
        "x_meas=Measured X (m),y_meas=Measured Y (m),z_meas=Measured Z (m)",
    ],
}
INSIDE = "id,x,y,z\nH1,1250.5,-550,1150\nH2,1333.25,-420.75,1280.125\nH3,1399,-401,1101\n"


def _format(options: list[str]) -> TableFormat:
    """The TableFormat the CLI builds from ``options`` (parsed by the real parser)."""
    from accugrid.app.cli import build_parser
    from accugrid.app.cli_options import reading_format
    from accugrid.infra import csvtable

    args = build_parser("correct").parse_args(["correct", "P", "-o", "O", *options])
    with reading_format(args):
        return csvtable._FORMAT.get()


@pytest.mark.parametrize("name", sorted(EXAMPLES_AND_OPTIONS))
def test_every_example_reads_as_the_canonical_csv(name):
    canonical = read_measurements(CANONICAL)
    example = read_measurements(TRACKER / name, _format(EXAMPLES_AND_OPTIONS[name]))
    assert np.array_equal(example.commanded, canonical.commanded)
    assert np.array_equal(example.measured, canonical.measured)
    assert np.array_equal(example.position_decimals, canonical.position_decimals)
    assert len(example.commanded) == 8


@pytest.mark.parametrize("name", sorted(EXAMPLES_AND_OPTIONS))
def test_correct_with_an_export_writes_the_canonical_bytes(tmp_path, name, capsys):
    """The whole command: the points (canonical, mm) corrected by the export's grid give the
    same file as by the canonical grid; the mapping and the units leave the points alone."""
    points = tmp_path / "points.csv"
    points.write_text(INSIDE)
    ref, out = tmp_path / "ref.csv", tmp_path / "out.csv"
    assert main(["correct", str(points), "--grid", str(CANONICAL), "-o", str(ref)]) == 0
    options = EXAMPLES_AND_OPTIONS[name]
    assert (
        main(["correct", str(points), "--grid", str(TRACKER / name), "-o", str(out), *options]) == 0
    )
    # the same bytes but the header line naming the grid file (and its SHA-256) read
    ref_lines, out_lines = ref.read_bytes().splitlines(), out.read_bytes().splitlines()
    (grid_line,) = [n for n, line in enumerate(ref_lines) if line.startswith(b"# grid grid_8.csv ")]
    assert out_lines[grid_line].startswith(f"# grid {name} sha256 ".encode())
    del ref_lines[grid_line], out_lines[grid_line]
    assert out_lines == ref_lines


def test_a_mapping_naming_a_missing_column_is_one_located_line(tmp_path, capsys):
    points = tmp_path / "points.csv"
    points.write_text(INSIDE)
    options = EXAMPLES_AND_OPTIONS["polyworks_grid_8.csv"][1].replace("Measured Z", "Meas Z")
    grid = TRACKER / "polyworks_grid_8.csv"
    out = tmp_path / "out.csv"
    code = main(["correct", str(points), "--grid", str(grid), "-o", str(out), "--columns", options])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert err.count("\n") == 1
    assert f"{grid}:1: column mapping z_meas=Meas Z: no column 'Meas Z' in the header" in err


def test_a_mapping_that_fits_no_column_of_a_file_says_so_where_columns_are_missing(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("# tracker\nPoint;X;Y;Z\nP1;1;2;3\n")
    with pytest.raises(InputError) as info:
        read_measurements(path, TableFormat(columns={"x": "X_nom", "x_meas": "X_act"}))
    assert info.value.line == 2
    assert "the column mapping x=X_nom,x_meas=X_act names none of them" in str(info.value)


def test_mixed_decimal_marks_are_a_located_error_naming_the_option(tmp_path, capsys):
    path = tmp_path / "m.csv"
    path.write_text("id;x;y;z;x_meas;y_meas;z_meas\nP1;1,5;2;3;1;2;3\nP2;1;2;3;1;2.25;3\n")
    code = main(["identify", str(path), "--robot", "kr210", "-o", str(tmp_path / "c.yaml")])
    err = capsys.readouterr().err
    assert code == 2
    assert f"{path}:3:6: numbers with a decimal point and with a decimal comma" in err
    assert "'1,5' on line 2 column 2" in err and "--decimal point or --decimal comma" in err


def test_the_decimal_option_decides_a_file_with_a_time_column():
    text = "Name;Time;X;Y;Z\nP1;12.30;1,5;2,25;-3,125\n"
    with pytest.raises(InputError, match="--decimal"):
        parse_table(text, "t.csv")
    table = parse_table(text, "t.csv", TableFormat(decimal=","))
    assert table.floats(["x", "y", "z"]).tolist() == [[1.5, 2.25, -3.125]]
    assert table.text("time") == ["12.30"]


def test_an_undecidable_delimiter_names_what_was_found():
    with pytest.raises(InputError) as info:
        parse_table("# note\nid,x;y\nP1,1;2\n", "d.csv")
    assert info.value.line == 2
    assert "comma: 2 column(s) in the header, [2] per row" in str(info.value)
    assert "give --delimiter comma or semicolon" in str(info.value)
    table = parse_table("# note\nid,x;y\nP1,1;2\n", "d.csv", TableFormat(delimiter=";"))
    assert table.header == ["id,x", "y"]


def test_the_export_options_leave_a_canonical_file_of_the_same_command_alone():
    """--delimiter and --decimal describe the export: a comma file (the job's points) is read
    with a comma and points all the same."""
    fmt = TableFormat(delimiter=";", decimal=",", columns={"x": "X_nom"})
    table = parse_table("id,x,y\nP1,1.5,2\n", "p.csv", fmt)
    assert table.floats(["x", "y"]).tolist() == [[1.5, 2.0]]
    export = parse_table("id;X_nom;y\nP1;1,5;2\n", "e.csv", fmt)
    assert export.floats(["x", "y"]).tolist() == [[1.5, 2.0]]


def test_the_canonical_file_keeps_the_fast_reader():
    table = parse_table("id,x,y,z\nP1,1.5,2,3\nP2,4,5,6\n", "f.csv")
    assert table.row_bytes(0, 2) is not None  # only the fast reader keeps the row text
    mapped = parse_table("id,X_n,y,z\nP1,1.5,2,3\n", "f.csv", TableFormat(columns={"x": "X_n"}))
    assert mapped.header == ["id", "x", "y", "z"] and mapped.row_bytes(0, 1) is not None


def test_points_in_inch_with_semicolons_and_a_mapping_read_as_mm():
    canonical = parse_points("id,x,y,z,i,j,k,diameter,feed\nH1,38.10,-50.8,2.54,0,0,1,6.35,5\n")
    export = parse_points(
        "Hole;PX;PY;PZ;I;J;K;Dia;feed\nH1;1,5;-2;0,1;0;0;1;0,25;5\n",
        "h.csv",
        TableFormat(
            units="in", columns={"id": "Hole", "x": "PX", "y": "PY", "z": "PZ", "diameter": "Dia"}
        ),
    )
    for field in ("xyz", "axis", "diameter", "feed"):  # feed stays mm/s
        assert np.array_equal(getattr(export, field), getattr(canonical, field)), field
    assert export.ids == ["H1"]


_MM = st.decimals(min_value=-3000, max_value=3000, places=4, allow_nan=False)


@given(
    rows=st.lists(st.tuples(*[_MM] * 6), min_size=1, max_size=12),
    delimiter=st.sampled_from([",", ";", "\t"]),
    comma=st.booleans(),
    units=st.sampled_from(["mm", "m", "in"]),
    rename=st.booleans(),
)
def test_any_export_reads_as_its_canonical_file(rows, delimiter, comma, units, rename):
    """A table written canonically and as an export (delimiter, decimal comma with a semicolon
    or tab, lengths in m or inch, other column names) reads to the same float64 numbers."""
    comma = comma and delimiter != ","
    names = [f"{n.upper()}_file" if rename else n for n in SIX]
    # the export's numbers in its unit; the canonical file holds their exact value in mm
    if units == "in":
        exported = [[v.scaleb(-2) for v in row] for row in rows]
        in_mm = [[v * Decimal("25.4") for v in row] for row in exported]
    else:
        exported = [[v.scaleb(-3) if units == "m" else v for v in row] for row in rows]
        in_mm = [list(row) for row in rows]
    canonical = "id," + ",".join(SIX) + "\n"
    canonical += "".join(f"P{r}," + ",".join(map(str, row)) + "\n" for r, row in enumerate(in_mm))
    text = delimiter.join(["Name", *names]) + "\n"
    for r, row in enumerate(exported):
        cells = [format(v, "f").replace(".", ",") if comma else format(v, "f") for v in row]
        text += delimiter.join([f"P{r}", *cells]) + "\n"
    mapping = dict(zip(SIX, names, strict=True)) if rename else {}
    fmt = TableFormat(columns={"id": "Name", **mapping}, units=units)
    expected = parse_table(canonical, "c.csv").floats(SIX)
    assert np.array_equal(parse_table(text, "e.csv", fmt).floats(SIX), expected)


def _cell_with_grid(tmp_path, name: str, grid, tracker: str = ""):
    """examples/cell.yaml with its grid replaced (and a tracker: section appended)."""
    text = (EXAMPLES / "cell.yaml").read_text().replace("grid: grid_200mm.csv", f"grid: {grid}")
    path = tmp_path / name
    path.write_text(text + tracker)
    return path


def test_the_cell_tracker_section_reads_its_grid_file(tmp_path, capsys):
    """A cell whose grid is a PolyWorks-shaped export with a tracker: section makes the same KRL
    program as the cell with the canonical grid (only the lines naming files and SHA-256 differ);
    the points file of the job is read as it is."""
    from accugrid.codegen.cell import load_cell
    from accugrid.kinematics.frames import invert, transform_points

    option = EXAMPLES_AND_OPTIONS["polyworks_grid_8.csv"][1]
    columns = dict(item.split("=") for item in option.split(","))
    tracker = "\ntracker:\n  columns: {" + ", ".join(f"{k}: {v}" for k, v in columns.items())
    tracker += "}\n  decimal: comma\n"
    plain = _cell_with_grid(tmp_path, "plain.yaml", CANONICAL)
    export = _cell_with_grid(tmp_path, "export.yaml", TRACKER / "polyworks_grid_8.csv", tracker)
    assert load_cell(export).tracker == TableFormat(decimal=",", columns=columns)
    robot_points = np.array([[1250.5, -550, 1150], [1333.25, -420.75, 1280.125]])
    base = transform_points(invert(load_cell(plain).robot_T_base), robot_points)
    points = tmp_path / "holes.csv"
    points.write_text(
        "id,x,y,z,i,j,k\n"
        + "".join(f"H{n},{x},{y},{z},0,0,-1\n" for n, (x, y, z) in enumerate(base))
    )
    outputs = {}
    for cell in (plain, export):
        out = tmp_path / cell.stem
        assert main(["krl", str(points), "--cell", str(cell), "-o", str(out)]) == 0, (
            capsys.readouterr()
        )
        outputs[cell.stem] = {
            p.name: [line for line in p.read_text().splitlines() if "sha256" not in line]
            for p in sorted(out.iterdir())
        }
    assert outputs["plain"] == outputs["export"]
    assert len(outputs["plain"]) == 2


def test_a_bad_tracker_section_names_its_key(tmp_path):
    from accugrid.codegen.cell import load_cell

    cell = _cell_with_grid(tmp_path, "c.yaml", CANONICAL, "\ntracker:\n  units: km\n")
    with pytest.raises(InputError, match="tracker.units"):
        load_cell(cell)


def test_a_ragged_semicolon_file_is_located_at_its_row():
    """Only the semicolon splits the header: the reader takes it and names the ragged row."""
    with pytest.raises(InputError) as info:
        parse_table("id;x;y\nP1;1;2\nP2;1;2;3\n", "r.csv")
    assert (info.value.line, info.value.message) == (3, "4 fields, but the header has 3")
