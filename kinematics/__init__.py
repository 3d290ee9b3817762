"""Pure geometry: robot models, forward/inverse kinematics, the DH error model, frame maths,
model identification and the calibrated robot file.

This is the lowest layer of accugrid; it imports nothing from ``compensation`` or ``codegen``.
The names of ``__all__`` are imported on first use (``infra.exports``).
"""

from accugrid.infra.exports import lazy_namespace

_API = {
    "Robot": "accugrid.kinematics.robot",
    "load_robot": "accugrid.kinematics.robot",
    "RobotModel": "accugrid.kinematics.model",
    "Configuration": "accugrid.kinematics.configuration",
    "abc_to_matrix": "accugrid.kinematics.frames",
    "matrix_to_abc": "accugrid.kinematics.frames",
    "pose_from_xyzabc": "accugrid.kinematics.frames",
    "xyzabc_from_pose": "accugrid.kinematics.frames",
    "transform_points": "accugrid.kinematics.frames",
    "invert": "accugrid.kinematics.frames",
    "simulate_measurements": "accugrid.kinematics.simulation",
    "simulate_pose_measurements": "accugrid.kinematics.simulation",
    "PoseSet": "accugrid.kinematics.identification",
    "Identification": "accugrid.kinematics.identification",
    "pose_set": "accugrid.kinematics.identification",
    "identify": "accugrid.kinematics.identification",
    "identification_summary": "accugrid.kinematics.calibrated",
    "calibrated_yaml": "accugrid.kinematics.calibrated",
    "fit_robot_frame": "accugrid.kinematics.base_frame",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
