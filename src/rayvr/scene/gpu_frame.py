"""The per-frame part of the GPU scene: instance transforms, the TLAS over them, punctual lights,
and the render-space shift.

Render space is world space minus the frame's origin (the head), and the origin moves every
frame the head translates. Rebuilding the TLAS and re-uploading every instance and light for
that would be work per instance per frame. Instead they are kept in *anchor space* (world minus
an anchor, the origin when they were last built) and the shaders add the small float32 shift
`anchor - origin` (scene.glsl: instance_point_to_render, lights.glsl; ray_query.glsl moves rays
into anchor space). A moving head then rewrites 32 bytes a frame. The anchor follows the head
(everything rebuilt around the current origin) once the shift exceeds RECENTRE_FRACTION of the
scene's extent, which bounds the precision the shift costs: positions near the viewer are off
by at most an ulp of the shift, ~1e-8 of the scene's size.

Instances and lights are compared against what was uploaded (numpy over arrays, no loop over
instances); only a real change rebuilds the TLAS or re-uploads the lights.
"""
from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..gpu.records import INSTANCE_DATA, PUNCTUAL_LIGHT
from . import bvh as bvh_mod
from . import bvh_layouts

INSTANCE_HEADER_FLOATS = 8    # uvec4 scene_info + vec4 scene_shift
RECENTRE_FRACTION = 1.0 / 8.0


class SceneFrame:
    """Uploads what changes per frame into a GpuScene's buffers (see the module docstring)."""

    def __init__(self, gpu_scene):
        self.gs = gpu_scene
        self.anchor = np.zeros(3)
        self.origin = np.zeros(3)
        self.rebuilds = 0            # TLAS builds (instances moved, or the anchor recentred)
        self._uploaded = None        # (transforms, mesh ids) the TLAS was built from
        self._lights = None          # (LightList.version, anchor) of the lights last uploaded
        self._shift = None

    @property
    def shift(self) -> np.ndarray:
        """anchor - origin: render space = anchor space + shift."""
        return self.anchor - self.origin

    def update(self, origin) -> bool:
        """Move to this frame's origin; returns whether anything but the shift was uploaded."""
        self.origin = np.zeros(3) if origin is None else np.asarray(origin, dtype=np.float64)
        changed = False
        if np.linalg.norm(self.shift) > RECENTRE_FRACTION * self.gs.scale:
            self.anchor = self.origin.copy()
            self._uploaded, self._lights = None, None
        instances = self.gs.scene.instances
        mats, meshes = instances.transforms, instances.meshes
        if not (self._uploaded is not None and np.array_equal(mats, self._uploaded[0])
                and np.array_equal(meshes, self._uploaded[1])):
            self._upload_instances(mats, meshes)
            self._uploaded = (mats.copy(), meshes.copy())
            changed = True
        changed |= self._upload_lights()
        self._upload_header()
        return changed

    def invalidate(self) -> None:
        """Upload the instances again at the next update (e.g. after a BLAS refit)."""
        self._uploaded = None

    # ---- instances and TLAS ------------------------------------------------------------------
    def _upload_header(self) -> None:
        shift = self.shift.astype(np.float32)
        if self._shift is not None and np.array_equal(shift, self._shift):
            return
        header = np.zeros(INSTANCE_HEADER_FLOATS, np.float32)
        bits = header.view(np.uint32)
        bits[0] = self._live_count
        bits[1] = len(self.gs.scene.materials)
        header[4:7] = shift
        self.gs.buffers["instances"].write(header.tobytes())
        self._shift = shift

    def _upload_instances(self, mats: np.ndarray, mesh_ids: np.ndarray) -> None:
        """Anchor-space instance matrices and the TLAS over their boxes (no per-vertex work)."""
        gs = self.gs
        n = len(mats)
        m = mats.copy()
        m[:, :3, 3] -= self.anchor
        bad = np.flatnonzero(~(np.abs(np.linalg.det(m[:, :3, :3])) > 1e-300) | ~np.isfinite(m).all(axis=(1, 2)))
        if len(bad):
            name = gs.scene.instances[bad[0]].name
            raise SceneError(f"instance '{name}'.transform: singular or non-finite matrix; give it a non-zero scale")
        rows = INSTANCE_DATA.zeros(max(n, 1))   # one placeholder row when empty
        rows["to_render"][:n] = m[:, :3]
        rows["to_object"][:n] = np.linalg.inv(m)[:, :3]
        rows["info"][:n, 0] = mesh_ids
        rows["info"][:n, 1] = gs.blas_roots[mesh_ids]         # read by the traversal's instance entry
        rows["info"][:n, 2] = gs.first_triangles[mesh_ids]    # for scene_triangle()
        w = np.einsum("nij,nkj->nki", m[:, :3], gs.mesh_corners[mesh_ids])   # each mesh box's corners
        live = np.flatnonzero(gs.mesh_live[mesh_ids])
        self._live_count = n if len(live) else 0     # 0: no geometry, traversal returns at once
        header = np.zeros(INSTANCE_HEADER_FLOATS, np.float32)
        header.view(np.uint32)[0] = self._live_count
        header.view(np.uint32)[1] = len(gs.scene.materials)
        header[4:7] = self.shift.astype(np.float32)
        gs.upload("instances", np.concatenate([header.view(np.uint8), rows.view(np.uint8)]))
        self._shift = header[4:7].copy()
        self._build_tlas(live, w.min(axis=1), w.max(axis=1))
        gs.write_emissive_clusters(mats, self.anchor)
        self.rebuilds += 1

    def _build_tlas(self, live: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> None:
        gs = self.gs
        if not len(live):
            gs.upload("tlas_nodes", np.zeros((1, gs.node_floats), np.float32))
            return
        pad = 1e-6 * np.maximum(np.abs(lo[live]), np.abs(hi[live])).max(axis=1, keepdims=True)
        t = bvh_mod.build(lo[live] - pad, hi[live] + pad, method="sah" if len(live) < 4096 else "lbvh",
                          leaf_size=1, progress=False)
        w = bvh_layouts.collapse_to(t, gs.bvh_layout)
        nodes = w.tlas_nodes(live[w.order].astype(np.uint32))
        gs.upload("tlas_nodes", nodes)

    # ---- punctual lights ---------------------------------------------------------------------
    def _upload_lights(self) -> bool:
        """The punctual lights in anchor space, when they changed (LightList.version) or the anchor
        moved: no work per light on other frames."""
        lights = self.gs.scene.lights
        key = (lights.version, tuple(self.anchor))
        if not lights or key == self._lights:
            return False
        header = np.array([len(lights), 0, 0, 0], np.uint32)   # uvec4 punctual_info
        out = PUNCTUAL_LIGHT.zeros(len(lights))
        for k, L in enumerate(lights):
            out["position_type"][k, :3] = L.position - self.anchor
            out["position_type"].view(np.uint32)[k, 3] = L.type
            out["direction_range"][k] = (*L.direction, L.range)
            out["intensity"][k, :3] = np.asarray(L.color) * L.intensity
            cos_outer, cos_inner = np.cos(L.outer_cone_angle), np.cos(L.inner_cone_angle)
            out["cone"][k, :2] = (cos_outer, 1.0 / max(cos_inner - cos_outer, 1e-4))
        self.gs.upload("punctual_lights", np.concatenate([header.view(np.uint8), out.view(np.uint8)]))
        self._lights = key
        return True
