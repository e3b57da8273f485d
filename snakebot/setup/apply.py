"""Write only the differences, in a safe order, verifying every write; a rerun finishes the job.

Order per servo, head to tail: Status Return Level first (every later write must be answered),
a reboot if a hardware error is latched, torque off before EEPROM items (the joint goes limp),
Operating Mode before the other EEPROM items (a mode change resets gains and profiles, e-Manual
Operating Mode), the EEPROM items inside the family's EEPROM lock where it has one (Feetech: Lock
0 before them, so they are saved, and 1 after), a reboot after settings that act at boot, then RAM
items. Baud rates change last,
one servo at a time (unlocked first where the family locks its EEPROM), each found again at its
new rate (and locked there) before the next. IDs never change here: a
servo is known by its ID (``assign-id`` changes IDs). Torque is left off. Before the first write,
a servo that stands outside the Min/Max Position Limit about to be written is warned about
(:class:`PositionOutsideLimitsWarning`): it could not hold there with torque on.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from snakebot.families import family_for
from snakebot.servo.ticks import ticks_to_rad
from snakebot.setup.bauds import port_bauds, port_rate
from snakebot.setup.diff import ChainDiff, Difference, survey
from snakebot.setup.errors import SetupError, VerifyError
from snakebot.setup.link import Link, unanswered_ok
from snakebot.setup.maintenance import reboot, wait_for_boot
from snakebot.setup.settings import REBOOT_KEYS, ChainSettings, Setting

Action = Literal["write", "torque_off", "reboot", "baud", "unlock", "lock"]
FIRST_KEYS = ("status_return_level",)
LIMIT_KEYS = ("min_position_limit", "max_position_limit")


class PositionOutsideLimitsWarning(UserWarning):
    """A servo stands outside the Min/Max Position Limit that ``config apply`` is about to write."""


@dataclass(frozen=True)
class Step:
    """One action on one servo; ``write`` steps with ``recheck`` are skipped if already right."""

    servo_id: int
    action: Action
    setting: Setting | None = None
    current: int | None = None
    recheck: bool = False
    reason: str = ""

    def describe(self) -> str:
        """One line for the plan, e.g. ``servo 3: return_delay_time 500 -> 0 us``."""
        head = f"servo {self.servo_id}:"
        if self.setting is None:
            what = {"torque_off": "torque off", "unlock": "unlock EEPROM", "lock": "lock EEPROM"}
            return f"{head} {what.get(self.action, self.action)} ({self.reason})"
        want, unit = self.setting.show(self.setting.raw)
        want = f"{want} {unit}".rstrip()
        if self.current is None:
            return f"{head} {self.setting.key} -> {want} (checked again after the {self.reason})"
        have, _ = self.setting.show(self.current)
        kind = "baud rate" if self.action == "baud" else self.setting.key
        return f"{head} {kind} {have} -> {want}"


@dataclass(frozen=True)
class ApplyPlan:
    """The steps in order; ``limp`` lists servos whose torque is on now and will go off."""

    steps: tuple[Step, ...]
    limp: tuple[int, ...]

    @property
    def empty(self) -> bool:
        """Nothing to do."""
        return not self.steps


def _refusals(chain: ChainSettings, diff: ChainDiff) -> list[str]:
    """Why the plan cannot be carried out by any order of writes: a locked EEPROM (AX/MX Lock,
    which snakebot never sets) or a latched error in a family without Reboot."""
    family = family_for(chain.table, chain.robot.bus.protocol)
    can_reboot = family.capabilities(chain.table).reboot
    out = []
    for wanted in chain.servos:
        state = diff.servos[wanted.servo_id]
        eeprom = [d.key for d in diff.for_id(wanted.servo_id) if d.setting.eeprom]
        if state.locked and eeprom:
            out.append(
                f"servo {wanted.servo_id} has its EEPROM locked (Lock = 1) and "
                f"{', '.join(eeprom)} differ: power-cycle it (the lock clears only then)"
            )
        if state.hardware_error and not can_reboot:
            out.append(
                f"servo {wanted.servo_id} has a latched hardware error and "
                f"{family.label} has no Reboot: power-cycle it"
            )
    return out


def plan_apply(chain: ChainSettings, diff: ChainDiff) -> ApplyPlan:
    """The steps that bring every servo to ``chain``'s settings, given what ``survey`` found.

    SetupError where no order of writes can (a locked EEPROM, a latched error without Reboot).
    """
    refused = _refusals(chain, diff)
    if refused:
        raise SetupError("cannot apply the settings: " + "; ".join(refused))
    family = family_for(chain.table, chain.robot.bus.protocol)
    can_reboot = family.capabilities(chain.table).reboot
    lock = (
        family.eeprom_lock if family.eeprom_lock and family.eeprom_lock.key in chain.table else None
    )
    steps: list[Step] = []
    bauds: list[Step] = []
    limp: list[int] = []
    for wanted in chain.servos:
        servo_id = wanted.servo_id
        state = diff.servos[servo_id]
        diffs = diff.for_id(servo_id)
        first = [d for d in diffs if d.key in FIRST_KEYS]
        eeprom = [d for d in diffs if d.setting.eeprom and d.key != "baud_rate"]
        eeprom.sort(key=lambda d: (d.key != "operating_mode", d.setting.register.address))
        ram = [d for d in diffs if not d.setting.eeprom and d.key not in FIRST_KEYS]
        steps += [_write(d) for d in first]
        resets = bool(state.hardware_error)
        if state.hardware_error:
            steps.append(Step(servo_id, "reboot", reason="clears the latched hardware error"))
        if eeprom:
            limp += [servo_id] if state.torque_on else []
            why = "the joint goes limp" if state.torque_on else "already off"
            steps.append(Step(servo_id, "torque_off", reason=f"EEPROM writes need it; {why}"))
            if lock is not None:
                why = f"{lock.key} {lock.unlocked}: the EEPROM writes that follow are saved"
                steps.append(Step(servo_id, "unlock", reason=why))
            steps += [_write(d) for d in eeprom]
            if lock is not None:
                why = f"{lock.key} {lock.locked} again, its power-on value"
                steps.append(Step(servo_id, "lock", reason=why))
            resets |= any(d.key == "operating_mode" for d in eeprom)
        # Without a Reboot instruction (Protocol 1.0) they act at the next power-up.
        booted = [d.key for d in eeprom if d.key in REBOOT_KEYS] if can_reboot else []
        if booted:
            steps.append(Step(servo_id, "reboot", reason=f"{', '.join(booted)} acts at boot"))
        if resets or booted:
            why = "reboot" if state.hardware_error or booted else "mode change"
            steps += [
                Step(servo_id, "write", s, None, recheck=True, reason=why)
                for s in wanted.settings
                if not s.eeprom
            ]
        else:
            steps += [_write(d) for d in ram]
        bauds += [
            Step(servo_id, "baud", d.setting, d.current) for d in diffs if d.key == "baud_rate"
        ]
    return ApplyPlan(tuple(steps + bauds), tuple(limp))


def _write(diff: Difference) -> Step:
    return Step(diff.servo_id, "write", diff.setting, diff.current)


class Applier:
    """Runs a plan's steps on a link, tracking the baud each servo listens at (``where``)."""

    def __init__(self, link: Link, diff: ChainDiff) -> None:
        self.link = link
        self.where = {i: s.baud for i, s in diff.servos.items()}
        # Below its highest value (Dynamixel 2, Feetech 1) Status Return Level leaves writes
        # unanswered (e-Manual Status Return Level; Feetech Response Status Level 8).
        self.answers_all = (
            link.bus.table["status_return_level"].maximum
            if "status_return_level" in link.bus.table
            else 2
        )
        self.quiet = {
            i
            for i, s in diff.servos.items()
            if s.values.get("status_return_level", self.answers_all) < self.answers_all
        }

    def run(self, step: Step) -> bool:
        """Execute one step; False if a ``recheck`` write found the value already right."""
        servo_id, baud = step.servo_id, self.where[step.servo_id]
        bus = self.link.at(baud)
        if step.action == "reboot":
            reboot(self.link, servo_id, baud)
            self.quiet.discard(servo_id)
            return True
        if step.action == "torque_off":
            self._write(servo_id, "torque_enable", 0)
            return True
        if step.action in ("unlock", "lock"):
            self._lock(servo_id, step.action == "lock")
            return True
        assert step.setting is not None
        if step.action == "baud":
            self._change_baud(servo_id, step.setting.raw)
            return True
        if step.recheck and bus.read(servo_id, step.setting.key) == step.setting.raw:
            return False
        self._write(servo_id, step.setting.key, step.setting.raw)
        return True

    def _write(self, servo_id: int, key: str, value: int) -> None:
        bus = self.link.at(self.where[servo_id])
        if servo_id in self.quiet or key == "status_return_level":
            bus.sync_write(key, {servo_id: value})  # answered or not, the read-back decides
        else:
            bus.write(servo_id, key, value)
        back = bus.read(servo_id, key)
        if back != value:
            raise VerifyError(self.link.port, servo_id, key, value, back)
        if key == "status_return_level":
            (self.quiet.discard if value >= self.answers_all else self.quiet.add)(servo_id)

    def _lock(self, servo_id: int, locked: bool) -> None:
        """Close (``locked``) or open the family's EEPROM lock, where it has one."""
        lock = self.link.family.eeprom_lock
        if lock is not None and lock.key in self.link.bus.table:
            self._write(servo_id, lock.key, lock.locked if locked else lock.unlocked)

    def _change_baud(self, servo_id: int, index: int) -> None:
        old = self.where[servo_id]
        rate = self.link.bus.table.baud_rates[index]
        new = port_rate(rate, port_bauds(self.link.bus.table)) or rate
        other = self.link.probe(servo_id, new, tries=1)
        if other.models or other.corrupt:
            raise SetupError(
                f"{self.link.port}: cannot move servo {servo_id} from {old} to {new} baud: another "
                f"servo already answers as ID {servo_id} at {new} baud. Unplug it, or give it "
                "another ID with `snakebot config assign-id`"
            )
        self._lock(servo_id, locked=False)
        bus = self.link.at(old)
        # The status may already come back at the new rate; finding the servo there decides.
        with unanswered_ok():
            bus.write(servo_id, "baud_rate", index)
        try:
            wait_for_boot(self.link, servo_id, new, timeout_s=1.0)
        except SetupError:
            raise SetupError(
                f"{self.link.port}: servo {servo_id} does not answer at {new} baud after the "
                f"change (it was at {old}). Nothing else was changed; run `snakebot scan --port "
                f"{self.link.port} --all-bauds` to find it, then apply again"
            ) from None
        self.where[servo_id] = new
        back = self.link.at(new).read(servo_id, "baud_rate")
        if back != index:
            raise VerifyError(self.link.port, servo_id, "baud_rate", index, back)
        self._lock(servo_id, locked=True)


