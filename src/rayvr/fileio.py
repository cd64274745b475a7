"""Writing output files so that a failure never leaves a half-written file or a partial set behind.

Everything rayvr writes (images, graphs, reports, plots) goes through `atomic_write`: the data is
written to a temporary file in the target's folder, then renamed over the target. Outputs made of
several files (stereo L/R, camera-grid views, a quilt beside them, a report folder) are written
inside one `atomic_group()`: every file goes to a temporary first and the renames happen together
when the group ends; if any write or rename fails (or Ctrl-C arrives), the temporaries are removed,
files already renamed are taken back (a file they replaced is put back) and folders the group
created are removed again. `check_writable` refuses an unwritable target before any work is done. A report of many files can also go through
`atomic_folder`: written into a temporary folder beside the target, which replaces the target
only once every file is there.
"""
from __future__ import annotations

import contextlib
import contextvars
import io
import os
import shutil
import stat
import tempfile
from pathlib import Path

import numpy as np

from .errors import OptionError, OutputError

IMAGE_FORMATS = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG"}   # what write_image writes, by suffix

_GROUP: contextvars.ContextVar["_Group | None"] = contextvars.ContextVar("rayvr_atomic_group", default=None)


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _publish_mode(tmp: Path, target: Path, folder: bool = False) -> None:
    """Give a temporary (made private by mkstemp/mkdtemp) the mode `target` would have had if
    opened directly: the replaced file's mode, else the default mode less the umask."""
    with contextlib.suppress(OSError):   # the mode is a courtesy: the data is written either way
        mode = stat.S_IMODE(target.stat().st_mode) if target.exists() else (0o777 if folder else 0o666) & ~_umask()
        os.chmod(tmp, mode)


def _existing_ancestor(folder: Path) -> Path:
    """`folder` or its nearest ancestor that exists (as anything: a folder or a file)."""
    folder = Path(os.path.abspath(folder))
    while not (folder.exists() or folder.is_symlink()) and folder != folder.parent:
        folder = folder.parent
    return folder


def check_writable(path, option: str = "output", folder: bool = False) -> Path:
    """Raise OutputError now if `path` could not be written later: its folder lies under a regular
    file, or it (or the nearest folder that exists above it) refuses new files (read-only file
    system, no permission, /proc). `folder`: `path` is a folder to write files into. Writes
    nothing that stays: a probe file is created in the nearest existing folder and removed."""
    path = Path(path)
    where = f"{option} {path}" if option else str(path)
    if path.is_dir() and not folder:
        raise OutputError(f"{where}: is a folder; name a file inside it")
    if folder and path.exists() and not path.is_dir():
        raise OutputError(f"{where}: exists and is not a folder; name a folder")
    base = _existing_ancestor(path if folder else path.parent)
    if not base.is_dir():
        raise OutputError(f"{where}: {base} is a file, not a folder; choose a path in a folder")
    try:
        fd, probe = tempfile.mkstemp(prefix=".rayvr-probe.", dir=base)
    except OSError as exc:
        raise OutputError(f"{where}: cannot create files in {base} ({_reason(exc)}); "
                          f"choose a writable folder") from None
    os.close(fd)
    os.unlink(probe)
    return path


def _move_aside(target: Path) -> Path:
    """Rename an existing `target` to a hidden name beside it (so a failed group can put it back)."""
    fd, name = tempfile.mkstemp(prefix=f".{target.stem}.old.", suffix=target.suffix, dir=target.parent)
    os.close(fd)
    try:
        os.replace(target, name)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(name)
        raise
    return Path(name)


class _Group:
    """The pending files of one atomic_group: (temporary, target) pairs and the folders made."""

    def __init__(self):
        self.pending: list[tuple[Path, Path]] = []
        self.created: list[Path] = []

    def _make_folders(self, folder: Path) -> None:
        missing = []
        while not folder.exists() and folder != folder.parent:
            missing.append(folder)
            folder = folder.parent
        for f in reversed(missing):
            try:
                f.mkdir()
            except FileExistsError:
                if not f.is_dir():
                    raise OutputError(f"{f}: exists and is not a folder; choose another output path") from None
                continue
            except OSError as exc:
                raise OutputError(f"{f}: cannot create the folder ({_reason(exc)}); choose a writable folder") from None
            self.created.append(f)

    def add(self, path: Path, write) -> Path:
        """Write `path`'s data to a temporary now (`write(tmp_path)`); rename it on commit."""
        if any(target == path for _, target in self.pending):
            raise OutputError(f"{path}: written twice in one output; give each file its own name")
        if path.is_dir():
            raise OutputError(f"{path}: is a folder; name a file inside it")
        self._make_folders(path.parent)
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
        except OSError as exc:
            raise OutputError(f"{path}: cannot write ({_reason(exc)}); choose a writable folder") from None
        os.close(fd)
        self.pending.append((Path(tmp), path))
        try:
            write(Path(tmp))
        except OSError as exc:
            raise OutputError(f"{path}: cannot write ({_reason(exc)}); free space or choose another "
                              f"folder") from None
        _publish_mode(Path(tmp), path)
        return path

    def commit(self) -> None:
        """Rename every temporary over its target; on any failure undo the renames done so far
        (a file that a rename replaced is put back)."""
        renamed: list[tuple[Path, Path | None]] = []   # (target holding new data, backup of the old)
        target = None
        try:
            for tmp, target in self.pending:
                backup = _move_aside(target) if (target.exists() or target.is_symlink()) else None
                try:
                    os.replace(tmp, target)
                except BaseException:
                    if backup is not None:
                        os.replace(backup, target)
                    raise
                renamed.append((target, backup))
        except BaseException as exc:
            for done, backup in reversed(renamed):
                with contextlib.suppress(OSError):
                    done.unlink(missing_ok=True)
                    if backup is not None:
                        os.replace(backup, done)
            if isinstance(exc, OSError):
                raise OutputError(f"{target}: cannot write ({_reason(exc)}); nothing was written") from None
            raise
        for _, backup in renamed:
            if backup is not None:
                with contextlib.suppress(OSError):
                    backup.unlink()
        self.pending = []

    def discard(self) -> None:
        """Remove the temporaries and the folders this group created (when empty)."""
        for tmp, _ in self.pending:
            with contextlib.suppress(OSError):
                tmp.unlink(missing_ok=True)
        self.pending = []
        for folder in reversed(self.created):
            with contextlib.suppress(OSError):
                folder.rmdir()
        self.created = []


