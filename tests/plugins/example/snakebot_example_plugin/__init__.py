"""An example snakebot plugin: a standing-wave gait, found through the ``snakebot.gaits`` group."""
