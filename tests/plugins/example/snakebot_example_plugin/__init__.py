"""An example snakebot plugin: a standing-wave gait (entry-point group ``snakebot.gaits``) and a
kinematic backend (``snakebot.backends``)."""
