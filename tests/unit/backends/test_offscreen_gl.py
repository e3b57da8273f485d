"""MuJoCo's offscreen platform is chosen before mujoco is imported: EGL, else OSMesa, and only
when nothing chose one and there is no display."""

from __future__ import annotations

import pytest

from snakebot.backends.offscreen_gl import choose_offscreen_gl


def libraries(*present: str) -> object:
    return lambda name: f"lib{name}.so.1" if name in present else None


@pytest.mark.parametrize(
    ("environ", "present", "chosen"),
    [
        ({}, ("EGL", "OSMesa"), "egl"),
        ({}, ("OSMesa",), "osmesa"),
        ({"MUJOCO_GL": ""}, ("EGL",), "egl"),  # empty is MuJoCo's default, not a choice
        ({}, (), None),  # neither installed: leave MuJoCo's default and its own error
        ({"MUJOCO_GL": "osmesa"}, ("EGL",), None),  # the user's choice wins
        ({"DISPLAY": ":0"}, ("EGL",), None),  # a display: GLFW works, the viewer needs it
        ({"WAYLAND_DISPLAY": "wayland-0"}, ("EGL",), None),
    ],
)
def test_choice(environ: dict[str, str], present: tuple[str, ...], chosen: str | None) -> None:
    env = dict(environ)
    assert choose_offscreen_gl(env, platform="linux", find_library=libraries(*present)) == chosen
    if chosen is not None:
        assert env["MUJOCO_GL"] == chosen and env["PYOPENGL_PLATFORM"] == chosen
    else:
        assert env == environ


@pytest.mark.parametrize("platform", ["darwin", "win32"])
def test_other_systems_keep_mujocos_default(platform: str) -> None:
    env: dict[str, str] = {}
    assert choose_offscreen_gl(env, platform=platform, find_library=libraries("EGL")) is None
    assert env == {}
