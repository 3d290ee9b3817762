"""One CLI vocabulary: every numeric option's help names its unit, every --robot help lists the
built-in robots from ``kinematics.robot.BUILTIN``, shared options keep one default, no help text
speaks of issues or work rounds, and every former spelling still works with one deprecation
line on stderr (docs/cli.md lists them)."""

from __future__ import annotations

import argparse
import re

import pytest
from conftest import EXAMPLES

from accugrid.app.cli import build_parser, main
from accugrid.app.cli_options import DEFAULT_ROBOT, DEFAULT_TILT_DEG
from accugrid.app.commands import COMMANDS
from accugrid.kinematics.robot import BUILTIN

UNITS = ("mm", "deg", "mm/s", "s", "%", "MiB")  # a unit the help must name as a word
# numbers without a unit: counts, indices, seeds, ratios, choices of a small integer
UNITLESS = {
    "--base",
    "--base-number",
    "--budgets",
    "--candidates",
    "--count",
    "--decimals",
    "--folds",
    "--iterations",
    "--max-order",
    "--number",
    "--power",
    "--repeats",
    "--seed",
    "--status",
    "--std-fraction",
    "--targets",
    "--tool-number",
    "--validation-points",
    "--wait-input",
}


def _parsers():
    """(name, parser) of every command and subcommand (``plan``, ``plan grid``, ...)."""

    def walk(name, parser):
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        yield name, parser
        for sub in subs:
            for kind, child in sub.choices.items():
                yield from walk(f"{name} {kind}", child)

    for command in COMMANDS:
        top = build_parser(command)
        sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
        yield from walk(command, sub.choices[command])


PARSERS = dict(_parsers())


def _options(parser):
    """The visible options of ``parser`` (deprecated spellings are hidden)."""
    return [a for a in parser._actions if a.option_strings and a.help != argparse.SUPPRESS]


def _names_unit(help_text, unit):
    return re.search(rf"(?<![\w/]){re.escape(unit)}(?![\w/])", help_text) is not None


def test_the_walk_sees_every_command():
    kinds = {"plan", "plan grid", "plan cube", "plan experiment", "plan identify", "correct"}
    assert kinds <= set(PARSERS)
    assert all(name.split()[0] in COMMANDS for name in PARSERS)


def test_every_numeric_option_names_its_unit_or_is_a_count():
    missing = []
    for name, parser in PARSERS.items():
        for action in _options(parser):
            unit = getattr(action.type, "unit", "" if action.type in (int, float) else None)
            if unit is None:  # not a number
                continue
            option = action.option_strings[-1]
            needed = [u for u in unit.split(" or ") if u in UNITS]
            if needed:
                if not all(_names_unit(action.help % vars(action), u) for u in needed):
                    missing.append(f"{name} {option}: help does not say {unit}")
            elif option not in UNITLESS:
                missing.append(f"{name} {option}: a number without a unit ({unit!r})")
    assert not missing, "\n".join(missing)


def test_the_unit_check_can_fail():
    assert _names_unit("grid step, mm", "mm") and not _names_unit("speed, mm/s", "mm")
    assert _names_unit("dwell, s (default: 3)", "s") and not _names_unit("passes", "s")


def test_every_robot_option_lists_every_builtin_robot_and_one_default():
    with_robot = {
        n: a for n, p in PARSERS.items() for a in _options(p) if "--robot" in a.option_strings
    }
    assert {"simulate", "identify", "compare", "study", "plan identify", "plan grid"} <= set(
        with_robot
    )
    for name, action in with_robot.items():
        assert all(robot in action.help for robot in BUILTIN), name
        assert action.default in (DEFAULT_ROBOT, None), name
        assert action.required == (action.default is None), name
    assert with_robot["identify"].required  # the model of one's own arm is never guessed


def test_shared_options_have_one_default():
    defaults = {}
    for name, parser in PARSERS.items():
        for action in _options(parser):
            option = action.option_strings[-1]
            if option in ("--tilt", "--abc", "--tool", "--status", "--outside", "--allow-partial"):
                defaults.setdefault(option, {})[name] = action.default
    assert set(defaults["--tilt"].values()) == {DEFAULT_TILT_DEG}
    assert len({tuple(v) for v in defaults["--abc"].values()}) == 1
    assert set(defaults["--tool"].values()) == {None}
    assert set(defaults["--status"].values()) == {None}
    for name, parser in PARSERS.items():
        for action in _options(parser):
            if "--status" in action.option_strings:
                assert action.help.startswith("KUKA Status 0..7 "), name
                assert list(action.choices) == list(range(8)), name
    assert set(defaults["--outside"]) == set(defaults["--allow-partial"])  # every correcting one
    assert {"correct", "krl", "gcode", "rewrite"} <= set(defaults["--outside"])
    assert set(defaults["--outside"].values()) == {"refuse"}


def test_no_help_text_speaks_of_issues_or_rounds():
    texts = [help_text for _, help_text in COMMANDS.values()]
    for parser in PARSERS.values():
        texts += [parser.description or ""] + [a.help or "" for a in _options(parser)]
    found = [t for t in texts if re.search(r"\bissues?\b|\brounds?\b(?!-)", t, re.IGNORECASE)]
    assert not found


