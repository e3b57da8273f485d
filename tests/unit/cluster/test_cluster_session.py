"""snakebot.cluster without a cluster: addresses, the missing-Ray message, a light import."""

from __future__ import annotations

import subprocess
import sys

import pytest

from snakebot.cluster import INSTALL, is_loopback, require_ray
from snakebot.errors import ClusterError, MissingDependencyError


@pytest.mark.parametrize(
    ("address", "loopback"),
    [
        ("127.0.0.1:6379", True),
        ("127.0.0.1", True),
        ("127.3.4.5:10", True),
        ("localhost:6379", True),
        ("[::1]:6379", True),
        ("::1", True),
        ("10.0.0.5:6379", False),
        ("head.cluster.lab:6379", False),
        ("auto", False),
    ],
)
def test_loopback_addresses_are_told_apart(address: str, loopback: bool) -> None:
    assert is_loopback(address) is loopback


def test_a_missing_ray_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray now raises ImportError
    with pytest.raises(MissingDependencyError, match=r"snakebot\[cluster\]") as caught:
        require_ray()
    assert INSTALL in str(caught.value)


def test_importing_the_cluster_package_does_not_import_ray() -> None:
    code = "import sys, snakebot.cluster; assert 'ray' not in sys.modules, 'ray imported'"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_cluster_errors_say_which_cluster() -> None:
    assert "the Ray cluster at 10.0.0.5:6379: gone" in str(ClusterError("10.0.0.5:6379", "gone"))
    assert str(ClusterError(None, "gone")).startswith("Ray on this machine")
    assert isinstance(ClusterError(None, "x"), ConnectionError)


def test_keep_loopback_switches_the_rewrite_off_only_inside_the_block() -> None:
    pytest.importorskip("ray")
    from ray._private import services

    from snakebot.cluster import keep_loopback

    original = services.resolve_ip_for_localhost
    with keep_loopback():
        assert services.resolve_ip_for_localhost("127.0.0.1") == "127.0.0.1"
        assert services.canonicalize_bootstrap_address("127.0.0.1:6390") == "127.0.0.1:6390"
    assert services.resolve_ip_for_localhost is original
