"""Placeholders of template files: ours and the reference's (MultiUAV-Plat) vocabulary.

Inside ``{...}``, resolved in this order:

1. entity names: ``{drone_1_id}``, ``{drone_1_name}``, ``{target_id}``, ... (entity groups);
2. the template's named values: ``{alt}`` (an int or float), ``{p}`` (a point, written
   "(x, y)"), ``{p.x}``, ``{p.y}``;
3. the reference's predefined sticky randoms (integers): ``random_altitude`` [5, 100],
   ``random_x`` [0, 1024], ``random_y`` [0, 768], ``random_z`` [5, 100], ``random_heading``
   [0, 360], ``random_distance`` [10, 500], ``random_speed`` [1, 30], ``random_hovertime``
   [2, 20], ``random_duration`` [5, 30];
4. ``randint:a:b`` and ``random:a:b[:d]`` (anonymous, new per occurrence),
   ``randint_<var>:a:b`` and ``random_<var>:a:b[:d]`` (named and sticky: the first occurrence
   draws, later ones reuse it whatever range they state), and references ``{randint_<var>}``,
   ``{random_<var>}`` to a value already drawn;
5. coordinates ``randx | randy | randz | randxy | randxyc | randxyz | randpos``, anonymous, with
   a range ``:a:b[:d]``, or named ``randx_<v>`` (sticky). Named positions are coordinated and
   collision-aware: before a text is filled, composites (``randxy_<v>`` ...) are drawn first,
   then every ``<v>`` with both ``randx_<v>`` and ``randy_<v>`` is drawn jointly (ranges from the
   last occurrence), redrawn up to 100 times while (x, y) lies within 1 m of an obstacle.
   Without a range x and y span the map less 50 m, z [0, 100] (z ranges are capped at 100).

Anything else is left as written. Texts end with "Drone Drone" collapsed to "Drone". In check
parameters and plans, a string that is exactly one placeholder becomes a value: an entity id
stays a string; a named int stays an int in a plan and becomes a float in checks (as the
reference converts with float()); other text becomes a float when it reads as one.
"""

from __future__ import annotations

import random
import re
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from benchmark.authoring.templates.base import SessionView

__all__ = ["PLACEHOLDER", "PREDEFINED", "Filler"]

PLACEHOLDER = re.compile(r"\{([^{}]+)\}")
PREDEFINED = {"random_altitude": (5, 100), "random_x": (0, 1024), "random_y": (0, 768),
              "random_z": (5, 100), "random_heading": (0, 360), "random_distance": (10, 500),
              "random_speed": (1, 30), "random_hovertime": (2, 20), "random_duration": (5, 30)}
_COORD = re.compile(r"^(randxyz|randxyc|randxy|randpos|randx|randy|randz)"
                    r"(?:_([^_:]+))?(?::(-?[0-9.]+):(-?[0-9.]+)(?::([0-9]+))?)?$")
_NAMED = re.compile(r"^(randint|random)_([A-Za-z0-9-]+)(?::(-?[0-9.]+):(-?[0-9.]+)"
                    r"(?::([0-9]+))?)?$")
_ANON = re.compile(r"^(randint|random):(-?[0-9.]+):(-?[0-9.]+)(?::([0-9]+))?$")
_COMPOSITES = ("randxyz", "randxyc", "randxy", "randpos")
_TRIES = 100
_MARGIN_M = 50.0
_Z_CAP = 100.0


def _fmt(value: float, decimals: int) -> str:
    return f"{value:.{decimals}f}" if decimals else str(round(value))


