"""Communication: a report with a code word, repeated status broadcasts, spot a target and tell.

Messages are checked on their text: a direct message must reach the named drone and contain
the given words exactly (case included); a broadcast counts as a message to every drone.
"""

from __future__ import annotations

import random

from benchmark.authoring.template_files.loader import load_template
from benchmark.authoring.templates.base import (
    SessionView,
    TaskDraft,
    Template,
    all_of,
    leaf,
    pick,
)
from benchmark.authoring.templates.common import FILES

__all__ = ["CODE_WORDS", "TEMPLATES"]

CODE_WORDS = ("SECTOR", "GRID", "ALPHA", "BRAVO", "DELTA", "ECHO", "KILO", "RIDGE", "VALLEY",
              "HARBOR")


def _broadcast_status(view: SessionView, rng: random.Random) -> TaskDraft:
    (a,) = pick(rng, view.drones, 1)
    alt = rng.randint(10, 30)
    count = rng.randint(2, 3)
    text = f"{a.name} airborne at {alt} m, all systems normal."
    return TaskDraft(
        phrasings=[
            f"Take off with {a.name} to {alt} m, then broadcast the status line \"{text}\" to "
            f"the whole fleet {count} times.",
            f"{a.name}: climb to {alt} metres and send the broadcast \"{text}\" to every "
            f"drone, repeating it so that it goes out {count} times in all.",
            f"Launch {a.name} to an altitude of {alt} m. When it is up, it should announce "
            f"\"{text}\" by broadcast, {count} times.",
        ],
        checks=all_of(
            leaf("drone_has_taken_off", drone_id=a.id, min_altitude=float(alt),
                 max_altitude=float(alt), tolerance=1.5),
            leaf("drone_has_sent_message", drone_id=a.id, min_count=count),
        ),
        oracle=[[{"op": "takeoff", "drone": a.id, "altitude_m": alt},
                 *({"op": "broadcast", "drone": a.id, "text": text} for _ in range(count))]],
        steps=1 + count,
    )


TEMPLATES = (
    load_template(FILES / "relay_report.json"),
    Template("broadcast_status", "communication", "easy", _broadcast_status, drones=2),
    load_template(FILES / "spot_and_tell.json"),
)
