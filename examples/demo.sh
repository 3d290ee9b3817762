#!/bin/sh
# The README's main job on the built-in defaults; `make demo` runs it with .venv/bin on PATH.
# Every step writes into out/ and may be re-run (--force).
set -eu
mkdir -p out
accugrid --version

# Drilling programs: simulated laser-tracker grid (the same command made examples/grid_200mm.csv)
# -> the example wing-panel holes -> corrected KUKA KRL and G-code.
accugrid simulate --robot kr210-paper --region 1200 2200 -600 600 1100 2100 --step 200 \
    --abc 0 90 0 --tool 0 0 250 0 0 0 --repeats 5 --noise-tracker 0.02 --noise-repeat 0.03 \
    --seed 1 -o out/grid_200mm.csv --force
cmp out/grid_200mm.csv examples/grid_200mm.csv
accugrid krl examples/wing_panel_points.csv --cell examples/cell.yaml --grid out/grid_200mm.csv \
    -o out/krl --force
accugrid gcode examples/wing_panel_points.csv --cell examples/cell.yaml --grid out/grid_200mm.csv \
    -o out/wing_panel.ngc --force

# The same holes for an ABB IRB 6700 (examples/cell_irb6700.yaml): a simulated grid of that
# robot (examples/irb6700_simulated.yaml: the nominal arm plus parameter errors), then the
# corrected RAPID module (examples/WING.mod is its output) and the pre-flight rewrite of a RAPID
# module (examples/cam_drill_rewritten.mod): its approach by Offs and its hole passed to the
# routine Drill cannot be placed, so --allow-partial writes them as they are, named in the header.
accugrid simulate --robot examples/irb6700_simulated.yaml --region 1600 2400 -600 600 1000 2000 \
    --step 200 --abc 0 90 0 --tool 0 0 250 0 0 0 --repeats 5 --noise-tracker 0.02 \
    --noise-repeat 0.03 --seed 1 -o out/grid_irb6700_200mm.csv --force
cmp out/grid_irb6700_200mm.csv examples/grid_irb6700_200mm.csv
accugrid rapid examples/wing_panel_points.csv --cell examples/cell_irb6700.yaml -o out/WING.mod \
    --force
accugrid rewrite examples/cam_drill.mod --cell examples/cell_irb6700.yaml --header \
    -o out/cam_drill.mod --report out/cam_drill_rapid_report.csv --force --allow-partial

# The same holes for a FANUC R-2000iC/165F (examples/cell_fanuc.yaml): a simulated grid of that
# robot (examples/r2000ic_simulated.yaml), then the corrected TP program (WING.ls).
accugrid simulate --robot examples/r2000ic_simulated.yaml --region 1600 1800 -400 400 400 1000 \
    --step 200 --abc 0 90 0 --tool 0 0 250 0 0 0 --repeats 5 --noise-tracker 0.02 \
    --noise-repeat 0.03 --seed 1 -o out/grid_r2000ic_200mm.csv --force
cmp out/grid_r2000ic_200mm.csv examples/grid_r2000ic_200mm.csv
accugrid fanuc examples/wing_panel_points.csv --cell examples/cell_fanuc.yaml -o out/WING.ls --force

# The grid model on its own: the same holes in the robot frame -> corrected points CSV
# (every input column, then x_cmd,y_cmd,z_cmd = P + e and ex,ey,ez = e, mm).
accugrid correct examples/wing_panel_robot.csv --grid out/grid_200mm.csv \
    -o out/wing_panel_corrected.csv --force

# Planning and choosing the step (seed Sec. 4-5), quick version: one centre, four steps.
# The tracker plan (CSV + KRL measurement program), then the study on the simulated robot:
# Table 4, the chosen step, Table 5, Fig. 12 and a report in out/study/.
accugrid plan experiment --centre D 1700 0 1500 --steps 20:380:120 --repeats 3 \
    -o out/plan --force
accugrid study --robot kr210-paper --centre D 1700 0 1500 --steps 20:380:120 --repeats 3 \
    --region 1500 1900 -200 200 1300 1700 --validation-points 50 -o out/study --force

# Pre-flight rewrite of programs a CAM system wrote (examples/cam_drill.*): only the numbers of
# the positions inside the grid change; the report lists every position with its status/reason.
# Their clearance moves (the home pose, outside the grid; a Z-only move before any X, Y) cannot be
# corrected: --allow-partial writes them left as they are, counted on stderr and in the report.
# The grid is the cell's (examples/grid_200mm.csv).
accugrid rewrite examples/cam_drill.src examples/cam_drill.dat --cell examples/cell.yaml \
    -o out/rewrite --report out/rewrite/cam_drill_krl_report.csv --force --allow-partial
accugrid rewrite examples/cam_drill.ngc --cell examples/cell.yaml \
    -o out/rewrite/cam_drill.ngc --report out/rewrite/cam_drill_ngc_report.csv --force \
    --allow-partial
diff examples/cam_drill.dat out/rewrite/cam_drill.dat || true

