"""Pure geometry: robot models, forward/inverse kinematics, the DH error model, frame maths.

This is the lowest layer of accugrid; it imports nothing from ``compensation`` or ``codegen``.
"""

__all__: list[str] = []
