"""The mavswarm distribution's composition root: the one `mavswarm` command (`mavswarm.cli`)."""

__all__: list[str] = []
