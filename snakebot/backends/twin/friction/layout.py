"""Where a twin model carries its scale-friction parameters, shared by the C and numpy forms.

A ``numeric`` element holds the parameters (so they can be changed on a compiled model) and a
user sensor, one value per link, receives each link's contact normal load in N.
"""

from __future__ import annotations

from enum import IntEnum

NUMERIC_NAME = "snakebot_scale_friction"
SENSOR_NAME = "snakebot_contact_load"


class Slot(IntEnum):
    """Index of each parameter in the numeric element's data."""

    FIRST_BODY = 0
    LINK_COUNT = 1
    MU_FORWARD = 2
    MU_BACKWARD = 3
    MU_LATERAL = 4
    V0_M_S = 5
    AT_CONTACT = 6
