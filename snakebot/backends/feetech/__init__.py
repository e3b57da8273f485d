"""Feetech STS/SCS servos on the chain backend: only ``sdk.py`` imports ``scservo_sdk``.

The chain backend (``snakebot.backends.dynamixel``: bus, read plans, stopping, supervision) is
shared; :func:`snakebot.backends.dynamixel.links.link_for` gives it a Feetech link for a servo
whose family's vendor is ``"feetech"``. The backend name ``"feetech"`` is registered beside
``"dynamixel"`` (``snakebot.backends.registry``).
"""
