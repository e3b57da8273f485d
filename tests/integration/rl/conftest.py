"""The learning tests need the ``rl`` extra (gymnasium); the ones that train need the
``rl-train`` extra (stable-baselines3 and torch) as well. .ci/run installs both; without them (a
contributor's plain ``.[test]`` venv) the tests they need are left out of collection, not
failed, and the rest still run."""

import importlib.util


def _missing(*modules: str) -> bool:
    return any(importlib.util.find_spec(m) is None for m in modules)


# Files that train a policy (stable-baselines3, torch); every other one needs gymnasium only.
TRAINING = ["test_rl_cli.py", "test_rl_train.py", "test_rl_compare_ray.py"]
if _missing("gymnasium"):
    collect_ignore_glob = ["test_*.py"]
elif _missing("stable_baselines3", "torch"):
    collect_ignore_glob = TRAINING
else:
    collect_ignore_glob = []
