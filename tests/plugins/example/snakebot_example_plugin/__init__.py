"""An example snakebot plugin: a standing-wave gait (entry-point group ``snakebot.gaits``), a
kinematic backend (``snakebot.backends``) and a ridges terrain (``snakebot.terrains``)."""
