"""The fleet over real Zenoh sessions on the loopback: a router in the test process, real ``arbiter-backend
--zenoh`` processes as its clients, the console's client (``arbiter_tui.fleet.client``) as another.

Robots appear; one killed reads "lost" within its lease and "alive" again after a restart; a robot's
payloads never show under another's name; malformed payloads mark that robot's row and nothing else; a
console the router's access control does not allow a robot never sees it; ``fleet --json`` prints the
rows the screen shows; a console the router allows stops a robot (its controller aborted, a foreign
action's goal cancelled, the robot standing), one it does not allow gets one line and the robot drives on."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest
import zenoh

from arbiter_core import fleet
from arbiter_tui.fleet.client import ConsoleSettings, FleetClient
from arbiter_tui.fleet.rows import COLUMNS, FleetModel, cells

from ..support.backend import free_port, get_json, start_backend
from ..support.foreign import FakeNav2
from ..support.waits import wait_for

LEASE_MS = 1000  # the robots' liveliness lease in these tests


def open_router(port, extra=None):
    cfg = {
        "mode": "router",
        "listen": {"endpoints": [f"tcp/127.0.0.1:{port}"]},
        "scouting": {"multicast": {"enabled": False}},
        **(extra or {}),
    }
    return zenoh.open(zenoh.Config.from_json5(json.dumps(cfg)))


@pytest.fixture
def router():
    port = free_port()
    r = open_router(port)
    yield f"tcp/127.0.0.1:{port}"
    r.close()


def robot(endpoint, name, *extra):
    return start_backend(
        "--no-bridge", "--zenoh", endpoint, "--robot-name", name, "--zenoh-lease", str(LEASE_MS), *extra
    )


def console(endpoint, config_file=None):
    c = FleetClient(
        ConsoleSettings(connect=(endpoint,), config_file=config_file), FleetModel(stale_after=3.0)
    )
    c.open(connect_timeout_ms=5000)
    return c


def row(client, name):
    return next((r for r in client.view().rows if r.name == name), None)


def state(client, name):
    r = row(client, name)
    return None if r is None else r.state


def announced(client, name):
    """Alive with its status and latency summary received."""
    r = row(client, name)
    return r is not None and r.state == "alive" and r.driver is not None and r.latency_count is not None


@pytest.fixture
def cleanup():
    procs, clients = [], []
    yield procs, clients
    for c in clients:
        c.close()
    for p in procs:
        if p.proc.poll() is None:
            os.kill(p.proc.pid, signal.SIGCONT)
        p.stop()


def test_robots_appear_a_killed_one_is_lost_within_its_lease_and_alive_after_a_restart(router, cleanup):
    procs, clients = cleanup
    bots = {name: robot(router, name) for name in ("r1", "r2", "r3")}
    procs += bots.values()
    c = console(router)
    clients.append(c)
    assert wait_for(lambda: all(announced(c, n) for n in bots), timeout=10), c.view()
    for name, b in bots.items():  # each row carries its own robot's figures
        assert row(c, name).tracker == f"http://127.0.0.1:{b.api_port}"

    # kill -9: its router sees the socket close, the token goes, the row reads lost (and stays listed)
    t0 = time.monotonic()
    bots["r2"].proc.kill()
    assert wait_for(lambda: state(c, "r2") == "lost", timeout=LEASE_MS / 1000 + 2)
    killed_to_lost = time.monotonic() - t0
    assert killed_to_lost < LEASE_MS / 1000 + 1.0
    assert state(c, "r1") == state(c, "r3") == "alive"

    # frozen (SIGSTOP): no socket closes, only the lease tells; then it comes back by itself
    t0 = time.monotonic()
    os.kill(bots["r3"].proc.pid, signal.SIGSTOP)
    assert wait_for(lambda: state(c, "r3") == "lost", timeout=LEASE_MS / 1000 + 3)
    frozen_to_lost = time.monotonic() - t0
    assert LEASE_MS / 1000 * 0.5 < frozen_to_lost < LEASE_MS / 1000 + 1.5
    os.kill(bots["r3"].proc.pid, signal.SIGCONT)
    assert wait_for(lambda: state(c, "r3") == "alive", timeout=10)

    # restarted under the same name: alive again, with its new ports
    t0 = time.monotonic()
    again = robot(router, "r2")
    procs.append(again)
    assert wait_for(lambda: state(c, "r2") == "alive", timeout=10)
    restart_to_alive = time.monotonic() - t0
    assert wait_for(lambda: row(c, "r2").tracker == f"http://127.0.0.1:{again.api_port}", timeout=5)
    print(
        f"kill->lost {killed_to_lost:.2f} s, SIGSTOP->lost {frozen_to_lost:.2f} s, "
        f"restart->alive {restart_to_alive:.2f} s (lease {LEASE_MS} ms)"
    )


def test_a_robot_whose_router_is_not_there_says_so_in_its_health_and_its_log(cleanup):
    """Issue 54, item 6: pointed at a closed port the backend does not look healthy: /api/health's
    ``fleet`` key says connecting and why, the log says it once; then connected, then retrying when the
    router goes, each change logged once."""
    procs, _ = cleanup
    port = free_port()
    bot = robot(f"tcp/127.0.0.1:{port}", "r9")
    procs.append(bot)

    def link():
        return get_json(f"{bot.api}/api/health")["fleet"]

    first = link()
    assert first["state"] == "connecting" and first["endpoints"] == [f"tcp/127.0.0.1:{port}"], first
    assert wait_for(lambda: link()["last_error"] is not None, timeout=15), link()
    health = get_json(f"{bot.api}/api/health")
    assert health["status"] == "ok" and health["fleet"]["state"] == "connecting"  # the other keys as ever
    r = open_router(port)
    try:
        assert wait_for(lambda: link()["state"] == "connected", timeout=20), link()
        since = link()["since"]
    finally:
        r.close()
    assert wait_for(lambda: link()["state"] == "retrying", timeout=15), link()
    assert link()["since"] > since
    bot.stop()
    log = bot.proc.stderr.read()
    assert [log.count(w) for w in ("cannot reach", "reached tcp/", "lost tcp/")] == [1, 1, 1], log


def test_while_the_consoles_own_link_is_down_no_robot_is_called_lost_or_alive(cleanup):
    """The router goes away: the rows read "unknown since" (never "lost": the robots did not go, this
    console's link did) and the header says the console reconnects; the router back, the robots are
    alive again and the header says since when it is connected."""
    procs, clients = cleanup
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    r = open_router(port)
    try:
        procs += [robot(endpoint, "r1"), robot(endpoint, "r2")]
        c = console(endpoint)
        clients.append(c)
        assert wait_for(lambda: announced(c, "r1") and announced(c, "r2"), timeout=10)
        assert " · connected since " in c.view().session
        r.close()
        closed = time.monotonic()
        seen: set[str] = set()  # every state a row showed from here on

        def states():
            now = {x.state for x in c.view().rows}
            seen.update(now)
            return now

        # unknown at once, and still so two seconds on (past the robots' lease)
        assert wait_for(lambda: states() == {"unknown"} and time.monotonic() - closed > 2.0, timeout=6), seen
        assert " · reconnecting since " in c.view().session
        assert c.stop("r1") == "not stopped: this console's link to its router is down (nothing was asked)"
        r = open_router(port)
        assert wait_for(lambda: states() == {"alive"}, timeout=15), c.view()
        assert " · connected since " in c.view().session
        assert seen == {"alive", "unknown"}, seen  # never "lost": the robots did not go, the link did
    finally:
        r.close()


def test_a_frozen_router_makes_every_robot_unknown_not_stale_or_lost(cleanup):
    """The router frozen (SIGSTOP) keeps its links open until its lease: every robot silent at once reads
    "unknown" (the router is silent, not the robots) within SILENT_S, and alive again when it thaws."""
    from arbiter_tui.fleet.rows import SILENT_S

    procs, clients = cleanup
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    router_proc = subprocess.Popen(
        [sys.executable, "-m", "arbiter_tui.cli", "fleet", "--listen", endpoint, "--json", "--wait", "120"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        procs += [robot(endpoint, "r1"), robot(endpoint, "r2")]
        c = FleetClient(ConsoleSettings(connect=(endpoint,)), FleetModel())  # stale after 5 s
        c.open(connect_timeout_ms=10000)
        clients.append(c)
        assert wait_for(lambda: announced(c, "r1") and announced(c, "r2"), timeout=15)
        seen: set[str] = set()

        def states():
            now = {x.state for x in c.view().rows}
            seen.update(now)
            return now

        os.kill(router_proc.pid, signal.SIGSTOP)
        frozen = time.monotonic()
        assert wait_for(lambda: states() == {"unknown"}, timeout=SILENT_S + 3), c.view()
        took = time.monotonic() - frozen
        os.kill(router_proc.pid, signal.SIGCONT)
        assert wait_for(lambda: states() == {"alive"}, timeout=15), c.view()
        assert seen == {"alive", "unknown"}, seen
        print(f"router frozen -> every robot unknown in {took:.2f} s")
    finally:
        os.kill(router_proc.pid, signal.SIGCONT)
        router_proc.kill()
        router_proc.wait()


def test_malformed_payloads_mark_their_row_and_nothing_else(router, cleanup):
    procs, clients = cleanup
    procs += [robot(router, "victim"), robot(router, "bystander")]
    c = console(router)
    clients.append(c)
    assert wait_for(lambda: announced(c, "victim") and announced(c, "bystander"), timeout=10)
    rogue = zenoh.open(
        zenoh.Config.from_json5(json.dumps({"mode": "client", "connect": {"endpoints": [router]}}))
    )
    try:
        good = fleet.encode(fleet.Status("victim", time.time(), time.time(), "nobody", "fake"))
        cases = [
            (b"this is not JSON", "status: not JSON"),
            (good.replace(b'"v":1', b'"v":2'), "schema version 2, this console reads version 1"),
            (good.replace(b'"started":', b'"started":NaN,"x":'), "NaN (numbers must be finite)"),
            (b"{" + b" " * (10 * 1024 * 1024), "status: 10.5 MB, over the 1.5 kB a status may be"),
            (
                fleet.encode(fleet.Status("bystander", time.time(), 0.0, "nobody", "forged")),
                "names robot 'bystander' on victim's key",
            ),
        ]
        for data, reason in cases:
            before = row(c, "victim").bad_count

            def marked(data=data, before=before):  # sent again if it came over the robot's status rate
                if row(c, "victim").bad_count > before:
                    return True
                rogue.put(fleet.key("victim", "status"), data)
                return False

            assert wait_for(marked, timeout=5, interval=0.5), reason
            assert reason in row(c, "victim").bad
        rogue.put("arbiter/victim/unknown-kind", b"{}")
        rogue.put("arbiter/not a name/status", b"{}")
        assert wait_for(lambda: c.view().unknown >= 2, timeout=5)
        assert c.view().to_json()["dropped"]["odd_keys"] >= 2
        # a flood of valid statuses (the rogue's own robot, "flooder"): named on its row, the excess dropped
        flood = fleet.encode(fleet.Status("flooder", time.time(), time.time(), "nobody", "flood"))
        for _ in range(3000):
            rogue.put(fleet.key("flooder", "status"), flood)
        assert wait_for(lambda: c.view().flood_dropped > 2000, timeout=5), c.view().flood_dropped
        assert row(c, "flooder").flooding > 50 and c.model.received_bytes()["flooder"] <= 20 * len(flood)
    finally:
        rogue.close()
    rows = {r.name: r for r in c.view().rows}
    assert rows["victim"].severity == 3 and rows["victim"].state == "alive"  # its own payloads still come
    assert rows["bystander"].bad is None and rows["bystander"].severity < 3
    assert rows["bystander"].mode != "forged"  # the forgery never reached the bystander's row
    t = row(c, "bystander").age_s
    assert wait_for(lambda: row(c, "bystander").age_s < t or row(c, "bystander").age_s < 1.5, timeout=5)
    assert [x.name for x in c.view().rows[:2]] == ["flooder", "victim"]  # bad data and floods sort first


ROBOT_KEYS = ["put", "delete", "declare_queryable", "liveliness_token", "reply"]
CONSOLE_ASKS = ["declare_subscriber", "declare_liveliness_subscriber", "liveliness_query"]
SEES = ["put", "delete", "reply", "liveliness_token"]


def site_acl():
    """The README's router ACL: each robot writes only its own keys, a console sees what its policy lists."""
    rules = (
        [
            {
                "id": f"{r}-own",
                "messages": ROBOT_KEYS,
                "flows": ["ingress"],
                "permission": "allow",
                "key_exprs": [f"arbiter/{r}/**"],
            }
            for r in ("robot1", "robot2")
        ]
        + [
            {  # a robot's publishers send only where a subscriber is: it must learn that consoles subscribe
                "id": "to-robots",
                "messages": ["query", "liveliness_query", "declare_subscriber"],
                "flows": ["egress"],
                "permission": "allow",
                "key_exprs": ["arbiter/**"],
            },
            {
                "id": "console-asks",
                "messages": CONSOLE_ASKS,
                "flows": ["ingress"],
                "permission": "allow",
                "key_exprs": ["arbiter/**"],
            },
            {  # every console may ask any robot's history (the robot's answer still passes see-<robot>)
                "id": "console-history",
                "messages": ["query"],
                "flows": ["ingress"],
                "permission": "allow",
                "key_exprs": ["arbiter/*/history"],
            },
        ]
        + [
            {  # who may stop a robot: a rule per robot, granted to named consoles
                "id": f"stop-{r}",
                "messages": ["query"],
                "flows": ["ingress"],
                "permission": "allow",
                "key_exprs": [f"arbiter/{r}/stop"],
            }
            for r in ("robot1", "robot2")
        ]
        + [
            {
                "id": f"see-{r}",
                "messages": SEES,
                "flows": ["egress"],
                "permission": "allow",
                "key_exprs": [f"arbiter/{r}/**"],
            }
            for r in ("robot1", "robot2")
        ]
    )
    users = ("robot1", "robot2", "console-a", "console-all", "supervisor")
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": [{"id": u, "usernames": [u]} for u in users],
        "policies": [
            {"rules": ["robot1-own", "to-robots"], "subjects": ["robot1"]},
            {"rules": ["robot2-own", "to-robots"], "subjects": ["robot2"]},
            {"rules": ["console-asks", "console-history", "see-robot1"], "subjects": ["console-a"]},
            {
                "rules": ["console-asks", "console-history", "see-robot1", "see-robot2"],
                "subjects": ["console-all"],
            },
            {  # sees both robots, may stop robot1 only
                "rules": ["console-asks", "console-history", "see-robot1", "see-robot2", "stop-robot1"],
                "subjects": ["supervisor"],
            },
        ],
    }


