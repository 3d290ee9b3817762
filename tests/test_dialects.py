"""The dialect registry: a program's dialect comes from its suffix, unknown suffixes are refused."""

from __future__ import annotations

import dataclasses

import pytest

from accugrid.app.cli import main
from accugrid.codegen.dialects import DIALECTS, dialect_of
from accugrid.infra.errors import InputError


@pytest.mark.parametrize(
    ("name", "dialect"),
    [
        ("a.src", "krl"),
        ("B.DAT", "krl"),
        ("x.sub", "krl"),
        ("p.ngc", "gcode"),
        ("p.NC", "gcode"),
        ("m.mod", "rapid"),
        ("m.MODX", "rapid"),
        ("p.prg", "rapid"),
        ("user.sys", "rapid"),
    ],
)
def test_suffix_names_the_dialect(name, dialect):
    assert dialect_of(name) == dialect


def test_no_suffix_is_claimed_twice():
    suffixes = [s for d in DIALECTS.values() for s in d.suffixes]
    assert len(suffixes) == len(set(suffixes))


@pytest.mark.parametrize("name", ["notes.txt", "program", "drill.pdl"])
def test_unknown_suffix_is_refused_not_taken_for_gcode(name):
    with pytest.raises(InputError, match="unknown program type"):
        dialect_of(name)


def test_rewrite_refuses_an_unknown_suffix(tmp_path, capsys):
    program = tmp_path / "drill.pdl"
    program.write_text("PROGRAM drill\nEND drill\n")
    out = tmp_path / "out.pdl"
    code = main(["rewrite", str(program), "--cell", "examples/cell.yaml", "-o", str(out)])
    assert code == 2 and not out.exists()
    assert "unknown program type '.pdl'" in capsys.readouterr().err


def test_every_dialect_is_a_plugin_with_every_member_of_the_interface():
    from accugrid.codegen.dialects import plugin_of
    from accugrid.codegen.plugin import DialectPlugin

    members = set(DialectPlugin.__annotations__) | {
        k for k, v in vars(DialectPlugin).items() if callable(v) and not k.startswith("_")
    }
    assert {"suffixes", "render", "scan", "splice", "add_header", "read_section"} <= members
    for name, dialect in DIALECTS.items():
        plugin = plugin_of(name)
        missing = {m for m in members if not hasattr(plugin, m)}
        assert not missing, f"{name} lacks {sorted(missing)}"
        assert (plugin.name, plugin.title, plugin.suffixes) == (
            dialect.name,
            dialect.title,
            dialect.suffixes,
        )
        assert dialect.plugin == f"accugrid.codegen.{name}.plugin"  # its own folder


def test_the_measurement_program_is_a_capability_a_dialect_may_lack(tmp_path):
    """The plan job reaches the measurement program through the plug-in: KRL writes one (a .src
    and .dat beside the plan CSV); asking a dialect without one is a one-line InputError naming
    it, and nothing is written."""
    from accugrid.app.jobs.plan import PlanRequest, plan_files, plan_targets
    from accugrid.codegen.dialects import plugin_of
    from accugrid.kinematics.robot import load_robot

    names = [p.name for p in plan_targets(tmp_path, "cube", "Probe 1", "krl")]
    assert names == ["probe_1.csv", "probe_1.src", "probe_1.dat"]
    lacking = []
    for name, dialect in DIALECTS.items():
        try:
            plugin_of(name).measurement()
        except InputError as exc:
            assert (
                str(exc)
                == f"accugrid writes no laser-tracker measurement program in {dialect.title}"
            )
            lacking.append(name)
    assert "krl" not in lacking and {"gcode", "rapid"} <= set(lacking)
    request = PlanRequest(
        "cube", load_robot("kr210"), (0.0, 90.0, 0.0), centre=(1700.0, 0.0, 1500.0), step_mm=100.0
    )
    for name in lacking:
        with pytest.raises(InputError, match="no laser-tracker measurement program"):
            plan_targets(tmp_path, "cube", None, name)
        with pytest.raises(InputError, match=DIALECTS[name].title):
            plan_files(dataclasses.replace(request, dialect=name), tmp_path)
    assert not list(tmp_path.iterdir())
    job = plan_files(request, tmp_path)  # the default: KRL
    assert [p.name for p in job.files] == [
        "measure_cube.csv",
        "measure_cube.src",
        "measure_cube.dat",
    ]
    assert job.main == [tmp_path / "measure_cube.src"]
    assert job.files[tmp_path / "measure_cube.src"].startswith("&ACCESS")


def test_the_library_names_a_dialect_exports_resolve_through_the_registry():
    """``accugrid.codegen`` lists a dialect's renderer by the registry, not by its module."""
    import accugrid
    import accugrid.codegen as codegen
    from accugrid.codegen.dialects import plugin_of
    from accugrid.codegen.krl.emit import render_krl

    exported = {name for d in DIALECTS for name in plugin_of(d).exports}
    assert exported == {n for n, m in codegen._API.items() if m == "accugrid.codegen.dialects"}
    assert exported <= set(accugrid.__all__)
    assert accugrid.render_krl is codegen.render_krl is render_krl
    import accugrid.codegen.dialects as registry

    with pytest.raises(AttributeError, match="render_toy"):
        registry.render_toy  # noqa: B018


def test_a_plugin_says_whether_it_writes_measurement_programs_as_it_does():
    from accugrid.codegen.dialects import measuring, plugin_of

    for name in DIALECTS:
        plugin = plugin_of(name)
        if plugin.measures:
            assert plugin.measurement().name("probe 1")
        else:
            with pytest.raises(InputError, match="no laser-tracker measurement program"):
                plugin.measurement()
    assert measuring() == [name for name in DIALECTS if plugin_of(name).measures]
    assert measuring(), "a dialect writes the measurement program of accugrid plan"


def test_plan_writes_the_measurement_program_of_its_dialect(tmp_path, capsys):
    """``plan --dialect``: the dialects that write measurement programs, by default the first;
    another is refused by the parser (exit 2), nothing written."""
    from accugrid.codegen.dialects import measuring, plugin_of

    argv = ["plan", "cube", "--centre", "1700", "0", "1500", "--step", "200", "-o"]
    for name in measuring():
        out = tmp_path / name
        assert main([*argv, str(out), "--dialect", name]) == 0
        program = plugin_of(name).measurement().targets(out, "measure_cube")
        assert all(path.exists() for path in program)
    default = tmp_path / "default"
    assert main([*argv, str(default)]) == 0
    first = plugin_of(measuring()[0]).measurement().targets(default, "measure_cube")
    assert sorted(default.iterdir()) == sorted([first[0].with_suffix(".csv"), *first])
    for name in set(DIALECTS) - set(measuring()):
        with pytest.raises(SystemExit) as stop:
            main([*argv, str(tmp_path / name), "--dialect", name])
        assert stop.value.code == 2 and "invalid choice" in capsys.readouterr().err
        assert not (tmp_path / name).exists()
