"""``python -m snakebot`` runs the command-line interface."""

from snakebot.cli.main import entry_point

entry_point()
