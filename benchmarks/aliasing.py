"""Memory that lifetime aliasing saves on a linear chain of same-sized transients.

Target: allocated bytes <= 30% of the unaliased total for 10 passes at 2 x 1440x1600 rgba16f.
"""
from __future__ import annotations

from rayvr.cli.options import parse_size
from rayvr.gpu import get_context

from ._graphs import linear_chain

TARGET = 0.30


def add_arguments(parser) -> None:
    parser.add_argument("--passes", type=int, default=10)
    parser.add_argument("--size", default="1440x1600", help="per-view WxH (quick: 256x256)")
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--format", default="rgba16f")


def run(args) -> dict:
    w, h = (256, 256) if args.quick else parse_size(args.size)
    gpu = get_context()
    cg = linear_chain(args.passes, args.format).compile(size=(w, h), views=args.views, gpu=gpu)
    cg.execute(cg.make_context())          # it must also run, not only plan
    gpu.gl.finish()
    rep = cg.report()
    objects = len({id(o) for o in cg.resources.values()})
    frac = rep.aliased_fraction
    cg.release()
    mib = 1 << 20
    return {
        "columns": ["passes", "size", "views", "format", "resources", "gpu_objects", "allocated_MiB",
                    "unaliased_MiB", "fraction", "target", "meets"],
        "rows": [[args.passes, f"{w}x{h}", args.views, args.format, len(rep.resources), objects,
                  round(rep.total_bytes / mib, 2), round(rep.unaliased_bytes / mib, 2), round(frac, 4),
                  TARGET, "yes" if frac <= TARGET else "NO"]],
    }