# The whole chain to the hole, on simulated measurements. The robot's base frame from tracker
# points (fit-frame: the mounting plane, the flange circle about A1, the flange holes at zero).
accugrid fit-frame --base-plane examples/tracker/base_plane.csv \
    --a1-circle examples/tracker/a1_circle.csv --flange-holes examples/tracker/flange_holes.csv \
    -o out/model/robot_frame.yaml --force

# Model-based calibration on kr210-realistic (seed Table 1 errors + compliance under gravity +
# reducer harmonics, none of which the user states): 60 D-optimal poses tilted up to 25 deg (CSV
# skeleton + KRL measurement program) -> a simulated tracker session at those poses, 3 repeats,
# with the joints the controller logs -> the calibrated model (DH errors, TCP and the joint-error
# terms plain `identify` chooses from the data by cross-validation) -> the wing panel holes
# corrected by the model plus a 27-vertex residual grid measured on the same robot.
accugrid plan identify --robot kr210-realistic --tool 0 0 250 0 0 0 --count 60 --tilt 25 \
    --name IDENT -o out/model --force
accugrid simulate --robot kr210-realistic --poses out/model/ident.csv --tool 0 0 250 0 0 0 \
    --repeats 3 --noise-tracker 0.02 --noise-repeat 0.03 --seed 2 \
    -o out/model/ident_measured.csv --force
accugrid identify out/model/ident_measured.csv --robot kr210-realistic --tool 0 0 250 0 0 0 \
    -o out/model/calibrated.yaml --force
# The drill on the calibrated arm: taught at 10 -5 320 mm, it really sits at 10.6 -5.4 320.5 mm
# with its axis 0.2 deg off; an SMR in a tip adapter (and one on the axis 60 mm behind) measured
# at 8 planned orientations, 3 repeats -> TOOL.yaml. The part: its 5 tooling balls measured 3
# times on a fixture that stands 1.8 mm and 0.1 deg off the cell's typed base -> PART.yaml.
# A cell with both files and the model -> the KRL program and its report, whose header and map
# carry each hole's 95 % bound (tool, part and model included).
accugrid plan tool --model out/model/calibrated.yaml --tool 10 -5 320 0 0 0 --axis-point \
    -o out/model/tool --force
accugrid simulate --robot kr210-realistic --poses out/model/tool/measure_tool.csv \
    --tool 10 -5 320 0 0 0 --smr 10.6 -5.4 320.5 --smr-axis 10.39 -5.4 260.5 --repeats 3 \
    --noise-tracker 0.02 --noise-repeat 0.03 --seed 5 -o out/model/tool_session.csv --force
accugrid identify-tool out/model/tool_session.csv --model out/model/calibrated.yaml \
    --tool 10 -5 320 0 0 0 --number 1 -o out/model/tool.yaml --force
accugrid simulate --datums examples/panel_nominal.csv \
    --part 1701.8 298.8 1000.9 -89.88 -0.08 90.05 --repeats 3 --noise-tracker 0.02 --seed 6 \
    -o out/model/datums.csv --force
accugrid fit-part out/model/datums.csv --nominal examples/panel_nominal.csv \
    -o out/model/part.yaml --force
sed -e 's|^grid: .*||' -e 's|^tool: {.*}|tool: {file: tool.yaml, number: 1}|' \
    -e 's|^base: {.*}|base: {file: part.yaml, number: 1}|' \
    -e 's|^correction:$|correction:\n  model: calibrated.yaml|' examples/cell.yaml \
    > out/model/cell_measured.yaml
accugrid krl examples/wing_panel_points.csv --cell out/model/cell_measured.yaml \
    -o out/model/krl_measured --report-html out/model/krl_measured.html --force
accugrid simulate --robot kr210-realistic --region 1200 2200 -500 500 1100 2100 --step 500 \
    --abc 0 90 0 --tool 0 0 250 0 0 0 --repeats 3 --noise-tracker 0.02 --noise-repeat 0.03 \
    --seed 3 -o out/model/residual_27.csv --force
accugrid correct examples/wing_panel_robot.csv --model out/model/calibrated.yaml \
    --grid out/model/residual_27.csv --method trilinear -o out/model/wing_panel_corrected.csv \
    --force
# The same model + residual grid in the drilling program: every hole corrected at its own
# orientation (the cell's tool and Status), header naming the model and its SHA-256.
accugrid krl examples/wing_panel_points.csv --cell examples/cell.yaml \
    --model out/model/calibrated.yaml --grid out/model/residual_27.csv -o out/model/krl --force

# Validation after correction: the corrected wing-panel holes measured on the simulated robot at
# their commands (3 repeats; x,y,z stay the targets) -> deviation statistics, ISO 9283 AP/RP,
# PASS/FAIL against +-0.3 mm per axis and the HTML report to sign.
accugrid simulate --robot kr210-realistic --poses out/model/wing_panel_corrected.csv \
    --tool 0 0 250 0 0 0 --repeats 3 --noise-tracker 0.02 --noise-repeat 0.03 --seed 4 \
    -o out/model/wing_panel_after.csv --force
accugrid validate out/model/wing_panel_after.csv --model out/model/calibrated.yaml \
    --grid out/model/residual_27.csv --report-html out/model/validation.html --force
