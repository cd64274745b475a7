"""Finished rows of the error study, cached, so that a study cut short resumes where it stopped.

A row (its timing, judged frames, motion, bias floor and images) is stored as soon as all of it
is judged, keyed by everything it depends on: rayvr's code, the scene, the views, the
configuration (its name and accumulation too), the study's settings and the images of the
references it was judged against. A study run again with the same inputs takes the stored row
instead of rendering it again; its GPU times are those of the run that measured it. Files are
written atomically into the reference cache's folder (`row-<scene>-<key>.pkl`).
"""
from __future__ import annotations

import hashlib
import json
import pickle
from pathlib import Path

from ..fileio import atomic_write
from .reference import code_digest, default_cache_dir, scene_digest, views_digest


def image_digest(image) -> str:
    """A hash of an image's pixels (a reference's identity, however many frames made it)."""
    return hashlib.sha256(memoryview(image).cast("B")).hexdigest()[:20] if image is not None else "-"


def row_key(scene, view_set, config, settings: dict, reference_digests: list[str]) -> str:
    """The key of `config`'s row: code, scene, views, configuration, study settings, references."""
    text = json.dumps([code_digest(), "row", scene_digest(scene), views_digest(view_set), config.name,
                       config.key(scene), config.accumulate, settings, reference_digests], sort_keys=True,
                      default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def row_path(scene, key: str, cache_dir=None) -> Path:
    folder = Path(cache_dir) if cache_dir else default_cache_dir()
    return folder / f"row-{scene.name}-{key}.pkl"


def load_row(path: Path):
    """The stored Row, or None when it is missing or unreadable (then it is measured again)."""
    try:
        with open(path, "rb") as f:
            row = pickle.load(f)
    except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ImportError, TypeError, ValueError):
        return None
    from .results import Row

    return row if isinstance(row, Row) else None


def store_row(path: Path, row) -> None:
    """Write `row` (atomically)."""
    def write(tmp):
        with open(tmp, "wb") as f:
            pickle.dump(row, f, protocol=pickle.HIGHEST_PROTOCOL)
    atomic_write(path, write)
