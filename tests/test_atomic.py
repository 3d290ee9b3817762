"""Issue 12 items 1, 2, 5 and 16: inputs are never replaced, special files are refused, a job's
files appear whole or not at all, temporaries never stay behind."""

from __future__ import annotations

import os
import shutil
import signal
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import EXAMPLES, ROOT

from accugrid.app.cli import main
from accugrid.infra import atomic
from accugrid.infra.atomic import check_targets, write_files
from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import read_input_bytes, track_inputs


@pytest.fixture
def cell_dir(tmp_path):
    """A copy of the example cell (built-in robot), its grid and the wing-panel points."""
    for name in ("cell.yaml", "grid_200mm.csv", "wing_panel_points.csv", "cam_drill.ngc"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    return tmp_path


def snapshot(folder):
    return {p.name: p.read_text("latin-1") for p in sorted(folder.rglob("*")) if p.is_file()}


def run(argv, capsys):
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


# ---------------------------------------------------------------- item 1: inputs never written


def test_rewrite_refuses_the_grid_the_cell_names_as_output_and_report(cell_dir, capsys):
    before = snapshot(cell_dir)
    grid = cell_dir / "grid_200mm.csv"
    ngc = cell_dir / "cam_drill.ngc"
    cell = cell_dir / "cell.yaml"
    code, err = run(
        ["rewrite", ngc, "--cell", cell, "-o", grid, "--force", "--allow-partial"], capsys
    )
    assert code == 2 and "refusing to overwrite an input file" in err
    out = cell_dir / "out.ngc"
    code, err = run(
        ["rewrite", ngc, "--cell", cell, "-o", out, "--report", grid, "--force", "--allow-partial"],
        capsys,
    )
    assert code == 2 and "refusing to overwrite an input file" in err
    assert snapshot(cell_dir) == before


def test_gcode_refuses_the_robot_yaml_the_cell_names(cell_dir, capsys):
    robot = cell_dir / "robot.yaml"
    shutil.copy(ROOT / "kinematics" / "robots" / "kr210-paper.yaml", robot)
    cell = cell_dir / "cell.yaml"
    cell.write_text(cell.read_text().replace("robot: kr210-paper", "robot: robot.yaml"))
    before = snapshot(cell_dir)
    argv = ["gcode", cell_dir / "wing_panel_points.csv", "--cell", cell, "-o", robot, "--force"]
    code, err = run(argv, capsys)
    assert code == 2 and f"{robot}: refusing to overwrite an input file" in err
    assert snapshot(cell_dir) == before


def test_gcode_refuses_a_template_file_and_symlinks_or_hard_links_to_inputs(cell_dir, capsys):
    templates = cell_dir / "templates"
    shutil.copytree(ROOT / "templates" / "gcode", templates)
    points = cell_dir / "wing_panel_points.csv"
    (cell_dir / "link.csv").symlink_to(points)
    os.link(points, cell_dir / "hard.csv")
    before = snapshot(cell_dir)
    common = ["gcode", points, "--cell", cell_dir / "cell.yaml", "--force"]
    for target in (
        next(templates.glob("*.j2")),
        cell_dir / "link.csv",
        cell_dir / "hard.csv",
    ):
        code, err = run([*common, "--templates", templates, "-o", target], capsys)
        assert code == 2 and "refusing to overwrite an input file" in err, target
    assert snapshot(cell_dir) == before


def test_tracked_inputs_are_refused_even_when_not_passed():
    with track_inputs():
        read_input_bytes(EXAMPLES / "cell.yaml")
        with pytest.raises(InputError, match="refusing to overwrite an input"):
            check_targets([EXAMPLES / "cell.yaml"], force=True)


# ---------------------------------------------------------------- item 5: special files


def test_special_outputs_are_refused_even_with_force(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for target, kind in ((os.devnull, "device"), (fifo, "FIFO"), (tmp_path, "folder")):
        with pytest.raises(InputError, match=f"output exists and is a {kind}"):
            write_files({target: "x"}, force=True)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and stat.S_ISCHR(os.stat(os.devnull).st_mode)


def test_an_output_whose_folder_is_a_file_is_an_input_error(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="is not a folder"):
        write_files({tmp_path / "file" / "out.csv": "y"})


def test_fifo_and_dev_zero_inputs_are_refused_without_blocking(tmp_path):
    """Issue items 5, 6 and 16: a FIFO input, /dev/zero and a symlink to it (past --max-mb)."""
    fifo = tmp_path / "points.csv"
    os.mkfifo(fifo)
    (tmp_path / "zero.ngc").symlink_to("/dev/zero")
    cell = EXAMPLES / "cell.yaml"
    runs = [
        ["correct", fifo, "--grid", EXAMPLES / "grid_200mm.csv", "-o", tmp_path / "o.csv"],
        ["rewrite", tmp_path / "zero.ngc", "--cell", cell, "-o", tmp_path / "o.ngc"],
        ["rewrite", "/dev/zero", "--cell", cell, "-o", tmp_path / "o.ngc"],
    ]
    for argv in runs:
        proc = subprocess.run(
            [sys.executable, "-m", "accugrid.app.cli", *map(str, argv)],
            capture_output=True,
            text=True,
            timeout=60,  # a guard against a hang, not a timing assertion
        )
        assert proc.returncode == 2, proc.stderr
        # a bare /dev/zero has no program suffix: refused by the dialect registry before reading
        bare = argv[1] == "/dev/zero"
        assert ("unknown program type" if bare else "not a regular file") in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["points.csv", "zero.ngc"]


# ---------------------------------------------------------------- item 2: whole or nothing


def test_permissions_follow_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        (path,) = write_files({tmp_path / "a.src": "x"})
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644


def fail_third_write(monkeypatch) -> list:
    """Make the third temporary file of a write fail with ENOSPC; returns the attempts."""
    real = atomic._write_temp
    calls = []

    def failing(tmp, payload):
        calls.append(tmp)
        if len(calls) == 3:
            raise OSError(28, "No space left on device")
        real(tmp, payload)

    monkeypatch.setattr(atomic, "_write_temp", failing)
    return calls


def test_a_failure_while_writing_leaves_targets_and_no_temporaries(tmp_path, monkeypatch):
    old = {tmp_path / f"J_{k}.src": f"old {k}" for k in range(4)}
    write_files(old)
    fail_third_write(monkeypatch)
    with pytest.raises(InputError, match="No space left"):
        write_files({p: "new" for p in old}, force=True)
    assert {p: p.read_text() for p in old} == old
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in old)


def test_a_job_of_several_files_writes_its_temporaries_in_one_folder_inside_the_targets(
    tmp_path, monkeypatch
):
    old = {tmp_path / f"J_{k}.src": f"old {k}" for k in range(3)}
    write_files(old)
    real, seen = atomic._write_temp, []

    def spy(tmp, payload):
        seen.append(Path(tmp))
        real(tmp, payload)

    monkeypatch.setattr(atomic, "_write_temp", spy)
    write_files({p: "new" for p in old}, force=True)
    (holder,) = {t.parent for t in seen}
    assert holder.parent == tmp_path and holder.name.endswith(".accugrid.tmp")
    assert sorted(t.name for t in seen) == sorted(p.name for p in old)
    assert {p: p.read_text() for p in old} == {p: "new" for p in old}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in old)
    write_files({tmp_path / "one.src": "x"})  # one file: its temporary beside it
    assert seen[-1].parent == tmp_path and seen[-1].name.startswith(".one.src.")


