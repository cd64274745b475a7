"""Pass classes by name, so a JSON graph can be loaded without executing code.

    @register_pass
    class Blit(RenderPass): ...

    get_pass_class("Blit")  -> Blit
"""
from __future__ import annotations

import importlib

from ..errors import GraphError, did_you_mean

_REGISTRY: dict[str, type] = {}
# Modules whose import registers passes, imported on the first look-up that misses (rayvr's own
# package adds its passes here: see rayvr/__init__.py).
_SOURCES: list[str] = []


def register_pass(cls: type) -> type:
    """Class decorator: make `cls` loadable by its class name. Re-registering the same name replaces it."""
    from .render_pass import RenderPass

    if not (isinstance(cls, type) and issubclass(cls, RenderPass)):
        raise GraphError(f"register_pass: {cls!r} is not a RenderPass subclass; decorate a pass class")
    _REGISTRY[cls.__name__] = cls
    return cls


def add_pass_source(module: str) -> None:
    """Name a module whose import registers passes (a plugin's package); it is imported when a
    look-up first misses, so a saved graph names its pass types without importing them."""
    if module not in _SOURCES:
        _SOURCES.append(module)


def _import_pass_packages() -> None:
    for name in _SOURCES:
        importlib.import_module(name)


def get_pass_class(name: str, where: str = "pass type") -> type:
    """The registered pass class called `name`; GraphError with a did-you-mean when unknown."""
    if name not in _REGISTRY:
        _import_pass_packages()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise GraphError(f"{where}: unknown pass type {name!r}{did_you_mean(name, _REGISTRY)}; "
                         f"registered: {', '.join(sorted(_REGISTRY)) or '(none)'}; "
                         f"decorate the class with @register_pass and import its module") from None


def registered_passes() -> dict[str, type]:
    """All registered pass classes by name (after importing the pass packages)."""
    _import_pass_packages()
    return dict(_REGISTRY)


def create_pass(type_name: str, props: dict | None = None):
    """A new pass of the registered class `type_name` (Falcor's `createPass`)."""
    return get_pass_class(type_name)(props or {})


createPass = create_pass
