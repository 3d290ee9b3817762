"""Building a GridModel from measurement files: averaging, grid detection, clear errors."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from accugrid.compensation import GridModel
from accugrid.infra.errors import InputError

HEADER = "id,x,y,z,a,b,c,x_meas,y_meas,z_meas"


def grid_rows(counts=(3, 2, 2), step=(200.0, 150.0, 100.0), origin=(1200.0, -600.0, 1100.0)):
    """Commanded vertices (N, 3) of a regular grid, x slowest."""
    axes = [origin[a] + step[a] * np.arange(counts[a]) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def csv_text(commanded, measured, abc=(0.0, 90.0, 0.0)):
    lines = [HEADER]
    for i, (p, m) in enumerate(zip(commanded, measured, strict=True)):
        nums = [*p, *abc, *m]
        lines.append(f"P{i}," + ",".join(f"{v:.4f}" for v in nums))
    return "\n".join(lines) + "\n"


def write(tmp_path, text, name="meas.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_repeats_are_averaged_and_the_grid_is_reported(tmp_path):
    points = grid_rows()
    rng = np.random.default_rng(0)
    true_error = rng.normal(scale=0.5, size=points.shape)
    commanded = np.repeat(points, 5, axis=0)
    measured = commanded - np.repeat(true_error, 5, axis=0) + rng.normal(0, 0.02, commanded.shape)
    path = write(tmp_path, "# tracker session\n" + csv_text(commanded, measured))
    model = GridModel.from_measurements(path)
    np.testing.assert_allclose(model.origin, [1200, -600, 1100])
    np.testing.assert_allclose(model.step, [200, 150, 100])
    np.testing.assert_array_equal(model.counts, [3, 2, 2])
    expected = (commanded - np.round(measured, 4)).reshape(-1, 5, 3).mean(axis=1)
    np.testing.assert_allclose(model.errors.reshape(-1, 3), expected, atol=1e-9)
    np.testing.assert_allclose(model.orientation_abc, [0, 90, 0])
    assert model.source_sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert (model.repeats == 5).all()
    text = model.describe()
    assert "vertices 3x2x2 = 12" in text and "repeats    5..5" in text


@given(
    st.randoms(use_true_random=False),
    st.integers(1, 3),
    st.tuples(*[st.integers(2, 4)] * 3),
    st.tuples(*[st.floats(5.0, 500.0)] * 3),
    st.tuples(*[st.floats(-3000.0, 3000.0)] * 3),
)
def test_any_regular_grid_is_found_whatever_the_row_order(rnd, repeats, counts, step, origin):
    points = grid_rows(counts, step, origin)
    error = np.arange(points.size, dtype=float).reshape(points.shape) * 0.01
    commanded = np.repeat(points, repeats, axis=0)
    # commanded coordinates jitter by up to 2e-4 mm (a controller's rounding): still one vertex
    jitter = np.array([rnd.uniform(-2e-4, 2e-4) for _ in range(commanded.size)])
    commanded = commanded + jitter.reshape(commanded.shape)
    measured = commanded - np.repeat(error, repeats, axis=0)
    order = list(range(len(commanded)))
    rnd.shuffle(order)
    model = GridModel.from_measurements((commanded[order], measured[order]))
    np.testing.assert_array_equal(model.counts, counts)
    # a level's centre is off by at most the jitter, so a step between two levels by twice it
    np.testing.assert_allclose(model.step, step, atol=4e-4)
    np.testing.assert_allclose(model.origin, origin, atol=2e-4)
    np.testing.assert_allclose(model.errors.reshape(-1, 3), error, atol=1e-9)
    assert model.orientation_abc is None and model.source_sha256 is None


def test_missing_vertices_are_counted_and_listed(tmp_path):
    points = grid_rows()
    keep = np.ones(len(points), bool)
    keep[[3, 7]] = False
    path = write(tmp_path, csv_text(points[keep], points[keep]))
    with pytest.raises(InputError, match=r"2 of 12 grid vertices not measured") as err:
        GridModel.from_measurements(path)
    message = str(err.value)
    assert str(path) in message
    assert "(1200.0000, -450.0000, 1200.0000)" in message  # vertex 3 = (0, 1, 1)
    assert "stray" not in message


def test_uneven_spacing_names_the_axis_and_values(tmp_path):
    points = grid_rows((2, 2, 3))
    points[points[:, 2] == 1300.0, 2] = 1250.0
    with pytest.raises(InputError, match=r"uneven grid spacing along z: levels 1100.0000, "):
        GridModel.from_measurements(write(tmp_path, csv_text(points, points)))


def test_a_stray_point_is_pointed_out(tmp_path):
    # on an even spacing: 1200, 1300, 1400 look like a 3-level grid with a sparse plane
    points = np.vstack([grid_rows((2, 2, 2)), [[1300.0, -600.0, 1100.0]]])
    path = write(tmp_path, csv_text(points, points))
    with pytest.raises(InputError, match=r"x=1300.0000 has 1 of 4 vertices \(line 10\)"):
        GridModel.from_measurements(path)
    # off the spacing: 1200, 1250, 1400
    points[-1, 0] = 1250.0
    path = write(tmp_path, csv_text(points, points))
    with pytest.raises(InputError, match=r"along x.*stray points\?\): x=1250.0000 \(1 rows\)"):
        GridModel.from_measurements(path)


def test_disagreeing_repeats_name_the_line(tmp_path):
    points = np.repeat(grid_rows((2, 2, 2)), 2, axis=0)
    measured = points.copy()
    measured[5, 1] += 1.6  # vertex 2, second repeat: 0.8 mm from the mean of the two
    path = write(tmp_path, csv_text(points, measured))
    with pytest.raises(
        InputError, match=r"meas.csv:6: repeated .* 0.800 mm .*limit 0.5 mm; line 6, line 7"
    ):
        GridModel.from_measurements(path)
    assert GridModel.from_measurements(path, repeat_tol_mm=1.0).spread_mm == pytest.approx(0.8)


@pytest.mark.parametrize(
    ("cell", "message"),
    [("nan", r":4:9: 'nan' in column 'y_meas' is not a finite"), ("", r":4:9: empty cell")],
)
def test_bad_cells_name_file_line_and_column(tmp_path, cell, message):
    points = grid_rows((2, 2, 2))
    lines = csv_text(points, points).splitlines()
    fields = lines[3].split(",")
    fields[8] = cell
    lines[3] = ",".join(fields)
    with pytest.raises(InputError, match=message):
        GridModel.from_measurements(write(tmp_path, "\n".join(lines)))


def test_missing_columns_and_mixed_orientation(tmp_path):
    with pytest.raises(InputError, match="missing column.*z_meas"):
        GridModel.from_measurements(write(tmp_path, "x,y,z,x_meas,y_meas\n1,2,3,4,5\n"))
    with pytest.raises(InputError, match=r"missing column\(s\) c"):
        GridModel.from_measurements(
            write(tmp_path, "x,y,z,a,b,x_meas,y_meas,z_meas\n1,2,3,0,0,1,2,3\n")
        )
    points = grid_rows((2, 2, 2))
    lines = csv_text(points, points).splitlines()
    lines[6] = lines[6].replace(",0.0000,90.0000,0.0000,", ",0.0000,89.0000,0.0000,")
    with pytest.raises(InputError, match=r"meas.csv:7: a grid holds for one TCP orientation"):
        GridModel.from_measurements(write(tmp_path, "\n".join(lines)))


def test_a_flat_set_is_not_a_grid(tmp_path):
    points = grid_rows((2, 2, 1))
    with pytest.raises(InputError, match="single z value"):
        GridModel.from_measurements(write(tmp_path, csv_text(points, points)))


def test_bad_arrays_are_input_errors():
    points = grid_rows((2, 2, 2))
    with pytest.raises(InputError, match="differ in length"):
        GridModel.from_measurements((points, points[:-1]))
    bad = points.copy()
    bad[2, 1] = np.inf
    with pytest.raises(InputError, match="measured row 2 is not finite"):
        GridModel.from_measurements((points, bad))
    with pytest.raises(InputError, match=r"\(N, 3\)"):
        GridModel.from_measurements((points[:, :2], points[:, :2]))
