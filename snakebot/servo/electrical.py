"""The servos' electrical side in the twin: current draw, supply sag, energy, overload protection.

A Dynamixel is a DC motor behind an H-bridge. At the output shaft its torque constant is
kt = tau_stall / I_stall and its winding resistance R = V_nom / I_stall (the datasheet's stall
point), so a servo giving torque tau draws I = tau / kt and turns I^2 R into heat on top of the
mechanical power tau * omega. The supply (a battery's internal resistance R_b) then sits at
V = V_supply - R_b * sum|I|, and the torque-speed line scales with V: stall torque and the gains
by V / V_supply. The overload protection turns a servo's torque off when it has pushed at its
torque limit without moving for ``overload_trip_s``. Each part is on only when its key is set
(ServoExtras); docs/physics.md.
"""

from __future__ import annotations

import numpy as np

from snakebot.config.schema import ServoPhysics

GRAVITY_M_S2 = 9.81
STALL_TORQUE_FRACTION = 0.95
STALL_SPEED_FRACTION = 0.05


class ServoElectrics:
    """Per control period: currents, supply voltage, energies and overload timers of N servos.

    ``torque_limit_nm`` and ``no_load_speed_rad_s`` are at the supply voltage.
    """

    def __init__(
        self,
        physics: ServoPhysics,
        joint_count: int,
        torque_limit_nm: float,
        no_load_speed_rad_s: float,
    ) -> None:
        extras = physics.extras
        self.supply_voltage_v = physics.supply_voltage_v
        self.voltage_v = physics.supply_voltage_v
        self.metered = extras.stall_current_a is not None
        stall_current = extras.stall_current_a or 1.0
        self.torque_constant_nm_per_a = physics.stall_torque_nm / stall_current
        self.resistance_ohm = physics.nominal_voltage_v / stall_current
        self.battery_resistance_ohm = extras.battery_resistance_ohm
        self.trip_s = extras.overload_trip_s
        self._torque_limit = torque_limit_nm
        self._no_load = no_load_speed_rad_s
        self._stall_s = np.zeros(joint_count)
        self.tripped = np.zeros(joint_count, dtype=bool)
        self.restart_account()

    def restart_account(self) -> None:
        """Count energy, charge, peak current and the lowest voltage from now on; the servos'
        state (supply voltage, overload timers, trips) stays as it is."""
        self.electrical_energy_j = 0.0
        self.copper_loss_j = 0.0
        self.mechanical_energy_j = 0.0
        self.peak_current_a = 0.0
        self.charge_c = 0.0
        self.time_s = 0.0
        self.lowest_voltage_v = self.voltage_v

    @property
    def voltage_ratio(self) -> float:
        """Supply voltage now over the nominal supply: what scales torque and gains."""
        return self.voltage_v / self.supply_voltage_v

    def update(
        self, torque_nm: np.ndarray, drive_nm: np.ndarray, velocity_rad_s: np.ndarray, dt_s: float
    ) -> np.ndarray:
        """Account one period; return the joints (N,) whose overload protection trips now.

        ``torque_nm`` is each servo's output torque, ``drive_nm`` the drive before back-EMF
        (the actuator force, what the torque limit clips), ``velocity_rad_s`` the joint speeds.
        """
        self.time_s += dt_s
        if self.metered:
            current = np.abs(torque_nm) / self.torque_constant_nm_per_a
            copper = current * current * self.resistance_ohm
            mechanical = torque_nm * velocity_rad_s
            power = np.maximum(copper + mechanical, 0.0)  # the H-bridge does not feed back
            total = float(current.sum())
            self.electrical_energy_j += float(power.sum()) * dt_s
            self.copper_loss_j += float(copper.sum()) * dt_s
            self.mechanical_energy_j += float(np.maximum(mechanical, 0.0).sum()) * dt_s
            self.peak_current_a = max(self.peak_current_a, total)
            self.charge_c += total * dt_s
            if self.battery_resistance_ohm is not None:
                sag = self.battery_resistance_ohm * total
                self.voltage_v = max(self.supply_voltage_v - sag, 0.0)
                self.lowest_voltage_v = min(self.lowest_voltage_v, self.voltage_v)
        if self.trip_s is None:
            return np.zeros_like(self.tripped)
        limit = STALL_TORQUE_FRACTION * self._torque_limit * self.voltage_ratio
        stalled = (np.abs(drive_nm) >= limit) & (
            np.abs(velocity_rad_s) < STALL_SPEED_FRACTION * self._no_load
        )
        self._stall_s = np.where(stalled & ~self.tripped, self._stall_s + dt_s, 0.0)
        trips = (self._stall_s >= self.trip_s - 1e-9) & ~self.tripped
        self.tripped |= trips
        return trips

    def reset(self, joints: np.ndarray) -> None:
        """Clear the overload of ``joints`` (bool (N,)), as a reboot does."""
        self.tripped &= ~joints
        self._stall_s[joints] = 0.0

    def summary(self, mass_kg: float, distance_m: float) -> dict[str, object]:
        """JSON-ready electrical figures; the cost of transport over ``distance_m``."""
        out: dict[str, object] = {}
        if self.metered:
            out.update(
                electrical_energy_j=self.electrical_energy_j,
                copper_loss_j=self.copper_loss_j,
                mechanical_energy_j=self.mechanical_energy_j,
                mean_current_a=self.charge_c / self.time_s if self.time_s > 0 else 0.0,
                peak_current_a=self.peak_current_a,
                electrical_cost_of_transport=(
                    self.electrical_energy_j / (mass_kg * GRAVITY_M_S2 * distance_m)
                    if distance_m > 1e-9
                    else None
                ),
            )
        if self.battery_resistance_ohm is not None:
            out["lowest_supply_voltage_v"] = self.lowest_voltage_v
        if self.trip_s is not None:
            out["overload_tripped_joints"] = np.flatnonzero(self.tripped).tolist()
        return out
