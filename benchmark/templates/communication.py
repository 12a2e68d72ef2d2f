"""Communication: a report with a code word, repeated status broadcasts, spot a target and tell.

Messages are checked on their text: a direct message must reach the named drone and contain
the given words exactly (case included); a broadcast counts as a message to every drone.
"""

from __future__ import annotations

import random

from benchmark.template_files.loader import load_template
from benchmark.templates.base import (
    SessionView,
    TaskDraft,
    Template,
    TemplateUnfit,
    all_of,
    fmt_xy,
    leaf,
    pick,
)
from benchmark.templates.common import FILES
from benchmark.templates.common import diagonal_m as _diagonal_m

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


def _spot_and_tell(view: SessionView, rng: random.Random) -> TaskDraft:
    a, b = pick(rng, view.drones, 2)
    candidates = [*view.points, *view.areas]
    if not candidates:
        raise TemplateUnfit("no point or area target to spot")
    target = rng.choice(candidates)
    alt = rng.randint(15, 30)
    where = fmt_xy(target.position_m[0], target.position_m[1])
    text = f"{target.name} spotted, come and confirm."
    return TaskDraft(
        phrasings=[
            f"{a.name} flies at {alt} m over {target.name} at {where}. When it gets there, it "
            f"sends {b.name} a message naming the target (\"{target.name}\"). Then {b.name} "
            f"flies over {target.name} as well.",
            f"Spot and tell: take {a.name} over {target.name} {where} at {alt} metres, have "
            f"it message {b.name} with the name \"{target.name}\", and afterwards send "
            f"{b.name} over the same target.",
            f"First {a.name} reaches {target.name} (around {where}, fly at {alt} m); next it "
            f"tells {b.name} by direct message, including the text \"{target.name}\"; "
            f"finally {b.name} also flies over {target.name}.",
        ],
        checks=all_of(
            leaf("target_is_reached_by_drone", target_id=target.id, drone_id=a.id),
            leaf("drone_has_sent_message_content", drone_id=a.id, content=target.name,
                 to_drone_id=b.id),
            leaf("target_is_reached_by_drone", target_id=target.id, drone_id=b.id),
        ),
        oracle=[
            [{"op": "reach", "drone": a.id, "target": target.id, "altitude_m": alt}],
            [{"op": "message", "drone": a.id, "to": b.id, "text": text}],
            [{"op": "reach", "drone": b.id, "target": target.id, "altitude_m": alt}],
        ],
        flight_m=_diagonal_m(view),
        steps=5,
    )


TEMPLATES = (
    load_template(FILES / "relay_report.json"),
    Template("broadcast_status", "communication", "easy", _broadcast_status, drones=2),
    Template("spot_and_tell", "communication", "medium", _spot_and_tell, drones=2),
)
