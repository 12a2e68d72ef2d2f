"""Agents by name, for `mavswarm bench run --agent SPEC` and `mavswarm bench agents`.

SPEC is one of

- a built-in agent: ``oracle``, ``noop``, ``react``, ``workflow``;
- an installed plug-in: the name of an entry point in the group ``mavswarm.agents``, which a
  package declares in its pyproject.toml
  (``[project.entry-points."mavswarm.agents"] NAME = "package.module:Name"``);
- ``package.module:Name``: ``Name`` imported from ``package.module`` (on sys.path);
- ``path/to/file.py:Name``: ``Name`` from a Python file (a relative path is taken from the
  directory the run's command started in, in workers and on Ray nodes too; the file's folder
  is added to sys.path so it can import its neighbours);

``Name`` may be dotted (``Outer.attr``). Any but ``oracle`` and ``noop`` may end in
``:per-drone``: one instance per drone (`swarm_agents.teams.per_drone`). ``external`` is reserved (a
hosted run, not an agent in this process).

What ``Name`` may be (an agent instance, a class or a function called with the run's
`AgentOptions`) is in `agent_contract.protocol`. A spec is resolved from its text wherever a
session runs (this process, worker processes, Ray tasks): `check_spec` proves it in the driver
before a run starts (one line: `AgentSpecError`, a ValueError); `make_agent` builds it for one
session, where anything that goes wrong with a plug-in (its import, its factory, an object that
is no agent) becomes an agent whose every task ends as ``agent_error`` with the reason.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import re
import sys
import traceback
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from agent_contract import Agent, AgentOptions, AgentTask, AgentTools

if TYPE_CHECKING:
    from benchmark.authoring.session_file import Session

__all__ = ["BUILTIN_AGENTS", "ENTRY_POINT_GROUP", "LLM_AGENTS", "PER_DRONE", "RESERVED",
           "AgentListing", "AgentSpec", "AgentSpecError", "check_spec", "listing",
           "make_agent", "parse_spec"]

ENTRY_POINT_GROUP = "mavswarm.agents"
PER_DRONE = ":per-drone"
BUILTIN_AGENTS = {
    "oracle": "follows each task's hidden reference plan (the ceiling; not an AI)",
    "noop": "finishes at once without touching a drone (the floor)",
    "react": "ReAct loop over an OpenAI-compatible model (--model, --base-url)",
    "workflow": "plan-then-act LLM workflow (--model, --base-url)",
}
LLM_AGENTS = ("react", "workflow")
RESERVED = ("external",)  # a hosted run: no agent object in this process

Kind = Literal["builtin", "entry_point", "module", "file"]
_MODULE = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$")
_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]*$")
_HINT = ("a plug-in is package.module:Name, path/to/file.py:Name or an installed plug-in's "
         "name (`mavswarm bench agents` lists them)")


class AgentSpecError(ValueError):
    """An `--agent` spec that names no usable agent; the message is one line."""


@dataclass(frozen=True)
class AgentSpec:
    """A parsed `--agent` spec (see the module docstring)."""

    text: str  # as given: the name the records carry
    kind: Kind
    target: str  # the built-in or entry point's name, the module, or the file's path
    attr: str = ""  # the object in the module or file
    per_drone: bool = False


@dataclass(frozen=True)
class AgentListing:
    """One agent `mavswarm bench agents` lists: its name, where it comes from, a line on it."""

    name: str
    source: str
    about: str


def parse_spec(text: str) -> AgentSpec:
    """The spec's parts, from its text alone (nothing is imported)."""
    if not isinstance(text, str) or not text.strip():
        raise AgentSpecError(f"--agent: an agent name or spec is required; {_HINT}")
    base, per_drone = text, text.endswith(PER_DRONE)
    if per_drone:
        base = text.removesuffix(PER_DRONE)
    if base in RESERVED:
        raise AgentSpecError(f"--agent {text}: {base!r} is a hosted run, not an agent in this "
                             "process")
    if base in BUILTIN_AGENTS:
        if per_drone and base not in LLM_AGENTS:
            raise AgentSpecError(f"--agent {text}: {base} has no per-drone form (react, "
                                 "workflow and plug-ins do)")
        return AgentSpec(text, "builtin", base, per_drone=per_drone)
    where, sep, attr = base.rpartition(":")
    if not sep:
        if not _NAME.match(base) or base.endswith(".py"):
            raise AgentSpecError(f"--agent {text}: not an agent name; {_HINT}")
        return AgentSpec(text, "entry_point", base, per_drone=per_drone)
    if not where or not attr or not all(p.isidentifier() for p in attr.split(".")):
        raise AgentSpecError(f"--agent {text}: expected package.module:Name or "
                             "path/to/file.py:Name, with Name a Python name")
    if where.endswith(".py") or "/" in where or "\\" in where:
        return AgentSpec(text, "file", where, attr, per_drone)
    if not _MODULE.match(where):
        raise AgentSpecError(f"--agent {text}: {where!r} is neither a module name nor a .py "
                             "file")
    return AgentSpec(text, "module", where, attr, per_drone)


