"""Table: Miller's scales with finite backward friction, against the kinematic ratchet bound.

For each backward-friction ratio r (backward friction r times the floor's; inf is Miller's ideal
no-backward rule, 1 no scales) it runs

- the worm's rectilinear progression (10 s gait at 100 Hz): its speed in the steady part
  (t >= 2 s, after the 1 s ramp), per cycle, against the kinematic ratchet bound: the advance
  per cycle of a body whose segments take exactly the commanded lengths and whose touching
  points never slide back nor forward more than the lengths force (at every instant the point
  that would go back most stands still: advance = the integral over a cycle of
  max_j sum_{i<j} dl_i/dt over the rings j, head = ring 0);
- the snake's miller_sidewinding (the snake body's unit time T, 10 s): its speed and heading
  drift per cycle (the head's turn over the run divided by the cycles).

    python tools/soft_backward_friction.py [--ratios 1,1.5,2,3,5,10,30,inf] [--duration 10]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from snakebot.backends.softbody import SoftBodyBackend
from snakebot.config.body import BodyConfig
from snakebot.config.body_loader import load_body
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.gaits.miller import MillerGait

STEADY_FROM_S = 2.0


def ratchet_bound_m(gait: MillerGait, segments: int, segment_length_m: float) -> float:
    """Advance per cycle, m, of the kinematic ratchet for the gait's axial wave (see above)."""
    period = 2 * math.pi / gait.omega
    times = np.linspace(0.0, period, 20001)
    phase = 2 * math.pi * gait.waves * np.arange(segments) / segments
    # l_i = L0 (1 - A sin(omega t - phase_i)); its rate, (T, S)
    rate = (
        -segment_length_m
        * gait.axial_amplitude
        * gait.omega
        * np.cos(gait.omega * times[:, None] - phase)
    )
    # Ring j sits sum_{i<j} l_i behind the head: the head must move at max_j sum_{i<j} dl_i/dt.
    behind = np.concatenate((np.zeros((len(times), 1)), np.cumsum(rate, axis=1)), axis=1)
    return float(np.trapezoid(behind.max(axis=1), times))


def run(body: BodyConfig, gait_name: str, ratio: float, duration_s: float) -> dict[str, float]:
    """One run: steady speed per cycle (m), the summary's BL/cycle and turn per cycle (deg)."""
    gait = make_gait(gait_name, body.joint_count)
    metrics = RunMetrics(body.joint_count, body.body_length_m, body.total_mass_kg)
    samples: list[tuple[float, np.ndarray]] = []

    def keep(record: CycleRecord) -> None:
        if record.body is not None and record.scored:
            samples.append((record.time_s, record.body.com_m[:2].copy()))

    with SoftBodyBackend(body, backward_ratio=ratio) as soft:
        result = run_gait(
            soft,
            gait,
            SafetyLayer.for_robot(body),
            RunPlan(duration_s=duration_s, ramp_out=False),
            metrics,
            observers=[keep],
        )
    period = float(gait.period_s or 1.0)
    steady = [(t, com) for t, com in samples if t >= STEADY_FROM_S]
    (t0, a), (t1, b) = steady[0], steady[-1]
    cycles = float(result.summary["cycles"] or 1.0)  # type: ignore[arg-type]
    return {
        "steady_m_per_cycle": float(np.hypot(*(b - a))) / ((t1 - t0) / period),
        "bl_per_cycle": float(result.summary["body_lengths_per_cycle"] or 0.0),  # type: ignore[arg-type]
        "turn_deg_per_cycle": float(result.summary["turn_deg"] or 0.0) / cycles,  # type: ignore[arg-type]
        "heading_deg": float(result.summary["heading_deg"] or 0.0),  # type: ignore[arg-type]
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ratios", default="1,1.5,2,3,5,10,30,inf")
    parser.add_argument("--duration", type=float, default=10.0)
    args = parser.parse_args()
    ratios = [float(r) for r in args.ratios.split(",")]
    worm, snake = load_body("worm"), load_body("snake")
    gait = make_gait("rectilinear", worm.joint_count)
    assert isinstance(gait, MillerGait)
    bound = ratchet_bound_m(gait, worm.lattice.segments, worm.lattice.segment_length_m)
    print(
        f"worm rectilinear: amplitude {gait.axial_amplitude:g}, {gait.waves:g} wave(s), "
        f"{gait.omega / (2 * math.pi):g} Hz; kinematic ratchet bound {bound * 1e3:.2f} mm/cycle "
        f"({bound / worm.body_length_m:.3f} BL/cycle)"
    )
    print(
        f"snake miller_sidewinding: unit time T = {snake.springs.time_unit_s:g} s "
        f"(k {snake.springs.k:g}, D {snake.springs.damping:g} in Miller's units)\n"
    )
    print(
        "| backward ratio | worm steady mm/cycle | ÷ ratchet bound | worm BL/cycle (run) | "
        "sidewinding BL/cycle | sidewinding heading deg | heading drift deg/cycle |"
    )
    print("|---|---|---|---|---|---|---|")
    for ratio in ratios:
        crawl = run(worm, "rectilinear", ratio, args.duration)
        side = run(snake, "miller_sidewinding", ratio, args.duration)
        label = "inf (Miller)" if math.isinf(ratio) else f"{ratio:g}"
        print(
            f"| {label} | {crawl['steady_m_per_cycle'] * 1e3:.2f} | "
            f"{crawl['steady_m_per_cycle'] / bound:.2f} | {crawl['bl_per_cycle']:.3f} | "
            f"{side['bl_per_cycle']:.3f} | {side['heading_deg']:.0f} | "
            f"{side['turn_deg_per_cycle']:+.2f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
