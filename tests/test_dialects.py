"""The dialect registry: a program's dialect comes from its suffix, unknown suffixes are refused."""

from __future__ import annotations

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


@pytest.mark.parametrize("name", ["notes.txt", "program", "drill.ls"])
def test_unknown_suffix_is_refused_not_taken_for_gcode(name):
    with pytest.raises(InputError, match="unknown program type"):
        dialect_of(name)


def test_rewrite_refuses_an_unknown_suffix(tmp_path, capsys):
    program = tmp_path / "drill.ls"
    program.write_text("/PROG DRILL\n/END\n")
    out = tmp_path / "out.ls"
    code = main(["rewrite", str(program), "--cell", "examples/cell.yaml", "-o", str(out)])
    assert code == 2 and not out.exists()
    assert "unknown program type '.ls'" in capsys.readouterr().err


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