def open_as(endpoint: str, user: str, password: str):
    """A Zenoh session, a client of the test's router with a user's credentials."""
    config = {
        "mode": "client",
        "connect": {"endpoints": [endpoint]},
        "transport": {"auth": {"usrpwd": {"user": user, "password": password}}},
    }
    return zenoh.open(zenoh.Config.from_json5(json.dumps(config)))


USERS = {
    "robot1": "pw-r1", "robot2": "pw-r2", "console-a": "pw-a", "console-all": "pw-all", "supervisor": "pw-s"
}  # fmt: skip


def acl_router(tmp_path):
    """The site's router with the users and access control above; each user's config file in tmp_path."""
    (tmp_path / "users.txt").write_text("".join(f"{u}:{p}\n" for u, p in USERS.items()))
    for u, p in USERS.items():
        (tmp_path / f"{u}.json5").write_text(
            json.dumps({"transport": {"auth": {"usrpwd": {"user": u, "password": p}}}})
        )
    port = free_port()
    r = open_router(
        port,
        {
            "transport": {"auth": {"usrpwd": {"dictionary_file": str(tmp_path / "users.txt")}}},
            "access_control": site_acl(),
        },
    )
    return r, f"tcp/127.0.0.1:{port}"


def test_a_console_without_permission_to_a_robot_never_sees_it(tmp_path, cleanup):
    procs, clients = cleanup
    r, endpoint = acl_router(tmp_path)
    try:
        for name in ("robot1", "robot2"):
            procs.append(robot(endpoint, name, "--zenoh-config", str(tmp_path / f"{name}.json5")))
        everyone = console(endpoint, tmp_path / "console-all.json5")
        only_one = console(endpoint, tmp_path / "console-a.json5")
        clients += [everyone, only_one]
        assert wait_for(lambda: announced(everyone, "robot1") and announced(everyone, "robot2"), timeout=10)
        assert wait_for(lambda: announced(only_one, "robot1"), timeout=5)
        assert everyone.history("robot2", 1.0).robot == "robot2"
        # a watcher with every permission sees robot2's payloads from here on
        seen: set[str] = set()
        watcher = open_as(endpoint, "console-all", "pw-all")
        try:
            sub = watcher.declare_subscriber(
                f"{fleet.PREFIX}/robot2/*", lambda sample: seen.add(str(sample.key_expr).rsplit("/", 1)[-1])
            )
            assert only_one.history("robot2", 1.0) == "robot2 did not answer in 3 s"
            # every kind of payload robot2 sends on a period has gone by at least once since the watcher
            # subscribed (proving that nothing arrives at the console without permission)
            periodic = {fleet.STATUS, fleet.LATENCY, fleet.TOPICS}
            assert wait_for(lambda: periodic <= seen, timeout=fleet.TOPICS_PERIOD_S + 5), seen
            sub.undeclare()
        finally:
            watcher.close()
        assert [x.name for x in only_one.view().rows] == ["robot1"]
        assert only_one.view().unknown == 0

        # robot1's credentials cannot write robot2's keys: the router drops the forgery
        forger = open_as(endpoint, "robot1", "pw-r1")
        try:
            forger.put(fleet.key("robot2", "status"), b"forged by robot1")
            forger.put(fleet.key("robot1", "status"), b"robot1's own bad payload")
            assert wait_for(lambda: row(everyone, "robot1").bad is not None, timeout=5)  # its own keys pass
            assert row(everyone, "robot2").bad is None
        finally:
            forger.close()
        with pytest.raises(Exception, match="Unable to connect"):  # a wrong password is no session at all
            open_as(endpoint, "console-a", "guess")
    finally:
        r.close()


