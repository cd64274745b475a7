"""TraceDecision: once per frame, before the ray passes, which pixels trace rays and where each of
the others takes its light from (glsl/trace_decision.glsl has the texel; decide.comp the rules)."""
from __future__ import annotations

from ...errors import OptionError
from ...gpu.program_resources import program_resources
from ...rendergraph.registry import register_pass
from ...rendergraph.render_pass import Reflection, RenderPass
from ...xr import foveation
from ...xr.cameras import grid_for_views
from ..dispatch import DITHERED_TRACE, ONE_VIEW_TILES, SOURCE_VIEWS, groups_2d
from ..compaction.pixel_list import empty_lists
from ..effects import effect_defines, scene_defines
from ..gbuffer import channels
from . import work_tiles
from .fill import DECISION, DECISION_FILLS

FOVEATION = ("none", *foveation.MODES)


@register_pass
class TraceDecision(RenderPass):
    """Decides per pixel of every view whether it traces its rays this frame (`decision`, rg32ui:
    glsl/trace_decision.glsl). A pixel whose effect needs rays traces when

    - it is in a source view, or its surface point, projected into the nearest source views, lands
      on a traced pixel of the same surface (effect word, normal, position within a few pixel
      footprints) whose lobe looks alike from both (no transmission, and roughness >=
      `reuse_min_roughness` or the angle between the two eyes seen from the point below
      `reuse_lobe_fraction` of the GGX lobe's width, roughness^2 radians (0.25: a lobe 4x wider
      than the eyes' parallax reuses); 0: roughness alone; with `reuse_delta_lobes` also a delta
      lobe at a RASTER or SHADOWS pixel, whose light samples give it nothing and whose probe light
      about the mirror direction is irradiance, smooth in direction: on by default, at 64 views of
      tauray 11.0 ms a frame against 12.2 without, at 0.99x the FLIP, benchmarks/RESULTS.md):
      then it REUSEs that pixel's shaded light (`reuse`; with two views the first eye is the
      source, or the eye of the frame's parity with `alternate`; with more, every
      `source_stride`-th column and row of a grid of `grid_cols` columns, 0: the default grid of
      rayvr.xr.grid_for_views; 4 by default: at 64 views of tauray 12.5 ms a frame against 13.1
      at 3 and 14.2 at 2, 12.5 at 5 and 8, all within 1% of the same FLIP, benchmarks/RESULTS.md).
      A pixel that fails the test traces: disocclusions are traced, never filled; and
    - the foveation budget (`foveation` 'fixed' about each image's centre, 'gaze' about where the
      eye tracker says the eye looks; rayvr.xr.foveation: 1 within `foveal_radius_deg`, falling to
      `periphery_share`) gives it its turn this frame: an ordered dither the frame index rotates, so
      a pixel at budget b traces on a share b of the frames, evenly spread; a pixel without its
      turn FILLs from the nearest traced pixel of the same surface within 2 pixels (none: it traces).

    `share_light_samples` (with `reuse`, not `every_surface`): a pixel of effect SHADOWS or
    REFLECTIONS (glass too) whose lobe fails that test but whose surface the source view shows on a traced
    pixel still traces (its lobe is its own), yet takes that pixel's direct light sample and shadow
    ray (DECISION_SHARED_LIGHT: RTShadows with its own `share_light_samples` shades it over them; a
    pass that does not traces it as any other).

    `source_views_first` (more than two views, with `reuse`): the ray passes' workgroups that span
    several views take whole workgroups of source views first (rayvr.passes.dispatch.view_order), so
    that such a warp holds only views traced in full; sources too few to fill one stay in grid order.
    `one_view_tiles` (more than two views, with `reuse`): the ray passes' and the composite's
    workgroups that read the decision hold one view each whatever their view group
    (rayvr.passes.dispatch.decision_view_group; `source_views_first` then has no workgroup to order):
    a tile of a view that reuses is mostly idle or wholly so, and a wholly idle one costs nothing.
    `work_tiles` (True; with `reuse` and `spread`): also lists the 8x4 tiles that hold a pixel
    whose light is not spread (`workTiles`, glsl/work_tiles.glsl), and the ray passes and the
    composite whose workgroup is such a tile run over that list: a wholly spread tile launches
    nothing. Measured at 64 views (benchmarks/RESULTS.md, 2026-12-07 ninth): RTShadows -0.28 ms,
    the composite's shader -0.22, the decision +0.12, and ~3 ms for the composite's clear of its
    colour before the tiles, then glClearTexImage; the clear is now a compute dispatch, a write of
    the image (not yet timed). (False: the list is declared but left empty and unread.)

    `every_surface`: every pixel has rays (a path tracer from the camera), else only those of effect
    SHADOWS and above. `spread` (the graphs set it with SVGF): SVGF gives a pixel whose light is
    another view's that view's filtered light itself, so the decision flags it (DECISION_SPREAD)
    and the ray passes' fills and the composite leave it. The ray passes read the decision (their
    lists and tiles skip the reconstructed pixels, and a last dispatch of each fills them:
    trace_decision.fill) and SVGF follows the budget. With one view and foveation 'none' there is nothing to decide: the pass is
    left out, and so is its texture."""

    USES_SCENE = True
    DECISION = DECISION
    CHOICES = {"foveation": dict(zip(FOVEATION, ("", "about each image's centre",
                                                 "about where the eye tracker says the eye looks")))}
    PROPERTIES = {"reuse": False, "foveation": "none", "foveal_radius_deg": foveation.DEFAULT_RADIUS_DEG,
                  "periphery_share": foveation.DEFAULT_PERIPHERY_SHARE, "reuse_min_roughness": 0.5,
                  "reuse_lobe_fraction": 0.25,
                  "source_stride": 4, "grid_cols": 0, "alternate": False, "every_surface": False, "spread": False,
                  "share_light_samples": True, "source_views_first": True,
                  "one_view_tiles": True, "reuse_delta_lobes": True, "work_tiles": True}
    WHOLE = {"source_stride": (2, None, "grid steps between source views"),
             "grid_cols": (0, None, "the camera grid's columns; 0: the most square")}

    def validate_property(self, key, value):
        value = super().validate_property(key, value)
        if key == "foveal_radius_deg":
            foveation.check_falloff(value, foveation.DEFAULT_PERIPHERY_SHARE, f"pass {self.name}: property '{key}'")
        if key == "periphery_share":
            foveation.check_falloff(foveation.DEFAULT_RADIUS_DEG, value, f"pass {self.name}: property '{key}'")
        if key == "reuse_min_roughness" and not 0.0 <= value <= 1.0:
            raise OptionError(f"pass {self.name}: property 'reuse_min_roughness' must be a perceptual roughness in "
                              f"[0, 1], got {value!r}")
        if key == "reuse_lobe_fraction" and not (isinstance(value, (int, float)) and 0.0 <= value <= 4.0):
            raise OptionError(f"pass {self.name}: property 'reuse_lobe_fraction' must be a number in [0, 4] (the "
                              f"eyes' parallax as a fraction of the lobe's width; 0: roughness alone), got {value!r}")
        return value

    def reuses(self, views: int) -> bool:
        return bool(self.reuse) and views > 1

    def reflect(self, cd):
        r = Reflection()
        channels.add_inputs(r)
        r.add_output(self.DECISION, "per pixel: trace, or reuse / fill from which traced pixel; the ray budget"
                     ).format("rg32ui")
        if self.spread and self.reuse:
            r.add_output(work_tiles.WORK_TILES, "the 8x4 tiles that hold a pixel whose light is not spread (scratch)"
                         ).buffer(work_tiles.work_tiles_bytes(cd.size, cd.views))
        return r

    def skip_reason(self, cd):
        if self.foveation == "none" and not self.reuses(cd.views):
            return ("one view and foveation 'none': every pixel traces" if self.reuse
                    else "neither reuse nor foveation is on: every pixel traces")
        return None

    def compile(self, ctx, cd):
        cols = int(self.grid_cols) or grid_for_views(cd.views)[0]
        self._defines = {"REUSE": int(self.reuses(cd.views)), "REUSE_COLS": cols,
                         "REUSE_STRIDE": int(self.source_stride), "REUSE_ALTERNATE": int(bool(self.alternate)),
                         "REUSE_MIN_ROUGHNESS": float(self.reuse_min_roughness),
                         "REUSE_LOBE_FRACTION": float(self.reuse_lobe_fraction),
                         "REUSE_DELTA_LOBES": int(bool(self.reuse_delta_lobes)),
                         "FOVEATION": FOVEATION.index(self.foveation), "FOVEAL_RADIUS": float(self.foveal_radius_deg),
                         "PERIPHERY_SHARE": float(self.periphery_share),
                         "EVERY_SURFACE": int(bool(self.every_surface)),
                         "REUSE_SPREAD": int(bool(self.spread) and self.reuses(cd.views)),
                         "SHARE_LIGHT_SAMPLES": int(bool(self.share_light_samples) and self.reuses(cd.views)
                                                   and not self.every_surface),
                         "WORK_TILES_APPEND": int(bool(self.work_tiles and self.spread) and self.reuses(cd.views))}
        ctx.dictionary[work_tiles.WORK_TILES_LISTED] = bool(self._defines["WORK_TILES_APPEND"])
        ctx.dictionary[DECISION_FILLS] = not (self._defines["REUSE_SPREAD"] and self.foveation == "none")
        grid_reuse = self.reuses(cd.views) and cd.views > 2   # a camera grid's: stereo's source may alternate
        if self.source_views_first and grid_reuse:
            ctx.dictionary[SOURCE_VIEWS] = self.source_views(cd.views, cols)
        ctx.dictionary[ONE_VIEW_TILES] = bool(self.one_view_tiles) and grid_reuse
        ctx.dictionary[DITHERED_TRACE] = self.foveation != "none"
        self._res = program_resources(self.compute_program(ctx.gl, "decide.comp", {
            **scene_defines(ctx), **effect_defines(), **self._defines}))
        self._groups = groups_2d(cd.size, cd.views)

    def source_views(self, views: int, cols: int) -> tuple[int, ...]:
        """The views of a grid of `cols` columns that trace in full (more than two views)."""
        stride = int(self.source_stride)
        return tuple(v for v in range(views) if (v % cols) % stride == 0 and (v // cols) % stride == 0)

    def defines(self) -> dict:
        d = dict(getattr(self, "_defines", {}))
        if d.get("REUSE"):
            lobes = (f", or glossier ones whose lobe is over {1 / self.reuse_lobe_fraction:.3g}x the eyes' parallax"
                     if self.reuse_lobe_fraction else "")
            d["reuse"] = (f"views reuse rough surfaces (roughness >= {self.reuse_min_roughness:g}{lobes}) "
                          "of source views: "
                          + ("the first eye" if not self.alternate else "the eye of the frame's parity")
                          + f" with 2 views, else one in {self.source_stride} of the {d['REUSE_COLS']} columns "
                            "and of the rows"
                          + ("; SVGF spreads their filtered light to the reusing pixels" if d.get("REUSE_SPREAD") else "")
                          + ("; glossier surfaces take the source's light samples and their shadow rays"
                             if d.get("SHARE_LIGHT_SAMPLES") else ""))
        if d.get("FOVEATION"):
            d["foveation"] = (f"{self.foveation}: every pixel within {self.foveal_radius_deg:g} degrees of "
                              + ("each view's centre" if self.foveation == "fixed" else "the gaze (else the centre)")
                              + f", beyond it a share falling to {self.periphery_share:g}")
        return d

    def execute(self, ctx, data):
        channels.bind_inputs(self._res, data)
        self._res.image("dst", data[self.DECISION])
        if self._defines["WORK_TILES_APPEND"]:
            empty_lists(ctx, data[work_tiles.WORK_TILES])
            self._res.buffer("WorkTiles", data[work_tiles.WORK_TILES])
        self._res.prog.run(*self._groups)
