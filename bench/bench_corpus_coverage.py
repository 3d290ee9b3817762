"""Corpus coverage: `accugrid rewrite` over every KRL, G-code and RAPID program in
../shared/realworld, each with the cell and options the realworld tests use
(``tests/rewrite_helpers.REALWORLD_REWRITES``, ``REALWORLD_RAPID``), once with a grid and
once with a calibrated model (``out/model/calibrated.yaml`` from ``make demo``; skipped when it
is missing; RAPID cells are an ABB arm, so grid only). Per dialect: the motion positions (those
a job must correct: what a motion commands, a lone .dat's POS/E6POS with --base), how many are
corrected by default (``--allow-partial`` only so that the rest is counted) and the reasons
left, with counts (numbers and names in a reason shown as ``#``). "KRL, no options" is every KRL
program (each set of files once) rewritten without ``--base``/``--trust-calls``/
``--ignore-external-axes``: what a user gets who states nothing the program does not.

Run: ``make bench ARGS=corpus`` (or ``.venv/bin/python bench/bench_corpus_coverage.py``).
"""

from __future__ import annotations

import re
import sys
import tempfile
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from rewrite_helpers import (  # noqa: E402
    REALWORLD_BASE_DATA,
    REALWORLD_RAPID,
    REALWORLD_REWRITES,
    write_cell,
    write_rapid_cell,
)

from accugrid.app.jobs.rewrite import RewriteRequest, rewrite_job  # noqa: E402
from accugrid.codegen.rewrite import CORRECTED  # noqa: E402
from accugrid.compensation.policy import CORRECTED as POLICY_CORRECTED  # noqa: E402
from accugrid.compensation.policy import PolicyRequest  # noqa: E402
from bench.timing import table  # noqa: E402

REALWORLD = ROOT.parent / "shared" / "realworld"
MODEL = ROOT / "out" / "model" / "calibrated.yaml"
_FLAGS = ("--trust-calls", "--ignore-external-axes")  # the dialects' own switches
# what varies inside one kind of reason: numbers, quoted text, names with digits or brackets
_VARYING = re.compile(r"'[^']*'|\"[^\"]*\"|\b\w*\d[\w.]*|\w+\[[^\]]*\](?:\.\w+)*")


def _request(cell: Path, inputs: list[Path], options: list[str], out: Path, model) -> dict:
    """The RewriteRequest fields of one case (the realworld tests' command-line options)."""
    fields = {"cell": str(cell), "policy": PolicyRequest(allow_partial=True), "model": model}
    own = {}  # the dialects' own options (``RewriteRequest.options``)
    it = iter(options)
    for option in it:
        key = option.lstrip("-").replace("-", "_")
        if option in _FLAGS:
            own[key] = True
        elif option == "--decimals":
            fields[key] = int(next(it))
        else:
            own[key] = int(next(it))
    fields["options"] = own
    fields["outputs"] = {p: out / p.name for p in inputs}
    return fields


def _cases(folder: Path):
    """(dialect, inputs, options, cell) of every program in the corpus."""
    plain = set()
    for case, (names, options) in sorted(REALWORLD_REWRITES.items()):
        kind = "KRL" if names[0].startswith("krl/") else "G-code"
        yield case, kind, [REALWORLD / n for n in names], options, "grid"
        if kind == "KRL" and tuple(names) not in plain:
            plain.add(tuple(names))
            yield case, "KRL, no options", [REALWORLD / n for n in names], [], "grid"
    for name, (tool, wobj) in sorted(REALWORLD_RAPID.items()):
        yield name, "RAPID", [REALWORLD / "rapid" / name], [], (tool, wobj)


def _model_cell(grid_cell: Path) -> Path:
    """The grid cell without its grid, corrected by the calibrated model."""
    lines = [ln for ln in grid_cell.read_text().splitlines() if not ln.startswith("grid:")]
    cell = grid_cell.with_name("cell_model.yaml")
    cell.write_text("\n".join(lines + [f"correction: {{model: {MODEL}}}"]) + "\n")
    return cell


def coverage() -> dict[tuple[str, str], tuple[int, int, Counter]]:
    """(dialect, correction) -> (motion positions, corrected, reasons of the rest by count)."""
    out: dict[tuple[str, str], tuple[int, int, Counter]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "krl").mkdir()
        grid_cell = write_cell(folder / "krl", base_data=REALWORLD_BASE_DATA)
        model_cell = _model_cell(grid_cell) if MODEL.exists() else None
        for n, (_, kind, inputs, options, how) in enumerate(_cases(folder)):
            if how == "grid":
                cells = [("grid", grid_cell)] + ([("model", model_cell)] if model_cell else [])
            else:
                sub = folder / f"rapid{n}"
                sub.mkdir()
                cells = [("grid", write_rapid_cell(sub, *how))]
            for correction, cell in cells:
                job = rewrite_job(RewriteRequest(**_request(cell, inputs, options, folder, None)))
                rows = job.result.rows
                total, done, reasons = out.get((kind, correction), (0, 0, Counter()))
                # the positions the job's rule counts: corrected, refused by the policy, or
                # commanded by a motion and not placed (``partial_check`` codes those)
                done_rows = rows.status == CORRECTED
                motion = done_rows | (rows.code != POLICY_CORRECTED)
                total += int(motion.sum())
                done += int(done_rows.sum())
                for i in (motion & ~done_rows).nonzero()[0].tolist():
                    reasons[_VARYING.sub("#", rows.reason[i])[:110]] += 1
                out[kind, correction] = (total, done, reasons)
    return out


def main() -> None:
    found = coverage()
    summary = []
    for (kind, correction), (total, done, _) in found.items():
        share = f"{100 * done / total:.1f} %" if total else "-"
        summary.append((kind, correction, total, done, share))
    print(table(summary, ("dialect", "correction", "motion positions", "corrected", "share")))
    if not MODEL.exists():
        print(f"(no {MODEL.relative_to(ROOT)}: run `make demo` for the calibrated model)")
    for (kind, correction), (_, _, reasons) in found.items():
        if reasons:
            print(f"\n{kind}, {correction}: reasons left")
            print(table(reasons.most_common(), ("reason", "positions")))


if __name__ == "__main__":
    main()
