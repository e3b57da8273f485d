from __future__ import annotations

import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.types import JointCommand


def _trace() -> np.ndarray:
    rows = []
    with TwinBackend(load_robot("snake12")) as twin:
        for k in range(100):
            twin.send_command(JointCommand(0.5 * np.sin(0.03 * k - 0.5 * np.arange(12))))
            twin.advance(0.01)
            state = twin.read_state()
            rows.append(np.concatenate((state.position_rad, state.velocity_rad_s, state.effort_nm)))
    return np.array(rows)


def test_two_twin_runs_with_the_same_inputs_are_identical() -> None:
    np.testing.assert_array_equal(_trace(), _trace())
