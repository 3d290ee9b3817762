"""Lines built as bytes by numpy (``codegen.linebytes``) and the hole lines the emitters build
with it, against lines written out the obvious way: one f-string per line, ``fixed`` per number,
``comment_text`` per label, following the documented layout of each line (the emitters'
module docstrings), on programs of generated numbers, labels and cell settings."""

from __future__ import annotations

import dataclasses
import os
from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from program_helpers import cell, cell_with

from accugrid.codegen.gcode import emit as gcode_emit
from accugrid.codegen.krl import emit as krl_emit
from accugrid.codegen.krl.configuration import configuration_words, read_configuration
from accugrid.codegen.linebytes import (
    SLOT,
    image_bytes,
    line_image,
    merge_images,
    number_cells,
    text_cells,
)
from accugrid.codegen.points import Points
from accugrid.codegen.program import STAGES, Program
from accugrid.infra.csvtable import Table
from accugrid.infra.textsafe import comment_text, fixed
from accugrid.kinematics.frames import abc_to_matrix

VALUES = st.one_of(
    st.floats(-5000, 5000, allow_nan=False),
    st.integers(-(10**7), 10**7).map(lambda k: k / 2000),  # halfway cases at 3 decimals
    st.sampled_from([0.0, -0.0, -0.0004, -0.0005, 0.0005, -1e-9, 1e-300, 999.9995, -99.99995]),
)
ASCII = st.text(st.characters(min_codepoint=1, max_codepoint=127), max_size=12)


# --- linebytes itself -------------------------------------------------------------------------


@given(st.lists(ASCII, min_size=1, max_size=6), st.data())
def test_line_image_is_the_template_with_each_row_s_texts_in_its_slots(constants, data):
    """Each row of the image, NULs dropped, is the constant text with the row's cells (texts
    and ``fixed`` numbers) in their slots; rows follow each other in order."""
    constants = [c.replace(SLOT, "") for c in constants]
    slots = len(constants) - 1
    n = data.draw(st.integers(1, 6))
    kinds = data.draw(st.lists(st.booleans(), min_size=slots, max_size=slots))
    texts, cells = [], []
    for is_number in kinds:
        if is_number:
            places = data.draw(st.integers(0, 6))
            values = data.draw(st.lists(VALUES, min_size=n, max_size=n))
            texts.append([fixed(v, places) for v in values])
            cells.append(number_cells(np.array(values), places))
        else:
            column = data.draw(st.lists(ASCII, min_size=n, max_size=n))
            column = [t.replace(SLOT, "") for t in column]
            texts.append(column)
            cells.append(text_cells(column))
    template = SLOT.join(constants)
    if not slots:
        with pytest.raises(ValueError):
            line_image(template, cells)
        return
    expected = "".join(
        constants[0] + "".join(texts[k][i] + constants[k + 1] for k in range(slots))
        for i in range(n)
    )
    assert image_bytes(line_image(template, cells)).decode("ascii") == expected


@given(st.lists(st.integers(0, 2), min_size=1, max_size=20))
def test_merged_images_keep_every_row_in_place(kinds):
    """Rows of several templates merged by their masks: the text of each item in item order."""
    kinds = np.array(kinds)
    templates = [f"a{SLOT};\n", f"bb{SLOT}{SLOT}\n", f"{SLOT}c\n"]
    masks, images = [], []
    for k, template in enumerate(templates):
        rows = np.flatnonzero(kinds == k)
        cells = [number_cells(rows, 0) for _ in range(template.count(SLOT))]
        masks.append(kinds == k)
        images.append(line_image(template, cells))
    expected = "".join(templates[k].replace(SLOT, str(i)) for i, k in enumerate(kinds.tolist()))
    assert image_bytes(merge_images(masks, images)).decode("ascii") == expected


def test_cells_of_nothing_and_of_empty_texts():
    assert text_cells([]).shape == (0, 1)
    assert text_cells(["", ""]).shape == (2, 1)
    assert image_bytes(line_image(f"<{SLOT}>", [text_cells(["", "x"])])) == b"<><x>"
    assert number_cells(np.zeros((2, 3)), 2).shape[:2] == (2, 3)
    with pytest.raises(UnicodeEncodeError):
        text_cells(["\u00e9"])
    with pytest.raises(ValueError):
        number_cells(np.array([1.0, np.nan]), 3)


