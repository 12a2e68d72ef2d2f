"""Verified generation: sessions drawn by `benchmark.authoring.generate` whose every task the
oracle has flown over MAVLink and passed (a task it fails is redrawn), one session, a world of
one's own, or the whole suite in local processes or as Ray tasks."""

from __future__ import annotations

import asyncio
import functools
import multiprocessing
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from benchmark.authoring import generate as draw_tasks
from benchmark.authoring.generate import (
    MAX_ATTEMPTS,
    TASKS_PER_SESSION,
    Drawer,
    GenerationError,
    catalogue_with,
    write_session,
)
from benchmark.authoring.scenarios import SESSION_INDICES, all_session_keys
from benchmark.authoring.scenarios.placement import PlacementError
from benchmark.authoring.session_file import Session, read_session_json, task_from_dict
from benchmark.authoring.suite import Draw, suite_keys
from benchmark.authoring.templates import TemplateUnfit
from benchmark.running.episode import swarm_gateway
from benchmark.running.proof import fly_task, proof_of
from swarm_agents.oracle import OracleAgent

__all__ = ["generate_for_world", "generate_session", "generate_suite", "generate_world_file",
           "verified_tasks"]

_ALL = Draw()  # the shipped suite's draw


def verified_tasks(world: dict[str, Any], session: Session, drawer: Drawer, count: int,
                   progress: Callable[[str], None]) -> list[dict[str, Any]]:
    """`count` tasks drawn for the world's empty session, each kept only once the oracle has
    passed it (the `prove` of `benchmark.authoring.generate`)."""
    return asyncio.run(_proved_tasks(world, session, drawer, count, progress))


def generate_session(family: str, level: str, index: int, *, verify: bool = True,
                     **options: Any) -> dict[str, Any]:
    """`benchmark.authoring.generate.generate_session`, proved by the oracle when verify."""
    return draw_tasks.generate_session(family, level, index,
                                       prove=verified_tasks if verify else None, **options)


def generate_for_world(world: dict[str, Any], *, verify: bool = True,
                       **options: Any) -> dict[str, Any]:
    """`benchmark.authoring.generate.generate_for_world`, proved by the oracle when verify."""
    return draw_tasks.generate_for_world(world, prove=verified_tasks if verify else None,
                                         **options)


async def _proved_tasks(world: dict[str, Any], session: Session, drawer: Drawer,
                          count: int, progress: Callable[[str], None]) -> list[dict[str, Any]]:
    agent = OracleAgent(session.scenario, {})
    tasks: list[dict[str, Any]] = []
    async with swarm_gateway(session) as (swarm, services, gateway):
        for slot in range(count):
            start = services.operator_snapshot()
            unproved: list[str] = []
            for attempt in range(MAX_ATTEMPTS):
                try:
                    raw = drawer.draw(slot, attempt)
                except TemplateUnfit:
                    continue
                spec = task_from_dict(slot, raw, session.scenario)
                if spec.error is not None:
                    raise GenerationError(f"{world['id']}: {spec.error}")
                agent.set_plan(spec.id, spec.oracle)
                if spec.checks is not None:  # no hand plan: one derived from the checks
                    agent.set_checks(spec.id, spec.checks, sorted(
                        {f.drone for f in spec.faults.failures} if spec.faults else ()))
                record = await fly_task(session, spec, agent, swarm, services, gateway, start)
                if record["passed"]:
                    drawer.accept(raw)
                    tasks.append(raw)
                    break
                proof = proof_of(str(world["id"]), spec, record)
                unproved.append(proof.line())
                progress(f"{proof.line()}; redrawing")
            else:
                raise GenerationError(f"{world['id']}: slot {slot + 1}: no task the oracle can "
                                      f"prove in {MAX_ATTEMPTS} attempts: "
                                      + " | ".join(unproved[-3:]))
    return tasks



