"""`mavswarm bench`: generate, run, report and import the benchmark.

  mavswarm bench generate [--out DIR] [--only ID ...] [--no-verify] [--workers N]
                          [--backend local|ray [--ray-address ADDR]] [--verbose]
  mavswarm bench run --agent oracle|noop|react|workflow|external|NAME|module:Name|file.py:Name
                     [--model M --base-url URL] [--agent-timeout-s S]
                     [--suite smoke|full | --sessions FILE ...]
                     [--workers N] [--trials K] [--clock lockstep|stepped] [--out DIR]
                     [--backend local|ray [--ray-address ADDR]] [--inspector-url URL]
                     [--host H --port P] [--verbose]
  mavswarm bench agents
  mavswarm bench report RESULTS [RESULTS ...] [--out DIR] [--inspector-url URL]
  mavswarm bench compare RUN [RUN ...] [--baseline RUN] [--intersect] [--out DIR]
                         [--seed N] [--resamples N] [--inspector-url URL]
  mavswarm bench import FILE [FILE ...] --out DIR [--no-prove]
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from typing import Any

from benchmark.authoring.suite import SUITES, suite_paths
from benchmark.reporting.report_html import DEFAULT_INSPECTOR_URL
from benchmark.running.backends import BACKENDS
from benchmark.running.episode import CLOCKS
from benchmark.running.hosted import EXTERNAL
from benchmark.running.hosted.options import add_hosted_arguments
from benchmark.running.worker_count import AUTO, auto_workers
from emulator.link_faults import add_link_arguments, link_faults_from_args
from mqtt_bus.cli import add_mqtt_arguments, mqtt_options
from swarm_agents.plugins import ENTRY_POINT_GROUP

__all__ = ["add_parsers", "add_verbose_argument", "run_bench"]


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """The `bench` command and its subcommands, on the `mavswarm` command's subparsers."""
    bench = sub.add_parser("bench", help="generate, run and report the benchmark",
                           description=__doc__,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    bench.set_defaults(run=run_bench)
    bsub = bench.add_subparsers(dest="bench_command", required=True)

    gen = bsub.add_parser("generate", help="generate the 100 seeded sessions with their tasks")
    gen.add_argument("--out", type=Path, default=Path("runs/suite"), help="output folder")
    gen.add_argument("--only", nargs="+", metavar="ID",
                     help="session ids to generate (e.g. area_search-easy-1)")
    gen.add_argument("--no-verify", action="store_true",
                     help="skip proving each task with the oracle (faster; not for release)")
    gen.add_argument("--workers", type=_at_least_one, default=1, help="sessions generated at once")
    _add_draw_arguments(gen)
    _add_backend_arguments(gen)
    add_verbose_argument(gen)

    run = bsub.add_parser("run", help="run an agent over the benchmark")
    run.add_argument("--agent", default="oracle", metavar="SPEC",
                     help="oracle (default), noop, react, workflow, an installed plug-in's "
                          "name, package.module:Name or path/to/file.py:Name (an agent, its "
                          "class or a factory: docs/agents/plugins.md); NAME:per-drone "
                          "gives each drone its own instance. `mavswarm bench agents` lists them; "
                          "external: host the run for an agent outside this process "
                          "(docs/agents/hosted.md)")
    run.add_argument("--agent-timeout-s", type=float, default=600.0, metavar="S",
                     help="stop an agent that makes no tool call and lets no simulated time "
                          "pass for S wall seconds (hung); its task ends as agent_error "
                          "(default 600)")
    run.add_argument("--model", default="", help="LLM agents: model name (or OPENAI_MODEL)")
    run.add_argument("--base-url", default="",
                     help="LLM agents: OpenAI-compatible base URL (or OPENAI_BASE_URL; the "
                          "key comes from OPENAI_API_KEY)")
    run.add_argument("--price-in", type=float, default=0.0, metavar="USD",
                     help="LLM agents: price per million prompt tokens, for the cost per task")
    run.add_argument("--price-out", type=float, default=0.0, metavar="USD",
                     help="LLM agents: price per million completion tokens")
    group = run.add_mutually_exclusive_group()
    group.add_argument("--suite", choices=SUITES, default="smoke",
                       help="smoke: 3 easy sessions, 6 tasks each; full: 125 sessions, 2500 tasks")
    group.add_argument("--sessions", type=Path, nargs="+", metavar="FILE",
                       help="session files to run instead of a suite")
    run.add_argument("--workers", type=_workers, default=1,
                     help="sessions run at once, spread over at most one process per core; "
                          "auto: chosen from the cores (an agent that answers at once) or the "
                          "memory (one that thinks); see docs/performance.md")
    run.add_argument("--trials", type=_at_least_one, default=1,
                     help="repeats of every task (pass^k)")
    run.add_argument("--clock", choices=CLOCKS, default="lockstep",
                     help="lockstep (default): simulated time runs only while the agent waits "
                          "on the world, so results do not depend on think time; stepped: it "
                          "runs whenever a drone executes a goal, thinking included")
    run.add_argument("--out", type=Path, default=None,
                     help="results folder (default runs/bench-<agent>-<suite>); re-running "
                          "with the same folder resumes")
    _add_backend_arguments(run)
    _add_inspector_argument(run)
    add_verbose_argument(run)
    add_mqtt_arguments(run, session=False)
    add_link_arguments(run)
    add_hosted_arguments(run)

    bsub.add_parser("agents", help="list the agents --agent can name: built-in and installed "
                    f"plug-ins (entry points in the group {ENTRY_POINT_GROUP})")

    report = bsub.add_parser("report", help="metrics report of results files")
    report.add_argument("results", type=Path, nargs="+",
                        help="results.jsonl files or their folders; several are reported "
                             "each on its own")
    report.add_argument("--out", type=Path, default=None,
                        help="folder for report.md, report.json and report.html (default: "
                             "beside the first)")
    _add_inspector_argument(report)
    report.add_argument("--allow-mixed", action="store_true",
                        help="pool records of different suites (session files of one id with "
                             "different fingerprints, e.g. a public and a private split)")

    compare = bsub.add_parser("compare", help="compare runs: paired transitions with McNemar "
                              "tests, rates with bootstrap intervals (compare.md/.json/.html)")
    compare.add_argument("runs", type=Path, nargs="+", metavar="RUN",
                         help="results folders or results.jsonl files (a file with several "
                              "agents counts as one run per agent)")
    compare.add_argument("--baseline", default=None, metavar="RUN",
                         help="the run the others are paired against: a run id or path "
                              "(default: the first)")
    compare.add_argument("--intersect", action="store_true",
                         help="compare runs of different suites or task sets on the tasks all "
                              "of them ran (default: refuse)")
    compare.add_argument("--out", type=Path, default=Path("runs/compare"),
                         help="folder for compare.md, compare.json and compare.html (default "
                              "runs/compare)")
    compare.add_argument("--seed", type=int, default=0, help="bootstrap seed (default 0)")
    compare.add_argument("--resamples", type=int, default=2000,
                         help="bootstrap resamples (default 2000)")
    _add_inspector_argument(compare)

    imp = bsub.add_parser("import", help="convert MultiUAV-Plat session files (with their tasks)")
    imp.add_argument("files", type=Path, nargs="+")
    imp.add_argument("--out", type=Path, required=True)
    imp.add_argument("--no-prove", action="store_true",
                     help="skip flying every task with the oracle (by default each task's "
                          "proof is written into it and a task not proved makes the exit "
                          "status 1)")


def _at_least_one(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of at least 1")
    return value


def _workers(text: str) -> int | str:
    from benchmark.running.worker_count import parse_workers
    try:
        return parse_workers(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def add_verbose_argument(parser: argparse.ArgumentParser) -> None:
    """`--verbose`: MAVSDK's own log lines and the packages' info logging on the terminal
    (off by default; the `mavswarm` command applies it)."""
    parser.add_argument("--verbose", action="store_true",
                        help="also print MAVSDK's own log lines and info logging")


def _add_inspector_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--inspector-url", default=DEFAULT_INSPECTOR_URL, metavar="URL",
                        help="where report.html links each task: the inspector that "
                             "`mavswarm replay RESULTS_DIR` serves (default "
                             f"{DEFAULT_INSPECTOR_URL})")


def _add_backend_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--backend", choices=BACKENDS, default="local",
                        help="where sessions run: local worker processes (default) or Ray "
                             "tasks on a Ray cluster (pip install 'mavswarm[ray]')")
    parser.add_argument("--ray-address", default="", metavar="ADDR",
                        help="--backend ray: the cluster to join (HEAD_IP:PORT or auto; "
                             "default: RAY_ADDRESS, a cluster started here, else a one-node "
                             "instance for this run)")


def _add_draw_arguments(gen: argparse.ArgumentParser) -> None:
    """A researcher's draw: docs/benchmark/own-tasks.md."""
    gen.add_argument("--seed", default="", metavar="SECRET",
                     help="draw a private split: the shipped suite's distribution, other "
                          "sessions nobody draws again without SECRET")
    gen.add_argument("--families", nargs="+", default=[], metavar="FAMILY")
    gen.add_argument("--levels", nargs="+", default=[], metavar="LEVEL")
    gen.add_argument("--sessions-per-cell", type=int, default=0, metavar="N",
                     help="sessions per family x level (default 5)")
    gen.add_argument("--tasks-per-session", type=int, default=0, metavar="N",
                     help="tasks per session (default 20)")
    gen.add_argument("--templates", type=Path, action="append", default=[], metavar="DIR",
                     help="a folder of template files (*.json) added to the built-ins "
                          "(repeatable)")
    gen.add_argument("--replace-templates", action="store_true",
                     help="draw from the --templates folders only")
    gen.add_argument("--world", type=Path, default=None, metavar="FILE",
                     help="draw tasks for this session file's world instead of the suite's")
    gen.add_argument("--drones", type=_at_least_one, default=0, metavar="N",
                     help="drones in every drawn world (1-100; default: the level's)")
    gen.add_argument("--map-size-m", type=float, default=0.0, metavar="M",
                     help="every drawn world on an M x M m map (200-10000; default: the "
                          "level's)")


def _generate(args: argparse.Namespace) -> int:
    from benchmark.authoring.suite import Draw
    from benchmark.running.generation import generate_suite
    from benchmark.running.progress import ProgressBar
    draw = Draw(secret=args.seed, families=tuple(args.families), levels=tuple(args.levels),
                sessions_per_cell=args.sessions_per_cell, tasks=args.tasks_per_session,
                templates=tuple(args.templates), replace=args.replace_templates,
                drones=args.drones, map_size_m=args.map_size_m)
    if args.world is not None:
        if args.drones or args.map_size_m:
            raise ValueError("--drones and --map-size-m shape the worlds bench generate draws; "
                             "a --world file keeps its own drones and map")
        from benchmark.running.generation import generate_world_file
        print(f"wrote {generate_world_file(args.world, args.out, draw, not args.no_verify)}")
        return 0
    with ProgressBar("sessions", pass_rate=False) as bar:
        written = generate_suite(args.out, only=args.only, verify=not args.no_verify,
                                 draw=draw,
                                 workers=args.workers, backend=args.backend,
                                 ray_address=args.ray_address, mavsdk_log=args.verbose,
                                 on_start=bar.begin,
                                 on_generated=lambda path: bar.advance(f"generated {path}"),
                                 progress=bar.say)
    print(f"wrote {len(written)} session files to {args.out}")
    return 0


def _run(args: argparse.Namespace) -> int:
    from benchmark.reporting.report import metrics_table, write_report
    from benchmark.reporting.report_html import check_inspector_url
    from benchmark.running.orchestrator import RunPlan, check_session_files, run_benchmark
    from benchmark.running.progress import ProgressBar
    from benchmark.running.results import read_records
    from benchmark.scoring.metrics import summarize
    from swarm_agents.plugins import check_spec
    if args.agent != EXTERNAL:
        check_spec(args.agent)  # a bad --agent is one line, before anything starts
    if not args.agent_timeout_s > 0:
        raise ValueError(f"--agent-timeout-s must be > 0, got {args.agent_timeout_s:g}")
    if args.sessions:
        paths, limit, label = tuple(args.sessions), None, "custom"
        check_session_files(paths)  # unreadable or without tasks: refused, nothing runs
    else:
        paths, limit = suite_paths(args.suite)
        label = args.suite
    if args.workers == AUTO:
        args.workers = auto_workers(args.agent, args.trials * len(paths))
        print(f"--workers auto: {args.workers} sessions at once")
    agent_label = re.sub(r"[^A-Za-z0-9_.:-]+", "-", args.agent).strip("-.")
    out = args.out or Path(f"runs/bench-{agent_label}-{label}")
    check_inspector_url(args.inspector_url)
    url = mqtt_options(args)
    plan = RunPlan(sessions=paths, agent=args.agent, trials=args.trials, workers=args.workers,
                   out_dir=out, task_limit=limit, model=args.model, base_url=args.base_url,
                   price_in_usd_per_mtok=args.price_in, price_out_usd_per_mtok=args.price_out,
                   clock=args.clock, backend=args.backend, ray_address=args.ray_address,
                   mavsdk_log=args.verbose, live_hz=getattr(args, "live_hz", 0.0),
                   link_faults=_link_faults_json(args), agent_timeout_s=args.agent_timeout_s,
                   external_host=args.host)
    where = ""
    if args.backend == "ray":
        where = f" as Ray tasks at {args.ray_address}" if args.ray_address else " as Ray tasks"
    print(f"mavswarm bench: {args.agent} agent, {len(paths)} sessions"
          f"{f' ({limit} tasks each)' if limit else ''}, {args.trials} trial(s), "
          f"{args.workers} worker(s){where}; results in {plan.results_path}")
    on_live = getattr(args, "on_live", None)
    on_message = getattr(args, "on_message", None)  # --agent external (_run_hosted)
    if url is None:
        with ProgressBar("tasks") as bar:
            outcome = run_benchmark(plan, sink=bar, on_live=on_live, on_message=on_message)
        records = read_records(plan.results_path)
    else:
        from mqtt_bus import BenchBus
        run_name = re.sub(r"[^A-Za-z0-9_.:-]", "-", out.resolve().name)[:64] or "run"
        from benchmark.running.results import ResultsError, read_task_records
        try:  # a resumed run first publishes what the file already holds
            earlier = (read_task_records(plan.results_path) if plan.results_path.exists()
                       else [])
        except ResultsError:  # a damaged line: run_benchmark repairs or refuses it
            earlier = []
        with BenchBus(url, run_name) as bus:
            print(f"MQTT: {url.redacted()} topics {bus.topics.base}/tasks, .../progress")
            for record in earlier:
                bus.record(record)
            with ProgressBar("tasks") as bar:
                outcome = run_benchmark(plan, sink=bar, on_record=bus.record,
                                        on_live=on_live, on_message=on_message)
            records = read_records(plan.results_path)
            bus.finish(len(records))
        stats = bus.stats
        print(f"MQTT: {stats.published} messages published, {stats.dropped} dropped")
    md, js, html = write_report(records, out, inspector_url=args.inspector_url,
                                run_id=out.resolve().name)
    print()
    print(metrics_table(summarize(records)))
    print(f"\n{outcome.records_written} new task records in {outcome.wall_s:.1f} s; "
          f"{len(records)} in {plan.results_path}; report: {md}, {js}, {html}")
    print(f"charts: open {html} in a browser; `mavswarm replay {out}` serves the task pages "
          "it links to")
    for error in outcome.errors:
        print(f"error: {error}", file=sys.stderr)
    return 1 if outcome.errors else 0


def _run_hosted(args: argparse.Namespace) -> int:
    """--agent external: `_run` with the hosted run's endpoint around it
    (benchmark/running/hosted)."""
    from benchmark.running.hosted.run import hosting
    sessions = args.sessions or suite_paths(args.suite)[0]
    if args.workers == AUTO:
        args.workers = auto_workers(EXTERNAL, args.trials * len(sessions))
    with hosting(workers=args.workers, units=args.trials * len(sessions), host=args.host,
                 port=args.port) as on_message:
        args.on_message = on_message
        return _run(args)


def _link_faults_json(args: argparse.Namespace) -> dict[str, Any] | None:
    """--link-* options as LinkFaults JSON for every session (None: each session's own)."""
    faults = link_faults_from_args(args)
    return None if faults is None else faults.to_json()


def _report(args: argparse.Namespace) -> int:
    from benchmark.authoring.fingerprint import check_poolable
    from benchmark.reporting.report import metrics_table, write_report
    from benchmark.reporting.report_html import check_inspector_url
    from benchmark.reporting.report_runs import load_report_runs, write_runs_report
    from benchmark.scoring.metrics import summarize
    check_inspector_url(args.inspector_url)
    runs = load_report_runs(args.results)
    # one suite unless asked (benchmark.authoring.fingerprint), though each run is reported apart
    check_poolable([r for run in runs for r in run.records], allow_mixed=args.allow_mixed)
    out = args.out or runs[0].source.parent
    if len(runs) == 1:
        md, js, html = write_report(runs[0].records, out, inspector_url=args.inspector_url,
                                    results_dir=runs[0].source.parent, run_id=runs[0].id)
        print(metrics_table(summarize(runs[0].records)))
    else:  # each run on its own: never one pooled headline
        md, js, html, *_ = write_runs_report(runs, out, inspector_url=args.inspector_url)
        for run in runs:
            print(f"{run.id} ({run.source}):\n{metrics_table(summarize(run.records))}\n")
    folders = " ".join(str(run.source.parent) for run in runs)
    print(f"\nreport: {md}, {js}, {html}")
    print(f"charts: open {html} in a browser; `mavswarm replay {folders}` serves the task pages "
          "it links to")
    return 0


def _compare(args: argparse.Namespace) -> int:
    from benchmark.reporting.compare import compare_paths, write_compare
    from benchmark.reporting.compare.markdown import p_value, pct_interval
    from benchmark.reporting.report_html import check_inspector_url
    check_inspector_url(args.inspector_url)
    report = compare_paths(args.runs, baseline=args.baseline, intersect=args.intersect,
                           resamples=args.resamples, seed=args.seed)
    folders = " ".join(sorted({str(Path(r.source).parent) for r in report.runs}))
    paths = write_compare(report, args.out, inspector_url=args.inspector_url,
                          serve_hint=folders)
    for warning in report.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    for run in report.runs:
        print(f"{run.id:<24} Task Pass {pct_interval(run.task_pass_rate)}  ({run.tasks} tasks)")
    for pair in report.pairs:
        t = pair.overall
        print(f"{pair.run} vs {pair.baseline}: {t.fail_to_pass} fail->pass, {t.pass_to_fail} "
              f"pass->fail, {t.both_pass} both pass, {t.both_fail} both fail; McNemar p = "
              f"{p_value(t.mcnemar_p)}")
    print(f"\ncompare: {', '.join(map(str, paths))}")
    return 0


def _agents(args: argparse.Namespace) -> int:
    from swarm_agents.plugins import listing
    rows = listing()
    width = max(len(r.name) for r in rows) + 2
    for row in rows:
        print(f"{row.name:<{width}}{row.source}: {row.about}")
    print(f"\nAlso: package.module:Name or path/to/file.py:Name; NAME:per-drone (react, "
          f"workflow, plug-ins) for one instance per drone. Packages add agents with entry "
          f"points in the group {ENTRY_POINT_GROUP}.")
    return 0


def _import(args: argparse.Namespace) -> int:
    from benchmark.running.proof import import_files
    return 1 if import_files(args.files, args.out, prove=not args.no_prove) else 0


def run_bench(args: argparse.Namespace) -> int:
    """Run a parsed `mavswarm bench` command; bad input is printed, exit 2."""
    from benchmark.authoring.session_file import SessionFileError
    from benchmark.running.results import ResultsError
    hosted = getattr(args, "agent", None) == EXTERNAL
    handlers = {"generate": _generate, "run": _run_hosted if hosted else _run,
                "report": _report, "import": _import, "agents": _agents, "compare": _compare}
    try:
        return handlers[args.bench_command](args)
    except (SessionFileError, ResultsError, ValueError, OSError) as error:
        print(f"mavswarm: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\nmavswarm: interrupted; re-run the same command to resume", file=sys.stderr)
        return 130
