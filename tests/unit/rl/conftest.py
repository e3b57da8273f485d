"""snakebot.rl needs the ``rl`` extra (gymnasium), which .ci/run installs; without it only the
import tests (which check the message naming the extra) run here."""

import importlib.util

collect_ignore_glob = (
    ["test_rl_encodings.py", "test_rl_eval_table.py", "test_rl_sweep.py"]
    if importlib.util.find_spec("gymnasium") is None
    else []
)
