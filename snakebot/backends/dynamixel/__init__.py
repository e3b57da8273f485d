"""Dynamixel servos on the servo chain (:mod:`snakebot.backends.chain`): ``sdk.py`` is the one
module that imports ``dynamixel_sdk``."""
