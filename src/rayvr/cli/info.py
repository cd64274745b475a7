"""`rayvr info`: the OpenGL driver and the capabilities rayvr chooses between."""
from __future__ import annotations

import json


def register(sub) -> None:
    p = sub.add_parser("info", help="show the OpenGL driver and its capabilities")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..gpu import get_context

    caps = get_context().caps
    if args.json:
        print(json.dumps(caps.as_dict(), indent=2))
        return 0
    width = max(len(k) for k in caps.as_dict())
    for key, value in caps.as_dict().items():
        if isinstance(value, bool):
            value = "yes" if value else "no"
        print(f"{key:<{width}}  {value}")
    return 0
