"""``python -m snakebot`` runs the command-line interface."""

import sys

try:
    from snakebot.cli.main import entry_point
except KeyboardInterrupt:  # Ctrl-C while Python imports the CLI: no traceback for that either
    print("snakebot: interrupted", file=sys.stderr)
    sys.exit(130)

entry_point()
