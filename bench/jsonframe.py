#!/usr/bin/env python
"""What the endpoint spends on one camera frame's JSON: the ROS message's JSON form (base64 of its
``uint8[]``) and the frame's text, spliced (``arbiter_backend/jsonframe.py``) and by ``json.dumps``.

Needs the ``[ros]`` extra (``sensor_msgs``). Medians of ``--repeat`` calls, per image size:

    python bench/jsonframe.py --sizes 640x480,1280x720
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

from _common import emit


def median_ms(fn: Callable[[], Any], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return round(statistics.median(times) * 1e3, 3)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="640x480,1280x720", help="rgb8 images, WIDTHxHEIGHT, comma-separated")
    p.add_argument("--repeat", type=int, default=20)
    a = p.parse_args()
    try:
        from sensor_msgs.msg import Image
    except ImportError:
        print("jsonframe: needs the [ros] extra (sensor_msgs)", file=sys.stderr)
        return 1
    from arbiter_backend import jsonframe
    from arbiter_backend.ros.convert import to_json

    rows = []
    for size in a.sizes.split(","):
        w, h = (int(n) for n in size.split("x"))
        image = Image(height=h, width=w, encoding="rgb8", step=w * 3)
        image.data = random.Random(1).randbytes(w * h * 3)
        body = {"op": "publish", "topic": "/camera", "msg": to_json(image)}
        plain = json.dumps(body, separators=(",", ":"), allow_nan=False)
        assert jsonframe.dumps(body) == plain  # the same text
        rows.append({
            "size": size, "frame_mb": round(len(plain) / 1e6, 2),
            "to_json_ms": median_ms(lambda: to_json(image), a.repeat),  # noqa: B023
            "spliced_ms": median_ms(lambda: jsonframe.dumps(body), a.repeat),  # noqa: B023
            "json_dumps_ms": median_ms(lambda: json.dumps(body, separators=(",", ":")), a.repeat),  # noqa: B023
        })  # fmt: skip
        r = rows[-1]
        print(f"{size:>9}: to_json {r['to_json_ms']} ms, frame text spliced {r['spliced_ms']} ms, "
              f"json.dumps {r['json_dumps_ms']} ms ({r['frame_mb']} MB)")  # fmt: skip
    emit({"bench": "jsonframe", "repeat": a.repeat, "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
