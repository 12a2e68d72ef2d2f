"""How many tasks drawn from MultiUAV-Plat's default templates (read in the reference's own
template layout: tests/data/multiuav_default_templates.json) the oracle proves, with plans
derived from the checks alone (the templates carry no plan of ours).

    python perf/reference_templates.py                    # every template, 1 task each,
                                                                # on each world that suits it
    python perf/reference_templates.py --per-template 3 --only basic_takeoff
    python perf/reference_templates.py --world path/to/session.json

Worlds: the reference's two example sessions (imported as `bench import` reads them, when
/work/shared/sessions or shared/sessions holds them) and a moderate (1000 x 1000 m) session of
each family of the shipped suite (the templates' coordinates reach ~1000 m). Prints the proof
rate, every task not proved with its leaf and reason, and the time taken.
"""

from __future__ import annotations

import argparse
import collections
import json
import random
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmark.authoring.generate import build_task  # noqa: E402
from benchmark.authoring.importer import import_session  # noqa: E402
from benchmark.authoring.session_file import read_session_json, session_from_dict  # noqa: E402
from benchmark.authoring.template_files import read_templates, template_of  # noqa: E402
from benchmark.authoring.templates.base import SessionView, TemplateUnfit  # noqa: E402
from benchmark.running.proof import TaskProof, prove_session  # noqa: E402

CATALOGUE = ROOT / "tests" / "data" / "multiuav_default_templates.json"
EXAMPLES = ("Example_Session_Area_Search.json", "Example_Session_Target_Assignment.json")
OURS = ("area_search", "area_assignment_and_patrol", "target_assignment", "target_tracking")


def _worlds(extra: list[Path]) -> list[dict[str, Any]]:
    worlds = []
    for folder in (ROOT / "shared" / "sessions", ROOT.parent.parent / "shared" / "sessions",
                   Path("/work/shared/sessions")):
        if folder.is_dir():
            for name in EXAMPLES:
                if (folder / name).exists():
                    data, _ = import_session(json.loads((folder / name).read_text()),
                                             source=str(folder / name))
                    worlds.append(data)
            break
    for family in OURS:
        worlds.append(read_session_json(ROOT / "benchmark" / "sessions" /
                                        f"{family}-moderate-1.json"))
    for path in extra:
        data = read_session_json(path)
        worlds.append(data if data.get("schema") else import_session(data, source=str(path))[0])
    return worlds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--per-template", type=int, default=1)
    parser.add_argument("--only", nargs="+", default=[], metavar="KEY")
    parser.add_argument("--world", type=Path, nargs="+", default=[])
    parser.add_argument("--seed", default="reference")
    args = parser.parse_args()
    templates = [template_of(m) for m in read_templates(CATALOGUE)
                 if not args.only or m.id in args.only]
    proofs: list[TaskProof] = []
    wall0 = time.perf_counter()
    for world in _worlds(args.world):
        empty = session_from_dict({**world, "tasks": []}, source=world["id"])
        w, h = world["map_size_m"]
        view = SessionView(str(world.get("family") or world.get("task_type")), empty.scenario,
                           float(w), float(h))
        tasks = []
        for template in templates:
            if not template.fits(view):
                continue
            for k in range(args.per_template):
                rng = random.Random(f"{args.seed}/{world['id']}/{template.key}/{k}")
                try:
                    tasks.append(build_task(template, view, rng, f"t{len(tasks) + 1:03d}"))
                except TemplateUnfit as unfit:
                    print(f"{world['id']} {template.key}: does not fit ({unfit})")
        session = session_from_dict({**world, "tasks": tasks}, source=world["id"])
        t0 = time.perf_counter()
        proofs += prove_session(session, progress=lambda p: print(p.line(), flush=True))
        print(f"{world['id']}: {len(tasks)} tasks in {time.perf_counter() - t0:.0f} s",
              flush=True)
    wall_s = time.perf_counter() - wall0
    by_template: dict[str, list[bool]] = collections.defaultdict(list)
    for proof in proofs:
        by_template[proof.template].append(proof.proved)
    proved = sum(p.proved for p in proofs)
    print(f"\nproved {proved} of {len(proofs)} tasks ({100.0 * proved / max(1, len(proofs)):.1f} "
          f"%) from {len(by_template)} templates in {wall_s:.0f} s")
    for proof in proofs:
        if not proof.proved:
            print(f"  {proof.line()}")


if __name__ == "__main__":
    main()
