"""The mavswarm distribution's composition root: the one `mavswarm` command (`mavswarm.cli`)."""
