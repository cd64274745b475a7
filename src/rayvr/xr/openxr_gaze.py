"""XR_EXT_eye_gaze_interaction for OpenXRSink: where the eyes look, as a pose action.

When the runtime offers the extension (and the system says it supports eye gaze, through
XrSystemEyeGazeInteractionPropertiesEXT chained to xrGetSystemProperties), the sink enables it
and makes an action set with one pose action bound to the eye gaze
(/interaction_profiles/ext/eye_gaze_interaction, /user/eyes_ext/input/gaze_ext/pose), attached to
the session, and an action space of it. Each frame syncs the actions and locates that space at
the frame's display time: its -Z axis is the gaze. `xr` is pyopenxr, passed in.
"""
from __future__ import annotations

import ctypes

import numpy as np

from .openxr_convert import pose_from_xr

PROFILE = "/interaction_profiles/ext/eye_gaze_interaction"
GAZE_POSE = "/user/eyes_ext/input/gaze_ext/pose"


def system_supports(xr, instance, system) -> bool:
    """Whether the system supports eye gaze interaction (the extension must be enabled)."""
    eye = xr.SystemEyeGazeInteractionPropertiesEXT()
    props = xr.SystemProperties(next=ctypes.cast(ctypes.pointer(eye), ctypes.c_void_p))
    result = xr.raw_functions.xrGetSystemProperties(instance, system, ctypes.byref(props))
    return int(result) >= 0 and bool(eye.supports_eye_gaze_interaction)


class EyeGaze:
    """The eye gaze action of one session (see the module docstring)."""

    def __init__(self, xr, instance, session):
        self.xr = xr
        self.action_set = xr.create_action_set(instance, xr.ActionSetCreateInfo(
            action_set_name="rayvr_gaze", localized_action_set_name="rayvr eye gaze", priority=0))
        self.action = xr.create_action(self.action_set, xr.ActionCreateInfo(
            action_name="eye_gaze", action_type=xr.ActionType.POSE_INPUT, localized_action_name="Eye gaze"))
        binding = xr.ActionSuggestedBinding(action=self.action, binding=xr.string_to_path(instance, GAZE_POSE))
        xr.suggest_interaction_profile_bindings(instance, xr.InteractionProfileSuggestedBinding(
            interaction_profile=xr.string_to_path(instance, PROFILE), suggested_bindings=[binding]))
        xr.attach_session_action_sets(session, xr.SessionActionSetsAttachInfo(action_sets=[self.action_set]))
        self.space = xr.create_action_space(session, xr.ActionSpaceCreateInfo(action=self.action))
        self.session = session

    def direction(self, base_space, display_time, world_from_space=None) -> np.ndarray | None:
        """The gaze as a world-space unit direction at `display_time` (XrTime), or None while the
        runtime does not track it (eyes closed, tracker lost)."""
        xr = self.xr
        xr.sync_actions(self.session, xr.ActionsSyncInfo(active_action_sets=[xr.ActiveActionSet(
            action_set=self.action_set, subaction_path=xr.NULL_PATH)]))
        location = xr.locate_space(self.space, base_space, display_time)
        flags = int(location.location_flags)
        if not (flags & int(xr.SpaceLocationFlags.ORIENTATION_VALID_BIT)
                and flags & int(xr.SpaceLocationFlags.ORIENTATION_TRACKED_BIT)):
            return None
        return pose_from_xr(location.pose, world_from_space).rotation_matrix() @ np.array([0.0, 0.0, -1.0])

    def destroy(self) -> None:
        for handle, destroy in ((self.space, "destroy_space"), (self.action_set, "destroy_action_set")):
            try:
                getattr(self.xr, destroy)(handle)
            except Exception:   # gone with a lost session or instance
                pass
