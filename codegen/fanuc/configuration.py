"""FANUC position configuration, ``CONFIG : 'F U T, t1, t4, t6'``: the TP words of a robot
configuration (``kinematics.configuration``).

The words are FANUC's wrist, arm, front/back and the turn numbers of J1, J4 and J6, in a FANUC
robot file's axis angles (J1, J2, J4, J5, J6 as the controller has them; axis 3 the forearm's
angle to the lower arm, ``kinematics/robots/r2000ic-165f.yaml``):

- ``F``/``N``: the wrist is flipped (``F``) when J5 >= 0 (the faceplate tilted up towards the
  forearm), not flipped (``N``) when J5 < 0: the faceplate of a horizontal forearm points down
  at J5 = -90 deg, the usual ``N`` pose. It is the configuration's wrist flag negated;
- ``U``/``D``: the elbow flag (up: axis 3 on the normal side of the angle at which the lower
  arm, the forearm and the wrist centre are in line);
- ``T``/``B``: the wrist centre in front of the J1 axis (top) or behind it (back: the shoulder
  flag);
- t1, t4, t6: the whole turns of J1, J4, J6 (``Configuration.turns``: 0 for -180 <= angle <
  180 deg, 1 for 180..540, -1 for -540..-180).

``configuration_words`` gives them as integers (..., 6) [flip, up, back, t1, t4, t6] (flags 0/1),
``config_texts`` the CONFIG texts, ``read_configuration`` the configuration written words name.
"""

from __future__ import annotations

import re
from functools import lru_cache

import numpy as np

from accugrid.kinematics.configuration import Configuration

__all__ = ["CONFIG", "configuration_words", "read_configuration", "words_of_config"]

# a CONFIG text: 'F U T, 0, 0, 0' (flip, up, top, turns of J1, J4, J6)
CONFIG = re.compile(r"'\s*([FN])\s*([UD])\s*([TB])\s*,\s*(-?\d+)\s*,\s*(-?\d+)\s*,\s*(-?\d+)\s*'")
_AXES = [0, 3, 5]  # the axes whose turns CONFIG names


def configuration_words(configuration: Configuration) -> np.ndarray:
    """CONFIG words (..., 6) int [flip, up, back, t1, t4, t6] of a configuration (...)."""
    c = configuration
    out = np.empty((*np.shape(c.shoulder), 6), dtype=np.int64)
    out[..., 0] = ~np.asarray(c.wrist)
    out[..., 1] = c.elbow
    out[..., 2] = c.shoulder
    out[..., 3:] = c.turns[..., _AXES]
    return out


def read_configuration(words: np.ndarray) -> Configuration:
    """The configuration (...) CONFIG words (..., 6) int name: J1, J4, J6 in the turns named and
    J5 on the side the wrist names, each in its first quarter (0..90 deg of its turn, -90..0
    for a J5 that is not flipped); axes 2 and 3, which CONFIG does not name, 0..90 deg."""
    words = np.asarray(words, dtype=np.int64)
    quarter = np.zeros((*words.shape[:-1], 6), np.int8)
    quarter[..., _AXES] = 4 * words[..., 3:]
    quarter[..., 4] = np.where(words[..., 0] == 1, 0, -1)
    return Configuration(words[..., 2] == 1, words[..., 1] == 1, words[..., 0] == 0, quarter)


@lru_cache(maxsize=1024)  # a program holds a few distinct CONFIG texts, many times each
def words_of_config(text: str) -> tuple[int, ...] | None:
    """The words (6 ints) of a CONFIG text (``F U T, 0, 0, 0``, without its quotes), None when
    it is not one accugrid reads."""
    m = CONFIG.fullmatch(f"'{text}'")
    if m is None:
        return None
    flip, up, back = m.group(1) == "F", m.group(2) == "U", m.group(3) == "B"
    return (int(flip), int(up), int(back), *map(int, m.groups()[3:]))
