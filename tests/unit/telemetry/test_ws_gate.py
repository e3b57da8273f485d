"""Which browser origins may open the live Foxglove stream, and the URLs printed for a host."""

from __future__ import annotations

import pytest

from snakebot.cli.main import main
from snakebot.cli.telemetry_options import client_url
from snakebot.telemetry.ws_gate import origin_allowed


@pytest.mark.parametrize(
    "origin",
    [
        None,
        "https://app.foxglove.dev",
        "https://app.foxglove.dev/",
        "http://localhost",
        "http://localhost:8080",
        "https://dev.localhost:3000",
        "http://127.0.0.1:5173",
        "http://127.5.6.7",
        "http://[::1]:8000",
        "HTTP://LOCALHOST",
    ],
)
def test_this_machine_and_foxglove_may_connect(origin: str | None) -> None:
    assert origin_allowed(origin)


@pytest.mark.parametrize(
    "origin",
    [
        "https://evil.example",
        "null",
        "",
        "http://localhost.evil.example",
        "http://127.0.0.1.evil.example",
        "https://app.foxglove.dev.evil.example",
        "http://app.foxglove.dev",
        "file://",
        "ws://localhost",
        "http://10.0.0.2",
        "http://[::2]",
        "http://[not-an-address",
        "http://0.0.0.0",
    ],
)
def test_other_sites_may_not(origin: str) -> None:
    assert not origin_allowed(origin)


def test_an_origin_the_user_names_may_connect_and_only_that_one() -> None:
    extra = ("https://viz.example.org",)
    assert origin_allowed("https://viz.example.org", extra)
    assert not origin_allowed("https://viz.example.org:444", extra)
    assert not origin_allowed("http://viz.example.org", extra)


@pytest.mark.parametrize(
    ("host", "url"),
    [
        ("127.0.0.1", "ws://127.0.0.1:8765"),
        ("0.0.0.0", "ws://127.0.0.1:8765"),
        ("::", "ws://[::1]:8765"),
        ("::1", "ws://[::1]:8765"),
        ("[::1]", "ws://[::1]:8765"),
        ("fe80::1", "ws://[fe80::1]:8765"),
        ("192.168.1.20", "ws://192.168.1.20:8765"),
        ("robot.local", "ws://robot.local:8765"),
    ],
)
def test_the_printed_url_is_one_a_client_can_open(host: str, url: str) -> None:
    assert client_url(host, 8765) == url


@pytest.mark.parametrize(
    ("option", "value", "expected"),
    [
        ("--foxglove-origin", "viz.example.org", "https://viz.example.org"),
        ("--foxglove-origin", "https://viz.example.org/page", "scheme://host"),
        ("--foxglove-max-clients", "0", "1-1000"),
        ("--foxglove-max-clients", "many", "number of clients"),
    ],
)
def test_a_bad_access_option_is_a_usage_error_naming_it(
    option: str, value: str, expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", "--duration", "1", "--foxglove=0", option, value]) == 2
    err = capsys.readouterr().err
    assert option in err and expected in err