class Filler:
    """Fills one task's texts, checks and plan; random values are shared across all of them."""

    def __init__(self, rng: random.Random, view: SessionView, entities: Mapping[str, str],
                 values: Mapping[str, Any]) -> None:
        self.rng, self.view = rng, view
        self.entities = dict(entities)
        self.values = dict(values)
        self.cache: dict[str, float] = {}
        self.decimals: dict[str, int] = {}

    # ------------------------------------------------------------ texts
    def text(self, text: str) -> str:
        self._coordinate(text)
        out = PLACEHOLDER.sub(lambda m: self._resolve(m.group(1)) or m.group(0), text)
        return re.sub(r"\bdrone drone\b", "Drone", out, flags=re.IGNORECASE)

    def structure(self, data: Any, *, plan: bool) -> Any:
        """Checks (plan=False) or a plan with every placeholder filled."""
        if isinstance(data, Mapping):
            out = {self.text(str(k)): self.structure(v, plan=plan) for k, v in data.items()}
            if "expect" in out and isinstance(out["expect"], str):
                word = out["expect"].strip().lower()
                if word in ("true", "false"):
                    out["expect"] = word == "true"
                else:
                    del out["expect"]
            return out
        if isinstance(data, list):
            return [self.structure(v, plan=plan) for v in data]
        if not isinstance(data, str):
            return data
        whole = PLACEHOLDER.fullmatch(data)
        if whole is None:
            return self.text(data)
        return self._typed(whole.group(1), data, plan)

    def _typed(self, inner: str, raw: str, plan: bool) -> Any:
        if inner in self.entities:
            return self.entities[inner]
        value = self._named(inner)
        if value is not None and not isinstance(value, tuple):
            return value if plan else float(value)
        self._coordinate(raw)
        text = self._resolve(inner)
        if text is None:
            return raw
        try:
            return float(text)
        except ValueError:
            return text

    # ------------------------------------------------------------ resolution
    def _named(self, inner: str) -> Any:
        if inner in self.values:
            return self.values[inner]
        name, _, part = inner.partition(".")
        point = self.values.get(name)
        if isinstance(point, tuple) and part in ("x", "y"):
            return point[0] if part == "x" else point[1]
        return None

    def _resolve(self, inner: str) -> str | None:
        if inner in self.entities:
            return self.entities[inner]
        value = self._named(inner)
        if isinstance(value, tuple):
            return f"({value[0]:.0f}, {value[1]:.0f})"
        if isinstance(value, float) and "." in inner:
            return f"{value:.0f}"
        if value is not None:
            return str(value)
        if inner in PREDEFINED:
            if inner not in self.cache:
                low, high = PREDEFINED[inner]
                self.cache[inner] = float(round(self.rng.uniform(low, high)))
            return str(round(self.cache[inner]))
        if m := _ANON.match(inner):
            kind, a, b, dec = m.group(1), float(m.group(2)), float(m.group(3)), m.group(4)
            if kind == "randint":
                return str(self.rng.randint(round(a), round(b)))
            return _fmt(self.rng.uniform(a, b), int(dec or 0))
        if m := _NAMED.match(inner):
            return self._sticky(m)
        if m := _COORD.match(inner):
            return self._coord(m)
        return None

    def _sticky(self, m: re.Match[str]) -> str | None:
        kind, var, lo, hi, dec = m.groups()
        key = f"{kind}_{var}"
        if key not in self.cache:
            if lo is None:
                return None  # a reference to a value not drawn yet stays as written
            if kind == "randint":
                self.cache[key] = float(self.rng.randint(round(float(lo)), round(float(hi))))
                self.decimals[key] = 0
            else:
                self.decimals[key] = int(dec or 0)
                self.cache[key] = round(self.rng.uniform(float(lo), float(hi)),
                                        self.decimals[key])
        return _fmt(self.cache[key], self.decimals.get(key, 0))

    # ------------------------------------------------------------ coordinates
    def _range(self, axis: str, lo: str | None, hi: str | None) -> tuple[float, float]:
        if lo is not None and hi is not None:
            a, b = float(lo), float(hi)
            if axis == "z":
                a, b = (0.0, _Z_CAP) if a > _Z_CAP else (a, min(b, _Z_CAP))
            return a, b
        if axis == "x":
            return _MARGIN_M, self.view.map_w_m - _MARGIN_M
        if axis == "y":
            return _MARGIN_M, self.view.map_h_m - _MARGIN_M
        return 0.0, _Z_CAP

    def _draw_xy(self, xr: tuple[float, float], yr: tuple[float, float], dec: int
                 ) -> tuple[float, float]:
        x = y = 0.0
        for _ in range(_TRIES):
            x = round(self.rng.uniform(*xr), dec)
            y = round(self.rng.uniform(*yr), dec)
            if self.view.is_free(x, y, clearance_m=1.0, avoid_targets=False):
                break
        return x, y

    def _coordinate(self, text: str) -> None:
        """Draw the named positions of a text together, composites first."""
        found = [_COORD.match(inner) for inner in PLACEHOLDER.findall(text)]
        matches = [m for m in found if m is not None and m.group(2)]
        for m in matches:
            kind, var, lo, hi, dec = m.groups()
            if kind in _COMPOSITES and f"randx_{var}" not in self.cache:
                d = int(dec or 0)
                x, y = self._draw_xy(self._range("x", lo, hi), self._range("y", lo, hi), d)
                self._store(var, x, y, d)
                if kind in ("randxyz", "randpos"):
                    self.cache[f"randz_{var}"] = round(self.rng.uniform(
                        *self._range("z", lo, hi)), d)
        last: dict[tuple[str, str], re.Match[str]] = {}
        for m in matches:
            if m.group(1) in ("randx", "randy", "randz"):
                last[(m.group(2), m.group(1)[-1])] = m
        for (var, axis), m in list(last.items()):
            if axis != "x" or (var, "y") not in last or f"randx_{var}" in self.cache:
                continue
            mx, my, mz = m, last[(var, "y")], last.get((var, "z"))
            d = max(int(g.group(5) or 0) for g in (mx, my, mz) if g is not None)
            x, y = self._draw_xy(self._range("x", mx.group(3), mx.group(4)),
                                 self._range("y", my.group(3), my.group(4)), d)
            self._store(var, x, y, d)
            if mz is not None:
                self.cache[f"randz_{var}"] = round(self.rng.uniform(
                    *self._range("z", mz.group(3), mz.group(4))), d)

    def _store(self, var: str, x: float, y: float, d: int) -> None:
        self.cache[f"randx_{var}"], self.cache[f"randy_{var}"] = x, y
        for axis in "xyz":
            self.decimals[f"rand{axis}_{var}"] = d

    def _coord(self, m: re.Match[str]) -> str:
        kind, var, lo, hi, dec = m.groups()
        d = int(dec or 0)
        if var is None:  # anonymous: a fresh draw, no collision check
            if kind in _COMPOSITES:
                x, y = self._draw_xy(self._range("x", lo, hi), self._range("y", lo, hi), d)
                z = round(self.rng.uniform(*self._range("z", lo, hi)), d)
                return self._compose(kind, x, y, z, d)
            return _fmt(self.rng.uniform(*self._range(kind[-1], lo, hi)), d)
        if kind in _COMPOSITES:
            x, y = self.cache[f"randx_{var}"], self.cache[f"randy_{var}"]
            z = self.cache.setdefault(f"randz_{var}", round(self.rng.uniform(0.0, _Z_CAP), d))
            return self._compose(kind, x, y, z, self.decimals.get(f"randx_{var}", d))
        key = f"{kind}_{var}"
        if key not in self.cache:  # a lone scalar: drawn alone, no collision check
            self.cache[key] = round(self.rng.uniform(*self._range(kind[-1], lo, hi)), d)
            self.decimals[key] = d
        return _fmt(self.cache[key], self.decimals.get(key, d))

    @staticmethod
    def _compose(kind: str, x: float, y: float, z: float, d: int) -> str:
        xs, ys, zs = _fmt(x, d), _fmt(y, d), _fmt(z, d)
        return {"randxy": f"{xs} {ys}", "randxyc": f"{xs}, {ys}",
                "randxyz": f"{xs} {ys} {zs}", "randpos": f"{xs}, {ys}, {zs}"}[kind]
