"""A command ended by SIGINT or SIGTERM exits 128 + the signal's number with one line on stderr
and no traceback, whether the signal arrives while its modules are imported or while it
computes. The command runs in a child process as the console script runs it (``main`` of
``accugrid.app.cli``); the signal is sent by the child to itself at a chosen point, so the test
does not depend on timing: while numpy is imported (start-up), or when the structure selection
is done and the identification starts (mid-compute: seconds of work done, seconds to go)."""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest

from tests.test_identify_cli import TOOL, joints, write_csv

# argv: signal number, when ("import" or "compute"), then the accugrid arguments
CHILD = """
import os, sys
sig, when, argv = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
if when == "import":
    class SignalOnImport:  # the signal arrives while numpy is being imported
        def find_spec(self, name, path=None, target=None):
            if name == "numpy":
                os.kill(os.getpid(), sig)
            return None
    sys.meta_path.insert(0, SignalOnImport())
elif when == "write":
    import accugrid.infra.atomic as atomic
    real_write = atomic._write_temp
    def write_temp(*args):  # the signal arrives while the first temporary is written
        os.kill(os.getpid(), sig)
        return real_write(*args)
    atomic._write_temp = write_temp
else:
    import accugrid.kinematics.identification as identification
    real, calls = identification.identify, []
    def identify(*args, **kwargs):  # the signal arrives at the first identification
        calls.append(1)
        if len(calls) == 1:
            os.kill(os.getpid(), sig)
        return real(*args, **kwargs)
    identification.identify = identify
from accugrid.app.cli import main
sys.exit(main(argv))
"""


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("when", ["import", "compute"])
def test_a_signal_ends_identify_with_128_plus_its_number_and_one_line(tmp_path, sig, when):
    csv = write_csv(tmp_path / "meas.csv", joints(40, 1), noise=0.02)
    out = tmp_path / "cal.yaml"
    argv = ["identify", str(csv), "--robot", "kr210", "--tool", *TOOL, "-o", str(out)]
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(int(sig)), when, *argv],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 128 + sig, proc.stderr
    assert proc.stderr == f"accugrid identify: interrupted ({sig.name})\n"
    assert not out.exists()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_writing_ends_the_command_with_one_line_and_the_old_output(tmp_path, sig):
    out = tmp_path / "grid.csv"
    out.write_text("before\n")
    argv = ["simulate", "--region", "1200", "2200", "-500", "500", "1100", "2100", "--step", "500"]
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(int(sig)), "write", *argv, "-o", str(out), "--force"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 128 + sig, proc.stderr
    assert proc.stderr == f"accugrid simulate: interrupted ({sig.name})\n"
    assert out.read_text() == "before\n" and [p.name for p in tmp_path.iterdir()] == ["grid.csv"]
