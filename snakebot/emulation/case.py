"""`ServoCase`: the axes of one multi-axis servo (2XL430-W250) and the rules of their module.

Each axis has its own ID and control table, but one communication module serves both
(e-Manual 2XL430-W250, control table notes; reference/servo-families.md §3.3):

- Baud Rate(8) and Protocol Type(13) always change on every axis at once;
- an axis cannot take the ID of another axis of its case: Data Limit Error (0x06), nothing set;
- EEPROM is writable only while Torque Enable is 0 on every axis (else Access Error, 0x07);
- the axes share the bus and the connector: unplugging the case takes every axis off it.

A chain built for such a model pairs the IDs in the order given (1-2, 3-4, ..., as the factory
numbers a case's axes and a robot file lists them head to tail): see `cases_of`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from snakebot.emulation.errors import EmulationError
from snakebot.emulation.protocol import StatusError

if TYPE_CHECKING:
    from snakebot.emulation.memory import WritePlan
    from snakebot.emulation.virtual_servo import VirtualServo

SHARED_KEYS = frozenset({"baud_rate", "protocol_type"})  # held by the one communication module


class ServoCase:
    """The axes of one case; each axis's `case` is set to it.

    Raises EmulationError when the axes are not `table.specs.axes` servos of one model, or when
    an axis already belongs to a case.
    """

    def __init__(self, axes: Sequence[VirtualServo]) -> None:
        axes = tuple(axes)
        if not axes:
            raise EmulationError("a servo case needs its axes")
        table = axes[0].table
        if any(axis.table is not table for axis in axes):
            raise EmulationError("the axes of one case must be of one model")
        if len(axes) != table.specs.axes:
            raise EmulationError(
                f"a {table.model} case has {table.specs.axes} axes, not {len(axes)}"
            )
        if any(axis.case is not None for axis in axes):
            raise EmulationError("an axis belongs to one case only")
        self.axes = axes
        for axis in axes:
            axis.case = self
        self.follow(axes[0])

    def others(self, axis: VirtualServo) -> tuple[VirtualServo, ...]:
        """The other axes of `axis`'s case."""
        return tuple(other for other in self.axes if other is not axis)

    def check_write(self, axis: VirtualServo, plan: WritePlan) -> int:
        """The case's rules for a write to `axis` that its own firmware allowed: 0 or an error."""
        others = self.others(axis)
        if any(r.eeprom for r in plan.items) and any(o.torque_enabled for o in others):
            return StatusError.ACCESS
        new_id = plan.values.get("id")
        if new_id is not None and any(o.servo_id == new_id for o in others):
            return StatusError.DATA_LIMIT
        return 0

    def follow(self, axis: VirtualServo) -> None:
        """Give every other axis `axis`'s Baud Rate and Protocol Type (the module's)."""
        for key in sorted(SHARED_KEYS):
            if axis.memory.has(key):
                value = axis.memory.get(key)
                for other in self.others(axis):
                    other.memory.set(key, value)


def cases_of(servos: Sequence[VirtualServo]) -> list[ServoCase]:
    """Group consecutive servos of a multi-axis model into cases (1-2, 3-4, ...); single-axis
    servos are left alone. EmulationError when a case would be left incomplete."""
    cases: list[ServoCase] = []
    index = 0
    while index < len(servos):
        axes = servos[index].table.specs.axes
        if axes == 1:
            index += 1
            continue
        group = servos[index : index + axes]
        if len(group) < axes or any(s.table is not servos[index].table for s in group):
            ids = [s.servo_id for s in group]
            raise EmulationError(
                f"a {servos[index].table.model} has {axes} axes, each with its own ID: give its "
                f"IDs in whole cases (IDs {ids} leave one incomplete)"
            )
        cases.append(ServoCase(group))
        index += axes
    return cases
