"""The output rule's two checks: an existing output is refused unless --force says so."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from snakebot.cli.common import check_robot_copy, refuse_replacing, refuse_replacing_in
from snakebot.errors import OutputError, OutputExistsError


def test_an_existing_file_is_refused_and_left_as_it_was(tmp_path: Path) -> None:
    path = tmp_path / "drive.mcap"
    path.write_bytes(b"recording")
    with pytest.raises(OutputExistsError) as caught:
        refuse_replacing(path, "MCAP file", force=False)
    assert isinstance(caught.value, OutputError)  # exit 1, like every output problem
    assert str(path) in str(caught.value) and "--force" in str(caught.value)
    assert path.read_bytes() == b"recording"


def test_a_new_file_or_force_goes_ahead(tmp_path: Path) -> None:
    refuse_replacing(tmp_path / "new.csv", "log", force=False)
    existing = tmp_path / "old.csv"
    existing.write_text("t\n")
    refuse_replacing(existing, "log", force=True)
    assert not (tmp_path / "new.csv").exists()


def test_a_folder_is_refused_only_for_the_files_it_would_replace(tmp_path: Path) -> None:
    refuse_replacing_in(tmp_path / "missing", ["policy.zip"], "policy", force=False)
    (tmp_path / "notes.txt").write_text("mine")
    refuse_replacing_in(tmp_path, ["policy.zip", "policy.json"], "policy", force=False)
    (tmp_path / "policy.json").write_text("{}")
    with pytest.raises(OutputExistsError, match=r"policy\.json"):
        refuse_replacing_in(tmp_path, ["policy.zip", "policy.json"], "policy", force=False)
    refuse_replacing_in(tmp_path, ["policy.json"], "policy", force=True)


def test_a_device_is_written_to_not_replaced() -> None:
    refuse_replacing(Path("/dev/null"), "log", force=False)  # nothing there to lose


def test_out_naming_the_robot_file_itself_writes_into_it(tmp_path: Path) -> None:
    """calibrate/tune gains/sysid: `--out FILE` that is the robot file (`--robot FILE`, or the
    copy `--robot NAME` found) says to write into it; another existing FILE is refused."""
    robot = tmp_path / "snake12.toml"
    robot.write_text("[bus]\n")
    check_robot_copy(argparse.Namespace(out=robot, force=False), robot)
    copy = tmp_path / "copy.toml"
    copy.write_text("mine")
    with pytest.raises(OutputExistsError, match=r"copy\.toml"):
        check_robot_copy(argparse.Namespace(out=copy, force=False), robot)
    check_robot_copy(argparse.Namespace(out=copy, force=True), robot)
    check_robot_copy(argparse.Namespace(out=None, force=False), robot)
    assert copy.read_text() == "mine"
