"""Issue 12 items 3, 6, 9, 13 and 14 on programs: the cases the fuzz campaign found in the KRL and
G-code readers, run as whole `accugrid` processes.

The readers must be linear in their input: each case runs in a subprocess with a generous
timeout that only guards against a hang (nothing here measures speed).
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from rewrite_helpers import write_cell

KRL_BODY = "LIN {X 1700,Y 300,Z 1000,A 0,B 90,C 0}\n"
CASES = {
    # item 3: exponential backtracking in the readers
    "gcode_words": ("a.ngc", " ".join(c + "1" * 12 for c in "XYZABCUVW") + " @\n"),
    "krl_bas_spaces": ("a.src", "DEF A()\nBAS(#BASE," + " " * 5000 + "\n" + KRL_BODY + "END\n"),
    "krl_brace_spaces": ("a.src", "DEF A()\nLIN {X 1," + " " * 65536 + "}\nEND\n"),
    # item 6: digits and characters that ended in an internal error
    "krl_base_data_digits": ("a.src", "DEF A()\n$BASE=BASE_DATA[" + "9" * 5000 + "]\nEND\n"),
    "krl_status_digits": ("a.src", "DEF A()\nPTP {X 1,Y 2,Z 3,S " + "9" * 5000 + ",T 2}\nEND\n"),
    "krl_base_no_superscript": (
        "a.dat",
        "DEFDAT A\nDECL FDAT FP1={TOOL_NO 1,BASE_NO \u00b2,IPO_FRAME #BASE}\nENDDAT\n",
    ),
    "krl_bas_digits": (
        "a.src",
        "DEF A()\nBAS(#BASE," + "9" * 5000 + ")\n" + KRL_BODY + "END\n",
    ),
}


def rewrite(tmp_path, name: str, text: str, *extra: str) -> subprocess.CompletedProcess:
    cell = write_cell(tmp_path, field="constant", step=500.0)
    program = tmp_path / name
    program.write_bytes(text.encode("utf-8"))
    out = tmp_path / "out"
    out.mkdir()
    argv = ["rewrite", str(program), "--cell", str(cell), "-o", str(out / name), *extra]
    return subprocess.run(
        [sys.executable, "-m", "accugrid.app.cli", *argv],
        capture_output=True,
        text=True,
        timeout=120,  # a hang guard, not a timing assertion
    )


@pytest.mark.parametrize("case", sorted(CASES))
def test_hostile_programs_end_in_success_or_a_located_error(tmp_path, case):
    name, text = CASES[case]
    proc = rewrite(tmp_path, name, text)
    assert proc.returncode in (0, 2), proc.stderr
    if proc.returncode == 2:
        (line,) = proc.stderr.splitlines()
        assert f"{tmp_path / name}:" in line


def test_a_gcode_file_with_a_bom_reads_like_one_without(tmp_path):
    body = "G21 G90\nG0 X1700 Y300 Z1000\n"
    for sub in ("plain", "bom"):
        (tmp_path / sub).mkdir()
    plain = rewrite(tmp_path / "plain", "a.ngc", body)
    with_bom = rewrite(tmp_path / "bom", "a.ngc", "\ufeff" + body)
    assert plain.returncode == with_bom.returncode == 0, with_bom.stderr


def test_a_non_finite_program_position_is_located(tmp_path):
    proc = rewrite(tmp_path, "a.ngc", "G21 G90\nG0 X10 Y10 Z5\nG1 X" + "9" * 320 + " Y1 Z1\n")
    assert proc.returncode == 2
    assert f"{tmp_path / 'a.ngc'}:3:" in proc.stderr


def test_a_krl_keyword_never_becomes_a_program_name(tmp_path):
    """Item 13: `plan --name END` wrote `DEF END( )`."""
    out = tmp_path / "plan"
    proc = subprocess.run(
        [sys.executable, "-m", "accugrid.app.cli", "plan", "grid", "--step", "500"]
        + ["--name", "END", "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    src = (out / "mend.src").read_text()
    assert "DEF MEND( )" in src and "DEF END(" not in src
