"""A scripted agent, no model: every drone takes off, flies outwards until its own sensor
perceives a target (a few legs at most), flies to the nearest one and photographs it; then the
agent finishes.

    mavswarm bench run --agent examples/scripted_agent.py:ScriptedAgent --suite smoke

It is written against the agent protocol alone (`agent_contract`, docs/agents/plugins.md):
`run(task, tools)`, the tools' outcomes, and `tools.concurrently` to fly the drones
side by side under the lockstep clock. With ``:per-drone`` each drone gets its own instance,
whose `tools.drone_ids` holds that drone only.
"""

from __future__ import annotations

from agent_contract import AgentOptions, AgentTask, AgentTools

ALTITUDE_M = 12.0
LEG_M = 80.0
SEARCH_LEGS = 3


class ScriptedAgent:
    """Take off, visit what you see, finish. Built with the run's options (see AgentOptions);
    it needs none of them."""

    def __init__(self, options: AgentOptions | None = None) -> None:
        self.altitude_m = ALTITUDE_M

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        drones = tools.drone_ids
        # One thread of control per drone: the lockstep clock waits for each of them.
        results = await tools.concurrently(*(
            self._fly(tools, d, 360.0 * k / len(drones)) for k, d in enumerate(drones)))
        for result in results:
            if isinstance(result, BaseException):  # e.g. BudgetExhausted: let it end the task
                raise result
        tools.finish("; ".join(results))

    async def _fly(self, tools: AgentTools, drone: str, heading_deg: float) -> str:
        launched = await tools.take_off(drone, self.altitude_m)
        if not launched.ok:
            return f"{drone}: {launched.message}"
        for leg in range(SEARCH_LEGS + 1):
            targets = (tools.nearby(drone).data or {}).get("targets", [])
            if targets:
                break
            if leg == SEARCH_LEGS:
                return f"{drone}: airborne, nothing in sight"
            moved = await tools.move_towards(drone, heading_deg, LEG_M)
            if not moved.ok:
                return f"{drone}: {moved.message}"
        nearest = min(targets, key=lambda t: t["distance_m"])
        x, y = nearest["position"][0], nearest["position"][1]
        moved = await tools.move_to(drone, x, y, self.altitude_m)
        if not moved.ok:
            return f"{drone}: {moved.message}"
        photo = await tools.take_photo(drone)
        return f"{drone}: at {nearest['id']}, {photo.message}"