@pytest.mark.parametrize("folder", ["", "new"])  # an existing folder, one made by the write
def test_every_file_is_synced_before_the_first_rename(tmp_path, monkeypatch, folder):
    """Each temporary is fsynced (on the background thread) before any rename puts a file in
    place; only folders are synced after."""
    target = tmp_path / folder
    files = job("JOB", 3, "new")
    if not folder:
        write_job(target, files, "JOB")
    events = []
    real_fsync, real_replace, real_rename = os.fsync, os.replace, os.rename

    def fsync(fd):
        kind = "folder" if stat.S_ISDIR(os.fstat(fd).st_mode) else "file"
        events.append(kind)
        real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    monkeypatch.setattr(
        atomic.os, "replace", lambda a, b: events.append("rename") or real_replace(a, b)
    )
    monkeypatch.setattr(
        atomic.os, "rename", lambda a, b: events.append("rename") or real_rename(a, b)
    )
    write_job(target, files, "JOB")
    first_rename = events.index("rename")
    # a folder made by the write: one rename of it; an existing one: the temporary folder's
    # entry, then the journal (a file and its folder) are made durable before its rename
    # commits the job
    before = ["file"] * len(files) + ([] if folder else ["folder", "file", "folder"])
    assert events[:first_rename] == before
    assert "file" not in events[first_rename:]
    assert snapshot(target) == files