# --- the emitters' hole lines -----------------------------------------------------------------


@st.composite
def programs(draw):
    """A program of 1-9 holes with generated numbers (not from IK: any values the lines must
    print), drill axes along the BASE Z or tilted, labels and cell settings."""
    n = draw(st.integers(1, 9))
    approach = draw(st.sampled_from([30.0, 12.5]))
    retract = draw(st.sampled_from([approach, 40.0, 0.5]))
    clearance, depth = 2.0, draw(st.sampled_from([6.5, 0.0004, 3.0]))
    c = cell_with(
        cell(),
        drilling={
            "approach_mm": approach,
            "retract_mm": retract,
            "clearance_mm": clearance,
            "dwell_s": draw(st.sampled_from([0.5, 0.0, 1.25])),
            "peck_mm": draw(st.sampled_from([0.0, 0.0, 1.5])),
            "approach_mm_s": draw(st.sampled_from([50.0, 33.3333])),
            "travel_mm_s": draw(st.sampled_from([500.0, 123.45678])),
        },
        gcode={
            "decimals": draw(st.integers(1, 6)),
            "canned_cycles": draw(st.booleans()),
        },
        krl={
            "decimals": draw(st.integers(1, 6)),
            "travel_motion": draw(st.sampled_from(["ptp", "lin"])),
            "clamp_output": draw(st.sampled_from([None, 2, 17])),
            "external_axes": tuple(draw(st.lists(VALUES, min_size=0, max_size=6))),
            "lines_per_file": draw(st.sampled_from([100000, 40, 25])),
        },
    )
    hole = np.array(draw(st.lists(st.tuples(VALUES, VALUES, VALUES), min_size=n, max_size=n)))
    tilt = np.array(
        draw(
            st.lists(st.sampled_from([0.0, 0.0, 1e-7, 0.3, -0.02]), min_size=n * 2, max_size=n * 2)
        )
    )
    axis = np.column_stack([tilt.reshape(n, 2), np.ones(n)])
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    offsets = np.array([approach, clearance, -depth, retract])
    positions = hole[:, None, :] + offsets[None, :, None] * axis[:, None, :]
    abc = np.array(draw(st.lists(st.tuples(VALUES, VALUES, VALUES), min_size=n, max_size=n)))
    status = np.array(draw(st.lists(st.integers(0, 7), min_size=4 * n, max_size=4 * n)))
    turn = np.array(draw(st.lists(st.integers(0, 63), min_size=4 * n, max_size=4 * n)))
    ids = draw(st.lists(st.text(max_size=70), min_size=n, max_size=n))
    diameter = np.array(
        draw(st.lists(st.sampled_from([np.nan, 4.83, 0.0005]), min_size=n, max_size=n))
    )
    feed = np.array(draw(st.lists(st.floats(0.01, 2000.0), min_size=n, max_size=n)))
    table = Table(os.fspath(c.path), ["x", "y", "z"], [["0", "0", "0"]] * n, list(range(2, n + 2)))
    points = Points(
        path=table.path,
        table=table,
        ids=ids,
        xyz=hole,
        abc=None,
        axis=axis,
        diameter=diameter,
        depth=np.full(n, depth),
        feed=feed,
    )
    return Program(
        cell=c,
        points=points,
        positions=positions,
        rotations=abc_to_matrix(abc),
        correction=np.zeros((n, 3)),
        feed_mm_s=feed,
        depth_mm=np.full(n, depth),
        configuration=read_configuration(np.stack([status, turn], axis=-1).reshape(n, 4, 2)),
        warnings=[],
        corrected=False,
    )


