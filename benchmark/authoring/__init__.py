"""Task authoring: the templates (Python and template files), seeded scenario generation, the
shipped suite, session files and their folders, imports of MultiUAV-Plat files, fingerprints and
the hidden faults a task schedules. Nothing here runs an agent or scores one."""

__all__: list[str] = []
