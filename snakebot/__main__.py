"""``python -m snakebot`` runs the command-line interface."""

import sys

from snakebot.cli.main import main

sys.exit(main())
