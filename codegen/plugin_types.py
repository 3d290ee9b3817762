"""The records the plug-in interface (``codegen.plugin``) passes between the rewrite and a dialect:
``Options`` (how to rewrite), ``ProgramContext`` (what the command line says of a program's
frames), ``Rows`` / ``Row`` (the report rows) and ``Scan`` (the positions a dialect's reader
found). Plain records over the correction policy (``compensation``): they import nothing else of
``codegen``, so the contract, the rewrite and the dialects import them one way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from copy import copy
from dataclasses import dataclass, field
from itertools import chain
from typing import TYPE_CHECKING

import numpy as np

from accugrid.codegen.program_text import MAX_BYTES
from accugrid.compensation.policy import Policy
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM, CorrectionSettings

if TYPE_CHECKING:
    from accugrid.compensation import GridModel
    from accugrid.kinematics.robot import Robot

__all__ = [
    "CORRECTED",
    "OUTSIDE",
    "SKIPPED",
    "STATUSES",
    "Options",
    "ProgramContext",
    "Row",
    "Rows",
    "Scan",
]

NAN3 = (math.nan, math.nan, math.nan)


@dataclass
class Options:
    """How to rewrite, whatever the dialect (what places a dialect's positions in the robot frame
    is its own record: ``DialectPlugin.placement``)."""

    model: GridModel | None  # the grid (the residual grid with a model; None: the model alone)
    correction: CorrectionSettings = CorrectionSettings()
    decimals: int | None = None  # None: the file's precision (see ``precision``)
    allow_partial: bool = False  # write although the policy leaves positions uncorrected
    tool_number: int | None = None  # the cell's TOOL_DATA number (the TCP the grid holds for)
    flange_T_tool: np.ndarray | None = None  # the cell's tool (None: not given, not checked)
    tool_data: dict[int, np.ndarray] | None = None  # tool number -> flange_T_tool (the cell's
    # tool_data with its tool; None: the cell's tool alone, every position corrected with it)
    max_bytes: int = MAX_BYTES
    tolerance_mm: float = DEFAULT_TOLERANCE_MM  # warn when rounding leaves more than a tenth
    policy: Policy | None = None  # decides every position (None: the grid's, default limits)
    model_file: str | None = None  # the calibrated robot YAML (header)
    reference_abc: tuple[float, float, float] | None = None  # robot-frame A,B,C deg the model
    # assumes where a position has none (3-axis G-code): the cell's configuration.reference

    def __post_init__(self) -> None:
        if self.policy is None:
            self.policy = Policy(self.correction, self.model)

    def other_tool(self, tool: int) -> str:
        """Without ``tool_data``: why the positions a program commands with tool number ``tool``
        (-1: none selected, the cell's) are not corrected, "" when it is the cell's tool."""
        if tool < 0 or self.tool_number is None or tool == self.tool_number:
            return ""
        return (
            f"tool {tool} is not the cell's tool {self.tool_number}, which the grid holds for "
            "(declare it in the cell file's tool_data)"
        )

    @property
    def calibrated(self) -> Robot | None:
        """The calibrated model the policy uses, None for the grid alone."""
        return self.policy.calibrated


@dataclass(frozen=True)
class ProgramContext:
    """What the command line says about a program's frames that its own text does not: the
    values of its dialect's own options (``DialectPlugin.options``) by key, a file option's as
    the file's text; a key not given is None (a switch: False). Each dialect's ``placement``
    reads its own."""

    options: Mapping[str, object] = field(default_factory=dict)

    def __getitem__(self, key: str) -> object:
        return self.options.get(key)


@dataclass(slots=True)
class Row:
    """One position (or unresolved motion target) in the report."""

    file: str
    line: int
    name: str
    status: str  # "corrected", "outside", "skipped"
    reason: str = ""
    old: tuple[float, float, float] = NAN3  # position as written (program/base frame, mm)
    new: tuple[float, float, float] = NAN3  # as rewritten (corrected rows)
    residual_mm: float = math.nan
    rounding_mm: float = math.nan  # how far rounding to the written decimals leaves it (mm)


STATUSES = ("skipped", "corrected", "outside")
SKIPPED, CORRECTED, OUTSIDE = 0, 1, 2


class Rows:
    """The report rows (N), column by column: ``files`` (distinct paths) and ``file`` (N,) index
    into it, ``line`` (N,) int, ``name`` and ``reason`` lists of str, ``status`` (N,) codes of
    ``STATUSES``, ``old`` and ``new`` (N, 3) mm (NaN: none), ``residual_mm`` and ``rounding_mm``
    (N,) mm, ``code`` (N,) the policy's reason code of a position it did not correct
    (``compensation.policy.REASONS``, 0: none), ``commanded`` (N,) bool: a Cartesian position a
    motion of the program commands (set by the dialect's reader; ``partial_check`` counts those
    left uncorrected), ``tool`` (N,) the tool number each position is commanded with (-1: the
    cell's tool; set by the dialect's reader with ``Options.tool_data``). Iterating gives
    ``Row`` objects (copies)."""

    def __init__(
        self,
        files: list[str],
        file: np.ndarray,
        line: np.ndarray,
        name: list[str],
        reason: list[str],
        old: np.ndarray,
    ) -> None:
        n = len(line)
        self.files = files
        self.file = np.asarray(file, dtype=np.int64).reshape(n)
        self.line = np.asarray(line, dtype=np.int64).reshape(n)
        self.name = name
        self.reason = reason
        self.status = np.zeros(n, np.int8)
        self.code = np.zeros(n, np.int8)
        self.commanded = np.zeros(n, bool)
        self.tool = np.full(n, -1, np.int64)
        self.old = np.asarray(old, dtype=float).reshape(n, 3)
        self.new = np.full((n, 3), math.nan)
        self.residual_mm = np.full(n, math.nan)
        self.rounding_mm = np.full(n, math.nan)

    @classmethod
    def concat(cls, parts: list[Rows]) -> Rows:
        """The rows of each part, in order (the arrays of the one part with rows, not copies,
        when the others have none: a part is not used after it is concatenated)."""
        files = sorted({f for p in parts for f in p.files})
        index = {f: i for i, f in enumerate(files)}
        full = [p for p in parts if len(p)]
        if len(full) == 1:
            (one,) = full
            out = copy(one)
            out.files = files
            out.file = np.array([index[f] for f in one.files], np.int64)[one.file]
            return out
        out = cls(
            files,
            np.concatenate(
                [np.array([index[f] for f in p.files], np.int64)[p.file] for p in parts]
                or [np.zeros(0, np.int64)]
            ),
            np.concatenate([p.line for p in parts] or [np.zeros(0, np.int64)]),
            list(chain.from_iterable(p.name for p in parts)),
            list(chain.from_iterable(p.reason for p in parts)),
            np.concatenate([p.old for p in parts] or [np.zeros((0, 3))]),
        )
        for key in ("status", "code", "commanded", "tool", "new", "residual_mm", "rounding_mm"):
            setattr(out, key, np.concatenate([getattr(p, key) for p in parts] or [out.status]))
        return out

    def __len__(self) -> int:
        return len(self.line)

    def __getitem__(self, i: int) -> Row:
        return Row(
            self.files[self.file[i]],
            int(self.line[i]),
            self.name[i],
            STATUSES[self.status[i]],
            self.reason[i],
            tuple(self.old[i].tolist()),
            tuple(self.new[i].tolist()),
            float(self.residual_mm[i]),
            float(self.rounding_mm[i]),
        )

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def where(self, i: int) -> tuple[str, int]:
        """(file, line) of row ``i``, for an error message."""
        return self.files[self.file[i]], int(self.line[i])

    def count(self, status: int) -> int:
        return int(np.count_nonzero(self.status == status))


@dataclass
class Scan:
    """The positions a dialect's ``scan`` found in the programs of a rewrite. ``rows``: the
    report rows the job rule judges (``partial_check``); ``at`` (M,): the rows of the positions
    placed in the robot frame, ``robot`` (M, 3) mm where they are (robot frame), ``rotations``
    (M, 3, 3) their orientations (robot frame; NaN rows or None: none), ``code`` (M,) the
    configuration code their own words name (``Configuration.code``; -1 or None: the job's);
    ``others``: rows reported after them that are no position to correct (data no motion uses);
    ``state``: what the dialect's ``splice`` needs."""

    rows: Rows
    at: np.ndarray
    robot: np.ndarray
    rotations: np.ndarray | None = None
    code: np.ndarray | None = None
    others: Rows | None = None
    state: object = None