def gcode_hole_lines(program: Program) -> str:
    """Every hole's G-code lines, one f-string per line (``gcode.emit`` docstring)."""
    c, dr = program.cell, program.cell.drilling
    d = c.dialects["gcode"].decimals
    pos, abc = program.in_frame(c.dialects["gcode"].robot_T_program)
    approach = fixed(dr.approach_mm_s * 60.0, 1)
    out = []
    for i, label in enumerate(program.labels()):
        app, clr, bot, ret = ([fixed(v, d) for v in p] for p in pos[i])
        a, b, cc = (fixed(v, d) for v in abc[i])
        feed = fixed(program.feed_mm_s[i] * 60.0, 1)
        out.append(f"({comment_text('hole ' + label)})\n")
        out.append(f"G0 X{app[0]} Y{app[1]} Z{app[2]} A{a} B{b} C{cc}\n")
        z = pos[i, :, 2]
        same_xy = all(p[:2] == app[:2] for p in (clr, bot, ret))
        if c.dialects["gcode"].canned_cycles and same_xy and z[0] > z[1] > z[2] and z[3] > z[1]:
            if dr.peck_mm > 0:
                cycle = f"G83 X{bot[0]} Y{bot[1]} Z{bot[2]} R{clr[2]} Q{fixed(dr.peck_mm, d)}"
            elif dr.dwell_s > 0:
                cycle = f"G82 X{bot[0]} Y{bot[1]} Z{bot[2]} R{clr[2]} P{fixed(dr.dwell_s, 3)}"
            else:
                cycle = f"G81 X{bot[0]} Y{bot[1]} Z{bot[2]} R{clr[2]}"
            out.append(f"G98 {cycle} F{feed}\nG80\n")
            if ret[2] != app[2]:
                out.append(f"G0 Z{ret[2]}\n")
        else:
            out.append(f"G1 X{clr[0]} Y{clr[1]} Z{clr[2]} F{approach}\n")
            out.append(f"G1 X{bot[0]} Y{bot[1]} Z{bot[2]} F{feed}\n")
            if dr.dwell_s > 0:
                out.append(f"G4 P{fixed(dr.dwell_s, 3)}\n")
            out.append(f"G1 X{ret[0]} Y{ret[1]} Z{ret[2]} F{approach}\n")
    return "".join(out)


def krl_lines(program: Program) -> tuple[str, str]:
    """Every hole's .src lines and .dat lines, one f-string per line (``krl.emit`` docstring)."""
    c, dr = program.cell, program.cell.drilling
    d = c.dialects["krl"].decimals
    stages = STAGES[:3] if dr.retract_mm == dr.approach_mm else STAGES
    pos, abc = program.in_frame(c.robot_T_base)
    status, turn = np.moveaxis(configuration_words(program.configuration), -1, 0)
    ext = "".join(f",E{k + 1} {fixed(v, d)}" for k, v in enumerate(c.dialects["krl"].external_axes))
    approach = f"$VEL.CP = {fixed(dr.approach_mm_s / 1000.0, 4)}"
    src, dat = [], []
    for i, label in enumerate(program.labels()):
        n = i + 1
        src.append(f"; hole {comment_text(label)}")
        if c.dialects["krl"].travel_motion == "ptp":
            src.append(f"PTP XH{n}_APP C_PTP")
        else:
            src += [f"$VEL.CP = {fixed(dr.travel_mm_s / 1000.0, 4)}", f"LIN XH{n}_APP C_DIS"]
        src += [approach, f"LIN XH{n}_CLR"]
        if c.dialects["krl"].clamp_output is not None:
            src.append(f"$OUT_C[{c.dialects['krl'].clamp_output}] = TRUE ; clamp")
        src.append(f"$VEL.CP = {fixed(program.feed_mm_s[i] / 1000.0, 4)}")
        src += [f"LIN XH{n}_BOT", f"WAIT SEC {fixed(dr.dwell_s, 3)}"]
        if c.dialects["krl"].clamp_output is not None:
            src.append(f"$OUT[{c.dialects['krl'].clamp_output}] = FALSE ; unclamp")
        src += [approach, f"LIN XH{n}_{stages[-1] if len(stages) == 4 else 'APP'} C_DIS"]
        a, b, cc = (fixed(v, d) for v in abc[i])
        for stage in stages:
            k = STAGES.index(stage)
            x, y, z = (fixed(v, d) for v in pos[i, k])
            dat.append(
                f"DECL E6POS XH{n}_{stage}={{X {x},Y {y},Z {z},A {a},B {b},C {cc},"
                f"S {status[i, k]},T {turn[i, k]}{ext}}}"
            )
    return "".join(ln + "\r\n" for ln in src), "".join(ln + "\r\n" for ln in dat)


