"""KUKA KRL as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``. Light to import
(the registry reads its name and suffixes): the emitter and the reader are imported when first
used."""

from __future__ import annotations

import re

from accugrid.codegen.plugin import (
    EXTERNAL_AXES,
    DialectFolder,
    DialectHelp,
    DialectOption,
    Rendered,
)

__all__ = ["PLUGIN", "KrlPlugin"]


HELP = DialectHelp(
    summary="corrected KUKA KRL drilling program (.src/.dat) from a points CSV",
    description="""Write a corrected KUKA KRL drilling program (.src/.dat) from a points CSV.

Each hole: travel (PTP ... C_PTP, or LIN ... C_DIS) to the approach point on the drill axis, LIN at
approach speed to the clearance point, LIN at the feed to the depth, WAIT SEC dwell, LIN back to
the retract point. Positions are E6POS in the .dat, in the cell's BASE frame (BASE_DATA[n]), with
the KUKA Status and Turn from the robot model's IK. Every hole is corrected with the grid (its
point mapped to the robot frame, P' = P + e(P), and the same e applied to all its positions).
Long jobs are split into NAME_001, NAME_002, ... called from NAME.src (program.lines_per_file).

Units: mm, deg, mm/s in the inputs; $VEL.CP in m/s in the program. Exit 2 on bad input, with
nothing written.
""",
    output=("DIR", "folder for NAME.src and NAME.dat"),
    report="KUKA KRL drilling program",
    rewrite="""\
KRL: PROGRAM is a .src or .dat; give the .dat beside it as the second argument. A stored position
is corrected only if a motion uses it (never a frame given to $TOOL/$BASE/$LOAD, an operand of
':' or a CONST) and takes the base of the motions that use it ($BASE = BASE_DATA[n],
BAS(#BASE,n), FDAT BASE_NO); BASE_DATA values come from --config-dat or the cell file (base,
base_data); base 0 is the robot frame. Where a routine starts without setting $BASE, and for the
POS/E6POS of a .dat given alone, --base N says which BASE_DATA they are in (a position's own FDAT
wins over it). Left untouched: frame arithmetic ':', a base from a variable or a call, EK(),
AXIS/E6AXIS targets, $POS_ACT, and external axes in use (non-zero E1..E6) unless
--ignore-external-axes. A position's Status is its S, else the last S written before it
in its file, else the cell's configuration.status. The files of a .src/.dat pair keep their
names, which KRL needs to match DEF/DEFDAT.
""",
    measure="""\
KUKA KRL: NAME.src/NAME.dat, LIN at the fixed orientation (first motion a complete PTP), waiting
at each row for the tracker: WAIT SEC (--wait-sec) or WAIT FOR $IN[n] (--wait-input); $VEL.CP
from --speed, TOOL_DATA[--tool-number]. Positions are in the robot frame ($BASE = $NULLFRAME,
i.e. $ROBROOT = $WORLD) unless --base-number names a BASE_DATA that equals the robot frame; the
IK gives each E6POS its T.
""",
)
OPTIONS = (
    DialectOption("--config-dat", "$config.dat with BASE_DATA[n] values", metavar="$config.dat"),
    DialectOption(
        "--base",
        "BASE_DATA number in effect where the program does not set one (a lone .dat, or the "
        "start of a routine); 0 = robot frame",
        metavar="N",
        whole=(0, 32),
    ),
    DialectOption(
        "--trust-calls",
        "assume no call changes $BASE or $TOOL (without it, a call keeps them when its routine "
        "is in the given files and changes neither)",
    ),
    EXTERNAL_AXES,
)


class KrlPlugin(DialectFolder):
    """KUKA KRL: a program is a ``.src`` (what runs) and its ``.dat``; ``.sub`` for submit
    programs. A new program is ``NAME.src``/``NAME.dat`` in a folder, split into modules
    ``NAME_001``.. when long. Members as ``DialectPlugin`` says."""

    name = "krl"
    title = "KUKA KRL"
    help = HELP
    suffixes = (".src", ".dat", ".sub")
    controllers = ("kuka",)  # the robots it drives
    pair = (".src", ".dat")
    exports = ("render_krl",)
    options = OPTIONS
    measures = True

    def targets(self, cell, out):
        name = cell.dialects[self.name].name
        return [out / f"{name}{suffix}" for suffix in reversed(self.pair)]  # .src renamed last

    def plan(self, cell, holes, header, templates):
        from accugrid.codegen.krl.emit import module_split

        return module_split(cell, holes, header, templates)

    def render(self, program, header, templates, out, plan):
        """The modules of an earlier job of this name are stale; ``NAME.src`` is written last
        (``NAME.dat`` before it)."""
        from accugrid.codegen.krl.emit import render_krl

        name = program.cell.dialects[self.name].name
        files = render_krl(program, header, templates, plan)
        module = re.compile(rf"{re.escape(name)}_[0-9]{{3,}}\.(src|dat)")
        stale = [p for p in out.glob(f"{name}_*") if module.fullmatch(p.name)]
        return Rendered(files.at(out), self.targets(program.cell, out), stale)

    def placement(self, cell, context):
        from accugrid.codegen.krl.rewrite import KrlPlacement

        return KrlPlacement(
            base_data=cell.base_data,
            base=context["base"],
            trust_calls=bool(context["trust_calls"]),
            ignore_external_axes=bool(context["ignore_external_axes"]),
            config_dat=context["config_dat"],
        )

    def measurement(self):
        """The laser-tracker measurement program (``krl.emit.KrlMeasurement``)."""
        from accugrid.codegen.krl.emit import MEASUREMENT

        return MEASUREMENT


PLUGIN = KrlPlugin()