def post_json(url, body):
    import httpx

    return httpx.post(url, json=body, timeout=5).json()


def test_a_stop_from_the_fleet_reaches_the_robots_its_console_may_stop_and_no_other(tmp_path, cleanup):
    """Two robots each running a mission: the supervisor's console may stop robot1 (the router's ACL),
    not robot2. Stopping robot1 aborts its controller, cancels the foreign action goal there, and the
    robot stands within a second; stopping robot2 is one line saying so, and robot2 drives on."""
    procs, clients = cleanup
    r, endpoint = acl_router(tmp_path)
    nav2 = None
    try:
        bots = {}
        for name in ("robot1", "robot2"):
            bots[name] = start_backend(
                "--autonomy", "--zenoh", endpoint, "--robot-name", name, "--zenoh-lease", str(LEASE_MS),
                "--zenoh-config", str(tmp_path / f"{name}.json5"),
            )  # fmt: skip
        procs += bots.values()
        c = console(endpoint, tmp_path / "supervisor.json5")
        clients.append(c)
        assert wait_for(lambda: announced(c, "robot1") and announced(c, "robot2"), timeout=15)
        nav2 = FakeNav2(bots["robot1"].bridge_port, "/cmd_vel")  # a foreign action server on robot1
        nav2.start_goal()
        for b in bots.values():
            started = post_json(f"{b.api}/api/autonomy", {"algorithm": "stanley", "mission": "figure_eight"})
            assert started["state"] == "running", started
        # both drive (the robots' own statuses say so), watched on the router as a console sees them
        statuses: dict[str, list[fleet.Status]] = {"robot1": [], "robot2": []}
        watcher = open_as(endpoint, "console-all", "pw-all")
        clients.append(watcher)

        def heard(sample):
            s = fleet.decode(sample.payload.to_bytes(), "status", str(sample.key_expr).split("/")[1])
            statuses[s.robot].append(s)

        watcher.declare_subscriber("arbiter/*/status", heard)

        def moving(name, after=0.0):
            return any(s.t > after and s.velocity and abs(s.velocity[0]) > 0.05 for s in statuses[name])

        assert wait_for(lambda: moving("robot1") and moving("robot2"), timeout=10), statuses

        # allowed: the answer within a second says what it stopped; the robot stands
        t0, asked = time.monotonic(), time.time()
        answer = c.stop("robot1")
        took = time.monotonic() - t0
        assert isinstance(answer, fleet.StopAnswer), answer
        assert took < 1.0, took
        words = answer.words()
        assert words.startswith("stopped: stanley aborted")
        assert "1 goal of /navigate_to_pose cancelled" in words
        assert answer.driver == "robot" and answer.zero
        assert get_json(f"{bots['robot1'].api}/api/autonomy")["state"] == "aborted"
        assert wait_for(lambda: not nav2.active, timeout=2) and len(nav2.cancels) == 1

        def stood(name):
            later = [s for s in statuses[name] if s.t > asked + 0.05]
            return later and later[0].velocity and max(map(abs, later[0].velocity)) < 1e-3 and later[0]

        assert wait_for(lambda: stood("robot1"), timeout=3), statuses["robot1"][-3:]
        assert stood("robot1").t - asked < 1.0 + 0.3  # its first status after the stop (one a second)

        # not allowed: one line at once, and robot2 drives on
        t0, asked = time.monotonic(), time.time()
        refused = c.stop("robot2")
        assert refused == (
            "not stopped: this console may not stop robot2 (the router let the stop through to nobody: "
            "its access control on arbiter/robot2/stop)"
        )
        assert time.monotonic() - t0 < 0.8
        assert wait_for(lambda: moving("robot2", after=asked + 1.0), timeout=5)
        assert get_json(f"{bots['robot2'].api}/api/autonomy")["state"] == "running"
        print(f"stop answered in {took * 1e3:.0f} ms: {words}")
    finally:
        if nav2 is not None:
            nav2.close()
        r.close()


