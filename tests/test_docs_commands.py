"""The commands a newcomer copies from README.md and docs/*.md run, and the pages' links resolve.

Every ```sh block of README.md and docs/*.md is a list of shell commands: each `accugrid ...`
command (backslash continuations joined, `#` comments dropped) runs with the venv's console
script from a temporary folder holding a copy of examples/, the commands of one page in order
(later ones read what earlier ones wrote), and must exit 0. `make ...` lines are skipped (the
quick start is `make demo` / `make test` itself). Blocks that only illustrate (the install, a
user's own file names, a long study, the output a command prints) are fenced ```text or
```console and are not run. docs/validation.md is run by tests/test_validate.py and is skipped
here.
"""

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT

__all__: list[str] = []

RUN_ELSEWHERE = {"validation.md"}  # tests/test_validate.py runs its sh blocks
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
ACCUGRID = Path(sys.executable).with_name("accugrid")


def sh_commands(text: str) -> list[str]:
    """The commands of the ```sh blocks of a Markdown text, continuations joined, in order."""
    commands = []
    for block in re.findall(r"^```sh\n(.*?)^```", text, flags=re.M | re.S):
        joined = re.sub(r"\s*\\\n\s*", " ", block)
        for line in joined.splitlines():
            line = line.strip()
            if line and not line.startswith("#"):
                commands.append(line)
    return commands


def test_the_extractor_reads_blocks_continuations_and_comments():
    text = "x\n```sh\n# c\naccugrid a \\\n    --b 1\nmake demo\n```\n```text\naccugrid no\n```\n"
    assert sh_commands(text) == ["accugrid a --b 1", "make demo"]


def _page_id(page: Path) -> str:
    return str(page.relative_to(ROOT))


RUNNABLE = [p for p in PAGES if p.name not in RUN_ELSEWHERE and sh_commands(p.read_text())]


@pytest.mark.parametrize("page", RUNNABLE, ids=_page_id)
def test_every_command_of_the_page_runs(page, tmp_path):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    ran = 0
    for command in sh_commands(page.read_text()):
        words = shlex.split(command)
        if words[0] == "make":
            continue
        assert words[0] == "accugrid", f"{_page_id(page)}: not an accugrid command: {command}"
        done = subprocess.run(
            [str(ACCUGRID), *words[1:]], cwd=tmp_path, capture_output=True, text=True, timeout=120
        )
        assert done.returncode == 0, f"{_page_id(page)}: {command}\n{done.stderr[-2000:]}"
        ran += 1
    assert ran, f"{_page_id(page)}: no accugrid command ran"


LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


@pytest.mark.parametrize("page", PAGES + [ROOT / "CHANGELOG.md"], ids=_page_id)
def test_every_relative_link_resolves(page):
    text = page.read_text()
    anchors = {_anchor(h) for h in re.findall(r"^#+ (.*)$", text, flags=re.M)}
    missing = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):
            continue  # an external address
        path, _, anchor = target.partition("#")
        if path:
            resolved = (page.parent / path).resolve()
            if not resolved.exists():
                missing.append(target)
            elif anchor and resolved.suffix == ".md":
                heads = re.findall(r"^#+ (.*)$", resolved.read_text(), flags=re.M)
                if anchor not in {_anchor(h) for h in heads}:
                    missing.append(target)
        elif anchor not in anchors:
            missing.append(target)
    assert not missing, f"{_page_id(page)}: links that do not resolve: {missing}"


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces as dashes."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def test_the_docs_name_no_issue_numbers():
    for page in PAGES:
        found = re.findall(r"issue [0-9]+", page.read_text(), flags=re.I)
        assert not found, f"{_page_id(page)}: {found}"


WRITTEN_MD = {"report.md": "app/jobs/study.py"}  # Markdown a command writes, and where


def _help_texts() -> dict[str, str]:
    """Every subcommand's --help text, by name."""
    import argparse

    from accugrid.app.cli import build_parser
    from accugrid.app.commands import COMMANDS

    texts = {}
    for name in COMMANDS:
        parser = build_parser(name)
        (commands,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        texts[name] = commands.choices[name].format_help()
    return texts


def test_the_docs_and_the_help_name_only_markdown_files_the_project_has():
    """A page or a --help that names a .md file names one the project ships (beside the page,
    at the root or in docs/), or one a command writes."""
    for source, path in WRITTEN_MD.items():
        assert f'"{source}"' in (ROOT / path).read_text(), (source, path)
    texts = {_page_id(p): (p.parent, p.read_text()) for p in PAGES + [ROOT / "CHANGELOG.md"]}
    texts.update({f"accugrid {n} --help": (ROOT, t) for n, t in _help_texts().items()})
    missing = []
    for where, (folder, text) in texts.items():
        for name in re.findall(r"[\w./-]*\.md\b", text):
            places = (folder / name, ROOT / name, ROOT / "docs" / name)
            if Path(name).name not in WRITTEN_MD and not any(p.exists() for p in places):
                missing.append(f"{where}: {name}")
    assert not missing, missing


def test_rewrite_help_says_arcs_move_rigidly():
    """G-code arcs are rewritten (codegen.gcode.arc_shift): the help does not count them among
    what is left untouched."""
    text = " ".join(_help_texts()["rewrite"].split())
    untouched = text.split(" is left untouched")[0].rsplit("Anything that cannot be placed", 1)[1]
    assert "arc" not in untouched
    assert "A G-code arc (G2/G3) moves rigidly" in text


HISTORY = ("this round", "load average", "(before)", "earlier code", "earlier run", "not kept")


def test_the_docs_state_the_current_method_and_numbers_not_their_history():
    """README and docs/ describe what the product does and measures now; how it got there is the
    CHANGELOG's."""
    found = [
        f"{_page_id(page)}: {phrase}"
        for page in PAGES
        for phrase in HISTORY
        if phrase in page.read_text().lower()
    ]
    assert not found, found
