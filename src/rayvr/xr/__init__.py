"""Views and stereo math, the simulated headset, the OpenXR sink, light-field output."""
from .views import Fov, Pose, View, ViewSet

__all__ = ["Fov", "Pose", "View", "ViewSet"]