def _one_line(error: BaseException) -> str:
    """`Type: message (file:line)` of an exception, where it was raised."""
    message = " ".join(str(error).split()) or "(no message)"
    frames = [f for f in traceback.extract_tb(error.__traceback__)
              if not f.filename.startswith("<") and Path(f.filename) != Path(__file__)]
    where = f" ({Path(frames[-1].filename).name}:{frames[-1].lineno})" if frames else ""
    return f"{type(error).__name__}: {message}{where}"


def _plugin_entry_points() -> dict[str, list[EntryPoint]]:
    found: dict[str, list[EntryPoint]] = {}
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        found.setdefault(ep.name, []).append(ep)
    return found


def _dist(ep: EntryPoint) -> str:
    dist = ep.dist
    return f"{dist.name} {dist.version}" if dist is not None else "an unnamed distribution"


def _entry_point(spec: AgentSpec) -> EntryPoint:
    eps = _plugin_entry_points()
    found = eps.get(spec.target, [])
    if not found:
        builtin = ", ".join(BUILTIN_AGENTS)
        plugins = ", ".join(sorted(n for n in eps if n not in BUILTIN_AGENTS)) or "none"
        raise AgentSpecError(f"unknown agent {spec.text!r}: not a built-in ({builtin}) nor an "
                             f"installed plug-in ({plugins}); {_HINT}")
    if len(found) > 1:
        raise AgentSpecError(f"--agent {spec.text}: {len(found)} installed packages register "
                             f"it ({', '.join(_dist(ep) for ep in found)}); uninstall all but one")
    return found[0]


def _file_module(path: Path) -> Any:
    """The module of a plug-in file, imported once per process under a name of its own."""
    digest = hashlib.sha1(str(path).encode()).hexdigest()[:10]
    name = "mavswarm_agent_" + re.sub(r"\W", "_", path.stem) + "_" + digest
    if name in sys.modules:
        return sys.modules[name]
    module_spec = importlib.util.spec_from_file_location(name, path)
    if module_spec is None or module_spec.loader is None:
        raise AgentSpecError(f"{path} cannot be imported as a Python module")
    module = importlib.util.module_from_spec(module_spec)
    if str(path.parent) not in sys.path:
        sys.path.append(str(path.parent))
    sys.modules[name] = module
    try:
        module_spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def _load(spec: AgentSpec, base_dir: str) -> Any:
    """The object a plug-in spec names (AgentSpecError, one line, when it cannot be had)."""
    where = spec.target
    try:
        if spec.kind == "entry_point":
            ep = _entry_point(spec)
            where = f"entry point {ep.value} of {_dist(ep)}"
            return ep.load()
        if spec.kind == "file":
            path = (Path(base_dir or ".") / Path(spec.target).expanduser()).resolve()
            where = str(path)
            if not path.is_file():
                raise AgentSpecError(f"--agent {spec.text}: no file {path}")
            owner = _file_module(path)
        else:
            owner = importlib.import_module(spec.target)
        for part in spec.attr.split("."):
            if not hasattr(owner, part):
                raise AgentSpecError(f"--agent {spec.text}: {where} has no {spec.attr!r}")
            owner = getattr(owner, part)
        return owner
    except AgentSpecError:
        raise
    except (Exception, SystemExit) as error:  # the plug-in's own import failed
        raise AgentSpecError(f"--agent {spec.text}: importing {where} failed: "
                             f"{_one_line(error)}") from error


def _takes_options(factory: Any) -> bool | None:
    """Whether a factory is called with the options (True), with nothing (False), or cannot
    be called either way (None)."""
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):
        return None
    params = [p for p in signature.parameters.values()
              if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD, p.VAR_POSITIONAL)]
    first = params[0] if params else None
    wants = first is not None and first.kind is not first.VAR_POSITIONAL and (
        first.default is first.empty or first.name == "options")
    try:
        if wants:
            signature.bind(object())
        else:
            signature.bind()
    except TypeError:
        return None
    return wants


def _run_problem(run: Any, bound: bool) -> str | None:
    """Why `run` is not `async def run(self, task, tools)`, or None."""
    if run is None:
        return "has no run method"
    if not inspect.iscoroutinefunction(run):
        return "has a run that is not `async def` (it must be async def run(self, task, tools))"
    try:
        inspect.signature(run).bind(*([] if bound else [object()]), object(), object())
    except (TypeError, ValueError):
        return "has a run that does not take (task, tools)"
    return None