@contextlib.contextmanager
def atomic_group():
    """All files written by `atomic_write` (and the writers below) inside the block appear
    together when it ends, or none does. Nested groups join the outermost one."""
    if _GROUP.get() is not None:
        yield _GROUP.get()
        return
    group = _Group()
    token = _GROUP.set(group)
    try:
        yield group
    except BaseException:
        _GROUP.reset(token)
        group.discard()
        raise
    _GROUP.reset(token)
    try:
        group.commit()
    except BaseException:
        group.discard()
        raise


def atomic_write(path, write) -> Path:
    """Call `write(tmp_path)` and rename the result to `path` (folders are created); inside an
    atomic_group the rename waits for the group. OSError becomes OutputError naming the file."""
    path = Path(path)
    with atomic_group() as group:
        return group.add(path, write)


def read_json(path, where: str, error=OptionError, what: str = "it", hint: str = "check the path"):
    """The JSON document in `path`; `error` (a RayvrError class) naming `where` (and `what` the
    file is) when it cannot be read or is not JSON (with the line and column), `hint` saying what
    to give instead."""
    import json

    try:
        return json.loads(Path(path).read_text())
    except OSError as exc:
        raise error(f"{where}: cannot read {what}: {exc.strerror or exc}; {hint}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        pos = f" (line {exc.lineno}, column {exc.colno}): {exc.msg}" if isinstance(exc, json.JSONDecodeError) else ""
        raise error(f"{where}: not valid JSON{pos}") from None


def write_text(path, text: str) -> Path:
    """Write `text` to `path` atomically."""
    return atomic_write(path, lambda tmp: tmp.write_text(text))


def image_format(path, option: str = "output") -> str:
    """The Pillow format that `write_image` uses for `path`'s suffix; OptionError for others."""
    fmt = IMAGE_FORMATS.get(Path(path).suffix.lower())
    if fmt is None:
        raise OptionError(f"{option} {path}: unknown image type '{Path(path).suffix}'; "
                          f"use {', '.join(IMAGE_FORMATS)}")
    return fmt


def write_image(path, pixels: np.ndarray, alpha: bool = False) -> Path:
    """An (h, w, c) uint8 image, rows top-down, as PNG or JPEG by the suffix of `path`; alpha is
    kept only in PNG and only when `alpha`."""
    from PIL import Image

    fmt = image_format(path)
    keep = 4 if alpha and fmt == "PNG" else 3
    rgb = np.ascontiguousarray(pixels[..., :keep] if pixels.ndim == 3 else pixels)
    options = {"quality": 95} if fmt == "JPEG" else {}
    return atomic_write(path, lambda tmp: Image.fromarray(rgb).save(tmp, format=fmt, **options))


def write_png(path, pixels: np.ndarray, alpha: bool = False) -> Path:
    """An (h, w, c) uint8 image, rows top-down; alpha is dropped unless `alpha`."""
    from PIL import Image

    rgb = np.ascontiguousarray(pixels[..., :4 if alpha else 3] if pixels.ndim == 3 else pixels)
    return atomic_write(path, lambda tmp: Image.fromarray(rgb).save(tmp, format="PNG"))


def png_bytes(pixels: np.ndarray) -> bytes:
    """An (h, w, c) uint8 image encoded as PNG bytes (for data URIs)."""
    from PIL import Image

    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(pixels)).save(out, format="PNG")
    return out.getvalue()


def check_folder_target(path, option: str = "--report") -> Path:
    """`path` for `atomic_folder`: refused now, before any work, if it cannot be one (see
    check_writable)."""
    return check_writable(path, option, folder=True)


@contextlib.contextmanager
def atomic_folder(path):
    """Yield a temporary folder beside `path`; when the block ends normally it becomes `path`
    (an existing folder there is replaced), and when it raises (Ctrl-C included) it is removed,
    so `path` is either the old folder or the complete new one, never a half."""
    path = check_folder_target(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        yield tmp
        _publish_mode(tmp, path, folder=True)
        old = None
        if path.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{path.name}.old.", dir=path.parent))
            os.replace(path, old / path.name)
        os.replace(tmp, path)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return path


def write_exr(path, pixels: np.ndarray) -> Path:
    """An (h, w, c) float image as a ZIP-compressed scanline EXR (RGB, float32)."""
    try:
        import OpenEXR
    except ImportError:
        raise OptionError(f"{path}: EXR output needs the 'openexr' package: pip install openexr") from None
    rgb = np.ascontiguousarray(pixels[..., :3].astype(np.float32))

    def write(tmp: Path):
        header = {"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION}
        with OpenEXR.File(header, {"RGB": rgb}) as f:
            f.write(str(tmp))

    return atomic_write(path, write)