def _generate_one(key: tuple[str, str, int], out_dir: Path, verify: bool,
                  mavsdk_log: bool = False,
                  progress: Callable[[str], None] = print, draw: Draw = _ALL) -> Path:
    from mavlink_gateway import set_mavsdk_log
    set_mavsdk_log(mavsdk_log)
    catalogue = catalogue_with(draw.templates, replace=draw.replace)
    try:
        session = generate_session(*key, verify=verify, progress=progress, secret=draw.secret,
                                   tasks=draw.tasks or TASKS_PER_SESSION, catalogue=catalogue,
                                   max_index=max(key[2], SESSION_INDICES[-1]),
                                   drones=draw.drones, map_size_m=draw.map_size_m)
    except PlacementError as error:
        if not (draw.drones or draw.map_size_m):
            raise
        raise ValueError(f"{error}: the level's entities do not fit; choose a larger "
                         f"--map-size-m or fewer --drones") from None
    return write_session(session, out_dir)


def _print_generated(path: Path) -> None:
    print(f"generated {path}", flush=True)


def generate_suite(out_dir: Path, *, only: Sequence[str] | None = None, verify: bool = True,
                   workers: int = 1, backend: str = "local", ray_address: str = "",
                   mavsdk_log: bool = False,
                   on_start: Callable[[int], None] | None = None,
                   on_generated: Callable[[Path], None] = _print_generated,
                   progress: Callable[[str], None] = print, draw: Draw = _ALL
                   ) -> list[Path]:
    """Generate the suite's session files (all 125, or the ids in `only`) into out_dir, in
    `workers` local processes or, with backend "ray", as Ray tasks (benchmark/running/backends.py).
    `on_start(n)` is told how many sessions will be generated, `on_generated(path)` each file
    as it is written, and `progress` (in this process) each redrawn task; `mavsdk_log`
    prints MAVSDK's own log lines."""
    keys = list(all_session_keys()) if draw.is_default else suite_keys(draw)
    if draw.templates:
        catalogue_with(draw.templates, replace=draw.replace)  # bad files: said before any work
    if only:
        wanted = set(only)
        unknown = wanted - {f"{k[0]}-{k[1]}-{k[2]}" for k in keys}
        if unknown:
            raise ValueError(f"unknown session ids: {', '.join(sorted(unknown))}")
        keys = [k for k in keys if f"{k[0]}-{k[1]}-{k[2]}" in wanted]
    if on_start is not None:
        on_start(len(keys))
    if backend != "local" or ray_address:
        if not draw.is_default:
            raise ValueError("--backend ray draws the shipped suite only; drop --seed, "
                             "--families, --levels, --sessions-per-cell, --tasks-per-session "
                             "and --templates, or generate locally")
        from benchmark.running.backends import make_backend
        make_backend(backend, workers=workers, ray_address=ray_address)  # says what is wrong
        from benchmark.running.ray_backend import generate_on_ray
        return generate_on_ray(keys, out_dir, verify=verify, workers=workers,
                               address=ray_address, on_generated=on_generated)
    if workers <= 1:
        written = []
        for key in keys:
            path = _generate_one(key, out_dir, verify, mavsdk_log, progress, draw)
            on_generated(path)
            written.append(path)
        return written
    ctx = multiprocessing.get_context("spawn")
    one = functools.partial(_generate_one, out_dir=out_dir, verify=verify,
                            mavsdk_log=mavsdk_log, draw=draw)
    with ctx.Pool(workers) as pool:
        results = [pool.apply_async(one, (k,)) for k in keys]
        written = []
        for result in results:
            path = result.get()
            on_generated(path)
            written.append(path)
    return written


def generate_world_file(world_file: Path, out_dir: Path, draw: Draw, verify: bool) -> Path:
    """`bench generate --world FILE`: draw the tasks for the world of a session file (its own
    tasks are replaced), prove them with the oracle when verify, and write the session into
    out_dir."""
    data = read_session_json(world_file)
    if not isinstance(data, dict):
        raise ValueError(f"{world_file}: the top level must be a JSON object")
    catalogue = catalogue_with(draw.templates, replace=draw.replace)
    session = generate_for_world(data, secret=draw.secret, verify=verify,
                                 tasks=draw.tasks or TASKS_PER_SESSION, catalogue=catalogue)
    return write_session(session, out_dir)
