"""The cell file: robot, grid, tool, base frames, and one typed record per concern, as YAML.

Read with ``infra.yamlfile.load_yaml``; every key is validated and an error names the key
(``tool.z``) with its file line. Paths in the file are relative to the file. ``base`` is a frame
or a part file measured by ``accugrid fit-part`` (``base: {file: PART.yaml, number: N}``,
``codegen.part_file``); ``tool`` a frame or a tool file measured by ``accugrid identify-tool``
(``tool: {file: TOOL.yaml, number: N}``, ``codegen.tool_file``). Lengths mm, angles
deg, speeds mm/s, times s. The commented reference is ``examples/cell.yaml``.

``Cell`` (``codegen.cell_record``: the records the plug-ins receive) holds what the cell is made
of (robot, grid and model files, tool and base frames) and one frozen record per concern, each
built and validated in one place:

- ``cell.drilling`` (``DrillingSection``): the dialect-neutral process, from ``drilling:`` and
  ``speeds:`` (distances along the drill axis, dwell, peck, travel/approach/feed speeds);
- ``cell.configuration`` (``ConfigurationSection``): ``configuration:`` (Status/Turn to require,
  configuration changes, wrist-singularity margin, reference orientation);
- ``cell.correction`` (``compensation.settings.CorrectionSettings``): ``correction:`` (method,
  power, iterations); ``correction.model`` is ``cell.model_path``, beside ``cell.grid_path``;
- ``cell.tracker`` (``infra.csvtable.TableFormat`` or None): ``tracker:`` (columns, units,
  delimiter, decimal), how the cell's tracker software writes the grid file (the command line's
  ``--columns``/``--units``/... win over it);
- ``cell.dialects[name]`` for every dialect ``name`` of ``codegen.dialects.DIALECTS`` (the record
  of ``codegen/<name>/section.py``): what only that dialect reads. Each dialect's plug-in
  (``codegen.plugin``) declares the YAML keys it reads (``section_keys()``) and its reader
  (``read_section(reader, robot_T_base)``), so a new dialect brings its cell section in its own
  folder; a key may be read by several records (``program.decimals`` by every dialect), any key
  no record reads is an error.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from accugrid.codegen.cell_record import Cell, ConfigurationSection, DrillingSection
from accugrid.codegen.cellfile import DISTANCE_MAX_MM, FRAME_KEYS, CellReader, SectionKeys
from accugrid.codegen.dialects import DIALECTS, plugin_of
from accugrid.codegen.part_file import read_base
from accugrid.codegen.tool_file import read_tool
from accugrid.compensation.interpolation import METHODS
from accugrid.compensation.settings import TOOL_DISTANCE_MM, CorrectionSettings
from accugrid.infra.csvtable import FORMAT_KEYS, TableFormat, table_format_of
from accugrid.infra.errors import InputError
from accugrid.infra.yamlfile import load_yaml

__all__ = ["load_cell"]


# The YAML keys the neutral records read, by section (the dialects declare theirs)
_KEYS: SectionKeys = {
    "speeds": frozenset({"travel", "approach", "feed"}),
    "drilling": frozenset({"approach", "clearance", "retract", "depth", "dwell", "peck"}),
    "configuration": frozenset({"status", "turn", "allow_change", "singular_a5", "reference"}),
    "correction": frozenset({"method", "iterations", "power", "model", "tool_distance"}),
    "tracker": frozenset(FORMAT_KEYS),
}
_TOP_KEYS = {"robot", "grid", "tool", "base", "base_data", "tool_data"}
TOOL_NUMBER_MAX = 9999  # tool_data keys: KRL TOOL_DATA (1..32), G-code T numbers


def _sections(*declared: SectionKeys) -> dict[str, frozenset[str]]:
    """Every YAML section with the union of the keys its readers declare."""
    out: dict[str, frozenset[str]] = {}
    for keys in declared:
        for section, names in keys.items():
            out[section] = out.get(section, frozenset()) | names
    return out


def load_cell(path: str | os.PathLike[str]) -> Cell:
    """Read and validate a cell YAML file; InputError naming the key and line on any problem."""
    sections = {name: plugin_of(name) for name in DIALECTS}
    path = Path(path)
    doc = load_yaml(path)
    keys = _sections(_KEYS, *(plugin.section_keys() for plugin in sections.values()))
    r = CellReader(path, doc, _TOP_KEYS, keys)
    if not r.top:
        raise InputError("empty cell file", os.fspath(path))
    robot = r.top.get("robot")
    if not isinstance(robot, str) or not robot.strip():
        raise r.error("robot", "is required: a built-in robot name or a robot YAML path")
    if robot.endswith((".yaml", ".yml")):
        robot = os.fspath(path.parent / robot)
    grid_path = r.file_path("", "grid", "a file path")
    model_path = r.file_path("correction", "model", "a calibrated robot YAML path")
    tool_number, flange_T_tool = read_tool(r, robot, model_path)
    base_number, robot_T_base = read_base(r, robot, flange_T_tool)
    tool_data = _tool_data(r, tool_number, flange_T_tool)
    return Cell(
        path=path,
        robot_name=robot,
        grid_path=grid_path,
        model_path=model_path,
        tool_number=tool_number,
        flange_T_tool=flange_T_tool,
        base_number=base_number,
        robot_T_base=robot_T_base,
        base_data=_base_data(r, base_number, robot_T_base),
        drilling=_drilling(r),
        configuration=_configuration(r),
        correction=_correction(r),
        dialects={n: plugin.read_section(r, robot_T_base) for n, plugin in sections.items()},
        sha256=doc.sha256,
        tracker=_tracker(r),
        tool_data=tool_data,
    )


def _base_data(r: CellReader, base_number: int, robot_T_base: np.ndarray) -> dict:
    base_data = {base_number: robot_T_base}
    for n, frame in r.mapping(r.top.get("base_data"), "base_data", None).items():
        try:
            number = int(n)
        except ValueError:
            raise r.error(f"base_data.{n}", "key must be a BASE_DATA number") from None
        if not 1 <= number <= 32:
            raise r.error(f"base_data.{n}", "BASE_DATA number must be 1..32")
        if number == base_number:
            raise r.error(f"base_data.{n}", "repeats base.number; define it in base")
        base_data[number] = r.frame(frame, f"base_data.{n}", False)[1]
    return base_data


def _tool_data(r: CellReader, tool_number: int, flange_T_tool: np.ndarray) -> dict | None:
    """``tool_data: {n: {x, y, z, a, b, c[, name]}}``: number -> flange_T_tool with the cell's
    tool and tool 0 (the flange), None when the key is absent. ``name`` (the tool's name on its
    controller) is read by the dialects that name their tools."""
    data = r.top.get("tool_data")
    if data is None:
        return None
    tools = {0: np.eye(4), tool_number: flange_T_tool}  # 0: the flange
    for n, frame in r.mapping(data, "tool_data", None).items():
        key = f"tool_data.{n}"
        try:
            number = int(n)
        except ValueError:
            raise r.error(key, "key must be a tool number (TOOL_DATA[n], T n)") from None
        if not 1 <= number <= TOOL_NUMBER_MAX:
            raise r.error(key, f"tool number must be 1..{TOOL_NUMBER_MAX}")
        if number == tool_number:
            raise r.error(key, "repeats tool.number; define it in tool")
        d = r.mapping(frame, key, {*FRAME_KEYS, "name"})
        d.pop("name", None)
        tools[number] = r.frame(d, key, False)[1]
    return tools


def _drilling(r: CellReader) -> DrillingSection:
    approach = r.number("drilling", "approach", 30.0, 0.0, DISTANCE_MAX_MM, True)
    clearance = r.number("drilling", "clearance", 2.0, 0.0, DISTANCE_MAX_MM)
    if clearance >= approach:
        raise r.error(
            "drilling.clearance",
            f"must be smaller than drilling.approach ({approach:g} mm), got {clearance:g}",
        )
    return DrillingSection(
        approach_mm=approach,
        clearance_mm=clearance,
        retract_mm=r.number("drilling", "retract", approach, 0.0, DISTANCE_MAX_MM, True),
        depth_mm=r.number("drilling", "depth", 10.0, 0.0, DISTANCE_MAX_MM, True),
        dwell_s=r.number("drilling", "dwell", 0.5, 0.0, 60.0),
        peck_mm=r.number("drilling", "peck", 0.0, 0.0, DISTANCE_MAX_MM),
        travel_mm_s=r.number("speeds", "travel", 500.0, 0.0, 2000.0, True),
        approach_mm_s=r.number("speeds", "approach", 50.0, 0.0, 2000.0, True),
        feed_mm_s=r.number("speeds", "feed", 5.0, 0.0, 2000.0, True),
    )


def _configuration(r: CellReader) -> ConfigurationSection:
    key = "configuration"
    return ConfigurationSection(
        status=r.integer(key, "status", None, 0, 7, optional=True),
        turn=r.integer(key, "turn", None, 0, 63, optional=True),
        allow_change=r.boolean(key, "allow_change", False),
        singular_a5_deg=r.number(key, "singular_a5", 5.0, 0.0, 90.0),
        reference_abc=r.abc(r.value(key, "reference"), f"{key}.reference", (0.0, 90.0, 0.0)),
    )


def _tracker(r: CellReader) -> TableFormat | None:
    """``tracker:``: how the cell's tracker software writes the grid file (the keys of a
    format file: columns, units, delimiter, decimal); None when the section is absent."""
    if not r.section("tracker"):
        return None
    return table_format_of(r.doc, "tracker")


def _correction(r: CellReader) -> CorrectionSettings:
    return CorrectionSettings(
        method=r.choice("correction", "method", "idw", METHODS),
        iterations=r.integer("correction", "iterations", 1, 1, 10),
        power=r.number("correction", "power", 1.0, 0.0, 10.0, True),
        tool_distance_mm=r.number(
            "correction", "tool_distance", TOOL_DISTANCE_MM, 0.0, DISTANCE_MAX_MM
        ),
    )