def test_speeds_are_mm_per_s_and_the_old_vel_in_m_per_s_still_works(tmp_path, capsys):
    new, old = tmp_path / "new", tmp_path / "old"
    assert main(["plan", "grid", "--step", "500", "--speed", "300", "-o", str(new)]) == 0
    assert "deprecated" not in capsys.readouterr().err
    assert main(["plan", "grid", "--step", "500", "--vel", "0.3", "-o", str(old)]) == 0
    err = capsys.readouterr().err
    assert "accugrid plan grid: warning: --vel 0.3 is deprecated, use --speed 300\n" == err
    for path in new.iterdir():
        assert path.read_bytes() == (old / path.name).read_bytes(), path.name
    assert "$VEL.CP=0.3000\n" in (new / "measure_grid.src").read_text().replace(" ", "")


@pytest.mark.parametrize("command", ["compare", "study"])
def test_simulate_robot_is_the_former_robot(command, capsys):
    args = ["-o", "OUT"]
    new = build_parser(command).parse_args([command, "--robot", "kr210", *args])
    assert capsys.readouterr().err == ""
    old = build_parser(command).parse_args([command, "--simulate", "kr210", *args])
    err = capsys.readouterr().err
    assert (
        err == f"accugrid {command}: warning: --simulate kr210 is deprecated, use --robot kr210\n"
    )
    assert vars(old) == vars(new) and new.robot == "kr210"


def test_study_simulates_the_default_robot_unless_measured(capsys):
    args = build_parser("study").parse_args(["study", "-o", "OUT"])
    assert args.robot == DEFAULT_ROBOT and args.measured is None
    with pytest.raises(SystemExit) as exit_:
        build_parser("study").parse_args(["study", "--robot", "kr210", "--measured", "m.csv"])
    assert exit_.value.code == 2 and "not allowed with" in capsys.readouterr().err


def test_outside_error_is_the_former_refuse(tmp_path, capsys):
    points = tmp_path / "points.csv"
    points.write_text("id,x,y,z\nin,1600,0,1500\nfar,2500,0,1500\n")
    grid = str(EXAMPLES / "grid_200mm.csv")
    runs = {}
    for word in ("refuse", "error"):
        out = tmp_path / f"{word}.csv"
        runs[word] = main(
            ["correct", str(points), "--grid", grid, "--outside", word, "-o", str(out)]
        )
        runs[word, "err"] = capsys.readouterr().err
        assert not out.exists()
    assert runs["refuse"] == runs["error"] == 2
    first, _, rest = runs["error", "err"].partition("\n")
    assert first == "accugrid correct: warning: --outside error is deprecated, use --outside refuse"
    assert rest == runs["refuse", "err"] and "outside the grid" in rest


def test_outside_clamp_corrects_a_program_hole_outside_the_grid(tmp_path, capsys):
    """--outside means the same in the program commands as in correct: clamp uses the nearest
    cell and flags; refuse (the default) refuses the job, and --allow-partial leaves it as is."""
    lines = (EXAMPLES / "wing_panel_points.csv").read_text().splitlines()
    first = next(i for i, line in enumerate(lines) if line[:1] not in ("#", "i"))
    cells = lines[first].split(",")
    cells[1] = "950"  # base X runs along robot -Y from Y 300: robot Y -650, 50 mm outside the grid
    lines[first] = ",".join(cells)
    holes = tmp_path / "holes.csv"
    holes.write_text("\n".join(lines) + "\n")
    argv = ["gcode", str(holes), "--cell", str(EXAMPLES / "cell.yaml")]
    assert main([*argv, "-o", str(tmp_path / "refused.ngc")]) == 2
    assert "outside the grid" in capsys.readouterr().err
    assert main([*argv, "--outside", "clamp", "-o", str(tmp_path / "clamped.ngc")]) == 0
    err = capsys.readouterr().err
    assert err.startswith("accugrid gcode: warning: 1 hole(s) flagged, first hole 'WP-R1-001'")
    assert err.endswith(
        "holes.csv:4): outside the grid box by 50.000 mm: the nearest cell's error used\n"
    )
    assert main([*argv, "--allow-partial", "-o", str(tmp_path / "partial.ngc")]) == 0
    assert (
        "(not corrected: hole WP-R1-001: outside the grid box by 50.000 mm)"
        in (tmp_path / "partial.ngc").read_text()
    )
    assert "not corrected" not in (tmp_path / "clamped.ngc").read_text()
    assert not (tmp_path / "refused.ngc").exists()


def test_rewrite_takes_outside_as_correct_does(tmp_path, capsys):
    """The example G-code's home pose lies 250 mm outside the example grid: refused by default,
    corrected from the nearest cell and flagged with --outside clamp (the example also has a
    position it cannot place, which --allow-partial leaves as it is)."""
    argv = ["rewrite", str(EXAMPLES / "cam_drill.ngc"), "--cell", str(EXAMPLES / "cell.yaml")]
    assert main([*argv, "-o", str(tmp_path / "refused.ngc")]) == 2
    assert "cannot be corrected (2 outside the grid, " in capsys.readouterr().err
    report = tmp_path / "report.csv"
    out = ["-o", str(tmp_path / "clamped.ngc"), "--report", str(report)]
    assert main([*argv, "--outside", "clamp", "--allow-partial", *out]) == 0
    assert "2 corrected position(s) flagged" in capsys.readouterr().err
    clamped = [r for r in report.read_text().splitlines() if "outside the grid box by 250" in r]
    assert len(clamped) == 2 and all(",corrected,flag: " in r for r in clamped)
    assert not (tmp_path / "refused.ngc").exists()
