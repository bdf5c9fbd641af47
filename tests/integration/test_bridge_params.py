"""rosapi parameters on the embedded transport (no ROS graph): a store in memory, through roslibpy's
``Param`` as a dashboard uses it and through raw frames; bad arguments are result false naming them."""

import json

import roslibpy


async def call(ws, **frame):
    await ws.send_json({"op": "call_service", **frame})
    while True:
        reply = json.loads((await ws.receive(timeout=10)).data)
        if reply.get("id") == frame.get("id"):
            return reply


async def test_parameters_in_memory(server, session):
    ws = await session.ws_connect(f"ws://127.0.0.1:{server.bridge_port}/")

    async def param(service, **args):
        return await call(ws, id=service, service=f"/rosapi/{service}", args=args)

    assert (await param("has_param", name="max_speed"))["values"] == {"exists": False}
    assert (await param("get_param", name="max_speed", default_value="0.5"))["values"] == {"value": "0.5"}
    assert (await param("set_param", name="max_speed", value="1.25"))["result"] is True
    assert (await param("get_param", name="max_speed"))["values"] == {"value": "1.25"}
    assert (await param("set_param", name="frames", value='["odom", "base_link"]'))["result"] is True
    assert (await param("get_param_names"))["values"] == {"names": ["frames", "max_speed"]}
    assert (await param("delete_param", name="frames"))["result"] is True
    assert (await param("has_param", name="frames"))["values"] == {"exists": False}
    bad = await param("set_param", name="x", value="{oops")
    assert bad["result"] is False and "args.value must be JSON" in bad["values"]
    bad = await param("set_param", name="x", value='{"a": 1}')
    assert bad["result"] is False and "a parameter is a bool, number, string" in bad["values"]
    bad = await param("get_param", name=3)
    assert bad["result"] is False and "args.name" in bad["values"]
    await ws.close()


def test_roslibpy_param(backend):
    ros = roslibpy.Ros("127.0.0.1", backend.bridge_port)
    ros.run(timeout=10)
    try:
        speed = roslibpy.Param(ros, "max_speed")
        speed.set(0.75, timeout=10)
        assert speed.get(timeout=10) == 0.75
        assert "max_speed" in ros.get_params()
        speed.delete(timeout=10)
        assert roslibpy.Param(ros, "max_speed").get(timeout=10) == ""  # rosapi's answer: no default
    finally:
        ros.close()


async def test_parameters_outside_the_glob_are_not_reachable(session):
    from arbiter_backend.config import BackendConfig
    from arbiter_backend.server import Backend

    backend = Backend(BackendConfig(bridge_port=0, api_port=0, sim=False, params_glob="max_*"))
    await backend.start()
    try:
        ws = await session.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}/")

        async def param(service, **args):
            return await call(ws, id=service, service=f"/rosapi/{service}", args=args)

        assert (await param("set_param", name="max_speed", value="1.0"))["result"] is True
        bad = await param("set_param", name="secret", value="1")
        assert bad["result"] is False and "secret is not exposed" in bad["values"]
        bad = await param("get_param", name="secret")
        assert bad["result"] is False and "--params-glob" in bad["values"]
        assert (await param("has_param", name="secret"))["values"] == {"exists": False}
        assert (await param("get_param_names"))["values"] == {"names": ["max_speed"]}
        await ws.close()
    finally:
        await backend.stop()