def fleet_cli(*args, timeout=30):
    return subprocess.run(
        [sys.executable, "-m", "arbiter_tui.cli", "fleet", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def test_fleet_json_prints_the_rows_the_screen_shows_and_history_answers(router, cleanup):
    procs, clients = cleanup
    procs += [robot(router, "r1", "--autonomy"), robot(router, "r2", "--expect", "/scan>=10")]
    c = console(router)
    clients.append(c)
    with_topics = [lambda n=n: announced(c, n) and row(c, n).worst_topic is not None for n in ("r1", "r2")]
    assert wait_for(lambda: all(f() for f in with_topics), timeout=10)
    r = fleet_cli("--connect", router, "--json", "--wait", "8")
    assert r.returncode == 0, r.stderr
    printed = json.loads(r.stdout)
    shown = c.view()
    assert [x["name"] for x in printed["robots"]] == [x.name for x in shown.rows] == ["r2", "r1"]
    for obj, mine in zip(printed["robots"], shown.rows, strict=True):
        want = dict(zip(COLUMNS, cells(mine), strict=True))
        for col in ("robot", "driver", "worst topic", "runs", "note"):
            assert obj["cells"][col] == want[col]
        assert obj["state"] == mine.state == "alive"
    assert printed["robots"][0]["cells"]["worst topic"] == "/scan missing"  # a warning sorts first

    r = fleet_cli("--connect", router, "--history", "r1", "--minutes", "1")
    assert r.returncode == 0, r.stderr
    answer = fleet.decode(r.stdout.strip().encode(), "history", "r1")
    assert {e.kind for e in answer.entries} >= {"status", "latency", "topics"}


@pytest.mark.parametrize(
    ("args", "code", "words"),
    [
        (["--connect", "10.0.0.1:7447", "--json"], 2, "'10.0.0.1:7447' is not a Zenoh endpoint"),
        (["--json", "--wait", "0.3", "--connect", "tcp/127.0.0.1:{free}"], 3, "cannot reach the router at"),
        (["--history", "a/b"], 2, "is not one key chunk"),
    ],
)
def test_fleet_command_errors_are_one_line(args, code, words):
    r = fleet_cli(*[a.replace("{free}", str(free_port())) for a in args])
    assert r.returncode == code
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--zenoh", "tcp/127.0.0.1:7447", "--robot-name", "a/b"], "--robot-name: robot name 'a/b'"),
        (["--robot-name", "r1"], "--robot-name needs --zenoh ENDPOINT"),
        (["--zenoh", "localhost:7447"], "--zenoh: 'localhost:7447' is not a Zenoh endpoint"),
        (["--zenoh", "tcp/127.0.0.1:7447", "--expect", "/scan"], "--expect: bad expectation '/scan'"),
        (["--zenoh", "tcp/127.0.0.1:7447", "--zenoh-lease", "50"], "--zenoh-lease: must be between 200"),
        (["--zenoh", "tcp/127.0.0.1:7447", "--zenoh-config", "{bad}"], "--zenoh-config"),
    ],
)
def test_backend_fleet_flags_are_checked_in_one_line(args, words, tmp_path):
    bad = tmp_path / "bad.json5"
    bad.write_text("{ mode: 'starship' }")
    cmd = [sys.executable, "-m", "arbiter_backend.cli", *[a.replace("{bad}", str(bad)) for a in args]]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    assert r.returncode == 2
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


