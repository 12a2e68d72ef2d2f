"""The bus's topic tree, in one place (payload schemas: mqtt_bus.schemas).

    {prefix}/{session}/status                 online/offline (retained; the Last Will)
    {prefix}/{session}/{drone}/osd            periodic telemetry
    {prefix}/{session}/{drone}/state          flight state, home, primitive (retained)
    {prefix}/{session}/{drone}/events         STATUSTEXT, photos, holds, failsafes, radio
    {prefix}/{session}/{drone}/services       commands (operators only, by the broker's ACL)
    {prefix}/{session}/{drone}/services_reply their outcomes
    {prefix}/bench/{run}/tasks                one benchmark record per task, as it ends
    {prefix}/bench/{run}/progress             the run's counts so far (retained)
    {prefix}/bench/{run}/status               online/offline of the run (retained; Last Will)
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["DEFAULT_PREFIX", "BenchTopics", "SessionTopics", "check_prefix", "check_segment"]

DEFAULT_PREFIX = "mavswarm"
_SEGMENT = re.compile(r"^[A-Za-z0-9_.:-]{1,64}$")


def check_segment(value: str, what: str) -> str:
    """One topic level (a session, drone or run name): 1-64 of A-Z a-z 0-9 _ . : -."""
    if not isinstance(value, str) or not _SEGMENT.match(value):
        raise ValueError(f"{what} {value!r} cannot be an MQTT topic level: use 1-64 letters, "
                         "digits, '_', '.', ':' or '-'")
    return value


def check_prefix(prefix: str) -> str:
    """A prefix of one or more levels (`mavswarm`, `site/a`)."""
    for level in prefix.split("/"):
        check_segment(level, f"prefix level in {prefix!r}:")
    return prefix


@dataclass(frozen=True, slots=True)
class SessionTopics:
    """The topics of one live session (a swarm, or a fleet behind a bridge)."""

    prefix: str
    session: str

    def __post_init__(self) -> None:
        check_prefix(self.prefix)
        check_segment(self.session, "session name")

    @property
    def base(self) -> str:
        return f"{self.prefix}/{self.session}"

    @property
    def status(self) -> str:
        return f"{self.base}/status"

    def osd(self, drone: str) -> str:
        return f"{self.base}/{drone}/osd"

    def state(self, drone: str) -> str:
        return f"{self.base}/{drone}/state"

    def events(self, drone: str) -> str:
        return f"{self.base}/{drone}/events"

    def services_reply(self, drone: str) -> str:
        return f"{self.base}/{drone}/services_reply"

    @property
    def services_filter(self) -> str:
        return f"{self.base}/+/services"

    def drone_of_services(self, topic: str) -> str | None:
        """The drone level of a `.../{drone}/services` topic of this session, else None."""
        head, tail = f"{self.base}/", "/services"
        if not (topic.startswith(head) and topic.endswith(tail)):
            return None
        drone = topic[len(head):-len(tail)]
        return drone if drone and "/" not in drone else None


@dataclass(frozen=True, slots=True)
class BenchTopics:
    """The topics of one benchmark run."""

    prefix: str
    run: str

    def __post_init__(self) -> None:
        check_prefix(self.prefix)
        check_segment(self.run, "run name")

    @property
    def base(self) -> str:
        return f"{self.prefix}/bench/{self.run}"

    @property
    def tasks(self) -> str:
        return f"{self.base}/tasks"

    @property
    def progress(self) -> str:
        return f"{self.base}/progress"

    @property
    def status(self) -> str:
        return f"{self.base}/status"
