"""FANUC position configuration: ``CONFIG : 'F U T, t1, t4, t6'`` of a Cartesian position.

The words (FANUC's "configuration": wrist, arm, front/back and the turn numbers of J1, J4, J6)
come from the joint angles q (N, 6) rad the pose is reached with, in a FANUC robot file's axis
angles (J1, J2, J4, J5, J6 as the controller has them; axis 3 the forearm's angle to the lower
arm, ``kinematics/robots/r2000ic-165f.yaml``):

- ``F``/``N``: the wrist is flipped when J5 > 0 (the faceplate tilted up towards the forearm),
  not flipped when J5 <= 0: the faceplate of a forearm held horizontal points down at
  J5 = -90 deg, the usual ``N`` pose;
- ``U``/``D``: the elbow is up when the elbow flag of ``kinematics.configuration`` is set (axis 3
  at or beyond the angle at which the lower arm, the forearm and the wrist centre are in line,
  on the side of the normal posture), down otherwise;
- ``T``/``B``: the wrist centre is in front of the J1 axis (top) or behind it (back: the
  shoulder flag of ``kinematics.configuration``);
- turn numbers t1, t4, t6: how many whole turns J1, J4, J6 are from (-180, 180] deg:
  ceil((angle - 180) / 360), so 0 for -180 < angle <= 180, 1 for 180 < angle <= 540, ...

``kuka_status_of`` reads the words back as the KUKA Status of the same arm configuration, so
that the correction policy holds a rewritten position against the Status its grid was measured
in.
"""

from __future__ import annotations

import re

import numpy as np

from accugrid.kinematics.configuration import Configuration, kuka_status
from accugrid.kinematics.ik import wrap

__all__ = ["CONFIG", "config_columns", "kuka_status_of", "turn_numbers"]

# the words of a CONFIG text: 'F U T, 0, 0, 0' (flip, up, top, turns of J1, J4, J6)
CONFIG = re.compile(r"'\s*([FN])\s*([UD])\s*([TB])\s*,\s*(-?\d+)\s*,\s*(-?\d+)\s*,\s*(-?\d+)\s*'")


def turn_numbers(angle: np.ndarray) -> np.ndarray:
    """FANUC turn numbers (...) int of axis angles (...) rad: 0 in (-180, 180] deg, then one
    more (less) a whole turn up (down)."""
    return np.ceil((np.degrees(angle) - 180.0) / 360.0 - 1e-12).astype(np.int64)


def config_columns(robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The CONFIG of joint vectors q (N, 6) rad of a FANUC robot (a DH ``Robot``): its three
    letters as ASCII bytes (N, 3) uint8 (``F``/``N``, ``U``/``D``, ``T``/``B``) and the turn
    numbers (N, 3) int of J1, J4, J6."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    c = Configuration.of_joints(robot, q)
    letters = np.empty((len(q), 3), np.uint8)
    letters[:, 0] = np.where(wrap(q[:, 4]) > 0, ord("F"), ord("N"))
    letters[:, 1] = np.where(c.elbow, ord("U"), ord("D"))
    letters[:, 2] = np.where(c.shoulder, ord("B"), ord("T"))
    return letters, turn_numbers(q[:, [0, 3, 5]])


def kuka_status_of(letters: list[str]) -> np.ndarray:
    """The KUKA Status (N,) of CONFIG letters (N,) (``"NUT"``; "" for none: -1): shoulder =
    back, elbow = up, wrist (A5 < 0) = not flipped."""
    out = np.full(len(letters), -1, np.int64)
    given = [i for i, w in enumerate(letters) if w]
    if given:
        words = np.array([letters[i] for i in given], dtype="U3").view("U1").reshape(-1, 3)
        out[given] = kuka_status(words[:, 2] == "B", words[:, 1] == "U", words[:, 0] == "N")
    return out
