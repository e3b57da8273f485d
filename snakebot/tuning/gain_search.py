"""`tune gains` without the command line: search the Position gains, report, write the config.

The search runs over the Position P/I/D Gain registers (what the robot file holds); the report
gives each candidate in registers and in SI (kp N·m/rad, kd N·m·s/rad).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from snakebot.config.fields import read_toml
from snakebot.config.schema import GainRegisters, RobotConfig
from snakebot.errors import ConfigError
from snakebot.tuning.config_edit import set_table_values
from snakebot.tuning.gains import (
    BackendSession,
    GainScore,
    GainTest,
    candidate_grid,
    evaluate_gains,
    measure_chirps,
    refine,
)
from snakebot.tuning.trace import FloatArray

Chirp = tuple[float, tuple[FloatArray, FloatArray, FloatArray]]
Listener = Callable[[int, int, GainScore, GainScore], None]


@dataclass(frozen=True)
class GainSearch:
    """The current gains' score, the best candidate's, every candidate in order, and chirps."""

    current: GainScore
    best: GainScore
    scores: tuple[GainScore, ...]
    chirp_before: dict[int, Chirp]
    chirp_after: dict[int, Chirp]

    @property
    def improved(self) -> bool:
        """True when the best feasible candidate tracks the gait better than the current gains."""
        return (
            self.best.feasible
            and self.best.gains != self.current.gains
            and (not self.current.feasible or self.best.loss < self.current.loss)
        )

    def summary(self, robot: RobotConfig, test: GainTest) -> dict[str, object]:
        """JSON-ready report."""
        joints = test.joints
        return {
            "robot": robot.name,
            "reference_gait": test.gait,
            "joints": list(joints),
            "current": self.current.as_dict(joints),
            "best": self.best.as_dict(joints),
            "improved": self.improved,
            "tracking_rms_before_rad": self.current.tracking_rms_rad,
            "tracking_rms_after_rad": self.best.tracking_rms_rad,
            "chirp_rms_before_rad": {str(j): v[0] for j, v in self.chirp_before.items()},
            "chirp_rms_after_rad": {str(j): v[0] for j, v in self.chirp_after.items()},
            "evaluations": len(self.scores),
            "candidates": [s.as_dict(joints) for s in self.scores],
        }


def search_gains(
    session: BackendSession,
    robot: RobotConfig,
    test: GainTest,
    *,
    budget: int,
    i_values: Sequence[int] = (),
    chirps: bool = True,
    listener: Listener | None = None,
) -> GainSearch:
    """A coarse grid around the current gains, then a finer pattern around the best; at most
    ``budget`` candidates (the current gains count as the first). ConfigError naming the robot
    file's ``[gains]`` for a servo without Position P/I/D Gain (an AX's Compliance Slope has
    seven levels: set ``compliance_slope`` there)."""
    if robot.servo.gain_kind != "pid":
        raise ConfigError(
            robot.source,
            "gains",
            f"the gain search tunes Position P/I/D Gain registers, which "
            f"{robot.servo.name} does not have; its stiffness is the Compliance Slope "
            "(compliance_slope = 2, 4, 8, 16, 32, 64 or 128 in [gains])",
        )
    current = robot.gain_registers
    maxima = robot.servo.gain_max
    grid = candidate_grid(
        current,
        maxima,
        p_values=4 if budget >= 16 else 3,
        d_values=3 if budget >= 10 else 2,
        i_values=i_values,
    )
    scores: list[GainScore] = []

    def run(candidates: Sequence[GainRegisters]) -> None:
        for gains in candidates:
            if len(scores) >= budget:
                return
            scores.append(evaluate_gains(session, robot, gains, test))
            if listener is not None:
                listener(len(scores), budget, scores[-1], min(scores, key=_key))

    run(grid)
    run(refine(min(scores, key=_key).gains, grid, maxima))
    best = min(scores, key=_key)
    before: dict[int, Chirp] = {}
    after: dict[int, Chirp] = {}
    if chirps:
        before = measure_chirps(session, robot, current, test)
        after = measure_chirps(session, robot, best.gains, test)
    return GainSearch(scores[0], best, tuple(scores), before, after)


def write_gains(robot: RobotConfig, gains: GainRegisters, path: Path | None = None) -> Path:
    """Set ``[gains]`` of robot file ``path`` (default the robot's own file) in place, comments
    and layout kept; returns the path written: the Position P/I/D Gain registers, or, where the
    file gives its gains in SI, kp/kd in SI and the I register (a file holds one form, never
    both). ConfigError naming the file if it cannot be read, or if the edit would not parse back."""
    target = robot.source if path is None else path
    values: dict[str, object] = {
        "position_p": gains.position_p,
        "position_i": gains.position_i,
        "position_d": gains.position_d,
    }
    if "kp_nm_per_rad" in read_toml(target).get("gains", {}):
        pd = robot.servo.gains_of(gains)
        values = {
            "kp_nm_per_rad": pd.kp_nm_per_rad,
            "kd_nms_per_rad": pd.kd_nms_per_rad,
            "position_i": gains.position_i,
        }
    set_table_values(target, "gains", values)
    return target


def _key(score: GainScore) -> tuple[float, float]:
    tracking = score.tracking_rms_rad
    return (score.loss, tracking if math.isfinite(tracking) else math.inf)
