"""The Warp engine's scores: a run summary and its violations from each world's running values.

The same keys and formulas as snakebot.control.metrics.RunMetrics.summary and
snakebot.tuning.feasibility.assess, applied to what snakebot.tuning.warp_kernels accumulated
on the device (the columns of ``WarpRun.acc``) instead of to a recorded trace.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

from snakebot.config.schema import RobotConfig
from snakebot.control.metrics import GRAVITY_M_S2
from snakebot.tuning.feasibility import (
    MAX_CHATTER,
    MAX_PENETRATION_FRACTION,
    MAX_UPSIDE_DOWN_FRACTION,
    Envelope,
    Violations,
)
from snakebot.tuning.trace import FloatArray

if TYPE_CHECKING:
    from snakebot.tuning.engine_warp import WarpRun


def outcomes(
    run: WarpRun,
    robot: RobotConfig,
    envelope: Envelope,
    duration_s: float,
    periods_s: Sequence[float | None],
    start_com_m: FloatArray,
) -> list[tuple[dict[str, object], Violations]]:
    """Each world's run summary (the keys and formulas of RunMetrics.summary) and violations
    (those of feasibility.assess), from the device's running values."""
    from snakebot.tuning import warp_kernels as k

    out = []
    joints, dt = robot.joint_count, run.dt_s
    for b, period in enumerate(periods_s):
        a, cycles = run.acc[b], int(run.cycles[b])
        duration = round(float(run.time_s[cycles - 1]), 6) if cycles else 0.0
        gait_cycles = round(duration / period, 6) if period else None
        work = float(a[k.POSITIVE_WORK_J])
        dx = float(a[k.COM_X] - start_com_m[0])
        dy = float(a[k.COM_Y] - start_com_m[1])
        distance = math.hypot(dx, dy)
        summary: dict[str, object] = {
            "duration_s": duration,
            "joints": joints,
            "body_length_m": robot.body_length_m,
            "control_cycles": cycles,
            "cycles": gait_cycles,
            "tracking_rms_rad": math.sqrt(float(a[k.SQUARED_ERROR]) / max(cycles * joints, 1)),
            "max_abs_command_rad": float(a[k.MAX_ABS_COMMAND]),
            "positive_work_j": work,
            "distance_m": distance,
            "displacement_m": [dx, dy],
            "speed_mps": distance / duration if duration > 0 else 0.0,
            "turn_deg": math.degrees(float(a[k.TURN_RAD])),
            "heading_deg": math.degrees(math.atan2(dy, dx)) if distance > 0 else 0.0,
            "body_lengths_per_cycle": (distance / robot.body_length_m / gait_cycles)
            if gait_cycles
            else None,
            "cost_of_transport": (work / (robot.total_mass_kg * GRAVITY_M_S2 * distance))
            if distance > 1e-9
            else None,
        }
        out.append((summary, _violations(a, cycles, dt, envelope, duration_s, run.stop_reason[b])))
    return out


def _violations(
    a: FloatArray, cycles: int, dt: float, envelope: Envelope, duration_s: float, stopped: str
) -> Violations:
    from snakebot.tuning import warp_kernels as k

    speed = max(
        float(a[k.MAX_TARGET_STEP_RAD]) / dt / envelope.max_speed_rad_s - 1.0,
        float(a[k.MAX_SPEED_RAD_S]) / envelope.no_load_speed_rad_s - 1.0,
        0.0,
    )
    planned = max(round(duration_s / dt), cycles, 1)
    longest_s = float(a[k.LONGEST_SATURATION]) * dt
    upside_down = float(a[k.UPSIDE_DOWN_CYCLES]) / cycles if cycles else 0.0
    excess = 0.0 if envelope.allow_roll else upside_down - MAX_UPSIDE_DOWN_FRACTION
    reversals = float(a[k.MAX_REVERSALS]) / cycles if cycles >= 2 else 0.0
    penetration = 0.0
    if envelope.radius_m > 0 and cycles:
        penetration = -float(a[k.MIN_CLEARANCE_M]) / envelope.radius_m - MAX_PENETRATION_FRACTION
    return Violations(
        joint_limit_rad=max(float(a[k.BEYOND_LIMIT_RAD]), 0.0),
        speed_excess=speed,
        saturation_excess_s=max(longest_s - envelope.max_saturation_s, 0.0),
        airborne_fraction=(float(a[k.AIRBORNE_CYCLES]) + planned - cycles) / planned,
        stopped=stopped,
        upside_down_fraction=upside_down,
        upside_down_excess=max(excess, 0.0),
        penetration_excess=max(penetration, 0.0),
        chatter_excess=max(reversals - MAX_CHATTER, 0.0),
    )