def _classify(obj: Any, spec: AgentSpec) -> Literal["instance", "factory"]:
    """Whether `obj` is an agent or a factory of agents (a class or a function);
    AgentSpecError if it is neither."""
    label = f"--agent {spec.text}"
    if inspect.ismodule(obj):
        raise AgentSpecError(f"{label}: names a module, not an agent; add :Name")
    if inspect.isclass(obj):
        problem = _run_problem(getattr(obj, "run", None), False)
        if problem is not None:
            raise AgentSpecError(f"{label}: class {obj.__name__} {problem}")
        if _takes_options(obj) is None:
            raise AgentSpecError(f"{label}: class {obj.__name__} cannot be made with no "
                                 "arguments nor with the run's options (AgentOptions)")
        return "factory"
    if not inspect.isroutine(obj) and hasattr(obj, "run"):
        problem = _run_problem(obj.run, True)
        if problem is not None:
            raise AgentSpecError(f"{label}: {type(obj).__name__} object {problem}")
        return "instance"
    if callable(obj):
        if inspect.iscoroutinefunction(obj):
            raise AgentSpecError(f"{label}: is a coroutine function; an agent is an object "
                                 "with async def run(self, task, tools), or its class")
        if _takes_options(obj) is None:
            raise AgentSpecError(f"{label}: {getattr(obj, '__name__', 'the callable')} takes "
                                 "neither no arguments nor the run's options (AgentOptions)")
        return "factory"
    raise AgentSpecError(f"{label}: a {type(obj).__name__} object is not an agent (it needs "
                         "async def run(self, task, tools))")


def check_spec(text: str, base_dir: str = "") -> AgentSpec:
    """Parse the spec and, for a plug-in, import and check its object (nothing is called):
    AgentSpecError, one line, if it names no usable agent."""
    spec = parse_spec(text)
    if spec.kind != "builtin":
        _classify(_load(spec, base_dir), spec)
    return spec


class PluginAgent:
    """A plug-in's agent under the name its records carry (its spec)."""

    def __init__(self, name: str, agent: Any) -> None:
        self.name = name
        self.agent = agent

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        result = self.agent.run(task, tools)
        if not inspect.isawaitable(result):
            raise TypeError(f"{type(self.agent).__name__}.run returned "
                            f"{type(result).__name__}, not an awaitable; define it as "
                            "async def run(self, task, tools)")
        await result


class BrokenAgent:
    """A plug-in that could not be made: each task ends as agent_error with the reason."""

    def __init__(self, name: str, error: BaseException) -> None:
        self.name = name
        self.error = error

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        raise self.error


def _build_plugin(spec: AgentSpec, options: AgentOptions, base_dir: str) -> Agent:
    """One instance of the plug-in; a BrokenAgent when anything goes wrong."""
    try:
        obj = _load(spec, base_dir)
        agent = obj
        if _classify(obj, spec) == "factory":
            agent = obj(options) if _takes_options(obj) else obj()
            problem = _run_problem(getattr(agent, "run", None), True)
            if problem is not None:
                raise AgentSpecError(f"--agent {spec.text}: the factory made a "
                                     f"{type(agent).__name__} object, which {problem}")
    except Exception as error:  # the plug-in's own code failed: its tasks say why
        return BrokenAgent(spec.text, error)
    return PluginAgent(spec.text, agent)


def _build_builtin(name: str, session: Session, options: AgentOptions) -> Agent:
    if name == "noop":
        from swarm_agents.baselines import NoopAgent
        return NoopAgent()
    if name == "oracle":
        from swarm_agents.oracle.session_oracle import oracle_for_session
        return oracle_for_session(session)
    from swarm_agents.llm import ModelConfig, ReactAgent, WorkflowAgent
    config = ModelConfig(base_url=options.base_url, model=options.model,
                         price_in_usd_per_mtok=options.price_in_usd_per_mtok,
                         price_out_usd_per_mtok=options.price_out_usd_per_mtok)
    return ReactAgent(config) if name == "react" else WorkflowAgent(config)


def make_agent(text: str, session: Session, options: AgentOptions, base_dir: str = ""
               ) -> Agent:
    """The agent `text` names, for one session (and trial): a built-in, or a plug-in built
    with `options`; with ``:per-drone``, a team of one instance per drone. Raises
    AgentSpecError only for a spec that is malformed or names no agent at all."""
    spec = parse_spec(text)
    if spec.per_drone:
        from dataclasses import replace

        from swarm_agents.teams.per_drone import PerDroneTeam
        single = text.removesuffix(PER_DRONE)
        return PerDroneTeam(text, lambda drone_id: make_agent(
            single, session, replace(options, agent=text, drone_id=drone_id), base_dir))
    if spec.kind == "builtin":
        return _build_builtin(spec.target, session, options)
    return _build_plugin(spec, options, base_dir)


def listing() -> list[AgentListing]:
    """The built-in agents and every installed plug-in (none is imported)."""
    rows = [AgentListing(name, "built-in", about) for name, about in BUILTIN_AGENTS.items()]
    for name, eps in sorted(_plugin_entry_points().items()):
        for ep in eps:
            note = ""
            if name in BUILTIN_AGENTS:
                note = " (hidden by the built-in of that name)"
            elif name in RESERVED:
                note = " (reserved name: cannot be used)"
            elif len(eps) > 1:
                note = " (registered by several packages: cannot be used)"
            rows.append(AgentListing(name, f"plug-in: {_dist(ep)}",
                                     f"entry point {ep.value}{note}"))
    return rows
