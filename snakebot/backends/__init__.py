"""Backends behind one contract (base.py): the MuJoCo twin and the Dynamixel chain."""

from snakebot.backends.offscreen_gl import choose_offscreen_gl

# Before any backend module imports mujoco, which reads MUJOCO_GL only then: headless Linux
# renders offscreen (--video, mujoco.Renderer) with nothing set. Imports nothing heavy.
choose_offscreen_gl()
