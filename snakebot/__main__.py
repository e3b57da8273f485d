"""``python -m snakebot`` runs the command-line interface."""

import sys

try:
    from snakebot.cli.main import entry_point

    entry_point()
except KeyboardInterrupt:  # Ctrl-C before entry_point's own handler is in place: no traceback
    print("snakebot: interrupted", file=sys.stderr)
    exec("")  # clears CPython's unhandled-interrupt flag: see cli.main.forget_unhandled_interrupt
    sys.exit(130)
