"""Decode the cycle's state read (load or current, velocity, position) into joint-frame SI."""

from __future__ import annotations

import numpy as np

from snakebot.backends.chain.ticks import TickConverter
from snakebot.config.schema import RobotConfig
from snakebot.servo_tables import ServoTable


class StateDecoder:
    """Register rows to a (3, N) array: position rad, velocity rad/s, effort N·m, joint frame.

    Effort: XL430/XC430 report Present Load in 0.1 % of the stall torque (taken at the robot's
    supply voltage); XM430/XL330 report Present Current, times the torque constant
    stall torque / stall current. ``read_effort=False`` leaves load out of the read (zeros).
    """

    def __init__(
        self, robot: RobotConfig, table: ServoTable, converter: TickConverter, read_effort: bool
    ) -> None:
        physics = robot.servo.physics
        load_key = "present_current" if "present_current" in table else "present_load"
        if load_key == "present_current":
            per_unit = table[load_key].scale * physics.stall_torque_nm / table.specs.stall_current_a
        else:
            stall = physics.stall_torque_nm * physics.supply_voltage_v / physics.nominal_voltage_v
            per_unit = table[load_key].scale / 100.0 * stall
        self.read_effort = read_effort
        self.measures_current = read_effort and load_key == "present_current"
        """Whether the read holds Present Current (the X series' XM/XL330 tables)."""
        self._current_gain = converter.direction * table[load_key].scale  # A per unit, (N,)
        wanted = (load_key,) * read_effort + ("present_velocity", "present_position")
        self.keys: tuple[str, ...] = tuple(sorted(wanted, key=lambda k: table[k].address))
        """The registers to read, in address order (the order of each row): load, velocity,
        position on the X series; position, speed, load on AX/MX."""
        self.position_index = self.keys.index("present_position")
        """Where Present Position sits in a row."""
        self._velocity_index = self.keys.index("present_velocity")
        self._effort_index = self.keys.index(load_key) if read_effort else None
        velocity = converter.direction * table["present_velocity"].scale
        effort = converter.direction * per_unit
        # Plain floats per joint: (position gain, position bias, velocity gain, effort gain).
        self._terms = [
            (pg, pb, vg, eg)
            for (pg, pb), vg, eg in zip(
                converter.state_terms(), velocity.tolist(), effort.tolist(), strict=True
            )
        ]

    def decode(self, rows: list[tuple[int, ...]]) -> np.ndarray:
        """(3, N): position, velocity, effort from one row per servo, head to tail."""
        p, v, e = self.position_index, self._velocity_index, self._effort_index
        position, velocity, effort = [], [], []
        for row, (pg, pb, vg, eg) in zip(rows, self._terms, strict=True):
            position.append(row[p] * pg + pb)
            velocity.append(row[v] * vg)
            effort.append(0.0 if e is None else row[e] * eg)
        return np.array((position, velocity, effort))

    def current_a(self, rows: list[tuple[int, ...]]) -> np.ndarray:
        """Present Current (N,) A in the joints' sense from the same rows; only where
        ``measures_current``."""
        assert self._effort_index is not None and self.measures_current
        e = self._effort_index
        raw = np.array([row[e] for row in rows], dtype=float)
        current: np.ndarray = raw * self._current_gain
        return current
