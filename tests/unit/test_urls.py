"""Server URLs: every part kept, every bad one a one-line reason, no token in clear to another host."""

import pytest

from arbiter_core.urls import (
    Endpoint,
    UrlError,
    check_token_transport,
    rosbridge_endpoint,
    tracker_beside,
    tracker_endpoint,
)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("ws://127.0.0.1:9090", Endpoint("ws", "127.0.0.1", 9090, "/")),
        ("ws://robot", Endpoint("ws", "robot", 9090, "/")),
        ("wss://robot.lan:8443/rosbridge", Endpoint("wss", "robot.lan", 8443, "/rosbridge")),
        ("ws://[::1]:9090/rb", Endpoint("ws", "::1", 9090, "/rb")),
    ],
)
def test_rosbridge_urls_keep_scheme_host_port_and_path(text, expected):
    got = rosbridge_endpoint(text)
    assert got == expected
    assert rosbridge_endpoint(got.url) == got


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("http://robot:9090", "must start with ws:// or wss://"),
        ("robot:9090", "must start with"),
        ("ws://:9090", "no host"),
        ("ws://robot:99999", "out of range"),
        ("ws://robot:abc", "robot:abc"),
        ("ws://robot:0", "port 0"),
        ("ws://robot:9090/?token=x", "no query"),
    ],
)
def test_bad_rosbridge_urls_are_one_line_errors(text, words):
    with pytest.raises(UrlError) as err:
        rosbridge_endpoint(text)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_tracker_urls_and_the_tracker_beside_a_bridge():
    assert tracker_endpoint("https://robot/api-root") == Endpoint("https", "robot", 8085, "/api-root")
    with pytest.raises(UrlError, match="http:// or https://"):
        tracker_endpoint("ws://robot:8085")
    assert tracker_beside(rosbridge_endpoint("ws://10.0.0.5:9090/rb")).url == "http://10.0.0.5:8085/"
    assert tracker_beside(rosbridge_endpoint("wss://robot.lan")).url == "https://robot.lan:8085/"


def test_a_token_goes_in_clear_only_to_this_machine():
    token = "x" * 24
    check_token_transport(rosbridge_endpoint("ws://127.0.0.1:9090"), "--rosbridge", token)
    check_token_transport(rosbridge_endpoint("wss://robot:9090"), "--rosbridge", token)
    check_token_transport(rosbridge_endpoint("ws://robot:9090"), "--rosbridge", None)  # no token: fine
    with pytest.raises(UrlError, match="use wss:// or use an SSH tunnel"):
        check_token_transport(rosbridge_endpoint("ws://robot:9090"), "--rosbridge", token)
    with pytest.raises(UrlError, match="use https://"):
        check_token_transport(tracker_endpoint("http://10.1.2.3:8085"), "--tracker", token)
