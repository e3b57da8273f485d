"""A corpus of malformed robot files (and the servo files they name): every field, every rule.

Each case edits a copy of snake12 (or its servo file, servos/xl430-w250.toml) and must be refused
with a ConfigError that names the edited file and the key path where the bad value is written.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

from snakebot.config import load_robot
from snakebot.config.bounds import ROBOT, SERVO
from snakebot.errors import ConfigError

ROBOT_FILE = Path("robots") / "snake12.toml"
SERVO_FILE = Path("servos") / "xl430-w250.toml"

Edit = Callable[[str], str | bytes] | tuple[str, str]


@dataclass(frozen=True)
class Case:
    """One malformed file: which file, the edit, the key the error names, a part of its reason."""

    name: str
    file: Path
    edit: Edit
    key: str
    reason: str


def robot(name: str, old: str, new: str, key: str, reason: str) -> Case:
    return Case(name, ROBOT_FILE, (old, new), key, reason)


def servo(name: str, old: str, new: str, key: str, reason: str) -> Case:
    return Case(name, SERVO_FILE, (old, new), key, reason)


def twin_servo(name: str, line: str, key: str, reason: str) -> Case:
    return robot(name, "[joint_defaults]", f"[twin.servo]\n{line}\n\n[joint_defaults]", key, reason)


def without_joints(text: str) -> str:
    """The robot file up to its first ``[[joints]]`` table."""
    return text[: text.index("\n[[joints]]") + 1]


def joints(count: int) -> Callable[[str], str]:
    def edit(text: str) -> str:
        head = without_joints(text)
        body = "".join(f'[[joints]]\nservo_id = {i + 1}\naxis = "yaw"\n\n' for i in range(count))
        return head + body

    return edit


RANGE = "expected a number in"
REGISTER_GAINS = "position_p = 640\nposition_i = 0\nposition_d = 4000"
INT_RANGE = "expected an integer in"

CASES = [
    # -- the file itself and its top level -----------------------------------------------------
    Case("binary robot file", ROBOT_FILE, lambda t: b"\x00\xff\xfe" + t.encode(), "", "not UTF-8"),
    Case(
        "latin-1 robot file",
        ROBOT_FILE,
        lambda t: ("# Müller's snake\n" + t).encode("latin-1"),
        "",
        "not UTF-8",
    ),
    robot("not TOML", "[bus]", "[bus", "", "not valid TOML"),
    robot("empty name", 'name = "snake12"', 'name = ""', "name", "non-empty"),
    robot("name not a string", 'name = "snake12"', "name = 12", "name", "expected a string"),
    # Names are printed back: no bidirectional override, no control character, bounded length.
    robot(
        "right-to-left override in the name",
        'name = "snake12"',
        'name = "snake\u202e21"',
        "name",
        "U+202E",
    ),
    robot(
        "500 kB name",
        'name = "snake12"',
        'name = "' + "a" * 500_000 + '"',
        "name",
        "at most 128 characters",
    ),
    robot(
        "5 MB name (the file is too big to read)",
        'name = "snake12"',
        'name = "' + "a" * 5_000_000 + '"',
        "",
        "larger than a TOML config file may be",
    ),
    robot("C1 control in the name", 'name = "snake12"', 'name = "snake\u009b12"', "name", "U+009B"),
    robot(
        "zero-width space in the name",
        'name = "snake12"',
        'name = "snake\u200b12"',
        "name",
        "U+200B",
    ),
    robot(
        "line separator in the name", 'name = "snake12"', 'name = "snake\u202812"', "name", "U+2028"
    ),
    robot(
        "100 kB port",
        'port = "/dev/ttyUSB0"',
        'port = "/dev/' + "a" * 100_000 + '"',
        "bus.port",
        "at most 4096 characters",
    ),
    robot(
        "bidirectional override in the servo",
        'servo = "XL430-W250"',
        'servo = "XL430\u202e-W250"',
        "servo",
        "U+202E",
    ),
    robot(
        "integer beyond any float",
        "mass_kg = 0.085",
        "mass_kg = " + "9" * 400,
        "link.mass_kg",
        "finite",
    ),
    robot(
        "deeply nested array",
        'name = "snake12"',
        'name = "snake12"\nx = ' + "[" * 5000 + "]" * 5000,
        "",
        "nested too deeply",
    ),
    robot("unknown servo", 'servo = "XL430-W250"', 'servo = "XL999"', "servo", "xl999.toml"),
    robot(
        "servo path",
        'servo = "XL430-W250"',
        'servo = "../../etc/passwd"',
        "servo",
        "expected a servo model name",
    ),
    robot(
        "servo not a string", 'servo = "XL430-W250"', "servo = 430", "servo", "expected a string"
    ),
    robot(
        "unknown top-level key",
        'name = "snake12"',
        'name = "snake12"\ncolour = "red"',
        "colour",
        "unknown key",
    ),
    robot("unknown table", "[safety]", "[wheels]\ncount = 4\n\n[safety]", "wheels", "unknown key"),
    # -- [bus] ---------------------------------------------------------------------------------
    robot(
        "socket URL port",
        'port = "/dev/ttyUSB0"',
        'port = "socket://10.0.0.1:7"',
        "bus.port",
        "not a serial port",
    ),
    robot(
        "spy URL port",
        'port = "/dev/ttyUSB0"',
        'port = "spy:///dev/ttyUSB0?file=x"',
        "bus.port",
        "not a serial port",
    ),
    robot(
        "emulator URL port",
        'port = "/dev/ttyUSB0"',
        'port = "dxlemu://bus0"',
        "bus.port",
        "only as a port given directly",
    ),
    robot("empty port", 'port = "/dev/ttyUSB0"', 'port = ""', "bus.port", "non-empty"),
    robot(
        "port not a string", 'port = "/dev/ttyUSB0"', "port = 0", "bus.port", "expected a string"
    ),
    robot("odd baud", "baud = 1000000", "baud = 1000001", "bus.baud", "expected one of"),
    robot("baud as text", "baud = 1000000", 'baud = "fast"', "bus.baud", "expected an integer"),
    robot(
        "protocol 3",
        "protocol = 2.0",
        "protocol = 3.0",
        "bus.protocol",
        "speak Protocol 2.0, 1.0 only",
    ),
    Case(
        "protocol 1 on servos without it",
        ROBOT_FILE,
        lambda text: text.replace('servo = "XL430-W250"', 'servo = "XL330-M288"').replace(
            "protocol = 2.0", "protocol = 1.0"
        ),
        "bus.protocol",
        "XL330-M288 servos speak Protocol 2.0 only",
    ),
    robot(
        "a baud the model lacks", "baud = 1000000", "baud = 500000", "bus.baud", "expected one of"
    ),
    robot(
        "unknown bus key",
        "protocol = 2.0",
        'protocol = 2.0\nparity = "N"',
        "bus.parity",
        "unknown key",
    ),
    robot("no bus", "[bus]", "[bus_]", "bus", "missing"),
    # -- [link] --------------------------------------------------------------------------------
    robot("zero length", "length_m = 0.065", "length_m = 0", "link.length_m", RANGE),
    robot("huge length", "length_m = 0.065", "length_m = 1e308", "link.length_m", RANGE),
    robot("tiny radius", "radius_m = 0.022", "radius_m = 1e-300", "link.radius_m", RANGE),
    robot(
        "radius too big for the module",
        "radius_m = 0.022",
        "radius_m = 0.05",
        "link.radius_m",
        "does not fit",
    ),
    robot("huge mass", "mass_kg = 0.085", "mass_kg = 1e308", "link.mass_kg", RANGE),
    robot("tiny mass", "mass_kg = 0.085", "mass_kg = 1e-300", "link.mass_kg", RANGE),
    robot("negative mass", "mass_kg = 0.085", "mass_kg = -1", "link.mass_kg", RANGE),
    robot("nan mass", "mass_kg = 0.085", "mass_kg = nan", "link.mass_kg", "finite"),
    robot(
        "mass as text", "mass_kg = 0.085", 'mass_kg = "light"', "link.mass_kg", "expected a number"
    ),
    robot("no mass", "mass_kg = 0.085", "", "link.mass_kg", "missing"),
    robot(
        "unknown link key",
        "mass_kg = 0.085",
        "mass_kg = 0.085\nmaterial = 1",
        "link.material",
        "unknown key",
    ),
    # -- [gains] -------------------------------------------------------------------------------
    robot(
        "P gain beyond the register",
        "position_p = 640",
        "position_p = 20000",
        "gains.position_p",
        INT_RANGE,
    ),
    robot("negative I gain", "position_i = 0", "position_i = -1", "gains.position_i", INT_RANGE),
    robot(
        "fractional D gain",
        "position_d = 4000",
        "position_d = 40.5",
        "gains.position_d",
        "expected an integer",
    ),
    robot(
        "unknown gain",
        "position_d = 4000",
        "position_d = 4000\nposition_q = 3",
        "gains.position_q",
        "unknown key",
    ),
    robot(
        "gains as registers and in SI",
        "position_d = 4000",
        "position_d = 4000\nkp_nm_per_rad = 2.0",
        "gains.kp_nm_per_rad",
        "not both",
    ),
    robot(
        "SI stiffness beyond the P register",
        REGISTER_GAINS,
        "kp_nm_per_rad = 1000.0",
        "gains.kp_nm_per_rad",
        RANGE,
    ),
    robot(
        "negative SI damping",
        REGISTER_GAINS,
        "kp_nm_per_rad = 2.0\nkd_nms_per_rad = -0.1",
        "gains.kd_nms_per_rad",
        RANGE,
    ),
    robot(
        "SI I gain beyond the register",
        REGISTER_GAINS,
        "kp_nm_per_rad = 2.0\nposition_i = 16384",
        "gains.position_i",
        INT_RANGE,
    ),
    # -- [settings] and joints[].settings ------------------------------------------------------
    robot(
        "misspelt setting",
        "[settings]",
        "[settings]\nshutdwn = 1",
        "settings.shutdwn",
        "did you mean shutdown",
    ),
    robot(
        "setting out of range",
        "[settings]",
        "[settings]\nreturn_delay_time_us = 99999",
        "settings.return_delay_time_us",
        "is outside",
    ),
    robot(
        "setting the tools own",
        "[settings]",
        "[settings]\nid = 3",
        "settings.id",
        "comes from the robot file",
    ),
    robot(
        "setting as text",
        "[settings]",
        '[settings]\nshutdown = "52"',
        "settings.shutdown",
        "expected a number",
    ),
    robot(
        "setting nan",
        "[settings]",
        "[settings]\ntemperature_limit_c = nan",
        "settings.temperature_limit_c",
        "finite",
    ),
    robot(
        "setting a wrong unit",
        "[settings]",
        "[settings]\nshutdown_ms = 1",
        "settings.shutdown_ms",
        "does not fit",
    ),
    robot(
        "joint setting unknown",
        "servo_id = 2\n",
        "servo_id = 2\nsettings = { bogus = 1 }\n",
        "joints[1].settings.bogus",
        "bogus",
    ),
    # -- [safety] ------------------------------------------------------------------------------
    robot("endless ramp", "ramp_s = 1.0", "ramp_s = 1e308", "safety.ramp_s", RANGE),
    robot("negative ramp", "ramp_s = 1.0", "ramp_s = -1", "safety.ramp_s", RANGE),
    robot(
        "zero speed",
        "max_speed_fraction = 0.9",
        "max_speed_fraction = 0",
        "safety.max_speed_fraction",
        RANGE,
    ),
    robot(
        "speed above no-load",
        "max_speed_fraction = 0.9",
        "max_speed_fraction = 1.5",
        "safety.max_speed_fraction",
        RANGE,
    ),
    robot(
        "unknown stop policy",
        'stop_policy = "hold"',
        'stop_policy = "coast"',
        "safety.stop_policy",
        "expected one of",
    ),
    robot(
        "unknown safety key",
        "ramp_s = 1.0",
        "ramp_s = 1.0\nbrake = true",
        "safety.brake",
        "unknown key",
    ),
    # -- [twin] --------------------------------------------------------------------------------
    robot("one-second timestep", "timestep_s = 0.002", "timestep_s = 1", "twin.timestep_s", RANGE),
    robot("tiny timestep", "timestep_s = 0.002", "timestep_s = 1e-300", "twin.timestep_s", RANGE),
    robot(
        "unknown ground", 'ground = "isotropic"', 'ground = "ice"', "twin.ground", "expected one of"
    ),
    robot(
        "negative friction",
        "axial_friction = 0.7",
        "axial_friction = -0.1",
        "twin.axial_friction",
        RANGE,
    ),
    robot(
        "huge friction",
        "lateral_friction = 0.7",
        "lateral_friction = 1e308",
        "twin.lateral_friction",
        RANGE,
    ),
    robot(
        "negative backward friction",
        "axial_friction = 0.7",
        "axial_friction = 0.7\nbackward_friction = -1",
        "twin.backward_friction",
        RANGE,
    ),
    robot(
        "unknown friction model",
        "axial_friction = 0.7",
        'axial_friction = 0.7\nfriction_model = "wheels"',
        "twin.friction_model",
        "expected one of",
    ),
    robot(
        "unknown twin key",
        "timestep_s = 0.002",
        "timestep_s = 0.002\ngravity = 9.8",
        "twin.gravity",
        "unknown key",
    ),
    twin_servo("zero stiffness", "stiffness_scale = 0", "twin.servo.stiffness_scale", RANGE),
    twin_servo("negative damping", "damping_nms = -1", "twin.servo.damping_nms", RANGE),
    twin_servo("huge armature", "armature_kgm2 = 1e308", "twin.servo.armature_kgm2", RANGE),
    twin_servo(
        "negative friction loss", "friction_loss_nm = -0.1", "twin.servo.friction_loss_nm", RANGE
    ),
    twin_servo("long delay", "actuator_delay_s = 0.5", "twin.servo.actuator_delay_s", RANGE),
    twin_servo("zero P divisor override", "p_gain_divisor = 0", "twin.servo.p_gain_divisor", RANGE),
    twin_servo(
        "unknown twin.servo key", "backlash_rad = 0.1", "twin.servo.backlash_rad", "unknown key"
    ),
    # -- [joint_defaults] ----------------------------------------------------------------------
    robot(
        "default lower limit above 0",
        "lower_rad = -1.5",
        "lower_rad = 0.5",
        "joint_defaults.lower_rad",
        RANGE,
    ),
    robot(
        "default upper limit beyond pi",
        "upper_rad = 1.5",
        "upper_rad = 4",
        "joint_defaults.upper_rad",
        RANGE,
    ),
    robot(
        "default direction 2",
        "direction = 1",
        "direction = 2",
        "joint_defaults.direction",
        "expected one of",
    ),
    robot(
        "default offset beyond pi",
        "zero_offset_rad = 0.0",
        "zero_offset_rad = 7",
        "joint_defaults.zero_offset_rad",
        RANGE,
    ),
    robot(
        "default servo ID",
        "[joint_defaults]",
        "[joint_defaults]\nservo_id = 1",
        "joint_defaults.servo_id",
        "set it per joint",
    ),
    robot(
        "unknown default",
        "[joint_defaults]",
        "[joint_defaults]\nstiffness = 1",
        "joint_defaults.stiffness",
        "unknown key",
    ),
    # -- [[joints]] ----------------------------------------------------------------------------
    robot(
        "duplicate ID",
        "servo_id = 3\n",
        "servo_id = 2\n",
        "joints[2].servo_id",
        "already used by joints[1]",
    ),
    robot("broadcast ID", "servo_id = 1\n", "servo_id = 254\n", "joints[0].servo_id", INT_RANGE),
    robot("negative ID", "servo_id = 1\n", "servo_id = -1\n", "joints[0].servo_id", INT_RANGE),
    robot("roll axis", 'axis = "pitch"', 'axis = "roll"', "joints[1].axis", "expected one of"),
    robot("no axis", 'servo_id = 1\naxis = "yaw"', "servo_id = 1", "joints[0].axis", "missing"),
    robot(
        "no servo ID", 'servo_id = 1\naxis = "yaw"', 'axis = "yaw"', "joints[0].servo_id", "missing"
    ),
    robot(
        "upper limit below 0",
        "servo_id = 1\n",
        "servo_id = 1\nupper_rad = -0.1\n",
        "joints[0].upper_rad",
        RANGE,
    ),
    robot(
        "no range",
        "servo_id = 1\n",
        "servo_id = 1\nlower_rad = 0.0\nupper_rad = 0.0\n",
        "joints[0].upper_rad",
        "upper_rad > lower_rad",
    ),
    robot(
        "unknown joint key",
        "servo_id = 1\n",
        "servo_id = 1\nspeed = 1\n",
        "joints[0].speed",
        "unknown key",
    ),
    Case("one joint", ROBOT_FILE, joints(1), "joints", "expected 2 to 64 joints"),
    Case("65 joints", ROBOT_FILE, joints(65), "joints", "expected 2 to 64 joints"),
    Case(
        "joints not tables",
        ROBOT_FILE,
        lambda t: "joints = 5\n" + without_joints(t),
        "joints",
        "array of tables",
    ),
    # -- the servo file ------------------------------------------------------------------------
    Case(
        "binary servo file",
        SERVO_FILE,
        lambda t: b"\x89PNG\r\n\x1a\n\x00\xff" + t.encode(),
        "",
        "not UTF-8",
    ),
    servo(
        "model without a control table",
        'model = "XL430-W250"',
        'model = "XL999"',
        "model",
        "no control table",
    ),
    servo(
        "model of another file",
        'model = "XL430-W250"',
        'model = "XM430-W350"',
        "model",
        "names model",
    ),
    servo(
        "model number in the servo file",
        'model = "XL430-W250"',
        'model = "XL430-W250"\nmodel_number = 1060',
        "model_number",
        "kept once",
    ),
    servo(
        "stall torque in the servo file",
        "[physics]",
        "[physics]\nstall_torque_nm = 1.4",
        "physics.stall_torque_nm",
        "kept once",
    ),
    servo(
        "no-load speed in the servo file",
        "[physics]",
        "[physics]\nno_load_speed_rad_s = 6",
        "physics.no_load_speed_rad_s",
        "kept once",
    ),
    servo(
        "nominal voltage in the servo file",
        "[physics]",
        "[physics]\nnominal_voltage_v = 12",
        "physics.nominal_voltage_v",
        "kept once",
    ),
    servo(
        "resolution in the servo file",
        "[physics]",
        "[physics]\nticks_per_rev = 4096",
        "physics.ticks_per_rev",
        "kept once",
    ),
    servo(
        "default gains in the servo file",
        "[settings]",
        "[default_gains]\nposition_p = 640\n\n[settings]",
        "default_gains",
        "kept once",
    ),
    servo(
        "zero P divisor",
        "p_gain_divisor = 256",
        "p_gain_divisor = 0",
        "physics.p_gain_divisor",
        RANGE,
    ),
    servo(
        "P divisor in the servo file's twin table",
        "[settings]",
        "[twin]\np_gain_divisor = 128\n\n[settings]",
        "twin.p_gain_divisor",
        "the P-gain divisor is physics.p_gain_divisor",
    ),
    servo(
        "huge D divisor",
        "d_gain_divisor = 32",
        "d_gain_divisor = 1e9",
        "physics.d_gain_divisor",
        RANGE,
    ),
    servo("no D divisor", "d_gain_divisor = 32", "", "physics.d_gain_divisor", "missing"),
    servo(
        "mains supply",
        "supply_voltage_v = 11.1",
        "supply_voltage_v = 230",
        "physics.supply_voltage_v",
        RANGE,
    ),
    servo(
        "negative armature",
        "armature_kgm2 = 0.002",
        "armature_kgm2 = -1",
        "physics.armature_kgm2",
        RANGE,
    ),
    servo(
        "huge friction loss",
        "friction_loss_nm = 0.03",
        "friction_loss_nm = 1e308",
        "physics.friction_loss_nm",
        RANGE,
    ),
    servo(
        "nan damping",
        "viscous_damping_nms = 0.004",
        "viscous_damping_nms = nan",
        "physics.viscous_damping_nms",
        "finite",
    ),
    servo(
        "PWM beyond the register",
        "pwm_limit = 885",
        "pwm_limit = 886",
        "physics.pwm_limit",
        "at most 885",
    ),
    servo(
        "zero D period",
        "d_gain_loop_period_s = 0.001",
        "d_gain_loop_period_s = 0",
        "physics.d_gain_loop_period_s",
        RANGE,
    ),
    servo(
        "unknown physics key",
        "pwm_limit = 885",
        "pwm_limit = 885\ngear_ratio = 258",
        "physics.gear_ratio",
        "unknown key",
    ),
    servo(
        "unknown servo setting", "[settings]", "[settings]\nbogus = 1", "settings.bogus", "bogus"
    ),
    servo(
        "unknown servo table",
        "[settings]",
        "[extras]\nnote = 1\n\n[settings]",
        "extras",
        "unknown key",
    ),
    servo(
        "unknown servo key",
        'model = "XL430-W250"',
        'model = "XL430-W250"\nvendor = "ROBOTIS"',
        "vendor",
        "unknown key",
    ),
]


def test_the_corpus_is_big_and_covers_every_documented_range() -> None:
    assert len(CASES) >= 47
    assert len({case.name for case in CASES}) == len(CASES)
    robot_keys = {
        re.sub(r"^(joint_defaults|joints\[\d+\])\.", "joints[].", c.key)
        for c in CASES
        if c.file == ROBOT_FILE
    }
    assert set(ROBOT) <= robot_keys
    assert set(SERVO) <= {c.key for c in CASES if c.file == SERVO_FILE}


def write(config_dir: Path, case: Case) -> Path:
    path = config_dir / case.file
    text = path.read_text(encoding="utf-8")
    if isinstance(case.edit, tuple):
        old, new = case.edit
        assert old in text, f"{old!r} not in {path}"
        edited: str | bytes = text.replace(old, new, 1)
    else:
        edited = case.edit(text)
    path.write_bytes(edited if isinstance(edited, bytes) else edited.encode())
    return path


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_malformed_file_is_refused_naming_file_and_key(config_dir: Path, case: Case) -> None:
    edited = write(config_dir, case)
    with pytest.raises(ConfigError) as info:
        load_robot(config_dir / ROBOT_FILE)
    error = info.value
    assert (error.source, error.key) == (str(edited), case.key), str(error)
    assert case.reason in error.reason, str(error)
    assert str(error).startswith(f"{edited}: {case.key}: " if case.key else f"{edited}: ")


def test_docs_list_every_range_as_the_code_has_it() -> None:
    docs = (Path(__file__).resolve().parents[3] / "docs" / "config.md").read_text(encoding="utf-8")
    for key, limits in {**ROBOT, **SERVO}.items():
        assert f"| `{key}` | {limits.describe()} | {limits.why} |" in docs, key


def test_docs_list_the_twin_servo_model_ranges() -> None:
    from snakebot.config.servos.twin import BOUNDS

    docs = (Path(__file__).resolve().parents[3] / "docs" / "config.md").read_text(encoding="utf-8")
    for key, limits in BOUNDS.items():
        for where in (f"twin.servo.{key}", f"twin.{key}"):
            assert f"| `{where}` | {limits.describe()} | {limits.why} |" in docs, where
