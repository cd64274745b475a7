"""Unit quaternions in OpenXR's (x, y, z, w) order, float64: products, axis-angle, slerp, matrices."""
from __future__ import annotations

import numpy as np

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def normalize(q) -> np.ndarray:
    """`q` scaled to unit length (float64)."""
    q = np.asarray(q, dtype=np.float64)
    return q / np.linalg.norm(q)


def multiply(a, b) -> np.ndarray:
    """The rotation `a` after `b` (Hamilton product a*b)."""
    ax, ay, az, aw = np.asarray(a, dtype=np.float64)
    bx, by, bz, bw = np.asarray(b, dtype=np.float64)
    return np.array([
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ])


def from_axis_angle(axis, angle: float) -> np.ndarray:
    """The rotation by `angle` radians about `axis` (any length), right-handed."""
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    s = np.sin(angle / 2)
    return np.array([*(axis * s), np.cos(angle / 2)])


def to_matrix(q) -> np.ndarray:
    """3x3 rotation matrix of a (not necessarily normalised) quaternion; (n, 4) -> (n, 3, 3)."""
    q = np.asarray(q, dtype=np.float64)
    x, y, z, w = (q / np.sqrt((q * q).sum(axis=-1, keepdims=True))).T
    m = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    return m if q.ndim == 1 else m.transpose(2, 0, 1)


def from_matrix(m) -> np.ndarray:
    """Quaternion of a 3x3 rotation matrix (Shepperd's method: branch on the largest term)."""
    m = np.asarray(m, dtype=np.float64)[:3, :3]
    t = np.trace(m)
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [s / 4, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 1] + m[1, 0]) / s, s / 4, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, s / 4, (m[1, 0] - m[0, 1]) / s]
    return normalize(q)


def slerp(a, b, t: float) -> np.ndarray:
    """Shortest-arc spherical interpolation from `a` (t=0) to `b` (t=1)."""
    a, b = normalize(a), normalize(b)
    d = float(np.dot(a, b))
    if d < 0:           # q and -q are the same rotation: take the short way round
        b, d = -b, -d
    if d > 0.9995:      # nearly parallel: lerp is exact to float precision and avoids 0/0
        return normalize(a + t * (b - a))
    theta = np.arccos(d)
    return (np.sin((1 - t) * theta) * a + np.sin(t * theta) * b) / np.sin(theta)
