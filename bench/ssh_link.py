"""The console over SSH on a Wi-Fi link (issue 55): a table per link profile, a row per console.

OpenSSH's server runs ``arbiter-tui`` (embedded backend) in a network namespace, the Pi; a real
``ssh -tt`` in tmux, the laptop, reaches it through a user-space link (``tests/support/tunlink.py``)
with the profile's delay, jitter, loss (bursty on ``poor``) and rate; keys are typed at a laptop's
auto-repeat (30 Hz after 250 ms). What the robot was commanded is read inside the namespace with
roslibpy (``tests/support/sshlink.py``, the rig the tests use). Per profile and console:

* command gaps p50/p95/max (ms) between the commands the tracker forwarded during ``--holds`` steady
  holds of ``i`` of 5 s each (10 Hz is 100 ms), and the deadman's cut-outs (a zero within a hold) a minute;
* motion after release (m, odometry's path) when the link stalls 3 s (dropping; TCP retransmits) 1.5 s
  into a hold and the key is let go 1 s into the stall;
* stop key -> zero command (ms, p95 of ``--trials``): from the stop key's TCP segment delivered on the
  Pi to the first zero on /cmd_vel_measured;
* the mission's hold after a stall begins (s): a mission (``a``, ``g``) driving for a second, the link
  stalls 3 s; from the stall's start to the first zero command, or "never (drives on)" with the path
  driven during the stall (m);
* bytes a second toward the laptop (IP, headers included) at 80x24 and 200x60, idle and with a key held;
* key-to-echo (ms, p50/p95 of ``--trials``, at each size): from ``q`` (or ``z``) typed in tmux to the
  laptop's screen showing the new max speed, the robot standing still.

Root, /dev/net/tun, sshd, ssh and tmux needed. Run it where the load average is under ~2.

    python bench/ssh_link.py                                   # this checkout, every profile
    python bench/ssh_link.py --console main=/path/to/old --console new=.   # rows side by side
    python bench/ssh_link.py --only-mission            # that column alone (a rig and one stall a profile)
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from _common import emit

from tests.support.sshlink import PROFILES, ROOT, SshRig, missing, pct

COLUMNS = (
    "console",
    "gaps p50/p95/max ms",
    "cut-outs/min",
    "motion after release (3 s stall)",
    "stop → zero p95",
    "mission's hold after a stall begins",
    "B/s 80x24 idle/held",
    "B/s 200x60 idle/held",
    "key-to-echo p50/p95 80x24",
    "key-to-echo p50/p95 200x60",
)


def measure(profile: str, root: Path, holds: int, trials: int) -> dict:
    t_start = time.monotonic()
    with SshRig(PROFILES[profile], console_root=root) as rig:
        setup_s = time.monotonic() - t_start
        hold = [rig.hold(5.0) for _ in range(holds)]
        rig.drained()
        idle_small = rig.screen_bytes(3.0)
        echoes = [rig.key_echo("q" if i % 2 == 0 else "z") for i in range(trials)]
        stall = rig.stall_release()
        stops = [rig.stop_trial() for _ in range(trials)]
        mission = rig.mission_stall()
        rig.resize(200, 60)
        idle_big = rig.screen_bytes(3.0)
        held_big = rig.hold(3.0)["bytes_per_s_down"]
        rig.drained()
        echoes_big = [rig.key_echo("q" if i % 2 == 0 else "z") for i in range(trials)]
    found = [s for s in stops if s is not None]
    shown, shown_big = [e for e in echoes if e is not None], [e for e in echoes_big if e is not None]
    return {
        "profile": profile,
        "console": str(root),
        "setup_s": round(setup_s, 1),
        "gap_p50_ms": statistics.median(h["gap_p50_ms"] for h in hold),
        "gap_p95_ms": max(h["gap_p95_ms"] for h in hold),
        "gap_max_ms": max(h["gap_max_ms"] for h in hold),
        "cutouts_per_min": round(
            60.0 * sum(h["cutouts"] for h in hold) / sum(h["hold_span_s"] for h in hold), 1
        ),
        "motion_after_release_m": stall["motion_after_release_m"],
        "burst_after_stall_end_s": stall["burst_after_stall_end_s"],
        "stop_to_zero_ms": stops,
        "stop_to_zero_p95_ms": pct(found, 0.95),
        "mission_hold_after_stall_s": mission["mission_hold_after_stall_s"],
        "driven_during_stall_m": mission["driven_during_stall_m"],
        "bytes_per_s_80x24_idle": idle_small,
        "bytes_per_s_80x24_held": round(statistics.median(h["bytes_per_s_down"] for h in hold)),
        "bytes_per_s_200x60_idle": idle_big,
        "bytes_per_s_200x60_held": held_big,
        "key_echo_ms": echoes,
        "key_echo_p50_ms": pct(shown, 0.5),
        "key_echo_p95_ms": pct(shown, 0.95),
        "key_echo_200x60_ms": echoes_big,
        "key_echo_200x60_p50_ms": pct(shown_big, 0.5),
        "key_echo_200x60_p95_ms": pct(shown_big, 0.95),
    }


def _echo(all_ms: list, p50: float | None, p95: float | None) -> str:
    lost = sum(1 for e in all_ms if e is None)
    shown = "none shown" if p50 is None or p95 is None else f"{p50:.0f} / {p95:.0f} ms"
    return shown + (f" ({lost} of {len(all_ms)} not shown in 5 s)" if lost else "")


def _mission(r: dict) -> str:
    held = r["mission_hold_after_stall_s"]
    if held is None:
        return f"never (drives on: {r['driven_during_stall_m']:.2f} m in the stall)"
    return f"{held:.2f} s ({r['driven_during_stall_m']:.2f} m in the stall)"


def measure_mission(profile: str, root: Path) -> dict:
    with SshRig(PROFILES[profile], console_root=root) as rig:
        return {"profile": profile, "console": str(root), **rig.mission_stall()}


def row(label: str, r: dict) -> str:
    cells = (
        label,
        f"{r['gap_p50_ms']:.0f} / {r['gap_p95_ms']:.0f} / {r['gap_max_ms']:.0f}",
        f"{r['cutouts_per_min']:g}",
        f"{r['motion_after_release_m']:.3f} m",
        "n/a" if r["stop_to_zero_p95_ms"] is None else f"{r['stop_to_zero_p95_ms']:.0f} ms",
        _mission(r),
        f"{r['bytes_per_s_80x24_idle']:,} / {r['bytes_per_s_80x24_held']:,}",
        f"{r['bytes_per_s_200x60_idle']:,} / {r['bytes_per_s_200x60_held']:,}",
        _echo(r["key_echo_ms"], r["key_echo_p50_ms"], r["key_echo_p95_ms"]),
        _echo(r["key_echo_200x60_ms"], r["key_echo_200x60_p50_ms"], r["key_echo_200x60_p95_ms"]),
    )
    return "| " + " | ".join(cells) + " |"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--profiles", default=",".join(PROFILES), help=f"comma-separated, of {', '.join(PROFILES)}"
    )
    p.add_argument(
        "--console",
        action="append",
        metavar="LABEL=CHECKOUT",
        help="a console to run on the Pi (a checkout's root); repeat for rows side by side (default: this)",
    )
    p.add_argument("--holds", type=int, default=3, help="steady 5 s holds per profile (default 3)")
    p.add_argument(
        "--trials", type=int, default=10, help="stop keys and echoed keys per profile (default 10)"
    )
    p.add_argument(
        "--only-mission", action="store_true", help="the mission's hold after a stall alone, per profile"
    )
    a = p.parse_args()
    if (why := missing()) is not None:
        sys.exit(f"ssh_link: {why}")
    consoles = [
        (c.split("=", 1)[0], Path(c.split("=", 1)[1]).resolve()) for c in a.console or [f"this={ROOT}"]
    ]
    load = os.getloadavg()[0]
    busy = "  (over 2: the figures are the box's as much as the console's)" if load > 2 else ""
    print(f"load average at start: {load:.2f}{busy}")
    results = []
    for profile in a.profiles.split(","):
        lines = [
            f"### {PROFILES[profile].about}",
            "",
            "| " + " | ".join(COLUMNS) + " |",
            "|---" * len(COLUMNS) + "|",
        ]
        if a.only_mission:
            lines[2:] = ["| console | mission's hold after a stall begins |", "|---|---|"]
        for label, root in consoles:
            if a.only_mission:
                r = measure_mission(profile, root)
            else:
                r = measure(profile, root, a.holds, a.trials)
            r["label"] = label
            results.append(r)
            lines.append(f"| {label} | {_mission(r)} |" if a.only_mission else row(label, r))
        print("\n".join(lines) + "\n", flush=True)
    emit({"bench": "ssh_link", "load_at_start": round(load, 2), "results": results})


if __name__ == "__main__":
    main()
