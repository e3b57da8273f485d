"""Feetech STS/SCS servos on the chain backend: only ``sdk.py`` imports ``scservo_sdk``.

The chain backend (``snakebot.backends.chain``: bus, read plans, stopping, supervision) is
shared; :func:`snakebot.backends.chain.links.link_for` gives it a Feetech link for a servo
whose family's vendor is ``"feetech"``. The backend name ``"feetech"`` is registered beside
``"dynamixel"`` (``snakebot.backends.registry``).
"""
