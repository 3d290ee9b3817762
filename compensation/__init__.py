"""The measured error model: regular grid, inverse-distance weighting (seed Eq. 12–13),
correction (Eq. 14), correction by a calibrated model, sampling plans, ISO 9283 / GB/T 12642 test
points and the grid-step study. The names of ``__all__`` are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "GridModel": "accugrid.compensation.grid",
    "GridCheck": "accugrid.compensation.grid",
    "CorrectionSettings": "accugrid.compensation.settings",
    "Policy": "accugrid.compensation.policy",
    "Measurements": "accugrid.compensation.measurements",
    "read_measurements": "accugrid.compensation.measurements",
    "measurements_from_arrays": "accugrid.compensation.measurements",
    "ModelCorrection": "accugrid.compensation.model_correction",
    "model_correct": "accugrid.compensation.model_correction",
    "residual_grid": "accugrid.compensation.model_correction",
    "Plan": "accugrid.compensation.plans",
    "grid_plan": "accugrid.compensation.plans",
    "cube_plan": "accugrid.compensation.plans",
    "experiment_plan": "accugrid.compensation.plans",
    "identification_plan": "accugrid.compensation.plans",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
