"""snakebot: one controller for Dynamixel servo snakes and their MuJoCo twin."""

__version__ = "0.1.0"
