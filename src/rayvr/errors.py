"""The one family of rayvr exceptions.

Every message names what is wrong (file, pass, pin, field or option) and what would fix it;
the CLI prints it on one line and exits with code 2.
"""


class RayvrError(Exception):
    """Base of every error rayvr raises on purpose."""


class GpuError(RayvrError):
    """No usable OpenGL context, or a capability the request needs is missing."""


class ShaderError(RayvrError):
    """A GLSL source failed to preprocess or compile; the message names file and line."""


class GraphError(RayvrError):
    """A render graph is malformed: unknown pass or pin, cycle, unconnected input, conflict."""


class SceneError(RayvrError):
    """A scene file or scene description is invalid; the message names the file and field."""


class OptionError(RayvrError):
    """A bad option or property value; the message names the option and the accepted values."""


class XrError(RayvrError):
    """An OpenXR runtime or headset problem (no runtime, lost session, bad view config)."""


class OutputError(RayvrError):
    """An output file or folder cannot be written (read-only, under a regular file, disk full)."""


class SceneWarning(UserWarning):
    """A scene file is valid but questionable (the glTF validator's warnings); the CLI prints each
    on one line, library users get it through the `warnings` module and in `Scene.warnings`."""


class ClusterError(RayvrError):
    """rayvr.cluster cannot run a job: no Ray (the cluster extra), no reachable cluster, or
    every worker lost."""


class ViewerError(RayvrError):
    """The viewer cannot start or run: no display, the viewer extra missing, no window."""


def did_you_mean(name: str, candidates) -> str:
    """A ' (did you mean 'x'?)' suffix for the closest candidate, or '' when none is close."""
    import difflib

    close = difflib.get_close_matches(name, list(candidates), n=1, cutoff=0.5)
    return f" (did you mean '{close[0]}'?)" if close else ""
