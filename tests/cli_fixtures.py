"""The shipped `mavswarm` command, as tests run it: the console script installed beside this
interpreter."""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["MAVSWARM", "ROOT"]

ROOT = Path(__file__).resolve().parents[1]
_SCRIPT = Path(sys.executable).with_name("mavswarm")
MAVSWARM: list[str] = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "mavswarm"]
"""argv prefix of the `mavswarm` command."""