def site_pki(directory):
    """A site CA and a router certificate it signed (for localhost and 127.0.0.1): Zenoh's TLS (rustls)
    wants a real CA, not a self-signed leaf."""
    import datetime
    import ipaddress

    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    now = datetime.datetime.now(datetime.timezone.utc)

    def cert(subject, issuer, public, signer, ca, names=()):
        b = (
            x509.CertificateBuilder()
            .subject_name(subject)
            .issuer_name(issuer)
            .public_key(public)
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5))
            .not_valid_after(now + datetime.timedelta(days=1))
            .add_extension(x509.BasicConstraints(ca=ca, path_length=None), critical=True)
        )
        if names:
            b = b.add_extension(x509.SubjectAlternativeName(list(names)), critical=False)
        return b.sign(signer, hashes.SHA256())

    def write(name, key, c):
        (directory / f"{name}.key").write_bytes(
            key.private_bytes(
                serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
            )
        )
        (directory / f"{name}.pem").write_bytes(c.public_bytes(serialization.Encoding.PEM))

    ca_key, key = ec.generate_private_key(ec.SECP256R1()), ec.generate_private_key(ec.SECP256R1())
    ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "arbiter site CA")])
    write("ca", ca_key, cert(ca_name, ca_name, ca_key.public_key(), ca_key, True))
    names = (x509.DNSName("localhost"), x509.IPAddress(ipaddress.ip_address("127.0.0.1")))
    router_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "router")])
    write("router", key, cert(router_name, ca_name, key.public_key(), ca_key, False, names))


