"""Cycle records as a control loop makes them, for tests of the sinks that observe them."""

from __future__ import annotations

import numpy as np

from snakebot.control.cycle import CycleRecord
from snakebot.types import BodyState, JointState


def record(
    index: int,
    time_s: float,
    command: np.ndarray,
    position: np.ndarray | None = None,
    velocity: np.ndarray | None = None,
    effort: np.ndarray | None = None,
    com: np.ndarray | None = None,
    quat: np.ndarray | None = None,
    gyro: np.ndarray | None = None,
) -> CycleRecord:
    """The record of cycle ``index`` (0 for the first: the CSV's ``cycle`` column) read at
    ``time_s``; unset joint arrays are the command (position) or zeros, ``com`` None: no body
    (hardware); a body without ``quat`` faces +x."""
    zeros = np.zeros_like(command)
    body = None
    if com is not None:
        head = np.array([1.0, 0.0, 0.0, 0.0]) if quat is None else quat
        body = BodyState(np.asarray(com, dtype=float), head, gyro)
    return CycleRecord(
        cycle=index + 1,
        gait_time_s=time_s,
        target_rad=command,
        command_rad=command,
        state=JointState(
            time_s,
            command if position is None else position,
            zeros if velocity is None else velocity,
            zeros if effort is None else effort,
        ),
        body=body,
        amplitude=1.0,
        scored=True,
        period_s=0.01,
        overrun=False,
        achieved_rate_hz=100.0,
    )
