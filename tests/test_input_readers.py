"""Issue 12 items 4, 6, 8, 10, 11, 12, 14 (CSV with a BOM), 16: the guarded reader, the strict
YAML loader, the CSV number parser and one-line printable error messages."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from conftest import EXAMPLES
from hypothesis import given
from hypothesis import strategies as st

from accugrid.app.cli import main
from accugrid.app.jobs.robot_frame import load_frame
from accugrid.codegen.cell import load_cell
from accugrid.infra.csvtable import parse_number, parse_table, read_table
from accugrid.infra.errors import MESSAGE_MAX, InputError, printable
from accugrid.infra.inputfile import read_input_bytes, read_input_text
from accugrid.infra.yamlfile import MAX_DEPTH, YamlDoc, load_yaml
from accugrid.kinematics.robot import load_robot

# ---------------------------------------------------------------- the guarded reader


def test_size_limit_is_checked_before_reading(tmp_path):
    path = tmp_path / "big.csv"
    path.write_bytes(b"x" * 1001)
    with pytest.raises(InputError, match="over the limit"):
        read_input_bytes(path, limit=1000)
    assert read_input_bytes(path, limit=1001) == b"x" * 1001


def test_bad_utf8_is_located_by_line_and_column_with_bom_and_crlf(tmp_path):
    path = tmp_path / "a.csv"
    path.write_bytes(b"\xef\xbb\xbfx,y\r\n1,2\r\n3,\xff\r\n")
    with pytest.raises(InputError) as info:
        read_input_text(path)
    assert (info.value.line, info.value.column, info.value.message) == (3, 3, "not UTF-8 text")


def test_non_utf8_robot_yaml_is_a_located_input_error(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_bytes(b"name: r\ndescription: caf\xe9\n")
    with pytest.raises(InputError) as info:
        load_robot(path)
    assert (info.value.path, info.value.line, info.value.column) == (str(path), 2, 17)


# ---------------------------------------------------------------- the YAML loader (items 4, 6, 12)

BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n"
    for i in range(20)
)


@pytest.mark.parametrize(
    "text, message, line, column",
    [
        (BOMB, "anchors (&name) are not accepted", 1, 4),
        ("a: 1\nb: *a\n", "aliases (*name) are not accepted", 2, 4),
        ("a: !!int 5\n", "explicit tags (tag:yaml.org,2002:int)", 1, 4),
        ("a: !!float 5\n", "explicit tags (tag:yaml.org,2002:float)", 1, 4),
        ("a: !!python/object:os.system x\n", "explicit tags", 1, 4),
        ("base: {x: 1}\ntool: 2\nbase: {x: 3}\n", "duplicate key 'base' (first on line 1)", 3, 1),
        ("a:\n  b: 1\n  b: 2\n", "duplicate key 'b'", 3, 3),
        ("a: " + "[" * (MAX_DEPTH + 5) + "]" * (MAX_DEPTH + 5) + "\n", "nested deeper", 1, None),
        ("a: " + "9" * 400 + "\n", "integer out of range", 1, 4),
        ("a: " + "9" * 5000 + "\n", "integer out of range", 1, 4),
        ("a: 1\n  b: 2\n", "invalid YAML", 2, None),
        ("a: \x00\n", "invalid YAML", 1, 4),
    ],
)
def test_yaml_refusals_are_located(text, message, line, column):
    with pytest.raises(InputError) as info:
        YamlDoc.parse(text, "f.yaml")
    err = info.value
    assert message in err.message
    assert (err.path, err.line) == ("f.yaml", line)
    if column is not None:
        assert err.column == column


def test_an_alias_bomb_robot_or_cell_is_refused_not_expanded(tmp_path, capsys):
    for name in ("robot.yaml", "cell.yaml"):
        (tmp_path / name).write_text(BOMB)
    with pytest.raises(InputError, match="anchors"):
        load_robot(tmp_path / "robot.yaml")
    code = main(
        [
            "krl",
            str(EXAMPLES / "wing_panel_points.csv"),
            "--cell",
            str(tmp_path / "cell.yaml"),
            "-o",
            str(tmp_path / "out"),
        ]
    )
    assert code == 2 and "anchors (&name) are not accepted" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_duplicated_base_in_a_cell_names_its_line(tmp_path):
    text = (EXAMPLES / "cell.yaml").read_text()
    line = next(i for i, t in enumerate(text.splitlines(), 1) if t.startswith("base:"))
    path = tmp_path / "cell.yaml"
    path.write_text(text + "base: {number: 2, x: 0, y: 0, z: 0, a: 0, b: 0, c: 0}\n")
    with pytest.raises(InputError) as info:
        load_cell(path)
    assert f"duplicate key 'base' (first on line {line})" in info.value.message
    assert info.value.line == len(text.splitlines()) + 1


def test_every_yaml_reader_goes_through_the_strict_loader(tmp_path):
    frame = tmp_path / "frame.yaml"
    frame.write_text("tracker_T_robot: {x: 1, y: 2, z: 3, a: 0, b: 0, c: 0, x: 4}\n")
    with pytest.raises(InputError, match="duplicate key 'x'"):
        load_frame(frame)
    cell = tmp_path / "cell.yaml"
    cell.write_text("robot: !!str kr210\n")
    with pytest.raises(InputError, match="explicit tags"):
        load_cell(cell)


def test_the_example_configuration_files_load_unchanged():
    doc = load_yaml(EXAMPLES / "cell.yaml")
    assert doc.data["robot"] == "kr210-paper" and len(doc.sha256) == 64
    for name in ("cell.yaml", "cell_heatsink.yaml"):
        load_cell(EXAMPLES / name)


# ---------------------------------------------------------------- CSV numbers and lines (10, 11)


@pytest.mark.parametrize(
    "cell", ["1_000", "\u0661\u0662", "\uff11\uff12", "12\u00a0", "0x10", "1,5", "1e", "--1"]
)
def test_only_ascii_decimal_numbers_are_numbers(cell):
    with pytest.raises(ValueError, match="not a number"):
        parse_number(cell)
    table = parse_table(f'x,y\n1,"{cell}"\n', "t.csv")
    with pytest.raises(InputError) as info:
        table.floats(["x", "y"])
    assert (info.value.line, info.value.column) == (2, 2)


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_every_finite_float_round_trips_through_the_number_parser(value):
    assert parse_number(repr(value)) == value
    assert parse_number(f" {value:.6e} ") == float(f"{value:.6e}")


@given(
    st.lists(
        st.one_of(
            st.floats(-1e9, 1e9).map(repr),
            st.sampled_from(["", " 7 ", "1_0", "nan", "-inf", "1e999", "\u0663", ".5", "5."]),
        ),
        min_size=1,
        max_size=12,
    ),
    st.booleans(),
)
def test_column_conversion_agrees_with_the_cell_by_cell_parser(cells, allow_empty):
    """The fast column path and the locating slow path accept and refuse the same cells."""
    table = parse_table("i,v\n" + "".join(f'{r},"{c}"\n' for r, c in enumerate(cells)), "t.csv")
    expected = []
    for r, cell in enumerate(cells):
        if allow_empty and not cell.strip(" "):
            expected.append(np.nan)
            continue
        try:
            expected.append(parse_number(cell))
        except ValueError:
            with pytest.raises(InputError) as info:
                table.floats(["v"], allow_empty)
            assert info.value.line == r + 2
            return
    np.testing.assert_array_equal(table.floats(["v"], allow_empty)[:, 0], expected)


@pytest.mark.parametrize("brk", ["\r", "\r\n", "\x0b", "\x0c", "\x85", "\u2028", "\u2029"])
def test_quoted_fields_keep_any_line_break_as_data(brk):
    table = parse_table(f'id,x\n"a{brk}b",1\n"c",2\n', "t.csv")
    assert table.text("id") == [f"a{brk}b", "c"]
    assert table.lines == [2, 3 + brk.count("\n") + brk.count("\r") - brk.count("\r\n")]


@pytest.mark.parametrize("ending", ["\n", "\r\n", "\r"])
def test_line_endings_and_bom(tmp_path, ending):
    path = tmp_path / "t.csv"
    path.write_bytes(("\ufeffx,y" + ending + "# c" + ending + "1,2" + ending).encode())
    table = read_table(path)
    assert table.header == ["x", "y"] and table.lines == [3]


# ---------------------------------------------------------------- messages (item 8)


@pytest.mark.parametrize(
    "hostile", ["a\nLIN P1", "\x1b[31mred", "\u202eevil", "nul\x00", "x" * 10_000, "\u2028"]
)
def test_messages_are_one_printable_bounded_line(tmp_path, capsys, hostile):
    path = tmp_path / "p.csv"
    path.write_text(f'x,y,z\n1,2,"{hostile}"\n')
    code = main(["correct", str(path), "--grid", str(EXAMPLES / "grid_200mm.csv"), "-o", "o.csv"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.endswith("\n") and err.count("\n") == 1
    line = err[:-1]
    assert line.isprintable() and len(line) < 2 * MESSAGE_MAX
    assert f"{path}:2:3: " in line


def test_printable_escapes_and_cuts():
    assert printable("a\nb\x1b[0m\u202e") == "a\\x0ab\\x1b[0m\\u202e"
    assert len(printable("y" * 1000)) == MESSAGE_MAX
    assert printable("é ü 中") == "é ü 中"


def test_numpy_warnings_do_not_precede_the_error(tmp_path, capsys):
    """A grid whose levels overflow float arithmetic: numpy would warn before the message."""
    grid = tmp_path / "grid.csv"
    shutil.copy(EXAMPLES / "grid_200mm.csv", grid)
    with grid.open("a") as f:
        f.write("x,1.7e308,0,0,0,90,0,1.7e308,0,0\n")
    code = main(
        ["correct", str(EXAMPLES / "wing_panel_robot.csv"), "--grid", str(grid), "-o", "o.csv"]
    )
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Warning" not in err
    assert f"{grid}:{len(grid.read_text().splitlines())}:" in err


def test_library_warnings_are_held_back_on_error_and_shown_on_success(monkeypatch, capsys):
    import warnings

    from accugrid.app.commands import correct

    def warns_then(fail):
        def run(args):
            warnings.warn("overflow encountered in reduce", RuntimeWarning, stacklevel=1)
            if fail:
                raise InputError("bad cell", "p.csv", 3, 1)
            return 0

        return run

    argv = ["correct", "p.csv", "--grid", "g.csv", "-o", "o.csv"]
    monkeypatch.setattr(correct, "run", warns_then(True))
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        assert main(argv) == 2
    assert shown == []
    assert capsys.readouterr().err == "accugrid correct: error: p.csv:3:1: bad cell\n"
    monkeypatch.setattr(correct, "run", warns_then(False))
    with pytest.warns(RuntimeWarning, match="overflow encountered"):
        assert main(argv) == 0


@pytest.mark.parametrize("name", ["END", "def", "Lin", "DECL"])
def test_krl_keywords_are_no_program_names(tmp_path, name):
    """Item 13: `DEF END( )` must never be written."""
    from accugrid.codegen.krl.names import krl_identifier

    path = tmp_path / "cell.yaml"
    path.write_text((EXAMPLES / "cell.yaml").read_text().replace("WING_PANEL", name))
    with pytest.raises(InputError, match="not a KRL keyword") as info:
        load_cell(path)
    assert info.value.line is not None
    assert krl_identifier(name, prefix="M") == "M" + name