@pytest.mark.parametrize("folder", ["", "new"])
def test_a_file_that_cannot_be_synced_leaves_targets_and_no_temporaries(
    tmp_path, monkeypatch, folder
):
    target = tmp_path / folder
    old = job("JOB", 3, "old")
    if not folder:
        write_job(target, old, "JOB")
    real_fsync, synced = os.fsync, []

    def failing(fd):
        synced.append(fd)
        if len(synced) == 2:
            raise OSError(5, "Input/output error")
        real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", failing)
    with pytest.raises(InputError, match="cannot write: Input/output error") as error:
        write_job(target, job("JOB", 3, "new"), "JOB")
    assert Path(error.value.path).parent == target  # names the target, not its temporary
    monkeypatch.undo()
    if folder:
        assert list(tmp_path.iterdir()) == []
    else:
        assert snapshot(target) == old
        assert sorted(p.name for p in target.iterdir()) == sorted(old)


def job(name, parts, tag):
    """A KRL-like job: NAME.src calls NAME_001..; every file says which job it belongs to.
    File name -> text."""
    files = {
        f"{name}_{k:03d}.{ext}": f"{tag}" for k in range(1, parts + 1) for ext in "src dat".split()
    }
    files[f"{name}.dat"] = tag
    files[f"{name}.src"] = (
        tag + " calls " + " ".join(f"{name}_{k:03d}" for k in range(1, parts + 1))
    )
    return files


def write_job(folder, files, name, **kw):
    stale = [p for p in folder.glob(f"{name}_[0-9][0-9][0-9].*")]
    return write_files(
        {folder / f: t for f, t in files.items()},
        force=True,
        main=[folder / f"{name}.dat", folder / f"{name}.src"],
        stale=stale,
        **kw,
    )


def consistent(folder, name):
    """The invariant a kill must keep: if NAME.src exists, every module it calls exists and is
    from the same job as it."""
    main_src = folder / f"{name}.src"
    if not main_src.exists():
        return True
    tag, _, calls = main_src.read_text().partition(" calls ")
    return (
        all(
            (folder / f"{m}.{ext}").exists() and (folder / f"{m}.{ext}").read_text() == tag
            for m in calls.split()
            for ext in ("src", "dat")
        )
        and (folder / f"{name}.dat").read_text() == tag
    )


class Killed(BaseException):
    """Stands for SIGKILL: the process stops at once, nothing is cleaned up."""


@pytest.mark.parametrize("new_parts", [2, 5])
def test_a_job_killed_at_any_step_of_the_swap_is_whole_after_recovery(
    tmp_path, monkeypatch, new_parts
):
    """Stop the write after every possible number of file operations (the journal's rename,
    each removal and rename): until the next write the entry point never stands beside a mix;
    after ``recover`` the folder holds exactly the old job or exactly the new one."""
    name = "JOB"
    old, new = job(name, 4, "old"), job(name, new_parts, "new")
    outcomes = set()
    for stop_after in range(2 * new_parts + 20):
        folder = tmp_path / f"k{stop_after}"
        folder.mkdir()
        write_job(folder, old, name)
        count = [0]

        def op(real, count=count, stop_after=stop_after):
            def wrapped(*args):
                if count[0] == stop_after:
                    raise Killed
                count[0] += 1
                return real(*args)

            return wrapped

        for call in ("replace", "rename", "unlink", "rmdir"):
            monkeypatch.setattr(atomic.os, call, op(getattr(os, call)))
        try:
            write_job(folder, new, name)
            done = True
        except Killed:
            done = False
        monkeypatch.undo()
        assert consistent(folder, name), (stop_after, snapshot(folder))
        atomic.recover([folder])  # what the next accugrid write into the folder does first
        after = {p.name: p.read_text() for p in folder.iterdir()}
        assert after in (old, new), (stop_after, after)
        outcomes.add("new" if after == new else "old")
        if done:
            break
    assert outcomes == {"old", "new"}  # kills before and after the journal were both seen