def outside_new_limits(
    link: Link, chain: ChainSettings, plan: ApplyPlan, diff: ChainDiff
) -> list[str]:
    """One line per servo whose Present Position lies outside the position limits ``plan`` writes.

    Such a servo cannot hold where it stands once torque is on (a goal there is refused; the
    backend refuses to start), so the user should move the joint inside by hand first.
    """
    changing = {
        s.servo_id for s in plan.steps if s.setting is not None and s.setting.key in LIMIT_KEYS
    }
    notes = []
    for wanted in chain.servos:
        if wanted.servo_id not in changing:
            continue
        low, high = (wanted.get(key) for key in LIMIT_KEYS)
        bus = link.at(diff.servos[wanted.servo_id].baud)
        present = bus.read(wanted.servo_id, "present_position")
        if low.raw <= present <= high.raw:
            continue
        angle = ticks_to_rad(present, ticks=bus.table.specs.ticks)
        lo_text, unit = low.show(low.raw)
        hi_text, _ = high.show(high.raw)
        notes.append(
            f"servo {wanted.servo_id} stands at {angle:.3f} rad from centre (tick {present}), "
            f"outside the Min/Max Position Limit {lo_text}..{hi_text} {unit or 'ticks'} about to "
            "be written: with torque on it cannot hold there (`snakebot run` refuses to start). "
            "Move the joint inside by hand (torque is off) before running"
        )
    return notes


def apply(
    link: Link,
    chain: ChainSettings,
    plan: ApplyPlan,
    diff: ChainDiff,
    on_step: Callable[[Step], None] | None = None,
) -> ChainDiff:
    """Run ``plan`` (from ``plan_apply(chain, diff)``), then diff again; SetupError unless empty."""
    for note in outside_new_limits(link, chain, plan, diff):
        warnings.warn(note, PositionOutsideLimitsWarning, stacklevel=2)
    applier = Applier(link, diff)
    for step in plan.steps:
        if on_step is not None:
            on_step(step)
        applier.run(step)
    after = survey(link, chain)
    if not after.identical:
        left = "; ".join(
            f"servo {d.servo_id} {d.key} {d.current} != {d.wanted}" for d in after.differences
        )
        raise SetupError(f"{link.port}: settings still differ after apply: {left}")
    return after
