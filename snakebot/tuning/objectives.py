"""What a gait search optimises, turned into one loss to minimise (feasible gaits always win)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from snakebot.errors import ConfigError
from snakebot.tuning.feasibility import Violations

OBJECTIVES = ("speed", "cost_of_transport", "speed_toward_heading")
_UNITS = {"speed": "m/s", "cost_of_transport": "", "speed_toward_heading": "m/s"}
# A gait that does not move has no cost of transport; it ranks with this value.
COT_CAP = 1000.0


@dataclass(frozen=True)
class Objective:
    """``speed`` (m/s of net COM displacement, maximised), ``cost_of_transport`` (minimised) or
    ``speed_toward_heading`` (m/s of displacement along ``heading_deg`` in the world, maximised).

    ``worst`` is a loss no feasible gait reaches: infeasible candidates score above it, ranked
    by how far they left the envelope, so a search is pulled back towards playable gaits.
    """

    name: str
    heading_deg: float = 0.0
    worst: float = COT_CAP

    def __post_init__(self) -> None:
        if self.name not in OBJECTIVES:
            raise ConfigError(
                "objective", "", f"expected one of {', '.join(OBJECTIVES)}, got {self.name!r}"
            )

    @property
    def maximise(self) -> bool:
        """True for the speeds, False for the cost of transport."""
        return self.name != "cost_of_transport"

    @property
    def unit(self) -> str:
        """Unit of ``value``."""
        return _UNITS[self.name]

    def value(self, summary: Mapping[str, object]) -> float:
        """The objective read from a run summary; NaN where the run gives none."""
        if self.name == "speed":
            return _number(summary.get("speed_mps"))
        if self.name == "cost_of_transport":
            return _number(summary.get("cost_of_transport"))
        dx, dy = _pair(summary.get("displacement_m"))
        duration = _number(summary.get("duration_s"))
        if not duration > 0:
            return math.nan
        heading = math.radians(self.heading_deg)
        return (dx * math.cos(heading) + dy * math.sin(heading)) / duration

    def loss(self, value: float, violations: Violations) -> float:
        """Minimisation loss: -value (speeds) or value (COT), capped; infeasible above ``worst``."""
        if not violations.feasible:
            return self.worst + 1.0 + violations.total
        if math.isnan(value):
            return self.worst
        oriented = -value if self.maximise else value
        return min(oriented, self.worst)

    def better(self, a: float, b: float) -> bool:
        """Whether objective value ``a`` beats ``b`` (NaN never does)."""
        if math.isnan(a):
            return False
        if math.isnan(b):
            return True
        return a > b if self.maximise else a < b


def objective_for(name: str, heading_deg: float, body_length_m: float) -> Objective:
    """The objective ``name``; for speeds, ``worst`` is 10 body lengths per second backwards."""
    worst = COT_CAP if name == "cost_of_transport" else 10.0 * body_length_m
    return Objective(name, heading_deg, worst)


def _number(value: object) -> float:
    return float(value) if isinstance(value, int | float) else math.nan


def _pair(value: object) -> tuple[float, float]:
    if isinstance(value, list | tuple) and len(value) == 2:
        return _number(value[0]), _number(value[1])
    return math.nan, math.nan