def test_robots_and_console_over_tls_and_a_client_without_the_ca_refused(tmp_path, cleanup):
    procs, clients = cleanup
    site_pki(tmp_path)
    port = free_port()
    tls = {
        "link": {
            "tls": {
                "listen_certificate": str(tmp_path / "router.pem"),
                "listen_private_key": str(tmp_path / "router.key"),
            }
        }
    }
    r = open_router(port, {"listen": {"endpoints": [f"tls/127.0.0.1:{port}"]}, "transport": tls})
    try:
        trust = tmp_path / "trust.json5"
        trust.write_text(
            json.dumps({"transport": {"link": {"tls": {"root_ca_certificate": str(tmp_path / "ca.pem")}}}})
        )
        endpoint = f"tls/localhost:{port}"
        procs.append(robot(endpoint, "tls-bot", "--zenoh-config", str(trust)))
        c = console(endpoint, trust)
        clients.append(c)
        assert wait_for(lambda: announced(c, "tls-bot"), timeout=10)
        untrusting = fleet_cli("--connect", endpoint, "--json", "--wait", "1")
        assert untrusting.returncode == 3 and "cannot reach the router at tls/localhost" in untrusting.stderr
    finally:
        r.close()


BLOCK_ZENOH = (
    "import sys\n"
    "class Block:\n"
    "    def find_spec(self, name, path=None, target=None):\n"
    "        if name.split('.')[0] == 'zenoh':\n"
    "            raise ImportError('no zenoh here')\n"
    "sys.meta_path.insert(0, Block())\n"
)


@pytest.mark.parametrize(
    ("main", "args", "words"),
    [
        ("arbiter_tui.cli", ["fleet", "--json"], "arbiter-tui fleet needs eclipse-zenoh (the [fleet] extra)"),
        ("arbiter_backend.cli", ["--zenoh", "tcp/127.0.0.1:7447"], "--zenoh needs eclipse-zenoh"),
    ],
)
def test_without_zenoh_the_fleet_says_how_to_install_it_in_one_line(main, args, words):
    code = (
        BLOCK_ZENOH
        + f"import runpy; sys.argv = ['x', *{args!r}]; runpy.run_module({main!r}, run_name='__main__')"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2
    assert words in r.stderr and "pip install 'arbiter-tui[fleet]'" in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_the_console_as_router_refuses_a_port_it_cannot_listen_on(router):
    r = fleet_cli("--listen", router, "--json", "--wait", "0.2")
    assert r.returncode == 3 and "cannot listen on" in r.stderr and len(r.stderr.strip().splitlines()) == 1
