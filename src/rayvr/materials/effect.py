"""Per-material effect ids (Ray-VR's), ordered by cost."""
from __future__ import annotations

import enum

from ..errors import OptionError


class Effect(enum.IntEnum):
    """What a material's pixels get: each level adds ray work to the one before."""

    RASTER = 0        # direct light from the G-buffer, no rays
    SHADOWS = 1       # + ray-traced shadows
    REFLECTIONS = 2   # + ray-traced mirror/glossy reflections
    PATH_TRACED = 3   # full path tracing

    @classmethod
    def parse(cls, value, where: str = "effect") -> "Effect":
        """Accept an Effect, its int, or its name in any case ('reflections', 'PATH_TRACED')."""
        if isinstance(value, Effect):
            return value
        if isinstance(value, int) and not isinstance(value, bool) and 0 <= value < len(cls):
            return cls(value)
        if isinstance(value, str):
            key = value.strip().upper().replace("-", "_").replace(" ", "_")
            if key in cls.__members__:
                return cls[key]
        names = ", ".join(m.name.lower() for m in cls)
        raise OptionError(f"{where}: unknown effect {value!r}; use one of {names}")
