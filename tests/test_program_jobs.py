"""The program commands (``krl``, ``gcode``, ``rapid``) are one job over the dialect's plug-in:
each writes its program and, asked for, its HTML report; ``rewrite`` takes a second file only as
the other half of a two-file program."""

from __future__ import annotations

from pathlib import Path

import pytest

from accugrid.app.cli import main
from accugrid.codegen.dialects import DIALECTS, plugin_of

POINTS = "examples/wing_panel_points.csv"
HOLES = sum(1 for line in open(POINTS) if line.strip() and not line.startswith("#")) - 1  # header
# command -> (cell, output, the program files it writes)
JOBS = {
    "krl": ("examples/cell.yaml", "out", ["out/WING_PANEL.src", "out/WING_PANEL.dat"]),
    "gcode": ("examples/cell.yaml", "wing.ngc", ["wing.ngc"]),
    "rapid": ("examples/cell_irb6700.yaml", "WING.mod", ["WING.mod"]),
    "fanuc": ("examples/cell_fanuc.yaml", "WING.ls", ["WING.ls"]),
}


def test_every_registered_dialect_has_a_program_command_here():
    assert set(JOBS) == set(DIALECTS)


@pytest.mark.parametrize("name", sorted(JOBS))
def test_a_program_command_writes_its_program_and_its_report(name, tmp_path, capsys):
    cell, output, files = JOBS[name]
    report = tmp_path / "report.html"
    argv = [name, POINTS, "--cell", cell, "-o", str(tmp_path / output)]
    assert main([*argv, "--report-html", str(report)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("wrote ") and all(str(tmp_path / f) in out for f in files)
    for file in files:
        text = (tmp_path / file).read_text(encoding="utf-8")
        assert f"holes {HOLES}" in text  # the header: every hole of the points file
    page = report.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and "drilling program" in page
    assert Path(cell).name in page and Path(POINTS).name in page
    # the same job again without --force is refused before anything is written
    before = {f: (tmp_path / f).read_bytes() for f in files}
    assert main([*argv, "--report-html", str(report)]) == 2
    assert "exists" in capsys.readouterr().err
    assert {f: (tmp_path / f).read_bytes() for f in files} == before


@pytest.mark.parametrize(
    ("first", "second"), [("a.ngc", "b.dat"), ("a.src", "b.ngc"), ("a.dat", "b.dat")]
)
def test_rewrite_takes_a_second_file_only_as_the_other_half_of_a_pair(
    first, second, tmp_path, capsys
):
    for name in (first, second):
        (tmp_path / name).write_text("; nothing\n")
    argv = ["rewrite", str(tmp_path / first), str(tmp_path / second)]
    assert main([*argv, "--cell", "examples/cell.yaml", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "the second file must be the .dat of a KUKA KRL .src" in err and second in err
    assert not (tmp_path / "out").exists()


def test_only_a_pair_dialect_names_the_suffixes_of_a_two_file_program():
    pairs = {name: plugin_of(name).pair for name in DIALECTS}
    assert pairs == {"krl": (".src", ".dat"), "gcode": None, "rapid": None, "fanuc": None}
    for name, pair in pairs.items():
        assert pair is None or set(pair) <= set(DIALECTS[name].suffixes)


@pytest.mark.parametrize(
    ("dialect", "stem", "why"),
    [
        ("rapid", "1panel", "must be a letter, then letters, digits or _"),
        ("rapid", "P" * 33, "has 33 characters, RAPID allows at most 32"),
        ("rapid", "Module", "is a RAPID reserved word"),
        ("fanuc", "1panel", "must be a letter, then letters, digits or _"),
        ("fanuc", "P" * 37, "has 37 characters, a FANUC program name at most 36"),
    ],
)
def test_an_output_stem_the_controller_refuses_as_its_name_is_a_located_error(dialect, stem, why):
    """Without a name in the cell a RAPID module and a FANUC program are named after the output
    file; a stem the controller refuses is an error naming the file and the cell key to set."""
    from accugrid.codegen.fanuc.emit import program_name
    from accugrid.codegen.rapid.emit import module_name
    from accugrid.infra.errors import InputError

    name_of, what, suffix = {
        "rapid": (module_name, "module", ".mod"),
        "fanuc": (program_name, "program", ".ls"),
    }[dialect]
    out = Path("out") / f"{stem}{suffix}"
    with pytest.raises(InputError) as raised:
        name_of(None, out)
    assert str(raised.value).endswith(
        f"the {what} name {stem!r} (the file's stem) {why}: rename the output or set "
        f"{dialect}.{what} in the cell file"
    )
    assert str(out) in str(raised.value)
    assert name_of("PANEL", out) == "PANEL"
    assert name_of(None, Path(f"panel{suffix}")) == {"rapid": "panel", "fanuc": "PANEL"}[dialect]
