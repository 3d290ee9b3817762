"""The interface every program dialect implements as a plug-in (``DialectPlugin``).

A dialect is one folder ``codegen/<name>/`` whose ``plugin.py`` holds ``PLUGIN``, an object with
the members below, light to import (its emitter and reader are imported when first used);
``codegen.dialects.DIALECTS`` names the module (the one registry). The jobs go through the
plug-in only: ``app.jobs.program`` writes a new program (``targets``, ``plan``, ``render``),
``codegen.rewrite.rewrite`` corrects an existing one (``placement``, ``scan``, ``splice``),
``codegen.cell`` reads its cell section (``section_keys``, ``read_section``), and
``app.jobs.plan`` writes a laser-tracker measurement program (``measurement``, a
capability a dialect may lack). Program text is latin-1 decoded bytes (one character per byte,
offsets are byte offsets), so a rewrite keeps any encoding and line ending.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from accugrid.infra.errors import InputError

if TYPE_CHECKING:
    import numpy as np

    from accugrid.codegen.cell_record import Cell
    from accugrid.codegen.cellfile import CellReader, SectionKeys
    from accugrid.codegen.plugin_types import Options, ProgramContext, Scan
    from accugrid.codegen.program import Program
    from accugrid.compensation.plans import Plan
    from accugrid.kinematics.configuration import Configuration
    from accugrid.kinematics.model import RobotModel

__all__ = [
    "EXTERNAL_AXES",
    "DialectFolder",
    "DialectOption",
    "DialectPlugin",
    "MeasureSettings",
    "MeasurementWriter",
    "DialectHelp",
    "Rendered",
]


@dataclass(frozen=True)
class DialectHelp:
    """What the command line says of a dialect. Its program command (``accugrid NAME``: a new
    program from a points CSV): ``summary`` (its line in ``accugrid --help``), ``description``
    (its ``--help`` text), ``output`` (the metavar and help of its ``-o``), ``report`` (the
    title of its HTML report); ``rewrite``: its paragraph in ``accugrid rewrite --help`` (what
    is corrected in its programs and what is left); ``measure``: its measurement program's
    paragraph in ``accugrid plan --help`` ("" when it writes none)."""

    summary: str
    description: str
    output: tuple[str, str]
    report: str
    rewrite: str
    measure: str = ""


@dataclass(frozen=True)
class DialectOption:
    """An option of ``accugrid rewrite`` read by the programs of the dialects that declare it
    (``DialectPlugin.options``) only: a switch (``metavar`` None: False unless given), a whole
    number within ``whole`` (low, high), or else a file, whose text (read as a program's) the
    job hands over and counts among its inputs. Its value reaches ``placement`` as
    ``ProgramContext.options[key]`` (None: not given)."""

    flag: str
    help: str
    metavar: str | None = None
    whole: tuple[int, int] | None = None

    @property
    def key(self) -> str:
        """The option's name in ``ProgramContext.options`` (``--config-dat``: ``config_dat``)."""
        return self.flag.lstrip("-").replace("-", "_")

    @property
    def file(self) -> bool:
        """Whether its value is a file."""
        return self.metavar is not None and self.whole is None


EXTERNAL_AXES = DialectOption(
    "--ignore-external-axes",
    "correct positions with external axes in use: the external axes move neither the robot "
    "nor the base",
)
"""The option of the dialects whose positions carry external axes."""


@dataclass
class Rendered:
    """The files of a new program: ``files`` (path -> text, or text in pieces fetched as it is
    written), ``main`` (among them, renamed last, in order) and ``stale`` (files of an earlier
    job of the same name to remove)."""

    files: Mapping[Path, object]
    main: list[Path] = field(default_factory=list)
    stale: list[Path] = field(default_factory=list)


@dataclass(frozen=True)
class MeasureSettings:
    """How a measurement program moves and waits: the tool and base numbers of the controller
    (base 0: the robot frame), the speed of the first joint move (% of the maximum), the linear
    speed between positions (m/s), the wait after each position: until digital input
    ``wait_input`` is on, else ``wait_sec`` s; ``ptp_only``: every move a joint move (poses that
    reorient), else a joint move to the first position and linear moves on."""

    tool: int
    base: int
    ptp_percent: float
    speed_m_s: float
    wait_sec: float
    wait_input: int | None
    ptp_only: bool = False


class MeasurementWriter(Protocol):
    """A dialect's laser-tracker measurement program (``DialectPlugin.measurement()``): the
    positions of a plan visited in order, waiting at each for the tracker.

    - ``name(requested)``: the program name the dialect writes for ``requested`` (made a name
      its controller accepts); ``targets(out, name)``: its files in folder ``out``;
    - ``motion(settings)``: how it moves and waits, as its header says ("first by PTP, then
      LIN, each followed by WAIT SEC 3.000"); ``listing``: where it lists its positions;
    - ``render(plan, configuration, name, header, settings, templates, out)``: its files
      (``Rendered``) visiting the rows of ``plan`` (``compensation.plans.Plan``: N positions mm
      in the robot frame, or ``settings.base``'s, KUKA A, B, C deg, ids) in the robot
      configurations (N,) ``configuration`` (``kinematics.configuration.Configuration``); numbers
      through ``infra.textsafe`` only.
    """

    listing: str

    def name(self, requested: str) -> str: ...

    def targets(self, out: Path, name: str) -> list[Path]: ...

    def motion(self, settings: MeasureSettings) -> str: ...

    def render(
        self,
        plan: Plan,
        configuration: Configuration,
        name: str,
        header: list[str],
        settings: MeasureSettings,
        templates: str | os.PathLike[str] | None,
        out: Path,
    ) -> Rendered: ...


class DialectPlugin(Protocol):
    """What a dialect provides.

    - ``name``: its ``codegen`` and ``templates`` folder and command; ``title``: what it is;
      ``suffixes``: the file suffixes it reads and writes (lower case, with the dot);
      ``pair``: the suffixes of a program given as two files (what runs, then its data, e.g.
      a KRL ``.src`` and ``.dat``), None when one file is a program; ``joints``: its
      configuration words need every pose's joint angles (``Program.joints``); ``exports``:
      the names of its ``emit`` module the library exports (``accugrid.render_krl``), resolved
      through the registry; ``help``: what the command line says of it
      (``DialectHelp``); ``options``: its own options of ``accugrid rewrite``
      (``DialectOption``); ``measures``: it writes measurement programs (``measurement()``);
      ``serves(robot)``: whether its programs drive ``robot`` (by the
      maker of the robot's controller, ``RobotModel.controller``; a robot that does not say is
      served).
    - ``section_keys()``, ``read_section(reader, robot_T_base)``: the YAML keys of its cell
      section and its record (``cell.dialects[name]``), InputError naming the key.
    - ``targets(cell, out)``: the files a new program into ``out`` writes that must not exist
      (without --force), refusing there an output it cannot name; ``plan(cell, holes, header,
      templates)``: run after reading and before the correction, refuses what it could not
      write (``header`` has as many lines as the job's); ``render(program, header, templates,
      out, plan)``: the files (``Rendered``), numbers through ``infra.textsafe`` only.
    - ``placement(cell, context)``: what places its positions in the robot frame (its record,
      from the cell and the command line's ``codegen.rewrite.ProgramContext``); ``scan(texts,
      opts, placement)``: the positions of existing programs (path -> text), as
      ``codegen.rewrite.Scan``; ``splice(scan, corrected, opts)``: the bytes of every program
      (path -> bytes) with the corrected robot-frame positions (M, 3) mm (NaN rows: not
      corrected) put back in place of the old numbers, nothing else changed, and the report
      rows of what it wrote.
    - ``add_header(text, lines)``: the program with the comment header inserted where its
      controller accepts comments.
    - ``configuration_words(configuration)``: the words (..., k) int its controller writes for
      robot configurations (...) (``kinematics.configuration.Configuration``: shoulder, elbow,
      wrist, each axis' quarter turn), e.g. KUKA [S, T], ABB [cf1, cf4, cf6, cfx];
      ``read_configuration(words)``: the configurations (...) written words (..., k) name (what
      they leave open taken as 0..90 deg), for the correction policy to hold a position against
      the configuration its grid was measured in. A dialect whose programs name no
      configuration (G-code) refuses both (InputError).
    - ``measurement()``: its laser-tracker measurement program (``MeasurementWriter``), a
      capability a dialect may lack: InputError then.
    - ``base_line(number, robot_T_base)``: the controller's line that sets base frame
      ``number`` to ``robot_T_base`` (4, 4) mm, for the user to enter (e.g. after
      ``accugrid fit-part``).
    - ``tool_line(number, flange_T_tool)``: the controller's line that sets tool ``number`` to
      ``flange_T_tool`` (4, 4) mm (e.g. after ``accugrid identify-tool``).
    """

    name: str
    title: str
    suffixes: tuple[str, ...]
    pair: tuple[str, str] | None
    joints: bool
    exports: tuple[str, ...]
    help: DialectHelp
    options: tuple[DialectOption, ...]
    measures: bool

    def serves(self, robot: RobotModel) -> bool: ...

    def section_keys(self) -> SectionKeys: ...

    def read_section(self, reader: CellReader, robot_T_base: np.ndarray) -> object: ...

    def targets(self, cell: Cell, out: Path) -> list[Path]: ...

    def plan(
        self,
        cell: Cell,
        holes: int,
        header: list[str],
        templates: str | os.PathLike[str] | None,
    ) -> object: ...

    def render(
        self,
        program: Program,
        header: list[str],
        templates: str | os.PathLike[str] | None,
        out: Path,
        plan: object,
    ) -> Rendered: ...

    def placement(self, cell: Cell, context: ProgramContext) -> object: ...

    def scan(self, texts: dict[str, str], opts: Options, placement: object) -> Scan: ...

    def splice(
        self, scan: Scan, corrected: np.ndarray, opts: Options
    ) -> dict[str, bytes | bytearray]: ...

    def add_header(self, text: str, lines: list[str]) -> str: ...

    def configuration_words(self, configuration: Configuration) -> np.ndarray: ...

    def read_configuration(self, words: np.ndarray) -> Configuration: ...

    def measurement(self) -> MeasurementWriter: ...

    def base_line(self, number: int, robot_T_base: np.ndarray) -> str: ...

    def tool_line(self, number: int, flange_T_tool: np.ndarray) -> str: ...


class DialectFolder:
    """The members of ``DialectPlugin`` a dialect folder gives by its modules' names, imported
    when first used: ``section.py`` (``KEYS``, ``read_section``), ``rewrite.py``
    (``scan_positions``, ``splice_positions``, ``add_header``), ``frames.py``
    (``base_line``, ``tool_line``) and ``configuration.py`` (``configuration_words``,
    ``read_configuration``; a folder without it names no configuration); the names in
    ``exports`` are its ``emit.py``'s (none by default); ``controllers``: the makers of the
    robot controllers its programs drive (``RobotModel.controller``, lower case; none: every
    robot). A plug-in derives from it and adds its name, suffixes, ``help``, ``targets``,
    ``plan``, ``render`` and ``placement`` (and ``measurement`` with ``measures`` when it writes
    measurement programs, ``options`` when it reads options of its own)."""

    name: str
    title: str
    pair: tuple[str, str] | None = None
    joints: bool = False
    exports: tuple[str, ...] = ()
    controllers: tuple[str, ...] = ()
    options: tuple[DialectOption, ...] = ()
    measures = False

    def serves(self, robot: RobotModel) -> bool:
        return not self.controllers or not robot.controller or robot.controller in self.controllers

    def _module(self, part: str):
        return importlib.import_module(f"accugrid.codegen.{self.name}.{part}")

    def section_keys(self) -> SectionKeys:
        return self._module("section").KEYS

    def read_section(self, reader: CellReader, robot_T_base: np.ndarray) -> object:
        return self._module("section").read_section(reader, robot_T_base)

    def plan(self, cell, holes, header, templates) -> object:
        return None  # nothing to refuse before the correction

    def scan(self, texts: dict[str, str], opts: Options, placement: object) -> Scan:
        return self._module("rewrite").scan_positions(texts, opts, placement)

    def splice(self, scan: Scan, corrected: np.ndarray, opts: Options) -> dict[str, bytes]:
        return self._module("rewrite").splice_positions(scan, corrected, opts)

    def add_header(self, text: str, lines: list[str]) -> str:
        return self._module("rewrite").add_header(text, lines)

    def base_line(self, number: int, robot_T_base: np.ndarray) -> str:
        return self._module("frames").base_line(number, robot_T_base)

    def tool_line(self, number: int, flange_T_tool: np.ndarray) -> str:
        return self._module("frames").tool_line(number, flange_T_tool)

    def configuration_words(self, configuration: Configuration) -> np.ndarray:
        return self._configuration().configuration_words(configuration)

    def read_configuration(self, words: np.ndarray) -> Configuration:
        return self._configuration().read_configuration(words)

    def _configuration(self):
        module = f"accugrid.codegen.{self.name}.configuration"
        try:
            return importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name != module:
                raise
        raise InputError(f"{self.title} programs name no robot configuration")

    def measurement(self) -> MeasurementWriter:
        raise InputError(f"accugrid writes no laser-tracker measurement program in {self.title}")
