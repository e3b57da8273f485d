"""``python -m snakebot.cluster.raycli ARGS``: Ray's own ``ray ARGS`` command, with loopback kept.

``ray start --node-ip-address 127.0.0.1`` and ``ray start --address 127.0.0.1:PORT`` both pass
through ``resolve_ip_for_localhost``, which on Linux swaps 127.0.0.1 for the machine's outward
address (Ray 2.60); a cluster meant to talk only over loopback then binds and dials that address.
This runs the unmodified Ray command line with that one swap switched off
(snakebot.cluster.session.keep_loopback); every other argument means what it means to ``ray``.
"""

from __future__ import annotations

import sys

from snakebot.cluster.session import keep_loopback, require_ray


def main(argv: list[str] | None = None) -> int:
    """Run ``ray`` with ``argv`` (default ``sys.argv[1:]``); returns its exit status."""
    require_ray()
    from ray.scripts.scripts import cli

    with keep_loopback():
        try:
            cli.main(args=sys.argv[1:] if argv is None else argv, prog_name="ray")
        except SystemExit as done:
            return done.code if isinstance(done.code, int) else int(done.code is not None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