def test_a_complete_job_replaces_a_longer_one_without_stale_modules(tmp_path):
    write_job(tmp_path, job("JOB", 4, "old"), "JOB")
    write_job(tmp_path, job("JOB", 2, "new"), "JOB")
    assert snapshot(tmp_path) == job("JOB", 2, "new")


def test_temporaries_of_dead_processes_are_removed(tmp_path):
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True
    )
    pid = int(dead.stdout)
    leftover = tmp_path / f".A.src.{pid}.deadbeef.accugrid.tmp"
    leftover.write_text("half")
    write_files({tmp_path / "A.src": "whole"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["A.src"]


SIGTERM_SCRIPT = """
import sys, time
from accugrid.infra import atomic
real = atomic._write_temp
def slow(tmp, payload):
    real(tmp, payload)
    print("wrote", flush=True)
    time.sleep(0.2)
atomic._write_temp = slow
atomic.write_files({f"{sys.argv[1]}/F_{k}.src": "new" for k in range(50)}, force=True)
"""


@pytest.mark.parametrize("folder", ["", "new"])  # an existing folder, one made by the write
def test_sigterm_while_writing_removes_the_temporaries(tmp_path, folder):
    proc = subprocess.Popen(
        [sys.executable, "-c", SIGTERM_SCRIPT, str(tmp_path / folder)],
        stdout=subprocess.PIPE,
        text=True,
    )
    for _ in range(3):
        proc.stdout.readline()
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=60) == 128 + signal.SIGTERM
    assert list(tmp_path.iterdir()) == []


def test_a_krl_job_over_a_longer_one_leaves_only_the_new_modules(cell_dir, capsys):
    cell = cell_dir / "cell.yaml"
    points = cell_dir / "wing_panel_points.csv"
    text = cell.read_text()
    cell.write_text(text.replace("lines_per_file: 5000 ", "lines_per_file: 120  "))
    assert run(["krl", points, "--cell", cell, "-o", cell_dir / "krl"], capsys)[0] == 0
    long_job = sorted(p.name for p in (cell_dir / "krl").iterdir())
    cell.write_text(text.replace("lines_per_file: 5000 ", "lines_per_file: 400  "))
    assert run(["krl", points, "--cell", cell, "-o", cell_dir / "krl", "--force"], capsys)[0] == 0
    short_job = sorted(p.name for p in (cell_dir / "krl").iterdir())
    assert len(short_job) < len(long_job)
    main_src = (cell_dir / "krl" / "WING_PANEL.src").read_text()
    modules = {p[:-4] for p in short_job if p != "WING_PANEL.src" and p != "WING_PANEL.dat"}
    assert modules and all(m in main_src for m in modules)


def test_a_file_may_come_as_text_bytes_a_bytearray_or_pieces(tmp_path):
    # the rewrite builds its programs as bytearrays, krl/gcode render text in pieces
    contents = {
        tmp_path / "text.txt": "naïve\n",
        tmp_path / "bytes.bin": b"\x00\xff",
        tmp_path / "array.bin": bytearray(b"LIN P1\r\n"),
        tmp_path / "pieces.txt": iter(["a", b"b", "c\n"]),
    }
    write_files(contents)
    assert (tmp_path / "text.txt").read_bytes() == "naïve\n".encode()
    assert (tmp_path / "bytes.bin").read_bytes() == b"\x00\xff"
    assert (tmp_path / "array.bin").read_bytes() == b"LIN P1\r\n"
    assert (tmp_path / "pieces.txt").read_bytes() == b"abc\n"


# ---------------------------------------------------------------- a job into a new folder


def test_a_job_into_a_new_folder_appears_whole_with_the_umask(tmp_path, monkeypatch):
    """Several files into a folder that does not exist: written in a temporary folder that one
    rename puts in place (no rename per file), with the umask's permissions like any folder."""
    folder = tmp_path / "deep" / "krl"
    files = job("JOB", 3, "new")
    renames = []
    for name in ("rename", "replace"):
        real = getattr(os, name)
        monkeypatch.setattr(
            atomic.os, name, lambda a, b, real=real: renames.append(b) or real(a, b)
        )
    old = os.umask(0o027)
    try:
        written = write_job(folder, files, "JOB")
    finally:
        os.umask(old)
    assert renames == [folder]
    assert snapshot(folder) == files and len(written) == len(files)
    assert stat.S_IMODE(folder.stat().st_mode) == 0o750
    assert stat.S_IMODE((folder / "JOB.src").stat().st_mode) == 0o640
    assert sorted(p.name for p in (tmp_path / "deep").iterdir()) == ["krl"]


def test_a_failure_while_writing_a_new_folder_leaves_nothing(tmp_path, monkeypatch):
    calls = fail_third_write(monkeypatch)
    with pytest.raises(InputError, match="No space left"):
        write_job(tmp_path / "krl", job("JOB", 2, "new"), "JOB")
    assert len(calls) == 3 and list(tmp_path.iterdir()) == []


def test_a_temporary_folder_of_a_dead_process_is_removed(tmp_path):
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True
    )
    leftover = tmp_path / f".krl.{int(dead.stdout)}.deadbeef.accugrid.tmp"
    leftover.mkdir()
    (leftover / "JOB_001.src").write_text("half")
    write_job(tmp_path / "krl", job("JOB", 1, "new"), "JOB")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["krl"]