@pytest.fixture(scope="module")
def bare_templates(tmp_path_factory):
    """KRL templates that print only the lines of the holes (any modules split into)."""
    folder = tmp_path_factory.mktemp("bare") / "krl"
    folder.mkdir()
    (folder / "program.src.j2").write_text("{{ hole_lines -}}")
    (folder / "program.dat.j2").write_text("{{ position_lines -}}")
    return folder


@settings(max_examples=150, deadline=None)
@given(programs(), st.sampled_from([16384, 1, 2, 5]))
def test_gcode_hole_lines_are_the_lines_written_out(program, block):
    """The built-in template's hole lines, in blocks of any size, of holes of mixed kinds
    (canned with and without a retract move, explicit), every decimals, cycle and dwell."""
    with mock.patch.object(gcode_emit, "BLOCK", block):
        text = gcode_emit.render_gcode(program, ["h"])
    head = f"M3 S{fixed(program.cell.dialects['gcode'].spindle_rpm, 0)}\n"
    assert text.count(head) == 1
    assert text.split(head)[1] == gcode_hole_lines(program) + "M5\nM2\n"


@settings(max_examples=150, deadline=None)
@given(programs(), st.sampled_from([16384, 1, 3]))
def test_krl_hole_and_position_lines_are_the_lines_written_out(bare_templates, program, block):
    """The lines of the .src and .dat files, in blocks of any size and cut into modules, for 3 or
    4 stages, PTP or LIN travel, a clamp output, external axes and every decimals; and the same
    lines where the built-in templates print them."""
    src, dat = krl_lines(program)
    with mock.patch.object(krl_emit, "BLOCK", block):
        files = krl_emit.render_krl(program, ["h"], bare_templates)
        texts = {
            ext: [files[name] for name in files if name.endswith(ext)] for ext in (".src", ".dat")
        }
    assert "".join(texts[".src"]) == src and "".join(texts[".dat"]) == dat
    single = cell_with(program.cell, krl={"lines_per_file": 100000})
    files = krl_emit.render_krl(dataclasses.replace(program, cell=single), ["h"])
    name = single.dialects["krl"].name
    assert files[f"{name}.src"].split("; spindle on\r\n")[1].rsplit("WAIT SEC 0\r\n", 1)[0] == src
    uncorrected = "; h\r\n; grid none, model none: positions are not corrected\r\n"
    assert files[f"{name}.dat"].split(uncorrected)[1] == dat + "ENDDAT\r\n"


@pytest.fixture(scope="module")
def twice_templates(tmp_path_factory):
    """KRL templates that print the lines of the holes twice, between lines of their own."""
    folder = tmp_path_factory.mktemp("twice") / "krl"
    folder.mkdir()
    for ext, lines in ((".src", "hole_lines"), (".dat", "position_lines")):
        text = f"; {{{{ name }}}}\n{{{{ {lines} }}}}; again\n{{{{- {lines} -}}}}\n; end\n"
        (folder / f"program{ext}.j2").write_text(text)
    return folder


@settings(max_examples=60, deadline=None)
@given(programs(), st.integers(0, 6), st.integers(0, 6))
def test_krl_files_count_the_lines_they_have(twice_templates, program, lo, more):
    """The line count a KRL file is checked against program.lines_per_file with (from the lines
    per hole where the lines stay bytes) is the number of lines in its text: built-in templates
    and templates that print the lines twice."""
    hi = min(len(program), lo + more)
    lo = min(lo, hi)
    for templates in (None, twice_templates):
        records = krl_emit._Records(program)
        files = krl_emit._file_renderer(program.cell, ["h", "i"], records, templates)
        for ext in (".src", ".dat"):
            for role in ("single", "part"):
                pieces, count = files("P", role, lo, hi, ext)
                assert count == b"".join(pieces).count(b"\n")
                assert len(pieces) == (5 if templates == twice_templates else 3)  # lines as bytes
