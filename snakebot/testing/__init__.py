"""Test helpers that ship with snakebot, for code built on it (plugins, third-party backends).

:class:`BackendContract` is the conformance suite every backend passes: the twin, the Dynamixel
chain (over the emulator), the soft body, and any backend a plugin registers. It needs pytest
(``pip install 'snakebot[test]'``); importing this package without it raises ImportError.
"""

from snakebot.testing.contract import BackendContract, RobotFactory

__all__ = ["BackendContract", "RobotFactory"]