# ---------------------------------------------------------------- names and folders at the limits


@pytest.mark.parametrize("count", [1, 3])
def test_output_names_of_255_bytes_are_written(tmp_path, count):
    """The temporary's name is cut to fit in NAME_MAX, not the output's: 255-byte names (here
    with two-byte characters) work alone, in a job of several files and as a new folder."""
    stem = "é" * 125  # 250 bytes
    files = {tmp_path / f"{stem}{k}.src": f"job {k}" for k in range(count)}
    assert all(len(os.fsencode(p.name)) == 255 for p in files)
    write_files(files)
    write_files({p: "again" for p in files}, force=True)  # over existing files: the journal
    assert {p: p.read_text() for p in files} == {p: "again" for p in files}
    folder = tmp_path / ("d" * 255)
    write_files({folder / "a.src": "a", folder / "b.src": "b"})
    assert snapshot(folder) == {"a.src": "a", "b.src": "b"}
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".accugrid.tmp")]


def test_an_output_a_thousand_folders_deep_is_made_without_recursion(tmp_path, capsys):
    deep = tmp_path.joinpath(*["a"] * 1000)
    points = tmp_path / "points.csv"
    points.write_text("x,y,z\n1700,0,1500\n")
    grid = EXAMPLES / "grid_200mm.csv"
    try:
        code, err = run(["correct", points, "--grid", grid, "-o", deep / "o.csv"], capsys)
        assert code == 0, err
        assert "\n1700,0,1500," in (deep / "o.csv").read_text()
    finally:  # shutil.rmtree (pytest's clean-up) recurses once per level
        levels = [tmp_path / "a"]
        while (levels[-1] / "a").is_dir():
            levels.append(levels[-1] / "a")
        for level in reversed(levels):
            for file in level.glob("*.csv"):
                file.unlink()
            if level.is_dir():
                level.rmdir()
    too_deep = tmp_path.joinpath(*["b" * 200] * 30)  # longer than PATH_MAX (4096 bytes)
    code, err = run(["correct", points, "--grid", grid, "-o", too_deep / "o.csv"], capsys)
    assert code == 2 and "File name too long" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["points.csv"]  # no folder begun
