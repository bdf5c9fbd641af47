"""rosbridge messages into the Observer's calls (link/observed.py): an action's goal status."""

from arbiter_tui.analytics.observe import Observer
from arbiter_tui.analytics.runs import ABORTED
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.link.observed import goal_statuses, observe_goal, observe_goal_status, observe_odometry

UUID = list(range(16))


def status_msg(*entries: tuple[object, int]) -> dict:
    return {
        "status_list": [
            {"goal_info": {"goal_id": {"uuid": uuid}, "stamp": {"sec": 1, "nanosec": 0}}, "status": status}
            for uuid, status in entries
        ]
    }


def test_goal_statuses_read_both_uuid_encodings_and_skip_what_does_not_parse():
    msg = status_msg((UUID, 2), ("AAECAwQFBgcICQoLDA0ODw==", 6))
    msg["status_list"].append({"goal_info": {}, "status": 2})
    msg["status_list"].append({"goal_info": {"goal_id": {"uuid": UUID}}, "status": "x"})
    assert goal_statuses(msg) == [(bytes(range(16)).hex(), 2), ("AAECAwQFBgcICQoLDA0ODw==", 6)]
    assert goal_statuses({}) == [] and goal_statuses({"status_list": None}) == []


def odometry(x: float) -> dict:
    return {
        "pose": {"pose": {"position": {"x": x, "y": 0.0, "z": 0.0},
                          "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}},
        "twist": {"twist": {"linear": {"x": 0.0}, "angular": {"z": 0.0}}},
    }  # fmt: skip


def test_an_aborted_action_goal_ends_the_observed_run():
    store = AnalyticsStore()
    store.start_collection()
    obs = Observer(store)
    observe_odometry(obs, odometry(0.0))
    observe_goal_status(obs, status_msg((UUID, 2)))
    observe_goal(obs, {"header": {}, "pose": {"position": {"x": 3.0, "y": 0.0}}})
    observe_odometry(obs, odometry(0.0))
    assert store.active_run is not None
    observe_goal_status(obs, status_msg((UUID, 6)))
    assert store.active_run is None and store.runs()[0].outcome == ABORTED
    observe_goal_status(obs, ["not", "a", "dict"])  # type: ignore[arg-type]  # a foreign robot's topic
