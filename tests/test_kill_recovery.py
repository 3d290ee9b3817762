"""A job of several files is all old or all new after a SIGKILL at any file operation.

A forked child runs the real command and SIGKILLs itself at the k-th temporary written, rename,
removal or folder removal of ``infra.atomic``, for every k the job has. Before any recovery the
entry point (the KRL ``.src``, the rewritten program, the calibrated YAML) never stands beside a
mix; after the recovery every accugrid write does first, the set is exactly the old or the new.
"""

from __future__ import annotations

import os
import shutil
import signal
import types

import pytest
from conftest import EXAMPLES

from accugrid.app.cli import main
from accugrid.infra import atomic


def visible(folders):
    """Every non-hidden file of ``folders``: (folder name, file name) -> bytes."""
    return {
        (f.name, p.name): p.read_bytes()
        for f in folders
        for p in sorted(f.iterdir())
        if not p.name.startswith(".")
    }


def restore(folders, state):
    """Put ``folders`` back to ``state`` (a ``visible`` snapshot), hidden leftovers removed."""
    for folder in folders:
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
    for (folder_name, name), data in state.items():
        next(f for f in folders if f.name == folder_name).joinpath(name).write_bytes(data)


def kill_at(at: int, argv) -> tuple[int, int]:
    """Run ``main(argv)`` in a forked child whose ``infra.atomic`` SIGKILLs the process at its
    ``at``-th temporary written, rename, removal or folder removal (0: never). (exit code, -9
    when killed; the number of those operations the child made)."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns to pytest
        code, count = 1, [0]
        try:
            os.close(read)
            for fd in (1, 2):
                os.dup2(os.open(os.devnull, os.O_WRONLY), fd)

            def counted(real):
                def call(*args, **kwargs):
                    count[0] += 1
                    os.write(write, b".")
                    if count[0] == at:
                        os.kill(os.getpid(), signal.SIGKILL)
                    return real(*args, **kwargs)

                return call

            fs = types.SimpleNamespace(**vars(os))
            for name in ("replace", "rename", "unlink", "rmdir"):
                setattr(fs, name, counted(getattr(os, name)))
            atomic.os = fs
            atomic._write_temp = counted(atomic._write_temp)  # and each temporary written
            code = main([str(a) for a in argv])
        finally:
            os._exit(code)
    os.close(write)
    with os.fdopen(read, "rb") as said:
        operations = len(said.read())  # until the child ends
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status), operations


def check_every_kill(folders, entry, old_argv, new_argv):
    """Run ``old_argv`` then, for every k, ``new_argv`` killed at its k-th file operation;
    check the invariant before recovery and all-old-or-all-new after. Returns the outcomes."""
    assert main([str(a) for a in old_argv]) == 0
    old = visible(folders)
    code, operations = kill_at(0, new_argv)  # never killed: counts the operations
    assert code == 0
    new = visible(folders)
    assert new != old and len(new) > 1
    outcomes = []
    for at in range(1, operations + 1):
        restore(folders, old)
        assert kill_at(at, new_argv)[0] == -9, at
        seen = visible(folders)
        if entry.exists():  # whoever starts from the entry point sees one job
            assert seen in (old, new), at
        atomic.recover(folders)  # what the next accugrid write into the folder does first
        after = visible(folders)
        assert after in (old, new), (at, sorted(set(after.items()) ^ set(old.items())))
        assert not [p for f in folders for p in f.iterdir() if p.name.endswith(".accugrid.tmp")]
        outcomes.append("new" if after == new else "old")
    # the kills fell before the journal (all old) and after it (all new)
    assert outcomes[0] == "old" and outcomes[-1] == "new", outcomes
    return outcomes


@pytest.fixture
def cell_dir(tmp_path):
    for name in ("cell.yaml", "grid_200mm.csv", "wing_panel_points.csv", "cam_drill.src"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    shutil.copy(EXAMPLES / "cam_drill.dat", tmp_path / "cam_drill.dat")
    return tmp_path


def test_krl_modules_after_a_kill_at_every_step(cell_dir):
    """The old job has more modules than the new one: stale modules go too, or none does."""
    cell = cell_dir / "cell.yaml"
    text = cell.read_text()
    (cell_dir / "long.yaml").write_text(
        text.replace("lines_per_file: 5000 ", "lines_per_file: 120  ")
    )
    (cell_dir / "short.yaml").write_text(
        text.replace("lines_per_file: 5000 ", "lines_per_file: 250  ")
    )
    out = cell_dir / "krl"
    common = ["krl", cell_dir / "wing_panel_points.csv", "-o", out, "--force", "--cell"]
    outcomes = check_every_kill(
        [out], out / "WING_PANEL.src", [*common, cell_dir / "long.yaml"], [*common, cell]
    )
    assert len(outcomes) > 8


def test_rewrite_program_and_report_after_a_kill_at_every_step(cell_dir):
    """A KRL pair and its report, the report in another folder: one job across two folders
    (the example's home PTP lies outside the grid: --allow-partial)."""
    out, reports = cell_dir / "out", cell_dir / "reports"
    out.mkdir()
    reports.mkdir()
    common = [
        "rewrite",
        *(cell_dir / f"cam_drill.{ext}" for ext in ("src", "dat")),
        "--cell",
        cell_dir / "cell.yaml",
        "-o",
        out,
        "--report",
        reports / "report.csv",
        "--force",
        "--allow-partial",
    ]
    check_every_kill([out, reports], out / "cam_drill.src", common, [*common, "--header"])


def test_identify_yaml_and_urdf_after_a_kill_at_every_step(tmp_path):
    robot = ["--robot", "kr210", "--tool", "0", "0", "250", "0", "0", "0"]
    plan, meas = tmp_path / "plan", tmp_path / "meas.csv"
    assert main(["plan", "identify", *robot, "--count", "30", "-o", str(plan)]) == 0
    poses = next(plan.glob("*.csv"))
    assert main(["simulate", *robot, "--poses", str(poses), "--seed", "1", "-o", str(meas)]) == 0
    out = tmp_path / "cal"
    out.mkdir()
    common = ["identify", meas, *robot, "-o", out / "cal.yaml", "--urdf", out / "cal.urdf"]
    old, new = [*common, "--structure", "dh", "--folds", "0"], [*common, "--force"]
    check_every_kill([out], out / "cal.yaml", old, new)


def test_the_next_write_into_the_folder_finishes_a_killed_job(cell_dir):
    """No explicit recovery: another command writing into the folder finds the dead job's
    journal and completes it before its own write."""
    out = cell_dir / "krl"
    common = [
        "krl",
        cell_dir / "wing_panel_points.csv",
        "-o",
        out,
        "--cell",
        cell_dir / "cell.yaml",
    ]
    assert main([str(a) for a in common]) == 0
    first = visible([out])
    for at in range(1, 20):  # the first kill after the journal took the old entry point
        restore([out], first)
        assert kill_at(at, [*common, "--force", "--no-correction"])[0] == -9
        if not (out / "WING_PANEL.src").exists():
            break
    assert not (out / "WING_PANEL.src").exists()  # killed between the journal and the end
    points = out / "wing_panel_copy.csv"
    argv = ["correct", EXAMPLES / "wing_panel_robot.csv", "--grid", cell_dir / "grid_200mm.csv"]
    assert main([str(a) for a in [*argv, "-o", points]]) == 0
    after = {k: v for k, v in visible([out]).items() if k[1] != points.name}
    assert after != first and after.keys() == first.keys()
    assert not [p for p in out.iterdir() if p.name.endswith(".accugrid.tmp")]
