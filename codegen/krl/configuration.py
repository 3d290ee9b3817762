"""KUKA Status and Turn: the KRL words of a robot configuration (``kinematics.configuration``).

Status bit 0 is the shoulder (the wrist point in the overhead area), bit 1 the elbow (A3 at or
beyond phi), bit 2 the wrist (A5 < 0); Turn bit i is set when A(i+1) < 0 (docs/formats.md;
checked against the KUKA, Siemens and Beckhoff descriptions). Both are the IK's codes
(``configuration_code``, ``sign_code``) by number.
"""

from __future__ import annotations

import numpy as np

from accugrid.kinematics.configuration import Configuration, sign_code

__all__ = ["configuration_words", "read_configuration"]


def configuration_words(configuration: Configuration) -> np.ndarray:
    """KUKA Status and Turn (..., 2) int [S, T] of a configuration (...)."""
    c = configuration
    return np.stack([c.code, sign_code(c.negative)], axis=-1)


def read_configuration(words: np.ndarray) -> Configuration:
    """The configuration (...) of KUKA Status and Turn (..., 2) int [S, T]: an axis whose Turn
    bit is set is in quarter -1 (-90..0 deg), else 0 (0..90 deg), the quarters with the sign
    Turn gives."""
    words = np.asarray(words, dtype=np.int64)
    turn = words[..., 1, None] >> np.arange(6)
    return Configuration.of_code(words[..., 0], -(turn & 1))
