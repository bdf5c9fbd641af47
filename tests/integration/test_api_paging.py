"""Paging by ``rx_seq`` end to end: the API's ``since`` and the console's poller against real trackers."""

import asyncio
import json

import aiohttp
import httpx
from aiohttp import web

from arbiter_core import envelope
from arbiter_tui.latency.tracker_client import TrackerClient

from ..support.backend import free_port, start_backend, wait_for
from ..support.servers import serve


async def publish(bridge_port: int, seqs: range) -> None:
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{bridge_port}/")
        await ws.send_str('{"op":"advertise","topic":"/stamped_cmd_vel","type":"std_msgs/String"}')
        for seq in seqs:
            data = envelope.build(0.1, 0.0, seq=seq)
            frame = {"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": data}}
            await ws.send_str(json.dumps(frame))
        await ws.close()


def total_seen(api: str) -> int:
    return httpx.get(f"{api}/api/latency?limit=0").json()["total_seen"]


def test_since_and_limit_over_http(backend):
    import roslibpy

    ros = roslibpy.Ros("127.0.0.1", backend.bridge_port)
    ros.run(timeout=10)
    try:
        pub = roslibpy.Topic(ros, "/stamped_cmd_vel", "std_msgs/String")
        pub.advertise()
        for i in range(12):
            pub.publish(roslibpy.Message({"data": envelope.build(0.1, 0.0, seq=i)}))
        api = backend.api
        assert wait_for(lambda: httpx.get(f"{api}/api/latency").json()["total_seen"] == 12)
        body = httpx.get(f"{api}/api/latency?since=9").json()
        assert [r["rx_seq"] for r in body["records"]] == [10, 11, 12] and body["more"] is False
        body = httpx.get(f"{api}/api/latency?since=0&limit=4").json()
        assert [r["seq"] for r in body["records"]] == [0, 1, 2, 3] and body["more"] is True
        for bad in ("since=-1", "since=x", "since=1e3"):
            r = httpx.get(f"{api}/api/latency?{bad}")
            assert r.status_code == 400 and "since" in r.json()["error"]
    finally:
        ros.close()


async def test_the_poller_takes_each_record_once_by_since():
    b = start_backend("--no-sim")
    client = TrackerClient(b.api, limit=5)
    try:
        await publish(b.bridge_port, range(12))
        assert wait_for(lambda: total_seen(b.api) == 12)
        view = await client.poll()  # first poll: the newest `limit` records
        assert [r.seq for r in view.records] == [7, 8, 9, 10, 11] and client.view.last_rx_seq == 12
        assert client.view.params(5) == {"since": 12, "limit": 120}
        await publish(b.bridge_port, range(12, 20))
        assert wait_for(lambda: total_seen(b.api) == 20)
        view = await client.poll()
        assert [r.seq for r in view.records] == list(range(7, 20))  # nothing twice, nothing missed
        assert len(view.window) == 13 and client.view.last_rx_seq == 20
        version = view.version
        view = await client.poll()  # nothing new: nothing added, nothing redrawn
        assert len(view.window) == 13 and view.version == version
    finally:
        await client.aclose()
        b.stop()


async def test_a_restarted_tracker_is_followed_from_its_new_counter():
    port = free_port()
    b = start_backend("--no-sim", "--api-port", str(port))
    client = TrackerClient(b.api, limit=50)
    try:
        await publish(b.bridge_port, range(10))
        assert wait_for(lambda: total_seen(b.api) == 10)
        assert len((await client.poll()).window) == 10
    finally:
        b.stop()
    b = start_backend("--no-sim", "--api-port", str(port))  # counts from 1 again
    try:
        await publish(b.bridge_port, range(100, 103))
        assert wait_for(lambda: total_seen(b.api) == 3)
        for _ in range(3):
            await client.poll()
        assert [r.seq for r in client.view.records][-3:] == [100, 101, 102]
        assert len(client.view.window) == 13 and client.view.last_rx_seq == 3
    finally:
        await client.aclose()
        b.stop()


async def test_a_tracker_without_rx_seq_is_polled_by_limit():
    """The seed's tracker answers the same shape without ``rx_seq``/``since``: a stand-in for it on a
    real HTTP server (the seed's own node needs ROS and FastAPI, which the tests do not carry)."""
    records: list[dict] = []
    queries: list[dict] = []

    async def latency(request: web.Request) -> web.Response:
        queries.append(dict(request.query))
        limit = int(request.query.get("limit", 100))
        body = {"records": records[-limit:], "stats": {"count": len(records)}, "deploy_mode": "docker"}
        return web.json_response(body)

    app = web.Application()
    app.router.add_get("/api/latency", latency)
    runner, port = await serve(app)
    client = TrackerClient(f"http://127.0.0.1:{port}", limit=4)

    def add(n: int) -> None:
        for _ in range(n):
            i = len(records)
            records.append(
                {
                    "latency_ms": 1.0 + i,
                    "linear_x": 0.1,
                    "angular_z": 0.0,
                    "timestamp": 100.0 + i,
                    "deploy_mode": "docker",
                }
            )

    try:
        add(6)
        view = await client.poll()
        assert list(view.window) == [3.0, 4.0, 5.0, 6.0] and not client.view.pages_by_rx_seq
        # its stats block has only a count: said, and the records are taken all the same
        assert view.reachable and view.stats is None and "stats.mean_ms" in (view.stats_error or "")
        add(2)
        view = await client.poll()
        view = await client.poll()
        assert list(view.window) == [3.0, 4.0, 5.0, 6.0, 7.0, 8.0]  # the overlap is not added twice
        assert all("since" not in q and q["limit"] == "4" for q in queries)
        assert view.deploy_mode == "docker"
    finally:
        await client.aclose()
        await runner.cleanup()
        await asyncio.sleep(0)
