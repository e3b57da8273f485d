"""`--backend` and its option flags come from the backend registry: a flag the chosen backend
does not take is a usage error naming it, never silently ignored."""

from __future__ import annotations

import pytest

from snakebot.cli.main import main


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["run", "--backend", "twin", "--port", "/dev/ttyUSB0"],
            "--port does nothing with the twin",
        ),
        (["run", "--backend", "sim", "--baud", "57600"], "--baud does nothing with the twin"),
        (["run", "--allow-extra-servos"], "--allow-extra-servos does nothing with the twin"),
        (
            ["run", "--backend", "dynamixel", "--robot", "snake12", "--friction", "0.1,1"],
            "--friction does nothing with the dynamixel backend",
        ),
        (
            ["run", "--backend", "dynamixel", "--robot", "snake12", "--realtime"],
            "--realtime does nothing with the dynamixel backend",
        ),
        (
            ["drive", "--backend", "sim", "--port", "/dev/ttyUSB0", "--script", "keys.txt"],
            "--port does nothing with the twin backend",
        ),
        (
            ["tune", "gains", "--backend", "twin", "--port", "/dev/ttyUSB0"],
            "--port does nothing with the twin",
        ),
        (
            ["sysid", "--record", "x.csv", "--backend", "twin", "--port", "/dev/ttyUSB0"],
            "--port does nothing",
        ),
        # --port alone means the servo chain of the robot's vendor: it needs the robot named.
        (["run", "--port", "/dev/ttyUSB0"], "drives real servos: name their robot with --robot"),
    ],
)
def test_a_flag_the_backend_does_not_take_is_a_usage_error(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_an_unknown_backend_is_a_usage_error_listing_the_choices(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["run", "--backend", "gazebo"]) == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'gazebo'" in err and "twin" in err and "dynamixel" in err


def test_bad_option_values_name_the_flag(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--friction", "slippery", "--duration", "0.1"]) == 2  # usage
    assert "--friction: expected AXIAL,LATERAL" in capsys.readouterr().err
    assert main(["run", "--terrain", "moon", "--duration", "0.1"]) == 2
    assert "--terrain: expected one of flat, slope" in capsys.readouterr().err


def test_a_viewer_on_hardware_is_refused_for_what_it_is(capsys: pytest.CaptureFixture[str]) -> None:
    # --viewer paces a simulation to the wall clock; on hardware it must not turn into a
    # complaint about --realtime, a flag the user never gave
    assert main(["run", "--backend", "dynamixel", "--robot", "snake12", "--viewer"]) == 2
    err = capsys.readouterr().err
    assert "--viewer: renders the simulation: it needs a simulated backend" in err
    assert "--realtime" not in err


@pytest.mark.parametrize(
    ("robot", "backend"), [("snake12-sts3215", "feetech"), ("snake12", "dynamixel")]
)
def test_port_alone_picks_the_backend_of_the_robots_servo_vendor(
    robot: str, backend: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", "--robot", robot, "--port", "/dev/ttyUSB0", "--dry-run", "--json"]
    assert main(argv) == 0
    assert f'"backend": "{backend}"' in capsys.readouterr().out


def test_the_dynamixel_backend_refuses_a_feetech_robot_naming_the_right_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["run", "--robot", "snake12-sts3215", "--backend", "dynamixel", "--port", "/dev/null"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "snake12-sts3215.toml: servo: STS3215 is a Feetech servo, not a Dynamixel one" in err
    assert "runs on the feetech backend" in err
