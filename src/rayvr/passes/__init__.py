"""Render passes, one folder each with its shaders beside it: the hybrid pipeline (G-buffer,
lighting, ray-traced effects, composite, tone mapping), path tracing with accumulation and TAA,
and the simple ones in `rayvr.passes.basic`.

Every sub-folder that is a package is imported here, so its passes register themselves
(`@register_pass`) and appear as `rayvr.passes.<ClassName>`: adding a pass is adding a folder
(see docs/adding-a-pass.md).
"""
from __future__ import annotations

import importlib
import pkgutil

__all__: list[str] = []
for _info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
    if _info.ispkg:
        _module = importlib.import_module(f"{__name__}.{_info.name}")
        for _name in getattr(_module, "__all__", ()):
            _value = getattr(_module, _name)
            if isinstance(_value, type):
                globals()[_name] = _value
                __all__.append(_name)
del _info, _module, _name, _value
